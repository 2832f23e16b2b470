//! Row sweeps: face fractions and volumes from the per-cell vector areas of a closed surface.
//!
//! Along a row of cells parallel to axis `a` (the other indices fixed), the solid area on the face
//! `f` between cells `p - 1` and `p` is, by the divergence theorem applied to the solid part of the
//! row's slab below that face with the constant field `e_a`,
//!
//! `A_a λ_f = − Σ_{cells q < p} Σ_{pieces in q} S_a`  (`S` = vector area out of the solid),
//!
//! summed from minus infinity (the extended slab `-1` gathers everything below the domain). This is
//! identity (19)–(21) of Puscas et al. 2015 (paper 003) *by construction*: the difference of the two
//! face fractions of a cell is the projected wet area inside it. Along the last active axis the
//! field `(x_last − x_lo) e_last` gives the solid volume of the cell,
//!
//! `V Λ = Σ_{pieces in cell} ∫ (x_last − x_lo) n_last dA + V λ_top`,
//!
//! so Λ, λ and the sub-faces come from the same pieces and agree to round-off.

use protocol::sum::odd_sum;

/// One piece's contribution to one row sweep.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Record {
    /// Row id (linear index over the two other axes, in-domain).
    pub(crate) row: u64,
    /// Extended position along the axis (`-1..=n`; slab `n` only closes the row).
    pub(crate) pos: i32,
    /// Piece number (tie-break that makes the sort total, hence the sums deterministic).
    pub(crate) order: u32,
    /// Vector-area component along the axis `S_a` [m²].
    pub(crate) flux: f64,
    /// Column moment [m³] (x axis only, else 0).
    pub(crate) moment: f64,
}

/// Sorts records by row, position and piece number.
pub(crate) fn sort_records(records: &mut [Record]) {
    // NOTE: one packed integer key (row, pos + 1, order) compares faster than a tuple; positions
    // are in -1..=n < 2^31 and rows and piece numbers below 2^32 for any grid that fits memory.
    records.sort_unstable_by_key(|x| {
        (u128::from(x.row) << 64) | (u128::from((x.pos + 1) as u32) << 32) | u128::from(x.order)
    });
}

/// Sorts records like [`sort_records`] in O(records + rows): a counting sort on the row (stable,
/// so each row keeps piece order), then a small sort of each row by position and piece.
///
/// NOTE: rows number n_b · n_c ∝ N^(2/3), so this keeps the cost of a sweep proportional to the
/// cut cells, without the log factor of a comparison sort over all records.
pub(crate) fn sort_records_by_rows(
    records: &mut Vec<Record>,
    scratch: &mut Vec<Record>,
    counts: &mut Vec<u32>,
    n_rows: usize,
) {
    sort_records_from_row(records, scratch, counts, 0, n_rows);
}

/// [`sort_records`] in O(records + rows) when the records' rows span few rows for their number
/// ([`sort_records_by_rows`] over the rows they span), else by comparison: the same order (the
/// key is unique), either way.
///
/// NOTE (issue 40 item 4): a block's sweeps sorted their records by comparison (the `u128`
/// key), where the whole grid's `compute` counts them by row: at 128³ on 2 ranks those sorts
/// were about 2 ms of a rank's step (the correct's block geometry and the loads' of each
/// trial surface).
pub(crate) fn sort_records_in_rows(records: &mut Vec<Record>) {
    let (Some(lo), Some(hi)) = (
        records.iter().map(|r| r.row).min(),
        records.iter().map(|r| r.row).max(),
    ) else {
        return;
    };
    let span = hi - lo + 1;
    if span > 4 * records.len() as u64 + 1024 {
        sort_records(records);
        return;
    }
    let (mut scratch, mut counts) = (Vec::new(), Vec::new());
    sort_records_from_row(records, &mut scratch, &mut counts, lo, span as usize);
}

/// [`sort_records_by_rows`] of records whose rows lie in `first..first + n_rows`.
fn sort_records_from_row(
    records: &mut Vec<Record>,
    scratch: &mut Vec<Record>,
    counts: &mut Vec<u32>,
    first: u64,
    n_rows: usize,
) {
    let at_row = |r: &Record| (r.row - first) as usize;
    counts.clear();
    counts.resize(n_rows + 1, 0);
    for r in records.iter() {
        counts[at_row(r) + 1] += 1;
    }
    for i in 1..counts.len() {
        counts[i] += counts[i - 1];
    }
    scratch.clear();
    scratch.resize(
        records.len(),
        Record {
            row: 0,
            pos: 0,
            order: 0,
            flux: 0.0,
            moment: 0.0,
        },
    );
    for r in records.iter() {
        let at = &mut counts[at_row(r)];
        scratch[*at as usize] = *r;
        *at += 1;
    }
    std::mem::swap(records, scratch);
    let mut start = 0;
    while start < records.len() {
        let row = records[start].row;
        let mut end = start + 1;
        while end < records.len() && records[end].row == row {
            end += 1;
        }
        records[start..end].sort_unstable_by_key(|x| (x.pos, x.order));
        start = end;
    }
}

/// What a sweep reports.
pub(crate) trait SweepSink {
    /// A face bounding a cut cell (and the last face of a row) with fraction λ ≠ 0.
    fn face(&mut self, row: u64, pos: i32, lambda: f64);
    /// A cut cell, with its summed moment [m³] and the fraction of its upper face.
    fn cell(&mut self, row: u64, pos: i32, moment: f64, lambda_top: f64);
    /// The uncut cells `from..to` and their lower faces `from..to` all have fraction λ ≠ 0 (only
    /// called when runs are filled).
    fn run(&mut self, row: u64, from: i32, to: i32, lambda: f64);
}

/// Sweeps sorted records of rows of `n` cells; `area` is the face area `A_a` [m²].
///
/// `snap_tol`: when given, the running fraction entering an uncut cell is rounded to the nearest
/// integer if within the tolerance (it is 0 or 1 in exact arithmetic for a closed surface); the
/// largest distance to an integer met there, and the largest |λ| left at the end of a row (0 for a
/// closed surface), are returned: an open surface shows up as a defect of order one.
///
/// `fill_runs`: report uncut runs through [`SweepSink::run`]; otherwise only the faces of cut cells are
/// reported (the caller fills the faces of covered cells from the runs of another sweep).
///
/// NOTE: snapping stops the round-off of the running sum from drifting along long rows; it moves
/// λ by at most `snap_tol`, far below any physical scale, and keeps uncovered/covered cells exact.
///
/// NOTE (mirror symmetry): a cell's pieces are summed independently of their order, and the
/// faces inside a run of adjacent cut cells whose exit was snapped take the running sum from the
/// end of the run on their side of the grid's middle (from below in the lower half, from above
/// in the upper half, the mean of both on the middle face). A scene symmetric about the middle
/// plane then gets mirror-exact fractions: its mirror image visits the same pieces from the
/// other end and in another order.
pub(crate) fn sweep_rows(
    records: &[Record],
    n: i32,
    area: f64,
    snap_tol: Option<f64>,
    fill_runs: bool,
    sink: &mut impl SweepSink,
) -> f64 {
    sweep_rows_from(records, n, area, snap_tol, fill_runs, |_| (0, 0.0), sink)
}

/// [`sweep_rows`] with each row entered at `start(row) = (position, fraction)`: the sweep of a
/// row begins at that position's lower face with that running fraction instead of at the row's
/// start with 0 (the records of the row must lie at or above the position). Entered at an uncut
/// cell with its solid fraction (an integer for a closed surface, the value the whole row's sweep
/// snaps to there), a row gives from there on the bits of the whole row's sweep
/// ([`crate::cutcell::compute_block`]).
pub(crate) fn sweep_rows_from(
    records: &[Record],
    n: i32,
    area: f64,
    snap_tol: Option<f64>,
    fill_runs: bool,
    start: impl Fn(u64) -> (i32, f64),
    sink: &mut impl SweepSink,
) -> f64 {
    let mut max_defect: f64 = 0.0;
    let mut scratch = ROW_SCRATCH.take();
    let RowScratch {
        cluster,
        below,
        terms,
        moments,
    } = &mut scratch;
    let mut i = 0;
    while i < records.len() {
        let row = records[i].row;
        // `next`: first face (and cell) of the row not yet reported.
        let (mut next, mut lambda) = start(row);
        while i < records.len() && records[i].row == row {
            // Gather one cluster: cells at consecutive positions.
            cluster.clear();
            while i < records.len()
                && records[i].row == row
                && cluster.last().is_none_or(|c| records[i].pos == c.0 + 1)
            {
                let pos = records[i].pos;
                terms.clear();
                moments.clear();
                while i < records.len() && records[i].row == row && records[i].pos == pos {
                    terms.push(records[i].flux);
                    moments.push(records[i].moment);
                    i += 1;
                }
                cluster.push((pos, odd_sum(terms), odd_sum(moments)));
            }
            let last = cluster[cluster.len() - 1].0;
            let next_pos = if i < records.len() && records[i].row == row {
                records[i].pos
            } else {
                n
            };
            // Bottom-up running fractions: below[c] on the lower face of cell c, then the exit.
            below.clear();
            let entry = lambda;
            for c in cluster.iter() {
                below.push(lambda);
                lambda -= c.1 / area;
            }
            let mut snapped = false;
            if let Some(tol) = snap_tol
                && next_pos > last + 1
                && last + 1 < n
            {
                let rounded = lambda.round();
                let defect = (lambda - rounded).abs();
                if defect <= tol {
                    lambda = rounded;
                    snapped = true;
                } else {
                    max_defect = max_defect.max(defect);
                }
            }
            // The faces strictly inside the cluster, from the end on their side of the middle.
            if snapped && cluster.len() > 1 {
                let mut above = lambda;
                for k in (1..cluster.len()).rev() {
                    above += cluster[k].1 / area;
                    let face = cluster[k].0;
                    below[k] = match (2 * face).cmp(&n) {
                        std::cmp::Ordering::Less => below[k],
                        std::cmp::Ordering::Greater => above,
                        std::cmp::Ordering::Equal => 0.5 * (below[k] + above),
                    };
                }
            }
            debug_assert_eq!(below[0], entry);
            for (k, c) in cluster.iter().enumerate() {
                let pos = c.0;
                let face_lambda = below[k];
                let top = if k + 1 < cluster.len() {
                    below[k + 1]
                } else {
                    lambda
                };
                if pos >= 0 {
                    if k == 0 && fill_runs && face_lambda != 0.0 && next < pos {
                        sink.run(row, next, pos, face_lambda);
                    }
                    if face_lambda != 0.0 {
                        sink.face(row, pos, face_lambda);
                    }
                }
                if pos >= 0 && pos < n {
                    sink.cell(row, pos, c.2, top);
                    // Upper face of a cut cell followed by an uncut one (else the next record's).
                    if !fill_runs && k + 1 == cluster.len() && next_pos > pos + 1 && top != 0.0 {
                        sink.face(row, pos + 1, top);
                    }
                }
                next = pos + 1;
            }
        }
        // Tail: cells next..n and faces next..=n.
        if lambda != 0.0 && next <= n {
            if fill_runs && next < n {
                sink.run(row, next, n, lambda);
            }
            sink.face(row, n, lambda);
        }
        // Beyond the last piece (slab `n` included) a closed surface leaves nothing.
        if let Some(tol) = snap_tol
            && lambda.abs() > tol
        {
            max_defect = max_defect.max(lambda.abs());
        }
    }
    ROW_SCRATCH.set(scratch);
    max_defect
}

/// Buffers of [`sweep_rows_from`]: one cluster of adjacent cut cells (position, summed flux,
/// summed moment), the running fraction on each of its cells' lower faces, and one cell's
/// fluxes and moments.
#[derive(Default)]
struct RowScratch {
    cluster: Vec<(i32, f64, f64)>,
    below: Vec<f64>,
    terms: Vec<f64>,
    moments: Vec<f64>,
}

thread_local! {
    /// [`RowScratch`] of the calls on this thread, kept from call to call (cleared before use).
    ///
    /// NOTE: `sweep_rows_from` runs once per sub-face's prism (`cutcell::prism`), thousands of
    /// times a step, and took four fresh buffers each time (`malloc`, `realloc` and `free` a
    /// call). Taken out of the cell for the call (a call from a sink would find it empty and
    /// use fresh ones), and every buffer is cleared before use: the same values whatever the
    /// buffers held before.
    static ROW_SCRATCH: std::cell::Cell<RowScratch> = std::cell::Cell::new(RowScratch::default());
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::{Record, sort_records, sort_records_in_rows};

    proptest! {
        /// Counted by rows or compared, the records come in the same order: rows close
        /// together (counted) and far apart (compared), positions from −1, pieces in any order.
        #[test]
        fn records_sorted_in_rows_are_sorted_records(
            rows in prop::collection::vec((0u64..40, -1i32..12), 0..300),
            first in prop_oneof![Just(0u64), Just(1_000_000u64)],
            far in any::<bool>(),
            seed in any::<u64>(),
        ) {
            let n = rows.len();
            // The pieces' numbers, a permutation of 0..n.
            let mut order: Vec<u32> = (0..n as u32).collect();
            let mut x = seed | 1;
            for i in (1..n).rev() {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                order.swap(i, (x % (i as u64 + 1)) as usize);
            }
            let records: Vec<Record> = (rows.iter().zip(&order))
                .map(|(&(row, pos), &o)| Record {
                    row: first + if far { row * 100_000 } else { row },
                    pos,
                    order: o,
                    flux: o as f64,
                    moment: 0.0,
                })
                .collect();
            let (mut counted, mut compared) = (records.clone(), records);
            sort_records_in_rows(&mut counted);
            sort_records(&mut compared);
            let key = |r: &Record| (r.row, r.pos, r.order, r.flux.to_bits());
            prop_assert_eq!(
                counted.iter().map(key).collect::<Vec<_>>(),
                compared.iter().map(key).collect::<Vec<_>>()
            );
        }
    }
}
