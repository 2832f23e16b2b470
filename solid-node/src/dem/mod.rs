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
//!                                           -> [[solid.init]] velocities of free particles
//! loop {
//!     dt = min(solid.max_dt(cell_size), fluid dt)
//!     solid.begin_step(dt)                  internal (+ contact) forces at Xⁿ (cached)
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
//! # Readings of the papers (details and reasons in [`link_force`])
//!
//! - `Δu_IJ = (X_I + Q_I (G − X⁰_I)) − (X_J + Q_J (G − X⁰_J))` (the printed form is not zero at
//!   rest); `n_IJ` in the volumetric terms is `(X_I − X_J)/D_IJ`; forces and torques are the
//!   exact negative gradient of one potential (energy conservation, checked by finite
//!   differences in the unit tests).
//! - Volumetric force `S λ (ε^v_I + ε^v_J)/2`: the printed sum doubles λ; the mean gives E
//!   exactly for a one-particle-thick bar with ν ≠ 0 (free-volume design, the integration test `dem_wave`).
//! - ε^v_I uses the free volume `V_I + 3ν/(1−2ν) V^f_I` (003; 000 prints `V_I` twice).
//! - Fracture: the relative elongation `(|X_I − X_J| − D⁰)/D⁰` is compared with
//!   `elongation_at_break` as a fraction (000 writes it in percent).
//! - A link of rest length h stands for the material between two particle centres: a clamp is
//!   modelled by a fixed particle centred on it (`scenes/cantilever.toml`).
//! - A body with `links = { spring = k, rotation = c }` (003 §5.3, the thin shell) has, instead,
//!   linear springs between particle centres, `½ k (|d| − D⁰)² + c (1 − cos θ_rel)`: no shear,
//!   no volumetric part, no torque from the spring, so a chain is a discrete string whose
//!   transverse stiffness comes from its tension only ([`link_force::spring_force_2d`]).
//!
//! # Wet surface layout
//!
//! Vertices are one per (lattice vertex, particle) slot, then (3-D) one per particle face
//! centroid; their number and the number of elements never change during a run. Elements
//! reference the representative slot of each mean vertex, so the wet elements are closed by
//! index; fracture changes the connectivity and the wet flags and bumps `revision`. The trial's
//! element velocities are `V^{n+1/2} + Ω^{n+1/2} × (x − X^{n+1})`; the committed surface's are
//! the instantaneous rigid velocities.
//!
//! # Limitations
//!
//! - Contact (`[solid.contact]`, [`contact`]) acts between particles that are not linked by an
//!   unbroken link, including particles of one intact body that touch only along an edge or at
//!   a vertex (their overlap, and so their contact energy, is of fourth order in the strain).
//!   Friction is regularised: no sticking under a sustained tangential load.
//! - Explicit particles are linked only through faces with the same vertex set.
//! - 2-D positions are stored with a zero z so that both dimensions share the state layout; the
//!   2-D kernels work on 2 translations and 1 angle.
//!
//! # Invariants
//!
//! - Numerical trouble is returned as [`Diagnostic`]s in the [`StepReport`], never a panic.
//! - Results are bit-identical for any thread count (fixed partition, serial reductions).
//! - No allocation in the per-link and per-particle kernels.

pub mod contact;
pub mod geometry;
pub mod lattice;
pub mod link_force;
pub mod model;
mod parallel;
pub mod rattle;
pub mod report;
pub mod solid;
pub mod stability;
pub mod walls;
pub mod wet;

#[cfg(test)]
mod tests;

pub use contact::ContactError;
pub use geometry::HullError;
pub use lattice::{BodyError, LatticeError};
pub use model::{LinkId, Material, ModelError, ParticleId, ParticleMotion};
pub use report::{BrokenLink, Diagnostic, Energies, Momentum, StepReport};
pub use solid::{CheckpointError, SetupError, Solid, Trial};
pub use wet::WetSurfaceData;
