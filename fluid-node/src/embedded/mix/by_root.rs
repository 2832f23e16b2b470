//! The groups mixed by their roots' ranks (issue 40 item 1, step 5): when no group needs to
//! merge or widen, a group's mixture reads only its root and its members, so the rank of its
//! root mixes it and every rank receives every mixture ([`Mixing::mixtures`]); and what the
//! mixing writes, in the order the whole mixing writes it.

use super::super::COVERED_TOLERANCE;
use super::super::cells::{CellKind, part_of, sum_parts};
use super::{Mixed, Mixing, Writes};
use crate::fv::FluidSolver;
use crate::fv::euler::NQ;

impl Mixing<'_> {
    /// Whether cell `c` (whole grid) is a cell of this rank (every cell on one rank).
    fn own_cell(&self, c: usize) -> bool {
        let grid = self.grid;
        (self.config.block).is_none_or(|b| b.contains(grid.ijk(c)))
    }

    /// The mixture of every group of `groups` (`(root, source slot)`, sorted), by root, if every
    /// group's mixture is physical; `None` if one is not, on every rank (collective on several
    /// ranks).
    ///
    /// Each rank sums the groups whose root it holds, from its root's predicted state and its
    /// members' contents, as [`Mixing::merge`] tests them and [`Mixing::mix_group`] mixes them,
    /// and one gather gives every rank every group's mixture and whether it is physical
    /// (`dim + 3` values per group).
    ///
    /// NOTE: when every group's mixture is physical, no group merges (the merge joins only
    /// groups whose mixture is not) and none widens, so a group's mixture is the sum of its
    /// root's part and its members' contents over their fluid fractions, which the root's rank
    /// has: the contents of every updated cell are on every rank (`gather_contents`), and a
    /// root's predicted state on its own rank. The sums do not depend on the order of their
    /// terms (`sum_parts`), so the mixture is the one every rank computed from the predicted
    /// states gathered around every group before (`cells_at`, `dim + 2` values per cell within
    /// `WIDEN_RINGS` of a group's cells). A root's part reads the kinds as the mixing starts:
    /// the groups before it mark only updated cells `Mixed` or `Updated`, which a part reads
    /// as it reads `Updated`.
    pub(super) fn mixtures(
        &self,
        solver: &FluidSolver,
        groups: &[(usize, usize)],
        kind: &[CellKind],
    ) -> Option<Vec<[f64; NQ]>> {
        let nvar = self.nvar;
        let mut roots: Vec<u32> = groups.iter().map(|g| g.0 as u32).collect();
        roots.dedup();
        let own_roots: Vec<u32> = (roots.iter().copied())
            .filter(|&c| self.own_cell(c as usize))
            .collect();
        let predicted = solver.own_cells_at(&own_roots);
        let mut mine = Vec::with_capacity(own_roots.len() * (nvar + 1));
        let mut parts: Vec<([f64; NQ], f64)> = Vec::new();
        let (mut i, mut own) = (0, 0);
        while i < groups.len() {
            let root = groups[i].0;
            let j = i + groups[i..].partition_point(|g| g.0 == root);
            if self.own_cell(root) {
                let u = &predicted[own * nvar..(own + 1) * nvar];
                own += 1;
                parts.clear();
                let alpha = self.alpha(root);
                let part = part_of(
                    self.slot_of,
                    self.content,
                    kind,
                    root,
                    alpha,
                    |q| u[q],
                    nvar,
                );
                parts.push((part, alpha));
                for &(_, k) in &groups[i..j] {
                    let c = self.near[k] as usize;
                    if c != root {
                        parts.push((self.content[k], self.alpha(c)));
                    }
                }
                let (sum, vol) = sum_parts(&parts, nvar);
                let physical = vol > 0.0 && self.config.physical(&sum, vol);
                mine.extend((0..nvar).map(|q| sum[q] / vol));
                mine.push(if physical { 1.0 } else { 0.0 });
            }
            i = j;
        }
        let all = solver.gather_owned_by(&roots, mine, nvar + 1);
        let mixtures = all.chunks_exact(nvar + 1);
        if mixtures.clone().any(|m| m[nvar] != 1.0) {
            return None;
        }
        Some(
            mixtures
                .map(|m| std::array::from_fn(|q| if q < nvar { m[q] } else { 0.0 }))
                .collect(),
        )
    }

    /// The updated cells that are not mixed: `U = content / α` (a covered one keeps its ghost
    /// state).
    pub(super) fn unmixed(&self, kind: &[CellKind], out: &mut Writes) {
        for (k, &c) in self.near.iter().enumerate() {
            if kind[k] != CellKind::Updated || self.sources.binary_search(&k).is_ok() {
                continue;
            }
            let a = self.alpha(c as usize);
            if a <= COVERED_TOLERANCE {
                // Covered, nothing to keep: the cell holds a ghost state.
                continue;
            }
            let mut v = [0.0; NQ];
            for q in 0..self.nvar {
                v[q] = self.content[k][q] / a;
            }
            out.writes.push((c, v));
        }
    }

    /// Writes each group's mixture (`mixtures`, by root) into its root and members and marks
    /// them, as [`Mixing::mix_group`] does for a group that neither merged nor widened.
    pub(super) fn write_mixtures(
        &self,
        groups: &[(usize, usize)],
        mixtures: &[[f64; NQ]],
        kind: &mut [CellKind],
        out: &mut Writes,
    ) {
        let (mut i, mut r) = (0, 0);
        while i < groups.len() {
            let root = groups[i].0;
            let j = i + groups[i..].partition_point(|g| g.0 == root);
            let mixture = mixtures[r];
            r += 1;
            out.writes.push((root as u32, mixture));
            for &(_, k) in &groups[i..j] {
                let c = self.near[k] as usize;
                if c != root && self.alpha(c) > COVERED_TOLERANCE {
                    out.writes.push((c as u32, mixture));
                }
                kind[k] = CellKind::Mixed;
                out.mixed += 1;
            }
            let km = self.slot_of[root] as usize;
            if km > 0 {
                kind[km - 1] = CellKind::Updated;
            }
            i = j;
        }
    }

    /// Writes `out` into the solver (each rank keeps its own cells) and gives what was written.
    pub(super) fn written(&self, solver: &mut FluidSolver, out: Writes) -> Mixed {
        let mut writes = out.writes;
        solver.set_cells(&writes);
        // The last value written of each cell, by cell.
        writes.reverse();
        writes.sort_by_key(|w| w.0);
        writes.dedup_by_key(|w| w.0);
        Mixed {
            cells: out.mixed,
            written: writes,
            leaving: out.leaving,
        }
    }
}
