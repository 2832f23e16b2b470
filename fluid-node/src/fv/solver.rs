//! [`FluidSolver`]: owns the state, the scratch buffers and the worker pool, and advances the
//! flow by split steps; reports totals and trouble as data.

mod hooks;

use std::sync::{Mutex, OnceLock};

use rayon::prelude::*;

use protocol::scene::FluidConfig;

use crate::fv::comm::{Comm, Serial, bytes_f64, f64_bytes};
use crate::fv::euler::{NQ, Primitive, sound_speed};
use crate::fv::line::{FluxKind, LineScratch, state_ok};
use crate::fv::slab::Slab;
use crate::fv::state::{BoundaryKind, FluidParams, FluidState, from_scene};
use crate::fv::sweep::{PencilOut, Pencils, SlabHalo, pencil_to_cells, sweep_axis};
use crate::grid::Grid;
use crate::memory::vec_bytes;

pub use hooks::{GhostFill, SplitHooks};

/// Cells per block of the parallel loops over cells (CFL step, directional pressures).
const BLOCK_CELLS: usize = 4096;

/// At most this many troubled cells are listed in one [`StepReport`].
pub const MAX_TROUBLES: usize = 16;

/// Conserved totals over the grid and what left through the domain faces.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Totals {
    /// Mass `Σ ρ V` \[kg\] (per unit length in 2-D, per unit area in 1-D).
    pub mass: f64,
    /// Momentum `Σ ρu V` per axis [kg m/s] (inactive axes 0).
    pub momentum: [f64; 3],
    /// Total energy `Σ E V` \[J\].
    pub energy: f64,
    /// Mass that left through the open (outflow) faces since the start \[kg\].
    pub outflow_mass: f64,
    /// Momentum that left through open and wall faces since the start (at walls: the wall
    /// pressure impulse) [kg m/s].
    pub outflow_momentum: [f64; 3],
    /// Energy that left through the open faces since the start \[J\].
    pub outflow_energy: f64,
}

/// What went wrong in a cell.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum TroubleKind {
    /// A value is NaN or infinite.
    NonFinite,
    /// ρ ≤ 0 outside a vacuum cell, or ρ < 0.
    Density,
    /// p ≤ 0 outside a vacuum cell, or p < 0.
    Pressure,
    /// The step was refused: `dt` not finite and positive, or above the CFL limit of the
    /// scheme (Courant number > 1); `cell` is zero, `rho` holds the refused `dt` \[s\] and `p`
    /// the largest accepted one \[s\].
    TimeStep,
}

/// A cell left non-physical by a sweep (the caller stops the run).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Trouble {
    /// What is wrong.
    pub kind: TroubleKind,
    /// Sweep axis that produced it (0, 1, 2).
    pub axis: usize,
    /// Cell `(i, j, k)` of the whole grid (on any rank).
    pub cell: [usize; 3],
    /// Cell centre \[m\].
    pub position: [f64; 3],
    /// Density [kg/m³].
    pub rho: f64,
    /// Velocity [m/s].
    pub velocity: [f64; 3],
    /// Pressure \[Pa\].
    pub p: f64,
}

/// What one call of [`FluidSolver::advance`] did.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StepReport {
    /// Step number (0 for the first step).
    pub step: u64,
    /// Time step \[s\].
    pub dt: f64,
    /// Time after the step \[s\].
    pub time: f64,
    /// Sweep axes in the order applied.
    pub sweeps: Vec<usize>,
    /// Faces that used Lax–Friedrichs (vacuum), summed over the sweeps.
    pub lax_friedrichs_faces: u64,
    /// Faces that used the HLLE fallback.
    pub hlle_faces: u64,
    /// Cells whose faces the positivity fix recomputed.
    pub positivity_fixes: u64,
    /// Amount that left through the domain faces during this step, `(mass, p_x, p_y, p_z,
    /// energy)` [kg, kg m/s, J].
    pub outflow: [f64; NQ],
    /// Non-physical cells after a sweep (at most [`MAX_TROUBLES`]); empty when all is well.
    pub troubles: Vec<Trouble>,
    /// Conserved totals after the step, with the cumulative outflow (see [`Totals`]).
    pub totals: Totals,
}

impl StepReport {
    /// Whether the step produced no trouble.
    pub fn ok(&self) -> bool {
        self.troubles.is_empty()
    }
}

/// Sweep orders of 3-D steps: each consecutive pair is a sequence and its reverse, and the six
/// steps cover all permutations.
///
/// NOTE: paper 003 §3.4 step 1 and Tenaud's `mr_chorus.f90` cycle through the 6 permutations
/// (second order every 6 steps); pairing each order with its reverse (`xyz`, `zyx`, ...) makes
/// every two consecutive steps a Strang-type symmetric product, so the splitting is second
/// order over each pair while all permutations are still visited.
const ORDERS_3D: [[usize; 3]; 6] = [
    [0, 1, 2],
    [2, 1, 0],
    [1, 2, 0],
    [0, 2, 1],
    [2, 0, 1],
    [1, 0, 2],
];

/// Sweep axes of step `step` in dimension `dim`.
pub fn sweep_order(dim: usize, step: u64) -> Vec<usize> {
    match dim {
        1 => vec![0],
        2 => {
            if step.is_multiple_of(2) {
                vec![0, 1]
            } else {
                vec![1, 0]
            }
        }
        _ => ORDERS_3D[(step % 6) as usize].to_vec(),
    }
}

/// Checkpoint layout (node-private bytes, see [`FluidSolver::to_checkpoint`]).
#[derive(serde::Serialize, serde::Deserialize)]
struct Checkpoint {
    version: u32,
    cells: [u64; 3],
    step: u64,
    time: f64,
    u: Vec<f64>,
    outflow: [f64; NQ],
    pbar: Vec<Vec<f64>>,
}

const CHECKPOINT_VERSION: u32 = 1;

/// What one rank's sweeps of a step found, gathered from every rank in rank order and merged
/// in a fixed order (so that the report does not depend on the number of ranks).
#[derive(Default, serde::Serialize, serde::Deserialize)]
struct SweepSummary {
    /// Outflow partial sums `dt × area × flux`: per plane of the slab axis for a sweep along
    /// another axis; for a sweep along the slab axis one for the low and one for the high
    /// domain face, from the ranks that hold them.
    partials: Vec<[f64; NQ]>,
    lax_friedrichs: u64,
    hlle: u64,
    positivity_fixes: u64,
    /// `(global pencil, trouble)`, pencils ascending, at most [`MAX_TROUBLES`].
    troubles: Vec<(u64, Trouble)>,
}

/// The finite-volume Euler solver on a Cartesian grid of 1, 2 or 3 dimensions, on one rank or
/// on one slab of a grid decomposed over several ([`Slab`], [`Comm`]).
pub struct FluidSolver {
    /// This rank's cells (the whole grid on one rank).
    grid: Grid,
    slab: Slab,
    comm: Box<dyn Comm>,
    /// Halo planes of the neighbours below and above (empty without neighbours).
    halo: [Vec<f64>; 2],
    /// The [`SplitHooks`] of a coupled step on this rank's slab (scratch).
    local: hooks::LocalHooks,
    params: FluidParams,
    state: FluidState,
    buffer: Vec<f64>,
    pencil_out: Vec<PencilOut>,
    scratch: Vec<Mutex<LineScratch>>,
    pool: rayon::ThreadPool,
    /// `p̄` per active axis, or empty when not kept (see [`FluidSolver::keep_directional_pressures`]).
    pbar: Vec<Vec<f64>>,
    /// `max_dt` of the current state and the cell that limits it, once computed (reset whenever
    /// the state changes).
    dt_cache: OnceLock<(f64, usize)>,
    step: u64,
    time: f64,
    outflow: [f64; NQ],
}

impl FluidSolver {
    /// Builds the solver from the scene's `[fluid]` table with `threads` worker threads
    /// (results do not depend on it).
    pub fn from_scene(cfg: &FluidConfig, threads: usize) -> Result<FluidSolver, String> {
        let (grid, params, state) = from_scene(cfg)?;
        FluidSolver::new(grid, params, state, threads)
    }

    /// Builds this rank's slab of the solver of the scene's `[fluid]` table, the grid
    /// decomposed over the ranks of `comm` (see [`FluidSolver::decomposed`]).
    pub fn from_scene_on(
        cfg: &FluidConfig,
        threads: usize,
        comm: Box<dyn Comm>,
    ) -> Result<FluidSolver, String> {
        let (grid, params, state) = from_scene(cfg)?;
        FluidSolver::decomposed(grid, params, state, threads, comm)
    }

    /// Builds the solver from parts (`state` must have `grid.dim + 2` values per cell).
    pub fn new(
        grid: Grid,
        params: FluidParams,
        state: FluidState,
        threads: usize,
    ) -> Result<FluidSolver, String> {
        FluidSolver::decomposed(grid, params, state, threads, Box::new(Serial))
    }

    /// Builds this rank's slab of a solver over the ranks of `comm`: `grid` and `state` are the
    /// whole grid's (every rank builds the same), the rank keeps its planes along the slowest
    /// axis ([`Slab`]). Every method that reduces over the grid (the step, the CFL step, the
    /// totals, checkpoints, [`FluidSolver::gather_state`]) is then collective: every rank calls
    /// it, in the same order.
    pub fn decomposed(
        grid: Grid,
        params: FluidParams,
        state: FluidState,
        threads: usize,
        comm: Box<dyn Comm>,
    ) -> Result<FluidSolver, String> {
        if state.nvar != grid.dim + 2 || state.u.len() != state.nvar * grid.n_cells() {
            return Err(format!(
                "state has {} values ({} per cell), grid needs {} per cell for {} cells",
                state.u.len(),
                state.nvar,
                grid.dim + 2,
                grid.n_cells()
            ));
        }
        if let FluxKind::Osmp(order) = params.flux
            && ![3, 5, 7].contains(&order)
        {
            return Err(format!("osmp order must be 3, 5 or 7, got {order}"));
        }
        let slab = if comm.size() == 1 {
            Slab::whole(&grid)
        } else {
            let axis = grid.dim - 1;
            Slab::new(
                &grid,
                comm.rank(),
                comm.size(),
                params.ghost_cells(),
                params.boundary[axis],
            )?
        };
        let nvar = state.nvar;
        let state = if slab.ranks == 1 {
            state
        } else {
            let range = slab.global_range();
            FluidState {
                nvar,
                u: state.u[range.start * nvar..range.end * nvar].to_vec(),
            }
        };
        let grid = slab.local.clone();
        let halo_len = slab.depth * slab.plane() * nvar;
        let halo = [
            if slab.lo.is_some() {
                vec![0.0; halo_len]
            } else {
                Vec::new()
            },
            if slab.hi.is_some() {
                vec![0.0; halo_len]
            } else {
                Vec::new()
            },
        ];
        let threads = threads.max(1);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(|e| format!("building a pool of {threads} threads: {e}"))?;
        let max_pencils = (0..grid.dim)
            .map(|a| grid.n_cells() / grid.cells[a])
            .max()
            .unwrap_or(1);
        Ok(FluidSolver {
            slab,
            comm,
            halo,
            local: hooks::LocalHooks::default(),
            buffer: vec![0.0; state.u.len()],
            pencil_out: vec![PencilOut::default(); max_pencils],
            scratch: (0..threads)
                .map(|_| Mutex::new(LineScratch::default()))
                .collect(),
            pool,
            pbar: Vec::new(),
            dt_cache: OnceLock::new(),
            grid,
            params,
            state,
            step: 0,
            time: 0.0,
            outflow: [0.0; NQ],
        })
    }

    /// This rank's grid: the cells of [`FluidSolver::state`] (the whole grid on one rank;
    /// on several, its `lower`/`upper` are those of the slab up to rounding, so positions are
    /// taken from [`FluidSolver::global_grid`]).
    pub fn grid(&self) -> &Grid {
        &self.grid
    }

    /// The whole grid over all ranks.
    pub fn global_grid(&self) -> &Grid {
        &self.slab.global
    }

    /// This rank's part of the grid.
    pub fn slab(&self) -> &Slab {
        &self.slab
    }

    /// The ranks of the grid.
    pub fn comm(&self) -> &dyn Comm {
        &*self.comm
    }

    /// The parameters.
    pub fn params(&self) -> &FluidParams {
        &self.params
    }

    /// The conserved state.
    pub fn state(&self) -> &FluidState {
        &self.state
    }

    /// Mutable conserved state (initial conditions of tests and benches).
    pub fn state_mut(&mut self) -> &mut FluidState {
        self.dt_cache = OnceLock::new();
        &mut self.state
    }

    /// Whether to keep the directional pressures `p̄` of every sweep (the coupling needs them,
    /// a fluid-only run does not; off by default). Turning it on allocates one value per cell
    /// and axis, zero until the next step.
    pub fn keep_directional_pressures(&mut self, keep: bool) {
        let n = self.grid.n_cells();
        self.pbar = if keep {
            (0..self.grid.dim).map(|_| vec![0.0; n]).collect()
        } else {
            Vec::new()
        };
    }

    /// Simulated time \[s\].
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Steps taken so far (selects the sweep permutation of the next step).
    pub fn steps(&self) -> u64 {
        self.step
    }

    /// Density [kg/m³], velocity [m/s] (inactive axes 0) and pressure \[Pa\] of cell `idx`.
    pub fn primitive(&self, idx: usize) -> (f64, [f64; 3], f64) {
        self.state.primitive(idx, self.params.gamma)
    }

    /// Directional pressures `p̄_axis` \[Pa\] of the last step, one per cell: the pressure of the
    /// state each sweep along `axis` started from (paper 003 §3.4 step 1). Zero before the
    /// first step; `None` unless [`FluidSolver::keep_directional_pressures`] turned them on.
    /// Panics if `axis >= dim` (a bug in the caller).
    pub fn directional_pressures(&self, axis: usize) -> Option<&[f64]> {
        assert!(
            axis < self.grid.dim,
            "axis {axis} of a {}-D grid",
            self.grid.dim
        );
        self.pbar.get(axis).map(Vec::as_slice)
    }

    /// Heap bytes of the per-cell and per-pencil buffers (capacities): the state, the sweep
    /// buffer, the directional pressures when kept, and the pencil reports. Not counted: the
    /// contents of the per-thread line scratch (O(cells of one line) each) and the thread pool.
    pub fn memory_bytes(&self) -> usize {
        vec_bytes(&self.state.u)
            + vec_bytes(&self.buffer)
            + vec_bytes(&self.pbar)
            + self.pbar.iter().map(vec_bytes).sum::<usize>()
            + vec_bytes(&self.pencil_out)
            + vec_bytes(&self.scratch)
            + self.halo.iter().map(vec_bytes).sum::<usize>()
    }

    /// Largest stable time step \[s\]: `cfl / max_cells max_axis (|u_axis| + c)/Δx_axis`, so that
    /// every directional sweep runs at Courant number ≤ `cfl`. Infinite for a fluid at rest
    /// with zero sound speed everywhere; NaN if a cell is non-finite. Computed once per state.
    pub fn max_dt(&self) -> f64 {
        self.dt_cache.get_or_init(|| self.compute_max_dt()).0
    }

    /// The cell that limits [`FluidSolver::max_dt`] (index into the whole grid,
    /// [`FluidSolver::global_grid`]; the first such cell, or the first non-finite one).
    pub fn limiting_cell(&self) -> usize {
        self.dt_cache.get_or_init(|| self.compute_max_dt()).1
    }

    /// `(max_dt, limiting cell)`; the reduction keeps the largest rate and, among equal ones,
    /// the lowest cell index, so the cell does not depend on the thread or rank count (a max
    /// is exact in any order).
    fn compute_max_dt(&self) -> (f64, usize) {
        let grid = &self.grid;
        let gamma = self.params.gamma;
        let vacuum_rho = self.params.vacuum_rho;
        let vacuum_p = self.params.vacuum_p;
        let nvar = self.state.nvar;
        let dim = grid.dim;
        let u = &self.state.u;
        let (rate, cell) = self.pool.install(|| {
            u.par_chunks(nvar * BLOCK_CELLS)
                .enumerate()
                .map(|(block, chunk)| {
                    let mut acc: (f64, usize) = (0.0, block * BLOCK_CELLS);
                    for (k, cell) in chunk.chunks_exact(nvar).enumerate() {
                        let idx = block * BLOCK_CELLS + k;
                        let w = crate::fv::euler::primitive_floored(
                            &to_full(cell, dim),
                            gamma,
                            vacuum_rho,
                        );
                        // Below the vacuum density and pressure, ρ, ρu and E are round-off (a
                        // covered cell beside a crack held ρ = 2e-30 and E = 1e-16, a sound
                        // speed of 5e6 m/s that collapsed the step): its speeds are taken at the
                        // vacuum density, as its velocity is. A gas of real pressure at such a
                        // density keeps its sound speed, so that its collapsing step stops the
                        // run (issue 11).
                        let floor = w.rho < vacuum_rho && w.p < vacuum_p;
                        let c = sound_speed(
                            &crate::fv::euler::Primitive {
                                rho: if floor { vacuum_rho } else { w.rho },
                                ..w
                            },
                            gamma,
                        );
                        for a in 0..dim {
                            let r = (w.vel[a].abs() + c) / grid.dx[a];
                            if !r.is_finite() {
                                return (f64::NAN, idx);
                            }
                            if r > acc.0 {
                                acc = (r, idx);
                            }
                        }
                    }
                    acc
                })
                .reduce(|| (0.0, usize::MAX), fastest)
        });
        let global = &self.slab.global;
        let mut best = (rate, self.slab.to_global(cell.min(grid.n_cells() - 1)));
        if self.slab.ranks > 1 {
            let mine = f64_bytes(&[best.0, best.1 as f64]);
            best = self
                .comm
                .all_gather(&mine)
                .iter()
                .map(|b| {
                    let v = bytes_f64(b);
                    (v[0], v[1] as usize)
                })
                .fold((0.0, usize::MAX), fastest);
        }
        (
            self.params.cfl / best.0,
            best.1.min(global.n_cells().saturating_sub(1)),
        )
    }

    /// Advances by one split step of length `dt` \[s\]: one full-`dt` sweep per active axis, in
    /// the order [`sweep_order`] gives for the current step number. Never panics on numerical
    /// trouble: it is listed in the report and the caller stops the run.
    pub fn advance(&mut self, dt: f64) -> StepReport {
        let mut report = self.sweeps(dt, None);
        report.totals = self.totals();
        report
    }

    /// The predict of a coupled step (paper 003 §3.4 step 1): the split sweeps of
    /// [`FluidSolver::advance`] over the whole grid, with the ghost states, pressures and face
    /// fluxes `hooks` asks for. Cells for which `covered` is true hold ghost states and are not
    /// checked. The report's totals are left empty: the embedded update corrects the cells near
    /// the solid afterwards, and its totals weigh cells by their fluid fraction.
    ///
    /// `hooks` and `covered` name cells of the whole grid ([`FluidSolver::global_grid`]): each
    /// rank applies the ghosts and vacuum of its own cells and keeps the pressures and fluxes of
    /// its own cells and faces, and the outputs are gathered, so that every rank ends with all
    /// of them (collective).
    pub fn predict(
        &mut self,
        dt: f64,
        hooks: &mut SplitHooks,
        covered: &dyn Fn(usize) -> bool,
    ) -> StepReport {
        self.sweeps(dt, Some((hooks, covered)))
    }

    fn sweeps(
        &mut self,
        dt: f64,
        mut hooks: Option<(&mut SplitHooks, &dyn Fn(usize) -> bool)>,
    ) -> StepReport {
        let order = sweep_order(self.grid.dim, self.step);
        let mut report = StepReport {
            step: self.step,
            dt,
            time: self.time,
            sweeps: order.clone(),
            ..StepReport::default()
        };
        let limit = self.max_dt() / self.params.cfl;
        if !(dt.is_finite() && dt > 0.0 && dt <= limit * (1.0 + 1e-12)) {
            report.troubles.push(Trouble {
                kind: TroubleKind::TimeStep,
                axis: 0,
                cell: [0; 3],
                position: [0.0; 3],
                rho: dt,
                velocity: [0.0; 3],
                p: limit,
            });
            return report;
        }
        let area_dt: Vec<f64> = (0..self.grid.dim)
            .map(|a| dt * self.grid.cell_volume() / self.grid.dx[a])
            .collect();
        self.dt_cache = OnceLock::new();
        let mut summaries: Vec<SweepSummary> = Vec::with_capacity(order.len());
        for &axis in &order {
            self.record_pressures(axis);
            if let Some((h, _)) = hooks.as_mut() {
                self.apply_ghosts(axis, &h.ghosts[axis]);
                self.apply_vacuum(&h.vacuum);
                self.record_pressures_at(&h.pressure_cells, &mut h.pressures[axis]);
                self.local
                    .localize(&self.slab, axis, &h.taps[axis], &h.walls[axis]);
            }
            let along_slab = axis == self.slab.axis && self.slab.decomposed();
            if along_slab {
                self.exchange_halo();
            }
            let grid = &self.grid;
            let params = &self.params;
            let (u, buffer) = (&self.state.u, &mut self.buffer);
            let (scratch, pencil_out) = (&self.scratch, &mut self.pencil_out);
            let (tap, walls) = match hooks.as_mut() {
                Some(_) => (
                    Some(&mut self.local.taps[axis]),
                    &self.local.walls[axis][..],
                ),
                None => (None, &[][..]),
            };
            let slab = &self.slab;
            let halo = if along_slab {
                let below = if slab.lo.is_some() { slab.overlap } else { 0 };
                SlabHalo {
                    lo: slab.lo.map(|_| &self.halo[0][..]),
                    hi: slab.hi.map(|_| &self.halo[1][..]),
                    depth: slab.depth,
                    overlap: slab.overlap,
                    n_global: slab.global.cells[axis],
                    start: slab.offset as isize - below as isize,
                }
            } else {
                SlabHalo::none(grid.cells[axis])
            };
            self.pool.install(|| {
                sweep_axis(
                    grid, params, axis, dt, u, buffer, scratch, pencil_out, tap, walls, &halo,
                );
            });
            if axis == 0 {
                std::mem::swap(&mut self.state.u, &mut self.buffer);
            } else {
                let (src, dst) = (&self.buffer, &mut self.state.u);
                self.pool.install(|| pencil_to_cells(grid, axis, src, dst));
            }
            let count = self.grid.n_cells() / self.grid.cells[axis];
            let mut summary = SweepSummary::default();
            let reps = &self.pencil_out[..count];
            let area = area_dt[axis];
            let slab = &self.slab;
            // Outflow partials, each a sum in pencil order (see `SweepSummary::partials`).
            let (per_plane, first_pencil) = if axis == slab.axis {
                (count, 0)
            } else {
                let per_plane = count / self.grid.cells[slab.axis];
                (per_plane, slab.offset * per_plane)
            };
            if axis == slab.axis {
                let bc = self.params.boundary[axis];
                let mine = [
                    bc[0] != BoundaryKind::Periodic && slab.lo.is_none(),
                    bc[1] != BoundaryKind::Periodic && slab.hi.is_none(),
                ];
                for side in 0..2 {
                    if mine[side] {
                        let mut acc = [0.0; NQ];
                        for rep in reps {
                            for q in 0..NQ {
                                acc[q] += area * rep.outflow[side][q];
                            }
                        }
                        summary.partials.push(acc);
                    }
                }
            } else {
                for plane in reps.chunks(per_plane) {
                    let mut acc = [0.0; NQ];
                    for rep in plane {
                        for q in 0..NQ {
                            acc[q] += area * (rep.outflow[0][q] + rep.outflow[1][q]);
                        }
                    }
                    summary.partials.push(acc);
                }
            }
            for (p, rep) in reps.iter().enumerate() {
                summary.lax_friedrichs += u64::from(rep.stats.lax_friedrichs);
                summary.hlle += u64::from(rep.stats.hlle);
                summary.positivity_fixes += u64::from(rep.stats.positivity_fixes);
                if let Some(idx) = rep.trouble
                    && summary.troubles.len() < MAX_TROUBLES
                {
                    let found = match &hooks {
                        Some((_, covered)) => self.first_checked_trouble(axis, idx, *covered),
                        None => Some(idx),
                    };
                    if let Some(idx) = found {
                        let pencil = (first_pencil + p) as u64;
                        summary.troubles.push((pencil, self.trouble_at(idx, axis)));
                    }
                }
            }
            summaries.push(summary);
        }
        if let Some((h, _)) = hooks.as_mut() {
            self.gather_hook_outputs(h, &order);
        }
        self.merge_summaries(summaries, &mut report);
        for q in 0..NQ {
            self.outflow[q] += report.outflow[q];
        }
        self.step += 1;
        self.time += dt;
        report.time = self.time;
        report
    }

    /// Adds the sweeps' summaries of every rank to `report` in a fixed order: sweep by sweep,
    /// the partials in rank order (= plane order), the troubles by pencil (on the slab axis,
    /// the lowest rank's trouble of a pencil is the one nearest its start).
    fn merge_summaries(&self, mine: Vec<SweepSummary>, report: &mut StepReport) {
        let all: Vec<Vec<SweepSummary>> = if self.slab.ranks == 1 {
            vec![mine]
        } else {
            let bytes = protocol::codec::encode_blob(&mine);
            self.comm
                .all_gather(&bytes)
                .iter()
                .map(|b| protocol::codec::decode_blob(b).expect("ranks send valid summaries"))
                .collect()
        };
        let n_sweeps = all[0].len();
        for sweep in 0..n_sweeps {
            let mut troubles: Vec<(u64, Trouble)> = Vec::new();
            for rank in &all {
                let s = &rank[sweep];
                for partial in &s.partials {
                    for q in 0..NQ {
                        report.outflow[q] += partial[q];
                    }
                }
                report.lax_friedrichs_faces += s.lax_friedrichs;
                report.hlle_faces += s.hlle;
                report.positivity_fixes += s.positivity_fixes;
                troubles.extend(s.troubles.iter().copied());
            }
            // Stable: among equal pencils the lowest rank stays first.
            troubles.sort_by_key(|(pencil, _)| *pencil);
            troubles.dedup_by_key(|(pencil, _)| *pencil);
            for (_, t) in troubles {
                if report.troubles.len() < MAX_TROUBLES {
                    report.troubles.push(t);
                }
            }
        }
    }

    /// The first troubled cell of the pencil through `idx` along `axis` that is not covered
    /// (`idx` itself when it is not; `covered` takes cells of the whole grid).
    fn first_checked_trouble(
        &self,
        axis: usize,
        idx: usize,
        covered: &dyn Fn(usize) -> bool,
    ) -> Option<usize> {
        let global = |c: usize| covered(self.slab.to_global(c));
        if !global(idx) {
            return Some(idx);
        }
        let pencils = Pencils::new(&self.grid, axis);
        let base = idx - self.grid.ijk(idx)[axis] * pencils.stride;
        let gamma = self.params.gamma;
        (0..pencils.n)
            .map(|m| base + m * pencils.stride)
            .filter(|&c| !global(c))
            .find(|&c| {
                let full = to_full(self.state.cell(c), self.grid.dim);
                !state_ok(&full, gamma, self.params.vacuum_rho, self.params.vacuum_p)
            })
    }

    /// Advances with CFL-limited steps until `t_end` \[s\] (the last step is shortened to land on
    /// it) or `max_steps` steps or the first trouble; returns the last report and the steps
    /// taken.
    pub fn run_until(&mut self, t_end: f64, max_steps: u64) -> (u64, StepReport) {
        let mut steps = 0;
        let mut last = StepReport::default();
        while self.time < t_end * (1.0 - 1e-14) && steps < max_steps {
            let dt = self.max_dt().min(t_end - self.time);
            last = self.advance(dt);
            steps += 1;
            if !last.ok() {
                break;
            }
        }
        (steps, last)
    }

    fn record_pressures(&mut self, axis: usize) {
        if self.pbar.is_empty() {
            return;
        }
        let nvar = self.state.nvar;
        let dim = self.grid.dim;
        let gamma = self.params.gamma;
        let (u, pbar) = (&self.state.u, &mut self.pbar[axis]);
        self.pool.install(|| {
            pbar.par_chunks_mut(BLOCK_CELLS)
                .zip(u.par_chunks(BLOCK_CELLS * nvar))
                .for_each(|(p, cells)| {
                    for (p, cell) in p.iter_mut().zip(cells.chunks_exact(nvar)) {
                        *p = cell_primitive(cell, dim, gamma).p;
                    }
                });
        });
    }

    fn trouble_at(&self, idx: usize, axis: usize) -> Trouble {
        let (rho, velocity, p) = self.primitive(idx);
        let cell = self.state.cell(idx);
        let kind = if cell.iter().any(|x| !x.is_finite()) || !p.is_finite() {
            TroubleKind::NonFinite
        } else if rho < 0.0 || (rho <= 0.0 && self.params.vacuum_rho <= 0.0) {
            TroubleKind::Density
        } else {
            TroubleKind::Pressure
        };
        let global = &self.slab.global;
        let ijk = global.ijk(self.slab.to_global(idx));
        Trouble {
            kind,
            axis,
            cell: ijk,
            position: global.cell_center(ijk),
            rho,
            velocity,
            p,
        }
    }

    /// Conserved totals over the whole grid, summed in a fixed order (each plane of the slab
    /// axis, then the planes in order), so the result does not depend on the thread or rank
    /// count.
    pub fn totals(&self) -> Totals {
        self.totals_by(None)
    }

    /// Conserved totals of the fluid around an embedded solid: each cell weighted by its fluid
    /// fraction `1 − Λ` (`solid_fraction` one value per cell; cells with Λ = 1 hold ghost states
    /// and count for nothing). Same fixed-order sums as [`FluidSolver::totals`].
    pub fn totals_with_solid(&self, solid_fraction: &[f64]) -> Totals {
        assert_eq!(solid_fraction.len(), self.grid.n_cells(), "one Λ per cell");
        self.totals_by(Some(solid_fraction))
    }

    fn totals_by(&self, solid_fraction: Option<&[f64]>) -> Totals {
        let nvar = self.state.nvar;
        let dim = self.grid.dim;
        let plane = self.slab.plane();
        // NOTE: compensated sums per plane and over planes, so that the totals are exact to a
        // few ulps and a conservation check measures the scheme, not the sum; planes of the
        // slab axis are the blocks, so that a rank sums whole blocks.
        let mut partial = vec![[CompensatedSum::default(); NQ]; self.grid.cells[self.slab.axis]];
        let u = &self.state.u;
        self.pool.install(|| {
            partial
                .par_iter_mut()
                .zip(u.par_chunks(plane * nvar))
                .enumerate()
                .for_each(|(block, (acc, cells))| match solid_fraction {
                    None => {
                        for cell in cells.chunks_exact(nvar) {
                            acc[0].add(cell[0]);
                            for a in 0..dim {
                                acc[1 + a].add(cell[1 + a]);
                            }
                            acc[4].add(cell[dim + 1]);
                        }
                    }
                    Some(lambda) => {
                        let lambda = &lambda[block * plane..];
                        for (cell, l) in cells.chunks_exact(nvar).zip(lambda) {
                            let alpha = 1.0 - l;
                            if alpha <= 0.0 {
                                continue;
                            }
                            acc[0].add(alpha * cell[0]);
                            for a in 0..dim {
                                acc[1 + a].add(alpha * cell[1 + a]);
                            }
                            acc[4].add(alpha * cell[dim + 1]);
                        }
                    }
                });
        });
        let flat: Vec<f64> = partial
            .iter()
            .flat_map(|acc| acc.iter().flat_map(|c| [c.sum, c.comp]))
            .collect();
        let flat = if self.slab.ranks == 1 {
            flat
        } else {
            self.comm
                .all_gather(&f64_bytes(&flat))
                .iter()
                .flat_map(|b| bytes_f64(b))
                .collect()
        };
        let mut total = [CompensatedSum::default(); NQ];
        for acc in flat.chunks_exact(2 * NQ) {
            for q in 0..NQ {
                total[q].add(acc[2 * q]);
                total[q].add(acc[2 * q + 1]);
            }
        }
        let sum: [f64; NQ] = std::array::from_fn(|q| total[q].value());
        let v = self.grid.cell_volume();
        Totals {
            mass: sum[0] * v,
            momentum: [sum[1] * v, sum[2] * v, sum[3] * v],
            energy: sum[4] * v,
            outflow_mass: self.outflow[0],
            outflow_momentum: [self.outflow[1], self.outflow[2], self.outflow[3]],
            outflow_energy: self.outflow[4],
        }
    }

    /// The whole grid's conserved state, gathered on rank 0 (`None` on the other ranks;
    /// collective). On one rank a copy of [`FluidSolver::state`].
    pub fn gather_state(&self) -> Option<FluidState> {
        let nvar = self.state.nvar;
        let u = self.gather_cells(&self.state.u)?;
        Some(FluidState { nvar, u })
    }

    /// Per-cell values of every rank concatenated in rank order (the global order) on rank 0.
    fn gather_cells(&self, mine: &[f64]) -> Option<Vec<f64>> {
        if self.slab.ranks == 1 {
            return Some(mine.to_vec());
        }
        let parts = self.comm.gather(0, &f64_bytes(mine))?;
        Some(parts.iter().flat_map(|b| bytes_f64(b)).collect())
    }

    /// Whether every cell of this rank is physical (see `line::state_ok`); the first bad cell
    /// otherwise.
    pub fn check_state(&self) -> Option<Trouble> {
        let gamma = self.params.gamma;
        (0..self.grid.n_cells())
            .find(|&idx| {
                let full = to_full(self.state.cell(idx), self.grid.dim);
                !state_ok(&full, gamma, self.params.vacuum_rho, self.params.vacuum_p)
            })
            .map(|idx| self.trouble_at(idx, 0))
    }

    /// Node-private checkpoint bytes: state, step counter, time, outflow and directional
    /// pressures (encoded with `protocol::codec::encode_blob`). Collective: the whole grid is
    /// gathered on rank 0, which gets the bytes one rank would write; the other ranks get none.
    pub fn to_checkpoint(&self) -> Vec<u8> {
        let u = self.gather_cells(&self.state.u);
        let pbar: Vec<Option<Vec<f64>>> = self.pbar.iter().map(|p| self.gather_cells(p)).collect();
        let Some(u) = u else {
            return Vec::new();
        };
        let c = Checkpoint {
            version: CHECKPOINT_VERSION,
            cells: self.slab.global.cells.map(|n| n as u64),
            step: self.step,
            time: self.time,
            u,
            outflow: self.outflow,
            pbar: pbar.into_iter().flatten().collect(),
        };
        protocol::codec::encode_blob(&c)
    }

    /// Restores a checkpoint written by [`FluidSolver::to_checkpoint`] for the same grid (every
    /// rank passes the whole checkpoint and keeps its slab, so any rank count restores it).
    pub fn restore_checkpoint(&mut self, bytes: &[u8]) -> Result<(), String> {
        let c: Checkpoint = protocol::codec::decode_blob(bytes)?;
        if c.version != CHECKPOINT_VERSION {
            return Err(format!(
                "checkpoint version {} (expected {CHECKPOINT_VERSION})",
                c.version
            ));
        }
        let global = &self.slab.global;
        let cells = global.cells.map(|n| n as u64);
        let nvar = self.state.nvar;
        if c.cells != cells
            || c.u.len() != nvar * global.n_cells()
            || (!c.pbar.is_empty() && c.pbar.len() != self.grid.dim)
            || c.pbar.iter().any(|p| p.len() != global.n_cells())
        {
            return Err(format!(
                "checkpoint for grid {:?} with {} values, this solver has {:?} with {}",
                c.cells,
                c.u.len(),
                cells,
                nvar * global.n_cells()
            ));
        }
        let range = self.slab.global_range();
        self.state
            .u
            .copy_from_slice(&c.u[range.start * nvar..range.end * nvar]);
        self.step = c.step;
        self.time = c.time;
        self.outflow = c.outflow;
        // Directional pressures come back only where this solver keeps them.
        if !self.pbar.is_empty() {
            if c.pbar.is_empty() {
                self.keep_directional_pressures(true);
            } else {
                self.pbar = c.pbar.iter().map(|p| p[range.clone()].to_vec()).collect();
            }
        }
        self.dt_cache = OnceLock::new();
        Ok(())
    }
}

/// The faster of two `(rate, cell)` candidates of the CFL step: a NaN rate first (the lowest
/// cell among NaNs), else the larger rate, the lower cell among equal ones.
fn fastest(a: (f64, usize), b: (f64, usize)) -> (f64, usize) {
    match (a.0.is_nan(), b.0.is_nan()) {
        (true, true) => {
            if a.1 <= b.1 {
                a
            } else {
                b
            }
        }
        (true, false) => a,
        (false, true) => b,
        _ if a.0 > b.0 || (a.0 == b.0 && a.1 <= b.1) => a,
        _ => b,
    }
}

/// Compensated sum: the running sum and the sum of its exact rounding errors.
#[derive(Clone, Copy, Debug, Default)]
struct CompensatedSum {
    sum: f64,
    comp: f64,
}

impl CompensatedSum {
    #[inline]
    fn add(&mut self, x: f64) {
        // Knuth's branch-free TwoSum: `err` is the exact rounding error of `sum + x` (the value
        // Neumaier's branching form computes too, without the branch).
        let t = self.sum + x;
        let z = t - self.sum;
        let err = (self.sum - (t - z)) + (x - z);
        self.comp += err;
        self.sum = t;
    }

    fn value(&self) -> f64 {
        self.sum + self.comp
    }
}

/// A storage cell as a 5-component state `(ρ, ρu_x, ρu_y, ρu_z, E)`.
#[inline]
fn to_full(cell: &[f64], dim: usize) -> [f64; NQ] {
    let mut s = [0.0; NQ];
    s[0] = cell[0];
    // NOTE: an indexed loop, not `copy_from_slice`: a run-time length makes that a `memmove`
    // call per cell.
    #[allow(clippy::manual_memcpy)]
    for a in 0..dim {
        s[1 + a] = cell[1 + a];
    }
    s[4] = cell[dim + 1];
    s
}

#[inline]
fn cell_primitive(cell: &[f64], dim: usize, gamma: f64) -> Primitive {
    crate::fv::euler::primitive(&to_full(cell, dim), gamma)
}
