//! Per-cell helpers shared by the solver's passes over the storage.

use crate::fv::euler::{NQ, Primitive};

/// Cells per block of the parallel loops over cells (CFL step, directional pressures).
pub(super) const BLOCK_CELLS: usize = 4096;

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
