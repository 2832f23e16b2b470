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

/// The dense geometry's bytes of each rank after 3 steps on `dims`, and those of the block
/// geometry it keeps for the next (`EmbeddedMemory::block_buffers`).
fn dense_per_rank(grid: &Grid, dims: [usize; 3]) -> Vec<(usize, usize)> {
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
        let m = e.memory();
        (m.dense_geometry, m.block_buffers)
    })
}

/// Bytes of Λ and λ the kept block geometry of `block` holds at most: each array as long as the
/// longer of the loads' window (the block and one cell around it: Λ and λ along x) and the
/// correct's (the block: Λ and λ along every axis).
fn block_dense(grid: &Grid, block: CellBox) -> usize {
    let loads = block.grown(grid, 1);
    let cells = loads.n_cells().max(block.n_cells());
    let x_faces = loads.n_faces(grid, 0).max(block.n_faces(grid, 0));
    let across: usize = (1..grid.dim).map(|a| block.n_faces(grid, a)).sum();
    8 * (cells + x_faces + across)
}

#[test]
fn the_dense_geometry_per_rank_is_the_blocks_and_the_hooks_halo() {
    let (grid, _) = blast(&[16, 16, 48]);
    let one = dense_per_rank(&grid, [1, 1, 1]);
    assert_eq!(
        one,
        vec![(dense_of(&grid, CellBox::whole(&grid)), 0)],
        "one rank: whole grid, no block geometry"
    );
    let halo = hook_halo(3);
    for dims in [[1, 1, 2], [1, 1, 4], [1, 2, 2]] {
        let dense = dense_per_rank(&grid, dims);
        for (r, &(bytes, block_bytes)) in dense.iter().enumerate() {
            let block = CellBox::of_rank(&grid, dims, r);
            let held = block.grown(&grid, halo);
            assert_eq!(bytes, dense_of(&grid, held), "{dims:?} rank {r}");
            // Its Λ and λ (the rest is the sub-faces of the block and one cell around it).
            let most = block_dense(&grid, block);
            assert!(
                (most..2 * most).contains(&block_bytes),
                "{dims:?} rank {r}: {block_bytes} bytes kept, against {most} for Λ and λ"
            );
        }
        // (The kept block geometry is not counted here: each step allocated as much afresh
        // before, so it adds nothing to a rank's peak.)
        if dims == [1, 1, 4] {
            assert!(
                dense.iter().all(|&(b, _)| b < one[0].0),
                "{dims:?}: {dense:?} against {one:?}"
            );
        }
    }
}
