//! [`SlotOf`]: the slot of each near cell among the near cells, found from the cell's index,
//! without an array of the whole grid on a decomposed grid.

use crate::cutcell::CellBox;
use crate::grid::Grid;

/// `slot + 1` of each near cell (its place in `NearCells::cells`), 0 for any other cell.
///
/// Dense over the cells this rank holds dense (`Config::held_box`: its block and the hooks'
/// halo; the whole grid on one rank), where nearly every lookup falls, and a list of the near
/// cells beyond them, ascending, searched by bisection. So a rank of a decomposed grid holds
/// 4 bytes per cell of its held box and 8 per near cell beyond it, not 4 per cell of the whole
/// grid (issue 40 item 1: 537 MB a rank at 512³). Indexed as the array it replaces:
/// `slot_of[c]` for a cell index `c` of the whole grid.
#[derive(Clone, Debug)]
pub(super) struct SlotOf {
    /// Where a cell of the grid lies in `dense`, if it does.
    place: Place,
    /// `slot + 1` of each cell of the held box, 0 where it is no near cell, by `CellBox::index`.
    dense: Vec<u32>,
    /// `(cell, slot + 1)` of the near cells beyond the held box, ascending by cell.
    beyond: Vec<(u32, u32)>,
}

/// Where a cell lies among the cells of the held box, from its index in the whole grid.
///
/// NOTE: a cell's `ijk` by `Grid::ijk` took two divisions a lookup: on 2 ranks the lookups
/// were 68 samples of a rank's 4,000 (against 7 on one rank, where the box is the whole grid
/// and a cell's index is its place). A box of whole rows and planes (slabs; the 2-rank cut) is
/// one range of indices, and any other box divides by constants (`FastDiv`).
#[derive(Clone, Copy, Debug)]
enum Place {
    /// The held box is the whole grid: a cell's index is its place.
    Whole,
    /// The held box is the cells `first .. first + len` of the grid (whole rows, and whole
    /// planes where it holds more than one).
    Range { first: usize, len: usize },
    /// Any other box: `lo` and `size` per axis, and the divisions by a row's and a plane's
    /// cells of the grid.
    Cut {
        lo: [u32; 3],
        size: [u32; 3],
        row: FastDiv,
        plane: FastDiv,
    },
}

impl Place {
    fn new(grid: &Grid, held: CellBox) -> Place {
        assert!(
            u32::try_from(grid.n_cells()).is_ok(),
            "a grid's cells are numbered in u32"
        );
        let [nx, ny, _] = grid.cells;
        if held == CellBox::whole(grid) {
            Place::Whole
        } else if held.size(0) == nx && (held.size(1) == ny || held.size(2) == 1) {
            Place::Range {
                first: grid.index(held.lo[0], held.lo[1], held.lo[2]),
                len: held.n_cells(),
            }
        } else {
            Place::Cut {
                lo: held.lo.map(|v| v as u32),
                size: [0, 1, 2].map(|a| held.size(a) as u32),
                row: FastDiv::new(nx as u32),
                plane: FastDiv::new((nx * ny) as u32),
            }
        }
    }

    /// Where cell `c` lies among the held box's cells (`CellBox::index`), if it does.
    #[inline]
    fn of(&self, c: usize) -> Option<usize> {
        match *self {
            Place::Whole => Some(c),
            Place::Range { first, len } => {
                let d = c.wrapping_sub(first);
                (d < len).then_some(d)
            }
            Place::Cut {
                lo,
                size,
                row,
                plane,
            } => {
                let c = c as u32;
                let k = plane.quotient(c);
                let in_plane = c - k * plane.divisor;
                let j = row.quotient(in_plane);
                let i = in_plane - j * row.divisor;
                let d = [i, j, k].map(|v| v as usize);
                let d: [usize; 3] = std::array::from_fn(|a| d[a].wrapping_sub(lo[a] as usize));
                let s = size.map(|v| v as usize);
                (d[0] < s[0] && d[1] < s[1] && d[2] < s[2])
                    .then(|| d[0] + s[0] * (d[1] + s[1] * d[2]))
            }
        }
    }
}

/// The quotient of a `u32` by a divisor fixed in advance, by a multiplication (Lemire, Kaser
/// and Kurz, "Faster remainder by direct computation", 2019: with `m = ⌈2⁶⁴ / d⌉`, `⌊n / d⌋`
/// is the high 64 bits of `m n` for every 32-bit `n` and `d`).
#[derive(Clone, Copy, Debug)]
struct FastDiv {
    divisor: u32,
    /// `⌈2⁶⁴ / divisor⌉`; 0 for the divisor 1 (2⁶⁴ does not fit).
    m: u64,
}

impl FastDiv {
    fn new(divisor: u32) -> FastDiv {
        assert!(divisor > 0, "a division by zero");
        let m = if divisor == 1 {
            0
        } else {
            u64::MAX / u64::from(divisor) + 1
        };
        FastDiv { divisor, m }
    }

    /// `n / divisor`.
    #[inline]
    fn quotient(self, n: u32) -> u32 {
        if self.m == 0 {
            n
        } else {
            ((u128::from(self.m) * u128::from(n)) >> 64) as u32
        }
    }
}

impl SlotOf {
    /// No near cell, over `grid` with the cells of `held` dense.
    pub(super) fn new(grid: &Grid, held: CellBox) -> SlotOf {
        SlotOf {
            place: Place::new(grid, held),
            dense: vec![0; held.n_cells()],
            beyond: Vec::new(),
        }
    }

    /// Where cell `c` is held dense, if it is.
    #[inline]
    fn dense_index(&self, c: usize) -> Option<usize> {
        self.place.of(c)
    }

    /// Makes `cells` (the near cells, ascending) no near cells again.
    pub(super) fn clear(&mut self, cells: &[u32]) {
        for &c in cells {
            if let Some(d) = self.dense_index(c as usize) {
                self.dense[d] = 0;
            }
        }
        self.beyond.clear();
    }

    /// Gives cell `c` the value `slot + 1`; the cells beyond the held box are given in
    /// ascending order (as `NearCells::cells` is built).
    pub(super) fn set(&mut self, c: usize, slot_plus_one: u32) {
        match self.dense_index(c) {
            Some(d) => self.dense[d] = slot_plus_one,
            None => {
                debug_assert!(self.beyond.last().is_none_or(|&(b, _)| (b as usize) < c));
                self.beyond.push((c as u32, slot_plus_one));
            }
        }
    }

    /// The dense array of the whole grid, indexed by cell (one rank's, `held` the whole grid).
    ///
    /// # Panics
    /// If the held box is not the whole grid.
    pub(super) fn whole_grid(&self) -> &[u32] {
        assert!(
            matches!(self.place, Place::Whole),
            "the slots of a block are not the whole grid's"
        );
        &self.dense
    }

    /// `slot + 1` of each cell of the held box, by `CellBox::index` of that box (0 where it is
    /// no near cell): what a [`super::hooks::NearView`] of the held box reads.
    pub(super) fn held_dense(&self) -> &[u32] {
        &self.dense
    }

    /// Heap bytes held.
    pub(super) fn memory_bytes(&self) -> usize {
        crate::memory::vec_bytes(&self.dense) + crate::memory::vec_bytes(&self.beyond)
    }
}

impl std::ops::Index<usize> for SlotOf {
    type Output = u32;

    /// `slot + 1` of cell `c` (a cell index of the whole grid), 0 if it is no near cell.
    #[inline]
    fn index(&self, c: usize) -> &u32 {
        match self.dense_index(c) {
            Some(d) => &self.dense[d],
            None => match self.beyond.binary_search_by_key(&(c as u32), |e| e.0) {
                Ok(k) => &self.beyond[k].1,
                Err(_) => &0,
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{FastDiv, SlotOf};
    use crate::cutcell::CellBox;
    use crate::grid::Grid;
    use proptest::prelude::*;

    proptest! {
        /// The quotient by multiplication is the division's, for any 32-bit numerator and
        /// divisor (the divisor 1, powers of two and `u32::MAX` among them).
        #[test]
        fn the_fast_quotient_is_the_divisions(
            n in any::<u32>(),
            d in prop_oneof![Just(1u32), Just(u32::MAX), (0u32..32).prop_map(|k| 1 << k), 1u32..],
        ) {
            prop_assert_eq!(FastDiv::new(d).quotient(n), n / d);
            prop_assert_eq!(FastDiv::new(d).quotient(u32::MAX), u32::MAX / d);
            prop_assert_eq!(FastDiv::new(d).quotient(n / d * d), n / d);
        }

        /// Whatever the held box and the near cells, `slot_of[c]` is the dense array's value
        /// of every cell of the grid, through two steps' near cells (set, cleared, set again).
        #[test]
        fn the_slots_are_the_dense_arrays(
            cells in prop::array::uniform3(1usize..9),
            lo in prop::array::uniform3(0usize..9),
            size in prop::array::uniform3(0usize..9),
            picks in prop::collection::vec(prop::collection::vec(any::<bool>(), 512), 2),
        ) {
            let grid = Grid::new(&[0.0; 3], &[1.0; 3], &cells).expect("grid");
            let held = CellBox {
                lo: std::array::from_fn(|a| lo[a].min(cells[a] - 1)),
                hi: std::array::from_fn(|a| (lo[a].min(cells[a] - 1) + size[a].max(1)).min(cells[a])),
            };
            let mut slots = SlotOf::new(&grid, held);
            let mut near: Vec<u32> = Vec::new();
            for pick in &picks {
                slots.clear(&near);
                near = (0..grid.n_cells() as u32).filter(|&c| pick[c as usize]).collect();
                let mut dense = vec![0u32; grid.n_cells()];
                for (k, &c) in near.iter().enumerate() {
                    slots.set(c as usize, k as u32 + 1);
                    dense[c as usize] = k as u32 + 1;
                }
                for (c, &d) in dense.iter().enumerate() {
                    prop_assert_eq!(slots[c], d, "cell {} of {:?}, held {:?}", c, cells, held);
                }
            }
        }
    }

    /// One rank's slots are the whole grid's array; a block's hold its box dense only.
    #[test]
    fn a_blocks_slots_hold_its_box_dense_only() {
        let grid = Grid::new(&[0.0; 3], &[1.0; 3], &[10, 10, 100]).expect("grid");
        let whole = SlotOf::new(&grid, CellBox::whole(&grid));
        assert_eq!(whole.whole_grid().len(), 10_000);
        let block = CellBox {
            lo: [0, 0, 20],
            hi: [10, 10, 50],
        };
        let part = SlotOf::new(&grid, block);
        assert_eq!(part.memory_bytes(), 3_000 * 4);
    }
}
