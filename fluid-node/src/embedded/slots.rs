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
    /// The cells held dense.
    held: CellBox,
    /// The grid (a cell's index to its `ijk`).
    grid: Grid,
    /// Whether `held` is the whole grid (then `dense` is indexed by the cell index itself).
    whole: bool,
    /// `slot + 1` of each cell of `held`, 0 where it is no near cell, by `CellBox::index`.
    dense: Vec<u32>,
    /// `(cell, slot + 1)` of the near cells beyond `held`, ascending by cell.
    beyond: Vec<(u32, u32)>,
}

impl SlotOf {
    /// No near cell, over `grid` with the cells of `held` dense.
    pub(super) fn new(grid: &Grid, held: CellBox) -> SlotOf {
        SlotOf {
            held,
            grid: grid.clone(),
            whole: held == CellBox::whole(grid),
            dense: vec![0; held.n_cells()],
            beyond: Vec::new(),
        }
    }

    /// Where cell `c` is held dense, if it is.
    #[inline]
    fn dense_index(&self, c: usize) -> Option<usize> {
        if self.whole {
            return Some(c);
        }
        let ijk = self.grid.ijk(c);
        self.held.contains(ijk).then(|| self.held.index(ijk))
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
        assert!(self.whole, "the slots of a block are not the whole grid's");
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
    use super::SlotOf;
    use crate::cutcell::CellBox;
    use crate::grid::Grid;
    use proptest::prelude::*;

    proptest! {
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
