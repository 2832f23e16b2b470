//! The rings a mixing group widens into ([`Mixing::ring`]), the cells it steps over when no
//! free cell borders it ([`Mixing::border`]), and the groups mixed as one when a group has
//! taken in every cell it could and is still not physical ([`Mixing::as_one`]).

use super::super::COVERED_TOLERANCE;
use super::super::cells::CellKind;
use super::shifted;
use super::{Groups, Mixing, Predicted};

impl Mixing<'_> {
    /// The next ring of free cells around a group's `members`, the `extra` cells it took in and
    /// the cells it `crossed`: holding fluid at both times, and no source, root or cell another
    /// group claimed.
    pub(super) fn ring(
        &self,
        members: &[usize],
        extra: &[usize],
        crossed: &[usize],
        roots: &[usize],
        claimed: &[usize],
    ) -> Vec<usize> {
        let mut ring = self.border(members, extra, crossed);
        ring.retain(|&q| {
            self.alpha(q) > COVERED_TOLERANCE
                && self.old.lambda(q) < 1.0 - COVERED_TOLERANCE
                && self.is_source(q).is_none()
                && roots.binary_search(&q).is_err()
                && claimed.binary_search(&q).is_err()
        });
        ring
    }

    /// The cells bordering a group (its `members`, `extra` and `crossed` cells) that are none of
    /// them, sorted: what a widening that found no free cell steps over.
    pub(super) fn border(
        &self,
        members: &[usize],
        extra: &[usize],
        crossed: &[usize],
    ) -> Vec<usize> {
        let grid = self.grid;
        let mut border: Vec<usize> = Vec::new();
        for &c in members.iter().chain(extra).chain(crossed) {
            let ijk = grid.ijk(c);
            for d in &self.span {
                let Some(q) = shifted(grid, ijk, *d) else {
                    continue;
                };
                let q = grid.index(q[0], q[1], q[2]);
                if members.binary_search(&q).is_err()
                    && !extra.contains(&q)
                    && crossed.binary_search(&q).is_err()
                {
                    border.push(q);
                }
            }
        }
        border.sort_unstable();
        border.dedup();
        border
    }

    /// The `groups` as one group rooted at the smallest root: every other root joins it as a
    /// member (a source) or a merged root (its content read as [`Mixing::merge`] reads it).
    pub(super) fn as_one(
        &self,
        groups: &Groups,
        kind: &[CellKind],
        predicted: &Predicted,
    ) -> Groups {
        let first = groups.groups[0].0;
        let mut merged: Vec<(usize, usize)> =
            groups.merged.iter().map(|&(_, old)| (first, old)).collect();
        let mut representatives: Vec<usize> = groups.groups.iter().map(|g| g.0).collect();
        representatives.dedup();
        for &r in &representatives {
            if r != first && self.is_source(r).is_none() {
                merged.push((first, r));
            }
        }
        merged.sort_unstable();
        merged.dedup();
        let merged_parts = merged
            .iter()
            .map(|m| self.part(kind, predicted, m.1))
            .collect();
        let mut one: Vec<(usize, usize)> = groups.groups.iter().map(|g| (first, g.1)).collect();
        one.sort_unstable();
        Groups {
            groups: one,
            roots: groups.roots.clone(),
            merged,
            merged_parts,
        }
    }
}
