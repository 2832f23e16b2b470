//! The CFL step of the current state: [`FluidSolver::max_dt`] and the cell that limits it.

use rayon::prelude::*;

use crate::fv::comm::{bytes_f64, f64_bytes};
use crate::fv::euler::sound_speed;
use crate::fv::isa::Isa;
use crate::fv::solver::FluidSolver;
use crate::fv::solver::cell::{BLOCK_CELLS, items_per_task, to_full};

impl FluidSolver {
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
        let (nvar, rates, isa) = (self.state.nvar, self.rate_params(), self.rate_isa());
        let u = &self.state.u;
        let (rate, cell) = self.pool.install(|| {
            u.par_chunks(nvar * BLOCK_CELLS)
                .enumerate()
                .with_max_len(items_per_task(BLOCK_CELLS))
                .map(|(block, chunk)| fastest_cell(isa, nvar, &rates, chunk, block * BLOCK_CELLS))
                .reduce(|| (0.0, usize::MAX), fastest)
        });
        self.finish_max_dt((rate, cell))
    }

    /// The instruction set the rates are taken on: the line kernel's.
    pub(super) fn rate_isa(&self) -> Isa {
        self.scratch.first().map_or(Isa::Baseline, |s| {
            s.lock()
                .unwrap_or_else(|poisoned| poisoned.into_inner())
                .isa()
        })
    }

    /// What [`RateParams::cell_rate`] needs of this solver.
    pub(super) fn rate_params(&self) -> RateParams<'_> {
        RateParams {
            dim: self.grid.dim,
            gamma: self.params.gamma,
            vacuum_rho: self.params.vacuum_rho,
            vacuum_p: self.params.vacuum_p,
            dx: &self.grid.dx,
        }
    }

    /// `(max_dt, limiting cell)` from this rank's fastest `(rate, local cell)` (collective).
    pub(super) fn finish_max_dt(&self, (rate, cell): (f64, usize)) -> (f64, usize) {
        let grid = &self.grid;
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
}

/// The constants of the CFL rate of a cell.
pub(super) struct RateParams<'a> {
    pub(super) dim: usize,
    pub(super) gamma: f64,
    pub(super) vacuum_rho: f64,
    pub(super) vacuum_p: f64,
    pub(super) dx: &'a [f64],
}

impl RateParams<'_> {
    /// The fastest rate `max_a (|u_a| + c)/Δx_a` of a stored cell; NaN if one is not finite.
    #[inline]
    pub(super) fn cell_rate(&self, cell: &[f64]) -> f64 {
        let (gamma, vacuum_rho, vacuum_p) = (self.gamma, self.vacuum_rho, self.vacuum_p);
        let w = crate::fv::euler::primitive_floored(&to_full(cell, self.dim), gamma, vacuum_rho);
        // Below the vacuum density and pressure, ρ, ρu and E are round-off (a covered cell
        // beside a crack held ρ = 2e-30 and E = 1e-16, a sound speed of 5e6 m/s that collapsed
        // the step): its speeds are taken at the vacuum density, as its velocity is. A gas of
        // real pressure at such a density keeps its sound speed, so that its collapsing step
        // stops the run (issue 11).
        let floor = w.rho < vacuum_rho && w.p < vacuum_p;
        let c = sound_speed(
            &crate::fv::euler::Primitive {
                rho: if floor { vacuum_rho } else { w.rho },
                ..w
            },
            gamma,
        );
        let mut rate = 0.0;
        for a in 0..self.dim {
            let r = (w.vel[a].abs() + c) / self.dx[a];
            if !r.is_finite() {
                return f64::NAN;
            }
            if r > rate {
                rate = r;
            }
        }
        rate
    }

    /// [`RateParams::cell_rate`] of `RATE_LANES` cells of `NV` stored values each (`dim + 2`),
    /// one cell a lane: the same IEEE operations in the same order in every lane, so the same
    /// bits (NaN where `cell_rate` gives NaN), with selects where `cell_rate` branches. The
    /// fixed-length loops over the lanes vectorise (`fv::isa`: no FMA, no reordering).
    ///
    /// NOTE: the cells are copied into one array per quantity first, so that the arithmetic
    /// runs on whole vectors (4 divisions and a square root a cell, 8.5 % of a 3-D 128³ step
    /// scalar).
    #[inline(always)]
    pub(super) fn cell_rates<const NV: usize>(&self, cells: &[f64]) -> [f64; RATE_LANES] {
        let dim = NV - 2;
        debug_assert_eq!(dim, self.dim);
        let cells = &cells[..RATE_LANES * NV];
        let (gamma, vacuum_rho, vacuum_p) = (self.gamma, self.vacuum_rho, self.vacuum_p);
        let mut rho = [0.0; RATE_LANES];
        // The momenta as `to_full` fills them: +0 along the axes the grid does not have.
        let mut mom = [[0.0; RATE_LANES]; 3];
        let mut energy = [0.0; RATE_LANES];
        for l in 0..RATE_LANES {
            rho[l] = cells[l * NV];
            for a in 0..dim {
                mom[a][l] = cells[l * NV + 1 + a];
            }
            energy[l] = cells[l * NV + NV - 1];
        }
        let dx: [f64; 3] = std::array::from_fn(|a| if a < dim { self.dx[a] } else { 1.0 });
        let mut out = [0.0; RATE_LANES];
        for l in 0..RATE_LANES {
            // `primitive_floored`.
            let inv_rho = 1.0 / rho[l].max(vacuum_rho);
            let inv = if rho[l] > 0.0 { inv_rho } else { 0.0 };
            let vel: [f64; 3] = std::array::from_fn(|a| mom[a][l] * inv);
            let kinetic = 0.5 * (mom[0][l] * vel[0] + mom[1][l] * vel[1] + mom[2][l] * vel[2]);
            let p = (gamma - 1.0) * (energy[l] - kinetic);
            // `cell_rate`'s floor and `sound_speed`.
            let floor = rho[l] < vacuum_rho && p < vacuum_p;
            let rho_c = if floor { vacuum_rho } else { rho[l] };
            let root = (gamma * p / rho_c).sqrt();
            let c = if rho_c > 0.0 && p > 0.0 { root } else { 0.0 };
            let (mut rate, mut finite) = (0.0, true);
            for a in 0..dim {
                let r = (vel[a].abs() + c) / dx[a];
                finite &= r.is_finite();
                rate = if r > rate { r } else { rate };
            }
            out[l] = if finite { rate } else { f64::NAN };
        }
        out
    }
}

/// Folds the rates of `group` (at most [`RATE_LANES`] cells of `NV` stored values, numbered
/// from `first`) into the fastest `(rate, cell)` so far, as `compute_max_dt` scans cells one at
/// a time: a NaN rate is taken and ends the group, else a larger rate (the first of equal ones).
/// A whole group takes [`RateParams::cell_rates`], a last short one [`RateParams::cell_rate`].
#[inline(always)]
pub(super) fn fold_rates<const NV: usize>(
    rates: &RateParams,
    group: &[f64],
    first: usize,
    fast: &mut (f64, usize),
) {
    let mut r = [0.0; RATE_LANES];
    if group.len() == RATE_LANES * NV {
        r = rates.cell_rates::<NV>(group);
    } else {
        for (r, cell) in r.iter_mut().zip(group.chunks_exact(NV)) {
            *r = rates.cell_rate(cell);
        }
    }
    let n = group.len() / NV;
    // NOTE: nearly every group has no rate above the fastest so far and no NaN: one test of the
    // whole group without a branch a cell (the scan's own test, `|` for `||`) says so, and the
    // scan, which then changes nothing, is skipped. The scan a cell with its branch was ~10
    // instructions a cell of the totals pass.
    let fastest = fast.0;
    if !r[..n]
        .iter()
        .fold(false, |any, &r| any | r.is_nan() | (r > fastest))
    {
        return;
    }
    for (k, &r) in r.iter().take(n).enumerate() {
        if r.is_nan() || r > fast.0 {
            *fast = (r, first + k);
            if r.is_nan() {
                break;
            }
        }
    }
}

/// The fastest `(rate, cell)` of `cells` (`nvar` stored values each, numbered from `first`),
/// as `compute_max_dt` scans them one at a time with [`RateParams::cell_rate`]: the first NaN,
/// else the first of the largest rates; the rates [`RATE_LANES`] cells at a time on `isa`.
pub(super) fn fastest_cell(
    isa: Isa,
    nvar: usize,
    rates: &RateParams,
    cells: &[f64],
    first: usize,
) -> (f64, usize) {
    match nvar {
        3 => fastest_on::<3>(isa, rates, cells, first),
        4 => fastest_on::<4>(isa, rates, cells, first),
        _ => fastest_on::<5>(isa, rates, cells, first),
    }
}

/// [`fastest_cells`] compiled for `isa` (the same bits on each, `fv::isa`).
fn fastest_on<const NV: usize>(
    isa: Isa,
    rates: &RateParams,
    cells: &[f64],
    first: usize,
) -> (f64, usize) {
    match isa {
        #[cfg(target_arch = "x86_64")]
        Isa::Avx512 if Isa::Avx512.supported() => {
            // SAFETY: the CPU has AVX-512F (checked on the line above).
            unsafe { fastest_avx512::<NV>(rates, cells, first) }
        }
        #[cfg(target_arch = "x86_64")]
        Isa::Avx2 if Isa::Avx2.supported() => {
            // SAFETY: the CPU has AVX2 (checked on the line above).
            unsafe { fastest_avx2::<NV>(rates, cells, first) }
        }
        _ => fastest_cells::<NV>(rates, cells, first),
    }
}

/// [`fastest_cells`] compiled for AVX2 (without FMA, `fv::isa`).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn fastest_avx2<const NV: usize>(rates: &RateParams, cells: &[f64], first: usize) -> (f64, usize) {
    fastest_cells::<NV>(rates, cells, first)
}

/// [`fastest_cells`] compiled for AVX-512F (without FMA, `fv::isa`).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn fastest_avx512<const NV: usize>(
    rates: &RateParams,
    cells: &[f64],
    first: usize,
) -> (f64, usize) {
    fastest_cells::<NV>(rates, cells, first)
}

/// [`fastest_cell`] of cells of `NV` values, up to the first NaN.
#[inline(always)]
fn fastest_cells<const NV: usize>(rates: &RateParams, cells: &[f64], first: usize) -> (f64, usize) {
    let mut fast: (f64, usize) = (0.0, first);
    for (g, group) in cells.chunks(RATE_LANES * NV).enumerate() {
        fold_rates::<NV>(rates, group, first + g * RATE_LANES, &mut fast);
        if fast.0.is_nan() {
            break;
        }
    }
    fast
}

/// The cells [`RateParams::cell_rates`] takes at once (8 lanes of f64 in AVX-512).
pub(super) const RATE_LANES: usize = 8;

/// The faster of two `(rate, cell)` candidates of the CFL step: a NaN rate first (the lowest
/// cell among NaNs), else the larger rate, the lower cell among equal ones.
pub(super) fn fastest(a: (f64, usize), b: (f64, usize)) -> (f64, usize) {
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
