//! The fluid around an embedded, moving and deforming solid (no IO, no clock): the conservative
//! cut-cell method of paper 003 (§2.3 eq. 12–13, §3.3 eq. 19–25, §3.4 steps 1–7) on top of the
//! finite-volume core ([`crate::fv`]) and the exact geometry ([`crate::cutcell`]).
//!
//! One coupling step, from the fluid's side:
//!
//! 1. [`Embedded::predict`]: the split sweeps over the whole grid, ignoring the solid except for
//!    the ghost states written into the covered cells before each sweep (mirror of the fluid
//!    along the sweep line, relative to the wall velocity, `ng` cells deep). Kept: `U^n`, the
//!    wall pressure `p̄` and the face fluxes, of the cells near the wet surface only (the cut
//!    cells of `F^n` dilated by [`NEAR_RADIUS`] cells).
//! 2. [`Embedded::loads`], once per fixed-point iteration: force and torque per particle from
//!    `p̄` over the wet sub-faces of the trial surface (eq. 23–25), torques about the trial
//!    centres of mass. Only the geometry of the trial surface is computed.
//! 3. [`Embedded::correct`] with the accepted surface `F^{n+1}`: in every cell near the solid,
//!    eq. (12) `(1 − Λ^{n+1}) U^{n+1} = (1 − Λ^{n+1}) U^n + Δt Φ_fluid + Δt Φ_solid + ΔU` with
//!    the fluid fluxes weighted by `1 − λ^{n+1}` (eq. 13), the solid flux (eq. 26) with the
//!    sub-face velocity `V_f = V^{n+1/2} + Ω^{n+1/2} × (X_f − X^{n+1})`, and the amounts swept
//!    by the prisms of the sub-faces of `F^{n+1}` back to `F^n` (paper 000 eq. 12); then the
//!    conservative mixing of small cells (`Λ > 1/2`), of cells the solid uncovers and of covered
//!    cells left with content (paper 000 §3.3, recursive). Away from the solid the predicted
//!    state is already eq. (12): all weights are 1 and the per-sweep increments add up.
//!
//! On a grid decomposed over ranks ([`crate::fv::Slab`], a block) every rank holds the whole
//! surface, the whole grid's sub-faces and cut cells, and Λ and λ dense in its block and the
//! hooks' halo only (the geometry of `F^{n+1}` computed by block and put together, `held.rs`),
//! and runs all of this on the whole grid but the loads (each rank takes the sub-faces
//! of its own block, and the terms of all are added as one rank adds them, `loads.rs`), the
//! ghost fills, wall runs and vacuum cells the sweeps write into its cells (derived from the
//! geometry of its block and a halo, `hooks.rs`, with the `U^n` and `p̄` of its near cells), and the
//! correct's prisms, cell updates, swept amounts and solid flux, and the mixing sources' walks
//! to their roots (each rank those of its own cells, all gathered on every rank in the one-rank
//! order, `correct.rs`, `mix.rs`); the solver
//! applies the sweeps' hooks per block and keeps the fluxes of every face of a rank's cells, and
//! the states of near cells come from their ranks ([`crate::fv::FluidSolver::cells_at`]), so
//! every rank computes the bits of one rank (the fluid-node tests `fv_ranks`, `fv_ranks_hooks`
//! and `embedded_hooks_block`, docs/mpi.md).
//!
//! Properties (tested in the fluid-node tests `embedded_*`): fluid mass, momentum and energy plus
//! what crossed the interface are conserved to round-off (the swept volumes telescope, the
//! face fluxes are shared); a uniform pressure gives no force on any cut cell and no velocity
//! (identity 19–21); a uniform flow around a body translating with it stays uniform (the
//! sub-face prisms give `Δt w·ν A` exactly).
//!
//! Readings chosen where the papers are silent:
//! - `p̄` of a sub-face is one pressure on every axis: the mean of the pressures of the cell
//!   holding it at t^n and after the sweeps (paper 003 takes along each axis the pressure that
//!   axis's sweep starts from; a face's work then need not have the sign of its normal velocity,
//!   see `predict.rs` and docs/cut-cells.md §3). A face in a cell covered at t^n takes the `p̄`
//!   of the fluid cell it faces (`cells::pressure_cell`): a thin covered run mirrors one side
//!   only.
//! - Ghost states mirror along the sweep line (numerics §2.6), which is exact for walls normal
//!   to the axis; the wall velocity is the area-averaged velocity of the sub-faces of the cut
//!   cell beside the covered run.
//! - Mixing target (paper 000 §3.3): among the neighbours (faces, edges and corners) with
//!   fluid fraction ≥ 1/2, the one best aligned with the wall normal `Σ A ν` of the cell; if
//!   there is none, the face neighbour with the largest aperture, recursively, until a large
//!   cell is found or the walk cycles (then the nearest target through open faces; for a closed
//!   pocket of covered cells, across the solid).
//! - Vacuum where nothing can reach (paper 000 §3.2 extended): a cell covered at t^n whose face
//!   neighbours are all covered or beyond the domain is sealed; what the solid uncovers of it
//!   holds vacuum, as a crack does (`crack.rs`, docs/cut-cells.md).
//! - With the solid sub-cycled (`run.solid_substeps` other than 1) and the semi-implicit scheme,
//!   the torques' lever arms, in the loads and the solid flux alike, are taken on `F^n`
//!   (`levers.rs`, docs/subcycling.md): held over a long step, the end surface's pumped the
//!   lever part of the fluid's stiffness, which those at `t^n` damp.
//!
//! The files follow the step: `state` (configuration, what persists between steps, the step's
//! near-surface data and the scratch, apart), `frame` (the solid as the core sees it), `cells`
//! (per-cell helpers every stage uses), `near_wall` (the wall in a near cell, for the ghost
//! states), `hooks` (the ghost fills, wall runs and vacuum cells of a rank's cells), `predict`
//! (step 1), `loads` (step 2), `levers` (the loads' lever arms), `crack`
//! (cells a crack opens), `correct` (eq. 12 and the solid flux), `mix` (small-cell mixing),
//! `gather` (the all-gathers of what each rank does for its own cells in those two),
//! `beyond` (elements beyond the domain), `memory` (heap bytes by part) and `error`.

// Index loops over the axes read like the formulas they implement.
#![allow(clippy::needless_range_loop)]

mod beyond;
mod cells;
mod correct;
mod crack;
mod error;
mod frame;
mod gather;
mod held;
mod hooks;
mod identity;
mod levers;
mod loads;
mod memory;
mod mix;
mod near_wall;
mod pool_sum;
mod predict;
mod slots;
mod state;

pub use correct::CorrectReport;
pub use error::EmbeddedError;
pub use frame::SolidFrame;
pub use hooks::{WallHooks, hook_halo, wall_hooks, wall_hooks_in};
pub use loads::Loads;
pub use memory::EmbeddedMemory;
pub use state::{Embedded, InterfaceBudget};

/// Cells within this Chebyshev distance of a cut cell of `F^n` keep their `U^n`, `p̄` and face
/// fluxes: the surface may move one cell per step, and a trial of the fixed point a little more.
pub const NEAR_RADIUS: usize = 2;

/// Fluid fraction under which a cut cell is mixed with a neighbour (paper 003 §2.3: Λ > 0.5).
pub const MIX_BELOW: f64 = 0.5;

/// Rounds in which a mixing group whose mixture is not physical takes in the groups beside it.
pub const MERGE_ROUNDS: usize = 4;

/// Rings of neighbours whose predicted states are read with the mixing groups' (collective, once
/// per step): a group whose mixture is not physical takes these in first, and further rings,
/// read as it needs them, until its mixture is physical (no limit: it ends at the latest when
/// the group holds every cell no other group holds; docs/cut-cells.md §3).
///
/// NOTE: two rings left the jets of a burst without contact non-physical (a cell 3 % open at
/// 7 km/s, p = −1.9e4 Pa, `burst-shell-2d` without `[solid.contact]`, step 498); eight left a
/// body at Mach 850 in cold gas non-physical at step 1 (its groups took up to 457 cells; fluid-node
/// test `bodies_at_hundreds_of_times_the_sound_speed_keep_every_cell_physical`).
pub const WIDEN_RINGS: usize = 2;

/// Largest defect of identity (3) (solid-fraction change against swept volume) a cell may show,
/// relative to its volume: round-off is ~1e-15.
pub const SWEPT_TOLERANCE: f64 = 1e-10;

/// A cell is covered (a ghost cell) when its solid fraction is at least `1 − COVERED_TOLERANCE`.
pub const COVERED_TOLERANCE: f64 = 1e-12;
