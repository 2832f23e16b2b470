//! Issue 40 item 1, step 4 (a): the whole grid's geometry put together from every block's own
//! cells (`cutcell::block_part` of `compute_block`, `CutGeometry::assemble`), what each rank of a
//! decomposed grid holds of `F^{n+1}` instead of computing it on the whole grid, is the whole
//! grid's `compute`, bit for bit: Λ of every cell, λ of every face along every axis, the
//! sub-faces (with their vertices' bits) and the cut cells, for the moving bodies of the
//! `fv_ranks` tests at several positions, on their process grids, with and without a halo, and
//! into buffers that held another geometry (the sparse reset). And the prisms of each block's
//! sub-faces taken from it (`subface_swept_volumes_of`, whose vertices it finds by cell), put
//! together as the correct gathers them, are the whole surface's. And what a rank holds of it
//! (`CutGeometry::assemble_held`: Λ and λ dense in its block and a halo, as runs elsewhere,
//! `HeldFractions`; the same from the whole grid's, `HeldFractions::from_whole`) reads the
//! whole grid's bits at every cell and face, into buffers that held another surface.

use fluid_node::cutcell::{
    CellBox, CutGeometry, HeldFractions, SubFace, SubfaceSwept, SubfaceSweptEntry, block_part,
    compute, compute_block, n_faces, subface_swept_volumes, subface_swept_volumes_of,
};
use fluid_node::embedded::SolidFrame;
use fluid_node::grid::Grid;

use crate::embedded_support::translated;
use crate::fv_ranks::{
    PROCESS_GRIDS_2D, PROCESS_GRIDS_3D, blast, bodies, moving_bodies_2d, moving_bodies_3d,
    seam_plate_2d,
};

/// A sub-face and its vertices as bits (its place in `subface_vertices` left out).
pub(crate) fn subface_bits(s: &SubFace, vertices: &[[f64; 3]]) -> Vec<u64> {
    let v = &vertices[s.first_vertex as usize..(s.first_vertex + s.n_vertices) as usize];
    let mut x = vec![s.cell as u64, s.element as u64, s.particle as u64];
    x.push(s.area.to_bits());
    x.extend(s.normal.iter().chain(&s.centroid).map(|y| y.to_bits()));
    x.extend(v.iter().flatten().map(|y| y.to_bits()));
    x
}

/// Asserts `got` holds the whole grid's geometry `whole`, bit for bit.
fn assert_same(grid: &Grid, whole: &CutGeometry, got: &CutGeometry, what: &str) {
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<u64>>();
    assert_eq!(whole.solid_fraction.len(), got.solid_fraction.len());
    for c in 0..grid.n_cells() {
        assert_eq!(
            whole.solid_fraction[c].to_bits(),
            got.solid_fraction[c].to_bits(),
            "{what}: Λ of cell {:?}",
            grid.ijk(c)
        );
    }
    for axis in 0..3 {
        let (w, g) = (&whole.face_fraction[axis], &got.face_fraction[axis]);
        if bits(w) != bits(g) {
            let f = (0..w.len()).find(|&f| w[f].to_bits() != g[f].to_bits());
            panic!("{what}: λ along {axis} differs first at face {f:?}");
        }
    }
    assert_eq!(
        whole.subfaces.len(),
        got.subfaces.len(),
        "{what}: sub-faces"
    );
    for (s, t) in whole.subfaces.iter().zip(&got.subfaces) {
        assert_eq!(
            subface_bits(s, &whole.subface_vertices),
            subface_bits(t, &got.subface_vertices),
            "{what}: sub-face of cell {} element {}",
            s.cell,
            s.element
        );
    }
    assert_eq!(whole.cut_cells, got.cut_cells, "{what}: cut cells");
}

/// Entries as bits, to compare.
fn entry_bits(entries: &[SubfaceSweptEntry]) -> Vec<(u32, u32, u64)> {
    entries
        .iter()
        .map(|e| (e.subface, e.cell, e.volume.to_bits()))
        .collect()
}

/// `frame` moved by `dt` and deformed (each vertex pushed by up to 0.3 of a cell of `dx` along
/// each axis), so that the prisms' bottoms are no translates of their tops.
fn deformed(frame: &SolidFrame, dt: f64, dx: f64) -> SolidFrame {
    let mut next = translated(frame, dt);
    for (k, x) in next.vertices.iter_mut().enumerate() {
        *x += 0.3 * dx * (1.7 * k as f64).sin();
    }
    next
}

/// Every process grid of `decomps`, at 3 moves of `dt`, halos 0 and 3: the geometry put together
/// is the whole grid's, and so are the gathered prisms of the blocks' sub-faces taken from it.
/// Returns the process grids whose put-together vertices lie in another layout than the whole
/// grid's (where finding a sub-face's vertices by cell matters).
fn check(name: &str, grid: &Grid, solid: &SolidFrame, dt: f64, decomps: &[[usize; 3]]) -> usize {
    let dx = grid.dx[0];
    let mut assembled = CutGeometry::new();
    let mut other_layout = 0;
    for k in 0..3 {
        let before = translated(solid, k as f64 * dt);
        let after = deformed(&before, dt, dx);
        let mut whole = CutGeometry::new();
        compute(grid, &after.surface(), &mut whole);
        let mut swept = SubfaceSwept::new();
        subface_swept_volumes(
            grid,
            &before.surface(),
            &after.surface(),
            &whole,
            &mut swept,
        );
        assert!(!swept.entries.is_empty(), "{name}: entries");
        for dims in decomps {
            let ranks: usize = dims.iter().product();
            for halo in [0, 3] {
                let what = format!("{name}, move {k}, {dims:?}, halo {halo}");
                let parts: Vec<Vec<u8>> = (0..ranks)
                    .map(|r| {
                        let block = CellBox::of_rank(grid, *dims, r);
                        block_part(grid, &compute_block(grid, &after.surface(), block, halo))
                    })
                    .collect();
                // Into the buffers of the last check (another position or process grid), and
                // over the whole grid's `compute` of the surface before: the reset is sparse.
                assembled.assemble(grid, &parts);
                assert_same(grid, &whole, &assembled, &what);
                other_layout += usize::from(assembled.subface_vertices != whole.subface_vertices);
                let mut gathered: Vec<SubfaceSweptEntry> = Vec::new();
                for r in 0..ranks {
                    let block = CellBox::of_rank(grid, *dims, r);
                    let mine = |s: &SubFace| block.contains(grid.ijk(s.cell as usize));
                    let mut part = SubfaceSwept::new();
                    let (b, a) = (before.surface(), after.surface());
                    subface_swept_volumes_of(grid, &b, &a, &assembled, mine, &mut part);
                    assert_eq!(part.n_skipped_subfaces, 0, "{what}, rank {r}: skipped");
                    gathered.extend_from_slice(&part.entries);
                }
                gathered.sort_by_key(|e| e.subface);
                assert_eq!(
                    entry_bits(&gathered),
                    entry_bits(&swept.entries),
                    "{what}: gathered entries"
                );
            }
        }
        compute(grid, &before.surface(), &mut assembled);
    }
    other_layout
}

#[test]
fn the_whole_geometry_put_together_from_the_blocks_is_computes_2d() {
    let (grid, _) = blast(&[40, 48]);
    let solid = bodies(&[moving_bodies_2d(), seam_plate_2d()]);
    let decomps = PROCESS_GRIDS_2D;
    let other = check("2-D", &grid, &solid, 0.006, &decomps);
    assert!(other > 0, "2-D: some vertices in another layout");
}

#[test]
fn the_whole_geometry_put_together_from_the_blocks_is_computes_3d() {
    let (grid, _) = blast(&[16, 16, 24]);
    let decomps = PROCESS_GRIDS_3D;
    let other = check("3-D", &grid, &moving_bodies_3d(), 0.012, &decomps);
    assert!(other > 0, "3-D: some vertices in another layout");
}

/// Asserts `held` reads the whole grid's Λ and λ of `whole` at every cell and face, bit for bit.
pub(crate) fn assert_held(grid: &Grid, whole: &CutGeometry, held: &HeldFractions, what: &str) {
    for c in 0..grid.n_cells() {
        assert_eq!(
            whole.solid_fraction[c].to_bits(),
            held.solid_fraction_of(c).to_bits(),
            "{what}: Λ of cell {:?} (held {:?})",
            grid.ijk(c),
            held.held
        );
    }
    for axis in 0..grid.dim {
        for f in 0..n_faces(grid, axis) {
            assert_eq!(
                whole.face_fraction[axis][f].to_bits(),
                held.face_fraction_of(axis, f).to_bits(),
                "{what}: λ along {axis} of face {f} (held {:?})",
                held.held
            );
        }
    }
}

/// Every block of every process grid of `decomps`, held with halos 0, 2 and 15, over 3 moves
/// of `dt` into the same buffers: `assemble_held` and `from_whole` read the whole grid's bits,
/// and the sub-faces and cut cells are the whole grid's, its dense arrays left empty. Returns
/// the blocks whose dense arrays are smaller than the whole grid's.
fn check_held(grid: &Grid, solid: &SolidFrame, dt: f64, decomps: &[[usize; 3]]) -> usize {
    let dx = grid.dx[0];
    let moves: Vec<(SolidFrame, CutGeometry)> = (0..3)
        .map(|k| {
            let frame = deformed(&translated(solid, k as f64 * dt), dt, dx);
            let mut whole = CutGeometry::new();
            compute(grid, &frame.surface(), &mut whole);
            (frame, whole)
        })
        .collect();
    let mut smaller = 0;
    for dims in decomps {
        let ranks: usize = dims.iter().product();
        for r in 0..ranks {
            for halo in [0, 2, 15] {
                let block = CellBox::of_rank(grid, *dims, r);
                let mut held = HeldFractions::new(grid, block.grown(grid, halo));
                let mut cut = CutGeometry::new();
                compute(grid, &moves[2].0.surface(), &mut cut);
                for (k, (frame, whole)) in moves.iter().enumerate() {
                    let what = format!("move {k}, {dims:?} rank {r}, halo {halo}");
                    let parts: Vec<Vec<u8>> = (0..ranks)
                        .map(|q| {
                            let b = CellBox::of_rank(grid, *dims, q);
                            block_part(grid, &compute_block(grid, &frame.surface(), b, 0))
                        })
                        .collect();
                    cut.assemble_held(grid, &parts, &mut held);
                    assert_held(grid, whole, &held, &what);
                    assert!(cut.solid_fraction.is_empty(), "{what}: no whole Λ");
                    assert_eq!(cut.cut_cells, whole.cut_cells, "{what}: cut cells");
                    let bits = |g: &CutGeometry| -> Vec<Vec<u64>> {
                        (g.subfaces.iter())
                            .map(|s| subface_bits(s, &g.subface_vertices))
                            .collect()
                    };
                    assert_eq!(bits(&cut), bits(whole), "{what}: sub-faces");
                    let from = HeldFractions::from_whole(grid, whole, held.held);
                    assert_held(grid, whole, &from, &format!("{what}, from the whole grid"));
                }
                smaller += usize::from(held.dense_bytes() < whole_dense(grid));
            }
        }
    }
    smaller
}

/// Bytes of the whole grid's Λ and λ.
fn whole_dense(grid: &Grid) -> usize {
    8 * (grid.n_cells() + (0..grid.dim).map(|a| n_faces(grid, a)).sum::<usize>())
}

#[test]
fn what_a_rank_holds_reads_the_whole_grids_fractions_2d() {
    let (grid, _) = blast(&[40, 48]);
    let solid = bodies(&[moving_bodies_2d(), seam_plate_2d()]);
    let decomps = [[1, 2, 1], [2, 2, 1], [3, 1, 1], [2, 4, 1]];
    let smaller = check_held(&grid, &solid, 0.006, &decomps);
    assert!(smaller > 0, "2-D: some ranks hold less than the whole grid");
}

#[test]
fn what_a_rank_holds_reads_the_whole_grids_fractions_3d() {
    let (grid, _) = blast(&[16, 16, 24]);
    let decomps = [[1, 1, 2], [1, 2, 2], [1, 1, 3], [1, 2, 4]];
    let smaller = check_held(&grid, &moving_bodies_3d(), 0.012, &decomps);
    assert!(smaller > 0, "3-D: some ranks hold less than the whole grid");
}
