//! Issue 40 item 1, steps 3 and 4: a surface beyond the near cells is refused on every rank of
//! slabs and blocks as one rank refuses it, naming the same cell (thread ranks, as in
//! `fv_ranks`).

use fluid_node::embedded::{Embedded, SolidFrame};
use fluid_node::fv::{BoundaryKind, FluidSolver};

use crate::embedded_support;
use crate::fv_ranks::{blast, moving_bodies_2d, on_thread_ranks, params};

/// What `refuse` says on each rank of the process grid `dims` (slabs and blocks of the 2-D
/// blast with the moving bodies), given the solver and embedded part after one predict, its
/// step and the surface moved 4 cells in 1/30 s (the tilted block, 2.5 m/s along y, cells of
/// 1/48 m): the refusals of a surface beyond the near cells.
fn refusals(
    dims: [usize; 3],
    refuse: fn(&mut Embedded, &mut FluidSolver, f64, SolidFrame) -> String,
) -> Vec<String> {
    let (grid, state) = blast(&[40, 48]);
    let solid = moving_bodies_2d();
    let params = params(5, [[BoundaryKind::Wall; 2]; 3]);
    let ranks = dims.iter().product();
    on_thread_ranks(ranks, |comm| {
        let (grid, state, params) = (grid.clone(), state.clone(), params.clone());
        let dims = (ranks > 1).then_some(dims);
        let mut s = FluidSolver::decomposed_as(grid, params, state, 1, Box::new(comm), dims)
            .expect("solver");
        let mut e = Embedded::new(&s, solid.clone()).expect("embedded");
        let dt = s.max_dt().min(0.5 * e.one_cell_dt());
        assert!(e.predict(&mut s, dt).ok());
        let far = embedded_support::translated(e.surface(), 1.0 / 30.0);
        refuse(&mut e, &mut s, dt, far)
    })
}

/// Issue 40 item 1, step 3: each rank takes the loads' terms of its own block's sub-faces, so
/// a trial surface that reaches beyond the near cells (moved 4 cells: the sub-face whose `p̄`
/// is missing lies in one rank's block) must be refused on every rank as one rank refuses it,
/// naming the same cell.
#[test]
fn a_trial_surface_beyond_the_near_cells_is_refused_on_every_rank_as_on_one() {
    let refuse = |e: &mut Embedded, s: &mut FluidSolver, _dt: f64, far: SolidFrame| {
        let err = e.loads(s, &far).expect_err("beyond the near cells");
        err.to_string()
    };
    let one = refusals([1, 1, 1], refuse);
    assert!(one[0].contains("the trial wet surface"), "{}", one[0]);
    for dims in [[1, 2, 1], [2, 2, 1], [2, 4, 1]] {
        for (r, refusal) in refusals(dims, refuse).iter().enumerate() {
            assert_eq!(refusal, &one[0], "{dims:?} rank {r}");
        }
    }
}

/// Issue 40 item 1, step 4: an accepted surface moved 4 cells in one step sweeps prisms beyond
/// the near cells; each rank clips the prisms of its own cells' sub-faces only, and the entries
/// are gathered in sub-face order, so every rank refuses the correct naming the cell one rank
/// names (the first piece beyond, in the sub-faces' order), on slabs and on blocks.
#[test]
fn an_accepted_surface_beyond_the_near_cells_is_refused_on_every_rank_as_on_one() {
    let refuse = |e: &mut Embedded, s: &mut FluidSolver, dt: f64, far: SolidFrame| {
        let err = e
            .correct(s, dt, far, 7, false)
            .expect_err("beyond the near cells");
        err.to_string()
    };
    let one = refusals([1, 1, 1], refuse);
    assert!(one[0].contains("step 7"), "{}", one[0]);
    assert!(one[0].contains("prism"), "{}", one[0]);
    for dims in [[1, 2, 1], [2, 2, 1], [2, 4, 1]] {
        for (r, refusal) in refusals(dims, refuse).iter().enumerate() {
            assert_eq!(refusal, &one[0], "{dims:?} rank {r}");
        }
    }
}
