//! Issue 40, docs/mpi.md step 1 ("What would fix that"): the geometry of each block of a
//! decomposed grid from the elements that reach it and the running sums passed along the pencils
//! of blocks (`cutcell::BlockSweep`, `compute_blocks`) is the whole grid's, bit for bit, on every
//! cell and every face of the block's cells, with no row swept whole; and a wrong running sum
//! passed at a boundary (one bit off, up or down) shows in the faces.

use fluid_node::cutcell::{
    BlockGeometry, BlockSweep, CellBox, CutGeometry, HeldFractions, block_part_shared, compute,
    compute_blocks, pass_messages,
};
use fluid_node::embedded::SolidFrame;
use fluid_node::grid::Grid;

use crate::cutcell_block::assert_block_is_whole;
use crate::cutcell_block_assemble::{assert_held, subface_bits};
use crate::embedded_support::translated;
use crate::fv_ranks::{
    PROCESS_GRIDS_3D, blast, bodies, moving_bodies_2d, moving_bodies_3d, seam_plate_2d,
};

/// Every block of every process grid in `decomps` at 4 positions `dt` apart, against `compute`;
/// returns how many blocks clipped fewer elements than the surface holds, and how many blocks.
fn check(name: &str, grid: &Grid, solid: &SolidFrame, dt: f64, decomps: &[[usize; 3]]) -> usize {
    let mut fewer = 0;
    for k in 0..4 {
        let frame = translated(solid, k as f64 * dt);
        let surface = frame.surface();
        let mut whole = CutGeometry::new();
        compute(grid, &surface, &mut whole);
        for dims in decomps {
            for (r, b) in compute_blocks(grid, &surface, *dims).iter().enumerate() {
                let what = format!("{name} chained, position {k}, {dims:?} rank {r}");
                assert_eq!(b.block, CellBox::of_rank(grid, *dims, r));
                assert_block_is_whole(grid, &whole, b, false, &what);
                assert_eq!(b.whole_rows, 0, "{what}: rows swept whole");
                fewer += usize::from(b.clipped_elements < surface.n_elements());
            }
        }
    }
    fewer
}

#[test]
fn chained_block_geometry_2d_is_the_whole_grids() {
    let (grid, _) = blast(&[40, 48]);
    let solid = bodies(&[moving_bodies_2d(), seam_plate_2d()]);
    let decomps = [[1, 2, 1], [1, 4, 1], [2, 2, 1], [1, 3, 1], [2, 4, 1]];
    assert!(check("2-D", &grid, &solid, 0.006, &decomps) > 0);
}

#[test]
fn chained_block_geometry_3d_is_the_whole_grids() {
    let (grid, _) = blast(&[16, 16, 24]);
    let solid = moving_bodies_3d();
    let decomps = PROCESS_GRIDS_3D;
    assert!(check("3-D", &grid, &solid, 0.012, &decomps) > 0);
}

/// The blocks of `dims` with each message of the pencils passed through `tamper`.
fn tampered(
    grid: &Grid,
    solid: &SolidFrame,
    dims: [usize; 3],
    mut tamper: impl FnMut(bool, Vec<f64>) -> Vec<f64>,
) -> Vec<BlockGeometry> {
    let surface = solid.surface();
    let ranks: usize = dims.iter().product();
    let mut sweeps: Vec<BlockSweep> = (0..ranks)
        .map(|r| BlockSweep::new(grid, &surface, CellBox::of_rank(grid, dims, r)))
        .collect();
    for axis in 1..grid.dim {
        pass_messages(dims, axis, &mut sweeps, |up, _, _, m| tamper(up, m));
    }
    sweeps.into_iter().map(BlockSweep::finish).collect()
}

fn face_bits(blocks: &[BlockGeometry]) -> Vec<u64> {
    (blocks.iter())
        .flat_map(|b| b.face_fraction.iter().flatten().map(|x| x.to_bits()))
        .collect()
}

/// One bit off in the running sums of the boundary messages, up or down, changes faces of the
/// blocks; the messages untouched give the whole grid's bits (above).
#[test]
fn a_wrong_boundary_running_sum_shows() {
    let (grid, _) = blast(&[16, 16, 24]);
    let solid = moving_bodies_3d();
    for dims in [[1, 1, 2], [1, 1, 3], [1, 2, 2]] {
        let right = face_bits(&tampered(&grid, &solid, dims, |_, m| m));
        for up in [true, false] {
            let mut changed = 0;
            let wrong = tampered(&grid, &solid, dims, |is_up, mut m| {
                if is_up == up {
                    for x in m.iter_mut().filter(|x| !x.is_nan()) {
                        *x = f64::from_bits(x.to_bits() + 1);
                        changed += 1;
                    }
                }
                m
            });
            assert!(changed > 0, "{dims:?}: messages (up {up}) to change");
            assert_ne!(right, face_bits(&wrong), "{dims:?}: up {up} one bit off");
        }
    }
}

/// The shares without the vertices (`block_part_shared`), put together on each rank with its own
/// vertices (`assemble_held_own`): Λ, λ and the sub-faces of the whole grid, every sub-face of the
/// rank's own cells with its vertices' bits, the others' without vertices.
#[test]
fn shares_without_vertices_give_the_whole_grid_and_each_ranks_own_vertices() {
    let (grid, _) = blast(&[16, 16, 24]);
    let solid = moving_bodies_3d();
    for k in 0..3 {
        let frame = translated(&solid, k as f64 * 0.012);
        let surface = frame.surface();
        let mut whole = CutGeometry::new();
        compute(&grid, &surface, &mut whole);
        for dims in [[1, 1, 2], [1, 2, 2], [1, 1, 3]] {
            let shares: Vec<_> = (compute_blocks(&grid, &surface, dims).iter())
                .map(|b| block_part_shared(&grid, b))
                .collect();
            let parts: Vec<Vec<u8>> = shares.iter().map(|s| s.0.clone()).collect();
            for (r, (_, vertices)) in shares.iter().enumerate() {
                let what = format!("position {k}, {dims:?} rank {r}");
                let block = CellBox::of_rank(&grid, dims, r);
                let mut held = HeldFractions::new(&grid, block);
                let mut cut = CutGeometry::new();
                cut.assemble_held_own(&grid, &parts, &mut held, (r, vertices));
                assert_held(&grid, &whole, &held, &what);
                assert_eq!(cut.cut_cells, whole.cut_cells, "{what}: cut cells");
                assert_eq!(cut.subfaces.len(), whole.subfaces.len(), "{what}");
                for (s, t) in cut.subfaces.iter().zip(&whole.subfaces) {
                    if block.contains(grid.ijk(s.cell as usize)) {
                        assert_eq!(
                            subface_bits(s, &cut.subface_vertices),
                            subface_bits(t, &whole.subface_vertices),
                            "{what}: own sub-face"
                        );
                    } else {
                        assert_eq!(s.first_vertex, u32::MAX, "{what}: no vertices");
                        let head = |s: &fluid_node::cutcell::SubFace| {
                            let mut x = vec![s.cell, s.element, s.particle, s.n_vertices];
                            let reals = [s.area].into_iter().chain(s.normal).chain(s.centroid);
                            x.extend(reals.flat_map(|y| {
                                let b = y.to_bits();
                                [b as u32, (b >> 32) as u32]
                            }));
                            x
                        };
                        assert_eq!(head(s), head(t), "{what}: sub-face");
                    }
                }
            }
        }
    }
}
