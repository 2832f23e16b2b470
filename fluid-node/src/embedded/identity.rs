//! Identity (3) of the sub-face prisms, checked cell by cell, and the fluid the solid newly
//! covers (the swept mass of the ledger), each rank over its own near cells (issue 40 item 1),
//! the ranks agreeing by one all-gather.

use super::error::Reach;
use super::{Embedded, EmbeddedError, SWEPT_TOLERANCE};
use crate::fv::FluidSolver;
use crate::fv::euler::NQ;

impl Embedded {
    /// Identity (3) of the sub-face prisms, cell by cell: what they sweep in a near cell is the
    /// change of its solid volume. Λ is the integral of the winding number (overlapping bodies
    /// count twice, see [`fluid_part`](super::cells::fluid_part)); where it is negative beyond round-off the accepted
    /// surface folds over itself (an element turned inside out) and the cell would hold more
    /// fluid than its volume: that stops the run too.
    ///
    /// On a decomposed grid each rank checks its own near cells (every rank holds every
    /// prism's pieces, so the sums of any cell) and returns the first that fails, which
    /// [`Embedded::displaced`] agrees on; on one rank the error.
    pub(super) fn check_swept(&mut self, step: u64) -> Result<Option<usize>, EmbeddedError> {
        let grid = &self.config.grid;
        self.scratch.content.clear();
        (self.scratch.content).resize(self.near.cells.len(), [0.0; NQ]);
        let pieces = (self.scratch.swept.entries.iter())
            .map(|e| (e.cell, e.volume))
            .chain(self.scratch.beyond.iter().copied());
        for (cell, v) in pieces {
            match self.near.slot(cell as usize) {
                None => return Err(self.outside_near(Some(step), Reach::SweptPrism, cell)),
                Some(k) => self.scratch.content[k][0] += v,
            }
        }
        let (new, old) = (&self.scratch.trial, &self.state.geom);
        let volume = grid.cell_volume();
        let own = &self.near.own;
        let folded = own.iter().find(|&k| {
            let c = self.near.cells[k] as usize;
            let (new_c, old_c) = (new.lambda(c), old.lambda(c));
            let defect = (new_c - old_c) * volume - self.scratch.content[k][0];
            defect.abs() > SWEPT_TOLERANCE * volume || new_c < -SWEPT_TOLERANCE
        });
        match folded {
            Some(k) if self.config.block.is_none() => Err(self.folded(step, k)),
            _ => Ok(folded),
        }
    }

    /// The error of near slot `k` failing identity (3) (after [`Embedded::check_swept`]).
    fn folded(&self, step: u64, k: usize) -> EmbeddedError {
        let grid = &self.config.grid;
        let volume = grid.cell_volume();
        let c = self.near.cells[k] as usize;
        let (from, to) = (self.state.geom.lambda(c), self.scratch.trial.lambda(c));
        let swept = self.scratch.content[k][0];
        let ijk = grid.ijk(c);
        EmbeddedError::Folded {
            step,
            cell: ijk,
            center: grid.cell_center(ijk),
            from,
            to,
            swept: swept / volume,
            defect: ((to - from) * volume - swept) / volume,
        }
    }

    /// The fluid at t^n in the volume the solid newly covers (every change of Λ is in a near
    /// cell: the prisms were checked to stay there), summed in the near cells' order.
    ///
    /// Collective on a decomposed grid: each rank takes its own near cells, and one all-gather
    /// gives every rank every rank's terms, which it adds in the near cells' order as one rank
    /// does, and every rank's first cell failing identity (3) (`folded`, from
    /// [`Embedded::check_swept`]): the first of them stops the run on every rank, as on one.
    pub(super) fn displaced(
        &self,
        solver: &FluidSolver,
        step: u64,
        folded: Option<usize>,
    ) -> Result<f64, EmbeddedError> {
        let volume = self.config.grid.cell_volume();
        let nvar = self.config.grid.dim + 2;
        let (new, old) = (&self.scratch.trial, &self.state.geom);
        let own = &self.near.own;
        let terms = own.iter().filter_map(|k| {
            let c = self.near.cells[k] as usize;
            let (l0, l1) = (old.lambda(c), new.lambda(c));
            let gained = l1.min(1.0) - l0.min(1.0);
            (gained > 0.0).then(|| (k as u32, gained * volume * self.near.saved[k * nvar]))
        });
        if self.config.block.is_none() {
            return Ok(terms.fold(0.0, |sum, (_, t)| sum + t));
        }
        let mut bytes = (folded.map_or(u32::MAX, |k| k as u32))
            .to_le_bytes()
            .to_vec();
        for (k, t) in terms {
            bytes.extend(k.to_le_bytes());
            bytes.extend(t.to_bits().to_le_bytes());
        }
        let parts = solver.comm().all_gather(&bytes);
        let u32_at = |b: &[u8], at: usize| u32::from_le_bytes(b[at..at + 4].try_into().expect("4"));
        if let Some(k) = (parts.iter())
            .map(|p| u32_at(p, 0))
            .min()
            .filter(|&k| k != u32::MAX)
        {
            return Err(self.folded(step, k as usize));
        }
        let mut all: Vec<(u32, f64)> = (parts.iter())
            .flat_map(|p| {
                p[4..].chunks_exact(12).map(|t| {
                    let bits = u64::from_le_bytes(t[4..12].try_into().expect("8 bytes"));
                    (u32_at(t, 0), f64::from_bits(bits))
                })
            })
            .collect();
        // (In the near cells' order: on slabs the ranks' terms come in it already.)
        all.sort_unstable_by_key(|t| t.0);
        Ok(all.iter().fold(0.0, |sum, (_, t)| sum + t))
    }
}
