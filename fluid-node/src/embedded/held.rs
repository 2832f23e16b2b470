//! [`Held`]: the geometry of a surface as this rank holds it (issue 40 item 1, step 4 (a);
//! docs/mpi.md). On one rank, the whole grid's [`CutGeometry`] with its dense Λ and λ. On a
//! decomposed grid, the whole grid's sub-faces and cut cells (surface-sized) and Λ and λ in
//! [`HeldFractions`]: dense in the rank's block and the halo of [`hook_halo`] cells its readers
//! need (the hooks read that window; the others read their own cells and their neighbours), as
//! runs of equal values elsewhere, so that the readers of other cells (identity (3) and the
//! swept mass over every near cell, the checks, the whole mixing, the outputs) read the bits of
//! one rank too. So the dense memory per rank falls with K, and no rank computes the whole
//! grid's geometry, in a step or at the start (`gather::assemble_by_block`).
//!
//! [`hook_halo`]: super::hook_halo

use std::ops::Deref;

use crate::cutcell::{CutGeometry, HeldFractions};
use crate::fv::comm::Gathered;

/// The geometry of `F^n` or `F^{n+1}` as this rank holds it (module docs). Its [`CutGeometry`]
/// (by `Deref`) holds the whole grid's sub-faces and cut cells; read Λ and λ through
/// [`Held::lambda`] and [`Held::face`] (on a decomposed grid its dense arrays are empty).
#[derive(Default)]
pub(super) struct Held {
    pub(super) cut: CutGeometry,
    /// Λ and λ on a decomposed grid (`None` on one rank: `cut`'s dense arrays).
    pub(super) fractions: Option<HeldFractions>,
    /// The blocks' shares it was put together from (a decomposed grid), kept for their buffer.
    pub(super) shares: Gathered,
}

impl Deref for Held {
    type Target = CutGeometry;

    fn deref(&self) -> &CutGeometry {
        &self.cut
    }
}

impl Held {
    /// Λ of cell `c` (a cell of the whole grid).
    #[inline]
    pub(super) fn lambda(&self, c: usize) -> f64 {
        match &self.fractions {
            None => self.cut.solid_fraction[c],
            Some(f) => f.solid_fraction_of(c),
        }
    }

    /// λ of face `f` along `axis` (`cutcell::face_index` of the whole grid).
    #[inline]
    pub(super) fn face(&self, axis: usize, f: usize) -> f64 {
        match &self.fractions {
            None => self.cut.face_fraction[axis][f],
            Some(h) => h.face_fraction_of(axis, f),
        }
    }

    /// Heap bytes of the dense arrays (capacities).
    pub(super) fn dense_bytes(&self) -> usize {
        self.cut.dense_bytes()
            + self
                .fractions
                .as_ref()
                .map_or(0, HeldFractions::dense_bytes)
    }

    /// Heap bytes of all buffers (capacities).
    pub(super) fn memory_bytes(&self) -> usize {
        self.cut.memory_bytes()
            + (self.fractions.as_ref()).map_or(0, |f| f.dense_bytes() + f.run_bytes())
    }
}
