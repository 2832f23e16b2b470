//! The solid node: Discrete Element Method of Monasse–Mariotti (rigid polyhedral particles
//! linked by elastic forces and torques, Verlet + RATTLE, fracture by breaking links, wet surface
//! from mean vertices), and the process that wires it to the bus.
//!
//! - [`dem`]: the pure DEM core (no IO, no clock).

#![warn(missing_docs)]

pub mod dem;
pub mod output;
