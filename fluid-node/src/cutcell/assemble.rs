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
use crate::cutcell::held_fractions::{HeldFractions, Run, Sink};
use crate::grid::Grid;

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
