//! The groups mixed by their roots' ranks (issue 40 item 1, step 5): when no group needs to
//! merge or widen, a group's mixture reads only its root and its members, so the rank of its
//! root mixes it and every rank receives every mixture ([`Mixing::mixtures`]); and what the
//! mixing writes, in the order the whole mixing writes it.

use super::super::COVERED_TOLERANCE;
use super::super::cells::{CellKind, part_of, sum_parts};
use super::{Failure, Mixed, Mixing, Writes, WrittenCheck};
use crate::fv::FluidSolver;
use crate::fv::euler::NQ;

impl Mixing<'_> {
    /// The mixture of every group of `groups` (`(root, source slot)`, sorted), by root, and the
    /// first cell any rank found not physical (`failure`, this rank's, see
    /// [`Mixing::first_failure`]), if every group's mixture is physical; `None` if one is not,
    /// on every rank (collective on several ranks), and `None` without a gather when the
    /// mixing by root is off (`Embedded::set_mixing_by_root`).
    ///
    /// Each rank sums the groups whose root it holds, from its root's predicted state and its
    /// members' contents, as [`Mixing::merge`] tests them and [`Mixing::mix_group`] mixes them,
    /// and one all-gather gives every rank every group's mixture and whether it is physical
    /// (`dim + 3` values per group), with each rank's `failure`.
    ///
    /// NOTE: when every group's mixture is physical, no group merges (the merge joins only
    /// groups whose mixture is not) and none widens, so a group's mixture is the sum of its
    /// root's part and its members' contents over their fluid fractions, which the root's rank
    /// has: the sources' contents come with their roots (`gather_roots`), and a root's predicted
    /// state and content are its own rank's. The sums do not depend on the order of their terms
    /// (`sum_parts`), so the mixture is the one every rank computed from the predicted states
    /// gathered around every group before (`cells_at`, `dim + 2` values per cell within
    /// `WIDEN_RINGS` of a group's cells). A root's part reads the kinds as the mixing starts:
    /// the groups before it mark only updated cells `Mixed` and roots `Updated`, and no group
    /// reads another's root, so a part reads what it read before.
    pub(super) fn mixtures(
        &self,
        solver: &FluidSolver,
        groups: &[(usize, usize)],
        kind: &[CellKind],
        failure: Failure,
    ) -> Option<(Vec<[f64; NQ]>, Failure)> {
        if !self.config.mixing_by_root {
            return None;
        }
        let nvar = self.nvar;
        let mut roots: Vec<u32> = groups.iter().map(|g| g.0 as u32).collect();
        roots.dedup();
        let own_roots: Vec<u32> = (roots.iter().copied())
            .filter(|&c| self.own_cell(c as usize))
            .collect();
        let predicted = solver.own_cells_at(&own_roots);
        // This rank's failure (the cell, or `u32::MAX`, and the state), then `nvar` values and
        // whether it is physical per group it roots.
        let (cell, state) = failure.unwrap_or((u32::MAX, [0.0; NQ]));
        let mut mine = vec![f64::from(cell)];
        mine.extend_from_slice(&state[..nvar]);
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
        let parts: Vec<Vec<f64>> = if self.config.block.is_some() {
            let bytes: Vec<u8> = mine
                .iter()
                .flat_map(|v| v.to_bits().to_le_bytes())
                .collect();
            (solver.comm().all_gather(&bytes).iter())
                .map(|b| {
                    (b.chunks_exact(8))
                        .map(|v| f64::from_bits(u64::from_le_bytes(v.try_into().expect("8"))))
                        .collect()
                })
                .collect()
        } else {
            vec![mine]
        };
        let slab = solver.slab();
        let mut at = vec![1 + nvar; parts.len()];
        let mut mixtures = Vec::with_capacity(roots.len());
        for &root in &roots {
            let r = if parts.len() > 1 {
                slab.owner(root as usize)
            } else {
                0
            };
            let m = &parts[r][at[r]..at[r] + nvar + 1];
            at[r] += nvar + 1;
            if m[nvar] != 1.0 {
                return None;
            }
            mixtures.push(std::array::from_fn(|q| if q < nvar { m[q] } else { 0.0 }));
        }
        let failure = (parts.iter())
            .filter(|p| p[0] != f64::from(u32::MAX))
            .map(|p| {
                (
                    p[0] as u32,
                    std::array::from_fn(|q| if q < nvar { p[1 + q] } else { 0.0 }),
                )
            })
            .min_by_key(|f| f.0);
        Some((mixtures, failure))
    }

    /// The updated cells that are not mixed: `U = content / α` (a covered one keeps its ghost
    /// state); this rank's only if `own_only` (the others' contents are not at hand then).
    pub(super) fn unmixed(&self, kind: &[CellKind], out: &mut Writes, own_only: bool) {
        let slots = if own_only {
            self.own.range()
        } else {
            0..self.near.len()
        };
        for k in slots {
            let c = self.near[k];
            if kind[k] != CellKind::Updated
                || (own_only && !self.own(k))
                || self.sources.binary_search(&k).is_ok()
            {
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
    pub(super) fn written(
        &self,
        solver: &mut FluidSolver,
        out: Writes,
        check: WrittenCheck,
    ) -> Mixed {
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
            check,
        }
    }

    /// The first of this rank's cells (in the near cells' order) that `Embedded::check_written`
    /// would refuse if every group's mixture is physical, with the state written into it:
    /// `unmixed` holds this rank's [`Mixing::unmixed`] writes, by cell (the near cells are
    /// ascending).
    ///
    /// NOTE: the check reads the last state written into each updated cell and each root. A
    /// root or a source is written a group's mixture last, which the check accepts when it is
    /// physical (`Config::physical` tests `sum / vol`, the state written), so only the other
    /// updated cells can fail, each with its own `content / α`, which this rank has for its own
    /// cells. The first of all is the first of the ranks' firsts.
    pub(super) fn first_failure(
        &self,
        kind: &[CellKind],
        groups: &[(usize, usize)],
        unmixed: &[(u32, [f64; NQ])],
    ) -> Failure {
        let mut roots: Vec<usize> = groups.iter().map(|g| g.0).collect();
        roots.dedup();
        for k in self.own.iter() {
            let c = self.near[k];
            if kind[k] == CellKind::Predicted
                || self.new.lambda(c as usize) >= 1.0 - COVERED_TOLERANCE
                || self.sources.binary_search(&k).is_ok()
                || roots.binary_search(&(c as usize)).is_ok()
            {
                continue;
            }
            let w = unmixed
                .binary_search_by_key(&c, |w| w.0)
                .expect("the correct wrote every updated cell it left uncovered");
            if !self.config.written_ok(&unmixed[w].1) {
                return Some(unmixed[w]);
            }
        }
        None
    }
}
