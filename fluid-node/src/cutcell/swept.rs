//! [`swept_volumes`]: the signed volume swept by each element between two positions, split among
//! the grid cells (Puscas et al. 2015, paper 000 eq. 12).
//!
//! NOTE: the prism `K_f` of an element is the closed polyhedron bounded by the element at `t^{n+1}`
//! (as oriented), the element at `t^n` (reversed) and, for every edge `p q`, the lateral quad
//! `p q q' p'` split into two triangles along a *canonical* diagonal (from the lexicographically
//! smaller endpoint at `t^n` to the other's position at `t^{n+1}`). Two elements sharing an edge
//! pick the same diagonal, so their lateral triangles cancel exactly; summed over a closed surface
//! the prisms then telescope to the surfaces at `t^{n+1}` and `t^n`, and in every cell
//! `Σ_f vol(K_f ∩ C) = (Λ^{n+1} − Λ^n) V` holds to round-off, for any motion (rigid or deforming,
//! any number of cells crossed). The volume inside each cell is computed with the same clipping and
//! column sweep as Λ ([`crate::cutcell::sweep`]). The planar split of the lateral quads differs
//! from the bilinear ruled surface of a linear-in-time motion by O(|motion|² · edge) per edge; these
//! differences cancel between neighbours, so only the attribution to elements, never a cell total,
//! depends on that choice. Positive volume: the solid gains it (the element moved along its normal).

use crate::cutcell::clip::{Polygon, clip_polygon, clip_segment};
use crate::cutcell::geometry::{SNAP_TOLERANCE, build_records, face_area, row_ijk};
use crate::cutcell::measure::{
    Piece, column_moment, polygon_measures, segment_measures, triangle_normal,
};
use crate::cutcell::surface::Surface;
use crate::cutcell::sweep::{Record, SweepSink, sort_records, sweep_rows};
use crate::grid::Grid;

/// Signed volume swept by one element inside one cell.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SweptEntry {
    /// Linear cell index ([`Grid::index`]).
    pub cell: u32,
    /// Element (triangle or segment).
    pub element: u32,
    /// Signed volume, in m³ (2-D: area, in m²); positive where the solid advances.
    pub volume: f64,
}

/// Swept volumes of all elements; buffers reused between calls.
#[derive(Clone, Debug, Default)]
pub struct SweptVolumes {
    /// One entry per (element, cell) pair with a non-zero volume, by element then cell.
    pub entries: Vec<SweptEntry>,
    /// Elements skipped: an index out of range or a non-finite coordinate at either time.
    pub n_skipped_elements: usize,
    pieces: Vec<Piece>,
    records: Vec<Record>,
}

/// Emits the volume of one prism in each cell it meets.
struct PrismSink<'a> {
    grid: &'a Grid,
    element: u32,
    volume: f64,
    entries: &'a mut Vec<SweptEntry>,
}

impl PrismSink<'_> {
    fn emit(&mut self, row: u64, pos: i32, v: f64) {
        if v != 0.0 {
            let ijk = row_ijk(self.grid, 0, row, pos);
            self.entries.push(SweptEntry {
                cell: self.grid.index(ijk[0], ijk[1], ijk[2]) as u32,
                element: self.element,
                volume: v,
            });
        }
    }
}

impl SweepSink for PrismSink<'_> {
    fn face(&mut self, _: u64, _: i32, _: f64) {}

    fn cell(&mut self, row: u64, pos: i32, moment: f64, lambda_right: f64) {
        self.emit(row, pos, moment + self.volume * lambda_right);
    }

    fn run(&mut self, row: u64, from: i32, to: i32, lambda: f64) {
        // Cells covered by the prism (a motion over more than a cell).
        for pos in from..to {
            self.emit(row, pos, self.volume * lambda);
        }
    }
}

impl SweptVolumes {
    /// Empty buffers.
    pub fn new() -> SweptVolumes {
        SweptVolumes::default()
    }

    /// Total signed swept volume in the domain, in m³ (2-D: m²).
    pub fn total(&self) -> f64 {
        self.entries.iter().map(|e| e.volume).sum()
    }

    /// Adds the swept volume of every entry to `acc[cell]` (`acc.len()` = number of cells).
    pub fn accumulate(&self, acc: &mut [f64]) {
        for e in &self.entries {
            acc[e.cell as usize] += e.volume;
        }
    }
}

/// Computes the volume swept by every element of `before` moving to `after` (same connectivity,
/// vertices moved), split among the cells of `grid`, into `out`.
///
/// Pure; no allocation once the buffers have grown. Cost O(pieces of the prisms).
pub fn swept_volumes(grid: &Grid, before: &Surface, after: &Surface, out: &mut SweptVolumes) {
    assert!(
        before.dim == grid.dim && after.dim == grid.dim,
        "surface dimensions ({}, {}) differ from the grid's {}",
        before.dim,
        after.dim,
        grid.dim
    );
    before.check();
    after.check();
    assert!(
        before.elements == after.elements,
        "swept volumes need the same connectivity at both times"
    );
    out.entries.clear();
    out.n_skipped_elements = 0;
    let volume = grid.cell_volume();
    for e in 0..before.n_elements() {
        let (Some(t0), Some(t1)) = (before.element(e), after.element(e)) else {
            out.n_skipped_elements += 1;
            continue;
        };
        out.pieces.clear();
        let pieces = &mut out.pieces;
        if grid.dim == 3 {
            let mut push = |tri: [[f64; 3]; 3]| {
                let poly = Polygon::from_slice(&tri);
                let normal = triangle_normal(&tri);
                clip_polygon(grid, &poly, &mut |cell, piece| {
                    let (area_vector, _, centroid) = polygon_measures(piece, normal);
                    pieces.push(Piece {
                        cell,
                        area_vector,
                        moment: column_moment(grid, cell, area_vector, centroid),
                    });
                });
            };
            push(t1);
            push([t0[0], t0[2], t0[1]]);
            for k in 0..3 {
                let (p, q) = (t0[k], t0[(k + 1) % 3]);
                let (p1, q1) = (t1[k], t1[(k + 1) % 3]);
                if (p, p1) <= (q, q1) || (p, p1).partial_cmp(&(q, q1)).is_none() {
                    push([p, q, q1]);
                    push([p, q1, p1]);
                } else {
                    push([p, q, p1]);
                    push([q, q1, p1]);
                }
            }
        } else {
            let mut push = |a: [f64; 3], b: [f64; 3]| {
                clip_segment(grid, a, b, &mut |cell, a, b| {
                    let (area_vector, _, centroid) = segment_measures(a, b);
                    pieces.push(Piece {
                        cell,
                        area_vector,
                        moment: column_moment(grid, cell, area_vector, centroid),
                    });
                });
            };
            let (a, b, a1, b1) = (t0[0], t0[1], t1[0], t1[1]);
            push(a1, b1);
            push(b1, b);
            push(b, a);
            push(a, a1);
        }
        build_records(grid, 0, &out.pieces, &mut out.records);
        sort_records(&mut out.records);
        let mut sink = PrismSink {
            grid,
            element: e as u32,
            volume,
            entries: &mut out.entries,
        };
        sweep_rows(
            &out.records,
            grid.cells[0] as i32,
            face_area(grid, 0),
            // NOTE: the prism is closed, so its running fraction entering an uncut cell is an
            // integer up to round-off; snapping it stops a 1e-17 residue from filling the row.
            Some(SNAP_TOLERANCE),
            true,
            &mut sink,
        );
    }
}
