//! The coupled step's cut-cell work on the fluid's pool (issue 36 item 4): the near cells'
//! walls of the hooks, the update of the cut cells (eq. 12–13) and the mixing groups' walks to
//! their roots run in parallel, each put together in a fixed order. On pools of 1, 2 and 5
//! threads a coupled run gives the same bits.

use crate::embedded_support;

use embedded_support::{at_rest_in_unit_box, box_3d, rotation, translated};
use fluid_node::embedded::Embedded;
use fluid_node::fv::FluidSolver;
use protocol::scene::Scene;

/// What one run showed, as text (`{:?}` of an f64 round-trips it), and its reports' counts.
struct Run {
    /// Every step's correct report, loads and totals, then every cell's state at the end.
    bits: Vec<String>,
    mixed: usize,
    cut: usize,
}

/// A tilted cube (half-side 0.12, reaching into the first cell layer at x = 0) driven at
/// (0.5, 0.1, 0.05) through gas at rest in the unit box of 20³ cells, outflow at x = 0 and
/// x = 1 and walls across, for 8 steps of a fluid on `threads` threads.
fn run(threads: usize) -> Run {
    let text = at_rest_in_unit_box("threads", &[20, 20, 20])
        .replace(r#"x = ["wall", "wall"]"#, r#"x = ["outflow", "outflow"]"#);
    let scene = Scene::from_toml_str(&text, "test.toml").expect("scene");
    let fluid = scene.fluid.as_ref().expect("[fluid]");
    let mut solver = FluidSolver::from_scene(fluid, threads).expect("solver");
    let w = [0.5, 0.1, 0.05];
    let body = box_3d(
        [0.16, 0.5, 0.5],
        [0.12; 3],
        rotation([0.0, 0.6, 0.8], 0.2),
        w,
    );
    assert!(
        body.vertices.chunks_exact(3).any(|v| v[0] < 0.05),
        "the cube reaches into the first cell layer"
    );
    let mut embedded = Embedded::new(&solver, body).expect("embedded");
    let mut out = Run {
        bits: Vec::new(),
        mixed: 0,
        cut: 0,
    };
    for step in 0..8 {
        let (cfl, one_cell) = (solver.max_dt(), embedded.one_cell_dt());
        let dt = 0.5 / (0.5 / cfl + 2.0 / one_cell);
        let report = embedded.predict(&mut solver, dt);
        assert!(report.ok(), "step {step}: {:?}", report.troubles);
        let current = embedded.surface().clone();
        let loads = embedded.loads(&solver, &current).expect("loads");
        let next = translated(&current, dt);
        let r = embedded
            .correct(&mut solver, dt, next, step, true)
            .unwrap_or_else(|e| panic!("step {step}: {e}"));
        (out.mixed, out.cut) = (out.mixed + r.mixed_cells, out.cut + r.cut_cells);
        let totals = embedded.totals(&solver);
        out.bits.push(format!("{r:?} {loads:?} {totals:?}"));
    }
    let cells: Vec<u32> = (0..solver.grid().n_cells() as u32).collect();
    out.bits.push(format!("{:?}", solver.cells_at(&cells)));
    out
}

#[test]
fn a_coupled_run_is_the_same_on_any_number_of_threads() {
    let one = run(1);
    assert!(
        one.mixed > 0 && one.cut > 1000,
        "mixed {} and cut {} cells",
        one.mixed,
        one.cut
    );
    for threads in [2, 5] {
        let many = run(threads);
        for (k, (a, b)) in one.bits.iter().zip(&many.bits).enumerate() {
            assert_eq!(a, b, "{threads} threads, record {k}");
        }
        assert_eq!(one.bits.len(), many.bits.len());
    }
}
