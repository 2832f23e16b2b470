//! [`HeldFractions`]: Λ and λ of a surface as one rank of a decomposed grid holds them, put
//! together from the blocks' shares (`CutGeometry::assemble_held`, module `assemble`).

use crate::cutcell::block::CellBox;
use crate::cutcell::geometry::{CutGeometry, face_index};
use crate::grid::Grid;
use crate::memory::vec_bytes;

/// A run of equal bits (of Λ or λ along x; a block's share sends them, module `assemble`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Run {
    pub(super) at: u32,
    pub(super) len: u32,
    pub(super) bits: u64,
}

/// What one part's runs and sub-faces go into.
pub(super) trait Sink {
    fn cells(&mut self, run: Run);
    fn faces(&mut self, axis: usize, run: Run);
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
    pub(super) fn clear(&mut self, grid: &Grid) {
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

    pub(super) fn sort_runs(&mut self) {
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
    pub(super) fn write_changes(&mut self) {
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
