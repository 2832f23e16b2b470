//! The groups merged when their mixtures are not physical ([`Mixing::merge`]) and one group
//! mixed into its members and root ([`Mixing::mix_group`]).

use super::super::cells::{CellKind, face_neighbours, sum_parts};
use super::super::{COVERED_TOLERANCE, CorrectReport, EmbeddedError, MERGE_ROUNDS};
use super::{Groups, Mixing, Predicted, Writes};
use crate::cutcell::face_index;
use crate::fv::FluidSolver;
use crate::fv::euler::NQ;

impl Mixing<'_> {
    /// NOTE: groups whose mixture is not physical take in the groups beside them (through open
    /// faces), all at once, round by round, before widening into free cells. A crack opening
    /// across a grid plane puts the gas of a thin gap in one row of small cells and the sliver
    /// it expands into in the row across the plane; the Lax–Friedrichs flux of paper 000 §3.2
    /// moves half a full cell's content per step through each whole face of that plane, ten
    /// times what a gap cell 4.6 % open holds, and the two rows had their targets on opposite
    /// sides (rho = -8.1 in a mixture, the flush cube at 100^3, step 148). Merging keeps
    /// conservation, and the partition does not depend on the order of the groups (the
    /// smallest root names a merged group).
    pub(super) fn merge(
        &self,
        mut groups: Vec<(usize, usize)>,
        kind: &[CellKind],
        predicted: &Predicted,
        report: &mut CorrectReport,
    ) -> Groups {
        let grid = self.grid;
        let mut roots: Vec<usize> = groups.iter().map(|g| g.0).collect();
        roots.dedup();
        // (cell, group) of every root and member, by cell.
        let group_of = {
            let mut owner: Vec<(usize, usize)> = Vec::with_capacity(groups.len() + roots.len());
            for (r, &root) in roots.iter().enumerate() {
                owner.push((root, r));
            }
            for &(root, k) in &groups {
                let r = roots
                    .binary_search(&root)
                    .expect("a group's root is a root");
                owner.push((self.near[k] as usize, r));
            }
            owner.sort_unstable();
            owner.dedup();
            owner
        };
        let mut parent: Vec<usize> = (0..roots.len()).collect();
        fn find(parent: &[usize], mut r: usize) -> usize {
            while parent[r] != r {
                r = parent[r];
            }
            r
        }
        for _ in 0..MERGE_ROUNDS {
            // The parts of each merged group, by its representative.
            let mut parts: Vec<Vec<([f64; NQ], f64)>> = vec![Vec::new(); roots.len()];
            for &(c, r) in &group_of {
                parts[find(&parent, r)].push((self.part(kind, predicted, c), self.alpha(c)));
            }
            let bad: Vec<bool> = parts
                .iter()
                .map(|p| {
                    !p.is_empty() && {
                        let (sum, vol) = sum_parts(p, self.nvar);
                        !(vol > 0.0 && self.config.physical(&sum, vol))
                    }
                })
                .collect();
            let mut joins: Vec<(usize, usize)> = Vec::new();
            for &(c, r) in &group_of {
                let r = find(&parent, r);
                if !bad[r] {
                    continue;
                }
                for (a, q, f) in face_neighbours(grid, grid.ijk(c)) {
                    let qi = grid.index(q[0], q[1], q[2]);
                    if self.new.face(a, face_index(grid, a, f)) >= 1.0 {
                        continue;
                    }
                    if let Ok(i) = group_of.binary_search_by_key(&qi, |o| o.0) {
                        let h = find(&parent, group_of[i].1);
                        if h != r {
                            joins.push((r.min(h), r.max(h)));
                        }
                    }
                }
            }
            if joins.is_empty() {
                break;
            }
            for (a, b) in joins {
                let (a, b) = (find(&parent, a), find(&parent, b));
                parent[a.max(b)] = a.min(b);
            }
        }
        // Re-root the sources of merged groups; their old roots join as members.
        let mut merged: Vec<(usize, usize)> = Vec::new();
        for (r, &root) in roots.iter().enumerate() {
            let to = find(&parent, r);
            if to != r {
                report.merged_groups += 1;
                if self.is_source(root).is_none() {
                    merged.push((roots[to], root));
                }
            }
        }
        merged.sort_unstable();
        let merged_parts: Vec<[f64; NQ]> = merged
            .iter()
            .map(|m| self.part(kind, predicted, m.1))
            .collect();
        for g in groups.iter_mut() {
            let r = roots.binary_search(&g.0).expect("a group's root is a root");
            g.0 = roots[find(&parent, r)];
        }
        groups.sort_unstable();
        Groups {
            groups,
            roots,
            merged,
            merged_parts,
        }
    }

    /// Mixes the group of `groups.groups[range]` (one root): sums its members' contents and
    /// fluid fractions, widens it into rings of free cells while the mixture is not physical,
    /// and writes the mixture into every member.
    pub(super) fn mix_group(
        &self,
        groups: &Groups,
        range: std::ops::Range<usize>,
        kind: &mut [CellKind],
        (predicted, solver): (&mut Predicted, &mut FluidSolver),
        out: &mut Writes,
        report: &mut CorrectReport,
    ) -> Result<bool, EmbeddedError> {
        let grid = self.grid;
        let members_of = &groups.groups[range];
        let root = members_of[0].0;
        // The members' contents and fluid fractions, summed apart from their order (a mirror
        // image lists them in another order).
        let mut parts: Vec<([f64; NQ], f64)> = Vec::new();
        // The root's own content.
        parts.push((self.part(kind, predicted, root), self.alpha(root)));
        let merged = &groups.merged;
        let first_merged = merged.partition_point(|m| m.0 < root);
        let n_merged = merged[first_merged..].partition_point(|m| m.0 == root);
        let merged_roots: Vec<usize> = merged[first_merged..first_merged + n_merged]
            .iter()
            .map(|m| m.1)
            .collect();
        for (&m, part) in merged_roots
            .iter()
            .zip(&groups.merged_parts[first_merged..])
        {
            parts.push((*part, self.alpha(m)));
        }
        for &(_, k) in members_of {
            if self.near[k] as usize != root {
                parts.push((self.content[k], self.alpha(self.near[k] as usize)));
            }
        }
        let (mut sum, mut vol) = sum_parts(&parts, self.nvar);
        if vol <= 0.0 && self.at_open_side(root, &merged_roots, members_of) {
            // NOTE: covered cells at an open side that still hold gas: a body moving out of the
            // domain covered them in this step, and the gas between its face and the side left
            // through the side (a rigid box leaving by an outflow side stopped here on a closed
            // pocket). What they hold is counted as leaving; they keep their ghost states.
            let (volume, d) = (grid.cell_volume(), grid.dim);
            out.leaving[0] += sum[0] * volume;
            for a in 0..d {
                out.leaving[1 + a] += sum[1 + a] * volume;
            }
            out.leaving[4] += sum[d + 1] * volume;
            for g in members_of {
                kind[g.1] = CellKind::Mixed;
                out.mixed += 1;
            }
            return Ok(true);
        }
        if vol <= 0.0 || vol.is_nan() {
            return Err(EmbeddedError::ClosedPocket {
                cell: grid.ijk(root),
                content: sum,
            });
        }
        // NOTE: at high Mach numbers the internal energy is a small part of the total, and a
        // small cell's content can hold less of it than its kinetic energy (a deficit the one
        // target cannot cover). The group then takes in rings of free neighbours until the
        // mixture is physical: conservative, and the mixture's internal energy is at least the
        // sum of its members' (the kinetic energy of a sum of momenta is at most the sum of
        // their kinetic energies), so each physical member helps.
        let mut members: Vec<usize> = std::iter::once(root)
            .chain(merged_roots.iter().copied())
            .chain(members_of.iter().map(|g| self.near[g.1] as usize))
            .collect();
        members.sort_unstable();
        members.dedup();
        let mut extra: Vec<usize> = Vec::new();
        // Cells the widening stepped over without taking them in (sorted).
        let mut crossed: Vec<usize> = Vec::new();
        while !self.config.physical(&sum, vol) {
            let ring = self.ring(&members, &extra, &crossed, &groups.roots, &out.claimed);
            if ring.is_empty() {
                // NOTE: no free cell borders the group: a sliver of gas sealed between a body
                // and the domain's boundary or another body within this step (a fragment of
                // the burst without contact pressed onto the wall it passes through stopped at
                // step 2042: a cell 0.08 % open and the covered cell beside it, holding gas at
                // 12.5 km/s, every neighbour covered). The gas would have escaped along the
                // closing gap, as a closed pocket's does (see [`Mixing::covered`]): the next
                // ring is looked for beyond the cells that border the group, which are
                // stepped over and keep what they hold. Test:
                // `embedded_wall_hit::gas_sealed_under_an_arch_pressed_through_a_wall_stays_physical`.
                let next = self.border(&members, &extra, &crossed);
                if next.is_empty() {
                    break;
                }
                crossed.extend(next);
                crossed.sort_unstable();
                continue;
            }
            // (The first `WIDEN_RINGS` rings were read with the groups.)
            predicted.extend(solver, &ring);
            for &q in &ring {
                parts.push((self.part(kind, predicted, q), self.alpha(q)));
            }
            (sum, vol) = sum_parts(&parts, self.nvar);
            extra.extend_from_slice(&ring);
        }
        if !extra.is_empty() {
            report.widened_groups += 1;
            report.widened_cells += extra.len();
            report.widest_group = report.widest_group.max(extra.len());
            for &q in &extra {
                let pos = out.claimed.partition_point(|&x| x < q);
                out.claimed.insert(pos, q);
            }
        }
        let physical = self.config.physical(&sum, vol);
        let mut mixture = [0.0; NQ];
        for q in 0..self.nvar {
            mixture[q] = sum[q] / vol;
        }
        out.writes.push((root as u32, mixture));
        for g in members_of {
            let c = self.near[g.1] as usize;
            if c != root && self.alpha(c) > COVERED_TOLERANCE {
                out.writes.push((c as u32, mixture));
            }
            kind[g.1] = CellKind::Mixed;
            out.mixed += 1;
        }
        for &c in &extra {
            out.writes.push((c as u32, mixture));
            let k = self.slot_of[c] as usize;
            if k > 0 {
                kind[k - 1] = CellKind::Mixed;
            }
        }
        for &m in std::iter::once(&root).chain(&merged_roots) {
            if m != root {
                out.writes.push((m as u32, mixture));
            }
            let km = self.slot_of[m] as usize;
            if km > 0 {
                kind[km - 1] = CellKind::Updated;
            }
        }
        Ok(physical)
    }

    /// Whether a cell of a mixing group (its `root`, `merged` roots and `members`) lies at an
    /// open side of the domain (outflow, characteristic).
    fn at_open_side(&self, root: usize, merged: &[usize], members: &[(usize, usize)]) -> bool {
        let grid = self.grid;
        let boundary = &self.config.boundary;
        let open = |a: usize, side: usize| boundary[a][side].is_open();
        let cells = std::iter::once(root)
            .chain(merged.iter().copied())
            .chain(members.iter().map(|g| self.near[g.1] as usize));
        for c in cells {
            let ijk = grid.ijk(c);
            for a in 0..grid.dim {
                if (ijk[a] == 0 && open(a, 0)) || (ijk[a] + 1 == grid.cells[a] && open(a, 1)) {
                    return true;
                }
            }
        }
        false
    }
}
