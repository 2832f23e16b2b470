//! Riemann problems (Sod, Lax, Toro 123, Toro 3; numerics.md §4.2) against the exact
//! solution: 1-D L1 density errors at N = 100, 200, 400 for OSMP3/5/7 (regression bounds 10 %
//! above the measured values, and convergence), positivity, the same problems as planar flows
//! along each axis of 2-D and 3-D grids (identical to 1-D to round-off, and the same L1), and
//! along the 2-D diagonal.

use crate::fv_common;

use fluid_node::fv::FluxKind;
use fv_common::*;

/// Measured L1(ρ) per case, order (3, 5, 7) and N (100, 200, 400), 1-D, CFL 0.5.
const MEASURED_1D: [(&str, [[f64; 3]; 3]); 4] = [
    (
        "sod",
        [
            [2.7291e-3, 1.6303e-3, 8.3803e-4],
            [2.1492e-3, 1.2607e-3, 6.0658e-4],
            [2.1672e-3, 1.2186e-3, 5.8262e-4],
        ],
    ),
    (
        "lax",
        [
            [1.2398e-2, 6.0567e-3, 3.5375e-3],
            [9.2981e-3, 4.0499e-3, 2.3070e-3],
            [8.2051e-3, 3.4248e-3, 1.9334e-3],
        ],
    ),
    (
        "toro-123",
        [
            [1.3150e-2, 6.2321e-3, 3.2045e-3],
            [2.8082e-2, 1.3854e-2, 7.0763e-3],
            [3.9934e-2, 2.6420e-2, 1.2199e-2],
        ],
    ),
    (
        "toro-3",
        [
            [6.9282e-2, 4.9566e-2, 2.8362e-2],
            [5.3548e-2, 3.6388e-2, 1.9808e-2],
            [4.8166e-2, 3.2547e-2, 1.7537e-2],
        ],
    ),
];

#[test]
fn riemann_1d_l1_errors() {
    for (case, (name, table)) in CASES.iter().zip(MEASURED_1D) {
        assert_eq!(case.name, name);
        for (k, order) in [3u32, 5, 7].into_iter().enumerate() {
            let mut errs = Vec::new();
            for (m, n) in [100, 200, 400].into_iter().enumerate() {
                let r = run_case(case, n, FluxKind::Osmp(order), Layout::OneD, 1);
                println!(
                    "{name} OSMP{order} N={n}: L1 {:.4e}, min rho {:.3e}, min p {:.3e}, {} steps",
                    r.l1, r.min_rho, r.min_p, r.steps
                );
                assert!(r.ok, "{name} OSMP{order} N={n}: trouble");
                assert!(r.min_rho > 0.0 && r.min_p > 0.0, "{name}: lost positivity");
                assert!(
                    r.l1 <= 1.1 * table[k][m],
                    "{name} OSMP{order} N={n}: L1 {} above 1.1 x {}",
                    r.l1,
                    table[k][m]
                );
                errs.push(r.l1);
            }
            assert!(
                errs[2] < 0.75 * errs[0],
                "{name} OSMP{order}: no convergence {errs:?}"
            );
        }
    }
}

#[test]
fn sod_n400_meets_target_at_orders_5_and_7() {
    for order in [5, 7] {
        let r = run_case(&SOD, 400, FluxKind::Osmp(order), Layout::OneD, 1);
        assert!(r.l1 < 9.6e-4, "OSMP{order}: {}", r.l1);
    }
}

#[test]
fn planar_problems_along_each_axis_match_1d() {
    for case in CASES {
        for order in [5, 7] {
            let one = run_case(&case, 100, FluxKind::Osmp(order), Layout::OneD, 1);
            for (dim, axis) in [(2, 0), (2, 1), (3, 0), (3, 1), (3, 2)] {
                let r = run_case(
                    &case,
                    100,
                    FluxKind::Osmp(order),
                    Layout::Axis { dim, axis },
                    2,
                );
                assert!(r.ok, "{} {dim}-D axis {axis}: trouble", case.name);
                // Same L1 against the exact solution as in 1-D.
                assert!(
                    (r.l1 - one.l1).abs() <= 1e-12 * one.l1,
                    "{} {dim}-D axis {axis}: L1 {} vs 1-D {}",
                    case.name,
                    r.l1,
                    one.l1
                );
                // Every pencil equals the 1-D solution (transverse sweeps are exact no-ops).
                let grid = r.solver.grid();
                for idx in 0..grid.n_cells() {
                    let m = grid.ijk(idx)[axis];
                    let (rho, vel, p) = r.solver.primitive(idx);
                    let (rho1, vel1, p1) = one.solver.primitive(m);
                    assert!(
                        (rho - rho1).abs() <= 1e-13 * rho1
                            && (p - p1).abs() <= 1e-13 * p1.max(1e-3)
                            && (vel[axis] - vel1[0]).abs() <= 1e-12,
                        "{} {dim}-D axis {axis} cell {idx}",
                        case.name
                    );
                }
            }
        }
    }
}

/// Measured L1(ρ) on the 2-D diagonal, N = 100 per unit length, per case and order 5, 7.
const MEASURED_DIAGONAL: [[f64; 2]; 4] = [
    [1.2966e-3, 1.0985e-3],
    [3.3025e-3, 2.7955e-3],
    [4.6403e-3, 5.5328e-3],
    [2.5657e-2, 2.2561e-2],
];

#[test]
fn riemann_problems_along_the_2d_diagonal() {
    for (case, table) in CASES.iter().zip(MEASURED_DIAGONAL) {
        for (k, order) in [5u32, 7].into_iter().enumerate() {
            let r = run_case(case, 100, FluxKind::Osmp(order), Layout::Diagonal, 2);
            println!(
                "{} diagonal OSMP{order} N=100: L1 {:.4e} min rho {:.3e} min p {:.3e}",
                case.name, r.l1, r.min_rho, r.min_p
            );
            assert!(r.ok && r.min_rho > 0.0 && r.min_p > 0.0, "{}", case.name);
            assert!(
                r.l1 <= 1.1 * table[k],
                "{} diagonal OSMP{order}: {} above 1.1 x {}",
                case.name,
                r.l1,
                table[k]
            );
        }
    }
    // Convergence along the diagonal (Sod, OSMP5).
    let n_fine = if slow_tests() { 200 } else { 100 };
    let coarse = run_case(&SOD, 50, FluxKind::Osmp(5), Layout::Diagonal, 2).l1;
    let fine = run_case(&SOD, n_fine, FluxKind::Osmp(5), Layout::Diagonal, 2).l1;
    println!("sod diagonal OSMP5: N=50 {coarse:.4e}, N={n_fine} {fine:.4e}");
    assert!(fine < 0.75 * coarse, "{coarse} -> {fine}");
}
