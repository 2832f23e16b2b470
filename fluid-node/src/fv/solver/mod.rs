//! [`FluidSolver`]: owns the state, the scratch buffers and the worker pool, and advances the
//! flow by split steps; reports totals and trouble as data.
//!
//! - `build.rs`: the type, its construction (one rank or a slab of several) and accessors.
//! - `cfl.rs`: the CFL step of the current state and the cell that limits it.
//! - `step.rs`: one split step (the time-step check, the sweeps, their summaries merged over
//!   the ranks in a fixed order).
//! - `hooks.rs`, `coupling.rs`: what a coupled step asks of the sweeps, and how they do it.
//! - `totals.rs`: conserved totals in fixed-order compensated sums; gathers on rank 0.
//! - `checkpoint.rs`: node-private checkpoint bytes.
//! - `report.rs`: what a step reports; `cell.rs`: per-cell helpers.

mod build;
mod cell;
mod cfl;
mod checkpoint;
mod coupling;
mod hooks;
mod outflow;
mod pages;
mod report;
mod step;
mod totals;

pub use build::{FluidSolver, SolverError};
pub(crate) use cell::items_per_task;
pub use checkpoint::CheckpointError;
pub use hooks::{GhostFill, SplitHooks};
pub use report::{
    MAX_TROUBLES, RefusedTimeStep, StepError, StepReport, Totals, Trouble, TroubleKind,
};
pub use step::sweep_order;
