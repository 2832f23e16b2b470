//! Bodies driven through a wall of the domain (issue 35 items 3 and 5): the fragments of
//! `burst-shell-2d` fly out through the walls. What the parts of the surface beyond the
//! boundary sweep in the boundary cells must close the mass to round-off, and the gas a body
//! squeezes against the wall must find fluid to go to.

use crate::embedded_support;

use embedded_support::{at_rest_in_unit_box, box_3d, polygon_2d, rotation, solver};
use fluid_node::embedded::{Embedded, SolidFrame};

/// The 2-D frame moved rigidly over `dt` at its velocity and angular velocity (about its
/// position).
fn moved(frame: &SolidFrame, dt: f64) -> SolidFrame {
    let mut next = frame.clone();
    let (s, c) = (frame.angular_velocity[0] * dt).sin_cos();
    let x0 = [frame.position[0], frame.position[1]];
    for v in next.vertices.chunks_exact_mut(2) {
        let r = [v[0] - x0[0], v[1] - x0[1]];
        v[0] = x0[0] + c * r[0] - s * r[1] + dt * frame.velocity[0];
        v[1] = x0[1] + s * r[0] + c * r[1] + dt * frame.velocity[1];
    }
    next.position[0] += dt * frame.velocity[0];
    next.position[1] += dt * frame.velocity[1];
    next
}

/// Moves the 2-D body of `embedded` rigidly, half a cell a step at most, while some vertex is
/// `inside`; returns the steps taken and the largest relative mass error over them.
fn drive(
    solver: &mut fluid_node::fv::FluidSolver,
    embedded: &mut Embedded,
    inside: impl Fn(&[f64]) -> bool,
) -> (u64, f64) {
    let m0 = embedded.totals(solver).mass;
    let (mut worst, mut step) = (0.0f64, 0);
    while embedded.surface().vertices.chunks_exact(2).any(&inside) {
        let dt = 0.5 * solver.max_dt().min(embedded.one_cell_dt());
        let report = embedded.predict(solver, dt);
        assert!(report.ok(), "step {step}: {:?}", report.troubles);
        let next = moved(embedded.surface(), dt);
        embedded
            .correct(solver, dt, next, step, false)
            .unwrap_or_else(|e| panic!("step {step}: {e}"));
        let mass = embedded.totals(solver).mass;
        worst = worst.max((mass - m0).abs() / m0);
        step += 1;
    }
    (step, worst)
}

/// Drives a square of side 0.1 from (0.8, 0.5) at `velocity` and `omega` through the wall
/// x = 1 of the unit box at rest (40 x 40 cells), half a cell a step at most, until it is out;
/// returns the largest relative mass error over the steps.
fn through_the_wall(velocity: [f64; 2], omega: f64, fracture: bool) -> f64 {
    let mut solver = solver(&at_rest_in_unit_box("wall", &[40, 40]));
    let square = [[0.75, 0.45], [0.85, 0.45], [0.85, 0.55], [0.75, 0.55]];
    let body = polygon_2d(&square, velocity, omega);
    let mut embedded = Embedded::new(&solver, body).expect("embedded");
    embedded.set_fracture(fracture);
    let (step, worst) = drive(&mut solver, &mut embedded, |x| x[0] < 1.0);
    println!(
        "v {velocity:?}, omega {omega}, fracture {fracture}: out after {step} steps, mass error {worst:e}"
    );
    worst
}

/// A square turning out through the wall uncovers boundary cells from beyond the domain; left
/// predicted, those cells dropped the pieces of prisms beyond the domain (2.3e-5 and 7.2e-6 of
/// the mass before the fix).
#[test]
fn a_square_turning_out_through_a_wall_conserves_mass() {
    for fracture in [false, true] {
        for (v, omega) in [([0.5, 0.2], 3.0), ([0.5, -0.3], -2.0)] {
            let err = through_the_wall(v, omega, fracture);
            assert!(err < 1e-14, "mass error {err:e}");
        }
    }
}

/// A face parallel to the wall squeezes the gas before it into boundary cells it covers along
/// with their neighbours (a closed pocket, which stopped the run at step 91 before the fix).
#[test]
fn a_square_squeezing_gas_against_a_wall_conserves_mass() {
    for fracture in [false, true] {
        for v in [[0.5, 0.0], [0.5, 0.13]] {
            let err = through_the_wall(v, 0.0, fracture);
            assert!(err < 1e-14, "mass error {err:e}");
        }
    }
}

/// The same in 3-D (16^3 cells): a cube of side 0.2 from (0.75, 0.5, 0.5), turning about a
/// tilted axis or flat against the wall, until it is out through x = 1 (the turning cube lost
/// 9.3e-7 of the mass before the fix).
#[test]
fn a_cube_driven_out_through_a_wall_conserves_mass() {
    let axis = [0.0, 0.6, 0.8];
    for (v, omega) in [([0.5, 0.1, 0.05], 2.0), ([0.5, 0.0, 0.0], 0.0)] {
        let at = |t: f64| {
            let c = [0.75 + v[0] * t, 0.5 + v[1] * t, 0.5 + v[2] * t];
            let mut f = box_3d(c, [0.1; 3], rotation(axis, omega * t), v);
            f.angular_velocity = axis.iter().map(|a| a * omega).collect();
            f
        };
        let mut solver = solver(&at_rest_in_unit_box("wall-3d", &[16, 16, 16]));
        let mut embedded = Embedded::new(&solver, at(0.0)).expect("embedded");
        let m0 = embedded.totals(&solver).mass;
        let (mut worst, mut step, mut t) = (0.0f64, 0, 0.0);
        while embedded
            .surface()
            .vertices
            .chunks_exact(3)
            .any(|x| x[0] < 1.0)
        {
            let dt = 0.5 * solver.max_dt().min(embedded.one_cell_dt());
            let report = embedded.predict(&mut solver, dt);
            assert!(report.ok(), "step {step}: {:?}", report.troubles);
            t += dt;
            embedded
                .correct(&mut solver, dt, at(t), step, false)
                .unwrap_or_else(|e| panic!("step {step}: {e}"));
            let mass = embedded.totals(&solver).mass;
            worst = worst.max((mass - m0).abs() / m0);
            step += 1;
        }
        println!("v {v:?}, omega {omega}: out after {step} steps, mass error {worst:e}");
        assert!(worst < 1e-14, "mass error {worst:e}");
    }
}

/// An arch (a Π, legs down) driven down through the wall y = 0 across gas streaming along it at
/// Mach 6.8 (40 x 40 cells): the gas under the arch is sealed off when the legs pass the wall,
/// then squeezed into a sliver whose cells have no free neighbour left. Their group's mixture
/// was not physical and could not widen: the run stopped at step 29 (`p = −2.5e-3` in a cell
/// 40 % open) before the widening stepped over the cells around it.
#[test]
fn gas_sealed_under_an_arch_pressed_through_a_wall_stays_physical() {
    let text = at_rest_in_unit_box("arch", &[40, 40])
        .replace("p = 1.0\n", "p = 1.0\nvelocity = [8.0, 0.0]\n");
    let mut solver = solver(&text);
    let arch = [
        [0.3, 0.02],
        [0.34, 0.02],
        [0.34, 0.1],
        [0.66, 0.1],
        [0.66, 0.02],
        [0.7, 0.02],
        [0.7, 0.14],
        [0.3, 0.14],
    ];
    let mut embedded =
        Embedded::new(&solver, polygon_2d(&arch, [0.0, -3.0], 0.0)).expect("embedded");
    let (step, worst) = drive(&mut solver, &mut embedded, |x| x[1] > 0.0);
    println!("out after {step} steps, mass error {worst:e}");
    // NOTE: measured 83 steps, mass error 0.
    assert!(step > 29, "{step} steps");
    assert!(worst < 1e-14, "mass error {worst:e}");
}
