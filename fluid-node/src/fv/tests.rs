//! Kernel unit tests: scalar OSMP orders, flux consistency, Roe decomposition, exact Riemann
//! star states, sweep orders.

use crate::fv::euler::*;
use crate::fv::exact_riemann::{ExactRiemann, Prim1};
use crate::fv::osmp::{SpeedLine, WaveLine, psi_line_dyn};

/// Speed and wave lines of `n_interfaces` interfaces for a constant speed `a`.
pub(super) fn line(n_interfaces: usize, a: f64, sigma: f64, order: u32) -> (SpeedLine, WaveLine) {
    let mut speed = SpeedLine::default();
    let mut wave = WaveLine::default();
    speed.resize(n_interfaces);
    wave.resize(n_interfaces);
    speed.lam.fill(a);
    speed.fill(order, sigma, 1.0 / sigma);
    (speed, wave)
}

/// Linear advection `u_t + a u_x = 0` of a sine over one period, periodic, CFL 0.5, with the
/// scalar OSMP kernel; returns the L1 error.
fn advect_sine(n: usize, a: f64, order: u32, limited: bool) -> f64 {
    let dx = 1.0 / n as f64;
    let t_end = 1.0 / a.abs();
    let steps = (t_end / (0.5 * dx / a.abs())).ceil() as usize;
    let dt = t_end / steps as f64;
    let sigma = dt / dx;
    let two_pi = 2.0 * std::f64::consts::PI;
    let u0: Vec<f64> = (0..n)
        .map(|i| {
            let (xa, xb) = (i as f64 * dx, (i + 1) as f64 * dx);
            ((two_pi * xa).cos() - (two_pi * xb).cos()) / (two_pi * dx)
        })
        .collect();
    let mut u = u0.clone();
    let ng = 4;
    let (mut speed, mut wave) = line(n + 2 * ng - 1, a, sigma, order);
    let mut psi = vec![0.0; n + 1];
    let mut flux = vec![0.0; n + 1];
    for _ in 0..steps {
        let ext: Vec<f64> = (0..n + 2 * ng).map(|i| u[(i + n - ng) % n]).collect();
        for l in 0..n + 2 * ng - 1 {
            wave.alpha[l] = ext[l + 1] - ext[l];
        }
        speed.fill(order, sigma, 1.0 / sigma);
        wave.fill(order, &speed);
        psi_line_dyn(order, limited, &speed, &wave, ng - 1, &mut psi);
        for (fi, f) in flux.iter_mut().enumerate() {
            let l = ng - 1 + fi;
            *f = 0.5 * a * (ext[l] + ext[l + 1]) - 0.5 * a.abs() * (wave.alpha[l] - psi[fi]);
        }
        for i in 0..n {
            u[i] -= sigma * (flux[i + 1] - flux[i]);
        }
    }
    u.iter().zip(&u0).map(|(x, y)| (x - y).abs()).sum::<f64>() * dx
}

#[test]
fn scalar_os_orders() {
    for order in [3u32, 5, 7] {
        for limited in [false, true] {
            for a in [1.0, -1.0] {
                let e: Vec<f64> = [20, 40, 80]
                    .iter()
                    .map(|&n| advect_sine(n, a, order, limited))
                    .collect();
                let rate = (e[1] / e[2]).log2();
                assert!(
                    rate > order as f64 - 0.2,
                    "order {order} limited {limited} a {a}: errors {e:?} rate {rate}"
                );
            }
        }
    }
}

#[test]
fn limited_scheme_keeps_square_wave_bounded() {
    // Square wave advected one period: the MP limiter allows no new extrema.
    let n = 100;
    let dx = 1.0 / n as f64;
    let a = 1.0;
    let sigma = 0.5;
    let mut u: Vec<f64> = (0..n)
        .map(|i| {
            let x = (i as f64 + 0.5) * dx;
            if (0.2..0.4).contains(&x) { 1.0 } else { 0.0 }
        })
        .collect();
    let ng = 4;
    let (mut speed, mut wave) = line(n + 2 * ng - 1, a, sigma, 7);
    let mut psi = vec![0.0; n + 1];
    for _ in 0..200 {
        let ext: Vec<f64> = (0..n + 2 * ng).map(|i| u[(i + n - ng) % n]).collect();
        for l in 0..n + 2 * ng - 1 {
            wave.alpha[l] = ext[l + 1] - ext[l];
        }
        speed.fill(7, sigma, 1.0 / sigma);
        wave.fill(7, &speed);
        psi_line_dyn(7, true, &speed, &wave, ng - 1, &mut psi);
        let flux: Vec<f64> = (0..=n)
            .map(|fi| {
                let l = ng - 1 + fi;
                a * ext[l] + 0.5 * a * psi[fi]
            })
            .collect();
        for i in 0..n {
            u[i] -= sigma * (flux[i + 1] - flux[i]);
        }
    }
    let max = u.iter().cloned().fold(f64::MIN, f64::max);
    let min = u.iter().cloned().fold(f64::MAX, f64::min);
    assert!(max <= 1.0 + 1e-12 && min >= -1e-12, "min {min} max {max}");
}

#[test]
fn roe_decomposition_reconstructs_jump() {
    let gamma = 1.4;
    let wl = Primitive {
        rho: 1.3,
        vel: [0.4, -0.7, 0.2],
        p: 2.1,
    };
    let wr = Primitive {
        rho: 0.6,
        vel: [-0.3, 0.5, 1.1],
        p: 0.4,
    };
    let (ul, ur) = (conserved(&wl, gamma), conserved(&wr, gamma));
    let roe = roe_average(&ul, &wl, &ur, &wr, gamma);
    assert!(roe.valid);
    let du: State = std::array::from_fn(|q| ur[q] - ul[q]);
    let alpha = roe_strengths(&roe, &du, gamma);
    let lam = roe_eigenvalues(&roe);
    let mut sum = [0.0; NQ];
    let mut flux_jump = [0.0; NQ];
    for k in 0..NQ {
        let r = roe_eigenvector(&roe, k);
        for q in 0..NQ {
            sum[q] += alpha[k] * r[q];
            flux_jump[q] += lam[k] * alpha[k] * r[q];
        }
    }
    let (fl, fr) = (physical_flux(&ul, &wl), physical_flux(&ur, &wr));
    for q in 0..NQ {
        assert!((sum[q] - du[q]).abs() < 1e-13, "R alpha != dU at {q}");
        // Roe property: A~ dU = dF.
        assert!(
            (flux_jump[q] - (fr[q] - fl[q])).abs() < 1e-13,
            "Roe property at {q}"
        );
    }
}

#[test]
fn fallback_fluxes_are_consistent() {
    let gamma = 1.4;
    let w = Primitive {
        rho: 0.8,
        vel: [0.3, -0.2, 0.1],
        p: 1.7,
    };
    let u = conserved(&w, gamma);
    let f = physical_flux(&u, &w);
    for g in [
        flux_hlle(&u, &u, gamma),
        flux_hllc(&u, &u, gamma),
        flux_lax_friedrichs(&u, &u, 0.3, gamma, 0.0),
    ] {
        for q in 0..NQ {
            assert!((g[q] - f[q]).abs() < 1e-14 * (1.0 + f[q].abs()));
        }
    }
}

#[test]
fn exact_riemann_star_states() {
    // numerics.md §4.2 (Toro's tables).
    let cases = [
        (
            (1.0, 0.0, 1.0),
            (0.125, 0.0, 0.1),
            [0.30313, 0.92745, 0.42632, 0.26557],
        ),
        (
            (0.445, 0.698, 3.528),
            (0.5, 0.0, 0.571),
            [2.4661, 1.52872, 0.34457, 1.30408],
        ),
        (
            (1.0, -2.0, 0.4),
            (1.0, 2.0, 0.4),
            [0.00189, 0.0, 0.02185, 0.02185],
        ),
        (
            (1.0, 0.0, 1000.0),
            (1.0, 0.0, 0.01),
            [460.894, 19.5975, 0.57506, 5.99924],
        ),
    ];
    for (l, r, want) in cases {
        let want: [f64; 4] = want;
        let ex = ExactRiemann::new(
            Prim1 {
                rho: l.0,
                u: l.1,
                p: l.2,
            },
            Prim1 {
                rho: r.0,
                u: r.1,
                p: r.2,
            },
            1.4,
        )
        .expect("physical data");
        let got = [ex.p_star, ex.u_star, ex.rho_star_left, ex.rho_star_right];
        for k in 0..4 {
            let tol = f64::max(6e-5 * want[k].abs(), 5e-6);
            assert!(
                (got[k] - want[k]).abs() < tol,
                "{l:?}|{r:?}: {got:?} vs {want:?}"
            );
        }
    }
}

#[test]
fn exact_cell_average_matches_fine_midpoint_rule() {
    let ex = ExactRiemann::new(
        Prim1 {
            rho: 1.0,
            u: 0.0,
            p: 1.0,
        },
        Prim1 {
            rho: 0.125,
            u: 0.0,
            p: 0.1,
        },
        1.4,
    )
    .expect("sod");
    // A cell holding the rarefaction tail and the contact.
    let (xa, xb) = (0.45, 0.72);
    let avg = ex.cell_average(xa, xb, 0.5, 0.2);
    let n = 200_000;
    let mut mid = [0.0; 3];
    for k in 0..n {
        let x = xa + (k as f64 + 0.5) * (xb - xa) / n as f64;
        let v = ex.conserved_at(x, 0.5, 0.2);
        for q in 0..3 {
            mid[q] += v[q] / n as f64;
        }
    }
    for q in 0..3 {
        assert!((avg[q] - mid[q]).abs() < 1e-6, "{avg:?} vs {mid:?}");
    }
}

#[test]
fn sweep_orders_cover_permutations_in_reverse_pairs() {
    let mut seen = std::collections::BTreeSet::new();
    for s in 0..6 {
        let o = crate::fv::sweep_order(3, s);
        seen.insert(o.clone());
        if s % 2 == 1 {
            let mut prev = crate::fv::sweep_order(3, s - 1);
            prev.reverse();
            assert_eq!(o, prev);
        }
    }
    assert_eq!(seen.len(), 6);
    assert_eq!(crate::fv::sweep_order(2, 0), vec![0, 1]);
    assert_eq!(crate::fv::sweep_order(2, 1), vec![1, 0]);
}

#[test]
fn branch_free_minmod_is_minmod() {
    // minmod4 against its definition (0 unless all four share a sign, else the smallest
    // magnitude), over values with zeros of both signs, ties, tiny and huge magnitudes.
    use crate::fv::osmp::minmod4;
    let values = [
        0.0, -0.0, 1.0, -1.0, 2.5, -2.5, 1e-300, -1e-300, 3e300, -3e300, 1.0, 0.5,
    ];
    let reference = |x: [f64; 4]| {
        if x.iter().all(|v| *v > 0.0) {
            x.iter().cloned().fold(f64::INFINITY, f64::min)
        } else if x.iter().all(|v| *v < 0.0) {
            x.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
        } else {
            0.0
        }
    };
    let mut checked = 0;
    for &a in &values {
        for &b in &values {
            for &c in &values {
                for &d in &values {
                    let got = minmod4(a, b, c, d);
                    let want = reference([a, b, c, d]);
                    assert!(
                        got == want,
                        "minmod4({a}, {b}, {c}, {d}) = {got}, expected {want}"
                    );
                    checked += 1;
                }
            }
        }
    }
    assert_eq!(checked, values.len().pow(4));
}

#[test]
fn a_mirror_state_reverses_the_velocity_normal_to_the_wall_only() {
    use crate::fv::sweep::{Wall, mirror};
    let gamma = 1.4;
    let w = Primitive {
        rho: 1.3,
        vel: [0.7, -1.9, 0.4],
        p: 2.5,
    };
    let s = conserved(&w, gamma);
    let len = (0.36f64 + 0.64 + 0.25).sqrt();
    let wall = Wall {
        velocity: [0.2, 0.1, -0.3],
        normal: [0.6 / len, 0.8 / len, -0.5 / len],
    };
    let g = primitive(&mirror(&s, &wall), gamma);
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let rel = |v: [f64; 3]| std::array::from_fn(|a| v[a] - wall.velocity[a]);
    let (r0, r1) = (rel(w.vel), rel(g.vel));
    assert_eq!(g.rho, w.rho);
    assert!((g.p - w.p).abs() <= 1e-14 * w.p, "p {} -> {}", w.p, g.p);
    let (n0, n1) = (dot(r0, wall.normal), dot(r1, wall.normal));
    assert!((n0 + n1).abs() <= 1e-14, "normal {n0} -> {n1}");
    for a in 0..3 {
        let (t0, t1) = (r0[a] - n0 * wall.normal[a], r1[a] - n1 * wall.normal[a]);
        assert!((t0 - t1).abs() <= 1e-14, "tangential {a}: {t0} -> {t1}");
    }
    // A wall normal to the sweep axis: `m → 2 ρ w − m` exactly, as along the sweep line.
    let axis = Wall {
        velocity: [0.2, 5.0, 5.0],
        normal: [-1.0, 0.0, 0.0],
    };
    let g = mirror(&s, &axis);
    assert_eq!(g[1], s[0] * 2.0 * 0.2 - s[1]);
    assert_eq!([g[0], g[2], g[3]], [s[0], s[2], s[3]]);
}

/// A decomposed line whose wall runs begin or end inside its ghost cells (issue 16): the ghosts
/// there are the mirror ghosts of the one-rank segment, so every face of the line, up to its
/// last, gets the one-rank flux bit for bit (the kept fluxes at both ends of the line see the
/// mirrored cells), and the rank's own cells the one-rank states.
#[test]
fn wall_runs_in_a_decomposed_lines_ghost_cells_give_one_rank_fluxes() {
    use crate::fv::line::FluxKind;
    use crate::fv::line::LineScratch;
    use crate::fv::slab::Slab;
    use crate::fv::state::{BoundaryKind, FluidParams};
    use crate::fv::sweep::{FaceTap, PencilOut, SlabHalo, Wall, WallRun, sweep_axis};
    use crate::grid::Grid;
    use std::sync::Mutex;

    let n = 40;
    let global = Grid::new(&[0.0], &[1.0], &[n]).expect("grid");
    let params = FluidParams {
        gamma: 1.4,
        cfl: 0.5,
        flux: FluxKind::Osmp(5),
        boundary: [[BoundaryKind::Wall; 2]; 3],
        vacuum_rho: 1e-10,
        vacuum_p: 1e-10,
    };
    // Rank 1 of 5 owns cells 8..16; its line runs over 5..19 with ghosts 2..5 and 19..22.
    let slab = Slab::new(&global, 1, [5, 1, 1], 3, [[BoundaryKind::Wall; 2]; 3]).expect("slab");
    assert_eq!((slab.offset[0], slab.depth, slab.overlap), (8, 6, 3));
    let nvar = 3;
    let mut u = smooth_1d(n);
    // Covered cells 2–3 and 20–21 hold states of their own (a ghost state of another sweep).
    for i in [2, 3, 20, 21] {
        u[i * nvar..(i + 1) * nvar].copy_from_slice(&[5.0, 1.0, 20.0]);
    }
    let mut moving = Wall::at_rest(0);
    moving.velocity[0] = 0.1;
    let walls = [
        WallRun {
            pencil: 0,
            lo: 2,
            hi: 4,
            walls: [moving, Wall::at_rest(0)],
        },
        WallRun {
            pencil: 0,
            lo: 20,
            hi: 22,
            walls: [Wall::at_rest(0), moving],
        },
    ];
    let dt = 0.2 / n as f64;
    let scratch = vec![Mutex::new(LineScratch::default())];
    let sweep = |grid: &Grid, u_in: &[f64], positions: Vec<u32>, halo: &SlabHalo<'_>| {
        let mut out = vec![0.0; u_in.len()];
        let mut reports = vec![PencilOut::default(); 1];
        let mut tap = FaceTap::default();
        tap.clear(1);
        tap.pencil_offsets[1] = positions.len() as u32;
        tap.positions = positions;
        sweep_axis(
            grid,
            &params,
            0,
            dt,
            u_in,
            &mut out,
            &scratch,
            &mut reports,
            Some(&mut tap),
            &walls,
            halo,
        );
        (out, tap.flux)
    };
    let (one, one_flux) = sweep(&global, &u, vec![5, 12, 19], &SlabHalo::none(n));
    let halo = SlabHalo {
        lo: Some(&u[2 * nvar..8 * nvar]),
        hi: Some(&u[16 * nvar..22 * nvar]),
        depth: 6,
        overlap: 3,
        n_global: n,
        start: 5,
    };
    let (rank, rank_flux) = sweep(&slab.local, &u[8 * nvar..16 * nvar], vec![0, 7, 14], &halo);
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    for (k, (a, b)) in one_flux.iter().zip(&rank_flux).enumerate() {
        assert_eq!(
            bits(a),
            bits(b),
            "kept face {k}: {a:?} on one rank, {b:?} on the slab"
        );
    }
    assert_eq!(bits(&one[8 * nvar..16 * nvar]), bits(&rank), "own cells");
}

/// The faces inside a wall run carry the two-point flux between the run's ghost states (kept
/// for the correct, where a face the solid uncovers takes it): a uniform flow with the walls at
/// its velocity gives its own flux there, as at the run's ends (they carried none before, and
/// a uniform flow carried past a thin box in 3-D lost its uniformity where such faces opened).
/// A run of vacuum ghosts gives finite fluxes (Lax–Friedrichs).
#[test]
fn faces_inside_a_wall_run_carry_the_flux_of_its_ghost_states() {
    use crate::fv::line::{FluxKind, LineScratch};
    use crate::fv::state::{BoundaryKind, FluidParams};
    use crate::fv::sweep::{FaceTap, PencilOut, SlabHalo, Wall, WallRun, sweep_axis};
    use crate::grid::Grid;
    use std::sync::Mutex;

    let n = 20;
    let grid = Grid::new(&[0.0], &[1.0], &[n]).expect("grid");
    let params = FluidParams {
        gamma: 1.4,
        cfl: 0.5,
        flux: FluxKind::Osmp(3),
        boundary: [[BoundaryKind::Periodic; 2]; 3],
        vacuum_rho: 1e-10,
        vacuum_p: 1e-10,
    };
    let (rho, vel, p) = (1.4, 0.4, 1.0);
    let e = p / 0.4 + 0.5 * rho * vel * vel;
    let exact = [rho * vel, rho * vel * vel + p, 0.0, 0.0, vel * (e + p)];
    let mut wall = Wall::at_rest(0);
    wall.velocity[0] = vel;
    let walls = [WallRun {
        pencil: 0,
        lo: 8,
        hi: 11,
        walls: [wall; 2],
    }];
    let scratch = vec![Mutex::new(LineScratch::default())];
    for ghost in [[rho, rho * vel, e], [0.0; 3]] {
        let mut u: Vec<f64> = (0..n).flat_map(|_| [rho, rho * vel, e]).collect();
        for i in 8..11 {
            u[i * 3..i * 3 + 3].copy_from_slice(&ghost);
        }
        let mut out = vec![0.0; u.len()];
        let mut reports = vec![PencilOut::default(); 1];
        let mut tap = FaceTap::default();
        tap.clear(1);
        tap.positions = vec![8, 9, 10, 11];
        tap.pencil_offsets[1] = 4;
        let (halo, dt) = (SlabHalo::none(n), 0.5 / n as f64);
        let (reports, tapped) = (&mut reports, Some(&mut tap));
        sweep_axis(
            &grid, &params, 0, dt, &u, &mut out, &scratch, reports, tapped, &walls, &halo,
        );
        for (face, f) in (8..=11).zip(&tap.flux) {
            assert!(f.iter().all(|x| x.is_finite()), "face {face}: {f:?}");
            let err = (0..5).map(|q| (f[q] - exact[q]).abs()).fold(0.0, f64::max);
            assert!(
                ghost[0] == 0.0 || err <= 1e-14,
                "face {face}: {f:?}, exact {exact:?}"
            );
        }
    }
}

/// The same pencil cut into 5 slabs of 8 cells, with wall runs that start at a cut (cells
/// 16–17, the first of rank 2) and end at one (22–23, before rank 3): every rank's cells get
/// the one-rank states, and the face counters summed over the ranks are the one-rank ones
/// (a face at a cut is counted once), also when every face takes Lax–Friedrichs (all cells
/// below the vacuum threshold).
#[test]
fn wall_runs_at_the_cuts_give_one_rank_states_and_counters() {
    use crate::fv::line::FluxKind;
    use crate::fv::line::LineScratch;
    use crate::fv::slab::Slab;
    use crate::fv::state::{BoundaryKind, FluidParams};
    use crate::fv::sweep::{PencilOut, SlabHalo, Wall, WallRun, sweep_axis};
    use crate::grid::Grid;
    use std::sync::Mutex;

    let n = 40;
    let global = Grid::new(&[0.0], &[1.0], &[n]).expect("grid");
    let nvar = 3;
    let mut u = smooth_1d(n);
    for i in [16, 17, 22, 23] {
        u[i * nvar..(i + 1) * nvar].copy_from_slice(&[5.0, 1.0, 20.0]);
    }
    let walls = [
        WallRun {
            pencil: 0,
            lo: 16,
            hi: 18,
            walls: [Wall::at_rest(0); 2],
        },
        WallRun {
            pencil: 0,
            lo: 22,
            hi: 24,
            walls: [Wall::at_rest(0); 2],
        },
    ];
    let dt = 0.2 / n as f64;
    let scratch = vec![Mutex::new(LineScratch::default())];
    for vacuum_rho in [1e-10, 100.0] {
        let params = FluidParams {
            gamma: 1.4,
            cfl: 0.5,
            flux: FluxKind::Osmp(5),
            boundary: [[BoundaryKind::Wall; 2]; 3],
            vacuum_rho,
            vacuum_p: 1e-10,
        };
        let sweep = |grid: &Grid, u_in: &[f64], halo: &SlabHalo<'_>| {
            let mut out = vec![0.0; u_in.len()];
            let mut reports = vec![PencilOut::default(); 1];
            sweep_axis(
                grid,
                &params,
                0,
                dt,
                u_in,
                &mut out,
                &scratch,
                &mut reports,
                None,
                &walls,
                halo,
            );
            (out, reports[0].stats)
        };
        let (one, one_stats) = sweep(&global, &u, &SlabHalo::none(n));
        let mut states = Vec::new();
        let mut counts = [0u32; 3];
        for rank in 0..5 {
            let bc = [[BoundaryKind::Wall; 2]; 3];
            let slab = Slab::new(&global, rank, [5, 1, 1], 3, bc).expect("slab");
            let (lo, hi, d) = (slab.offset[0], slab.offset[0] + 8, slab.depth);
            let halo = SlabHalo {
                lo: slab.lo[0].map(|_| &u[(lo - d) * nvar..lo * nvar]),
                hi: slab.hi[0].map(|_| &u[hi * nvar..(hi + d) * nvar]),
                depth: d,
                overlap: slab.overlap,
                n_global: n,
                start: lo as isize - if slab.lo[0].is_some() { 3 } else { 0 },
            };
            let (out, stats) = sweep(&slab.local, &u[lo * nvar..hi * nvar], &halo);
            states.extend(out);
            counts[0] += stats.lax_friedrichs;
            counts[1] += stats.hlle;
            counts[2] += stats.positivity_fixes;
        }
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(
            bits(&one),
            bits(&states),
            "vacuum below {vacuum_rho}: states"
        );
        let expected = [
            one_stats.lax_friedrichs,
            one_stats.hlle,
            one_stats.positivity_fixes,
        ];
        assert_eq!(
            expected, counts,
            "vacuum below {vacuum_rho}: lf, hlle, fixes"
        );
        if vacuum_rho > 1.0 {
            assert!(
                expected[0] > 30,
                "every face takes Lax–Friedrichs: {expected:?}"
            );
        }
    }
}

/// A smooth 1-D state of `n` cells (ρ, ρu, E with γ = 1.4) for the kernel tests of pencils cut
/// by walls at the rank cuts.
fn smooth_1d(n: usize) -> Vec<f64> {
    let nvar = 3;
    let mut u = vec![0.0; n * nvar];
    for i in 0..n {
        let x = (i as f64 + 0.5) / n as f64;
        let (rho, vel, p) = (
            1.0 + 0.3 * (7.0 * x).sin(),
            0.4 * (5.0 * x).cos(),
            1.0 + 0.2 * x,
        );
        u[i * nvar..(i + 1) * nvar].copy_from_slice(&[
            rho,
            rho * vel,
            p / 0.4 + 0.5 * rho * vel * vel,
        ]);
    }
    u
}

/// What the sweeps accept after an update (`line::state_ok`, thresholds 1e-10): gas, and vacuum
/// whose density and pressure are round-off of either sign (the crack cells of
/// `opening-fracture-3d` on 75³, where the crack plane is not a cell face: ρ = 1.4e-19 moving at
/// 6 m/s gives p = −1.0e-18; ρ = −1.7e-18 at rest), but not a negative density or pressure
/// beyond the thresholds, nor a gas with p < 0, nor a non-finite state.
#[test]
fn vacuum_cells_may_hold_round_off_of_either_sign() {
    use crate::fv::line::state_ok;
    let (g, vr, vp) = (1.4, 1e-10, 1e-10);
    let ok = |w: Primitive| state_ok(&conserved(&w, g), g, vr, vp);
    let w = |rho: f64, u: f64, p: f64| Primitive {
        rho,
        vel: [u, 0.0, 0.0],
        p,
    };
    assert!(ok(w(1.4, 3.0, 1.0)));
    assert!(ok(w(0.0, 0.0, 0.0)));
    assert!(ok(w(1.4456e-19, -6.0, -1.0408e-18)));
    assert!(ok(w(-1.7347e-18, 0.0, 0.0)));
    assert!(ok(w(1e-12, 0.0, -9e-11)));
    // Beyond minus the thresholds.
    assert!(!ok(w(-2e-10, 0.0, 0.0)));
    assert!(!ok(w(1e-12, 0.0, -2e-10)));
    // A gas of vacuum pressure, and one below it (p = −202 Pa beside a crack's mouth).
    assert!(ok(w(1.0, 0.0, 1e-12)));
    assert!(!ok(w(1.0, 0.0, -1e-9)));
    assert!(!ok(w(1.0, 0.0, -202.0)));
    assert!(!ok(w(f64::NAN, 0.0, 1.0)));
    assert!(!ok(w(1.0, f64::INFINITY, 1.0)));
}

/// The y line of `osmp_bounds_are_well_conditioned_at_a_stagnation_point`: conserved states
/// (ρ, ρv, ρu, 0, E) of 18 cells, in the sweep's frame (normal momentum second).
#[rustfmt::skip]
const STAGNATION_LINE: [State; 18] = [
    [1.1799046273189822e0, -3.458900995309489e-2, 6.75329163348555e-3, 0e0, 2.5328414319943776e5],
    [1.1173858785201667e0, 2.2357541397410635e1, 9.839868489599746e-1, 0e0, 2.3439940079133774e5],
    [2.868860860326211e-1, 2.742242654281947e1, 5.430311590458234e1, 0e0, 7.590896242434661e4],
    [2.228096630561372e-1, -2.3651104397392392e-1, 5.867094951516644e1, 0e0, 5.6209779503528545e4],
    [2.2990768477818474e-1, -2.733991161750956e-1, 6.261362179348206e1, 0e0, 5.821986550371284e4],
    [2.4103397321515366e-1, -5.672832526886702e0, 6.43075862394897e1, 0e0, 6.144040491876542e4],
    [8.452910897894417e-1, -1.2839060462681666e0, 1.754416335270112e1, 0e0, 1.8267369272046836e5],
    [8.745088192389155e-1, -1.0030898674942272e0, 1.785653622066777e1, 0e0, 1.8879304577950112e5],
    [9.085292247279981e-1, -4.660128805880735e-1, 1.8370375183483883e1, 0e0, 1.9607360052243783e5],
    [9.085292247280043e-1, 4.6601288058732065e-1, 1.8370375183484335e1, 0e0, 1.960736005224394e5],
    [8.745088192389421e-1, 1.003089867493518e0, 1.7856536220667692e1, 0e0, 1.887930457795067e5],
    [8.452910897893636e-1, 1.2839060462688396e0, 1.754416335269919e1, 0e0, 1.8267369272045148e5],
    [2.410339732151502e-1, 5.672832526886873e0, 6.430758623948745e1, 0e0, 6.144040491876442e4],
    [2.299076847781501e-1, 2.7339911617464446e-1, 6.261362179347195e1, 0e0, 5.821986550370421e4],
    [2.2280966305612282e-1, 2.3651104397427003e-1, 5.867094951516263e1, 0e0, 5.6209779503524944e4],
    [2.868860860326589e-1, -2.7422426542837513e1, 5.430311590457717e1, 0e0, 7.59089624243602e4],
    [1.1173858785201762e0, -2.2357541397391913e1, 9.839868489574933e-1, 0e0, 2.3439940079133373e5],
    [1.179904627318794e0, 3.4589009952323314e-2, 6.753291637501213e-3, 0e0, 2.5328414319939798e5],
];

/// A y line of `cylinder-explosion` beside the ring's symmetry axis (step 2, x = 14.9 m): the
/// flow is mirror-symmetric about the face between cells 8 and 9 up to 1e-14 of round-off, and
/// the entropy and shear waves stagnate there (v = ±0.5 m/s on either side). The fluxes of the
/// two faces next to it must be mirror images to the size of that round-off: with the UL bound
/// divided by ν_up alone they differed by 2.3e-4 (α_up/ν_up was round-off over round-off).
#[test]
fn osmp_bounds_are_well_conditioned_at_a_stagnation_point() {
    use crate::fv::line::{FluxKind, LineScratch, LineSetup, advance_line};
    let cells = STAGNATION_LINE;
    let ng = 3;
    let n = cells.len() - 2 * ng;
    let setup = LineSetup {
        n,
        ng,
        flux: FluxKind::Osmp(5),
        sigma: 2.6666666666666673e-4,
        gamma: 1.4,
        n_shear: 1,
        vacuum_rho: 1e-10,
        vacuum_p: 1e-10,
        wall: [false, false],
        own: [0, n],
        end_face: true,
    };
    let mut s = LineScratch::default();
    s.resize(n, ng);
    s.u.copy_from_slice(&cells);
    advance_line(&mut s, &setup);
    // Face f lies between line cells ng − 1 + f and ng + f: the axis is face 6.
    let (below, above) = (s.face[5], s.face[7]);
    let scale = below[0].abs().max(1.0);
    let mass = (below[0] + above[0]).abs() / scale;
    let energy = (below[4] + above[4]).abs() / below[4].abs();
    let momentum = (below[1] - above[1]).abs() / below[1].abs();
    assert!(
        mass < 1e-10 && energy < 1e-10 && momentum < 1e-10,
        "mirror faces differ: mass {mass:e}, normal momentum {momentum:e}, energy {energy:e}"
    );
}

/// A y line of `cube-mobile-walls` with flush walls (50³ cells, step 10, x = 1.30 m, the
/// crack between walls 4 and 5): the crack cell in the middle holds round-off, ρ = 5.0e-32 and
/// a tangential momentum of 6.9e-18, left there when a Lax–Friedrichs step beside vacuum
/// emptied it (that flux moves a lone cell's content to its two neighbours exactly). Read as
/// `ρu/ρ` that is a velocity of 1.4e14 m/s and p = −1.9e-4; the energy fluxes beside it were
/// −3.5e3, and the gas next to it came out at p = −238 Pa. Below the vacuum density the
/// velocity is `ρu / ρ_vacuum`: the cell reads as vacuum at rest, the line stays physical and
/// its CFL speed finite.
#[rustfmt::skip]
#[test]
fn round_off_in_an_emptied_crack_cell_moves_nothing() {
    use crate::fv::euler::{primitive, primitive_floored};
    use crate::fv::line::{FluxKind, LineScratch, LineSetup, advance_line, state_ok};
    let line: [State; 9] = [
        [1.3877573663015275, -2.525095827585579e-5, 7.621050896416449e-4, 0.04060555390772559, 2.4699725121852856],
        [1.3900475947536617, -2.159299071647394e-3, 2.2942011356795943e-3, 0.04271764671691919, 2.4756279247113544],
        [1.405893831579985, 2.182831647179544e-3, 0.016590384714092056, 0.06026697835029541, 2.5144620233119475],
        [1.419677241419656, 4.0919468494803185e-3, 0.011163266950482597, 0.05692641525254691, 2.5477428862801035],
        [5.021535620565968e-32, 1.8204671783454832e-24, 6.9388939039064734e-18, -1.581139858577762e-24, 0.0],
        [0.7674762062212299, -0.07356794904425812, 0.010339244126397865, 0.039444807370233204, 1.4182075748758363],
        [1.5299506631340052, -0.14708100243632505, 5.941018433238184e-3, 2.3220676271402008e-4, 2.8239306490377514],
        [1.3909567459733758, -7.970787740872981e-3, 2.4499848578788877e-4, 2.2643788057287602e-3, 2.475696497328243],
        [1.3971463406752096, -3.0656367712483578e-3, 4.954667190401844e-5, 6.244999161256795e-4, 2.4927063705911037],
    ];
    let (ng, n) = (3, 3);
    let (g, vr, vp) = (1.4, 1e-10, 1e-10);
    let setup = LineSetup {
        n,
        ng,
        flux: FluxKind::Osmp(5),
        sigma: 0.2 / 1.5,
        gamma: g,
        n_shear: 2,
        vacuum_rho: vr,
        vacuum_p: vp,
        wall: [false, false],
        own: [0, n],
        end_face: true,
    };
    let speed = |w: crate::fv::euler::Primitive| w.vel.iter().map(|v| v.abs()).fold(0.0, f64::max);
    assert!(speed(primitive(&line[4], g)) > 1e14);
    assert!(speed(primitive_floored(&line[4], g, vr)) < 1e-7);
    assert!(state_ok(&line[4], g, vr, vp));
    let mut s = LineScratch::default();
    s.resize(n, ng);
    s.u.copy_from_slice(&line);
    let stats = advance_line(&mut s, &setup);
    assert_eq!(stats.first_bad, None, "{:?}", &s.new[..n]);
    for (m, u) in s.new[..n].iter().enumerate() {
        let w = primitive_floored(u, g, vr);
        assert!(state_ok(u, g, vr, vp), "cell {m}: {u:?}");
        assert!(w.rho > 0.1 && w.p > 0.1, "cell {m}: {w:?}");
    }
    for (f, flux) in s.face[..=n].iter().enumerate() {
        assert!(flux[4].abs() < 10.0, "face {f}: {flux:?}");
    }
}
