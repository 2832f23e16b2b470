//! Issue 40 item 1, step 1: the geometry of a block and its halo from the elements that reach
//! them (`cutcell::compute_block`) is the whole grid's geometry, bit for bit: Λ, λ along x and
//! the sub-faces on every cell of the window, λ along every axis on the block's own faces, for
//! the moving bodies of the `fv_ranks` tests at several positions, on their process grids, with
//! halos from none (a block's own cells only) to the embedded part's; and the same for Λ, λ
//! along x and the sub-faces of `compute_block_cells` (the loads' geometry). Step 4: the prisms
//! of the sub-faces of each block's cells (`cutcell::subface_swept_volumes_of`), put together in
//! sub-face order, are the whole surface's.

use fluid_node::cutcell::{
    BlockGeometry, CellBox, CutGeometry, SubfaceSwept, SubfaceSweptEntry, compute, compute_block,
    compute_block_cells, compute_block_cells_reusing, compute_block_reusing, subface_swept_volumes,
    subface_swept_volumes_of,
};
use fluid_node::embedded::SolidFrame;
use fluid_node::grid::Grid;

use crate::embedded_support::translated;
use crate::fv_ranks::{
    PROCESS_GRIDS_2D, PROCESS_GRIDS_3D, blast, bodies, moving_bodies_2d, moving_bodies_3d,
    seam_plate_2d,
};

/// Halos checked: none, one and two cells (rows swept whole where a wall along a cut axis
/// enters the block), and wider ones.
const HALOS: [usize; 5] = [0, 1, 2, 5, 12];

/// What the blocks of one check did, summed.
#[derive(Default)]
struct Tally {
    whole_rows: usize,
    /// Blocks that clipped fewer elements than the surface holds.
    fewer: usize,
    blocks: usize,
}

/// Asserts every cell of the window (Λ, λ_x, sub-faces, cut cells) and every face of the
/// block's cells (λ along every axis) as the whole grid has them.
///
/// `cells_only`: the geometry of `compute_block_cells`, λ along x only.
pub(crate) fn assert_block_is_whole(
    grid: &Grid,
    whole: &CutGeometry,
    b: &BlockGeometry,
    cells_only: bool,
    what: &str,
) {
    let w = b.window;
    let dim = grid.dim;
    assert!(
        b.unwritten_values_are_zero(),
        "{what}: a row written unrecorded"
    );
    for c in 0..grid.n_cells() {
        let ijk = grid.ijk(c);
        if !w.contains(ijk) {
            continue;
        }
        let own = b.block.contains(ijk);
        assert_eq!(
            whole.solid_fraction[c].to_bits(),
            b.solid_fraction_at(ijk).to_bits(),
            "{what}: Λ of cell {ijk:?}"
        );
        for axis in 0..dim {
            if axis > 0 && (!own || cells_only) {
                continue;
            }
            for side in 0..2 {
                let mut at = ijk;
                at[axis] += side;
                let f = fluid_node::cutcell::face_index(grid, axis, at);
                assert_eq!(
                    whole.face_fraction[axis][f].to_bits(),
                    b.face_fraction_at(axis, at).to_bits(),
                    "{what}: λ along {axis} of face {at:?} (own cell {own})"
                );
            }
        }
    }
    let in_window = |cell: u32| w.contains(grid.ijk(cell as usize));
    let expected: Vec<_> = whole
        .subfaces
        .iter()
        .filter(|s| in_window(s.cell))
        .collect();
    assert_eq!(expected.len(), b.subfaces.len(), "{what}: sub-faces");
    for (s, t) in expected.iter().zip(&b.subfaces) {
        let bits = |s: &fluid_node::cutcell::SubFace, vs: &[[f64; 3]]| {
            let v = &vs[s.first_vertex as usize..(s.first_vertex + s.n_vertices) as usize];
            let mut x = vec![s.cell as u64, s.element as u64, s.particle as u64];
            x.push(s.area.to_bits());
            x.extend(s.normal.iter().chain(&s.centroid).map(|y| y.to_bits()));
            x.extend(v.iter().flatten().map(|y| y.to_bits()));
            x
        };
        assert_eq!(
            bits(s, &whole.subface_vertices),
            bits(t, &b.subface_vertices),
            "{what}: sub-face of cell {} element {}",
            s.cell,
            s.element
        );
    }
    let cut: Vec<u32> = whole
        .cut_cells
        .iter()
        .copied()
        .filter(|&c| in_window(c))
        .collect();
    assert_eq!(cut, b.cut_cells, "{what}: cut cells");
}

/// Every field of a block geometry as bits, to compare.
fn geometry_bits(b: &BlockGeometry) -> Vec<u64> {
    let mut x = vec![
        b.clipped_elements as u64,
        b.whole_rows as u64,
        b.n_pieces as u64,
    ];
    x.extend(b.block.lo.iter().chain(&b.block.hi).map(|&v| v as u64));
    x.extend(b.window.lo.iter().chain(&b.window.hi).map(|&v| v as u64));
    for values in std::iter::once(&b.solid_fraction).chain(&b.face_fraction) {
        x.push(values.len() as u64);
        x.extend(values.iter().map(|v| v.to_bits()));
    }
    for s in &b.subfaces {
        x.extend([s.cell, s.element, s.particle, s.first_vertex, s.n_vertices].map(u64::from));
        x.push(s.area.to_bits());
        x.extend(s.normal.iter().chain(&s.centroid).map(|v| v.to_bits()));
    }
    x.extend(b.subface_vertices.iter().flatten().map(|v| v.to_bits()));
    x.extend(b.cut_cells.iter().map(|&c| u64::from(c)));
    x
}

/// Every block of every process grid in `decomps`, with every halo, at `positions` steps of
/// `dt` along the bodies' velocities. Each geometry is also computed into the buffers of the
/// one before it (`compute_block_reusing`, `compute_block_cells_reusing`: another block, halo,
/// position or kind of geometry), which must give the same geometry, every field.
fn check(name: &str, grid: &Grid, solid: &SolidFrame, dt: f64, decomps: &[[usize; 3]]) -> Tally {
    let mut tally = Tally::default();
    let mut reused = BlockGeometry::default();
    for k in 0..4 {
        let frame = translated(solid, k as f64 * dt);
        let surface = frame.surface();
        let mut whole = CutGeometry::new();
        compute(grid, &surface, &mut whole);
        assert_eq!(whole.diagnostics.n_skipped_elements, 0);
        for dims in decomps {
            let ranks: usize = dims.iter().product();
            for r in 0..ranks {
                let block = CellBox::of_rank(grid, *dims, r);
                for halo in HALOS {
                    let b = compute_block(grid, &surface, block, halo);
                    let what = format!("{name}, position {k}, {dims:?} rank {r}, halo {halo}");
                    assert_block_is_whole(grid, &whole, &b, false, &what);
                    let cells = compute_block_cells(grid, &surface, block, halo);
                    assert_block_is_whole(grid, &whole, &cells, true, &what);
                    let buffers = std::mem::take(&mut reused);
                    reused = compute_block_reusing(grid, &surface, block, halo, buffers);
                    let same = geometry_bits(&reused) == geometry_bits(&b);
                    assert!(same && reused.unwritten_values_are_zero(), "{what}: reused");
                    let buffers = std::mem::take(&mut reused);
                    reused = compute_block_cells_reusing(grid, &surface, block, halo, buffers);
                    let same = geometry_bits(&reused) == geometry_bits(&cells);
                    assert!(
                        same && reused.unwritten_values_are_zero(),
                        "{what}: cells reused"
                    );
                    assert_eq!(cells.whole_rows, 0, "{what}: compute_block_cells");
                    tally.whole_rows += b.whole_rows;
                    tally.fewer += usize::from(b.clipped_elements < surface.n_elements());
                    tally.blocks += 1;
                }
            }
        }
    }
    eprintln!(
        "{name}: {} blocks, {} clipped fewer elements than the surface's, {} rows swept whole",
        tally.blocks, tally.fewer, tally.whole_rows
    );
    tally
}

#[test]
fn block_geometry_2d_is_the_whole_grids_on_every_process_grid() {
    let (grid, _) = blast(&[40, 48]);
    let solid = bodies(&[moving_bodies_2d(), seam_plate_2d()]);
    // 0.006 s moves the fastest body (2.7 m/s) 0.8 cells of 1/48 m.
    let decomps = PROCESS_GRIDS_2D;
    let tally = check("2-D", &grid, &solid, 0.006, &decomps);
    assert!(tally.whole_rows > 0, "rows swept whole");
    assert!(tally.fewer > tally.blocks / 2, "blocks clip fewer elements");
}

#[test]
fn block_geometry_3d_is_the_whole_grids_on_every_process_grid() {
    let (grid, _) = blast(&[16, 16, 24]);
    let solid = moving_bodies_3d();
    // 0.012 s moves the fastest body (2.7 m/s) 0.8 cells of 1/24 m.
    let decomps = PROCESS_GRIDS_3D;
    let tally = check("3-D", &grid, &solid, 0.012, &decomps);
    assert!(tally.whole_rows > 0, "rows swept whole");
    // The bodies span 7 of the 24 cells along z and 8 of 16 along y: only the blocks of the
    // narrower halos miss some of them (103 of 460 blocks).
    assert!(tally.fewer > tally.blocks / 5, "blocks clip fewer elements");
}

/// `frame` moved by `dt` along the bodies' velocity and deformed: each vertex pushed by up to 0.3
/// of a cell of `dx` along each axis, differently for each vertex (so that the prisms' bottoms
/// are no translates of their tops).
fn deformed(frame: &SolidFrame, dt: f64, dx: f64) -> SolidFrame {
    let mut next = translated(frame, dt);
    for (k, x) in next.vertices.iter_mut().enumerate() {
        *x += 0.3 * dx * (1.7 * k as f64).sin();
    }
    next
}

/// Entries as bits, to compare.
fn entry_bits(entries: &[SubfaceSweptEntry]) -> Vec<(u32, u32, u64)> {
    entries
        .iter()
        .map(|e| (e.subface, e.cell, e.volume.to_bits()))
        .collect()
}

/// On every block of every process grid in `decomps`, over 3 moves of `dt` (deformed): the
/// prisms of the block's sub-faces are the whole surface's prisms of those sub-faces, and those of
/// all the blocks, put together as the correct gathers them (in rank order, then a stable sort
/// by sub-face), are the whole surface's, bit for bit. Returns (blocks that clipped fewer
/// pieces than the whole surface, blocks).
fn check_prisms(
    name: &str,
    grid: &Grid,
    solid: &SolidFrame,
    dt: f64,
    decomps: &[[usize; 3]],
) -> (usize, usize) {
    let dx = grid.dx[0];
    let (mut fewer, mut blocks) = (0, 0);
    for k in 0..3 {
        let before = translated(solid, k as f64 * dt);
        let after = deformed(&before, dt, dx);
        let mut geom = CutGeometry::new();
        compute(grid, &after.surface(), &mut geom);
        let mut whole = SubfaceSwept::new();
        subface_swept_volumes(grid, &before.surface(), &after.surface(), &geom, &mut whole);
        assert!(!whole.entries.is_empty(), "{name}: entries");
        assert_eq!(whole.n_skipped_subfaces, 0, "{name}: skipped");
        for dims in decomps {
            let ranks: usize = dims.iter().product();
            let mut gathered: Vec<SubfaceSweptEntry> = Vec::new();
            let mut pieces = 0;
            for r in 0..ranks {
                let what = format!("{name}, move {k}, {dims:?} rank {r}");
                let block = CellBox::of_rank(grid, *dims, r);
                let mine =
                    |s: &fluid_node::cutcell::SubFace| block.contains(grid.ijk(s.cell as usize));
                let mut part = SubfaceSwept::new();
                subface_swept_volumes_of(
                    grid,
                    &before.surface(),
                    &after.surface(),
                    &geom,
                    mine,
                    &mut part,
                );
                assert_eq!(part.n_skipped_subfaces, 0, "{what}: skipped");
                let expected: Vec<SubfaceSweptEntry> = (whole.entries.iter())
                    .filter(|e| mine(&geom.subfaces[e.subface as usize]))
                    .copied()
                    .collect();
                assert_eq!(
                    entry_bits(&part.entries),
                    entry_bits(&expected),
                    "{what}: entries"
                );
                fewer += usize::from(part.n_pieces < whole.n_pieces);
                pieces += part.n_pieces;
                blocks += 1;
                gathered.extend_from_slice(&part.entries);
            }
            // Each rank clips a triangle again only in the box of its own cells, so a triangle
            // across the blocks is not clipped whole on each of them (2-D segments, a few cells
            // long, are).
            assert!(
                grid.dim == 2 || pieces <= whole.n_pieces,
                "{name}, move {k}, {dims:?}: {pieces} pieces on the ranks, {} on one",
                whole.n_pieces
            );
            gathered.sort_by_key(|e| e.subface);
            assert_eq!(
                entry_bits(&gathered),
                entry_bits(&whole.entries),
                "{name}, move {k}, {dims:?}: gathered entries"
            );
        }
    }
    eprintln!("{name}: {blocks} blocks, {fewer} clipped fewer pieces than the whole surface");
    (fewer, blocks)
}

#[test]
fn the_prisms_of_a_partition_of_the_subfaces_are_the_whole_surfaces() {
    let (grid, _) = blast(&[40, 48]);
    let solid = bodies(&[moving_bodies_2d(), seam_plate_2d()]);
    let decomps = [[1, 2, 1], [2, 2, 1], [3, 1, 1], [2, 4, 1]];
    let (fewer, blocks) = check_prisms("2-D", &grid, &solid, 0.006, &decomps);
    assert_eq!(fewer, blocks, "2-D: every block clips fewer pieces");
    let (grid, _) = blast(&[16, 16, 24]);
    let decomps = [[1, 1, 2], [1, 2, 2], [1, 1, 3], [1, 2, 4]];
    let (fewer, blocks) = check_prisms("3-D", &grid, &moving_bodies_3d(), 0.012, &decomps);
    assert_eq!(fewer, blocks, "3-D: every block clips fewer pieces");
}
