//! Per-cell helpers shared by the solver's passes over the storage.

use crate::fv::euler::{NQ, Primitive};

/// Cells per block of the parallel loops over cells (CFL step, directional pressures).
pub(super) const BLOCK_CELLS: usize = 4096;

/// Cells a task of the parallel loops over cells takes at most (in whole blocks or planes).
///
/// NOTE: rayon splits a loop into about four pieces a thread and splits a piece further only
/// when another thread steals it, so the piece a thread runs last is never split: the other
/// thread then sleeps until it ends (up to a quarter of the loop on 2 threads). Bounding the
/// tasks bounds that wait (`fv::sweep::BLOCKS_PER_TASK`).
pub(super) const CELLS_PER_TASK: usize = 16_384;

/// At most how many items of `cells` cells each a task takes: [`CELLS_PER_TASK`]'s worth, at
/// least one.
pub(crate) fn items_per_task(cells: usize) -> usize {
    (CELLS_PER_TASK / cells.max(1)).max(1)
}

/// A storage cell as a 5-component state `(ρ, ρu_x, ρu_y, ρu_z, E)`.
#[inline]
pub(super) fn to_full(cell: &[f64], dim: usize) -> [f64; NQ] {
    let mut s = [0.0; NQ];
    s[0] = cell[0];
    // NOTE: an indexed loop, not `copy_from_slice`: a run-time length makes that a `memmove`
    // call per cell.
    #[allow(clippy::manual_memcpy)]
    for a in 0..dim {
        s[1 + a] = cell[1 + a];
    }
    s[4] = cell[dim + 1];
    s
}

#[inline]
pub(super) fn cell_primitive(cell: &[f64], dim: usize, gamma: f64) -> Primitive {
    crate::fv::euler::primitive(&to_full(cell, dim), gamma)
}
