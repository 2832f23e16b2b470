//! The closed prism between two positions of a polygon (3-D) or segment (2-D), and its signed
//! volume in each cell: the shared core of [`crate::cutcell::swept_volumes`] (one prism per
//! element) and [`crate::cutcell::subface_swept_volumes`] (one prism per sub-face).
//!
//! NOTE: the prism is bounded by the polygon at `t^{n+1}` (as oriented), the polygon at `t^n`
//! (reversed) and, for every edge `p q`, the lateral quad `p q q' p'` split into two triangles
//! along a *canonical* diagonal (from the lexicographically smaller endpoint, comparing the pairs
//! (position at `t^n`, position at `t^{n+1}`), at `t^n` to the other's position at `t^{n+1}`). Two
//! prisms whose polygons share an edge (same bits at both times) pick the same diagonal, so their
//! lateral triangles cancel exactly. The volume inside each cell comes from the same clipping and
//! x sweep as Λ ([`crate::cutcell::sweep`]).

use crate::cutcell::clip::{Polygon, clip_polygon, clip_segment};
use crate::cutcell::geometry::{SNAP_TOLERANCE, build_records, face_area, row_ijk};
use crate::cutcell::measure::{
    Piece, column_moment, polygon_measures, segment_measures, triangle_normal,
};
use crate::cutcell::sweep::{Record, SweepSink, sort_records, sweep_rows};
use crate::grid::Grid;
use crate::memory::vec_bytes;

/// Buffers of one prism (pieces and sweep records), reused between prisms.
#[derive(Clone, Debug, Default)]
pub(crate) struct PrismScratch {
    pieces: Vec<Piece>,
    records: Vec<Record>,
}

impl PrismScratch {
    /// Heap bytes of the buffers (capacities).
    pub(crate) fn memory_bytes(&self) -> usize {
        vec_bytes(&self.pieces) + vec_bytes(&self.records)
    }
}

/// Calls `emit(cell, volume)` with the signed volume, in m³ (2-D: m²), of the prism from `bottom`
/// (at `t^n`) to `top` (at `t^{n+1}`) inside every domain cell it meets (non-zero volumes only,
/// ascending cell index). `bottom[k]` is the earlier position of `top[k]`. 3-D: `top` and `bottom`
/// are convex polygons of at most [`crate::cutcell::clip::MAX_VERTICES`] vertices with unit normals
/// `top_normal` and `bottom_normal` (of `top` as oriented and of `bottom` as oriented, not
/// reversed; zero for a degenerate polygon); 2-D: segments `top[0] -> top[1]`, normals unused.
/// Positive volume: the solid gains it (the polygon moved along its normal).
///
/// Returns the number of clipped pieces (the cost of the prism).
pub(crate) fn prism_volumes(
    grid: &Grid,
    top: &[[f64; 3]],
    bottom: &[[f64; 3]],
    top_normal: [f64; 3],
    bottom_normal: [f64; 3],
    scratch: &mut PrismScratch,
    emit: impl FnMut(u32, f64),
) -> usize {
    debug_assert_eq!(top.len(), bottom.len());
    scratch.pieces.clear();
    let pieces = &mut scratch.pieces;
    if grid.dim == 3 {
        let mut push = |poly: &Polygon, normal: [f64; 3]| {
            clip_polygon(grid, poly, &mut |cell, piece| {
                let (area_vector, _, centroid) = polygon_measures(piece, normal);
                pieces.push(Piece {
                    cell,
                    area_vector,
                    moment: column_moment(grid, cell, area_vector, centroid),
                });
            });
        };
        let n = top.len();
        let mut reversed = Polygon::EMPTY;
        reversed.n = n.min(reversed.v.len());
        for k in 0..reversed.n {
            reversed.v[k] = bottom[(n - k) % n];
        }
        push(&Polygon::from_slice(top), top_normal);
        // NOTE: `-n` is bitwise the normal `triangle_normal` gives the reversed triangle.
        push(&reversed, bottom_normal.map(|x| -x));
        let mut triangle =
            |tri: [[f64; 3]; 3]| push(&Polygon::from_slice(&tri), triangle_normal(&tri));
        for k in 0..n {
            let (p, q) = (bottom[k], bottom[(k + 1) % n]);
            let (p1, q1) = (top[k], top[(k + 1) % n]);
            if (p, p1) <= (q, q1) || (p, p1).partial_cmp(&(q, q1)).is_none() {
                triangle([p, q, q1]);
                triangle([p, q1, p1]);
            } else {
                triangle([p, q, p1]);
                triangle([q, q1, p1]);
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
        let (a, b, a1, b1) = (bottom[0], bottom[1], top[0], top[1]);
        push(a1, b1);
        push(b1, b);
        push(b, a);
        push(a, a1);
    }
    build_records(grid, 0, &scratch.pieces, &mut scratch.records);
    sort_records(&mut scratch.records);
    let mut sink = PrismSink {
        grid,
        volume: grid.cell_volume(),
        emit,
    };
    sweep_rows(
        &scratch.records,
        grid.cells[0] as i32,
        face_area(grid, 0),
        // NOTE: the prism is closed, so its running fraction entering an uncut cell is an
        // integer up to round-off; snapping it stops a 1e-17 residue from filling the row.
        Some(SNAP_TOLERANCE),
        true,
        &mut sink,
    );
    scratch.pieces.len()
}

/// Emits the volume of one prism in each cell it meets.
struct PrismSink<'a, F> {
    grid: &'a Grid,
    volume: f64,
    emit: F,
}

impl<F: FnMut(u32, f64)> PrismSink<'_, F> {
    fn emit(&mut self, row: u64, pos: i32, v: f64) {
        if v != 0.0 {
            let ijk = row_ijk(self.grid, 0, row, pos);
            (self.emit)(self.grid.index(ijk[0], ijk[1], ijk[2]) as u32, v);
        }
    }
}

impl<F: FnMut(u32, f64)> SweepSink for PrismSink<'_, F> {
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
