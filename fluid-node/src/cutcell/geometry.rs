//! [`compute`]: solid volume fractions Λ, face fractions λ and clipped sub-faces of a surface.

use rayon::prelude::*;

use crate::cutcell::clip::{Polygon, clip_polygon, clip_polygon_in, clip_segment};
use crate::cutcell::measure::{
    Piece, column_moment, polygon_measures, segment_measures, triangle_normal,
};
use crate::cutcell::surface::Surface;
use crate::cutcell::sweep::{Record, SweepSink, sort_records_by_rows, sweep_rows};
use crate::grid::Grid;
use crate::memory::vec_bytes;

/// Tolerance under which the running face fraction entering an uncut cell is snapped to 0 or 1.
pub const SNAP_TOLERANCE: f64 = 1e-9;

/// The part of one surface element inside one grid cell.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SubFace {
    /// Linear cell index ([`Grid::index`]).
    pub cell: u32,
    /// Element (triangle or segment) it comes from.
    pub element: u32,
    /// Particle of that element.
    pub particle: u32,
    /// Area, in m² (2-D: length, in m).
    pub area: f64,
    /// Unit normal out of the solid (the element's; zero for a degenerate element).
    pub normal: [f64; 3],
    /// Area centroid, in m (third coordinate 0 in 2-D).
    pub centroid: [f64; 3],
    /// First vertex in [`CutGeometry::subface_vertices`].
    pub first_vertex: u32,
    /// Number of vertices (2 for a 2-D segment).
    pub n_vertices: u32,
}

/// Numerical health of one [`compute`] call (reported as data, never a panic).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CutDiagnostics {
    /// Pieces produced by clipping (inside and outside the domain).
    pub n_pieces: usize,
    /// Elements skipped: an index out of range or a non-finite coordinate.
    pub n_skipped_elements: usize,
    /// Largest distance of a face fraction entering an uncut cell from 0 or 1 beyond
    /// [`SNAP_TOLERANCE`], or largest |λ| left beyond the last piece of a row (both 0 up to
    /// round-off for a closed surface; of order 1 for an open one).
    pub max_uncut_defect: f64,
}

/// Cut-cell geometry of a surface on a grid; buffers are reused between calls.
#[derive(Clone, Debug, Default)]
pub struct CutGeometry {
    /// Solid volume fraction Λ per cell [-], in `[0, 1]`, indexed like [`Grid::index`].
    pub solid_fraction: Vec<f64>,
    /// Solid area fraction λ per face and axis [-], in `[0, 1]`. Axis `a` holds the faces normal to
    /// `e_a`: `cells` with `cells[a] + 1` along `a`, x fastest ([`face_index`]); empty for an
    /// inactive axis.
    pub face_fraction: [Vec<f64>; 3],
    /// Sub-faces of the elements inside the domain, sorted by cell then element.
    pub subfaces: Vec<SubFace>,
    /// Vertices of the sub-face polygons, in m (segment endpoints in 2-D).
    pub subface_vertices: Vec<[f64; 3]>,
    /// Cells holding at least one sub-face, ascending.
    pub cut_cells: Vec<u32>,
    /// Diagnostics of the last call.
    pub diagnostics: CutDiagnostics,
    shape: (usize, [usize; 3]),
    pieces: Vec<Piece>,
    records: Vec<Record>,
    /// Written ranges `(first, len)` of `solid_fraction`, for the sparse reset.
    pub(super) written_cells: Vec<(u32, u32)>,
    /// Written ranges `(first, len)` of each `face_fraction`.
    pub(super) written_faces: [Vec<(u32, u32)>; 3],
    /// Covered runs of the x sweep `(row, from, to, λ)`, whose y and z faces are filled last.
    covered_runs: Vec<(u64, i32, i32, f64)>,
    /// Scratch of the counting sort.
    scratch: Vec<Record>,
    /// Row counts of the counting sort.
    counts: Vec<u32>,
    /// Sub-face of each piece (`u32::MAX` outside the domain).
    piece_subface: Vec<u32>,
    /// Scratch of the sub-face ordering.
    subface_scratch: Vec<SubFace>,
    /// One per [`CLIP_CHUNK`] elements: their pieces and sub-faces, clipped apart.
    clip_chunks: Vec<ClipChunk>,
    /// The records, scratch and row counts of the z sweep (run beside the y sweep's).
    records_z: Vec<Record>,
    scratch_z: Vec<Record>,
    counts_z: Vec<u32>,
}

/// Elements one task of [`clip_surface`] clips, in their order.
///
/// NOTE: an element's pieces depend on the element and the grid only, so runs of elements
/// are clipped in parallel on the pool the call runs in, each into its own buffers, and put
/// together in element order, their sub-face and vertex indices moved on by what came
/// before: the same pieces and sub-faces, in the same order, on any number of threads. The
/// clip was half of `compute`, which the loads of the semi-implicit scheme run on one thread
/// (`clamped-beam-3d`: 9 % of the fluid node's main thread). A task takes at most 2 runs, so
/// that no thread waits long for the other's last one.
const CLIP_CHUNK: usize = 256;

/// The pieces and sub-faces of one run of [`CLIP_CHUNK`] elements (indices within the run).
#[derive(Clone, Debug, Default)]
struct ClipChunk {
    pieces: Vec<Piece>,
    piece_subface: Vec<u32>,
    subfaces: Vec<SubFace>,
    subface_vertices: Vec<[f64; 3]>,
    skipped: usize,
}

/// Linear index of the face of axis `axis` at `ijk` (`ijk[axis]` in `0..=cells[axis]`).
#[inline]
pub fn face_index(grid: &Grid, axis: usize, ijk: [usize; 3]) -> usize {
    let mut n = grid.cells;
    n[axis] += 1;
    ijk[0] + n[0] * (ijk[1] + n[1] * ijk[2])
}

/// Number of faces normal to `axis` (0 for an inactive axis).
pub fn n_faces(grid: &Grid, axis: usize) -> usize {
    if axis >= grid.dim {
        return 0;
    }
    let mut n = grid.cells;
    n[axis] += 1;
    n[0] * n[1] * n[2]
}

impl CutGeometry {
    /// Empty buffers.
    pub fn new() -> CutGeometry {
        CutGeometry::default()
    }

    /// Solid volume in the domain `Σ Λ V` \[m³\] (2-D: \[m²\]).
    pub fn solid_volume(&self, grid: &Grid) -> f64 {
        let mut acc = 0.0;
        for &(first, len) in &self.written_cells {
            let first = first as usize;
            acc += self.solid_fraction[first..first + len as usize]
                .iter()
                .sum::<f64>();
        }
        acc * grid.cell_volume()
    }

    /// Wet area in the domain `Σ sub-face areas` \[m²\] (2-D: \[m\]).
    pub fn wet_area(&self) -> f64 {
        self.subfaces.iter().map(|s| s.area).sum()
    }

    /// Heap bytes of the dense outputs: Λ per cell and λ per face of each axis (capacities).
    pub fn dense_bytes(&self) -> usize {
        vec_bytes(&self.solid_fraction) + self.face_fraction.iter().map(vec_bytes).sum::<usize>()
    }

    /// Heap bytes of all buffers (capacities): [`CutGeometry::dense_bytes`] plus the sub-faces,
    /// cut-cell list and clipping scratch, which grow with the surface.
    pub fn memory_bytes(&self) -> usize {
        self.dense_bytes()
            + vec_bytes(&self.subfaces)
            + vec_bytes(&self.subface_vertices)
            + vec_bytes(&self.cut_cells)
            + vec_bytes(&self.pieces)
            + vec_bytes(&self.records)
            + vec_bytes(&self.written_cells)
            + self.written_faces.iter().map(vec_bytes).sum::<usize>()
            + vec_bytes(&self.covered_runs)
            + vec_bytes(&self.scratch)
            + vec_bytes(&self.counts)
            + vec_bytes(&self.piece_subface)
            + vec_bytes(&self.subface_scratch)
            + vec_bytes(&self.records_z)
            + vec_bytes(&self.scratch_z)
            + vec_bytes(&self.counts_z)
            + vec_bytes(&self.clip_chunks)
            + (self.clip_chunks.iter())
                .map(|c| {
                    vec_bytes(&c.pieces)
                        + vec_bytes(&c.piece_subface)
                        + vec_bytes(&c.subfaces)
                        + vec_bytes(&c.subface_vertices)
                })
                .sum::<usize>()
    }

    pub(super) fn reset(&mut self, grid: &Grid) {
        let shape = (grid.dim, grid.cells);
        if self.shape != shape || self.solid_fraction.len() != grid.n_cells() {
            self.shape = shape;
            self.solid_fraction.clear();
            self.solid_fraction.resize(grid.n_cells(), 0.0);
            for axis in 0..3 {
                self.face_fraction[axis].clear();
                self.face_fraction[axis].resize(n_faces(grid, axis), 0.0);
                self.written_faces[axis].clear();
            }
            self.written_cells.clear();
        } else {
            // NOTE: only the entries written last time are zeroed, so a call costs O(cut cells +
            // covered cells), not O(grid).
            for &(first, len) in &self.written_cells {
                let first = first as usize;
                self.solid_fraction[first..first + len as usize].fill(0.0);
            }
            self.written_cells.clear();
            for axis in 0..3 {
                for &(first, len) in &self.written_faces[axis] {
                    let first = first as usize;
                    self.face_fraction[axis][first..first + len as usize].fill(0.0);
                }
                self.written_faces[axis].clear();
            }
        }
        self.subfaces.clear();
        self.subface_vertices.clear();
        self.cut_cells.clear();
        self.pieces.clear();
        self.piece_subface.clear();
        self.covered_runs.clear();
        self.diagnostics = CutDiagnostics::default();
    }
}

/// Computes Λ, λ and the sub-faces of `surface` on `grid` into `out` (buffers reused).
///
/// Pure. Cost: O(pieces · log pieces + covered cells), independent of the grid size otherwise.
pub fn compute(grid: &Grid, surface: &Surface, out: &mut CutGeometry) {
    assert!(
        grid.dim == surface.dim,
        "grid dimension {} differs from surface dimension {}",
        grid.dim,
        surface.dim
    );
    surface.check();
    out.reset(grid);
    clip_surface(grid, surface, out);
    out.diagnostics.n_pieces = out.pieces.len();
    // NOTE: x first: its sweep fills Λ and λ_x of the covered runs contiguously and lists them;
    // the y and z sweeps then report only the faces of cut cells, and the faces of covered cells
    // are filled from the listed x runs, again contiguously.
    sweep_axis(grid, 0, out);
    order_subfaces(grid, out);
    if grid.dim > 1 {
        sweep_across(grid, out);
    }
    fill_covered_faces(grid, out);
    // NOTE: the key is unique (first_vertex), so the unstable, allocation-free sort is
    // deterministic.
    out.cut_cells.extend(out.subfaces.iter().map(|s| s.cell));
    out.cut_cells.dedup();
}

/// Clips every element; fills `out.pieces` (all) and `out.subfaces` (inside the domain). Runs
/// of [`CLIP_CHUNK`] elements in parallel on the pool the call runs in (the same bits on any
/// number of threads).
fn clip_surface(grid: &Grid, surface: &Surface, out: &mut CutGeometry) {
    let n = surface.n_elements();
    let n_chunks = n.div_ceil(CLIP_CHUNK);
    if out.clip_chunks.len() < n_chunks {
        out.clip_chunks.resize_with(n_chunks, ClipChunk::default);
    }
    out.clip_chunks[..n_chunks]
        .par_iter_mut()
        .enumerate()
        .with_max_len(2)
        .for_each(|(c, chunk)| {
            chunk.pieces.clear();
            chunk.piece_subface.clear();
            chunk.subfaces.clear();
            chunk.subface_vertices.clear();
            let mut clipped = Clipped {
                pieces: &mut chunk.pieces,
                piece_subface: &mut chunk.piece_subface,
                subfaces: &mut chunk.subfaces,
                subface_vertices: &mut chunk.subface_vertices,
            };
            let elements = c * CLIP_CHUNK..n.min((c + 1) * CLIP_CHUNK);
            chunk.skipped = clip_elements(
                grid,
                surface,
                elements,
                |_| true,
                None,
                |cell| domain_cell(grid, cell),
                &mut clipped,
            );
        });
    for chunk in &out.clip_chunks[..n_chunks] {
        let first_subface = out.subfaces.len() as u32;
        let first_vertex = out.subface_vertices.len() as u32;
        out.pieces.extend_from_slice(&chunk.pieces);
        out.piece_subface.extend(
            (chunk.piece_subface.iter())
                .map(|&s| if s == u32::MAX { s } else { s + first_subface }),
        );
        out.subfaces.extend(chunk.subfaces.iter().map(|s| SubFace {
            first_vertex: s.first_vertex + first_vertex,
            ..*s
        }));
        out.subface_vertices
            .extend_from_slice(&chunk.subface_vertices);
        out.diagnostics.n_skipped_elements += chunk.skipped;
    }
}

/// Where [`clip_elements`] puts the pieces and sub-faces.
pub(crate) struct Clipped<'a> {
    pub(crate) pieces: &'a mut Vec<Piece>,
    /// Sub-face of each piece (`u32::MAX` for a piece without one).
    pub(crate) piece_subface: &'a mut Vec<u32>,
    pub(crate) subfaces: &'a mut Vec<SubFace>,
    pub(crate) subface_vertices: &'a mut Vec<[f64; 3]>,
}

/// Clips the elements of `elements` that `keep` accepts (given their vertices), in element
/// order, into `out`; a piece gets a sub-face where `sub` gives its extended cell a linear index. With a `window`
/// (first and last extended slab per axis), 3-D elements give only their pieces in it
/// ([`clip_polygon_in`]; 2-D segments are clipped whole). Returns the number of elements skipped
/// (an index out of range or a non-finite coordinate).
///
/// NOTE: an element's pieces depend on the element and the grid only, so any subset of the
/// elements gives the bits of the whole surface's pieces for those elements, in the same order.
pub(crate) fn clip_elements(
    grid: &Grid,
    surface: &Surface,
    elements: std::ops::Range<usize>,
    mut keep: impl FnMut(&[[f64; 3]; 3]) -> bool,
    window: Option<[(i32, i32); 3]>,
    sub: impl Fn([i32; 3]) -> Option<u32>,
    out: &mut Clipped,
) -> usize {
    let Clipped {
        pieces,
        piece_subface,
        subfaces,
        subface_vertices,
    } = out;
    let mut skipped = 0;
    for e in elements {
        let Some(t) = surface.element(e) else {
            skipped += 1;
            continue;
        };
        if !keep(&t) {
            continue;
        }
        let particle = surface.particle(e);
        if surface.dim == 3 {
            let normal = triangle_normal(&t);
            let poly = Polygon::from_slice(&t);
            let mut emit = |cell: [i32; 3], piece: &Polygon| {
                let (area_vector, area, centroid) = polygon_measures(piece, normal);
                pieces.push(Piece {
                    cell,
                    area_vector,
                    moment: column_moment(grid, cell, area_vector, centroid),
                });
                let in_domain = sub(cell);
                piece_subface.push(in_domain.map_or(u32::MAX, |_| subfaces.len() as u32));
                if let Some(cell_idx) = in_domain {
                    subfaces.push(SubFace {
                        cell: cell_idx,
                        element: e as u32,
                        particle,
                        area,
                        normal,
                        centroid,
                        first_vertex: subface_vertices.len() as u32,
                        n_vertices: piece.n as u32,
                    });
                    subface_vertices.extend_from_slice(piece.vertices());
                }
            };
            match window {
                Some(w) => clip_polygon_in(grid, &poly, w, &mut emit),
                None => clip_polygon(grid, &poly, &mut emit),
            }
        } else {
            let (full, length, _) = segment_measures(t[0], t[1]);
            let normal = if length > 0.0 {
                [full[0] / length, full[1] / length, 0.0]
            } else {
                [0.0; 3]
            };
            clip_segment(grid, t[0], t[1], &mut |cell, a, b| {
                let (area_vector, area, centroid) = segment_measures(a, b);
                pieces.push(Piece {
                    cell,
                    area_vector,
                    moment: column_moment(grid, cell, area_vector, centroid),
                });
                let in_domain = sub(cell);
                piece_subface.push(in_domain.map_or(u32::MAX, |_| subfaces.len() as u32));
                if let Some(cell_idx) = in_domain {
                    subfaces.push(SubFace {
                        cell: cell_idx,
                        element: e as u32,
                        particle,
                        area,
                        normal,
                        centroid,
                        first_vertex: subface_vertices.len() as u32,
                        n_vertices: 2,
                    });
                    subface_vertices.push(a);
                    subface_vertices.push(b);
                }
            });
        }
    }
    skipped
}

/// Puts the sub-faces in cell order (then element, then piece order) by walking the sorted
/// records of the x sweep, whose (row, position) order is the cell order: O(pieces), no sort.
fn order_subfaces(grid: &Grid, out: &mut CutGeometry) {
    let n = grid.cells[0] as i32;
    out.subface_scratch.clear();
    for r in &out.records {
        if r.pos >= 0 && r.pos < n {
            let s = out.piece_subface[r.order as usize];
            if s != u32::MAX {
                out.subface_scratch.push(out.subfaces[s as usize]);
            }
        }
    }
    debug_assert_eq!(out.subface_scratch.len(), out.subfaces.len());
    std::mem::swap(&mut out.subfaces, &mut out.subface_scratch);
}

/// Linear index of an extended cell if it lies in the domain.
#[inline]
pub(crate) fn domain_cell(grid: &Grid, cell: [i32; 3]) -> Option<u32> {
    for (&c, &n) in cell.iter().zip(&grid.cells) {
        if c < 0 || c >= n as i32 {
            return None;
        }
    }
    Some(grid.index(cell[0] as usize, cell[1] as usize, cell[2] as usize) as u32)
}

/// The two axes other than `axis`, ascending.
#[inline]
pub(crate) fn other_axes(axis: usize) -> (usize, usize) {
    match axis {
        0 => (1, 2),
        1 => (0, 2),
        _ => (0, 1),
    }
}

/// Builds the (unsorted) sweep records of axis `axis` from `pieces` (rows in the domain, positions
/// `-1..=n`).
pub(crate) fn build_records(grid: &Grid, axis: usize, pieces: &[Piece], records: &mut Vec<Record>) {
    records.clear();
    let (b, c) = other_axes(axis);
    let n = grid.cells[axis] as i32;
    for (order, piece) in pieces.iter().enumerate() {
        let cell = piece.cell;
        if cell[axis] > n
            || cell[b] < 0
            || cell[b] >= grid.cells[b] as i32
            || cell[c] < 0
            || cell[c] >= grid.cells[c] as i32
        {
            continue;
        }
        records.push(Record {
            row: cell[b] as u64 + grid.cells[b] as u64 * cell[c] as u64,
            pos: cell[axis],
            order: order as u32,
            flux: piece.area_vector[axis],
            moment: if axis == 0 { piece.moment } else { 0.0 },
        });
    }
}

/// Cell `(row, pos)` of a row along `axis` as `[i, j, k]`.
#[inline]
pub(crate) fn row_ijk(grid: &Grid, axis: usize, row: u64, pos: i32) -> [usize; 3] {
    let (b, c) = other_axes(axis);
    let mut ijk = [0; 3];
    ijk[axis] = pos as usize;
    ijk[b] = (row % grid.cells[b] as u64) as usize;
    ijk[c] = (row / grid.cells[b] as u64) as usize;
    ijk
}

/// Face area normal to `axis` [m²] (2-D: length [m]).
#[inline]
pub(crate) fn face_area(grid: &Grid, axis: usize) -> f64 {
    let (b, c) = other_axes(axis);
    grid.dx[b] * grid.dx[c]
}

/// Writes one axis sweep into the dense arrays, recording the written ranges.
struct GeometrySink<'a> {
    grid: &'a Grid,
    axis: usize,
    volume: f64,
    cells: &'a mut [f64],
    faces: &'a mut [f64],
    cells_written: &'a mut Vec<(u32, u32)>,
    faces_written: &'a mut Vec<(u32, u32)>,
    covered_runs: &'a mut Vec<(u64, i32, i32, f64)>,
}

impl SweepSink for GeometrySink<'_> {
    fn face(&mut self, row: u64, pos: i32, lambda: f64) {
        let f = face_index(
            self.grid,
            self.axis,
            row_ijk(self.grid, self.axis, row, pos),
        );
        // NOTE: not clamped: outside [0, 1] by round-off for one body, by the overlap where two
        // bodies overlap (an open surface shows in `max_uncut_defect`).
        self.faces[f] = lambda;
        self.faces_written.push((f as u32, 1));
    }

    fn cell(&mut self, row: u64, pos: i32, moment: f64, lambda_top: f64) {
        if self.axis == 0 {
            let ijk = row_ijk(self.grid, 0, row, pos);
            let cell = self.grid.index(ijk[0], ijk[1], ijk[2]);
            self.cells[cell] = moment / self.volume + lambda_top;
            self.cells_written.push((cell as u32, 1));
        }
    }

    fn run(&mut self, row: u64, from: i32, to: i32, lambda: f64) {
        // Only the x sweep fills runs: its cells and x faces are contiguous in memory.
        let ijk = row_ijk(self.grid, 0, row, from);
        let cell = self.grid.index(ijk[0], ijk[1], ijk[2]);
        let face = face_index(self.grid, 0, ijk);
        let len = (to - from) as usize;
        let value = lambda;
        self.cells[cell..cell + len].fill(value);
        self.faces[face..face + len].fill(value);
        self.cells_written.push((cell as u32, len as u32));
        self.faces_written.push((face as u32, len as u32));
        self.covered_runs.push((row, from, to, value));
    }
}

fn sweep_axis(grid: &Grid, axis: usize, out: &mut CutGeometry) {
    let CutGeometry {
        solid_fraction,
        face_fraction,
        diagnostics,
        pieces,
        records,
        written_cells,
        written_faces,
        covered_runs,
        scratch,
        counts,
        ..
    } = out;
    let sort = SortBuffers {
        records,
        scratch,
        counts,
    };
    let sink = GeometrySink {
        grid,
        axis,
        volume: grid.cell_volume(),
        cells: solid_fraction,
        faces: &mut face_fraction[axis],
        cells_written: written_cells,
        faces_written: &mut written_faces[axis],
        covered_runs,
    };
    let defect = sweep_pieces(pieces, sort, sink);
    diagnostics.max_uncut_defect = diagnostics.max_uncut_defect.max(defect);
}

/// The sweeps along y and z after the one along x, in parallel on the pool the call runs in.
///
/// NOTE: after the x sweep (which fills Λ and the covered runs) a sweep along y or z writes
/// only its own axis's face fractions and written ranges, from the pieces and buffers of its
/// own: the two run at once, and their defects are taken in axis order as one thread took
/// them. The same bits on any number of threads.
fn sweep_across(grid: &Grid, out: &mut CutGeometry) {
    let CutGeometry {
        face_fraction: [_, faces_y, faces_z],
        written_faces: [_, written_y, written_z],
        diagnostics,
        pieces,
        records,
        scratch,
        counts,
        records_z,
        scratch_z,
        counts_z,
        ..
    } = out;
    let pieces = &*pieces;
    let mut y = move || {
        let sort = SortBuffers {
            records,
            scratch,
            counts,
        };
        sweep_faces(grid, 1, pieces, sort, faces_y, written_y)
    };
    let (defect_y, defect_z) = if grid.dim == 3 {
        let z = move || {
            let sort = SortBuffers {
                records: records_z,
                scratch: scratch_z,
                counts: counts_z,
            };
            sweep_faces(grid, 2, pieces, sort, faces_z, written_z)
        };
        let (dy, dz) = rayon::join(y, z);
        (dy, Some(dz))
    } else {
        (y(), None)
    };
    diagnostics.max_uncut_defect = diagnostics.max_uncut_defect.max(defect_y);
    if let Some(d) = defect_z {
        diagnostics.max_uncut_defect = diagnostics.max_uncut_defect.max(d);
    }
}

/// The sweep of `pieces` along `axis` (y or z: faces only, see [`sweep_across`]) into `faces`
/// and `faces_written`; returns the largest uncut defect.
fn sweep_faces(
    grid: &Grid,
    axis: usize,
    pieces: &[Piece],
    sort: SortBuffers,
    faces: &mut [f64],
    faces_written: &mut Vec<(u32, u32)>,
) -> f64 {
    // (Only the x sweep writes cells and runs: these stay empty.)
    let (mut cells_written, mut covered_runs) = (Vec::new(), Vec::new());
    let sink = GeometrySink {
        grid,
        axis,
        volume: grid.cell_volume(),
        cells: &mut [],
        faces,
        cells_written: &mut cells_written,
        faces_written,
        covered_runs: &mut covered_runs,
    };
    let defect = sweep_pieces(pieces, sort, sink);
    debug_assert!(cells_written.is_empty() && covered_runs.is_empty());
    defect
}

/// The buffers of one sweep's sort of the pieces' records.
struct SortBuffers<'a> {
    records: &'a mut Vec<Record>,
    scratch: &'a mut Vec<Record>,
    counts: &'a mut Vec<u32>,
}

/// Sorts the records of `pieces` along `sink.axis` by rows and sweeps them into `sink`;
/// returns the largest uncut defect.
fn sweep_pieces(pieces: &[Piece], sort: SortBuffers, mut sink: GeometrySink) -> f64 {
    let (grid, axis) = (sink.grid, sink.axis);
    build_records(grid, axis, pieces, sort.records);
    let (b, c) = other_axes(axis);
    sort_records_by_rows(
        sort.records,
        sort.scratch,
        sort.counts,
        grid.cells[b] * grid.cells[c],
    );
    sweep_rows(
        sort.records,
        grid.cells[axis] as i32,
        face_area(grid, axis),
        Some(SNAP_TOLERANCE),
        axis == 0,
        &mut sink,
    )
}

/// Sets the y (and z) faces of the covered runs of the x sweep: both faces of every uncut cell
/// carry its fraction (the sweeps of those axes reported only the faces of cut cells).
fn fill_covered_faces(grid: &Grid, out: &mut CutGeometry) {
    let CutGeometry {
        face_fraction,
        written_faces,
        covered_runs,
        ..
    } = out;
    for &(row, from, to, value) in covered_runs.iter() {
        let ijk = row_ijk(grid, 0, row, from);
        let len = (to - from) as usize;
        for axis in 1..grid.dim {
            for side in 0..2 {
                let mut at = ijk;
                at[axis] += side;
                let f = face_index(grid, axis, at);
                face_fraction[axis][f..f + len].fill(value);
                written_faces[axis].push((f as u32, len as u32));
            }
        }
    }
}
