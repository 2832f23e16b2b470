//! Per-cell helpers of every stage: fractions, neighbours, the order-independent sums of a
//! mixture. They sit below the stages (no stage file is imported here).

use protocol::sum::odd_sum;

use super::COVERED_TOLERANCE;
use super::held::Held;
use super::slots::SlotOf;
use crate::cutcell::{CellBox, SubFace};
use crate::fv::BoundaryKind;
use crate::fv::euler::NQ;
use crate::grid::Grid;

/// What the correct did to a near cell.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum CellKind {
    /// Not touched by the solid: the predicted state stands.
    Predicted,
    /// Updated by eq. (12) and large enough.
    Updated,
    /// Updated by eq. (12), then mixed into a neighbour.
    Mixed,
}

/// Fluid fraction of a cell of solid fraction `lambda`: `1 − Λ`, and 0 where Λ > 1.
///
/// Λ is the integral of the solid's winding number over the cell: where two bodies overlap (a
/// penalty contact, walls pressed together) it counts the overlap twice and may exceed 1. The
/// sums of swept prisms and sub-faces stay exact for it (they are linear in the surface); only
/// the fluid a cell holds is clamped at 0.
#[inline]
pub(crate) fn fluid_part(lambda: f64) -> f64 {
    1.0 - lambda.min(1.0)
}

/// Factor on the state a near cell's swept prisms carry, so that what they move out of it plus
/// what it keeps is the fluid it held: `(min(Λ¹, 1) − min(Λ⁰, 1)) / (Λ¹ − Λ⁰)`, exactly 1 unless
/// Λ exceeds 1 (overlapping bodies, see [`fluid_part`]), 0 for a cell covered at both times.
#[inline]
pub(super) fn overlap_scale(l0: f64, l1: f64) -> f64 {
    if l0 <= 1.0 && l1 <= 1.0 {
        1.0
    } else if l0 >= 1.0 && l1 >= 1.0 {
        0.0
    } else {
        (l1.min(1.0) - l0.min(1.0)) / (l1 - l0)
    }
}

/// The domain face `(axis, side)` (side 0 low, 1 high) a sub-face lies in with its normal out
/// of the domain: a solid face flush against the domain boundary, with no fluid beyond it (the
/// boundary condition acts there instead; the tie rule of [`crate::cutcell`] puts such a face
/// on the low side into the covered cells above it).
pub(super) fn domain_face(grid: &Grid, s: &SubFace) -> Option<(usize, usize)> {
    (0..grid.dim).find_map(|a| {
        let tol = 1e-12 * grid.dx[a];
        if s.normal[a] < 0.0 && (s.centroid[a] - grid.lower[a]).abs() <= tol {
            Some((a, 0))
        } else if s.normal[a] > 0.0 && (s.centroid[a] - grid.upper[a]).abs() <= tol {
            Some((a, 1))
        } else {
            None
        }
    })
}

/// A storage cell (`dim + 2` values) divided by `scale`, as a 5-component state.
pub(super) fn full_state(cell: &[f64], dim: usize, scale: f64) -> [f64; NQ] {
    let mut full = [0.0; NQ];
    full[0] = cell[0] / scale;
    for a in 0..dim {
        full[1 + a] = cell[1 + a] / scale;
    }
    full[4] = cell[dim + 1] / scale;
    full
}

/// The face neighbours of cell `ijk` inside the grid, axis by axis (see
/// [`face_neighbours_of`]).
pub(super) fn face_neighbours(grid: &Grid, ijk: [usize; 3]) -> impl Iterator<Item = FaceNeighbour> {
    let (faces, n) = face_neighbours_of(grid, ijk);
    faces.into_iter().take(n)
}

/// A face neighbour: `(axis, neighbour, the face's index triple)` (see [`face_neighbours`]).
pub(super) type FaceNeighbour = (usize, [usize; 3], [usize; 3]);

/// The face neighbours of cell `ijk` inside the grid, axis by axis, on each axis the side
/// towards the grid's middle first (see [`oriented`]): `(axis, neighbour, the face's index
/// triple)` (a face is indexed by the cell above it), into an array, and how many there are.
#[inline]
pub(super) fn face_neighbours_of(grid: &Grid, ijk: [usize; 3]) -> ([FaceNeighbour; 6], usize) {
    let mut out = [(0, [0; 3], [0; 3]); 6];
    let mut n = 0;
    for a in 0..grid.dim {
        let mut below = ijk;
        let mut above = ijk;
        below[a] = below[a].wrapping_sub(1);
        above[a] += 1;
        let below = (ijk[a] > 0).then_some((a, below, ijk));
        let above = (ijk[a] + 1 < grid.cells[a]).then_some((a, above, above));
        // The side towards the grid's middle first (see `oriented`).
        let sides = if 2 * ijk[a] + 1 > grid.cells[a] {
            [below, above]
        } else {
            [above, below]
        };
        for side in sides.into_iter().flatten() {
            out[n] = side;
            n += 1;
        }
    }
    (out, n)
}

/// The two axes other than `axis`, lower first: the pencils along `axis` are numbered by them,
/// `ijk[o1] + cells[o1] ijk[o2]` (as `fv::sweep::Pencils` numbers them).
pub(super) fn pencil_axes(axis: usize) -> (usize, usize) {
    match axis {
        0 => (1, 2),
        1 => (0, 2),
        _ => (0, 1),
    }
}

/// Offset `d` from cell `ijk` turned towards the grid's middle: its component along each axis
/// on which the cell lies in the upper half is negated.
///
/// NOTE: searches over neighbours that keep the first of equal candidates, and sums over them,
/// then visit the mirror image of a cell's neighbours (about the grid's middle along any axis)
/// in the mirrored order, so that a symmetric scene stays symmetric to the bit.
pub(super) fn oriented(grid: &Grid, ijk: [usize; 3], d: [isize; 3]) -> [isize; 3] {
    let mut out = d;
    for a in 0..3 {
        if 2 * ijk[a] + 1 > grid.cells[a] {
            out[a] = -d[a];
        }
    }
    out
}

/// Whether gas touches wet sub-face `s` in the geometry of solid fractions `lambda`: its cell
/// holds fluid, or the face neighbour it faces along its normal's largest component does (a
/// face on a grid plane, which the tie rule of [`crate::cutcell`] gives to the covered cell
/// behind it, faces the fluid in front).
///
/// NOTE: two bodies pressed together (flush walls, a penalty contact) or a crack thinner than
/// round-off put wet faces in covered cells with covered cells in front: no gas is there. Under
/// the covered cell's `p̄` the two faces' terms cancel only while their normals stay opposite;
/// tilted by one step's rotation they left a momentum of 1.8e-10 of `p̄ Δt / Δx` in a covered
/// cell with no fluid to mix it into (the flush cube at 100^3), and once the faces fell on two
/// sides of a grid plane, all of it. Such faces take no gas pressure, on either side of the
/// exchange; the contact carries the bodies' push.
pub(super) fn touches_gas(grid: &Grid, lambda: &Held, s: &SubFace) -> bool {
    touches_gas_with(grid, |c| lambda.lambda(c), s)
}

/// [`touches_gas`] with the solid fractions read through `lambda` (cell index to Λ: a block's
/// geometry, whose arrays are its window's).
pub(super) fn touches_gas_with(grid: &Grid, lambda: impl Fn(usize) -> f64, s: &SubFace) -> bool {
    let c = s.cell as usize;
    if fluid_part(lambda(c)) > COVERED_TOLERANCE {
        return true;
    }
    match faced(grid, s) {
        Some(q) => fluid_part(lambda(q)) > COVERED_TOLERANCE,
        // Beyond the grid: the boundary condition is there; keep the face's pressure.
        None => true,
    }
}

/// The face neighbour sub-face `s` faces along its normal's largest component (`None` beyond
/// the grid).
fn faced(grid: &Grid, s: &SubFace) -> Option<usize> {
    let axis = dominant_axis(grid.dim, s.normal);
    let mut d = [0isize; 3];
    d[axis] = if s.normal[axis] < 0.0 { -1 } else { 1 };
    shifted(grid, grid.ijk(s.cell as usize), d).map(|q| grid.index(q[0], q[1], q[2]))
}

/// The cell whose `p̄` wet sub-face `s` takes, in the loads (eq. 23–25) and the solid flux
/// alike: the cell holding it, unless that cell was covered at t^n (`lambda_n`: a ghost cell
/// of the sweeps) and the face neighbour it faces ([`touches_gas`]) held fluid at t^n; then
/// that neighbour, the gas in front of the face.
///
/// NOTE: a covered cell's ghost state for a sweep mirrors the fluid on one side of its run
/// only. A run of one cell, or the middle cell of an odd closed run, mirrors the side towards
/// the grid's middle (`hooks::ghost_fills`), so a face entering it from the other side took
/// the pressure beyond the body: the thin shell (`scenes/thin-shell.toml`, a cell covered
/// between two cut cells at x = 319 dx) took 0.99999999 Pa on its upstream face on one side of
/// the grid plane and the upstream 1.00077 Pa on the other, 5e-12 m apart, and the fixed point
/// alternated between the two forever (solid sub-steps K = 2, step 162). Facing the fluid in
/// front, the load is continuous across the plane; for a thick body the ghost already mirrors
/// that neighbour, and its pressure is the neighbour's to round-off (the mirror's kinetic
/// energy change).
pub(super) fn pressure_cell(grid: &Grid, lambda_n: &Held, s: &SubFace) -> usize {
    let c = s.cell as usize;
    if fluid_part(lambda_n.lambda(c)) > COVERED_TOLERANCE {
        return c;
    }
    match faced(grid, s) {
        Some(q) if fluid_part(lambda_n.lambda(q)) > COVERED_TOLERANCE => q,
        _ => c,
    }
}

/// The axis of the largest component of `normal` (the first of equal ones).
pub(super) fn dominant_axis(dim: usize, normal: [f64; 3]) -> usize {
    let mut axis = 0;
    for a in 1..dim {
        if normal[a].abs() > normal[axis].abs() {
            axis = a;
        }
    }
    axis
}

/// Content and fluid fraction of a mixing group from its members' (order-independent sums).
pub(super) fn sum_parts(parts: &[([f64; NQ], f64)], nvar: usize) -> ([f64; NQ], f64) {
    let mut sum = [0.0; NQ];
    let mut terms: Vec<f64> = Vec::with_capacity(parts.len());
    for q in 0..nvar {
        terms.clear();
        terms.extend(parts.iter().map(|p| p.0[q]));
        sum[q] = odd_sum(&mut terms);
    }
    terms.clear();
    terms.extend(parts.iter().map(|p| p.1));
    (sum, odd_sum(&mut terms))
}

/// All offsets of the `(2r + 1)^dim − 1` neighbours within Chebyshev distance `r`.
pub(super) fn offsets(dim: usize, r: isize) -> Vec<[isize; 3]> {
    let range = |a: usize| if a < dim { -r..=r } else { 0..=0 };
    let mut out = Vec::new();
    for k in range(2) {
        for j in range(1) {
            for i in range(0) {
                if (i, j, k) != (0, 0, 0) {
                    out.push([i, j, k]);
                }
            }
        }
    }
    out
}

/// The face neighbour of cell `c` along `axis`, below (`side` 0) or above (1): across a periodic
/// side too, `None` beyond a wall or an open side.
pub(super) fn across(
    grid: &Grid,
    boundary: &[[BoundaryKind; 2]; 3],
    c: usize,
    axis: usize,
    side: usize,
) -> Option<usize> {
    let ijk = grid.ijk(c);
    let stride: usize = grid.cells[..axis].iter().product();
    let n = grid.cells[axis];
    let periodic = boundary[axis][side] == BoundaryKind::Periodic;
    match side {
        0 if ijk[axis] > 0 => Some(c - stride),
        0 if periodic && n > 1 => Some(c + (n - 1) * stride),
        1 if ijk[axis] + 1 < n => Some(c + stride),
        1 if periodic && n > 1 => Some(c - (n - 1) * stride),
        _ => None,
    }
}

/// `ijk + d` if inside the grid.
pub(super) fn shifted(grid: &Grid, ijk: [usize; 3], d: [isize; 3]) -> Option<[usize; 3]> {
    let mut out = [0; 3];
    for a in 0..3 {
        let v = ijk[a] as isize + d[a];
        if v < 0 || v >= grid.cells[a] as isize {
            return None;
        }
        out[a] = v as usize;
    }
    Some(out)
}

/// The cells within `r` of `centres` (cells, by their `ijk`) along each active axis that lie in
/// the grid, ascending, each once.
///
/// NOTE: marked in a bit set of the box that holds them (the centres' bounding box grown by
/// `r`), not of the whole grid: a rank of a decomposed grid marks every near cell of the
/// surface, and a bit set of the whole grid (16.8 MB at 512³, zeroed and read out in every
/// predict whatever the number of ranks) was the last array of the whole grid its step built
/// (issue 40 item 1). Read out row by row, it is the ascending list the whole grid's gave.
pub(super) fn cells_around(grid: &Grid, centres: &[[usize; 3]], r: usize) -> Vec<u32> {
    let Some(bounds) = bounding_box(centres) else {
        return Vec::new();
    };
    let held = bounds.grown(grid, r);
    let mut marks = BoxMarks::new([0, 1, 2], held.lo, [0, 1, 2].map(|a| held.size(a)));
    for ijk in centres {
        let span = |a: usize| {
            let r = if a < grid.dim { r } else { 0 };
            (
                ijk[a].saturating_sub(r),
                (ijk[a] + r).min(grid.cells[a] - 1),
            )
        };
        let (x, y, z) = (span(0), span(1), span(2));
        for k in z.0..=z.1 {
            for j in y.0..=y.1 {
                marks.mark_row([x.0, j, k], x.1);
            }
        }
    }
    let mut cells = Vec::new();
    marks.for_each(|ijk| cells.push(grid.index(ijk[0], ijk[1], ijk[2]) as u32));
    cells
}

/// The smallest box that holds every cell of `cells` (`None` for none).
pub(super) fn bounding_box(cells: &[[usize; 3]]) -> Option<CellBox> {
    let first = cells.first()?;
    let mut b = CellBox {
        lo: *first,
        hi: first.map(|v| v + 1),
    };
    for ijk in cells {
        for a in 0..3 {
            b.lo[a] = b.lo[a].min(ijk[a]);
            b.hi[a] = b.hi[a].max(ijk[a] + 1);
        }
    }
    Some(b)
}

/// A bit set of the points of a box (cells, or the faces of one axis), a row of whole words
/// for each row along the box's fastest axis, read out in the box's order: its rows ascending
/// (the slowest axis slowest), each along the fastest axis.
pub(super) struct BoxMarks {
    /// The axes from the fastest to the slowest.
    order: [usize; 3],
    /// The first point and the number of points along each axis.
    lo: [usize; 3],
    size: [usize; 3],
    /// Words a row.
    row_words: usize,
    bits: Vec<u64>,
}

impl BoxMarks {
    /// No mark, over the points `lo .. lo + size`, rows along `order[0]`.
    pub(super) fn new(order: [usize; 3], lo: [usize; 3], size: [usize; 3]) -> BoxMarks {
        let row_words = size[order[0]].div_ceil(64);
        let rows = size[order[1]] * size[order[2]];
        BoxMarks {
            order,
            lo,
            size,
            row_words,
            bits: vec![0; row_words * rows],
        }
    }

    /// Marks the points from `first` to the one at `last` along the fastest axis (in the box).
    pub(super) fn mark_row(&mut self, first: [usize; 3], last: usize) {
        let [a, b, c] = self.order;
        let row = (first[b] - self.lo[b]) + self.size[b] * (first[c] - self.lo[c]);
        let base = 64 * self.row_words * row;
        mark_run(
            &mut self.bits,
            base + first[a] - self.lo[a],
            base + last - self.lo[a],
        );
    }

    /// Calls `f` with each marked point, in the box's order.
    pub(super) fn for_each(&self, mut f: impl FnMut([usize; 3])) {
        let [a, b, c] = self.order;
        let mut point = self.lo;
        let mut words = self.bits.chunks_exact(self.row_words);
        for kc in 0..self.size[c] {
            point[c] = self.lo[c] + kc;
            for kb in 0..self.size[b] {
                point[b] = self.lo[b] + kb;
                let row = words
                    .next()
                    .expect("a row of words for each row of the box");
                for (w, &word) in row.iter().enumerate() {
                    let mut bits = word;
                    while bits != 0 {
                        point[a] = self.lo[a] + 64 * w + bits.trailing_zeros() as usize;
                        f(point);
                        bits &= bits - 1;
                    }
                }
            }
        }
    }
}

/// Sets the bits `first..=last` of `marked`, a word at a time.
pub(super) fn mark_run(marked: &mut [u64], first: usize, last: usize) {
    let (w0, w1) = (first / 64, last / 64);
    let low = !0u64 << (first % 64);
    let high = !0u64 >> (63 - last % 64);
    if w0 == w1 {
        marked[w0] |= low & high;
    } else {
        marked[w0] |= low;
        marked[w0 + 1..w1].fill(!0);
        marked[w1] |= high;
    }
}

/// The cells marked in `marked` (see [`cell_bits`]), ascending: the set bits of any bit set.
pub(super) fn marked_cells(marked: &[u64]) -> impl Iterator<Item = usize> + '_ {
    marked.iter().enumerate().flat_map(|(w, &bits)| {
        let mut bits = bits;
        std::iter::from_fn(move || {
            (bits != 0).then(|| {
                let c = 64 * w + bits.trailing_zeros() as usize;
                bits &= bits - 1;
                c
            })
        })
    })
}

/// Cell `c`'s content as a part of a mixture: what the correct left in it (`content`, by slot
/// `slot_of[c] - 1`, unless its `kind` is still `Predicted`), or else its predicted state
/// `u(q)` times its fluid fraction `alpha`.
pub(super) fn part_of(
    slot_of: &SlotOf,
    content: &[[f64; NQ]],
    kind: &[CellKind],
    c: usize,
    alpha: f64,
    u: impl Fn(usize) -> f64,
    nvar: usize,
) -> [f64; NQ] {
    let kc = slot_of[c] as usize;
    let mut part = [0.0; NQ];
    if kc > 0 && kind[kc - 1] != CellKind::Predicted {
        part[..nvar].copy_from_slice(&content[kc - 1][..nvar]);
    } else {
        for q in 0..nvar {
            part[q] = alpha * u(q);
        }
    }
    part
}

/// The largest `|x|` of `values` (0 for none); exact in any order.
pub(super) fn max_abs(values: &[f64]) -> f64 {
    values.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

#[cfg(test)]
mod tests {
    use super::{
        BoxMarks, cells_around, face_neighbours, face_neighbours_of, offsets, pencil_axes, shifted,
    };
    use crate::grid::Grid;
    use proptest::prelude::*;

    /// The cells within `r` of `centres` that [`shifted`] keeps, ascending, each once: what a
    /// bit set of the whole grid gave.
    fn shifted_neighbourhoods(grid: &Grid, centres: &[[usize; 3]], r: usize) -> Vec<u32> {
        let mut expected: Vec<u32> = Vec::new();
        for &ijk in centres {
            expected.push(grid.index(ijk[0], ijk[1], ijk[2]) as u32);
            for d in offsets(grid.dim, r as isize) {
                if let Some(q) = shifted(grid, ijk, d) {
                    expected.push(grid.index(q[0], q[1], q[2]) as u32);
                }
            }
        }
        expected.sort_unstable();
        expected.dedup();
        expected
    }

    /// The marked runs are the cells of the offsets that [`shifted`] keeps, on 1-, 2- and 3-D
    /// grids, at the edges and corners, with runs across 64-bit words and longer than one.
    #[test]
    fn marking_around_cells_gives_the_shifted_neighbourhoods() {
        let grids = [
            Grid::new(&[0.0], &[1.0], &[150]).unwrap(),
            Grid::new(&[0.0; 2], &[1.0; 2], &[13, 70]).unwrap(),
            Grid::new(&[0.0; 3], &[1.0; 3], &[9, 7, 11]).unwrap(),
            Grid::new(&[0.0; 3], &[1.0; 3], &[130, 3, 4]).unwrap(),
        ];
        for grid in &grids {
            for r in [0, 1, 2, 70] {
                let n = grid.n_cells();
                let picks = [0, 1, n / 2, n / 3 + 5, n - 2, n - 1];
                let centres: Vec<[usize; 3]> = picks.iter().map(|&c| grid.ijk(c)).collect();
                let got = cells_around(grid, &centres, r);
                let expected = shifted_neighbourhoods(grid, &centres, r);
                assert_eq!(got, expected, "{:?}, r = {r}", grid.cells);
            }
        }
        let grid = &grids[2];
        assert!(cells_around(grid, &[], 2).is_empty());
    }

    proptest! {
        /// Marked in the bit set of the centres' box, the cells around any centres of any grid
        /// are those of the whole grid's neighbourhoods, in the same order.
        #[test]
        fn the_cells_around_are_the_whole_grids(
            dim in 1usize..=3,
            cells in prop::array::uniform3(1usize..80),
            picks in prop::collection::vec(any::<prop::sample::Index>(), 0..12),
            r in 0usize..4,
        ) {
            let cells = &cells[..dim];
            let grid = Grid::new(&vec![0.0; dim], &vec![1.0; dim], cells).expect("grid");
            let centres: Vec<[usize; 3]> =
                picks.iter().map(|i| grid.ijk(i.index(grid.n_cells()))).collect();
            prop_assert_eq!(
                cells_around(&grid, &centres, r),
                shifted_neighbourhoods(&grid, &centres, r)
            );
        }

        /// The face neighbours listed into an array are those of the iterator they replaced, in
        /// its order, for any cell of any 1-, 2- or 3-D grid.
        #[test]
        fn the_face_neighbours_array_is_the_iterators(
            dim in 1usize..=3,
            cells in prop::array::uniform3(1usize..6),
            pick in any::<prop::sample::Index>(),
        ) {
            let cells = &cells[..dim];
            let grid = Grid::new(&vec![0.0; dim], &vec![1.0; dim], cells).expect("grid");
            let ijk = grid.ijk(pick.index(grid.n_cells()));
            // The iterator the array replaced (the search's order, as before).
            let expected: Vec<_> = (0..grid.dim)
                .flat_map(move |a| {
                    let below = (ijk[a] > 0).then(|| {
                        let mut q = ijk;
                        q[a] -= 1;
                        (a, q, ijk)
                    });
                    let above = (ijk[a] + 1 < grid.cells[a]).then(|| {
                        let mut q = ijk;
                        q[a] += 1;
                        (a, q, q)
                    });
                    if 2 * ijk[a] + 1 > grid.cells[a] {
                        below.into_iter().chain(above)
                    } else {
                        above.into_iter().chain(below)
                    }
                })
                .collect();
            let (faces, n) = face_neighbours_of(&grid, ijk);
            prop_assert_eq!(&faces[..n], &expected[..]);
            let listed: Vec<_> = face_neighbours(&grid, ijk).collect();
            prop_assert_eq!(listed, expected);
        }

        /// Rows marked along any axis of a box are read out in the box's order: the points
        /// ascending by their slowest axis, then the middle one, then the fastest.
        #[test]
        fn a_boxs_marks_read_out_in_its_order(
            axis in 0usize..3,
            lo in prop::array::uniform3(0usize..20),
            size in prop::array::uniform3(1usize..70),
            rows in prop::collection::vec(
                (prop::array::uniform3(any::<prop::sample::Index>()), any::<prop::sample::Index>()),
                0..10,
            ),
        ) {
            let (o1, o2) = pencil_axes(axis);
            let mut marks = BoxMarks::new([axis, o1, o2], lo, size);
            let mut expected = Vec::new();
            for (first, len) in &rows {
                let first: [usize; 3] = std::array::from_fn(|a| lo[a] + first[a].index(size[a]));
                let last = first[axis] + len.index(lo[axis] + size[axis] - first[axis]);
                marks.mark_row(first, last);
                for m in first[axis]..=last {
                    let mut q = first;
                    q[axis] = m;
                    expected.push((q[o2], q[o1], q[axis]));
                }
            }
            expected.sort_unstable();
            expected.dedup();
            let mut got = Vec::new();
            marks.for_each(|q| got.push((q[o2], q[o1], q[axis])));
            prop_assert_eq!(got, expected);
        }
    }
}
