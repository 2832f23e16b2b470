//! [`compute_block`]: the geometry of one block of a decomposed grid and a halo around it, from
//! the elements that reach them only, with the bits of the whole grid's [`compute`] on the
//! block's cells (issue 40 item 1, step 1; docs/mpi.md).
//!
//! What each output depends on, and how the block gets the same bits:
//! - Pieces and sub-faces: an element's pieces depend on the element and the grid only
//!   ([`clip_elements`]); the block clips the elements whose cell range meets its window grown by
//!   one cell, so every cell of the window holds all its pieces, in the whole surface's order.
//! - Λ and λ along x: the x sweep runs along whole rows. x is never cut in 3-D
//!   (`protocol::decomp`), so the window's rows hold all their pieces; in 2-D, where x may be cut,
//!   the block also clips the elements of its band of rows (all x). Λ, λ_x and the sub-faces are
//!   then the whole grid's on every cell of the window.
//! - λ along a cut axis: the running sum along a row starts at the row's lower end, outside the
//!   window. The whole row's sweep snaps that sum at every uncut cell to the integer it is in
//!   exact arithmetic (the cell's winding number), which is the cell's Λ of the x sweep; so a
//!   row's sweep entered at its first uncut cell `u` in the window with Λ(u) gives the whole
//!   row's bits from `u` up to its last uncut cell in the window (`sweep_rows_from`). Where a
//!   block's own cells are not inside that stretch (a run of cut cells from beyond the window into
//!   the block: a wall along the axis), the row is swept whole from the elements that meet it.
//!   In the halo, λ along a cut axis is exact only within that stretch (a neighbour's block:
//!   the neighbour has it). [`crate::cutcell::BlockSweep`] (no halo) sweeps no row whole: it
//!   takes the running sums at the block's boundary faces from its neighbours along the axis.
//!
//! Assumption: the surface is closed, so that every running sum at an uncut cell is within
//! [`SNAP_TOLERANCE`] of its integer (an open surface shows in [`CutDiagnostics`] of the whole
//! grid's [`compute`], and gives other bits here).
//!
//! [`compute`]: crate::cutcell::compute
//! [`CutDiagnostics`]: crate::cutcell::CutDiagnostics

use std::collections::{HashMap, HashSet};

use crate::cutcell::clip::slab;
use crate::cutcell::geometry::{
    Clipped, SNAP_TOLERANCE, SubFace, clip_elements, face_area, other_axes, row_ijk,
};
use crate::cutcell::measure::Piece;
use crate::cutcell::surface::Surface;
use crate::cutcell::sweep::{Record, SweepSink, sort_records_in_rows, sweep_rows_from};
use crate::cutcell::written::WrittenRows;
use crate::grid::Grid;
use crate::memory::vec_bytes;

/// The cells `lo..hi` along each axis of a grid (global indices; inactive axes `0..1`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CellBox {
    /// First cell per axis.
    pub lo: [usize; 3],
    /// One past the last cell per axis.
    pub hi: [usize; 3],
}

impl CellBox {
    /// Every cell of `grid`.
    pub fn whole(grid: &Grid) -> CellBox {
        CellBox {
            lo: [0; 3],
            hi: grid.cells,
        }
    }

    /// The cells of rank `r` of the process grid `dims` (ranks x fastest, as
    /// `Slab::block_of_rank` cuts them).
    pub fn of_rank(grid: &Grid, dims: [usize; 3], r: usize) -> CellBox {
        let coords = crate::fv::slab::coords_of(dims, r);
        let mut block = CellBox::whole(grid);
        for a in 0..3 {
            let (first, own) = crate::fv::slab::share(grid.cells[a], dims[a], coords[a]);
            (block.lo[a], block.hi[a]) = (first, first + own);
        }
        block
    }

    /// Grown by `h` cells on each side of the active axes, within the grid.
    pub fn grown(&self, grid: &Grid, h: usize) -> CellBox {
        let mut b = *self;
        for a in 0..grid.dim {
            b.lo[a] = b.lo[a].saturating_sub(h);
            b.hi[a] = (b.hi[a] + h).min(grid.cells[a]);
        }
        b
    }

    /// Cells along `axis`.
    pub fn size(&self, axis: usize) -> usize {
        self.hi[axis] - self.lo[axis]
    }

    /// Number of cells.
    pub fn n_cells(&self) -> usize {
        (0..3).map(|a| self.size(a)).product()
    }

    /// Whether cell `ijk` lies in the box.
    pub fn contains(&self, ijk: [usize; 3]) -> bool {
        (0..3).all(|a| self.lo[a] <= ijk[a] && ijk[a] < self.hi[a])
    }

    /// Index of cell `ijk` (in the box) among the box's cells, x fastest.
    #[inline]
    pub fn index(&self, ijk: [usize; 3]) -> usize {
        let s = [self.size(0), self.size(1)];
        (ijk[0] - self.lo[0]) + s[0] * ((ijk[1] - self.lo[1]) + s[1] * (ijk[2] - self.lo[2]))
    }

    /// Whether the face of `axis` at `ijk` bounds a cell of the box (`ijk[axis]` in `lo..=hi`).
    pub fn has_face(&self, axis: usize, ijk: [usize; 3]) -> bool {
        (0..3).all(|a| {
            self.lo[a] <= ijk[a] && (ijk[a] < self.hi[a] || a == axis && ijk[a] == self.hi[a])
        })
    }

    /// Index of the face of `axis` at `ijk` among the box's faces of that axis, x fastest.
    #[inline]
    pub fn face_index(&self, axis: usize, ijk: [usize; 3]) -> usize {
        let mut s = [self.size(0), self.size(1)];
        if axis < 2 {
            s[axis] += 1;
        }
        (ijk[0] - self.lo[0]) + s[0] * ((ijk[1] - self.lo[1]) + s[1] * (ijk[2] - self.lo[2]))
    }

    /// Faces of `axis` bounding the box's cells (0 for an inactive axis of `grid`).
    pub fn n_faces(&self, grid: &Grid, axis: usize) -> usize {
        if axis >= grid.dim {
            return 0;
        }
        self.n_cells() / self.size(axis) * (self.size(axis) + 1)
    }
}

/// The cut-cell geometry of a block and its halo ([`compute_block`]).
#[derive(Clone, Debug, Default)]
pub struct BlockGeometry {
    /// The block (the cells a rank owns).
    pub block: CellBox,
    /// The block grown by the halo, within the grid: the cells the arrays hold.
    pub window: CellBox,
    /// Λ per cell of the window ([`CellBox::index`]).
    pub solid_fraction: Vec<f64>,
    /// λ per face of the window's cells and axis ([`CellBox::face_index`]); along the axes
    /// other than x empty for [`compute_block_cells`].
    pub face_fraction: [Vec<f64>; 3],
    /// Sub-faces in the window's cells (global cell indices), sorted by cell then element.
    pub subfaces: Vec<SubFace>,
    /// Vertices of the sub-face polygons, in m.
    pub subface_vertices: Vec<[f64; 3]>,
    /// Cells of the window holding at least one sub-face (global indices), ascending.
    pub cut_cells: Vec<u32>,
    /// Elements clipped (those that reach the window, and those of rows swept whole).
    pub clipped_elements: usize,
    /// Rows along a cut axis swept whole (a run of cut cells from beyond the window).
    pub whole_rows: usize,
    /// Pieces clipped (those of the window and one cell around it, and those of the elements
    /// of the rows swept whole): the work, as [`crate::cutcell::CutDiagnostics::n_pieces`]
    /// counts it for the whole grid.
    pub n_pieces: usize,
    /// The rows along x of Λ and λ that the computation wrote: every other row is zero.
    pub(crate) written: WrittenRows,
}

/// Values per row and rows of each array of `window`'s cells and faces, as [`WrittenRows`]
/// counts them (Λ, then λ along x, y and z).
fn written_counts(grid: &Grid, window: CellBox) -> ([usize; 4], [usize; 4]) {
    let row = std::array::from_fn(|a| match a {
        0 | 2 | 3 => window.size(0),
        _ => window.size(0) + 1,
    });
    let values = |a: usize| match a {
        0 => window.n_cells(),
        a => window.n_faces(grid, a - 1),
    };
    (row, std::array::from_fn(|a| values(a) / row[a].max(1)))
}

impl BlockGeometry {
    /// Makes this geometry (an earlier one of any window, or the default) the start of a
    /// computation of `block` and its `window`: Λ and λ along x zero on the window's cells and
    /// faces, λ along the other axes zero as well with `faces_across` and empty without, no
    /// sub-face, no row written. The buffers are kept: every value the earlier computation held
    /// lies in a row it recorded as written (or in an array with nothing recorded), and only
    /// those rows are zeroed, then each array takes its new length (issue 40 item 4: allocated
    /// and zeroed afresh, the loads' three trial geometries and the correct's block geometry of
    /// each step were 41 MB a rank at 100³ on 2 ranks).
    fn start(&mut self, grid: &Grid, block: CellBox, window: CellBox, faces_across: bool) {
        let [f0, f1, f2] = &mut self.face_fraction;
        self.written
            .zero_written([&mut self.solid_fraction, f0, f1, f2]);
        // (Grown exactly: a `resize` alone may double the capacity when the loads' window,
        // one cell wider, follows the correct's.)
        let zeroed = |v: &mut Vec<f64>, n: usize| {
            v.reserve_exact(n.saturating_sub(v.len()));
            v.resize(n, 0.0);
        };
        zeroed(&mut self.solid_fraction, window.n_cells());
        for (a, faces) in self.face_fraction.iter_mut().enumerate() {
            let n = if a == 0 || faces_across {
                window.n_faces(grid, a)
            } else {
                0
            };
            zeroed(faces, n);
        }
        let (row, rows) = written_counts(grid, window);
        self.written.reset(row, rows);
        self.block = block;
        self.window = window;
        self.subfaces.clear();
        self.subface_vertices.clear();
        self.cut_cells.clear();
        self.clipped_elements = 0;
        self.whole_rows = 0;
        self.n_pieces = 0;
    }

    /// Λ of cell `ijk` of the window.
    pub fn solid_fraction_at(&self, ijk: [usize; 3]) -> f64 {
        self.solid_fraction[self.window.index(ijk)]
    }

    /// λ of the face of `axis` at `ijk` of the window's faces.
    pub fn face_fraction_at(&self, axis: usize, ijk: [usize; 3]) -> f64 {
        self.face_fraction[axis][self.window.face_index(axis, ijk)]
    }

    /// Whether every value of Λ and λ outside the spans the computation recorded as written is
    /// zero, what [`crate::cutcell::block_part`] relies on to read only those spans.
    pub fn unwritten_values_are_zero(&self) -> bool {
        let w = &self.written;
        let arrays = std::iter::once(&self.solid_fraction).chain(&self.face_fraction);
        arrays.enumerate().all(|(a, values)| {
            (values.chunks(w.row_len(a).max(1)).enumerate()).all(|(r, row)| {
                let span = w.span(a, r);
                (row.iter().enumerate()).all(|(x, v)| span.contains(&x) || v.to_bits() == 0)
            })
        })
    }

    /// Heap bytes of Λ and λ (capacities).
    pub fn dense_bytes(&self) -> usize {
        vec_bytes(&self.solid_fraction) + self.face_fraction.iter().map(vec_bytes).sum::<usize>()
    }

    /// Heap bytes (capacities).
    pub fn memory_bytes(&self) -> usize {
        self.dense_bytes()
            + vec_bytes(&self.subfaces)
            + vec_bytes(&self.subface_vertices)
            + vec_bytes(&self.cut_cells)
    }
}

/// The geometry of `surface` on the cells of `block` grown by `halo` cells (within `grid`),
/// from the elements that reach them only: Λ, λ along x and the sub-faces are those of
/// [`crate::cutcell::compute`] on `grid`, bit for bit, on every cell of the window, and λ along
/// every axis on every face of the block's cells (module docs).
///
/// Pure. Cost: the elements that reach the window (in 2-D with x cut: its band of rows), plus
/// those of the rows swept whole.
pub fn compute_block(grid: &Grid, surface: &Surface, block: CellBox, halo: usize) -> BlockGeometry {
    compute_block_reusing(grid, surface, block, halo, BlockGeometry::default())
}

/// [`compute_block`] into the buffers of `reuse`, as [`compute_block_cells_reusing`] does.
pub fn compute_block_reusing(
    grid: &Grid,
    surface: &Surface,
    block: CellBox,
    halo: usize,
    reuse: BlockGeometry,
) -> BlockGeometry {
    block_geometry(grid, surface, block, halo, true, reuse)
}

/// [`compute_block`] without the sweeps along the axes other than x: Λ, λ along x and the
/// sub-faces only (exact on every cell of the window; λ along the other axes is left empty, not
/// allocated), what the loads need. No row is swept whole, so the cost is that of the window's
/// elements.
///
/// NOTE: the arrays of λ along y and z, zeroed and never written here, were half of the 16 MB
/// each of the loads' trial geometries allocated and zeroed at 100³ on 2 ranks.
pub fn compute_block_cells(
    grid: &Grid,
    surface: &Surface,
    block: CellBox,
    halo: usize,
) -> BlockGeometry {
    compute_block_cells_reusing(grid, surface, block, halo, BlockGeometry::default())
}

/// [`compute_block_cells`] into the buffers of `reuse`, an earlier block geometry of any block
/// and window (or the default): the same geometry, bit for bit, without allocating and zeroing
/// the window's arrays afresh (`BlockGeometry::start`).
pub fn compute_block_cells_reusing(
    grid: &Grid,
    surface: &Surface,
    block: CellBox,
    halo: usize,
    reuse: BlockGeometry,
) -> BlockGeometry {
    block_geometry(grid, surface, block, halo, false, reuse)
}

fn block_geometry(
    grid: &Grid,
    surface: &Surface,
    block: CellBox,
    halo: usize,
    cut_axes: bool,
    reuse: BlockGeometry,
) -> BlockGeometry {
    let (mut out, pieces, covered_runs) = block_cells(grid, surface, block, halo, cut_axes, reuse);
    if cut_axes {
        for axis in 1..grid.dim {
            sweep_cut_axis(grid, surface, axis, &pieces, &mut out);
        }
        fill_covered_faces(grid, &covered_runs, &mut out);
    }
    out
}

/// A run of covered cells of the x sweep, `(row, from, to, Λ)`.
pub(crate) type CoveredRun = (u64, i32, i32, f64);

/// The part of a block's geometry that needs no other block: the pieces clipped (of the
/// window's cells and one cell around them), Λ, λ along x and the sub-faces of the window, its
/// cut cells, and the covered runs of the x sweep; the arrays of λ along the other axes zero,
/// or empty without `faces_across`. Into the buffers of `reuse` (`BlockGeometry::start`).
pub(crate) fn block_cells(
    grid: &Grid,
    surface: &Surface,
    block: CellBox,
    halo: usize,
    faces_across: bool,
    reuse: BlockGeometry,
) -> (BlockGeometry, Vec<Piece>, Vec<CoveredRun>) {
    assert!(
        grid.dim == surface.dim,
        "grid dimension {} differs from surface dimension {}",
        grid.dim,
        surface.dim
    );
    surface.check();
    let window = block.grown(grid, halo);
    let mut out = reuse;
    out.start(grid, block, window, faces_across);
    // Rows of the x sweep: the window's and one more on each side (their covered cells give
    // the window's outermost faces).
    let rows = window.grown(grid, 1);
    let mut pieces = Vec::new();
    let mut piece_subface = Vec::new();
    let mut clipped = Clipped {
        pieces: &mut pieces,
        piece_subface: &mut piece_subface,
        subfaces: &mut out.subfaces,
        subface_vertices: &mut out.subface_vertices,
    };
    let dim = grid.dim;
    let mut n_kept = 0;
    let keep = |t: &[[f64; 3]; 3]| {
        let meets = (1..dim).all(|a| {
            let (lo, hi) = element_slabs(grid, a, &t[..dim]);
            hi >= rows.lo[a] as i32 - 1 && lo <= rows.hi[a] as i32
        });
        n_kept += usize::from(meets);
        meets
    };
    let sub = |cell: [i32; 3]| {
        let ijk = in_grid(grid, cell)?;
        window
            .contains(ijk)
            .then(|| grid.index(ijk[0], ijk[1], ijk[2]) as u32)
    };
    // Pieces of the rows' cells and of one slab beyond (the extended slabs at the domain's sides).
    let reach: [(i32, i32); 3] = std::array::from_fn(|a| match a {
        0 => (-1, grid.cells[0] as i32),
        _ if a < dim => (rows.lo[a] as i32 - 1, rows.hi[a] as i32),
        _ => (0, 0),
    });
    let all = 0..surface.n_elements();
    clip_elements(grid, surface, all, keep, Some(reach), sub, &mut clipped);
    out.clipped_elements = n_kept;
    out.n_pieces = pieces.len();
    let covered_runs = sweep_x(grid, &rows, &pieces, &piece_subface, &mut out);
    out.cut_cells.extend(out.subfaces.iter().map(|s| s.cell));
    out.cut_cells.dedup();
    (out, pieces, covered_runs)
}

/// Extended slabs `(lowest, highest)` along `axis` of an element's vertices.
fn element_slabs(grid: &Grid, axis: usize, vertices: &[[f64; 3]]) -> (i32, i32) {
    let lo = vertices
        .iter()
        .map(|v| v[axis])
        .fold(f64::INFINITY, f64::min);
    let hi = vertices
        .iter()
        .map(|v| v[axis])
        .fold(f64::NEG_INFINITY, f64::max);
    (slab(grid, axis, lo), slab(grid, axis, hi))
}

/// The cell of an extended cell index, if it lies in the grid.
fn in_grid(grid: &Grid, cell: [i32; 3]) -> Option<[usize; 3]> {
    let mut ijk = [0; 3];
    for a in 0..3 {
        if cell[a] < 0 || cell[a] >= grid.cells[a] as i32 {
            return None;
        }
        ijk[a] = cell[a] as usize;
    }
    Some(ijk)
}

/// The x sweep over the rows of `rows` (whole rows: all their pieces are clipped), writing Λ
/// and λ_x of the window's cells and ordering the sub-faces; returns the covered runs of the
/// window's x range, `(row, from, to, Λ)`.
fn sweep_x(
    grid: &Grid,
    rows: &CellBox,
    pieces: &[Piece],
    piece_subface: &[u32],
    out: &mut BlockGeometry,
) -> Vec<(u64, i32, i32, f64)> {
    let n = grid.cells[0] as i32;
    let mut records = Vec::new();
    for (order, piece) in pieces.iter().enumerate() {
        let cell = piece.cell;
        let inside = (1..3).all(|a| rows.lo[a] as i32 <= cell[a] && cell[a] < rows.hi[a] as i32);
        if inside && cell[0] <= n {
            records.push(Record {
                row: cell[1] as u64 + grid.cells[1] as u64 * cell[2] as u64,
                pos: cell[0],
                order: order as u32,
                flux: piece.area_vector[0],
                moment: piece.moment,
            });
        }
    }
    sort_records_in_rows(&mut records);
    let mut covered_runs = Vec::new();
    let mut sink = BlockSink {
        grid,
        window: out.window,
        axis: 0,
        volume: grid.cell_volume(),
        cells: &mut out.solid_fraction,
        faces: &mut out.face_fraction[0],
        written: &mut out.written,
        covered_runs: &mut covered_runs,
    };
    sweep_rows_from(
        &records,
        n,
        face_area(grid, 0),
        Some(SNAP_TOLERANCE),
        true,
        |_| (0, 0.0),
        &mut sink,
    );
    // Sub-faces in cell order (then element, then piece): the sorted records' order.
    let mut ordered = Vec::with_capacity(out.subfaces.len());
    for r in &records {
        let s = piece_subface[r.order as usize];
        if s != u32::MAX {
            ordered.push(out.subfaces[s as usize]);
        }
    }
    debug_assert_eq!(ordered.len(), out.subfaces.len());
    out.subfaces = ordered;
    covered_runs
}

/// λ along a cut axis `axis` (`1..dim`): the window's rows entered at their first uncut cell,
/// rows whose block cells lie beyond their exact stretch swept whole (module docs).
fn sweep_cut_axis(
    grid: &Grid,
    surface: &Surface,
    axis: usize,
    pieces: &[Piece],
    out: &mut BlockGeometry,
) {
    let n = grid.cells[axis] as i32;
    let (window, block) = (out.window, out.block);
    let (w0, w1) = (window.lo[axis] as i32, window.hi[axis] as i32);
    let (b, c) = other_axes(axis);
    let (first, last) = (
        if w0 == 0 { -1 } else { w0 },
        if w1 == n { n } else { w1 - 1 },
    );
    let row_of = |cell: [i32; 3]| cell[b] as u64 + grid.cells[b] as u64 * cell[c] as u64;
    let in_rows = |cell: [i32; 3], bx: &CellBox| {
        [b, c]
            .iter()
            .all(|&a| bx.lo[a] as i32 <= cell[a] && cell[a] < bx.hi[a] as i32)
    };
    let mut records: Vec<Record> = Vec::new();
    for (order, piece) in pieces.iter().enumerate() {
        let p = piece.cell[axis];
        if in_rows(piece.cell, &window) && first <= p && p <= last {
            records.push(record(
                row_of(piece.cell),
                p,
                order,
                piece.area_vector[axis],
            ));
        }
    }
    sort_records_in_rows(&mut records);
    // Per row: where its sweep is entered, or whether it is swept whole.
    let mut starts: HashMap<u64, (i32, f64)> = HashMap::new();
    let mut whole: HashSet<u64> = HashSet::new();
    let mut kept = Vec::with_capacity(records.len());
    for row_records in records.chunk_by(|x, y| x.row == y.row) {
        let row = row_records[0].row;
        let ijk = row_ijk(grid, axis, row, 0);
        let cut = |p: i32| row_records.binary_search_by_key(&p, |r| r.pos).is_ok();
        let u = (w0 > 0).then(|| (w0..w1).find(|&p| !cut(p))).flatten();
        let v = (w0..w1).rev().find(|&p| !cut(p));
        let low_ok = w0 == 0 || u.is_some_and(|u| u <= block.lo[axis] as i32);
        let high_ok = w1 == n || v.is_some_and(|v| v + 1 >= block.hi[axis] as i32);
        let owned = [b, c]
            .iter()
            .all(|&a| block.lo[a] <= ijk[a] && ijk[a] < block.hi[a]);
        if owned && !(low_ok && high_ok) {
            whole.insert(row);
            continue;
        }
        let from = match (w0 == 0, u) {
            (true, _) => -1,
            (false, Some(u)) => {
                let mut at = ijk;
                at[axis] = u as usize;
                starts.insert(row, (u, out.solid_fraction_at(at)));
                u
            }
            // Cut all through the window, not a row of the block: nothing exact to give.
            (false, None) => continue,
        };
        kept.extend(row_records.iter().filter(|r| r.pos >= from));
    }
    let area = face_area(grid, axis);
    let mut no_runs = Vec::new();
    let mut sink = BlockSink {
        grid,
        window,
        axis,
        volume: grid.cell_volume(),
        cells: &mut [],
        faces: &mut out.face_fraction[axis],
        written: &mut out.written,
        covered_runs: &mut no_runs,
    };
    let start = |row| starts.get(&row).copied().unwrap_or((0, 0.0));
    sweep_rows_from(
        &kept,
        n,
        area,
        Some(SNAP_TOLERANCE),
        false,
        start,
        &mut sink,
    );
    if !whole.is_empty() {
        sweep_whole_rows(grid, surface, axis, &whole, out);
    }
}

/// Sweeps the rows `whole` along `axis` from every element that meets them (clipped again),
/// as the whole grid's geometry does.
fn sweep_whole_rows(
    grid: &Grid,
    surface: &Surface,
    axis: usize,
    whole: &HashSet<u64>,
    out: &mut BlockGeometry,
) {
    let n = grid.cells[axis] as i32;
    let (b, c) = other_axes(axis);
    let row_of = |cell: [i32; 3]| cell[b] as u64 + grid.cells[b] as u64 * cell[c] as u64;
    // The rows swept whole: every element that meets one of them, clipped again.
    let mut row_pieces = Vec::new();
    let (mut subs, mut sub_vertices, mut piece_subface) = (Vec::new(), Vec::new(), Vec::new());
    let mut clipped = Clipped {
        pieces: &mut row_pieces,
        piece_subface: &mut piece_subface,
        subfaces: &mut subs,
        subface_vertices: &mut sub_vertices,
    };
    let dim = grid.dim;
    let mut n_whole = 0;
    let meets_row = |t: &[[f64; 3]; 3]| {
        let range = |a: usize| {
            let (lo, hi) = if a < dim {
                element_slabs(grid, a, &t[..dim])
            } else {
                (0, 0)
            };
            lo.max(0)..=hi.min(grid.cells[a] as i32 - 1)
        };
        let meets = range(b).any(|i| {
            range(c).any(|j| whole.contains(&(i as u64 + grid.cells[b] as u64 * j as u64)))
        });
        n_whole += usize::from(meets);
        meets
    };
    let all = 0..surface.n_elements();
    clip_elements(grid, surface, all, meets_row, None, |_| None, &mut clipped);
    let mut records = Vec::new();
    for (order, piece) in row_pieces.iter().enumerate() {
        let cell = piece.cell;
        let in_domain = [b, c]
            .iter()
            .all(|&a| 0 <= cell[a] && cell[a] < grid.cells[a] as i32);
        if in_domain && whole.contains(&row_of(cell)) {
            records.push(record(
                row_of(cell),
                cell[axis],
                order,
                piece.area_vector[axis],
            ));
        }
    }
    sort_records_in_rows(&mut records);
    let mut no_runs = Vec::new();
    let mut sink = BlockSink {
        grid,
        window: out.window,
        axis,
        volume: grid.cell_volume(),
        cells: &mut [],
        faces: &mut out.face_fraction[axis],
        written: &mut out.written,
        covered_runs: &mut no_runs,
    };
    sweep_rows_from(
        &records,
        n,
        face_area(grid, axis),
        Some(SNAP_TOLERANCE),
        false,
        |_| (0, 0.0),
        &mut sink,
    );
    out.clipped_elements += n_whole;
    out.n_pieces += row_pieces.len();
    out.whole_rows += whole.len();
}

/// A record of a sweep along an axis other than x (no moment).
pub(crate) fn record(row: u64, pos: i32, order: usize, flux: f64) -> Record {
    Record {
        row,
        pos,
        order: order as u32,
        flux,
        moment: 0.0,
    }
}

/// Sets the faces along y (and z) of the covered runs of the x sweep that bound the window's
/// cells, as [`crate::cutcell::compute`] does last.
pub(crate) fn fill_covered_faces(
    grid: &Grid,
    covered_runs: &[CoveredRun],
    out: &mut BlockGeometry,
) {
    let window = out.window;
    for &(row, from, to, value) in covered_runs {
        let ijk = row_ijk(grid, 0, row, from);
        let len = (to - from) as usize;
        for axis in 1..grid.dim {
            for side in 0..2 {
                let mut at = ijk;
                at[axis] += side;
                if window.has_face(axis, at) {
                    let f = window.face_index(axis, at);
                    out.face_fraction[axis][f..f + len].fill(value);
                    out.written.mark_range(1 + axis, f, len);
                }
            }
        }
    }
}

/// Writes one sweep into the window's arrays (what falls outside the window is dropped).
struct BlockSink<'a> {
    grid: &'a Grid,
    window: CellBox,
    axis: usize,
    volume: f64,
    cells: &'a mut [f64],
    faces: &'a mut [f64],
    written: &'a mut WrittenRows,
    covered_runs: &'a mut Vec<(u64, i32, i32, f64)>,
}

impl SweepSink for BlockSink<'_> {
    fn face(&mut self, row: u64, pos: i32, lambda: f64) {
        let ijk = row_ijk(self.grid, self.axis, row, pos);
        if self.window.has_face(self.axis, ijk) {
            let f = self.window.face_index(self.axis, ijk);
            self.faces[f] = lambda;
            self.written.mark(1 + self.axis, f);
        }
    }

    fn cell(&mut self, row: u64, pos: i32, moment: f64, lambda_top: f64) {
        if self.axis == 0 {
            let ijk = row_ijk(self.grid, 0, row, pos);
            if self.window.contains(ijk) {
                let c = self.window.index(ijk);
                self.cells[c] = moment / self.volume + lambda_top;
                self.written.mark(0, c);
            }
        }
    }

    fn run(&mut self, row: u64, from: i32, to: i32, lambda: f64) {
        // Only the x sweep fills runs (cells `from..to` and their lower faces); cut to the
        // window's cells and faces (its last face is the lower face of the cell beyond it).
        let (lo, hi) = (self.window.lo[0] as i32, self.window.hi[0] as i32);
        let (from, to_faces, to) = (from.max(lo), to.min(hi + 1), to.min(hi));
        if from >= to_faces {
            return;
        }
        let ijk = row_ijk(self.grid, 0, row, from);
        if self.window.has_face(0, ijk) {
            let face = self.window.face_index(0, ijk);
            self.faces[face..face + (to_faces - from) as usize].fill(lambda);
            self.written.mark_range(1, face, (to_faces - from) as usize);
        }
        if from >= to {
            return;
        }
        if self.window.contains(ijk) {
            let cell = self.window.index(ijk);
            self.cells[cell..cell + (to - from) as usize].fill(lambda);
            self.written.mark_range(0, cell, (to - from) as usize);
        }
        self.covered_runs.push((row, from, to, lambda));
    }
}
