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

/// The share of `b` (computed by `compute_block` for its block, any halo) in the whole grid's
/// geometry, as bytes for [`CutGeometry::assemble`]: Λ of the block's cells, λ of the faces it
/// owns along every active axis, the sub-faces of its cells with their vertices.
///
/// Pure. Size: 16 bytes per run of equal values along x (a covered run is one), 68 bytes and
/// 24 per vertex for each sub-face.
pub fn block_part(grid: &Grid, b: &BlockGeometry) -> Vec<u8> {
    let mut out = Vec::new();
    let block = b.block;
    let cells = runs(block, |ijk| {
        let c = grid.index(ijk[0], ijk[1], ijk[2]) as u32;
        (c, b.solid_fraction_at(ijk))
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
        let runs = runs(faces, |ijk| {
            let f = face_index(grid, axis, ijk) as u32;
            (f, b.face_fraction_at(axis, ijk))
        });
        put_runs(&mut out, &runs);
    }
    let own: Vec<&SubFace> = (b.subfaces.iter())
        .filter(|s| block.contains(grid.ijk(s.cell as usize)))
        .collect();
    out.extend((own.len() as u64).to_le_bytes());
    for s in own {
        for x in [s.cell, s.element, s.particle, s.n_vertices] {
            out.extend(x.to_le_bytes());
        }
        let reals = std::iter::once(s.area).chain(s.normal).chain(s.centroid);
        let first = s.first_vertex as usize;
        let vertices = &b.subface_vertices[first..first + s.n_vertices as usize];
        for x in reals.chain(vertices.iter().flatten().copied()) {
            out.extend(x.to_bits().to_le_bytes());
        }
    }
    out
}

/// Runs `(first index, length, bits)` of equal, non-zero bits of `value` over the cells (or
/// faces) of `cells`, x fastest; a run never leaves its row, whose indices are consecutive.
fn runs(cells: CellBox, value: impl Fn([usize; 3]) -> (u32, f64)) -> Vec<Run> {
    let mut out: Vec<Run> = Vec::new();
    for k in cells.lo[2]..cells.hi[2] {
        for j in cells.lo[1]..cells.hi[1] {
            let mut open = false;
            for i in cells.lo[0]..cells.hi[0] {
                let (at, v) = value([i, j, k]);
                let bits = v.to_bits();
                match out.last_mut() {
                    Some(r) if open && r.bits == bits => r.len += 1,
                    _ if bits == 0 => {
                        open = false;
                        continue;
                    }
                    _ => out.push(Run { at, len: 1, bits }),
                }
                open = true;
            }
        }
    }
    out
}

/// A run of equal bits.
#[derive(Clone, Copy)]
struct Run {
    at: u32,
    len: u32,
    bits: u64,
}

fn put_runs(out: &mut Vec<u8>, runs: &[Run]) {
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

impl CutGeometry {
    /// The whole grid's geometry from the [`block_part`]s of every block of a partition of the
    /// grid, in block order (buffers reused): Λ, λ, the sub-faces and the cut cells of
    /// [`crate::cutcell::compute`], bit for bit (module docs); the sub-faces' vertices in
    /// another layout, and the diagnostics left empty.
    ///
    /// Pure. Cost: the runs and sub-faces of the parts, and the sort of the sub-faces by cell.
    pub fn assemble(&mut self, grid: &Grid, parts: &[Vec<u8>]) {
        self.reset(grid);
        let mut subfaces: Vec<SubFace> = Vec::new();
        for part in parts {
            let mut r = Reader { bytes: part, at: 0 };
            for run in r.runs() {
                let (at, len) = (run.at as usize, run.len as usize);
                self.solid_fraction[at..at + len].fill(f64::from_bits(run.bits));
                self.written_cells.push((run.at, run.len));
            }
            for axis in 0..3 {
                for run in r.runs() {
                    let (at, len) = (run.at as usize, run.len as usize);
                    self.face_fraction[axis][at..at + len].fill(f64::from_bits(run.bits));
                    self.written_faces[axis].push((run.at, run.len));
                }
            }
            for _ in 0..r.u64() {
                let (cell, element, particle, n_vertices) = (r.u32(), r.u32(), r.u32(), r.u32());
                let area = r.f64();
                let normal = [r.f64(), r.f64(), r.f64()];
                let centroid = [r.f64(), r.f64(), r.f64()];
                let first_vertex = self.subface_vertices.len() as u32;
                for _ in 0..n_vertices {
                    let v = [r.f64(), r.f64(), r.f64()];
                    self.subface_vertices.push(v);
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
        }
        // Stable: a cell's sub-faces come from one block, in the whole surface's order.
        subfaces.sort_by_key(|s| s.cell);
        self.subfaces = subfaces;
        self.cut_cells.extend(self.subfaces.iter().map(|s| s.cell));
        self.cut_cells.dedup();
    }
}
