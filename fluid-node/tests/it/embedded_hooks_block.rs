//! Issue 40 item 1, step 2: the sweeps' hook inputs a rank derives from its block's geometry
//! and a halo of `hook_halo(ng)` cells (`embedded::wall_hooks` with a block: ghost fills, wall
//! runs, vacuum cells) are the whole grid's restricted to the block (`WallHooks::restricted`),
//! bit for bit, on every block of the `fv_ranks` process grids, for the moving bodies of the
//! `fv_ranks` tests and flush plates (vacuum cells), at several positions, for `ng` = 2, 3, 4,
//! on the `fv_ranks` grids and on grids three times finer (where the windows do not hold the
//! whole grid); and so are those a rank takes from the window of the whole grid's geometry
//! (`embedded::wall_hooks_in`, what the predict on a decomposed grid calls). That the restriction gives the sweeps the bits of one rank is what the coupled
//! `fv_ranks` tests pin.

use fluid_node::cutcell::{CellBox, CutGeometry, compute};
use fluid_node::embedded::{SolidFrame, WallHooks, hook_halo, wall_hooks, wall_hooks_in};
use fluid_node::grid::Grid;

use crate::embedded_support::{polygon_2d, translated};
use crate::fv_ranks::{
    PROCESS_GRIDS_2D, PROCESS_GRIDS_3D, bodies, moving_bodies_2d, moving_bodies_3d, seam_plate_2d,
};

/// What the blocks of one check held, summed, to show the check covers each hook.
#[derive(Debug, Default)]
struct Tally {
    blocks: usize,
    /// Blocks whose window (block and halo) is not the whole grid.
    windowed: usize,
    ghosts: usize,
    walls: usize,
    vacuum: usize,
    /// Wall runs of a block's pencils the restriction drops (beyond its line and ghosts).
    dropped_walls: usize,
}

/// Every block of every process grid in `decomps`, at 4 positions `dt` apart along the bodies'
/// velocities, for `ng` = 2, 3, 4.
fn check(name: &str, grid: &Grid, solid: &SolidFrame, dt: f64, decomps: &[[usize; 3]]) -> Tally {
    let mut tally = Tally::default();
    for k in 0..4 {
        let frame = translated(solid, k as f64 * dt);
        for ng in [2, 3, 4] {
            let whole = wall_hooks(grid, ng, &frame, None);
            let mut geom = CutGeometry::new();
            compute(grid, &frame.surface(), &mut geom);
            for dims in decomps {
                let ranks: usize = dims.iter().product();
                for r in 0..ranks {
                    let block = CellBox::of_rank(grid, *dims, r);
                    let what = format!("{name}, position {k}, ng {ng}, {dims:?} rank {r}");
                    let expected = whole.restricted(grid, ng, block);
                    let got = wall_hooks(grid, ng, &frame, Some(block));
                    assert_same(&expected, &got, &what);
                    let from_whole = wall_hooks_in(grid, ng, &frame, &geom, block);
                    assert_same(&expected, &from_whole, &format!("{what}, whole geometry"));
                    tally.blocks += 1;
                    let window = block.grown(grid, hook_halo(ng));
                    tally.windowed += usize::from(window != CellBox::whole(grid));
                    tally.ghosts += got.ghosts.iter().map(Vec::len).sum::<usize>();
                    tally.walls += got.walls.iter().map(Vec::len).sum::<usize>();
                    tally.vacuum += got.vacuum.len();
                    // Every run of the block's pencils: `ng` beyond any pencil's length.
                    let on_pencils = whole.restricted(grid, grid.cells.iter().sum(), block);
                    tally.dropped_walls += on_pencils.walls.iter().map(Vec::len).sum::<usize>()
                        - got.walls.iter().map(Vec::len).sum::<usize>();
                }
            }
        }
    }
    eprintln!("{name}: {tally:?}");
    tally
}

/// Asserts the two hooks equal as bits (`{:?}` of an f64 round-trips it), axis by axis.
fn assert_same(expected: &WallHooks, got: &WallHooks, what: &str) {
    for axis in 0..3 {
        assert_eq!(
            format!("{:?}", expected.ghosts[axis]),
            format!("{:?}", got.ghosts[axis]),
            "{what}: ghost fills along {axis}"
        );
        assert_eq!(
            format!("{:?}", expected.walls[axis]),
            format!("{:?}", got.walls[axis]),
            "{what}: wall runs along {axis}"
        );
    }
    assert_eq!(expected.vacuum, got.vacuum, "{what}: vacuum cells");
}

/// Two plates pressed together along y = 0.62 (their faces on it, inside a cell row): the
/// covered cells holding both faces are vacuum cells (a crack that has not opened yet).
fn flush_plates_2d() -> SolidFrame {
    let lower = polygon_2d(
        &[[0.40, 0.60], [0.60, 0.60], [0.60, 0.62], [0.40, 0.62]],
        [0.0, 0.3],
        0.0,
    );
    let upper = polygon_2d(
        &[[0.40, 0.62], [0.60, 0.62], [0.60, 0.64], [0.40, 0.64]],
        [0.0, 0.3],
        0.0,
    );
    bodies(&[lower, upper])
}

#[test]
fn block_hooks_2d_are_the_whole_grids_on_every_process_grid() {
    let solid = bodies(&[moving_bodies_2d(), seam_plate_2d(), flush_plates_2d()]);
    let mut total = Tally::default();
    for (cells, dt) in [([40, 48], 0.006), ([120, 144], 0.002)] {
        let grid = Grid::new(&[0.0, 0.0], &[1.0, 1.0], &cells).expect("grid");
        let t = check(
            &format!("2-D {cells:?}"),
            &grid,
            &solid,
            dt,
            &PROCESS_GRIDS_2D,
        );
        total.blocks += t.blocks;
        total.windowed += t.windowed;
        total.walls += t.walls;
        total.vacuum += t.vacuum;
        total.ghosts += t.ghosts;
        total.dropped_walls += t.dropped_walls;
    }
    assert!(
        total.windowed > total.blocks / 3,
        "{total:?}: windows smaller than the grid"
    );
    assert!(
        total.ghosts > 0 && total.walls > 0 && total.vacuum > 0 && total.dropped_walls > 0,
        "{total:?}: every hook checked"
    );
}

#[test]
fn block_hooks_3d_are_the_whole_grids_on_every_process_grid() {
    let solid = moving_bodies_3d();
    let mut total = Tally::default();
    for (cells, dt) in [([16, 16, 24], 0.012), ([48, 48, 72], 0.004)] {
        let grid = Grid::new(&[0.0; 3], &[1.0; 3], &cells).expect("grid");
        let t = check(
            &format!("3-D {cells:?}"),
            &grid,
            &solid,
            dt,
            &PROCESS_GRIDS_3D,
        );
        total.blocks += t.blocks;
        total.windowed += t.windowed;
        total.walls += t.walls;
        total.ghosts += t.ghosts;
    }
    assert!(
        total.windowed > total.blocks / 3,
        "{total:?}: windows smaller than the grid"
    );
    assert!(
        total.ghosts > 0 && total.walls > 0,
        "{total:?}: fills and runs checked"
    );
}

/// The cells' walls are summed in parallel by runs of sub-faces (issue 36 item 4): on pools of
/// 1, 2 and 5 threads the hooks (ghost fills, wall runs, vacuum cells) are those of one thread,
/// bit for bit, for the moving 3-D bodies on 48 × 48 × 72 cells and the 2-D bodies with the
/// flush plates (vacuum cells) on 120 × 144, whole grid and one block each.
#[test]
fn the_hooks_are_the_same_on_any_number_of_threads() {
    let grid3 = Grid::new(&[0.0; 3], &[1.0; 3], &[48, 48, 72]).expect("grid");
    let grid2 = Grid::new(&[0.0, 0.0], &[1.0, 1.0], &[120, 144]).expect("grid");
    let solid2 = bodies(&[moving_bodies_2d(), seam_plate_2d(), flush_plates_2d()]);
    let cases = [
        (&grid3, moving_bodies_3d(), [1, 2, 2]),
        (&grid2, solid2, [2, 2, 1]),
    ];
    for (grid, solid, dims) in cases {
        for block in [None, Some(CellBox::of_rank(grid, dims, 1))] {
            let on = |threads: usize| {
                rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .expect("pool")
                    .install(|| wall_hooks(grid, 3, &solid, block))
            };
            let one = on(1);
            let n_fills: usize = one.ghosts.iter().map(Vec::len).sum();
            assert!(n_fills > 100, "{n_fills} ghost fills checked");
            for threads in [2, 5] {
                let what = format!("{:?}, {block:?}, {threads} threads", grid.cells);
                assert_same(&one, &on(threads), &what);
            }
        }
    }
}
