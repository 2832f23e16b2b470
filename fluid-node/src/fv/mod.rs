//! Pure finite-volume core (no IO, no clock, no env): the Euler equations of an ideal gas on a
//! Cartesian grid of 1, 2 or 3 dimensions chosen at run time.
//!
//! Method: OSMP fluxes of Daru & Tenaud (JCP 2004) of order 3, 5 or 7 on Roe characteristic
//! variables, one full-`Δt` sweep per axis with the sweep order cycling through the
//! permutations (paper 003 §2.1 and §3.4 step 1); Lax–Friedrichs at faces beside vacuum cells
//! (paper 000 §3.2), in its local form between two vacuum cells (docs/cut-cells.md §4);
//! reflecting walls, periodic and zero-gradient outflow boundaries.
//!
//! Public API used by the node loop:
//! ```text
//! FluidSolver::from_scene(&FluidConfig, threads) -> Result<FluidSolver, SolverError>
//! solver.grid() -> &Grid                 solver.max_dt() -> f64 (CFL)
//! solver.advance(dt) -> StepReport       (one split step; report.ok() == false: stop)
//! solver.totals() -> Totals              (mass, momentum, energy, what left the domain)
//! solver.primitive(cell) -> (ρ, [u; 3], p)
//! solver.directional_pressures(axis) -> &[f64]   (p̄_x, p̄_y, p̄_z of paper 003 §3.4)
//! solver.to_checkpoint() -> Vec<u8>      solver.restore_checkpoint(&[u8]) -> Result<(), CheckpointError>
//! ```
//! Also: [`exact_riemann`] (Toro's exact solver with exact cell averages), [`init`]
//! (analytic initial conditions for verification) and [`study`] (pure parts of the
//! work–precision study; timing and files in `crate::report`).
//!
//! Pipeline of one step (`solver/step.rs`): check `dt` against the CFL step at Courant number
//! 1 (the one check of the step); for each sweep axis in the order of [`sweep_order`] (2-D:
//! xy, yx, ...; 3-D: xyz, zyx, yzx, xzy, zxy, yxz):
//! record `p̄_axis`, then for every pencil along the axis (rayon, fixed partition, `sweep.rs`)
//! gather the line with `ng` ghost cells from the boundary conditions, compute the face fluxes
//! and update (`line.rs`), and write back; then sum the outflow, counters and troubles in
//! pencil order and the totals with compensated sums.
//!
//! Storage: interior cells only, `dim + 2` conserved values per cell, x fastest (`state.rs`);
//! ghost layers (`ng` = 3 for OSMP3/5, 4 for OSMP7) live in the per-thread pencil scratch.
//!
//! Readings chosen where the sources are incomplete (details in `osmp.rs`, `solver/`):
//! division-free OSMP with `|λ_0|` curvature normalisation and upwind LC bound (numerics.md
//! §1.5); per-interface Roe eigensystems (Tenaud's `osmp7.f90`); sweep orders paired with their
//! reverse so the splitting is second order over every two steps; HLLE fallback where the Roe
//! linearisation is not physical and an a-posteriori positivity fix (numerics.md §1.8); wall
//! faces carry only the pressure flux.
//!
//! Example:
//! ```
//! use fluid_node::fv::FluidSolver;
//! let scene = protocol::scene::Scene::from_toml_str(r#"
//!     name = "sod"
//!     [fluid]
//!     lower = [0.0]
//!     upper = [1.0]
//!     cells = [100]
//!     [[fluid.init]]
//!     region = "all"
//!     rho = 0.125
//!     p = 0.1
//!     [[fluid.init]]
//!     region = { box = { lower = [0.0], upper = [0.5] } }
//!     rho = 1.0
//!     p = 1.0
//! "#, "sod.toml").unwrap();
//! let mut solver = FluidSolver::from_scene(scene.fluid.as_ref().unwrap(), 1).unwrap();
//! let report = solver.advance(solver.max_dt());
//! assert!(report.ok());
//! ```

// Index loops over the state components read like the formulas they implement.
#![allow(clippy::needless_range_loop)]

mod block;
pub mod comm;
pub mod euler;
pub mod exact_riemann;
pub mod init;
pub mod isa;
pub mod line;
pub mod osmp;
pub mod scene;
pub mod slab;
pub mod solver;
pub mod state;
pub mod study;
pub mod sweep;

#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_isa;
#[cfg(test)]
mod tests_upwind;
#[cfg(test)]
mod tests_vacuum;

pub use comm::{Comm, Serial};
pub use isa::Isa;
pub use line::FluxKind;
pub use scene::{ConfigError, from_scene};
pub use slab::Slab;
pub use slab::SlabError;
pub use solver::{
    CheckpointError, FluidSolver, GhostFill, RefusedTimeStep, SolverError, SplitHooks, StepError,
    StepReport, Totals, Trouble, TroubleKind, sweep_order,
};
pub use state::{BoundaryKind, CHARACTERISTIC_SIGMA, FluidParams, FluidState};
pub use sweep::{FaceTap, Wall, WallRun, mirror};
