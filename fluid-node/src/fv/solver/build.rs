//! [`FluidSolver`]: its fields (state, scratch buffers, worker pool), its construction and
//! its accessors.

use std::sync::{Mutex, OnceLock};

use protocol::scene::FluidConfig;

use crate::fv::comm::{Comm, Serial};
use crate::fv::euler::NQ;
use crate::fv::isa::Isa;
use crate::fv::line::{FluxKind, LineScratch};
use crate::fv::scene::{ConfigError, from_scene, init_by_block, regions_of_block, validated};
use crate::fv::slab::{Slab, SlabError, take_block};
use crate::fv::solver::hooks::LocalHooks;
use crate::fv::solver::pages;
use crate::fv::state::{FluidParams, FluidState};
use crate::fv::sweep::PencilOut;
use crate::grid::Grid;
use crate::memory::vec_bytes;

/// Why a solver cannot be built.
#[derive(Debug, thiserror::Error)]
pub enum SolverError {
    /// The scene's `[fluid]` table is invalid.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// A state that does not fit the grid.
    #[error(
        "state has {values} values ({per_cell} per cell), grid needs {needed_per_cell} per cell \
         for {cells} cells"
    )]
    StateSize {
        /// Values in the state.
        values: usize,
        /// Values per cell of the state.
        per_cell: usize,
        /// Values per cell the grid needs (`dim + 2`).
        needed_per_cell: usize,
        /// Cells of the grid.
        cells: usize,
    },
    /// An OSMP order other than 3, 5 or 7.
    #[error("osmp order must be 3, 5 or 7, got {order}")]
    FluxOrder {
        /// The order given.
        order: u32,
    },
    /// The grid cannot be decomposed over the ranks.
    #[error(transparent)]
    Slab(#[from] SlabError),
    /// The worker pool could not be built.
    #[error("building a pool of {threads} threads: {source}")]
    ThreadPool {
        /// Threads asked for.
        threads: usize,
        /// Rayon's reason.
        source: rayon::ThreadPoolBuildError,
    },
}

/// The finite-volume Euler solver on a Cartesian grid of 1, 2 or 3 dimensions, on one rank or
/// on one block of a grid decomposed over several ([`Slab`], [`Comm`]).
pub struct FluidSolver {
    /// This rank's cells (the whole grid on one rank).
    pub(super) grid: Grid,
    pub(super) slab: Slab,
    pub(super) comm: Box<dyn Comm>,
    /// Per axis: halo planes of the neighbours below and above (empty without neighbours),
    /// x-fastest in the order of the pencils along that axis, lowest plane first.
    pub(super) halo: [[Vec<f64>; 2]; 3],
    /// This rank's planes sent to the neighbours along an axis other than the last (scratch).
    pub(super) halo_send: [Vec<f64>; 2],
    /// The [`SplitHooks`](crate::fv::SplitHooks) of a coupled step on this rank's slab (scratch).
    pub(super) local: LocalHooks,
    pub(super) params: FluidParams,
    pub(super) state: FluidState,
    pub(super) buffer: Vec<f64>,
    pub(super) pencil_out: Vec<PencilOut>,
    pub(super) scratch: Vec<Mutex<LineScratch>>,
    pub(super) pool: rayon::ThreadPool,
    /// `p̄` per active axis, or empty when not kept (see [`FluidSolver::keep_directional_pressures`]).
    pub(super) pbar: Vec<Vec<f64>>,
    /// `max_dt` of the current state and the cell that limits it, once computed (reset whenever
    /// the state changes).
    pub(super) dt_cache: OnceLock<(f64, usize)>,
    /// The compensated sums of the conserved totals of the current state, once computed (one
    /// rank; reset whenever the state changes, ghost states and vacuum cells included).
    pub(super) sums_cache: OnceLock<[f64; NQ]>,
    pub(super) step: u64,
    pub(super) time: f64,
    pub(super) outflow: [f64; NQ],
}

impl FluidSolver {
    /// Builds the solver from the scene's `[fluid]` table with `threads` worker threads
    /// (results do not depend on it).
    pub fn from_scene(cfg: &FluidConfig, threads: usize) -> Result<FluidSolver, SolverError> {
        let (grid, params, state) = from_scene(cfg)?;
        FluidSolver::new(grid, params, state, threads)
    }

    /// Builds this rank's block of the solver of the scene's `[fluid]` table, the grid
    /// decomposed over the ranks of `comm` as `fluid.decomposition` says, or as
    /// [`protocol::decomp::choose`] chooses (see [`FluidSolver::decomposed`]).
    pub fn from_scene_on(
        cfg: &FluidConfig,
        threads: usize,
        comm: Box<dyn Comm>,
    ) -> Result<FluidSolver, SolverError> {
        // A given process grid is checked by `decomposed_as` (an error, not the default).
        let dims = cfg
            .decomposition
            .as_ref()
            .map(|d| std::array::from_fn(|a| d.get(a).map_or(1, |&k| k as usize)));
        if comm.size() > 1 && init_by_block(cfg) {
            return FluidSolver::from_regions_by_block(cfg, threads, comm, dims);
        }
        let (grid, params, state) = from_scene(cfg)?;
        FluidSolver::decomposed_as(grid, params, state, threads, comm, dims)
    }

    /// [`FluidSolver::from_scene_on`] of a scene whose initial state is its `[[fluid.init]]`
    /// regions ([`init_by_block`]) on several ranks: each rank builds its block's cells only
    /// (the whole grid's state on every rank was about 0.3 G instructions a rank at 100³, more
    /// than half of one rank's start). Collective: the first cell no region covers, in the
    /// grid's order, is the error of every rank, as on one rank (reported after an error of
    /// the process grid, which one rank does not check).
    fn from_regions_by_block(
        cfg: &FluidConfig,
        threads: usize,
        comm: Box<dyn Comm>,
        dims: Option<[usize; 3]>,
    ) -> Result<FluidSolver, SolverError> {
        let (grid, params) = validated(cfg)?;
        let slab = decompose(&grid, &params, comm.as_ref(), dims)?;
        let state = regions_of_block(cfg, &grid, params.gamma, slab.block_of_rank(slab.rank));
        let uncovered = match &state {
            Err(ConfigError::Uncovered { cell, .. }) => grid.index(cell[0], cell[1], cell[2]),
            _ => usize::MAX,
        } as u64;
        let first = (comm.all_gather(&uncovered.to_le_bytes()).iter())
            .map(|b| u64::from_le_bytes(b[..8].try_into().expect("8 bytes")))
            .min()
            .unwrap_or(u64::MAX);
        if first != u64::MAX {
            let cell = grid.ijk(first as usize);
            let position = grid.cell_center(cell)[..grid.dim].to_vec();
            return Err(ConfigError::Uncovered { cell, position }.into());
        }
        FluidSolver::on_block(params, state?, threads, comm, slab)
    }

    /// Builds the solver from parts (`state` must have `grid.dim + 2` values per cell).
    pub fn new(
        grid: Grid,
        params: FluidParams,
        state: FluidState,
        threads: usize,
    ) -> Result<FluidSolver, SolverError> {
        FluidSolver::decomposed(grid, params, state, threads, Box::new(Serial))
    }

    /// Builds this rank's block of a solver over the ranks of `comm`: `grid` and `state` are the
    /// whole grid's (every rank builds the same), the rank keeps its block ([`Slab`], the
    /// process grid of [`protocol::decomp::choose`]). Every method that reduces over the grid (the step, the CFL step, the
    /// totals, checkpoints, [`FluidSolver::gather_state`]) is then collective: every rank calls
    /// it, in the same order.
    pub fn decomposed(
        grid: Grid,
        params: FluidParams,
        state: FluidState,
        threads: usize,
        comm: Box<dyn Comm>,
    ) -> Result<FluidSolver, SolverError> {
        FluidSolver::decomposed_as(grid, params, state, threads, comm, None)
    }

    /// [`FluidSolver::decomposed`] with the process grid `dims` (blocks per axis, their
    /// product the ranks of `comm`; `None`: [`protocol::decomp::choose`]).
    pub fn decomposed_as(
        grid: Grid,
        params: FluidParams,
        state: FluidState,
        threads: usize,
        comm: Box<dyn Comm>,
        dims: Option<[usize; 3]>,
    ) -> Result<FluidSolver, SolverError> {
        if state.nvar != grid.dim + 2 || state.u.len() != state.nvar * grid.n_cells() {
            return Err(SolverError::StateSize {
                values: state.u.len(),
                per_cell: state.nvar,
                needed_per_cell: grid.dim + 2,
                cells: grid.n_cells(),
            });
        }
        if let FluxKind::Osmp(order) = params.flux
            && ![3, 5, 7].contains(&order)
        {
            return Err(SolverError::FluxOrder { order });
        }
        let slab = decompose(&grid, &params, comm.as_ref(), dims)?;
        let nvar = state.nvar;
        let state = if slab.ranks == 1 {
            state
        } else {
            FluidState {
                nvar,
                u: take_block(&grid, slab.block_of_rank(slab.rank), nvar, &state.u),
            }
        };
        FluidSolver::on_block(params, state, threads, comm, slab)
    }

    /// The solver of the block `slab` from its cells' state `state` (the whole grid's on one
    /// rank).
    fn on_block(
        params: FluidParams,
        state: FluidState,
        threads: usize,
        comm: Box<dyn Comm>,
        slab: Slab,
    ) -> Result<FluidSolver, SolverError> {
        let nvar = state.nvar;
        let grid = slab.local.clone();
        let halo = std::array::from_fn(|a| {
            let len = slab.depth * (grid.n_cells() / grid.cells[a]) * nvar;
            [slab.lo[a], slab.hi[a]].map(|n| {
                if n.is_some() {
                    vec![0.0; len]
                } else {
                    Vec::new()
                }
            })
        });
        let threads = threads.max(1);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(|source| SolverError::ThreadPool { threads, source })?;
        let max_pencils = (0..grid.dim)
            .map(|a| grid.n_cells() / grid.cells[a])
            .max()
            .unwrap_or(1);
        let mut state = state;
        state.u = pages::huge_vec(state.u.len(), Some(&state.u));
        Ok(FluidSolver {
            slab,
            comm,
            halo,
            halo_send: [Vec::new(), Vec::new()],
            local: LocalHooks::default(),
            buffer: pages::huge_vec(state.u.len(), None),
            pencil_out: vec![PencilOut::default(); max_pencils],
            scratch: (0..threads)
                .map(|_| Mutex::new(LineScratch::default()))
                .collect(),
            pool,
            pbar: Vec::new(),
            dt_cache: OnceLock::new(),
            sums_cache: OnceLock::new(),
            grid,
            params,
            state,
            step: 0,
            time: 0.0,
            outflow: [0.0; NQ],
        })
    }

    /// Runs the line kernel on `isa` from now on ([`Isa::best`] by default); every ISA gives
    /// the same bits (`fv::isa`), so this is for the tests that check it and for benchmarks.
    ///
    /// # Panics
    /// If this CPU does not have `isa` ([`Isa::supported`]).
    pub fn set_isa(&mut self, isa: Isa) {
        for s in &self.scratch {
            s.lock()
                .unwrap_or_else(|poisoned| poisoned.into_inner())
                .set_isa(isa);
        }
    }
    /// Runs `op` on this solver's thread pool (its `threads`), so that the rayon work it starts
    /// (the embedded part's parallel loops) uses the scene's thread count.
    pub fn install<R: Send>(&self, op: impl FnOnce() -> R + Send) -> R {
        self.pool.install(op)
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
        self.sums_cache = OnceLock::new();
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
            + self.halo.iter().flatten().map(vec_bytes).sum::<usize>()
            + self.halo_send.iter().map(vec_bytes).sum::<usize>()
    }
}

/// This rank's block of `grid` on the ranks of `comm`: the process grid `dims` (checked) or
/// the one [`protocol::decomp::choose`] chooses; the whole grid on one rank.
fn decompose(
    grid: &Grid,
    params: &FluidParams,
    comm: &dyn Comm,
    dims: Option<[usize; 3]>,
) -> Result<Slab, SolverError> {
    if comm.size() == 1 {
        return Ok(Slab::whole(grid));
    }
    let (ranks, depth) = (
        comm.size(),
        params.ghost_cells() + crate::fv::line::MAX_FIXES,
    );
    let cells = &grid.cells[..grid.dim];
    let dims = match dims {
        Some(dims) => protocol::decomp::check(cells, ranks, dims, depth).map(|()| dims),
        None => protocol::decomp::choose(cells, ranks, depth),
    }
    .map_err(|source| SlabError::Decomposition { ranks, source })?;
    Ok(Slab::new(
        grid,
        comm.rank(),
        dims,
        params.ghost_cells(),
        params.boundary,
    )?)
}
