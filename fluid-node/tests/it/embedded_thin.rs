//! A body whose faces lie within round-off of grid planes: the loads of a trial surface are
//! continuous as it crosses a plane (issue 37, the thin shell's fixed point).

use crate::embedded_support;

use embedded_support::*;
use fluid_node::embedded::Embedded;

/// Gas at rest, p = 2 upstream of the plane x = 15 dx and p = 1 downstream (ρ = 1.4 and 1).
const CHANNEL: &str = r#"
    name = "thin"
    [fluid]
    lower = [0.0, 0.0]
    upper = [1.0, 0.2]
    cells = [40, 8]
    boundary = { x = ["wall", "wall"], y = ["wall", "wall"] }
    [[fluid.init]]
    region = "all"
    rho = 1.0
    p = 1.0
    [[fluid.init]]
    region = { box = { lower = [0.0, 0.0], upper = [0.375, 0.2] } }
    rho = 1.4
    p = 2.0
"#;

/// A box two cells thick (dx = 0.025) from x0 to x0 + 2 dx, y from 0.05 to 0.15.
fn slab(x0: f64) -> fluid_node::embedded::SolidFrame {
    let x1 = x0 + 0.05;
    polygon_2d(
        &[[x0, 0.05], [x1, 0.05], [x1, 0.15], [x0, 0.15]],
        [0.0, 0.0],
        0.0,
    )
}

#[test]
fn the_load_is_continuous_across_the_grid_plane_beside_one_covered_cell() {
    // At t^n the upstream face lies 1e-9 m before the plane x = 15 dx: cell 14 is cut (a sliver
    // of solid), 15 covered, 16 cut (a sliver of fluid). A run of one covered cell below the
    // grid's middle takes its ghost states from the downstream side (cell 16, p = 1).
    let eps = 1e-9;
    let mut solver = solver(CHANNEL);
    let mut embedded = Embedded::new(&solver, slab(0.375 - eps)).unwrap();
    let dt = 0.1 * solver.max_dt();
    let report = embedded.predict(&mut solver, dt);
    assert!(report.ok(), "predict: {:?}", report.troubles);
    // Trials 1e-9 m before the plane (the face in cell 14) and 1e-9 m after it (in cell 15,
    // covered at t^n): the face moved 2e-9 m, the load must not jump.
    let before = embedded.loads(&slab(0.375 - eps)).unwrap();
    let after = embedded.loads(&slab(0.375 + eps)).unwrap();
    println!(
        "force x: before the plane {:.17e}, after it {:.17e}",
        before.force[0], after.force[0]
    );
    // Upstream p = 2 against downstream p = 1 on a face 0.1 m high: 0.1 N per unit depth
    // (the gas has moved for a tenth of a step at the body's ends: 1 % of slack).
    assert!(
        (before.force[0] - 0.1).abs() <= 1e-3,
        "before {:e}",
        before.force[0]
    );
    // The same cells' p̄ on both sides of the plane: equal to round-off of the faces' areas.
    assert!(
        (after.force[0] - before.force[0]).abs() <= 1e-12,
        "before {:.17e}, after {:.17e}",
        before.force[0],
        after.force[0]
    );
}
