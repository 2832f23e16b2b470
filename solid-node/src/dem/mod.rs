//! Pure DEM core (no IO, no clock, no environment): the Discrete Element Method of
//! Mariotti / Monasse (papers 003 §2.2, App. A and 000 §2.2, §3.1).
//!
//! Rigid polyhedral particles (polygonal prisms of unit depth moving in the plane in 2-D) are
//! linked through their shared faces by the forces and torques of eq. (29)–(30) of paper 003,
//! which derive from a potential ([`link_force`]); translation is integrated by velocity Verlet
//! and rotation by RATTLE ([`rattle`]); links break at a relative elongation (000 §3.1); the wet
//! surface is rebuilt from mean vertices (003 eq. (18), [`wet`]).
//!
//! # Pipeline (what the node loop calls)
//!
//! ```text
//! Solid::from_scene(cfg, dim, threads)      lattice -> model (particles, links) -> state
//! loop {
//!     dt = min(solid.max_dt(cell_size), fluid dt)
//!     solid.begin_step(dt)                  internal forces at Xⁿ (cached)
//!     loop { trial = solid.trial(F, M) }    half kick + drift, wet surface at n+1; repeatable
//!     report = solid.commit()               forces at n+1, fracture, half kick, diagnostics
//! }
//! solid.wet_surface(), solid.energies(), solid.momentum(), solid.normal_stress()
//! solid.to_checkpoint() / solid.restore_checkpoint(bytes)
//! ```
//!
//! Conventions for the wire (`protocol::wire`): positions and forces have `dim` components per
//! particle; torques and angular velocities 1 (2-D, about z) or 3 (3-D, space frame);
//! orientations are the angle (2-D) or the quaternion `(w, x, y, z)` of the rotation since
//! t = 0 (3-D). [`WetSurfaceData`] has the flat layout of `protocol::wire::WetSurface` plus
//! per-element area, normal, centroid and velocity. 2-D quantities are per unit depth.
//!
//! # Invariants
//!
//! - Numerical trouble is returned as [`Diagnostic`]s in the [`StepReport`], never a panic.
//! - Results are bit-identical for any thread count (fixed partition, serial reductions).
//! - No allocation in the per-link and per-particle kernels.

pub mod geometry;
pub mod lattice;
pub mod link_force;
pub mod model;
pub mod rattle;
pub mod report;
pub mod solid;
pub mod stability;
pub mod wet;

#[cfg(test)]
mod tests;

pub use model::{LinkId, Material, ParticleId, ParticleMotion};
pub use report::{BrokenLink, Diagnostic, Energies, Momentum, StepReport};
pub use solid::{Solid, Trial};
pub use wet::WetSurfaceData;
