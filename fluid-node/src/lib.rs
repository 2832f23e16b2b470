//! The fluid node: Euler equations of an ideal gas on a Cartesian grid (finite volumes, OSMP
//! flux with directional splitting, Lax–Friedrichs beside vacuum), the cut-cell geometry of the
//! embedded solid, and the process that wires them to the bus.
//!
//! - [`grid`]: the Cartesian grid (1, 2 or 3 active axes).
//! - [`fv`]: the pure finite-volume core (no IO, no clock).
//! - [`cutcell`]: the pure cut-cell geometry (no IO, no clock).
//! - [`node`]: the node loop over any transport, written against [`model::FluidModel`];
//!   [`double`]: the pressure double.
//! - [`output`]: fluid CSV and legacy VTK writers.
//! - [`report`]: work–precision study (wall time, CSV and SVG files).
//! - [`Error`]: what building or running the node fails with (each module's error converts in).

#![warn(missing_docs)]

#[cfg(feature = "node")]
pub mod cli;
pub mod cutcell;
#[cfg(feature = "node")]
pub mod cutcell_cmd;
pub mod double;
pub mod embedded;
mod error;
pub mod exchange;
pub mod fv;
pub mod grid;
mod memory;
pub mod model;
pub mod node;
pub mod output;
pub mod ranks;
pub mod report;

pub use error::Error;
