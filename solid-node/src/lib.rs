//! The solid node: Discrete Element Method of Monasse–Mariotti (rigid polyhedral particles
//! linked by elastic forces and torques, Verlet + RATTLE, fracture by breaking links, contact
//! between particles that are not linked, wet surface from mean vertices), and the process that
//! wires it to the bus.
//!
//! - [`dem`]: the pure DEM core (no IO, no clock).
//! - [`model`]: what the node loop needs from an implementation; [`node`]: the node loop over any
//!   transport; [`double`]: the prescribed double; `cli` (feature `node`): the binary's command
//!   line and the choice of model.
//! - [`output`]: particle CSV and VTK writers; [`error`]: the node's typed errors.

#![warn(missing_docs)]

#[cfg(feature = "node")]
pub mod cli;
pub mod dem;
pub mod double;
pub mod error;
pub mod exchange;
pub mod model;
pub mod node;
pub mod output;
