//! A crack opening in gas at rest (issue 14 items 1–3, paper 000 §3.2–3.3): two square
//! particles whose shared face has just become wet on both sides fly apart. The covered cells
//! between the two faces hold no fluid: they are vacuum, the faces beside them take the
//! Lax–Friedrichs flux, the crack fills from its mouths, and mass, momentum and energy close
//! against what crossed the interface to round-off.

use crate::embedded_support;

use embedded_support::{at_rest_in_unit_box, solver};
use fluid_node::embedded::{Embedded, SolidFrame};
use fluid_node::fv::FluidSolver;

/// Off the grid lines by 0.3 of a cell, so no face lies on a grid plane.
const X0: f64 = 0.3075;
const MID: f64 = 0.5075;
const X1: f64 = 0.7075;
const Y0: f64 = 0.3075;
const Y1: f64 = 0.7075;

/// Two squares side by side, split at `MID` (the crack), the left one moved by `-s`, the right
/// one by `+s` along x, moving at `∓u`. Every face is wet: the link between them has broken.
fn pair(s: f64, u: f64) -> SolidFrame {
    pair_between(Y0, Y1, s, u)
}

/// [`pair`] of rectangles from `y0` to `y1`.
pub(crate) fn pair_between(y0: f64, y1: f64, s: f64, u: f64) -> SolidFrame {
    let square = |a: f64, b: f64| [[a, y0], [b, y0], [b, y1], [a, y1]];
    let (l, r) = (square(X0 - s, MID - s), square(MID + s, X1 + s));
    let vertices: Vec<f64> = l.iter().chain(&r).flatten().copied().collect();
    let mut elements = Vec::new();
    for p in 0..2u32 {
        for i in 0..4u32 {
            elements.extend([4 * p + i, 4 * p + (i + 1) % 4]);
        }
    }
    let centre = |q: &[[f64; 2]; 4]| [(q[0][0] + q[1][0]) / 2.0, (y0 + y1) / 2.0];
    let (cl, cr) = (centre(&l), centre(&r));
    SolidFrame {
        dim: 2,
        position: vec![cl[0], cl[1], cr[0], cr[1]],
        velocity: vec![-u, 0.0, u, 0.0],
        angular_velocity: vec![0.0, 0.0],
        vertices,
        elements,
        element_particle: vec![0, 0, 0, 0, 1, 1, 1, 1],
        wet: vec![true; 8],
    }
}

/// Cells holding fluid whose density is below the vacuum threshold.
fn vacuum_cells(solver: &FluidSolver, embedded: &Embedded) -> usize {
    let lambda = embedded.solid_fraction();
    (0..solver.grid().n_cells())
        .filter(|&c| lambda[c] < 1.0 - 1e-12 && solver.primitive(c).0 < 1e-10)
        .count()
}

/// The forces `[left x, left y, right x, right y]` on the pair at rest position from `p̄ = (1 +
/// p_predicted) / 2` of the cells (40² cells of 0.025) holding their faces, vacuum in the
/// crack's covered cells.
fn crack_loads(solver: &FluidSolver) -> [f64; 4] {
    let dx = 0.025;
    let grid = solver.grid();
    let p_bar = |i: usize, j: usize| 0.5 * (1.0 + solver.primitive(grid.index(i, j, 0)).2);
    // The pieces of [a, b] in the cells of width dx: (cell, length).
    let pieces = |a: f64, b: f64| -> Vec<(usize, f64)> {
        let (first, last) = ((a / dx).floor() as usize, (b / dx).floor() as usize);
        (first..=last)
            .map(|i| (i, (b.min((i + 1) as f64 * dx) - a.max(i as f64 * dx))))
            .collect()
    };
    let column = |x: f64| (x / dx).floor() as usize;
    let row = |y: f64| (y / dx).floor() as usize;
    let mut f = [0.0; 4];
    for (p, (lo, hi)) in [(X0, MID), (MID, X1)].into_iter().enumerate() {
        for (j, len) in pieces(Y0, Y1) {
            // The outer face, and the crack face: gas only in the mouths' rows.
            let (outer, crack) = if p == 0 { (lo, hi) } else { (hi, lo) };
            let sign = if p == 0 { 1.0 } else { -1.0 };
            f[2 * p] += sign * p_bar(column(outer), j) * len;
            if j == row(Y0) || j == row(Y1) {
                f[2 * p] -= sign * p_bar(column(crack), j) * len;
            }
        }
        for (i, len) in pieces(lo, hi) {
            f[2 * p + 1] += (p_bar(i, row(Y0)) - p_bar(i, row(Y1))) * len;
        }
    }
    f
}

#[test]
fn issue_14_a_crack_opens_as_vacuum_and_fills_conserving_mass() {
    let mut solver = solver(&at_rest_in_unit_box("crack", &[40, 40]));
    let u = 0.2;
    let mut embedded = Embedded::new(&solver, pair(0.0, u)).expect("embedded");
    embedded.set_fracture(true);
    let m0 = embedded.totals(&solver).mass;
    let e0 = embedded.totals(&solver).energy;

    // The loads of F^0: every wet face takes `p̄` of the cell holding it, the mean of its
    // pressure at t^n (1) and after the sweeps (`Embedded::predict`); the crack faces carry
    // only the pressure of the two cut cells at its mouths (0.0175 + 0.0075 m of them): the
    // covered cells between them are vacuum, not the mirrored gas.
    let dt = 0.5 * solver.max_dt();
    let report = embedded.predict(&mut solver, dt);
    assert!(report.ok(), "{:?}", report.troubles);
    assert!(
        report.lax_friedrichs_faces > 0,
        "no face beside the vacuum took the Lax–Friedrichs flux"
    );
    let current = embedded.surface().clone();
    let loads = embedded.loads(&solver, &current).expect("loads");
    let want = crack_loads(&solver);
    println!("F^0 loads: {:?} (want {want:?})", loads.force);
    for (got, want) in loads.force.iter().zip(want) {
        assert!((got - want).abs() < 1e-12, "{:?}", loads.force);
    }
    // (With the mirrored gas in the crack's 15 covered rows, 15 × 0.025 of pressure ≈ 1 more
    // would press on each crack face.)

    let mut s = u * dt;
    embedded
        .correct(&mut solver, dt, pair(s, u), 0, false)
        .expect("first correct");
    let mut first_vacuum = vacuum_cells(&solver, &embedded);
    let mut work = embedded.budget().work_given;
    let mut steps = 1;
    let mut worst_mass = 0.0f64;
    let mut lowest_crack_rho = f64::INFINITY;
    // The crack opens to 0.06 m, more than two cells.
    while 2.0 * s < 0.06 {
        let dt = 0.5 * solver.max_dt();
        let report = embedded.predict(&mut solver, dt);
        assert!(report.ok(), "step {steps}: {:?}", report.troubles);
        s += u * dt;
        embedded
            .correct(&mut solver, dt, pair(s, u), steps, false)
            .unwrap_or_else(|e| panic!("step {steps}: {e}"));
        let totals = embedded.totals(&solver);
        worst_mass = worst_mass.max((totals.mass - m0).abs() / m0);
        work = embedded.budget().work_given;
        // Energy: the fluid's plus what it gave the solid is what it had.
        let energy_gap = (totals.energy + work - e0).abs() / e0;
        assert!(
            energy_gap < 1e-12,
            "step {steps}: energy gap {energy_gap:e}"
        );
        if steps == 1 {
            first_vacuum = first_vacuum.max(vacuum_cells(&solver, &embedded));
        }
        let lambda = embedded.solid_fraction();
        let grid = solver.grid().clone();
        for j in 14..26 {
            let c = grid.index(20, j, 0);
            if lambda[c] < 1.0 - 1e-12 {
                lowest_crack_rho = lowest_crack_rho.min(solver.primitive(c).0);
            }
        }
        steps += 1;
    }
    // The middle of the crack at the end: gas, thinner than the gas outside.
    let grid = solver.grid().clone();
    let mid = grid.index(20, 20, 0);
    let (rho_mid, _, p_mid) = solver.primitive(mid);
    println!(
        "{steps} steps, crack width {:.4} m: worst mass error {worst_mass:e}, vacuum cells after the first steps {first_vacuum}, now {}, lowest crack density {lowest_crack_rho:e}, crack middle rho {rho_mid} p {p_mid}, work given {work:e}",
        2.0 * s,
        vacuum_cells(&solver, &embedded)
    );
    assert!(worst_mass < 1e-14, "mass error {worst_mass:e}");
    assert!(lowest_crack_rho >= 0.0);
    assert!(rho_mid > 0.0 && rho_mid < 1.0, "crack middle rho {rho_mid}");
    assert!(p_mid > 0.0 && p_mid < 1.0, "crack middle p {p_mid}");
}
