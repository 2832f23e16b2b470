//! The solid node: Discrete Element Method of Monasse–Mariotti (rigid polyhedral particles
//! linked by elastic forces and torques, Verlet + RATTLE, fracture by breaking links, contact
//! between particles that are not linked, wet surface from mean vertices), and the process that
//! wires it to the bus.
//!
//! - [`dem`]: the pure DEM core (no IO, no clock).
//! - [`node`]: the node loop over any transport; [`double`]: the prescribed double.
//! - [`output`]: particle CSV and VTK writers.

#![warn(missing_docs)]

#[cfg(feature = "node")]
pub mod cli;
pub mod dem;
pub mod double;
pub mod exchange;
pub mod node;
pub mod output;
