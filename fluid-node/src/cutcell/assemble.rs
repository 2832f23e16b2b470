//! The whole grid's geometry put together from the blocks of a decomposed grid (issue 40 item 1,
//! step 4 (a); docs/mpi.md): each block gives what [`crate::cutcell::compute_block`] computes
//! exactly on its own cells ([`block_part`]: Λ of its cells, λ of their faces along every axis,
//! their sub-faces), and [`CutGeometry::assemble`] writes every block's share into the whole
//! grid's arrays, so that no rank clips the whole surface.
//!
//! How the bits stay those of [`crate::cutcell::compute`]:
//! - Λ and λ: every cell belongs to one block, and every face to one block (the low face of each
//!   of its cells along the axis, and the grid's last face to the last block); `compute_block`
//!   gives them the whole grid's bits on its own cells and faces (module `block`). Values are
//!   sent as runs of equal bits along x, zero bits left out (the arrays start from zero).
//! - Sub-faces: `compute` sorts them by cell, then in the surface's clip order within a cell;
//!   every cell's sub-faces come from one block, in that block's clip order, which is the
//!   whole surface's restricted to the block's elements. So a stable sort by cell of the blocks'
//!   sub-faces, taken in block order, is the whole list.
//! - Not the same: the layout of `subface_vertices` (each sub-face's vertices are its own bits,
//!   stored in the blocks' order) and the diagnostics (left empty; the embedded part reads
//!   none). `subface_swept_volumes_of` finds each sub-face's vertices by its cell, not by the
//!   layout, so its entries do not depend on it.

use crate::cutcell::block::{BlockGeometry, CellBox};
use crate::cutcell::geometry::{CutGeometry, SubFace, face_index};
use crate::grid::Grid;
use crate::memory::vec_bytes;

/// The share of `b` (computed by `compute_block` for its block, any halo) in the whole grid's
/// geometry, as bytes for [`CutGeometry::assemble`]: Λ of the block's cells, λ of the faces it
/// owns along every active axis, the sub-faces of its cells with their vertices.
///
/// Pure. Size: 16 bytes per run of equal values along x (a covered run is one), 68 bytes and
/// 24 per vertex for each sub-face.
pub fn block_part(grid: &Grid, b: &BlockGeometry) -> Vec<u8> {
    block_part_with(grid, b, &own_subfaces(grid, b), true)
}

/// [`block_part`] without the sub-faces' vertices (what other ranks do not read: each rank
/// clips the prisms of its own cells' sub-faces only), and those vertices apart, in the order of
/// the block's own sub-faces: the share a rank sends to the others, and what
/// [`CutGeometry::assemble_held_own`] puts back for its own part. Pure. Size: 72 bytes per
/// sub-face instead of 72 + 24 per vertex.
pub fn block_part_shared(grid: &Grid, b: &BlockGeometry) -> (Vec<u8>, Vec<[f64; 3]>) {
    let own = own_subfaces(grid, b);
    let mut vertices = Vec::with_capacity(own.iter().map(|s| s.n_vertices as usize).sum());
    for s in &own {
        let first = s.first_vertex as usize;
        vertices.extend_from_slice(&b.subface_vertices[first..first + s.n_vertices as usize]);
    }
    (block_part_with(grid, b, &own, false), vertices)
}

/// The sub-faces of `b`'s block's own cells, in their order: all of them when the window is
/// the block (no halo, the geometry a rank shares in each correct), without finding each one's
/// cell.
///
/// NOTE (issue 40 item 4): finding the cell (two divisions) of every sub-face twice, and
/// collecting their vertices one at a time through iterator adapters, was about 1 ms of a
/// rank's step at 128³ on 2 ranks (`opening-fracture-3d`).
fn own_subfaces<'a>(grid: &Grid, b: &'a BlockGeometry) -> Vec<&'a SubFace> {
    if b.window == b.block {
        return b.subfaces.iter().collect();
    }
    (b.subfaces.iter())
        .filter(|s| b.block.contains(grid.ijk(s.cell as usize)))
        .collect()
}

/// Set in a part's sub-face count when the part carries no vertices.
const NO_VERTICES: u64 = 1 << 63;

/// [`block_part`] of `b` whose own sub-faces are `own` ([`own_subfaces`]).
fn block_part_with(
    grid: &Grid,
    b: &BlockGeometry,
    own: &[&SubFace],
    with_vertices: bool,
) -> Vec<u8> {
    let mut out = Vec::new();
    let block = b.block;
    let (w, n0) = (b.window, block.size(0));
    // Only the spans of the rows the computation wrote can hold values (`WrittenRows`): the
    // rest is skipped without reading it (scanning every value of the block was 0.8 % of a
    // rank's samples at 100³ on 2 ranks, and then every value of each row written, which at
    // 128³ spans the whole grid along x for a body a fifth as wide).
    let row_of = |axis: Option<usize>, j: usize, k: usize| {
        let ny = w.size(1) + usize::from(axis == Some(1));
        (j - w.lo[1]) + ny * (k - w.lo[2])
    };
    // The span of a row of the window's array `array` within the `n0` values from `x0` (a row
    // of the block's, `x0` its place in the window's row): `(offset from x0, values)`.
    let within = |array: usize, row: usize, x0: usize, n0: usize| {
        let span = b.written.span(array, row);
        let (lo, hi) = (span.start.max(x0), span.end.min(x0 + n0));
        if lo < hi { (lo - x0, hi - lo) } else { (0, 0) }
    };
    let x0 = block.lo[0] - w.lo[0];
    let cells = runs(block, |j, k| {
        let (off, len) = within(0, row_of(None, j, k), x0, n0);
        let at = w.index([block.lo[0], j, k]) + off;
        let first = (grid.index(block.lo[0], j, k) + off) as u32;
        (first, &b.solid_fraction[at..at + len])
    });
    put_runs(&mut out, &cells);
    for axis in 0..3 {
        if axis >= grid.dim {
            put_runs(&mut out, &[]);
            continue;
        }
        // The faces the block owns: the low face of each of its cells, and the grid's last.
        let mut faces = block;
        if block.hi[axis] == grid.cells[axis] {
            faces.hi[axis] += 1;
        }
        let n0 = faces.size(0);
        let runs = runs(faces, |j, k| {
            let (off, len) = within(1 + axis, row_of(Some(axis), j, k), x0, n0);
            let at = w.face_index(axis, [faces.lo[0], j, k]) + off;
            let first = (face_index(grid, axis, [faces.lo[0], j, k]) + off) as u32;
            (first, &b.face_fraction[axis][at..at + len])
        });
        put_runs(&mut out, &runs);
    }
    let carried = |s: &SubFace| {
        if with_vertices {
            s.n_vertices as usize
        } else {
            0
        }
    };
    out.reserve_exact(8 + own.iter().map(|s| 72 + 24 * carried(s)).sum::<usize>());
    let flag = if with_vertices { 0 } else { NO_VERTICES };
    out.extend((own.len() as u64 | flag).to_le_bytes());
    for s in own.iter().copied() {
        for x in [s.cell, s.element, s.particle, s.n_vertices] {
            out.extend(x.to_le_bytes());
        }
        let reals = std::iter::once(s.area).chain(s.normal).chain(s.centroid);
        let first = s.first_vertex as usize;
        let vertices = &b.subface_vertices[first..first + carried(s)];
        for x in reals.chain(vertices.iter().flatten().copied()) {
            out.extend(x.to_bits().to_le_bytes());
        }
    }
    out
}

/// Runs `(first index, length, bits)` of equal, non-zero bits over the rows along x of
/// `cells` (`row(j, k)`: the global index of the row's first value, and its values); a run
/// never leaves its row, whose indices are consecutive.
fn runs<'a>(cells: CellBox, row: impl Fn(usize, usize) -> (u32, &'a [f64])) -> Vec<Run> {
    let mut out: Vec<Run> = Vec::new();
    for k in cells.lo[2]..cells.hi[2] {
        for j in cells.lo[1]..cells.hi[1] {
            let (first, values) = row(j, k);
            // NOTE: most rows hold no solid; they are skipped at the speed of a scan.
            if values.iter().all(|v| v.to_bits() == 0) {
                continue;
            }
            let mut open = false;
            for (i, v) in values.iter().enumerate() {
                let bits = v.to_bits();
                match out.last_mut() {
                    Some(r) if open && r.bits == bits => r.len += 1,
                    _ if bits == 0 => {
                        open = false;
                        continue;
                    }
                    _ => out.push(Run {
                        at: first + i as u32,
                        len: 1,
                        bits,
                    }),
                }
                open = true;
            }
        }
    }
    out
}

/// A run of equal bits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Run {
    at: u32,
    len: u32,
    bits: u64,
}

fn put_runs(out: &mut Vec<u8>, runs: &[Run]) {
    out.reserve(8 + 16 * runs.len());
    out.extend((runs.len() as u64).to_le_bytes());
    for r in runs {
        out.extend(r.at.to_le_bytes());
        out.extend(r.len.to_le_bytes());
        out.extend(r.bits.to_le_bytes());
    }
}

/// Reads the bytes of [`block_part`] in order.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn u32(&mut self) -> u32 {
        let x = u32::from_le_bytes(self.bytes[self.at..self.at + 4].try_into().expect("4"));
        self.at += 4;
        x
    }

    fn u64(&mut self) -> u64 {
        let x = u64::from_le_bytes(self.bytes[self.at..self.at + 8].try_into().expect("8"));
        self.at += 8;
        x
    }

    fn f64(&mut self) -> f64 {
        f64::from_bits(self.u64())
    }

    fn runs(&mut self) -> Vec<Run> {
        let n = self.u64() as usize;
        (0..n)
            .map(|_| Run {
                at: self.u32(),
                len: self.u32(),
                bits: self.u64(),
            })
            .collect()
    }
}

/// What one part's runs and sub-faces go into.
trait Sink {
    fn cells(&mut self, run: Run);
    fn faces(&mut self, axis: usize, run: Run);
}

/// The whole grid's dense arrays (and their written ranges, for the sparse reset).
struct Dense<'a>(&'a mut CutGeometry);

impl Sink for Dense<'_> {
    fn cells(&mut self, run: Run) {
        let (at, len) = (run.at as usize, run.len as usize);
        self.0.solid_fraction[at..at + len].fill(f64::from_bits(run.bits));
        self.0.written_cells.push((run.at, run.len));
    }

    fn faces(&mut self, axis: usize, run: Run) {
        let (at, len) = (run.at as usize, run.len as usize);
        self.0.face_fraction[axis][at..at + len].fill(f64::from_bits(run.bits));
        self.0.written_faces[axis].push((run.at, run.len));
    }
}

/// The runs only: their values reach the dense arrays in [`HeldFractions::write_changes`].
impl Sink for HeldFractions {
    fn cells(&mut self, run: Run) {
        self.cell_runs.push(run);
    }

    fn faces(&mut self, axis: usize, run: Run) {
        self.face_runs[axis].push(run);
    }
}

impl HeldFractions {
    /// Writes the values of `run` of Λ that lie in the held box.
    fn write_cells(&mut self, run: Run) {
        let held = self.held;
        write_row(
            run,
            self.cells,
            (held.lo, held.hi),
            |ijk| held.index(ijk),
            &mut self.solid_fraction,
        );
    }

    /// Writes the values of `run` of λ along `axis` that lie in the held box's faces.
    fn write_faces(&mut self, axis: usize, run: Run) {
        let held = self.held;
        let mut shape = self.cells;
        shape[axis] += 1;
        // The faces of the box's cells along `axis`: `lo..=hi` on that axis.
        let mut hi = held.hi;
        hi[axis] += 1;
        write_row(
            run,
            shape,
            (held.lo, hi),
            |ijk| held.face_index(axis, ijk),
            &mut self.face_fraction[axis],
        );
    }
}

/// Writes the values of `run` (one row along x of an array of `shape`, x fastest) that lie in
/// the box `lo..hi` (per axis) at their places in `out`, from `at` of the first of them (the
/// box's places are consecutive along x).
fn write_row(
    run: Run,
    shape: [usize; 3],
    (lo, hi): ([usize; 3], [usize; 3]),
    at: impl Fn([usize; 3]) -> usize,
    out: &mut [f64],
) {
    let first = run.at as usize;
    // The plane first: on a decomposed grid most runs lie in the other blocks' planes (one
    // division for those, not three).
    let plane = shape[0] * shape[1];
    let k = first / plane;
    if !(lo[2]..hi[2]).contains(&k) {
        return;
    }
    let in_plane = first - k * plane;
    let j = in_plane / shape[0];
    let i = in_plane - j * shape[0];
    let (from, to) = (i.max(lo[0]), (i + run.len as usize).min(hi[0]));
    if (lo[1]..hi[1]).contains(&j) && from < to {
        let p = at([from, j, k]);
        out[p..p + (to - from)].fill(f64::from_bits(run.bits));
    }
}

impl CutGeometry {
    /// The whole grid's geometry from the [`block_part`]s of every block of a partition of the
    /// grid, in block order (buffers reused): Λ, λ, the sub-faces and the cut cells of
    /// [`crate::cutcell::compute`], bit for bit (module docs); the sub-faces' vertices in
    /// another layout, and the diagnostics left empty.
    ///
    /// Pure. Cost: the runs and sub-faces of the parts, and the sort of the sub-faces by cell.
    pub fn assemble(&mut self, grid: &Grid, parts: &[impl AsRef<[u8]>]) {
        self.reset(grid);
        let mut vertices = std::mem::take(&mut self.subface_vertices);
        let subfaces = read_parts(parts, &mut vertices, &mut Dense(self), None);
        self.subface_vertices = vertices;
        self.put_subfaces(subfaces);
    }

    /// [`CutGeometry::assemble`] without the whole grid's dense arrays (left empty): the
    /// sub-faces and cut cells of the whole grid here, Λ and λ in `held` (dense in its box, as
    /// runs elsewhere), with the same bits.
    pub fn assemble_held(
        &mut self,
        grid: &Grid,
        parts: &[impl AsRef<[u8]>],
        held: &mut HeldFractions,
    ) {
        self.assemble_held_from(grid, parts, held, None);
    }

    /// [`CutGeometry::assemble_held`] of parts from [`block_part_shared`] (or [`block_part`]):
    /// part `own.0` is this rank's, whose sub-faces take their vertices from `own.1`; the other
    /// parts' sub-faces without vertices have none (`first_vertex` `u32::MAX`, `n_vertices`
    /// kept). The same bits otherwise.
    pub fn assemble_held_own(
        &mut self,
        grid: &Grid,
        parts: &[impl AsRef<[u8]>],
        held: &mut HeldFractions,
        own: (usize, &[[f64; 3]]),
    ) {
        self.assemble_held_from(grid, parts, held, Some(own));
    }

    /// [`CutGeometry::assemble_held`] (`own`: `None`) and [`CutGeometry::assemble_held_own`].
    fn assemble_held_from(
        &mut self,
        grid: &Grid,
        parts: &[impl AsRef<[u8]>],
        held: &mut HeldFractions,
        own: Option<(usize, &[[f64; 3]])>,
    ) {
        self.release_dense();
        self.subfaces.clear();
        self.subface_vertices.clear();
        self.cut_cells.clear();
        self.diagnostics = Default::default();
        held.clear(grid);
        let subfaces = read_parts(parts, &mut self.subface_vertices, held, own);
        held.sort_runs();
        held.write_changes();
        self.put_subfaces(subfaces);
    }

    /// Frees Λ and λ of the whole grid (what [`HeldFractions`] holds instead); a later
    /// [`crate::cutcell::compute`] allocates them again.
    pub fn release_dense(&mut self) {
        self.solid_fraction = Vec::new();
        self.face_fraction = Default::default();
        self.written_cells.clear();
        self.written_faces = Default::default();
    }

    fn put_subfaces(&mut self, mut subfaces: Vec<SubFace>) {
        // Stable: a cell's sub-faces come from one block, in the whole surface's order.
        subfaces.sort_by_key(|s| s.cell);
        self.subfaces = subfaces;
        self.cut_cells.extend(self.subfaces.iter().map(|s| s.cell));
        self.cut_cells.dedup();
    }
}

/// Reads every part: its runs into `sink`, its sub-faces' vertices onto `vertices` (part
/// `own.0`'s from `own.1` where it carries none); returns the sub-faces, in the parts' order.
fn read_parts(
    parts: &[impl AsRef<[u8]>],
    vertices: &mut Vec<[f64; 3]>,
    sink: &mut impl Sink,
    own: Option<(usize, &[[f64; 3]])>,
) -> Vec<SubFace> {
    let mut subfaces: Vec<SubFace> = Vec::new();
    for (p, part) in parts.iter().enumerate() {
        let part = part.as_ref();
        let mut own_vertices = own.filter(|o| o.0 == p).map(|o| o.1.iter());
        let mut r = Reader { bytes: part, at: 0 };
        for run in r.runs() {
            sink.cells(run);
        }
        for axis in 0..3 {
            for run in r.runs() {
                sink.faces(axis, run);
            }
        }
        let count = r.u64();
        let carried = count & NO_VERTICES == 0;
        for _ in 0..count & !NO_VERTICES {
            let (cell, element, particle, n_vertices) = (r.u32(), r.u32(), r.u32(), r.u32());
            let area = r.f64();
            let normal = [r.f64(), r.f64(), r.f64()];
            let centroid = [r.f64(), r.f64(), r.f64()];
            let mut first_vertex = vertices.len() as u32;
            for _ in 0..n_vertices {
                match (carried, own_vertices.as_mut()) {
                    (true, _) => vertices.push([r.f64(), r.f64(), r.f64()]),
                    (false, Some(from)) => vertices.push(*from.next().expect("own vertices")),
                    (false, None) => first_vertex = u32::MAX,
                }
            }
            subfaces.push(SubFace {
                cell,
                element,
                particle,
                area,
                normal,
                centroid,
                first_vertex,
                n_vertices,
            });
        }
        assert_eq!(r.at, part.len(), "a block part read to its end");
        if let Some(mut rest) = own_vertices {
            assert!(rest.next().is_none(), "own vertices read to their end");
        }
    }
    subfaces
}

/// Λ and λ of a surface as one rank of a decomposed grid holds them (issue 40 item 1, step 4
/// (a)): dense in a box of cells (a block and the halo its readers need), and as runs of equal
/// values over the whole grid, so that a value anywhere can still be read (slower).
#[derive(Clone, Debug, Default)]
pub struct HeldFractions {
    /// The cells held dense.
    pub held: CellBox,
    /// The grid's cells per axis.
    cells: [usize; 3],
    /// Λ per cell of `held` ([`CellBox::index`]).
    pub solid_fraction: Vec<f64>,
    /// λ per face of `held`'s cells and axis ([`CellBox::face_index`]).
    pub face_fraction: [Vec<f64>; 3],
    /// Λ of the whole grid: runs of equal, non-zero values, by first cell.
    cell_runs: Vec<Run>,
    /// λ of the whole grid per axis, the same way (by face index, [`face_index`]).
    face_runs: [Vec<Run>; 3],
    /// The runs of the dense arrays' values before the assembly in progress (`cell_runs`,
    /// `face_runs`), while it reads the new ones ([`HeldFractions::write_changes`]).
    old_cell_runs: Vec<Run>,
    old_face_runs: [Vec<Run>; 3],
    /// The run where the last look-up of `cell_runs` (and of each axis's `face_runs`) ended.
    cell_hint: RunHint,
    face_hint: [RunHint; 3],
}

/// Where the last look-up in a list of runs ended: the readers of cells outside the dense box
/// (every near cell of the grid, in ascending order) mostly ask for the same run or the next
/// one, which this finds without a binary search over every run of the grid (with the boxes
/// of `cube-mobile-walls` at 100³ on 2 ranks, `solid_fraction_of` took 2 % of a rank's samples,
/// most of it in the search). Only where the search starts: the value read is the same.
#[derive(Debug, Default)]
struct RunHint(std::sync::atomic::AtomicUsize);

impl Clone for RunHint {
    fn clone(&self) -> RunHint {
        RunHint(std::sync::atomic::AtomicUsize::new(self.get()))
    }
}

impl RunHint {
    fn get(&self) -> usize {
        self.0.load(std::sync::atomic::Ordering::Relaxed)
    }

    fn set(&self, p: usize) {
        self.0.store(p, std::sync::atomic::Ordering::Relaxed);
    }
}

impl HeldFractions {
    /// Empty, for the box `held` of `grid`'s cells.
    pub fn new(grid: &Grid, held: CellBox) -> HeldFractions {
        let mut out = HeldFractions {
            held,
            ..HeldFractions::default()
        };
        out.clear(grid);
        out
    }

    /// Starts an assembly: the runs held become the old runs ([`HeldFractions::write_changes`]
    /// then writes the difference) when the arrays have the box's size; else the arrays are
    /// zeroed whole, with no old runs.
    fn clear(&mut self, grid: &Grid) {
        let fits = self.cells == grid.cells
            && self.solid_fraction.len() == self.held.n_cells()
            && (0..3).all(|a| self.face_fraction[a].len() == self.held.n_faces(grid, a));
        if fits {
            std::mem::swap(&mut self.old_cell_runs, &mut self.cell_runs);
            for axis in 0..3 {
                std::mem::swap(&mut self.old_face_runs[axis], &mut self.face_runs[axis]);
            }
        } else {
            self.old_cell_runs.clear();
            for runs in &mut self.old_face_runs {
                runs.clear();
            }
            self.cells = grid.cells;
            self.solid_fraction.clear();
            self.solid_fraction.resize(self.held.n_cells(), 0.0);
            for axis in 0..3 {
                self.face_fraction[axis].clear();
                self.face_fraction[axis].resize(self.held.n_faces(grid, axis), 0.0);
            }
        }
        self.cell_runs.clear();
        for runs in &mut self.face_runs {
            runs.clear();
        }
    }

    fn sort_runs(&mut self) {
        self.cell_runs.sort_unstable_by_key(|r| r.at);
        for runs in &mut self.face_runs {
            runs.sort_unstable_by_key(|r| r.at);
        }
    }

    /// Puts the sorted new runs into the dense arrays, which hold the old runs' values: zeroes
    /// the old runs that are not among the new ones, then writes the new runs that were not
    /// among the old ones. The arrays then hold what zeroing every old run and writing every
    /// new one gives (the runs of one array are disjoint).
    ///
    /// NOTE (issue 40 item 4): most runs of a step are the step before's (the body's covered
    /// rows, a fixed particle's every run), and zeroing and writing them again was about 2 ms
    /// of a rank's step at 128³ on 2 ranks (`opening-fracture-3d`).
    fn write_changes(&mut self) {
        let (old, new) = (std::mem::take(&mut self.old_cell_runs), &self.cell_runs);
        let (gone, came) = (only_in(&old, new), only_in(new, &old));
        for run in gone {
            self.write_cells(Run { bits: 0, ..run });
        }
        for run in came {
            self.write_cells(run);
        }
        self.old_cell_runs = old;
        for axis in 0..3 {
            let old = std::mem::take(&mut self.old_face_runs[axis]);
            let new = &self.face_runs[axis];
            let (gone, came) = (only_in(&old, new), only_in(new, &old));
            for run in gone {
                self.write_faces(axis, Run { bits: 0, ..run });
            }
            for run in came {
                self.write_faces(axis, run);
            }
            self.old_face_runs[axis] = old;
        }
    }

    /// The same from the whole grid's geometry `whole` (its dense arrays): the reference the
    /// tests compare the assembled runs with (no rank computes the whole grid's geometry any
    /// more, at the start either, since `embedded::gather::assemble_by_block`).
    pub fn from_whole(grid: &Grid, whole: &CutGeometry, held: CellBox) -> HeldFractions {
        let mut out = HeldFractions::new(grid, held);
        out.cell_runs = whole_runs(&whole.solid_fraction, grid.cells[0]);
        for k in held.lo[2]..held.hi[2] {
            for j in held.lo[1]..held.hi[1] {
                for i in held.lo[0]..held.hi[0] {
                    let c = grid.index(i, j, k);
                    out.solid_fraction[held.index([i, j, k])] = whole.solid_fraction[c];
                }
            }
        }
        for axis in 0..grid.dim {
            let row = grid.cells[0] + usize::from(axis == 0);
            out.face_runs[axis] = whole_runs(&whole.face_fraction[axis], row);
            let mut faces = held;
            faces.hi[axis] += 1;
            for k in faces.lo[2]..faces.hi[2] {
                for j in faces.lo[1]..faces.hi[1] {
                    for i in faces.lo[0]..faces.hi[0] {
                        let f = face_index(grid, axis, [i, j, k]);
                        let p = held.face_index(axis, [i, j, k]);
                        out.face_fraction[axis][p] = whole.face_fraction[axis][f];
                    }
                }
            }
        }
        out
    }

    /// Λ of cell `c` (linear index of the whole grid).
    #[inline]
    pub fn solid_fraction_of(&self, c: usize) -> f64 {
        // NOTE: a box that spans x and y (slabs) holds one range of the global numbering; that
        // read is inlined into the readers (most of them read their own cells), the rest
        // (blocks, the runs) is not: it was 1.3 % of a rank's samples as one call per read.
        let plane = self.cells[0] * self.cells[1];
        if let Some(&v) = (self.slab_offset(c, plane)).and_then(|at| self.solid_fraction.get(at)) {
            return v;
        }
        self.solid_fraction_apart(c)
    }

    /// [`HeldFractions::solid_fraction_of`] of a cell outside a slab's range, or of a block.
    #[inline(never)]
    fn solid_fraction_apart(&self, c: usize) -> f64 {
        let n = self.cells;
        if self.spans_xy() {
            let first = n[0] * n[1] * self.held.lo[2];
            return match c.checked_sub(first) {
                Some(at) if at < self.solid_fraction.len() => self.solid_fraction[at],
                _ => run_value(&self.cell_runs, c, &self.cell_hint),
            };
        }
        let ijk = [c % n[0], (c / n[0]) % n[1], c / (n[0] * n[1])];
        if self.held.contains(ijk) {
            return self.solid_fraction[self.held.index(ijk)];
        }
        run_value(&self.cell_runs, c, &self.cell_hint)
    }

    /// λ of face `f` along `axis` ([`face_index`] of the whole grid).
    #[inline]
    pub fn face_fraction_of(&self, axis: usize, f: usize) -> f64 {
        let mut n = self.cells;
        n[axis] += 1;
        // The box's faces along `axis` are one range of the faces' numbering too.
        let faces = &self.face_fraction[axis];
        if let Some(&v) = (self.slab_offset(f, n[0] * n[1])).and_then(|at| faces.get(at)) {
            return v;
        }
        self.face_fraction_apart(axis, f)
    }

    /// [`HeldFractions::face_fraction_of`] of a face outside a slab's range, or of a block.
    #[inline(never)]
    fn face_fraction_apart(&self, axis: usize, f: usize) -> f64 {
        let mut n = self.cells;
        n[axis] += 1;
        let h = self.held;
        if self.spans_xy() {
            let first = n[0] * n[1] * h.lo[2];
            return match f.checked_sub(first) {
                Some(at) if at < self.face_fraction[axis].len() => self.face_fraction[axis][at],
                _ => run_value(&self.face_runs[axis], f, &self.face_hint[axis]),
            };
        }
        let ijk = [f % n[0], (f / n[0]) % n[1], f / (n[0] * n[1])];
        if self.held.has_face(axis, ijk) {
            return self.face_fraction[axis][self.held.face_index(axis, ijk)];
        }
        run_value(&self.face_runs[axis], f, &self.face_hint[axis])
    }

    /// Whether the held box spans x and y (slabs): its cells, and its faces along each axis,
    /// are one range of the global numbering.
    #[inline]
    fn spans_xy(&self) -> bool {
        let (h, n) = (self.held, self.cells);
        h.lo[0] == 0 && h.hi[0] == n[0] && h.lo[1] == 0 && h.hi[1] == n[1]
    }

    /// The place of global index `at` in a slab box's range (`plane`: the values per plane
    /// normal to z), when the box spans x and y and `at` lies at or above its first plane.
    #[inline]
    fn slab_offset(&self, at: usize, plane: usize) -> Option<usize> {
        if !self.spans_xy() {
            return None;
        }
        at.checked_sub(plane * self.held.lo[2])
    }

    /// Heap bytes of the dense arrays (capacities).
    pub fn dense_bytes(&self) -> usize {
        vec_bytes(&self.solid_fraction) + self.face_fraction.iter().map(vec_bytes).sum::<usize>()
    }

    /// Heap bytes of the runs (capacities), the last assembly's old runs included.
    pub fn run_bytes(&self) -> usize {
        vec_bytes(&self.cell_runs)
            + self.face_runs.iter().map(vec_bytes).sum::<usize>()
            + vec_bytes(&self.old_cell_runs)
            + self.old_face_runs.iter().map(vec_bytes).sum::<usize>()
    }
}

/// The runs of `a` that are not in `b` (both sorted by `at`), in order.
fn only_in(a: &[Run], b: &[Run]) -> Vec<Run> {
    let mut j = 0;
    let mut out = Vec::new();
    for &r in a {
        while j < b.len() && b[j].at < r.at {
            j += 1;
        }
        if b.get(j) != Some(&r) {
            out.push(r);
        }
    }
    out
}

/// The value at `at` of sorted, disjoint `runs` (0 outside them); the search starts at `hint`
/// and leaves it where it ended.
fn run_value(runs: &[Run], at: usize, hint: &RunHint) -> f64 {
    // `p`: the number of runs that start at or before `at` (the partition point), found from
    // the hint when `at` lies from the hinted run's start to the start of the run after the
    // next one, else by a binary search.
    let starts_by = |i: usize| runs.get(i).is_some_and(|r| r.at as usize <= at);
    let h = hint.get();
    let p = if starts_by(h) && !starts_by(h + 1) {
        h + 1
    } else if starts_by(h + 1) && !starts_by(h + 2) {
        h + 2
    } else {
        runs.partition_point(|r| r.at as usize <= at)
    };
    hint.set(p.saturating_sub(1));
    match p.checked_sub(1).map(|p| runs[p]) {
        Some(r) if at < (r.at + r.len) as usize => f64::from_bits(r.bits),
        _ => 0.0,
    }
}

/// Runs of equal, non-zero bits of a whole array of rows of `row` values, each within a row.
fn whole_runs(values: &[f64], row: usize) -> Vec<Run> {
    let mut out: Vec<Run> = Vec::new();
    let mut open = false;
    for (i, v) in values.iter().enumerate() {
        let bits = v.to_bits();
        if i % row == 0 {
            open = false;
        }
        match out.last_mut() {
            Some(r) if open && r.bits == bits => r.len += 1,
            _ if bits == 0 => open = false,
            _ => {
                out.push(Run {
                    at: i as u32,
                    len: 1,
                    bits,
                });
                open = true;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::{Run, RunHint, run_value};

    /// The value by a binary search over every run, without a hint.
    fn searched(runs: &[Run], at: usize) -> f64 {
        let p = runs.partition_point(|r| r.at as usize <= at);
        match p.checked_sub(1).map(|p| runs[p]) {
            Some(r) if at < (r.at + r.len) as usize => f64::from_bits(r.bits),
            _ => 0.0,
        }
    }

    #[test]
    fn a_hinted_look_up_reads_the_searched_value_from_any_hint() {
        // Runs of lengths 1 to 4 with gaps of 0 to 3 between them, each its own value.
        let mut runs = Vec::new();
        let mut at = 2;
        for i in 0..40u32 {
            let len = 1 + i % 4;
            runs.push(Run {
                at,
                len,
                bits: (0.25 + f64::from(i)).to_bits(),
            });
            at += len + (i * 7) % 4;
        }
        let end = at as usize + 3;
        let hint = RunHint::default();
        for h in 0..runs.len() + 3 {
            for at in (0..end).chain((0..end).rev()) {
                hint.set(h);
                assert_eq!(
                    run_value(&runs, at, &hint).to_bits(),
                    searched(&runs, at).to_bits()
                );
            }
        }
        // Left to its own hints, ascending and then descending.
        for at in (0..end).chain((0..end).rev()) {
            assert_eq!(
                run_value(&runs, at, &hint).to_bits(),
                searched(&runs, at).to_bits()
            );
        }
        assert_eq!(run_value(&[], 5, &hint), 0.0);
    }
}
