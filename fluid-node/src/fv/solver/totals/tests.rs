//! The totals pass against its references, to the bit: the batched CFL rates and sums of every
//! instruction set against the scalar ones (random cells with NaN, infinities and −0), and a 1-D
//! line summed in one pass against its planes' sums.

use super::*;
use crate::fv::solver::cfl::fastest_cell;

/// Cells of `nv` values: gas, vacuum-floored round-off, ρ ≤ 0, p < 0, NaN and ±∞ in any
/// value, and repeated cells (tied rates), drawn by a fixed splitmix64.
fn random_cells(nv: usize, n: usize, seed: u64) -> Vec<f64> {
    let mut x = seed;
    let mut next = move || {
        x = x.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = x;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    };
    let mut cells: Vec<f64> = Vec::with_capacity(n * nv);
    for k in 0..n {
        let kind = next() % 16;
        let unit = |v: u64| (v >> 11) as f64 / (1u64 << 53) as f64;
        if kind == 0 && k > 0 {
            let j = (next() as usize) % k;
            let copy = cells[j * nv..(j + 1) * nv].to_vec();
            cells.extend(copy);
            continue;
        }
        let scale = match kind {
            1 | 2 => 1e-14, // vacuum round-off, both signs
            3 => 1e-300,
            _ => 1.0,
        };
        let mut cell: Vec<f64> = (0..nv)
            .map(|_| scale * (2.0 * unit(next()) - 1.0))
            .collect();
        if kind >= 4 {
            cell[0] = 0.1 + 5.0 * unit(next());
            cell[nv - 1] = 0.5 + 20.0 * unit(next());
        }
        match kind {
            5 => cell[(next() as usize) % nv] = f64::NAN,
            6 => cell[(next() as usize) % nv] = f64::INFINITY,
            7 => cell[0] = 0.0,
            8 => cell[nv - 1] = -1.0,
            _ => {}
        }
        cells.extend(cell);
    }
    cells
}

/// The fastest `(rate, cell)` as `compute_max_dt` takes it, one cell at a time with the
/// scalar `cell_rate`.
fn reference(rates: &RateParams, nv: usize, cells: &[f64], first: usize) -> (f64, usize) {
    let mut fast: (f64, usize) = (0.0, first);
    for (k, cell) in cells.chunks_exact(nv).enumerate() {
        if fast.0.is_nan() {
            break;
        }
        let r = rates.cell_rate(cell);
        if r.is_nan() || r > fast.0 {
            fast = (r, first + k);
        }
    }
    fast
}

/// The batched rates of the totals pass are the scalar `cell_rate`'s to the bit, lane by
/// lane, and its fastest cell is the scalar scan's (the first NaN, the first of equal
/// rates), on every instruction set, in 1, 2 and 3-D, with and without a vacuum floor; the
/// sums are those of the pass without rates.
#[test]
fn batched_cfl_rates_are_the_scalar_rates_to_the_bit() {
    let dx = [0.01, 0.02, 0.005];
    let mut nans = 0;
    for dim in 1..=3 {
        let nv = dim + 2;
        for (vacuum_rho, vacuum_p) in [(1e-10, 1e-10), (0.0, 0.0)] {
            let rates = RateParams {
                dim,
                gamma: 1.4,
                vacuum_rho,
                vacuum_p,
                dx: &dx[..dim],
            };
            for seed in 0..40 {
                // 61 cells: seven groups of eight and a short one.
                let cells = random_cells(nv, 61, seed);
                for group in cells.chunks_exact(RATE_LANES * nv) {
                    let batched = match nv {
                        3 => rates.cell_rates::<3>(group),
                        4 => rates.cell_rates::<4>(group),
                        _ => rates.cell_rates::<5>(group),
                    };
                    for (r, cell) in batched.iter().zip(group.chunks_exact(nv)) {
                        let want = rates.cell_rate(cell);
                        assert_eq!(r.to_bits(), want.to_bits(), "{cell:?}");
                        nans += usize::from(want.is_nan());
                    }
                }
                // Without the NaN cells too, so that the scan runs to the end.
                let finite: Vec<f64> = cells
                    .chunks_exact(nv)
                    .filter(|c| !rates.cell_rate(c).is_nan())
                    .flatten()
                    .copied()
                    .collect();
                for cells in [&cells, &finite] {
                    let want = reference(&rates, nv, cells, 1000);
                    let mut plain = [CompensatedSum::default(); NQ];
                    match nv {
                        3 => sum_cells_on::<3>(Isa::Baseline, &mut plain, cells, None, 0),
                        4 => sum_cells_on::<4>(Isa::Baseline, &mut plain, cells, None, 0),
                        _ => sum_cells_on::<5>(Isa::Baseline, &mut plain, cells, None, 0),
                    };
                    for isa in Isa::available() {
                        let mut acc = [CompensatedSum::default(); NQ];
                        let got = match nv {
                            3 => sum_cells_on::<3>(isa, &mut acc, cells, Some(&rates), 1000),
                            4 => sum_cells_on::<4>(isa, &mut acc, cells, Some(&rates), 1000),
                            _ => sum_cells_on::<5>(isa, &mut acc, cells, Some(&rates), 1000),
                        };
                        assert_eq!((got.0.to_bits(), got.1), (want.0.to_bits(), want.1));
                        let alone = fastest_cell(isa, nv, &rates, cells, 1000);
                        assert_eq!((alone.0.to_bits(), alone.1), (want.0.to_bits(), want.1));
                        let bits = |a: &[CompensatedSum; NQ]| {
                            a.map(|c| (c.sum.to_bits(), c.comp.to_bits()))
                        };
                        assert_eq!(bits(&acc), bits(&plain), "{isa:?}");
                    }
                }
            }
        }
    }
    assert!(nans > 100, "{nans} NaN rates drawn");
}

/// A 1-D line is summed in one pass (`line_totals`): its totals, its fastest cell and its
/// totals weighted by a fluid fraction are, to the bit, the planes' sums (one cell a plane,
/// each summed from zero) added in plane order, as every other grid is summed; with zero and
/// −0 momenta, exact cancellations and fractions ≤ 0 (cells left out). (Finite states: with
/// infinities the two orders may give NaNs of another sign, and the run stops on either.)
#[test]
fn a_line_summed_in_one_pass_gives_the_bits_of_its_planes() {
    use crate::fv::{BoundaryKind, FluidParams, FluidState, FluxKind};
    use crate::grid::Grid;
    let params = FluidParams {
        gamma: 1.4,
        cfl: 0.7,
        flux: FluxKind::Osmp(5),
        boundary: [[BoundaryKind::Wall; 2]; 3],
        vacuum_rho: 1e-10,
        vacuum_p: 1e-10,
    };
    let slot = |j: usize| if j == 2 { NQ - 1 } else { j };
    let bits = |t: &Totals| [t.mass, t.momentum[0], t.energy].map(f64::to_bits);
    for seed in 0..12u64 {
        let n = 37 + 13 * seed as usize;
        let mut u = Vec::with_capacity(3 * n);
        let finite = |x: f64| if x.is_finite() { x } else { 0.3 };
        for (k, c) in random_cells(3, n, seed).chunks_exact(3).enumerate() {
            let c = [finite(c[0]), finite(c[1]), finite(c[2])];
            let rho = 0.1 + c[0].abs() * 5.0;
            let m = match k % 5 {
                0 => 0.0,
                1 => -0.0,
                2 => 1.0,
                3 => -1.0,
                _ => c[1] * 3.0,
            };
            u.extend([rho, m, 0.5 * m * m / rho + 1.0 + c[2].abs()]);
        }
        let lambda: Vec<f64> = random_cells(1, n, seed + 100)
            .iter()
            .map(|x| if x.is_finite() { 0.7 * x + 0.4 } else { 1.0 })
            .collect();
        let grid = Grid::new(&[0.0], &[1.0], &[n]).expect("grid");
        let rates = RateParams {
            dim: 1,
            gamma: 1.4,
            vacuum_rho: 1e-10,
            vacuum_p: 1e-10,
            dx: &grid.dx,
        };
        let want_fast = reference(&rates, 3, &u, 0);
        let state = FluidState {
            nvar: 3,
            u: u.clone(),
        };
        let solver = FluidSolver::new(grid.clone(), params.clone(), state, 2).expect("solver");
        for weighted in [false, true] {
            // The planes' way: each cell summed from zero, then its sum and compensation
            // added to the total in plane order.
            let mut total = [CompensatedSum::default(); NQ];
            for (cell, l) in u.chunks_exact(3).zip(&lambda) {
                let alpha = if weighted { 1.0 - l } else { 1.0 };
                if weighted && alpha <= 0.0 {
                    continue;
                }
                for (j, &x) in cell.iter().enumerate() {
                    let mut plane = CompensatedSum::default();
                    plane.add(if weighted { alpha * x } else { x });
                    total[slot(j)].add(plane.sum);
                    total[slot(j)].add(plane.comp);
                }
            }
            let want = solver.totals_from_sums(std::array::from_fn(|q| total[q].value()));
            let fraction = weighted.then_some(&lambda[..]);
            let (got, fast) = solver.totals_with_rate(fraction, !weighted);
            assert_eq!(bits(&got), bits(&want), "seed {seed}, weighted {weighted}");
            if !weighted {
                assert_eq!(
                    (fast.0.to_bits(), fast.1),
                    (want_fast.0.to_bits(), want_fast.1)
                );
            }
        }
    }
}

/// The totals weighted by a fluid fraction, on every instruction set, are to the bit (a NaN's
/// sign aside) those of the scalar loop they replace (`acc[q].add((1 − Λ) × value)` value by
/// value, the cells of a fraction ≤ 0 left out), in 1, 2 and 3-D: random cells with NaN,
/// infinities and −0, and fractions covered, cut, empty, beyond 1, below 0 and NaN, from
/// running sums that do not start at zero.
#[test]
fn weighted_sums_are_the_scalar_loops_to_the_bit() {
    let mut x = 7u64;
    let mut unit = move || {
        x = x
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (x >> 11) as f64 / (1u64 << 53) as f64
    };
    // A NaN's sign is not kept by the compiler (it may swap an addition's operands), so every
    // NaN is one value here; every other value is compared to the bit.
    let key = |v: f64| {
        if v.is_nan() {
            f64::NAN.to_bits()
        } else {
            v.to_bits()
        }
    };
    let bits = |a: &[CompensatedSum; NQ]| a.map(|c| (key(c.sum), key(c.comp)));
    let mut left_out = 0;
    for dim in 1..=3 {
        let nv = dim + 2;
        for seed in 0..30 {
            let cells = random_cells(nv, 61, 100 + seed);
            let lambda: Vec<f64> = (0..61)
                .map(|_| match (unit() * 10.0) as u32 {
                    0 => 1.0,
                    1 => 0.0,
                    2 => 1.0 + unit(),
                    3 => -unit(),
                    4 if seed % 3 == 0 => f64::NAN,
                    5 => 1.0 - 1e-17,
                    _ => unit(),
                })
                .collect();
            left_out += lambda.iter().filter(|&&l| 1.0 - l <= 0.0).count();
            let start: [CompensatedSum; NQ] = std::array::from_fn(|q| CompensatedSum {
                sum: 3.0 * q as f64 - 1.25,
                comp: 1e-17 * q as f64,
            });
            let mut want = start;
            for (cell, l) in cells.chunks_exact(nv).zip(&lambda) {
                let alpha = 1.0 - l;
                if alpha <= 0.0 {
                    continue;
                }
                want[0].add(alpha * cell[0]);
                for a in 0..dim {
                    want[1 + a].add(alpha * cell[1 + a]);
                }
                want[4].add(alpha * cell[dim + 1]);
            }
            for isa in Isa::available() {
                let mut acc = start;
                match nv {
                    3 => sum_weighted_on::<3>(isa, &mut acc, &cells, &lambda),
                    4 => sum_weighted_on::<4>(isa, &mut acc, &cells, &lambda),
                    _ => sum_weighted_on::<5>(isa, &mut acc, &cells, &lambda),
                }
                assert_eq!(bits(&acc), bits(&want), "{isa:?}, {dim}-D, seed {seed}");
            }
        }
    }
    assert!(left_out > 100, "{left_out} cells left out");
}
