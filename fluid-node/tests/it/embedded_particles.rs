//! The fluid's loads do not depend on how the particles are numbered, nor on particles that own
//! no element (issue 39 item 4: the coupler sends the fluid only the particles its surface's
//! elements belong to). A tilted cube driven through gas at rest, once as the only particle and
//! once as the middle one of three (the other two own no element, and move): the same correct
//! reports, totals, budget and states, and the cube's loads the same bits, the others' zero.

use crate::embedded_support;

use embedded_support::{at_rest_in_unit_box, box_3d, rotation, translated};
use fluid_node::embedded::{Embedded, Loads, SolidFrame};
use fluid_node::fv::FluidSolver;
use protocol::scene::Scene;

/// `frame` (one particle) as particle 1 of three; particles 0 and 2 own no element.
fn among_others(frame: &SolidFrame) -> SolidFrame {
    let mut out = frame.clone();
    let pad = |v: &[f64], w: usize, a: f64, b: f64| {
        let mut x = vec![a; w];
        x.extend_from_slice(v);
        x.extend(std::iter::repeat_n(b, w));
        x
    };
    out.position = pad(&frame.position, 3, 0.9, 0.1);
    out.velocity = pad(&frame.velocity, 3, -3.0, 2.0);
    out.angular_velocity = pad(&frame.angular_velocity, 3, 5.0, -7.0);
    out.element_particle.iter_mut().for_each(|p| *p = 1);
    out
}

/// 6 steps; per step the loads on `F^n` and on the trial, then the report, totals, budget as
/// text; at the end every cell's state.
fn run(padded: bool) -> (Vec<(Loads, Loads)>, Vec<String>) {
    let text = at_rest_in_unit_box("particles", &[16, 16, 16]);
    let scene = Scene::from_toml_str(&text, "test.toml").expect("scene");
    let mut solver = FluidSolver::from_scene(scene.fluid.as_ref().expect("[fluid]"), 1).unwrap();
    let cube = box_3d(
        [0.5, 0.45, 0.5],
        [0.15; 3],
        rotation([0.0, 0.6, 0.8], 0.3),
        [0.6, -0.2, 0.1],
    );
    let view = |f: &SolidFrame| if padded { among_others(f) } else { f.clone() };
    let mut embedded = Embedded::new(&solver, view(&cube)).expect("embedded");
    let (mut loads, mut bits) = (Vec::new(), Vec::new());
    let mut current = cube;
    for step in 0..6 {
        let dt = 0.5 / (0.5 / solver.max_dt() + 2.0 / embedded.one_cell_dt());
        let report = embedded.predict(&mut solver, dt);
        assert!(report.ok(), "step {step}: {:?}", report.troubles);
        let on_start = embedded.loads(&solver, &view(&current)).expect("loads");
        let next = translated(&current, dt);
        let on_trial = embedded.loads(&solver, &view(&next)).expect("loads");
        let r = (embedded.correct(&mut solver, dt, view(&next), step, false))
            .unwrap_or_else(|e| panic!("step {step}: {e}"));
        let totals = embedded.totals(&solver);
        bits.push(format!("{r:?} {totals:?} {:?}", embedded.budget()));
        loads.push((on_start, on_trial));
        current = next;
    }
    let cells: Vec<u32> = (0..solver.grid().n_cells() as u32).collect();
    bits.push(format!("{:?}", solver.cells_at(&cells)));
    (loads, bits)
}

#[test]
fn the_loads_of_a_particle_do_not_depend_on_the_others() {
    let (alone, alone_bits) = run(false);
    let (among, among_bits) = run(true);
    for (k, (a, b)) in alone_bits.iter().zip(&among_bits).enumerate() {
        assert_eq!(a, b, "record {k}");
    }
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    for (step, (a, b)) in alone.iter().zip(&among).enumerate() {
        for (a, b) in [(&a.0, &b.0), (&a.1, &b.1)] {
            assert!(a.force.iter().any(|&f| f != 0.0), "step {step}: no load");
            assert_eq!(bits(&a.force), bits(&b.force[3..6]), "step {step}");
            assert_eq!(bits(&a.torque), bits(&b.torque[3..6]), "step {step}");
            for p in [0, 2] {
                assert_eq!(bits(&b.force[3 * p..3 * p + 3]), bits(&[0.0; 3]));
                assert_eq!(bits(&b.torque[3 * p..3 * p + 3]), bits(&[0.0; 3]));
            }
        }
    }
}
