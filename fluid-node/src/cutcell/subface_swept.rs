//! [`subface_swept_volumes`]: the signed volume swept by each *sub-face* of the surface at
//! `t^{n+1}`, split among the grid cells (paper 000 eq. 12, paper 003 eq. 12).
//!
//! The conservative cut-cell update gives cell `i` the amount
//! `ΔU_i = Σ_{sub-faces f in i} Σ_{cells pqr} vol(K_f ∩ C_pqr) U^n_pqr`, where `K_f` is the prism
//! whose top is the sub-face `f` (the part of one element inside cell `i` at `t^{n+1}`) and whose
//! bottom is its preimage on the element at `t^n` under the element's affine motion (same
//! barycentric coordinates; 2-D: same parameter along the segment). For a translation by `d`,
//! `vol(K_f) = (d · n_f) area_f` exactly, which is what cancels the cut-cell fluxes of a uniform
//! flow around a translating body; the per-element prisms of [`crate::cutcell::swept_volumes`]
//! only give that sum per element.
//!
//! NOTE: preimages without a tolerance. For the lateral faces of two sub-prisms sharing an edge to
//! cancel exactly (conservation), a polygon vertex shared by two sub-faces must get the same
//! preimage bits in both. Within one element any deterministic map does; across a shared element
//! edge the two elements must compute it from the edge alone. Deciding from the coordinates whether
//! a clipped vertex lies on an element edge needs a tolerance (and fails for slivers); instead each
//! element at `t^{n+1}` is clipped again with its position at `t^n` carried as a payload of its
//! vertices (module `clip`). An element vertex carries its earlier position exactly; a cut point
//! gets its preimage by the same canonical interpolation as its position, between the same two
//! endpoints, so a vertex on a shared edge gets the same bits in both elements (and in a reversed
//! twin) by the argument that makes the cut points themselves agree, and an interior vertex gets
//! its affine preimage to round-off (linear interpolation of an affine map is exact). The second
//! clip repeats the one of [`crate::cutcell::compute`] on the same input, so it reproduces
//! `after_geometry`'s polygons bit for bit; every vertex is checked, and a sub-face whose vertices
//! do not match (a geometry computed from another surface) is skipped.

use rayon::prelude::*;

use crate::cutcell::clip::{Polygon, clip_polygon, clip_polygon_in, clip_segment};
use crate::cutcell::geometry::{CutGeometry, SubFace, domain_cell};
use crate::cutcell::measure::triangle_normal;
use crate::cutcell::prism::{PrismScratch, prism_volumes};
use crate::cutcell::surface::Surface;
use crate::grid::Grid;
use crate::memory::vec_bytes;

/// Signed volume of the prism of one sub-face (of the surface at `t^{n+1}`) inside one cell.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SubfaceSweptEntry {
    /// Sub-face: index into `after_geometry.subfaces`.
    pub subface: u32,
    /// Linear cell index ([`Grid::index`]).
    pub cell: u32,
    /// Signed volume, in m³ (2-D: area, in m²); positive where the solid advances.
    pub volume: f64,
}

/// Swept volumes of all sub-faces; buffers reused between calls.
#[derive(Clone, Debug, Default)]
pub struct SubfaceSwept {
    /// One entry per (sub-face, cell) pair with a non-zero volume, by sub-face then cell.
    pub entries: Vec<SubfaceSweptEntry>,
    /// Sub-faces skipped: a non-finite coordinate of their element at `t^n` (or a geometry that
    /// does not come from the surface at `t^{n+1}`).
    pub n_skipped_subfaces: usize,
    /// Pieces clipped by the last call (the second clip of the surface at `t^{n+1}`, then prism
    /// faces × cells they cross): its cost.
    pub n_pieces: usize,
    /// Preimage at `t^n` of every vertex of `after_geometry.subface_vertices` (NaN: none).
    preimages: Vec<[f64; 3]>,
    /// One per [`CHUNK`] sub-faces: what that run of sub-faces swept, computed apart.
    chunks: Vec<Chunk>,
}

/// Sub-faces whose prisms one task clips, in their order.
///
/// NOTE: the sub-faces' prisms are independent (each reads the grid, its own polygon and its
/// preimage), so runs of them are clipped in parallel on the pool the call runs in, each into
/// its own buffers, and the entries are put together in sub-face order: the same entries, in
/// the same order, whatever the thread count. In `cube-mobile-walls` on 50³ the prisms were
/// half of the correct's time, on one thread while the other waited. A task takes at most 4
/// runs, so that no thread waits long for the other's last one.
const CHUNK: usize = 128;

/// The entries, counters and scratch of one run of [`CHUNK`] sub-faces.
#[derive(Clone, Debug, Default)]
struct Chunk {
    entries: Vec<SubfaceSweptEntry>,
    n_pieces: usize,
    n_skipped: usize,
    prism: PrismScratch,
}

impl SubfaceSwept {
    /// Empty buffers.
    pub fn new() -> SubfaceSwept {
        SubfaceSwept::default()
    }

    /// Total signed swept volume in the domain, in m³ (2-D: m²).
    pub fn total(&self) -> f64 {
        self.entries.iter().map(|e| e.volume).sum()
    }

    /// Heap bytes of all buffers (capacities).
    pub fn memory_bytes(&self) -> usize {
        vec_bytes(&self.entries)
            + vec_bytes(&self.preimages)
            + vec_bytes(&self.chunks)
            + self
                .chunks
                .iter()
                .map(|c| vec_bytes(&c.entries) + c.prism.memory_bytes())
                .sum::<usize>()
    }

    /// Adds the swept volume of every entry to `acc[cell]` (`acc.len()` = number of cells).
    pub fn accumulate(&self, acc: &mut [f64]) {
        for e in &self.entries {
            acc[e.cell as usize] += e.volume;
        }
    }
}

/// Computes, for every sub-face `s` of `after_geometry` (= [`compute`](crate::cutcell::compute)
/// of `grid` and `after`), the signed volume of its prism `K_s` inside each cell, into `out`.
///
/// `K_s` is the closed polyhedron bounded by the polygon of `s` at `t^{n+1}` as oriented, its
/// preimage on the element at `t^n` in `before` (same connectivity, vertices moved), reversed, and
/// the lateral quads split along the canonical diagonal of
/// [`swept_volumes`](crate::cutcell::swept_volumes) (the same prism code). Entries are sorted by sub-face then cell,
/// zero volumes omitted; positive where the solid advances.
///
/// Identities (to round-off, for any motion): the sub-prisms of a closed surface telescope, so in
/// every cell `Σ entries = (Λ^{n+1} − Λ^n) V`, as for `swept_volumes`, provided the surface at
/// `t^{n+1}` lies inside the domain (sub-faces exist only there: a piece outside has no prism).
/// For a translation by `d`, `Σ_cells vol(K_s) = (d · n_s) area_s` for every sub-face, and the
/// sub-prisms of an element add up to its `swept_volumes` prism; for other motions they differ
/// from it by O(|motion|² · edge) per element edge (the lateral quads are split at more points),
/// cell totals unchanged.
///
/// Pure; no allocation once the buffers have grown; the prisms are clipped in parallel on the
/// rayon pool the call runs in, the same entries on any number of threads. Cost O(pieces): one more clip of the surface
/// at `t^{n+1}`, then per sub-face of `m` vertices `2 + 2m` polygons (2-D: 4 segments), each
/// clipped into the cells it crosses. On the bench sphere (`benches/cutcell.rs`, moved by 0.16
/// cell) that is 3.1 times the pieces of `swept_volumes` (32³: 110 828 against 35 964, of which
/// 6 516 for the second clip; 64³: 454 033 against 148 771), with 2.4 times the entries (test
/// `piece_counts_of_the_bench_sphere`).
pub fn subface_swept_volumes(
    grid: &Grid,
    before: &Surface,
    after: &Surface,
    after_geometry: &CutGeometry,
    out: &mut SubfaceSwept,
) {
    crate::cutcell::swept::check_pair(grid, before, after);
    out.n_pieces = lift_preimages(grid, before, after, after_geometry, &mut out.preimages);
    clip_prisms(grid, before, after, after_geometry, |_| true, out);
}

/// [`subface_swept_volumes`] of the sub-faces `keep` accepts only (a rank's share of a
/// decomposed grid, issue 40): the entries of those sub-faces, with their bits and in their order,
/// and the count of those skipped; the others have no entries and are not counted. The
/// preimages are lifted from the elements of the kept sub-faces only (each element clipped again
/// within the box of its kept sub-faces' cells, with the bits of the whole element's pieces
/// there, its pieces' vertices put at its kept sub-faces' by cell, `lift_preimages_of`), so the
/// cost is that of the kept sub-faces' prisms and of their pieces' second clip.
///
/// The entries of a partition of the sub-faces, put together in sub-face order (a stable sort by
/// sub-face), are those of [`subface_swept_volumes`] for a geometry computed from `after`
/// (fluid-node test `cutcell_block::the_prisms_of_a_partition_of_the_subfaces_are_the_whole_surfaces`).
pub fn subface_swept_volumes_of(
    grid: &Grid,
    before: &Surface,
    after: &Surface,
    after_geometry: &CutGeometry,
    keep: impl Fn(&SubFace) -> bool + Sync,
    out: &mut SubfaceSwept,
) {
    crate::cutcell::swept::check_pair(grid, before, after);
    out.n_pieces = lift_preimages_of(
        grid,
        before,
        after,
        after_geometry,
        &keep,
        &mut out.preimages,
    );
    clip_prisms(grid, before, after, after_geometry, keep, out);
}

/// The prisms of the sub-faces `keep` accepts, from the preimages in `out` (see
/// [`subface_swept_volumes`]); adds the pieces clipped to `out.n_pieces`.
fn clip_prisms(
    grid: &Grid,
    before: &Surface,
    after: &Surface,
    after_geometry: &CutGeometry,
    keep: impl Fn(&SubFace) -> bool + Sync,
    out: &mut SubfaceSwept,
) {
    out.entries.clear();
    out.n_skipped_subfaces = 0;
    let n_elements = after.n_elements();
    let subfaces = &after_geometry.subfaces;
    let n_chunks = subfaces.len().div_ceil(CHUNK);
    if out.chunks.len() < n_chunks {
        out.chunks.resize_with(n_chunks, Chunk::default);
    }
    let preimages = &out.preimages;
    out.chunks[..n_chunks]
        .par_iter_mut()
        .zip(subfaces.par_chunks(CHUNK))
        .enumerate()
        .with_max_len(4)
        .for_each(|(c, (chunk, run))| {
            chunk.entries.clear();
            chunk.n_pieces = 0;
            chunk.n_skipped = 0;
            for (k, subface) in run.iter().enumerate() {
                if !keep(subface) {
                    continue;
                }
                let s = c * CHUNK + k;
                let first = subface.first_vertex as usize;
                let range = first..first + subface.n_vertices as usize;
                let e = subface.element as usize;
                let (Some(top), Some(bottom)) = (
                    after_geometry.subface_vertices.get(range.clone()),
                    preimages.get(range),
                ) else {
                    chunk.n_skipped += 1;
                    continue;
                };
                let shape_ok = if grid.dim == 3 {
                    top.len() >= 3
                } else {
                    top.len() == 2
                };
                if e >= n_elements || !shape_ok || bottom.iter().flatten().any(|x| !x.is_finite()) {
                    chunk.n_skipped += 1;
                    continue;
                }
                let (top_normal, bottom_normal) =
                    match (grid.dim, after.element(e), before.element(e)) {
                        (3, Some(t1), Some(t0)) => (triangle_normal(&t1), triangle_normal(&t0)),
                        _ => ([0.0; 3], [0.0; 3]),
                    };
                let entries = &mut chunk.entries;
                chunk.n_pieces += prism_volumes(
                    grid,
                    top,
                    bottom,
                    top_normal,
                    bottom_normal,
                    &mut chunk.prism,
                    |cell, volume| {
                        entries.push(SubfaceSweptEntry {
                            subface: s as u32,
                            cell,
                            volume,
                        })
                    },
                );
            }
        });
    for chunk in &out.chunks[..n_chunks] {
        out.entries.extend_from_slice(&chunk.entries);
        out.n_pieces += chunk.n_pieces;
        out.n_skipped_subfaces += chunk.n_skipped;
    }
}

/// [`lift_preimages`] for the vertices of the sub-faces `keep` accepts (NaN elsewhere): only
/// their elements are clipped again, and each piece in the domain gives its vertices' preimages
/// to the kept sub-face of its element in its cell (the `n`-th piece of an element in a cell to
/// the `n`-th such sub-face in the order of their first vertices).
///
/// NOTE: by cell, not by the layout of `subface_vertices`: the whole grid's geometry put
/// together from the blocks' (`CutGeometry::assemble`) stores a sub-face's vertices where its
/// block's part put them, not where `compute` does (an element's pieces one after the other).
/// Within a cell an element's pieces are stored in their clip order by both, so the `n`-th
/// piece is the `n`-th sub-face; a vertex whose stored bits differ from the clip's is left NaN
/// (a geometry computed from another surface), and its sub-face skipped.
fn lift_preimages_of(
    grid: &Grid,
    before: &Surface,
    after: &Surface,
    geometry: &CutGeometry,
    keep: &(impl Fn(&SubFace) -> bool + Sync),
    preimages: &mut Vec<[f64; 3]>,
) -> usize {
    let stored = &geometry.subface_vertices;
    preimages.clear();
    preimages.resize(stored.len(), [f64::NAN; 3]);
    // `(element, cell, first vertex, vertices)` of the kept sub-faces.
    let mut targets: Vec<(u32, u32, u32, u32)> = (geometry.subfaces.iter())
        .filter(|s| keep(s) && (s.element as usize) < after.n_elements())
        .map(|s| (s.element, s.cell, s.first_vertex, s.n_vertices))
        .collect();
    targets.sort_unstable();
    let mut n_pieces = 0;
    let mut used = vec![false; targets.len()];
    let mut from = 0;
    while from < targets.len() {
        let e = targets[from].0;
        let to = from + targets[from..].partition_point(|t| t.0 == e);
        let (mine, taken) = (&targets[from..to], &mut used[from..to]);
        // The target of the piece being stored: its first vertex and count.
        let mut at: Option<(usize, usize)> = None;
        let window = Some(targets_window(grid, mine));
        let mut store = |cell, i, x: &[f64; 6]| {
            if i == 0 {
                let first = mine.partition_point(|t| t.1 < cell);
                at = (first..mine.len())
                    .take_while(|&k| mine[k].1 == cell)
                    .find(|&k| !taken[k])
                    .map(|k| {
                        taken[k] = true;
                        (mine[k].2 as usize, mine[k].3 as usize)
                    });
            }
            if let Some((first, n)) = at
                && i < n
            {
                put_preimage(stored, preimages, first + i, x);
            }
        };
        n_pieces += clip_lifted(grid, before, after, e as usize, window, &mut store);
        from = to;
    }
    n_pieces
}

/// The preimage of lifted vertex `x` (its position after, then before) at `at`, where the
/// stored vertex there is its position after (else left NaN: the walk has drifted).
fn put_preimage(stored: &[[f64; 3]], preimages: &mut [[f64; 3]], at: usize, x: &[f64; 6]) {
    if let Some(v) = stored.get(at)
        && v[..] == x[..3]
    {
        preimages[at] = [x[3], x[4], x[5]];
    }
}

/// The cells of `targets` (an element's kept sub-faces, as [`lift_preimages_of`] lists them):
/// their bounding box, as the slabs of [`clip_polygon_in`]'s window.
///
/// NOTE (issue 40 item 1): on a decomposed grid a rank keeps the sub-faces of its own cells,
/// and an element crossing the blocks was clipped whole on every rank that holds one of its
/// sub-faces: each of `opening-fracture-3d`'s side faces, two triangles across the whole box,
/// on both ranks of `1 × 1 × 2`.
fn targets_window(grid: &Grid, targets: &[(u32, u32, u32, u32)]) -> [(i32, i32); 3] {
    let mut window = [(i32::MAX, i32::MIN); 3];
    for t in targets {
        let ijk = grid.ijk(t.1 as usize);
        for (w, c) in window.iter_mut().zip(ijk) {
            *w = (w.0.min(c as i32), w.1.max(c as i32));
        }
    }
    window
}

/// Clips element `e` of `after` again (none when `compute` skips it), each vertex carrying its
/// position in `before` (NaN where `before` has none), and hands the vertices of its pieces in
/// the domain to `store` in the order `compute` stores them, each with its piece's cell and its
/// place in the piece. Returns the pieces clipped. `window`: in 3-D, only the pieces in these
/// slabs (`clip_polygon_in`: the same bits and order as the whole element's pieces there).
fn clip_lifted(
    grid: &Grid,
    before: &Surface,
    after: &Surface,
    e: usize,
    window: Option<[(i32, i32); 3]>,
    store: &mut impl FnMut(u32, usize, &[f64; 6]),
) -> usize {
    let Some(t1) = after.element(e) else {
        return 0;
    };
    let t0 = before.element(e).unwrap_or([[f64::NAN; 3]; 3]);
    let lift = |k: usize| [t1[k][0], t1[k][1], t1[k][2], t0[k][0], t0[k][1], t0[k][2]];
    let mut n_pieces = 0;
    if grid.dim == 3 {
        let poly: Polygon<6> = Polygon::from_slice(&[lift(0), lift(1), lift(2)]);
        let mut emit = |cell, piece: &Polygon<6>| {
            n_pieces += 1;
            if let Some(c) = domain_cell(grid, cell) {
                for (i, x) in piece.vertices().iter().enumerate() {
                    store(c, i, x);
                }
            }
        };
        match window {
            None => clip_polygon(grid, &poly, &mut emit),
            Some(w) => clip_polygon_in(grid, &poly, w, &mut emit),
        }
    } else {
        clip_segment(grid, lift(0), lift(1), &mut |cell, a, b| {
            n_pieces += 1;
            if let Some(c) = domain_cell(grid, cell) {
                store(c, 0, &a);
                store(c, 1, &b);
            }
        });
    }
    n_pieces
}

/// Fills `preimages` (aligned with `geometry.subface_vertices`) by clipping every element of
/// `after` again, its vertices carrying their position in `before` (NaN where `before` has none, or
/// where a clipped vertex differs from the stored one). Returns the number of pieces clipped.
fn lift_preimages(
    grid: &Grid,
    before: &Surface,
    after: &Surface,
    geometry: &CutGeometry,
    preimages: &mut Vec<[f64; 3]>,
) -> usize {
    let stored = &geometry.subface_vertices;
    preimages.clear();
    preimages.resize(stored.len(), [f64::NAN; 3]);
    let mut cursor = 0;
    let mut n_pieces = 0;
    let mut store = |_: u32, _: usize, x: &[f64; 6]| {
        put_preimage(stored, preimages, cursor, x);
        cursor += 1;
    };
    for e in 0..after.n_elements() {
        // NOTE: the same elements as `compute` skips, in the same order, so `cursor` follows
        // `subface_vertices`.
        n_pieces += clip_lifted(grid, before, after, e, None, &mut store);
    }
    n_pieces
}
