//! A body whose wet surface crosses a wall of the domain. The sub-faces, and so the swept
//! prisms, exist only inside the domain, so when part of an element moves across the boundary
//! the swept prisms miss volume; the fold check must stop the step and say why, not blame an
//! element turned inside out.

mod embedded_support;

use embedded_support::{polygon_2d, solver};
use fluid_node::embedded::Embedded;

const SCENE: &str = r#"
name = "boundary"
[fluid]
gamma = 1.4
cfl = 0.5
flux = { scheme = "osmp", order = 3 }
lower = [0.0, 0.0]
upper = [1.0, 1.0]
cells = [20, 20]
boundary = { x = ["wall", "wall"], y = ["wall", "wall"] }
[[fluid.init]]
region = "all"
rho = 1.0
p = 1.0
"#;

/// A square of side 0.2 centred on (0.5, 0.0125), half below the wall y = 0, turned by `theta`.
fn square(theta: f64, omega: f64) -> fluid_node::embedded::SolidFrame {
    let (c, s) = (theta.cos(), theta.sin());
    let corners = [[-0.1, -0.1], [0.1, -0.1], [0.1, 0.1], [-0.1, 0.1]]
        .map(|[x, y]| [0.5 + c * x - s * y, 0.0125 + s * x + c * y]);
    polygon_2d(&corners, [0.0, 0.0], omega)
}

#[test]
fn a_turning_body_across_a_wall_stops_with_the_boundary_named() {
    let mut solver = solver(SCENE);
    let omega = 1.0;
    let mut embedded = Embedded::new(&solver, square(0.0, omega)).expect("embedded");
    let dt = 0.5 * solver.max_dt();
    let report = embedded.predict(&mut solver, dt);
    assert!(report.ok(), "{:?}", report.troubles);
    let err = embedded
        .correct(&mut solver, dt, square(omega * dt, omega), 0, false)
        .expect_err("a turn across the wall misses swept volume");
    println!("{err}");
    assert!(
        err.contains("folds over itself")
            && err.contains("crosses the domain's boundary beside this cell (axis 1)"),
        "{err}"
    );
}

#[test]
fn a_fold_inside_the_domain_is_not_blamed_on_the_boundary() {
    let mut solver = solver(SCENE);
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
        .expect_err("a loop crossing itself is refused");
    println!("{err}");
    assert!(
        err.contains("folds over itself") && err.contains("an element turned inside out"),
        "{err}"
    );
}
