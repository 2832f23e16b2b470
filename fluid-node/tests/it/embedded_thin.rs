//! Issue 37, the thin shell: a body whose faces lie within round-off of grid planes (the loads
//! of a trial surface are continuous as it crosses a plane, the fixed point), and the
//! levers of the sub-cycled semi-implicit loads (`embedded/levers.rs`).

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
    let before = embedded.loads(&solver, &slab(0.375 - eps)).unwrap();
    let after = embedded.loads(&solver, &slab(0.375 + eps)).unwrap();
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

/// A particle of a thin shell, 0.06 m thick and 0.36 m high, wet on its two long faces only (the
/// short ones face its neighbours); `shear` slides the right face up and the left one down by
/// it, as the mean-vertex wet surface does when the shell's particles turn together by
/// `θ = asin(2 shear / thickness)`. The centre stays at (0.44, 0.5).
fn shell_particle(shear: f64) -> fluid_node::embedded::SolidFrame {
    let (x0, x1, y0, y1) = (0.41, 0.47, 0.32, 0.68);
    let mut frame = polygon_2d(
        &[
            [x0, y0 - shear],
            [x1, y0 + shear],
            [x1, y1 + shear],
            [x0, y1 - shear],
        ],
        [0.0, 0.0],
        0.0,
    );
    frame.position = vec![0.44, 0.5];
    // Elements: bottom, right, top, left.
    frame.wet = vec![false, true, false, true];
    frame
}

#[test]
fn levers_on_f_n_give_the_torque_of_f_n_with_the_forces_of_f_n_plus_1() {
    // Issue 37: a pressure p on the two long faces, slid by ±δ, torques the particle by
    // p h 2δ in the sense it turns, a negative stiffness; taken on the end surface and held
    // over the step it leads the motion and pumps it. The levers on F^n take the torque of
    // F^n (here none), which lags by the step and damps it.
    let mut solver = solver(&at_rest_in_unit_box("levers", &[20, 20]));
    let mut embedded = Embedded::new(&solver, shell_particle(0.0)).unwrap();
    let dt = 0.1 * solver.max_dt();
    let report = embedded.predict(&mut solver, dt);
    assert!(report.ok(), "predict: {:?}", report.troubles);
    let delta = 0.004;
    let on_n = embedded.loads(&solver, &shell_particle(0.0)).unwrap();
    let end = embedded.loads(&solver, &shell_particle(delta)).unwrap();
    embedded.set_start_levers(true);
    let start = embedded.loads(&solver, &shell_particle(delta)).unwrap();
    println!(
        "torque on F^n {:e}, on F^(n+1): end levers {:e}, levers on F^n {:e}",
        on_n.torque[0], end.torque[0], start.torque[0]
    );
    // Gas at rest: p̄ = 1 to round-off; the end torque p h 2δ.
    assert!(on_n.torque[0].abs() <= 1e-15, "{:e}", on_n.torque[0]);
    assert!((end.torque[0] - 0.36 * 2.0 * delta).abs() <= 1e-15);
    // The levers move no force, and the torque is F^n's.
    assert_eq!(start.force, end.force);
    assert!(
        (start.torque[0] - on_n.torque[0]).abs() <= 1e-15,
        "on F^n {:.17e}, levers on F^n {:.17e}",
        start.torque[0],
        on_n.torque[0]
    );
}
