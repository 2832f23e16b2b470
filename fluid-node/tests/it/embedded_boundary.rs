//! A body whose wet surface crosses a wall of the domain. The sub-faces of the domain's cells
//! alone miss the prisms of the parts of elements that move across the boundary: the fold
//! check stopped such a step. The parts beyond are now clipped on a grown grid, and the pieces
//! of their prisms in domain cells counted, so the step runs and mass closes to round-off.

use crate::embedded_support;

use embedded_support::{at_rest_in_unit_box, box_3d, polygon_2d, rotation, solver};
use fluid_node::embedded::{Embedded, SolidFrame};

/// A square of side 0.2 centred on (0.5, 0.0125), half below the wall y = 0, turned by `theta`.
fn square(theta: f64, omega: f64) -> SolidFrame {
    let (c, s) = (theta.cos(), theta.sin());
    let corners = [[-0.1, -0.1], [0.1, -0.1], [0.1, 0.1], [-0.1, 0.1]]
        .map(|[x, y]| [0.5 + c * x - s * y, 0.0125 + s * x + c * y]);
    polygon_2d(&corners, [0.0, 0.0], omega)
}

/// Turns the body `at(theta)` at 1 rad/s for `steps` steps in the gas of `scene`, and asserts
/// that the fluid's mass and the energy balance (fluid plus the work it gave) close.
fn turn(scene: &str, at: impl Fn(f64) -> SolidFrame, steps: u64) {
    let mut solver = solver(scene);
    let omega = 1.0;
    let mut embedded = Embedded::new(&solver, at(0.0)).expect("embedded");
    let t0 = embedded.totals(&solver);
    let (mut theta, mut worst_mass, mut worst_energy) = (0.0, 0.0f64, 0.0f64);
    for step in 0..steps {
        let dt = 0.5 * solver.max_dt();
        let report = embedded.predict(&mut solver, dt);
        assert!(report.ok(), "step {step}: {:?}", report.troubles);
        theta += omega * dt;
        embedded
            .correct(&mut solver, dt, at(theta), step, false)
            .unwrap_or_else(|e| panic!("step {step}: {e}"));
        let t = embedded.totals(&solver);
        worst_mass = worst_mass.max((t.mass - t0.mass).abs() / t0.mass);
        let work = embedded.budget().work_given;
        worst_energy = worst_energy.max((t.energy + work - t0.energy).abs() / t0.energy);
    }
    println!(
        "{steps} steps, turned {theta:.3} rad: mass error {worst_mass:e}, energy error {worst_energy:e}"
    );
    assert!(worst_mass < 1e-14, "mass error {worst_mass:e}");
    assert!(worst_energy < 1e-12, "energy error {worst_energy:e}");
}

#[test]
fn a_body_turning_across_a_wall_conserves_mass() {
    turn(
        &at_rest_in_unit_box("boundary", &[20, 20]),
        |theta| square(theta, 1.0),
        40,
    );
}

#[test]
fn a_fold_inside_the_domain_is_not_blamed_on_the_boundary() {
    let mut solver = solver(&at_rest_in_unit_box("boundary", &[20, 20]));
    let inside = [[0.4, 0.48], [0.6, 0.48], [0.6, 0.52], [0.4, 0.52]];
    let mut embedded =
        Embedded::new(&solver, polygon_2d(&inside, [0.0, 0.0], 0.0)).expect("embedded");
    let dt = 0.5 * solver.max_dt();
    let report = embedded.predict(&mut solver, dt);
    assert!(report.ok(), "{:?}", report.troubles);
    // The third corner moves across the first side (by 1.6 cells): the loop crosses itself.
    let folded = [[0.4, 0.48], [0.6, 0.48], [0.6, 0.44], [0.4, 0.52]];
    let err = embedded
        .correct(
            &mut solver,
            dt,
            polygon_2d(&folded, [0.0, 0.0], 0.0),
            0,
            false,
        )
        .expect_err("a loop crossing itself is refused")
        .to_string();
    println!("{err}");
    assert!(
        err.contains("folds over itself") && err.contains("an element turned inside out"),
        "{err}"
    );
}

/// The same in 3-D: a cube of side 0.25 centred on (0.5, 0.5, 0.02), 0.105 m of it below the wall
/// z = 0, turning about y.
#[test]
fn a_box_turning_across_a_wall_conserves_mass() {
    let cube = |theta: f64| {
        let mut f = box_3d(
            [0.5, 0.5, 0.02],
            [0.125; 3],
            rotation([0.0, 1.0, 0.0], theta),
            [0.0; 3],
        );
        f.angular_velocity = vec![0.0, 1.0, 0.0];
        f
    };
    turn(&at_rest_in_unit_box("boundary-3d", &[16, 16, 16]), cube, 15);
}
