//! Swept volumes (paper 000 eq. 12): in every cell the volumes swept by the elements add up to
//! `(Λ^{n+1} − Λ^n) V` (identity 3) under seeded random rigid motions and a deformation, in 3-D
//! and 2-D; a translated flat element sweeps exactly `area × (d · n)`.

#![allow(clippy::needless_range_loop)]

use crate::cutcell_support;

use cutcell_support::*;
use fluid_node::cutcell::{Surface, SweptVolumes, swept_volumes};
use fluid_node::grid::Grid;

/// Tolerance of identity (3), relative to the cell volume.
const SWEPT_TOL: f64 = 1e-12;

/// A random rigid motion moving points by at most about `max_shift` (rotation about `centre`).
fn random_rigid(
    rng: &mut Rng,
    centre: [f64; 3],
    max_shift: f64,
    radius: f64,
) -> impl Fn([f64; 3]) -> [f64; 3] {
    let axis = [
        rng.uniform(-1.0, 1.0),
        rng.uniform(-1.0, 1.0),
        rng.uniform(-1.0, 1.0),
    ];
    // Rotation moving points at distance `radius` by at most half the budget.
    let angle = rng.uniform(-0.5, 0.5) * max_shift / radius;
    let r = rotation(axis, angle);
    let s = 0.5 * max_shift / 3f64.sqrt();
    let shift = [rng.uniform(-s, s), rng.uniform(-s, s), rng.uniform(-s, s)];
    move |p| rigid(p, &r, centre, shift)
}

#[test]
fn rigid_motions_of_closed_bodies_satisfy_identity_3() {
    let grid = Grid::new(&[0.0; 3], &[1.0; 3], &[14, 12, 13]).unwrap();
    let dx = 1.0 / 14.0;
    let mut rng = Rng(2024);
    let bodies = [
        sphere_mesh([0.5, 0.48, 0.52], 0.3, 14, 28),
        torus_mesh([0.5, 0.5, 0.5], 0.28, 0.1, 32, 12),
        box_mesh([0.21, 0.33, 0.25], [0.77, 0.61, 0.7]),
    ];
    let mut worst: f64 = 0.0;
    for (b, body) in bodies.iter().enumerate() {
        for case in 0..8 {
            let motion = random_rigid(&mut rng, [0.5; 3], dx, 0.35);
            let before = body.clone();
            let after = body.map(&motion);
            let (residual, total) = swept_residual(&grid, &before, &after);
            worst = worst.max(residual);
            assert!(
                residual <= SWEPT_TOL,
                "body {b} case {case}: residual {residual}"
            );
            // Rigid motion inside the domain: no net volume change.
            assert!(total.abs() <= 1e-13, "body {b} case {case}: total {total}");
        }
    }
    eprintln!("rigid motions: max cell residual {worst:.2e}");
}

#[test]
fn deformation_satisfies_identity_3_and_the_volume_change() {
    let grid = Grid::new(&[0.0; 3], &[1.0; 3], &[16; 3]).unwrap();
    let body = sphere_mesh([0.5, 0.5, 0.5], 0.3, 16, 32);
    let mut rng = Rng(99);
    for case in 0..6 {
        let (a, b, c) = (
            rng.uniform(-1.0, 1.0),
            rng.uniform(-1.0, 1.0),
            rng.uniform(0.0, 6.0),
        );
        let amp = 0.9 / 16.0;
        let deform = move |p: [f64; 3]| {
            [
                p[0] + amp * (c * p[1] + a).sin() * 0.7,
                p[1] + amp * (b * p[2] + 3.0 * p[0]).cos() * 0.7,
                p[2] + amp * (a * p[0] * p[1] + c).sin() * 0.7,
            ]
        };
        let after = body.map(deform);
        let (residual, total) = swept_residual(&grid, &body, &after);
        let change = after.enclosed_volume() - body.enclosed_volume();
        assert!(residual <= SWEPT_TOL, "case {case}: residual {residual}");
        assert!(
            (total - change).abs() <= 1e-13,
            "case {case}: total {total} vs {change}"
        );
    }
}

#[test]
fn large_motion_across_several_cells_still_balances() {
    // The construction does not depend on the motion crossing at most one cell.
    let grid = Grid::new(&[0.0; 3], &[1.0; 3], &[10; 3]).unwrap();
    let body = box_mesh([0.2, 0.2, 0.2], [0.45, 0.5, 0.4]);
    let r = rotation([1.0, 0.5, 0.2], 0.8);
    let after = body.map(|p| rigid(p, &r, [0.3; 3], [0.31, 0.22, 0.27]));
    let (residual, total) = swept_residual(&grid, &body, &after);
    assert!(residual <= SWEPT_TOL, "residual {residual}");
    assert!(total.abs() <= 1e-13);
}

#[test]
fn bodies_leaving_the_domain_balance_in_every_cell() {
    let grid = Grid::new(&[0.0; 3], &[1.0; 3], &[9; 3]).unwrap();
    let body = sphere_mesh([0.9, 0.5, 0.05], 0.25, 12, 24);
    let after = body.map(|p| [p[0] + 0.08, p[1] - 0.05, p[2] - 0.07]);
    let (residual, _) = swept_residual(&grid, &body, &after);
    assert!(residual <= SWEPT_TOL, "residual {residual}");
}

#[test]
fn translated_triangle_sweeps_area_times_normal_displacement() {
    let grid = Grid::new(&[0.0; 3], &[1.0; 3], &[7; 3]).unwrap();
    let vertices = [0.1, 0.2, 0.3, 0.8, 0.25, 0.4, 0.3, 0.85, 0.6];
    let d = [0.05, -0.03, 0.11];
    let moved: Vec<f64> = vertices
        .iter()
        .enumerate()
        .map(|(i, x)| x + d[i % 3])
        .collect();
    let elements = [0, 1, 2];
    let before = Surface {
        dim: 3,
        vertices: &vertices,
        elements: &elements,
        element_particle: &[],
    };
    let after = Surface {
        dim: 3,
        vertices: &moved,
        elements: &elements,
        element_particle: &[],
    };
    let mut out = SweptVolumes::new();
    swept_volumes(&grid, &before, &after, &mut out);
    let t = before.element(0).unwrap();
    let area_vector = cross(sub(t[1], t[0]), sub(t[2], t[0]));
    let exact = 0.5 * dot(area_vector, d);
    assert!(
        (out.total() - exact).abs() <= 1e-15,
        "{} vs {exact}",
        out.total()
    );
    assert!(out.entries.len() > 1, "the prism crosses several cells");
    // Reversed twin: exactly the opposite in every cell (internal faces cancel).
    let reversed = [0, 2, 1];
    let before_r = Surface {
        elements: &reversed,
        ..before
    };
    let after_r = Surface {
        elements: &reversed,
        ..after
    };
    let mut out_r = SweptVolumes::new();
    swept_volumes(&grid, &before_r, &after_r, &mut out_r);
    let mut acc = vec![0.0; grid.n_cells()];
    out.accumulate(&mut acc);
    out_r.accumulate(&mut acc);
    assert!(acc.iter().all(|x| x.abs() <= 1e-17), "twins cancel");
}

#[test]
fn two_dimensional_motions_satisfy_identity_3() {
    let grid = Grid::new(&[0.0, 0.0], &[1.0, 1.0], &[23, 19]).unwrap();
    let dx = 1.0 / 23.0;
    let mut rng = Rng(5);
    let mut shapes = vec![disc_mesh([0.5, 0.5], 0.3, 40, 0.1)];
    let mut two = disc_mesh([0.3, 0.3], 0.15, 17, 0.0);
    two.append(
        &loop_mesh(&[[0.55, 0.5], [0.9, 0.52], [0.85, 0.9], [0.6, 0.8]]),
        1,
    );
    shapes.push(two);
    for (s, shape) in shapes.iter().enumerate() {
        for case in 0..10 {
            let angle = rng.uniform(-1.0, 1.0) * dx;
            let r = rotation([0.0, 0.0, 1.0], angle);
            let shift = [rng.uniform(-dx, dx) * 0.6, rng.uniform(-dx, dx) * 0.6, 0.0];
            let after = shape.map(|p| rigid(p, &r, [0.5, 0.5, 0.0], shift));
            let (residual, total) = swept_residual(&grid, shape, &after);
            assert!(residual <= SWEPT_TOL, "shape {s} case {case}: {residual}");
            assert!(total.abs() <= 1e-14, "shape {s} case {case}: total {total}");
        }
        // Deformation.
        let after = shape.map(|p| {
            [
                p[0] + 0.03 * (5.0 * p[1]).sin(),
                p[1] + 0.02 * (7.0 * p[0]).cos(),
                0.0,
            ]
        });
        let (residual, total) = swept_residual(&grid, shape, &after);
        assert!(residual <= SWEPT_TOL, "shape {s} deformation: {residual}");
        let change = after.enclosed_volume() - shape.enclosed_volume();
        assert!((total - change).abs() <= 1e-14);
    }
}
