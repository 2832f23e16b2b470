//! Conserved totals over the grid (compensated, fixed-order sums) and the gathers of the whole
//! grid's cells on rank 0.

use rayon::prelude::*;

use crate::fv::comm::{HaloExchange, bytes_f64, f64_bytes};
use crate::fv::euler::NQ;
use crate::fv::isa::{Isa, prefetch_line};
use crate::fv::slab::{put_block, rank_of, take_block};
use crate::fv::solver::cfl::{RATE_LANES, RateParams, fastest, fold_rates};
use crate::fv::solver::{FluidSolver, Totals, items_per_task};
use crate::fv::state::FluidState;

/// Chunks of planes a block sums between the messages of the totals' chain (see
/// `totals_with_rate`).
const CHAIN_CHUNKS: usize = 8;

impl FluidSolver {
    /// Conserved totals over the whole grid, summed in a fixed order (each plane of the last
    /// axis, then the planes in order), so the result does not depend on the thread or rank
    /// count.
    ///
    /// NOTE: on one rank the sums are kept until the state changes: the fluid node takes the
    /// totals of a step's state twice (the step's report and the ledger), a pass over the
    /// state each time (5 % of a 3-D step).
    pub fn totals(&self) -> Totals {
        if self.slab.ranks == 1
            && let Some(sum) = self.sums_cache.get()
        {
            return self.totals_from_sums(*sum);
        }
        self.totals_by(None)
    }

    /// Conserved totals of the fluid around an embedded solid: each cell weighted by its fluid
    /// fraction `1 − Λ` (`solid_fraction` one value per cell of the whole grid, every rank
    /// passing the same; cells with Λ = 1 hold ghost states
    /// and count for nothing). Same fixed-order sums as [`FluidSolver::totals`].
    pub fn totals_with_solid(&self, solid_fraction: &[f64]) -> Totals {
        assert_eq!(
            solid_fraction.len(),
            self.slab.global.n_cells(),
            "one Λ per cell of the whole grid"
        );
        self.totals_by(Some(solid_fraction))
    }

    /// [`FluidSolver::totals_with_solid`] from the solid fractions of this rank's cells only,
    /// in the order of its cells (x fastest over its block; every cell on one rank): the same
    /// bits, without the whole grid's Λ on every rank (issue 40 item 1, `embedded::held`).
    pub fn totals_with_own_solid(&self, own: &[f64]) -> Totals {
        assert_eq!(
            own.len(),
            self.grid.n_cells(),
            "one Λ per cell of this rank"
        );
        if self.slab.ranks == 1 {
            return self.totals_by(Some(own));
        }
        self.totals_of_own(Some(own), false).0
    }

    /// Adds `amount` (mass, momentum per axis, energy) to what left through the open sides
    /// since the start: the embedded solid's correct applies the sweeps' flux through a domain
    /// face of a cut cell times the face's fluid part, and counts the difference here. Every
    /// rank adds the same amount (the correct runs on the whole grid on every rank).
    pub fn add_outflow(&mut self, amount: &[f64; NQ]) {
        for q in 0..NQ {
            self.outflow[q] += amount[q];
        }
    }

    /// [`FluidSolver::totals`] and, in the same pass over the cells, the CFL step of the state
    /// into the cache [`FluidSolver::max_dt`] reads (one rank; on several the step is left to
    /// `max_dt`): the step after [`FluidSolver::advance`] then reads the state once less.
    pub(super) fn totals_and_max_dt(&self) -> Totals {
        if self.slab.ranks > 1 {
            return self.totals();
        }
        let (totals, fastest_cell) = self.totals_with_rate(None, true);
        let _ = self.dt_cache.set(self.finish_max_dt(fastest_cell));
        totals
    }

    fn totals_by(&self, solid_fraction: Option<&[f64]>) -> Totals {
        self.totals_with_rate(solid_fraction, false).0
    }

    /// The totals, and with `rate` the fastest `(rate, cell)` of the CFL step as
    /// `compute_max_dt` finds it (the same rates and the same choice among them, `fastest`;
    /// planes here, blocks of cells there, which the choice does not depend on).
    fn totals_with_rate(
        &self,
        solid_fraction: Option<&[f64]>,
        rate: bool,
    ) -> (Totals, (f64, usize)) {
        let dim = self.grid.dim;
        if dim == 1 && self.slab.ranks == 1 {
            return self.line_totals(solid_fraction, rate);
        }
        // NOTE: compensated sums per plane of the last axis (x fastest within it) and over
        // the planes, so that the totals are exact to a few ulps and a conservation check
        // measures the scheme, not the sum. A block's part of each of its planes is contiguous
        // in the one-rank order of the plane (x is not cut in 3-D, `protocol::decomp`), and
        // the blocks along axis `dim − 2` take turns in that order: each continues the running
        // sums of the block below it, so every plane's sum takes the one-rank steps.
        let lambda_block;
        let solid_fraction = match solid_fraction {
            Some(l) if self.slab.ranks > 1 => {
                let block = self.slab.block_of_rank(self.slab.rank);
                lambda_block = take_block(&self.slab.global, block, 1, l);
                Some(&lambda_block[..])
            }
            other => other,
        };
        self.totals_of_own(solid_fraction, rate)
    }

    /// [`FluidSolver::totals_with_rate`] with the solid fractions of this rank's cells, in
    /// their order.
    fn totals_of_own(&self, solid_fraction: Option<&[f64]>, rate: bool) -> (Totals, (f64, usize)) {
        let dim = self.grid.dim;
        let n_planes = self.grid.cells[dim - 1];
        let mut partial = vec![[CompensatedSum::default(); NQ]; n_planes];
        let mut fast: Vec<(f64, usize)> = vec![(0.0, usize::MAX); n_planes];
        let (below, above) = (self.row_neighbour(false), self.row_neighbour(true));
        // NOTE: in chunks of planes along a chain, so that the block above starts on a chunk
        // while this block sums the next: it then waits for one chunk of each block below, not
        // for their whole sums (at 128³ on `1 × 2 × 1` the whole wait was 17 ms, 5.6 % of the
        // upper rank's step).
        let chunk = if below.is_some() || above.is_some() {
            n_planes.div_ceil(CHAIN_CHUNKS)
        } else {
            n_planes
        };
        for start in (0..n_planes).step_by(chunk) {
            let r = start..(start + chunk).min(n_planes);
            if let Some(from) = below {
                self.receive_plane_sums(from, &mut partial[r.clone()]);
            }
            let (acc, fast) = (&mut partial[r.clone()], &mut fast[r.clone()]);
            self.sum_planes(r.start, acc, fast, solid_fraction, rate);
            if let Some(to) = above {
                self.send_plane_sums(to, &partial[r]);
            }
        }
        let flat: Vec<f64> = if above.is_some() {
            Vec::new()
        } else {
            partial
                .iter()
                .flat_map(|acc| acc.iter().flat_map(|c| [c.sum, c.comp]))
                .collect()
        };
        let flat = if self.slab.ranks == 1 {
            flat
        } else {
            self.comm
                .all_gather(&f64_bytes(&flat))
                .iter()
                .flat_map(bytes_f64)
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
        if solid_fraction.is_none() && self.slab.ranks == 1 {
            let _ = self.sums_cache.set(sum);
        }
        let fastest_cell = fast.into_iter().fold((0.0, usize::MAX), fastest);
        (self.totals_from_sums(sum), fastest_cell)
    }
    /// [`FluidSolver::totals_with_rate`] of a 1-D grid on one rank: its planes are single cells,
    /// so the planes' sums are the cells' values with no compensation, and adding them in plane
    /// order (each plane's sum, then its compensation, +0) is adding the cells in turn: the
    /// same running sums, bit for bit for finite states (adding +0 leaves `sum` and `comp` as
    /// they are, and the running sum, from +0, is never −0). The same holds for the fastest cell (the first NaN,
    /// else the first of the largest rates). So the line is summed in one pass, in order.
    ///
    /// NOTE: one rayon task a cell made the totals of a 1-D step cost as much as its sweep
    /// (thread wake-ups, the flattened partials): `fluid-node report work-precision` of Sod
    /// spent a quarter of its samples in the scheduler.
    fn line_totals(&self, solid_fraction: Option<&[f64]>, rate: bool) -> (Totals, (f64, usize)) {
        let u = &self.state.u;
        let mut acc = [CompensatedSum::default(); NQ];
        let mut fast = (0.0, 0);
        match solid_fraction {
            None => {
                let rates = self.rate_params();
                let rates = rate.then_some(&rates);
                fast = sum_cells_on::<3>(self.rate_isa(), &mut acc, u, rates, 0);
            }
            Some(lambda) => {
                for (cell, l) in u.chunks_exact(3).zip(lambda) {
                    let alpha = 1.0 - l;
                    if alpha <= 0.0 {
                        continue;
                    }
                    acc[0].add(alpha * cell[0]);
                    acc[1].add(alpha * cell[1]);
                    acc[4].add(alpha * cell[2]);
                }
            }
        }
        let sum: [f64; NQ] = std::array::from_fn(|q| acc[q].value());
        if solid_fraction.is_none() {
            let _ = self.sums_cache.set(sum);
        }
        (self.totals_from_sums(sum), fast)
    }

    /// The totals of the sums `sum` of the conserved values and what left the domain so far.
    fn totals_from_sums(&self, sum: [f64; NQ]) -> Totals {
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

    /// Per-cell values (`per` each) of every rank's block put together in the global order on
    /// rank 0 (`None` elsewhere; collective).
    pub(super) fn gather_cells(&self, mine: &[f64]) -> Option<Vec<f64>> {
        if self.slab.ranks == 1 {
            return Some(mine.to_vec());
        }
        let per = mine.len() / self.grid.n_cells();
        let parts = self.comm.gather(0, &f64_bytes(mine))?;
        let global = &self.slab.global;
        let mut whole = vec![0.0; global.n_cells() * per];
        for (r, b) in parts.iter().enumerate() {
            put_block(
                global,
                self.slab.block_of_rank(r),
                per,
                &bytes_f64(b),
                &mut whole,
            );
        }
        Some(whole)
    }

    /// Adds the cells of this rank's planes `first..first + acc.len()` into their running sums
    /// `acc` (weighted by the fluid fraction `1 − Λ` of the block's `solid_fraction`), and with
    /// `rate` their fastest `(rate, local cell)` into `fast`.
    fn sum_planes(
        &self,
        first: usize,
        acc: &mut [[CompensatedSum; NQ]],
        fast: &mut [(f64, usize)],
        solid_fraction: Option<&[f64]>,
        rate: bool,
    ) {
        let (nvar, dim) = (self.state.nvar, self.grid.dim);
        debug_assert_eq!(nvar, dim + 2);
        let plane = self.grid.n_cells() / self.grid.cells[dim - 1];
        let u = &self.state.u[first * plane * nvar..(first + acc.len()) * plane * nvar];
        let rates = self.rate_params();
        let isa = self.rate_isa();
        self.pool.install(|| {
            acc.par_iter_mut()
                .zip(fast.par_iter_mut())
                .zip(u.par_chunks(plane * nvar))
                .enumerate()
                .with_max_len(items_per_task(plane))
                .for_each(|(k, ((acc, fast), cells))| {
                    let block = first + k;
                    match solid_fraction {
                        None => {
                            let rates = rate.then_some(&rates);
                            *fast = match nvar {
                                3 => sum_cells_on::<3>(isa, acc, cells, rates, block * plane),
                                4 => sum_cells_on::<4>(isa, acc, cells, rates, block * plane),
                                _ => sum_cells_on::<5>(isa, acc, cells, rates, block * plane),
                            };
                        }
                        Some(lambda) => {
                            let lambda = &lambda[block * plane..];
                            match nvar {
                                3 => sum_weighted_on::<3>(isa, acc, cells, lambda),
                                4 => sum_weighted_on::<4>(isa, acc, cells, lambda),
                                _ => sum_weighted_on::<5>(isa, acc, cells, lambda),
                            }
                        }
                    }
                });
        });
    }

    /// The running sums of some of this rank's planes to start from: those the block below
    /// along axis `dim − 2` (rank `from`) ended its part of them with (collective with it).
    fn receive_plane_sums(&self, from: usize, partial: &mut [[CompensatedSum; NQ]]) {
        let mut buf = vec![0.0; partial.len() * 2 * NQ];
        self.comm.exchange_halo(HaloExchange {
            to_lo: None,
            to_hi: None,
            from_lo: Some((from, &mut buf[..])),
            from_hi: None,
        });
        for (acc, v) in partial.iter_mut().zip(buf.chunks_exact(2 * NQ)) {
            for q in 0..NQ {
                acc[q] = CompensatedSum {
                    sum: v[2 * q],
                    comp: v[2 * q + 1],
                };
            }
        }
    }

    /// Sends the running sums `partial` of some of this rank's planes to the block above along
    /// axis `dim − 2` (rank `to`), which continues them.
    fn send_plane_sums(&self, to: usize, partial: &[[CompensatedSum; NQ]]) {
        let flat: Vec<f64> = partial
            .iter()
            .flat_map(|acc| acc.iter().flat_map(|c| [c.sum, c.comp]))
            .collect();
        self.comm.exchange_halo(HaloExchange {
            to_lo: None,
            to_hi: Some((to, &flat)),
            from_lo: None,
            from_hi: None,
        });
    }

    /// The block below (`above` false) or above along axis `dim − 2`, not across a periodic
    /// side (the order of the sums of a plane's rows).
    fn row_neighbour(&self, above: bool) -> Option<usize> {
        let slab = &self.slab;
        let a = slab.global.dim.checked_sub(2)?;
        let c = slab.coords[a];
        let to = if above {
            (c + 1 < slab.dims[a]).then_some(c + 1)?
        } else {
            c.checked_sub(1)?
        };
        let mut coords = slab.coords;
        coords[a] = to;
        Some(rank_of(slab.dims, coords))
    }
}

/// [`sum_cells`] compiled for `isa` (the rates' vector width; the same bits on each, `fv::isa`).
fn sum_cells_on<const NV: usize>(
    isa: Isa,
    acc: &mut [CompensatedSum; NQ],
    cells: &[f64],
    rates: Option<&RateParams>,
    first: usize,
) -> (f64, usize) {
    match isa {
        #[cfg(target_arch = "x86_64")]
        Isa::Avx512 if Isa::Avx512.supported() => {
            // SAFETY: the CPU has AVX-512F (checked on the line above).
            unsafe { sum_cells_avx512::<NV>(acc, cells, rates, first) }
        }
        #[cfg(target_arch = "x86_64")]
        Isa::Avx2 if Isa::Avx2.supported() => {
            // SAFETY: the CPU has AVX2 (checked on the line above).
            unsafe { sum_cells_avx2::<NV>(acc, cells, rates, first) }
        }
        _ => sum_cells::<NV, Scalar<NV>>(acc, cells, rates, first),
    }
}

/// [`sum_cells`] compiled for AVX2 (without FMA, `fv::isa`).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn sum_cells_avx2<const NV: usize>(
    acc: &mut [CompensatedSum; NQ],
    cells: &[f64],
    rates: Option<&RateParams>,
    first: usize,
) -> (f64, usize) {
    sum_cells::<NV, lanes::Avx2<NV>>(acc, cells, rates, first)
}

/// [`sum_cells`] compiled for AVX-512F (without FMA, `fv::isa`).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn sum_cells_avx512<const NV: usize>(
    acc: &mut [CompensatedSum; NQ],
    cells: &[f64],
    rates: Option<&RateParams>,
    first: usize,
) -> (f64, usize) {
    sum_cells::<NV, lanes::Avx512<NV>>(acc, cells, rates, first)
}

/// Adds the cells `cells` (`NV` stored values each: ρ, the momenta, E) into `acc` (the
/// physical order), each value in turn, as [`CompensatedSum::add`] does (the running sums
/// `R` of the instruction set); with `rates`, returns the fastest `(rate, cell)` of the cells
/// (numbered from `first`) as `compute_max_dt` finds it: the first NaN, else the first of the
/// largest rates (`(0, first)` without `rates`).
///
/// NOTE: the sums run in local variables and are stored into `acc` once at the end. Adding
/// into `acc` in place kept its ten values in memory (the compiler cannot keep a `&mut` array
/// in registers across the loop), so every addition waited on the store of the one before:
/// the totals took 8 % of a 3-D step. Same operations in the same order, so the same bits.
/// The rates are taken [`RATE_LANES`] cells at a time ([`RateParams::cell_rates`], the same
/// bits as [`RateParams::cell_rate`], which takes the cells of a last short group).
#[inline(always)]
fn sum_cells<const NV: usize, R: RunningSums<NV>>(
    acc: &mut [CompensatedSum; NQ],
    cells: &[f64],
    rates: Option<&RateParams>,
    first: usize,
) -> (f64, usize) {
    let mut sums = R::start(acc);
    let mut fast: (f64, usize) = (0.0, first);
    for (g, group) in cells.chunks(RATE_LANES * NV).enumerate() {
        // NOTE: the lines of the group eight ahead (2.5 kB in 3-D): the hardware's stream
        // prefetcher alone left the pass waiting on its loads (160 → 135–140 samples).
        let ahead = group.as_ptr().wrapping_add(8 * RATE_LANES * NV);
        for line in 0..=RATE_LANES * NV / 8 {
            prefetch_line(ahead.wrapping_add(8 * line));
        }
        if let Some(rates) = rates
            && !fast.0.is_nan()
        {
            fold_rates::<NV>(rates, group, first + g * RATE_LANES, &mut fast);
        }
        for cell in group.chunks_exact(NV) {
            sums.add(cell.try_into().expect("NV values"));
        }
    }
    sums.finish(acc);
    fast
}

/// [`sum_weighted`] compiled for `isa` (the same bits on each, `fv::isa`).
fn sum_weighted_on<const NV: usize>(
    isa: Isa,
    acc: &mut [CompensatedSum; NQ],
    cells: &[f64],
    lambda: &[f64],
) {
    match isa {
        #[cfg(target_arch = "x86_64")]
        Isa::Avx512 if Isa::Avx512.supported() => {
            // SAFETY: the CPU has AVX-512F (checked on the line above).
            unsafe { sum_weighted_avx512::<NV>(acc, cells, lambda) }
        }
        #[cfg(target_arch = "x86_64")]
        Isa::Avx2 if Isa::Avx2.supported() => {
            // SAFETY: the CPU has AVX2 (checked on the line above).
            unsafe { sum_weighted_avx2::<NV>(acc, cells, lambda) }
        }
        _ => sum_weighted::<NV, Scalar<NV>>(acc, cells, lambda),
    }
}

/// [`sum_weighted`] compiled for AVX2 (without FMA, `fv::isa`).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn sum_weighted_avx2<const NV: usize>(
    acc: &mut [CompensatedSum; NQ],
    cells: &[f64],
    lambda: &[f64],
) {
    sum_weighted::<NV, lanes::Avx2<NV>>(acc, cells, lambda);
}

/// [`sum_weighted`] compiled for AVX-512F (without FMA, `fv::isa`).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn sum_weighted_avx512<const NV: usize>(
    acc: &mut [CompensatedSum; NQ],
    cells: &[f64],
    lambda: &[f64],
) {
    sum_weighted::<NV, lanes::Avx512<NV>>(acc, cells, lambda);
}

/// Adds the cells `cells` weighted by their fluid fraction `1 − Λ` (`lambda`, one value a
/// cell) into `acc`, the cells of a fraction ≤ 0 left out: each value `v` of a kept cell adds
/// `(1 − Λ) v` into its slot as [`CompensatedSum::add`] does.
///
/// NOTE: through [`RunningSums::add_scaled`], a cell's values in the lanes of one vector
/// multiplied there by the fraction, as [`sum_cells`] adds them: each lane makes the IEEE
/// operations of the scalar loop that was here (`acc[q].add(alpha * cell[q])` value by value)
/// on its own value, cell after cell, so the same bits. `clamped-beam-2d`, `perf record -F
/// 5000` of the fluid: 512–755 samples in 4 runs against about 900–1,150 of the scalar loop
/// (issue 36 item 4). The weighted values first put in an array and loaded from it as one
/// vector took 2,142–2,176 (the load of values just stored one at a time waits for the
/// stores); prefetching the cells ahead, as `sum_cells` does, changed nothing.
#[inline(always)]
fn sum_weighted<const NV: usize, R: RunningSums<NV>>(
    acc: &mut [CompensatedSum; NQ],
    cells: &[f64],
    lambda: &[f64],
) {
    let mut sums = R::start(acc);
    for (cell, &l) in cells.chunks_exact(NV).zip(lambda) {
        let alpha = 1.0 - l;
        if alpha <= 0.0 {
            continue;
        }
        sums.add_scaled(cell.try_into().expect("NV values"), alpha);
    }
    sums.finish(acc);
}

/// The compensated sums of the `NV` stored values of the cells (value `j` into slot `j` of
/// the physical order, the energy, last, into slot `NQ − 1`), as [`sum_cells`] runs them.
trait RunningSums<const NV: usize> {
    /// The sums of `acc` to continue.
    fn start(acc: &[CompensatedSum; NQ]) -> Self;
    /// [`CompensatedSum::add`] of each value of `cell` into its sum.
    fn add(&mut self, cell: &[f64; NV]);
    /// [`CompensatedSum::add`] of `alpha` times each value of `cell` into its sum (each
    /// product rounded once, as `alpha * v`).
    fn add_scaled(&mut self, cell: &[f64; NV], alpha: f64);
    /// Stores the sums into `acc`.
    fn finish(self, acc: &mut [CompensatedSum; NQ]);
}

/// The slot of the physical order that stored value `j` of a cell of `nv` values sums into.
#[inline(always)]
fn slot(nv: usize, j: usize) -> usize {
    if j == nv - 1 { NQ - 1 } else { j }
}

/// [`RunningSums`] one value at a time (the baseline).
struct Scalar<const NV: usize>([CompensatedSum; NV]);

impl<const NV: usize> RunningSums<NV> for Scalar<NV> {
    #[inline(always)]
    fn start(acc: &[CompensatedSum; NQ]) -> Self {
        Scalar(std::array::from_fn(|j| acc[slot(NV, j)]))
    }

    #[inline(always)]
    fn add(&mut self, cell: &[f64; NV]) {
        for j in 0..NV {
            self.0[j].add(cell[j]);
        }
    }

    #[inline(always)]
    fn add_scaled(&mut self, cell: &[f64; NV], alpha: f64) {
        for j in 0..NV {
            self.0[j].add(alpha * cell[j]);
        }
    }

    #[inline(always)]
    fn finish(self, acc: &mut [CompensatedSum; NQ]) {
        for j in 0..NV {
            acc[slot(NV, j)] = self.0[j];
        }
    }
}

/// [`RunningSums`] on the vector units: a cell's values in the lanes of one vector, each lane
/// the running sum of one value, so that a cell takes one vector `TwoSum`.
///
/// NOTE: each lane makes [`CompensatedSum::add`]'s IEEE operations on its own value, cell
/// after cell: the same sums in the same order as the scalar code, so the same bits (lanes
/// beyond `NV` add zeros and are dropped). One value at a time, the ten sums' ~35 scalar
/// operations a cell were most of the totals pass's instructions.
#[cfg(target_arch = "x86_64")]
mod lanes {
    use std::arch::x86_64::*;

    use super::{CompensatedSum, NQ, RunningSums, slot};

    /// A cell's values in the lanes of one AVX-512 vector (`NV ≤ 8`).
    pub(super) struct Avx512<const NV: usize> {
        sum: __m512d,
        comp: __m512d,
    }

    impl<const NV: usize> Avx512<NV> {
        /// The lanes that hold a cell's values.
        const MASK: __mmask8 = ((1u16 << NV) - 1) as __mmask8;

        /// A cell's `NV` values in the first lanes, zeros in the others.
        #[inline(always)]
        fn load(cell: &[f64; NV]) -> __m512d {
            // SAFETY: the caller runs on AVX-512F; the masked load reads the `NV` values alone.
            unsafe { _mm512_maskz_loadu_pd(Self::MASK, cell.as_ptr()) }
        }

        /// [`CompensatedSum::add`] of each lane of `x` into its sum.
        #[inline(always)]
        fn add_lanes(&mut self, x: __m512d) {
            // SAFETY: the caller runs on AVX-512F.
            unsafe {
                let t = _mm512_add_pd(self.sum, x);
                let z = _mm512_sub_pd(t, self.sum);
                let err = _mm512_add_pd(
                    _mm512_sub_pd(self.sum, _mm512_sub_pd(t, z)),
                    _mm512_sub_pd(x, z),
                );
                self.comp = _mm512_add_pd(self.comp, err);
                self.sum = t;
            }
        }
    }

    impl<const NV: usize> RunningSums<NV> for Avx512<NV> {
        #[inline(always)]
        fn start(acc: &[CompensatedSum; NQ]) -> Self {
            let sum: [f64; 8] =
                std::array::from_fn(|j| if j < NV { acc[slot(NV, j)].sum } else { 0.0 });
            let comp: [f64; 8] =
                std::array::from_fn(|j| if j < NV { acc[slot(NV, j)].comp } else { 0.0 });
            // SAFETY: the caller runs on AVX-512F (`sum_cells_avx512`); 8 values each.
            unsafe {
                Avx512 {
                    sum: _mm512_loadu_pd(sum.as_ptr()),
                    comp: _mm512_loadu_pd(comp.as_ptr()),
                }
            }
        }

        #[inline(always)]
        fn add(&mut self, cell: &[f64; NV]) {
            self.add_lanes(Self::load(cell));
        }

        #[inline(always)]
        fn add_scaled(&mut self, cell: &[f64; NV], alpha: f64) {
            // SAFETY: the caller runs on AVX-512F.
            let x = unsafe { _mm512_mul_pd(_mm512_set1_pd(alpha), Self::load(cell)) };
            self.add_lanes(x);
        }

        #[inline(always)]
        fn finish(self, acc: &mut [CompensatedSum; NQ]) {
            let (mut sum, mut comp) = ([0.0; 8], [0.0; 8]);
            // SAFETY: the caller runs on AVX-512F; 8 values each.
            unsafe {
                _mm512_storeu_pd(sum.as_mut_ptr(), self.sum);
                _mm512_storeu_pd(comp.as_mut_ptr(), self.comp);
            }
            for j in 0..NV {
                acc[slot(NV, j)] = CompensatedSum {
                    sum: sum[j],
                    comp: comp[j],
                };
            }
        }
    }

    /// A cell's first four values in the lanes of one AVX2 vector, a fifth alone (`3 ≤ NV ≤ 5`).
    pub(super) struct Avx2<const NV: usize> {
        sum: __m256d,
        comp: __m256d,
        fifth: CompensatedSum,
    }

    impl<const NV: usize> Avx2<NV> {
        /// The lanes that hold a cell's values (the sign bit set), of the first four.
        const MASK: [i64; 4] = [-1, -1, -1, if NV > 3 { -1 } else { 0 }];

        /// A cell's first `min(NV, 4)` values in the lanes, zeros in the others.
        #[inline(always)]
        fn load(cell: &[f64; NV]) -> __m256d {
            // SAFETY: the caller runs on AVX2; the masked load reads the first `min(NV, 4)`
            // values alone.
            unsafe {
                let mask = _mm256_loadu_si256(Self::MASK.as_ptr().cast());
                _mm256_maskload_pd(cell.as_ptr(), mask)
            }
        }

        /// [`CompensatedSum::add`] of each lane of `x` into its sum.
        #[inline(always)]
        fn add_lanes(&mut self, x: __m256d) {
            // SAFETY: the caller runs on AVX2.
            unsafe {
                let t = _mm256_add_pd(self.sum, x);
                let z = _mm256_sub_pd(t, self.sum);
                let err = _mm256_add_pd(
                    _mm256_sub_pd(self.sum, _mm256_sub_pd(t, z)),
                    _mm256_sub_pd(x, z),
                );
                self.comp = _mm256_add_pd(self.comp, err);
                self.sum = t;
            }
        }
    }

    impl<const NV: usize> RunningSums<NV> for Avx2<NV> {
        #[inline(always)]
        fn start(acc: &[CompensatedSum; NQ]) -> Self {
            let sum: [f64; 4] =
                std::array::from_fn(|j| if j < NV { acc[slot(NV, j)].sum } else { 0.0 });
            let comp: [f64; 4] =
                std::array::from_fn(|j| if j < NV { acc[slot(NV, j)].comp } else { 0.0 });
            // SAFETY: the caller runs on AVX2 (`sum_cells_avx2`); 4 values each.
            unsafe {
                Avx2 {
                    sum: _mm256_loadu_pd(sum.as_ptr()),
                    comp: _mm256_loadu_pd(comp.as_ptr()),
                    fifth: if NV > 4 {
                        acc[slot(NV, 4)]
                    } else {
                        CompensatedSum::default()
                    },
                }
            }
        }

        #[inline(always)]
        fn add(&mut self, cell: &[f64; NV]) {
            self.add_lanes(Self::load(cell));
            if NV > 4 {
                self.fifth.add(cell[4.min(NV - 1)]);
            }
        }

        #[inline(always)]
        fn add_scaled(&mut self, cell: &[f64; NV], alpha: f64) {
            // SAFETY: the caller runs on AVX2.
            let x = unsafe { _mm256_mul_pd(_mm256_set1_pd(alpha), Self::load(cell)) };
            self.add_lanes(x);
            if NV > 4 {
                self.fifth.add(alpha * cell[4.min(NV - 1)]);
            }
        }

        #[inline(always)]
        fn finish(self, acc: &mut [CompensatedSum; NQ]) {
            let (mut sum, mut comp) = ([0.0; 4], [0.0; 4]);
            // SAFETY: the caller runs on AVX2; 4 values each.
            unsafe {
                _mm256_storeu_pd(sum.as_mut_ptr(), self.sum);
                _mm256_storeu_pd(comp.as_mut_ptr(), self.comp);
            }
            for j in 0..NV.min(4) {
                acc[slot(NV, j)] = CompensatedSum {
                    sum: sum[j],
                    comp: comp[j],
                };
            }
            if NV > 4 {
                acc[slot(NV, 4)] = self.fifth;
            }
        }
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

#[cfg(test)]
mod tests;
