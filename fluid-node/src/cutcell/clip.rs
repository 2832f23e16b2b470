//! Clipping of surface elements (convex polygons in 3-D, segments in 2-D) into the cells of an
//! *extended* Cartesian grid.
//!
//! The extended grid adds one unbounded slab on each side of every active axis: along axis `a`,
//! slab `-1` is `x < plane(0)`, slab `s` in `0..n` is `plane(s) <= x < plane(s + 1)` and slab `n`
//! is `x >= plane(n)`. Pieces outside the domain are kept so that the column sweeps
//! ([`crate::cutcell::sweep`]) can start from minus infinity, which makes bodies that cross the
//! domain boundary exact.
//!
//! NOTE: tie-breaking. A point exactly on a grid plane belongs to the slab *above* it (half-open
//! cells, as [`crate::grid::Grid::locate`]). A polygon is split only when it has vertices strictly
//! on both sides of a plane; a polygon lying in a grid plane therefore belongs to the cell above
//! that plane. Every comparison is made against the same plane value [`plane`], so a point is
//! classified the same way by every element that contains it, except a vertex within round-off
//! of a plane that a polygon lying in it up to round-off crosses (see `sides`).
//!
//! NOTE: canonical intersections. The intersection of an edge with a plane is always interpolated
//! from the endpoint with the smaller coordinate along the split axis, so the two elements sharing
//! an edge (and an element and its reversed twin) compute bitwise identical cut points.
//!
//! Vertices may carry a payload after their three coordinates (`Polygon<N>`, `N > 3`): it is
//! interpolated with the same parameter as the position and never tested, so a cut point's payload
//! is, like its position, the same bits in every element sharing the edge (used to carry the
//! preimage of each vertex under an element's motion, [`crate::cutcell::subface_swept_volumes`]).

use crate::grid::Grid;

/// Most vertices a clipped polygon may hold. A triangle clipped by a box has at most 9; the margin
/// absorbs near-degenerate round-off (a vertex beyond it would be dropped).
///
/// NOTE: kept small: polygons live on the stack and are copied at every split.
pub(crate) const MAX_VERTICES: usize = 12;

/// A convex polygon with a fixed capacity (no allocation); each vertex holds its position and
/// `N - 3` payload values.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Polygon<const N: usize = 3> {
    /// Vertices [m]; only the first `n` are meaningful.
    pub(crate) v: [[f64; N]; MAX_VERTICES],
    /// Number of vertices.
    pub(crate) n: usize,
}

impl<const N: usize> Polygon<N> {
    /// The empty polygon.
    pub(crate) const EMPTY: Polygon<N> = Polygon {
        v: [[0.0; N]; MAX_VERTICES],
        n: 0,
    };

    /// A polygon from its vertices (at most [`MAX_VERTICES`]).
    pub(crate) fn from_slice(vertices: &[[f64; N]]) -> Polygon<N> {
        let mut poly = Polygon::EMPTY;
        for v in vertices {
            poly.push(*v);
        }
        poly
    }

    /// The vertices in use.
    pub(crate) fn vertices(&self) -> &[[f64; N]] {
        &self.v[..self.n]
    }

    /// Makes `self` hold `other`'s vertices (only those in use are copied: a split copies a
    /// polygon whole to one side, and the unused capacity is most of its bytes).
    #[inline]
    fn copy_from(&mut self, other: &Polygon<N>) {
        self.v[..other.n].copy_from_slice(other.vertices());
        self.n = other.n;
    }

    #[inline]
    fn push(&mut self, x: [f64; N]) {
        if self.n < MAX_VERTICES {
            self.v[self.n] = x;
            self.n += 1;
        }
    }
}

/// Coordinate of grid plane `i` (0..=n) along `axis` [m]; the one formula used everywhere.
#[inline]
pub(crate) fn plane(grid: &Grid, axis: usize, i: i32) -> f64 {
    grid.coord(axis, f64::from(i))
}

/// Extended slab (`-1..=n`) holding coordinate `x` along `axis`, with the tie rule of the module.
#[inline]
pub(crate) fn slab(grid: &Grid, axis: usize, x: f64) -> i32 {
    let n = grid.cells[axis] as i32;
    let t = (x - grid.lower[axis]) / grid.dx[axis];
    // NOTE: truncation equals floor for t >= 0 and avoids a software `floor` call on targets
    // without SSE4.1; the result is clamped to the extended range either way.
    let mut s = if t.is_nan() || t < 0.0 {
        -1
    } else if t >= f64::from(n) {
        n
    } else {
        t as i32
    };
    // NOTE: the division above may be off by one ulp near a plane; the comparisons below against
    // the exact plane values decide.
    while s >= 0 && x < plane(grid, axis, s) {
        s -= 1;
    }
    while s < n && x >= plane(grid, axis, s + 1) {
        s += 1;
    }
    s
}

/// Point on segment `p q` where coordinate `axis` equals `value`, interpolated from the endpoint
/// with the smaller coordinate in magnitude, the lower one on a tie (canonical: the same for
/// `p q` and `q p`, and for the mirror image about `x[axis] = 0`, so that a scene symmetric about
/// a grid centred on 0 is cut mirror-exactly); the payload is interpolated alike. Requires
/// `p[axis]` and `q[axis]` strictly on both sides.
#[inline]
fn cut_point<const N: usize>(p: &[f64; N], q: &[f64; N], axis: usize, value: f64) -> [f64; N] {
    let (pa, qa) = (p[axis].abs(), q[axis].abs());
    let (lo, hi) = if pa < qa || (pa == qa && p[axis] < q[axis]) {
        (p, q)
    } else {
        (q, p)
    };
    let t = (value - lo[axis]) / (hi[axis] - lo[axis]);
    let mut x = [0.0; N];
    for d in 0..N {
        x[d] = lo[d] + t * (hi[d] - lo[d]);
    }
    x[axis] = value;
    x
}

/// Splits `poly` by the plane `x[axis] = value` into the parts below and above (either may be empty).
pub(crate) fn split_polygon<const N: usize>(
    poly: &Polygon<N>,
    axis: usize,
    value: f64,
    below: &mut Polygon<N>,
    above: &mut Polygon<N>,
) {
    below.n = 0;
    above.n = 0;
    let verts = poly.vertices();
    let any_below = verts.iter().any(|x| x[axis] < value);
    let any_above = verts.iter().any(|x| x[axis] > value);
    if !any_below {
        above.copy_from(poly);
        return;
    }
    if !any_above {
        below.copy_from(poly);
        return;
    }
    let side = sides(verts, axis, value);
    for i in 0..verts.len() {
        let (p, q) = (&verts[i], &verts[(i + 1) % verts.len()]);
        let (sp, sq) = (side[i], side[(i + 1) % verts.len()]);
        if sp <= 0 {
            below.push(*p);
        }
        if sp >= 0 {
            above.push(*p);
        }
        if sp * sq < 0 {
            let x = cut_point(p, q, axis, value);
            below.push(x);
            above.push(x);
        }
    }
}

/// The side of `value` (−1 below, 0 on, +1 above) each vertex of a convex polygon with vertices
/// strictly on both sides is split to: the sign of `x[axis] − value`, made monotone along the two
/// arcs from the lowest vertex to the highest and back, with at most one vertex on the plane per
/// arc (the others of a run on it count as below).
///
/// NOTE: why. Along the loop of a convex planar polygon the coordinate rises from its lowest
/// vertex to its highest and falls back, so it meets a plane it crosses at one point (a vertex or
/// a cut) per arc, and the walk of [`split_polygon`] joins the two by one chord that both parts
/// share. A polygon lying in a grid plane up to round-off (an internal face of a tube on
/// `x = 0.5`, its vertices at `0.5 ± 1 ulp`, and its preimage in a swept prism) has signs that
/// alternate at random or several vertices "on" the plane; walked as they were, the parts were
/// joined by chords that did not cancel, so their area vectors did not add up to the polygon's
/// (by 17 % of it): the x sweep of a prism 1e-7 m thick left 6 % of a cell in every cell to the
/// end of its row, which stopped a 3-D tube with fracture at step 6 (issue 35, "the solid moved
/// too far"). Here the signs differ from the coordinates' only at vertices within round-off of
/// the plane, and a well-conditioned polygon is split as before, bit for bit.
fn sides<const N: usize>(verts: &[[f64; N]], axis: usize, value: f64) -> [i8; MAX_VERTICES] {
    let n = verts.len();
    let mut side = [0i8; MAX_VERTICES];
    let (mut lo, mut hi) = (0, 0);
    for (i, x) in verts.iter().enumerate() {
        side[i] = if x[axis] < value {
            -1
        } else {
            i8::from(x[axis] > value)
        };
        if x[axis] < verts[lo][axis] {
            lo = i;
        }
        if x[axis] > verts[hi][axis] {
            hi = i;
        }
    }
    // Rising arc lo -> hi: non-decreasing, only the last vertex of a run on the plane on it.
    let mut i = lo;
    while i != hi {
        let next = (i + 1) % n;
        side[next] = side[next].max(side[i]);
        if side[i] == 0 && side[next] == 0 {
            side[i] = -1;
        }
        i = next;
    }
    // Falling arc hi -> lo: non-increasing, only the first vertex of a run on the plane on it.
    while i != lo {
        let next = (i + 1) % n;
        side[next] = if side[i] <= 0 {
            -1
        } else {
            side[next].min(side[i])
        };
        i = next;
    }
    side
}

/// Clips a convex polygon into the extended cells of the first `grid.dim` axes, calling
/// `emit(cell, piece)` for every piece with at least 3 vertices. `cell` holds extended slab
/// indices (`-1..=n`); inactive axes are 0.
pub(crate) fn clip_polygon<const N: usize>(
    grid: &Grid,
    poly: &Polygon<N>,
    emit: &mut impl FnMut([i32; 3], &Polygon<N>),
) {
    peel(grid, 0, poly, [0; 3], emit);
}

fn peel<const N: usize>(
    grid: &Grid,
    axis: usize,
    poly: &Polygon<N>,
    mut cell: [i32; 3],
    emit: &mut impl FnMut([i32; 3], &Polygon<N>),
) {
    if poly.n < 3 {
        return;
    }
    if axis == grid.dim {
        emit(cell, poly);
        return;
    }
    let (lo, hi) = slab_range(grid, axis, poly.vertices());
    if lo == hi {
        // Within one slab (most elements, at the scale of a cell): nothing to split or copy.
        cell[axis] = hi;
        peel(grid, axis + 1, poly, cell, emit);
        return;
    }
    let mut rest = Polygon::EMPTY;
    rest.copy_from(poly);
    let mut below = Polygon::EMPTY;
    let mut above = Polygon::EMPTY;
    for s in lo..hi {
        split_polygon(
            &rest,
            axis,
            plane(grid, axis, s + 1),
            &mut below,
            &mut above,
        );
        cell[axis] = s;
        peel(grid, axis + 1, &below, cell, emit);
        // `above` is the rest; the next split overwrites the old rest.
        std::mem::swap(&mut rest, &mut above);
    }
    cell[axis] = hi;
    peel(grid, axis + 1, &rest, cell, emit);
}

/// [`clip_polygon`] restricted to the extended cells within `window` (`(first, last)` slab per
/// axis, inclusive): the same splits in the same order up to the window's last slab along each
/// axis, so every piece in the window has the bits [`clip_polygon`] gives it, and none outside
/// is emitted or split further (a block's geometry, [`crate::cutcell::compute_block`]).
pub(crate) fn clip_polygon_in<const N: usize>(
    grid: &Grid,
    poly: &Polygon<N>,
    window: [(i32, i32); 3],
    emit: &mut impl FnMut([i32; 3], &Polygon<N>),
) {
    peel_in(grid, 0, poly, [0; 3], &window, emit);
}

fn peel_in<const N: usize>(
    grid: &Grid,
    axis: usize,
    poly: &Polygon<N>,
    mut cell: [i32; 3],
    window: &[(i32, i32); 3],
    emit: &mut impl FnMut([i32; 3], &Polygon<N>),
) {
    if poly.n < 3 {
        return;
    }
    if axis == grid.dim {
        emit(cell, poly);
        return;
    }
    let (lo, hi) = slab_range(grid, axis, poly.vertices());
    let (first, last) = window[axis];
    let mut rest = *poly;
    let mut below = Polygon::EMPTY;
    let mut above = Polygon::EMPTY;
    for s in lo..hi {
        if s > last {
            return;
        }
        // NOTE: the slabs below the window are split off all the same: each split acts on what
        // the ones below it left, so skipping them would give the window's pieces other bits.
        split_polygon(
            &rest,
            axis,
            plane(grid, axis, s + 1),
            &mut below,
            &mut above,
        );
        if s >= first {
            cell[axis] = s;
            peel_in(grid, axis + 1, &below, cell, window, emit);
        }
        rest = above;
    }
    if (first..=last).contains(&hi) {
        cell[axis] = hi;
        peel_in(grid, axis + 1, &rest, cell, window, emit);
    }
}

fn slab_range<const N: usize>(grid: &Grid, axis: usize, verts: &[[f64; N]]) -> (i32, i32) {
    let mut x_min = verts[0][axis];
    let mut x_max = x_min;
    for x in &verts[1..] {
        if x[axis] < x_min {
            x_min = x[axis];
        }
        if x[axis] > x_max {
            x_max = x[axis];
        }
    }
    let lo = slab(grid, axis, x_min);
    // NOTE: `slab` gives the one slab `s` with `plane(s) <= x < plane(s + 1)` (the planes
    // increase), so `x_max` below the plane above `x_min`'s slab is in that slab: the same
    // slab without a second search (most pieces lie within one cell).
    let hi = if lo < grid.cells[axis] as i32 && x_max < plane(grid, axis, lo + 1) {
        lo
    } else {
        slab(grid, axis, x_max)
    };
    let range = (lo, hi);
    // NOTE: a face lying in a side of the domain up to round-off (a box flush against a wall,
    // its vertices turned by its principal axes to ±1e-17 of the plane) is not split across
    // it, nor put wholly beyond it: the part beyond the side was lost to the fluid's flush
    // faces, and a box at rest in a 3-D corner set the gas moving at 0.24 c in its first step
    // (corpus seed 2003). It takes the slab of an exact one (the tie rule: above the plane).
    let n = grid.cells[axis] as i32;
    for side in [0, n] {
        let at = plane(grid, axis, side);
        let tol = ON_SIDE * grid.dx[axis];
        if x_max - at <= tol && at - x_min <= tol {
            return (side, side);
        }
    }
    range
}

/// A polygon or segment within `ON_SIDE` cells of a side of the domain, on both sides of it, lies
/// in that side ([`slab_range`]).
const ON_SIDE: f64 = 1e-12;

/// Clips the segment `a -> b` (2-D, third coordinate 0; a payload may follow) into extended cells,
/// calling `emit(cell, a', b')` for each piece of non-zero length, orientation preserved.
pub(crate) fn clip_segment<const N: usize>(
    grid: &Grid,
    a: [f64; N],
    b: [f64; N],
    emit: &mut impl FnMut([i32; 3], [f64; N], [f64; N]),
) {
    peel_segment(grid, 0, a, b, [0; 3], emit);
}

fn peel_segment<const N: usize>(
    grid: &Grid,
    axis: usize,
    a: [f64; N],
    b: [f64; N],
    mut cell: [i32; 3],
    emit: &mut impl FnMut([i32; 3], [f64; N], [f64; N]),
) {
    if a[..3] == b[..3] {
        return;
    }
    if axis == grid.dim {
        emit(cell, a, b);
        return;
    }
    let (lo, hi) = slab_range(grid, axis, &[a, b]);
    // Walk from the low end to the high end, then restore the orientation of each piece. Every
    // cut point is interpolated between the two ends of the segment (not from the previous cut),
    // so it does not depend on the direction of the walk.
    let forward = a[axis] <= b[axis];
    let (mut start, end) = if forward { (a, b) } else { (b, a) };
    let origin = start;
    cell[axis] = lo;
    for s in lo..hi {
        let value = plane(grid, axis, s + 1);
        cell[axis] = s;
        if end[axis] <= value {
            // The rest ends on (or below) this plane: it lies in slab `s`.
            break;
        }
        if start[axis] < value {
            let x = cut_point(&origin, &end, axis, value);
            if forward {
                peel_segment(grid, axis + 1, start, x, cell, emit);
            } else {
                peel_segment(grid, axis + 1, x, start, cell, emit);
            }
            start = x;
        }
        cell[axis] = s + 1;
    }
    if forward {
        peel_segment(grid, axis + 1, start, end, cell, emit);
    } else {
        peel_segment(grid, axis + 1, end, start, cell, emit);
    }
}
