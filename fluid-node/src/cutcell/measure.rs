//! Measures of one clipped piece: vector area, area, centroid, and the column moment used by the
//! divergence-theorem volume.

use crate::cutcell::clip::{Polygon, plane};
use crate::grid::Grid;

/// What the sweeps need of one piece of the surface inside one extended cell.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Piece {
    /// Extended cell (`-1..=n` per active axis, 0 on inactive axes).
    pub(crate) cell: [i32; 3],
    /// Vector area `∫ n dA` [m²] (2-D: `∫ n dl` [m]), `n` out of the solid.
    pub(crate) area_vector: [f64; 3],
    /// Column moment `∫ (x - x_lo) n_x dA` [m³] (2-D: [m²]) about the lower x plane of the cell;
    /// 0 left of the domain (never used there).
    pub(crate) moment: f64,
}

/// Unit normal of the triangle `a b c` by the right-hand rule; zero for a degenerate triangle.
pub(crate) fn triangle_normal(t: &[[f64; 3]; 3]) -> [f64; 3] {
    let n = cross(sub(t[1], t[0]), sub(t[2], t[0]));
    let len = dot(n, n).sqrt();
    if len > 0.0 && len.is_finite() {
        [n[0] / len, n[1] / len, n[2] / len]
    } else {
        [0.0; 3]
    }
}

/// Vector area, area and centroid of a planar convex polygon lying in a plane of unit normal
/// `unit_normal` (zero normal: centroid = vertex mean).
///
/// NOTE: the fan is taken about the first vertex, with coordinates relative to it, so the result
/// keeps full relative precision far from the origin.
pub(crate) fn polygon_measures(poly: &Polygon, unit_normal: [f64; 3]) -> ([f64; 3], f64, [f64; 3]) {
    let v = poly.vertices();
    let origin = v[0];
    let mut area_vector = [0.0; 3];
    let mut weight = 0.0;
    let mut moment = [0.0; 3];
    for i in 1..v.len() - 1 {
        let d1 = sub(v[i], origin);
        let d2 = sub(v[i + 1], origin);
        let c = cross(d1, d2);
        for k in 0..3 {
            area_vector[k] += 0.5 * c[k];
        }
        let w = 0.5 * dot(c, unit_normal);
        weight += w;
        for k in 0..3 {
            moment[k] += w * (d1[k] + d2[k]) / 3.0;
        }
    }
    let area = dot(area_vector, area_vector).sqrt();
    let mut centroid = origin;
    if weight != 0.0 {
        for k in 0..3 {
            centroid[k] += moment[k] / weight;
        }
    } else {
        let mut mean = [0.0; 3];
        for x in v {
            for k in 0..3 {
                mean[k] += (x[k] - origin[k]) / v.len() as f64;
            }
        }
        for k in 0..3 {
            centroid[k] += mean[k];
        }
    }
    (area_vector, area, centroid)
}

/// Vector area (normal `(dy, -dx)` times length), length and midpoint of the 2-D segment `a -> b`.
pub(crate) fn segment_measures(a: [f64; 3], b: [f64; 3]) -> ([f64; 3], f64, [f64; 3]) {
    let d = sub(b, a);
    let area_vector = [d[1], -d[0], 0.0];
    let length = (d[0] * d[0] + d[1] * d[1]).sqrt();
    // NOTE: `(a + b) / 2`, symmetric in the two ends: the reversed segment (the mirror image of
    // an oriented boundary) has the same midpoint to the bit.
    let centroid = [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.0];
    (area_vector, length, centroid)
}

/// Column moment of a piece (see [`Piece::moment`]).
///
/// NOTE: volumes are integrated along x, the axis contiguous in memory, so that filling the
/// covered cells of long rows streams through memory instead of striding across planes.
#[inline]
pub(crate) fn column_moment(
    grid: &Grid,
    cell: [i32; 3],
    area_vector: [f64; 3],
    centroid: [f64; 3],
) -> f64 {
    if cell[0] < 0 {
        0.0
    } else {
        area_vector[0] * (centroid[0] - plane(grid, 0, cell[0]))
    }
}

#[inline]
pub(crate) fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[inline]
pub(crate) fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

#[inline]
pub(crate) fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
