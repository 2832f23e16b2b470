//! Issue 40 item 1: the cells a crack opens (`Embedded::opening_cells`), found by each rank among
//! its own near cells and gathered, are one rank's. The crack of `embedded_crack` (two
//! rectangles flying apart, their shared face just wet) meets the cuts: the crack plane x =
//! 0.5075 lies in column 20 of 40, where `2 × 1` cuts x, and its lower mouth (a cut cell) in row
//! 19, just below the cut of `1 × 2` at y = 0.5, so that the mouth (rank 0's) takes the
//! Lax–Friedrichs flux against the covered cell above it that the crack opens (rank 1's).
//! Every step's predict report, loads, correct report, totals, budget and solid-flux loads, and
//! the final state, are one rank's, as bits.

use fluid_node::embedded::Embedded;
use fluid_node::fv::{BoundaryKind, FluidSolver};

use crate::embedded_crack::pair_between;
use crate::fv_common;
use crate::fv_ranks::{on_thread_ranks, params};

/// Speed of each rectangle away from the other \[m/s\].
const U: f64 = 0.4;

/// The crack's mouths: in rows 19 and 28 of 40, 0.3 of a cell from their lower faces.
const Y0: f64 = 19.3 / 40.0;
const Y1: f64 = 28.3 / 40.0;

/// `steps` coupled steps of the opening crack on the thread ranks of process grid `dims`: each
/// step's results as text, the final state's bits, and the faces that took the Lax–Friedrichs
/// flux beside vacuum (rank 0's).
fn crack_run(dims: [usize; 3], steps: u64) -> (Vec<String>, Vec<u64>, u64) {
    // Gas in motion, the blast in a corner away from the rectangles ([0.3, 0.7] × [0.48, 0.71]).
    let (grid, state) = fv_common::blast_state(&[40, 40], 0.9);
    let ranks = dims.iter().product();
    let mut runs = on_thread_ranks(ranks, |comm| {
        let walls = params(5, [[BoundaryKind::Wall; 2]; 3]);
        let dims = (ranks > 1).then_some(dims);
        let (grid, state) = (grid.clone(), state.clone());
        let mut s = FluidSolver::decomposed_as(grid, walls, state, 1, Box::new(comm), dims)
            .expect("solver");
        let mut e = Embedded::new(&s, pair_between(Y0, Y1, 0.0, U)).expect("embedded");
        e.set_fracture(true);
        let (mut out, mut vacuum_faces, mut shift) = (Vec::new(), 0, 0.0);
        for n in 0..steps {
            let dt = s.max_dt().min(0.5 * e.one_cell_dt());
            let predicted = e.predict(&mut s, dt);
            assert!(predicted.ok(), "step {n}: {:?}", predicted.troubles);
            vacuum_faces += predicted.lax_friedrichs_faces;
            shift += U * dt;
            let next = pair_between(Y0, Y1, shift, U);
            let loads = e.loads(&s, &next).expect("loads on the trial");
            let report = e
                .correct(&mut s, dt, next, n, false)
                .unwrap_or_else(|err| panic!("step {n}: {err}"));
            out.push(format!(
                "{predicted:?} {loads:?} {report:?} {:?} {:?} {:?}",
                e.totals(&s),
                e.budget(),
                e.last_loads()
            ));
        }
        let state = s
            .gather_state()
            .map(|g| g.u.iter().map(|x| x.to_bits()).collect::<Vec<u64>>());
        state.map(|state| (out, state, vacuum_faces))
    });
    runs[0].take().expect("rank 0 gathers")
}

#[test]
fn a_crack_opening_across_the_cuts_is_bit_identical_on_slabs_and_blocks() {
    let steps = 8;
    let one = crack_run([1; 3], steps);
    assert!(
        one.2 > 0,
        "the crack opens as vacuum (Lax–Friedrichs faces beside it)"
    );
    for dims in [[1, 2, 1], [2, 1, 1], [2, 2, 1], [1, 3, 1]] {
        let many = crack_run(dims, steps);
        for (n, (a, b)) in one.0.iter().zip(&many.0).enumerate() {
            assert_eq!(a, b, "step {n} on 1 rank and {dims:?}");
        }
        assert!(one.1 == many.1, "state of 1 rank and {dims:?} differs");
    }
}
