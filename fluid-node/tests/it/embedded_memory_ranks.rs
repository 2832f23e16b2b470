//! Issue 40 items 1 and 4: on a decomposed grid each rank holds Λ and λ of `F^n` and `F^{n+1}`
//! dense in its block and the halo the hooks read only (`hook_halo`; `embedded::held`), so the
//! embedded part's dense memory per rank falls with K; on one rank it is the whole grid's. The
//! moving bodies of the 3-D `fv_ranks` test on a grid long enough along z for blocks of 12
//! planes plus the halo to hold less than the whole grid, 3 steps on 1, 2 and 4 thread ranks.

use fluid_node::cutcell::CellBox;
use fluid_node::embedded::{Embedded, hook_halo};
use fluid_node::fv::{BoundaryKind, FluidSolver};
use fluid_node::grid::Grid;

use crate::embedded_support::translated;
use crate::fv_ranks::{blast, moving_bodies_3d, on_thread_ranks, params};

/// Bytes of Λ and λ of the cells of `b` (both geometries).
fn dense_of(grid: &Grid, b: CellBox) -> usize {
    2 * 8 * (b.n_cells() + (0..grid.dim).map(|a| b.n_faces(grid, a)).sum::<usize>())
}

/// The dense geometry's bytes of each rank after 3 steps on `dims`.
fn dense_per_rank(grid: &Grid, dims: [usize; 3]) -> Vec<usize> {
    let (_, state) = blast(&grid.cells[..3]);
    let p = params(5, [[BoundaryKind::Wall; 2]; 3]);
    let ranks = dims.iter().product();
    on_thread_ranks(ranks, |comm| {
        let dims = (ranks > 1).then_some(dims);
        let (g, st) = (grid.clone(), state.clone());
        let mut s =
            FluidSolver::decomposed_as(g, p.clone(), st, 1, Box::new(comm), dims).expect("solver");
        let mut e = Embedded::new(&s, moving_bodies_3d()).expect("embedded");
        for n in 0..3 {
            let dt = s.max_dt().min(0.5 * e.one_cell_dt());
            assert!(e.predict(&mut s, dt).ok());
            let next = translated(e.surface(), dt);
            e.loads(&s, &next).expect("loads");
            e.correct(&mut s, dt, next, n, false).expect("correct");
        }
        e.memory().dense_geometry
    })
}

#[test]
fn the_dense_geometry_per_rank_is_the_blocks_and_the_hooks_halo() {
    let (grid, _) = blast(&[16, 16, 48]);
    let one = dense_per_rank(&grid, [1, 1, 1]);
    assert_eq!(
        one,
        vec![dense_of(&grid, CellBox::whole(&grid))],
        "one rank: whole grid"
    );
    let halo = hook_halo(3);
    for dims in [[1, 1, 2], [1, 1, 4], [1, 2, 2]] {
        let dense = dense_per_rank(&grid, dims);
        for (r, &bytes) in dense.iter().enumerate() {
            let held = CellBox::of_rank(&grid, dims, r).grown(&grid, halo);
            assert_eq!(bytes, dense_of(&grid, held), "{dims:?} rank {r}");
        }
        if dims == [1, 1, 4] {
            assert!(
                dense.iter().all(|&b| b < one[0]),
                "{dims:?}: {dense:?} against {one:?}"
            );
        }
    }
}
