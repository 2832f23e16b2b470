//! The all-gathers that give every rank one rank's results of the parts of the correct and the
//! mixing that each rank does for its own cells (issue 40 item 1, steps 4 and 5; docs/mpi.md):
//! the prism entries, the cell updates, the mixing sources, their roots and contents, and the
//! updated cells' contents when groups merge or widen. Each keeps the one-rank order, so what
//! reads them computes one rank's bits.

use protocol::sum::OddSum;

use super::cells::CellKind;
use super::held::Held;
use super::{Embedded, EmbeddedError};
use crate::cutcell::{
    BlockGeometry, BlockSweep, CellBox, HeldFractions, SubFace, SubfaceSwept, SubfaceSweptEntry,
    Surface, block_part_shared,
};
use crate::fv::FluidSolver;
use crate::fv::comm::HaloExchange;
use crate::fv::euler::NQ;
use crate::fv::slab::rank_of;
use crate::fv::state::copy_cell;

/// Eq. (12–13) in one near cell: its content, and what its weighted fluxes through open domain
/// sides add to the outflow, in the order one thread adds them (a low side's amount negated:
/// adding `−v` is subtracting `v`, bit for bit).
///
/// NOTE: 64 bytes, with the amounts through open sides (few cells have any) on the heap and a
/// failed update's error boxed ([`Updates`]): with those amounts in an array of six sides an
/// update was 288 bytes, and the list of them, collected afresh each step, 304 bytes a near cell
/// of which the pages were faulted in and copied (more than a third of the updates' time on one
/// rank in `embedded_ranks`).
pub(super) struct CellUpdate {
    /// `(1 − Λ^{n+1}) U^n` plus the weighted fluid fluxes.
    pub(super) content: [f64; NQ],
    /// What leaves through each open domain side the cell touches.
    pub(super) leaving: Vec<[f64; NQ]>,
}

/// Near cells' updates by slot ([`Embedded::fluid_fluxes`]), a failed one with its error.
pub(super) type Updates = Vec<(usize, Result<CellUpdate, Box<EmbeddedError>>)>;

impl Embedded {
    /// Whether near slot `k` is a cell of this rank (every slot on one rank).
    pub(super) fn own_slot(&self, k: usize) -> bool {
        self.near.own.contains(k)
    }

    /// The sub-faces of this rank's own cells in `subfaces` (sorted by cell), with their places
    /// there, in order: all of them on one rank; on a block, those from its first cell to its
    /// last (found by bisection) that lie in it, which on a slab (every axis but the last
    /// whole) is all of them.
    ///
    /// NOTE: the loops over a rank's own sub-faces tested every sub-face of the whole surface
    /// for its block (two divisions each) or looked up its near slot.
    pub(super) fn own_subfaces<'a>(
        &'a self,
        subfaces: &'a [SubFace],
    ) -> impl Iterator<Item = (usize, &'a SubFace)> + 'a {
        let grid = &self.config.grid;
        let (range, slab) = match self.config.block {
            None => (0..subfaces.len(), true),
            Some(b) => {
                let first = grid.index(b.lo[0], b.lo[1], b.lo[2]);
                let hi: [usize; 3] = std::array::from_fn(|a| b.hi[a].max(1) - 1);
                let end = grid.index(hi[0], hi[1], hi[2]) + 1;
                let at = |c: usize| subfaces.partition_point(|s| (s.cell as usize) < c);
                let last = grid.dim - 1;
                let slab = (0..last).all(|a| b.lo[a] == 0 && b.hi[a] == grid.cells[a]);
                (at(first)..at(end), slab)
            }
        };
        let block = self.config.block;
        range.map(move |i| (i, &subfaces[i])).filter(move |(_, s)| {
            slab || block.is_none_or(|b| b.contains(grid.ijk(s.cell as usize)))
        })
    }

    /// The contents of every rank's updated near cells on every rank (collective): each rank
    /// sends those of its own, complete with the swept amounts and the solid flux of every
    /// sub-face (each rank pushed the terms of its own cells), and puts the others' in place.
    /// Only updated cells have contents: the solid flux and the swept amounts go to updated
    /// cells only (the sub-faces' cells and those of prisms beyond the domain are marked
    /// updated, and a piece goes to another cell only if that one is updated), and the mixing
    /// reads the contents of updated cells only. Traffic: `dim + 2` values per updated cell.
    /// Only when mixing groups merge or widen, which reads the contents around any group; else
    /// a rank reads the contents of its own cells and of the sources (`gather_roots`).
    pub(super) fn gather_contents(&mut self, solver: &FluidSolver) {
        let nvar = self.config.grid.dim + 2;
        let updated: Vec<usize> = (0..self.near.cells.len())
            .filter(|&k| self.scratch.kind[k] == CellKind::Updated)
            .collect();
        let cells: Vec<u32> = updated.iter().map(|&k| self.near.cells[k]).collect();
        let mut mine = Vec::new();
        for &k in &updated {
            if self.own_slot(k) {
                mine.extend_from_slice(&self.scratch.content[k][..nvar]);
            }
        }
        let all = solver.gather_owned(&cells, mine);
        for (i, &k) in updated.iter().enumerate() {
            copy_cell(
                &mut self.scratch.content[k][..nvar],
                &all[i * nvar..(i + 1) * nvar],
            );
        }
    }
}

/// Every rank's prism entries (the sub-faces of its own cells, `subface_swept_volumes_of`) on
/// every rank (collective), in sub-face order, with the skipped sub-faces and the pieces summed
/// over the ranks: the entries and the count of one rank's `subface_swept_volumes`. Each
/// sub-face is one rank's, and a rank's entries come by sub-face, so a stable sort by sub-face of
/// the ranks' entries in rank order restores the one-rank order. Traffic: 16 bytes per entry.
pub(super) fn gather_swept(solver: &FluidSolver, swept: &mut SubfaceSwept) {
    let mut bytes = Vec::with_capacity(16 + 16 * swept.entries.len());
    bytes.extend((swept.n_skipped_subfaces as u64).to_le_bytes());
    bytes.extend((swept.n_pieces as u64).to_le_bytes());
    for e in &swept.entries {
        bytes.extend(e.subface.to_le_bytes());
        bytes.extend(e.cell.to_le_bytes());
        bytes.extend(e.volume.to_bits().to_le_bytes());
    }
    let u32_at = |b: &[u8], at: usize| u32::from_le_bytes(b[at..at + 4].try_into().expect("4"));
    let u64_at = |b: &[u8], at: usize| u64::from_le_bytes(b[at..at + 8].try_into().expect("8"));
    swept.entries.clear();
    (swept.n_skipped_subfaces, swept.n_pieces) = (0, 0);
    for part in &solver.comm().all_gather(&bytes) {
        swept.n_skipped_subfaces += u64_at(part, 0) as usize;
        swept.n_pieces += u64_at(part, 8) as usize;
        swept
            .entries
            .extend(part[16..].chunks_exact(16).map(|t| SubfaceSweptEntry {
                subface: u32_at(t, 0),
                cell: u32_at(t, 4),
                volume: f64::from_bits(u64_at(t, 8)),
            }));
    }
    swept.entries.sort_by_key(|e| e.subface);
}

/// Every rank's updates of its own near cells ([`Embedded::fluid_fluxes`]) on every rank
/// (collective), by near slot: the list one rank makes, the contents of other ranks' cells
/// left zero (see [`Embedded::gather_contents`]); this rank's own updates are moved in whole. A failed update (the only failure of
/// `cell_update` is [`EmbeddedError::FluxNotKept`]) travels as its slot and is made again by
/// `flux_not_kept`. Traffic per updated cell: 8 bytes, plus `NQ` values per open domain side
/// it touches.
pub(super) fn gather_updates(
    solver: &FluidSolver,
    mine: Updates,
    flux_not_kept: impl Fn(usize) -> EmbeddedError,
) -> Updates {
    const FAILED: u32 = u32::MAX;
    let mut bytes = Vec::with_capacity(mine.len() * (8 + 8 * NQ));
    let mut put = |values: &[f64; NQ]| {
        for v in values {
            bytes.extend(v.to_bits().to_le_bytes());
        }
    };
    let mut heads = Vec::with_capacity(mine.len());
    for (k, update) in &mine {
        match update {
            Ok(u) => {
                heads.push((*k as u32, u.leaving.len() as u32));
                for v in &u.leaving {
                    put(v);
                }
            }
            Err(_) => heads.push((*k as u32, FAILED)),
        }
    }
    let mut head_bytes = Vec::with_capacity(8 + 8 * heads.len());
    head_bytes.extend((heads.len() as u64).to_le_bytes());
    for (k, n) in heads {
        head_bytes.extend(k.to_le_bytes());
        head_bytes.extend(n.to_le_bytes());
    }
    head_bytes.append(&mut bytes);
    let u32_at = |b: &[u8], at: usize| u32::from_le_bytes(b[at..at + 4].try_into().expect("4"));
    let f64_at = |b: &[u8], at: usize| {
        f64::from_bits(u64::from_le_bytes(b[at..at + 8].try_into().expect("8")))
    };
    let values =
        |b: &[u8], at: usize| -> [f64; NQ] { std::array::from_fn(|q| f64_at(b, at + 8 * q)) };
    let rank = solver.slab().rank;
    let mut all = Vec::new();
    for (r, part) in solver.comm().all_gather(&head_bytes).iter().enumerate() {
        if r == rank {
            continue;
        }
        let n = u64::from_le_bytes(part[..8].try_into().expect("8")) as usize;
        let mut at = 8 + 8 * n;
        for i in 0..n {
            let (k, n_leaving) = (u32_at(part, 8 + 8 * i) as usize, u32_at(part, 12 + 8 * i));
            if n_leaving == FAILED {
                all.push((k, Err(Box::new(flux_not_kept(k)))));
                continue;
            }
            let mut u = CellUpdate {
                content: [0.0; NQ],
                leaving: Vec::new(),
            };
            for _ in 0..n_leaving {
                u.leaving.push(values(part, at));
                at += 8 * NQ;
            }
            all.push((k, Ok(u)));
        }
    }
    // (This rank's own updates keep their contents.)
    all.extend(mine);
    // NOTE: a slot is updated by one rank, so any sort by slot gives this order. The list is
    // the ranks' own lists one after the other, each by slot; the stable sort merges those
    // runs, where the unstable one sorted them afresh, moving each update (then over 300
    // bytes) about log n times.
    all.sort_by_key(|u| u.0);
    all
}

/// Every rank's solid-flux terms ([`Embedded::solid_flux`](super::Embedded), the sub-faces of its
/// own cells) on every rank (collective): `sum` gets every rank's load terms, in rank order (an
/// [`OddSum`]: the sums do not depend on it), and `by_subface` every rank's `(sub-face index,
/// [work, impulse])`, sorted by the index: the sub-faces' order, in which one rank sums them.
/// Traffic: 12 bytes per load term, `4 + 8 (dim + 1)` per wet sub-face.
pub(super) fn gather_solid_flux(
    solver: &FluidSolver,
    dim: usize,
    by_subface: &mut Vec<(u32, [f64; 4])>,
    sum: &mut OddSum,
) {
    let size = 4 + 8 * (dim + 1);
    let terms = sum.terms();
    let mut bytes = Vec::with_capacity(8 + size * by_subface.len() + 12 * terms.len());
    bytes.extend((by_subface.len() as u64).to_le_bytes());
    for (i, exchange) in by_subface.iter() {
        bytes.extend(i.to_le_bytes());
        for v in &exchange[..dim + 1] {
            bytes.extend(v.to_bits().to_le_bytes());
        }
    }
    for &(slot, value) in terms {
        bytes.extend(slot.to_le_bytes());
        bytes.extend(value.to_bits().to_le_bytes());
    }
    by_subface.clear();
    sum.clear();
    let u32_at = |b: &[u8], at: usize| u32::from_le_bytes(b[at..at + 4].try_into().expect("4"));
    let f64_at = |b: &[u8], at: usize| {
        f64::from_bits(u64::from_le_bytes(b[at..at + 8].try_into().expect("8")))
    };
    for part in &solver.comm().all_gather(&bytes) {
        let n = u64::from_le_bytes(part[..8].try_into().expect("8")) as usize;
        let (exchange, terms) = part[8..].split_at(n * size);
        by_subface.extend(exchange.chunks_exact(size).map(|t| {
            let mut e = [0.0; 4];
            for (q, v) in e[..dim + 1].iter_mut().enumerate() {
                *v = f64_at(t, 4 + 8 * q);
            }
            (u32_at(t, 0), e)
        }));
        sum.extend(terms.chunks_exact(12).map(|t| (u32_at(t, 0), f64_at(t, 4))));
    }
    // Each sub-face is one rank's, and each rank's come in the sub-faces' order: a stable
    // sort merges the runs.
    by_subface.sort_by_key(|e| e.0);
}

/// Every rank's mixing sources (near slots, ascending), uncovered cells' count and largest
/// residue dropped, from each rank's `mine`, `uncovered` and `dropped` for its own cells, on
/// every rank (collective): the sources one rank finds, their sum and their largest (the
/// largest of the ranks' largest is the largest of all, bit for bit). Traffic: 4 bytes per
/// source.
pub(super) fn gather_sources(
    solver: &FluidSolver,
    mine: &[usize],
    uncovered: usize,
    dropped: f64,
) -> (Vec<usize>, usize, f64) {
    let mut bytes = Vec::with_capacity(16 + 4 * mine.len());
    bytes.extend((uncovered as u64).to_le_bytes());
    bytes.extend(dropped.to_bits().to_le_bytes());
    for &k in mine {
        bytes.extend((k as u32).to_le_bytes());
    }
    let u64_at = |b: &[u8], at: usize| u64::from_le_bytes(b[at..at + 8].try_into().expect("8"));
    let (mut all, mut uncovered, mut dropped) = (Vec::new(), 0, dropped);
    for part in &solver.comm().all_gather(&bytes) {
        uncovered += u64_at(part, 0) as usize;
        dropped = dropped.max(f64::from_bits(u64_at(part, 8)));
        all.extend(
            (part[16..].chunks_exact(4))
                .map(|p| u32::from_le_bytes(p.try_into().expect("4")) as usize),
        );
    }
    all.sort_unstable();
    (all, uncovered, dropped)
}

/// Every rank's `(root, source slot)` pairs on every rank (collective), in rank order: each
/// rank walked from its own sources, so together they are the pairs one rank makes, in another
/// order (the caller sorts them). Each source's content (its first `nvar` values) comes with
/// it, into `content`: the sum of a group on its root's rank reads its members' contents
/// (`Mixing::mixtures`). Traffic: 8 bytes and `nvar` values per source.
pub(super) fn gather_roots(
    solver: &FluidSolver,
    mine: &[(usize, usize)],
    content: &mut [[f64; NQ]],
    nvar: usize,
) -> Vec<(usize, usize)> {
    let size = 8 + 8 * nvar;
    let mut bytes = Vec::with_capacity(size * mine.len());
    for &(root, k) in mine {
        bytes.extend((root as u32).to_le_bytes());
        bytes.extend((k as u32).to_le_bytes());
        for v in &content[k][..nvar] {
            bytes.extend(v.to_bits().to_le_bytes());
        }
    }
    let u32_at = |b: &[u8], at: usize| u32::from_le_bytes(b[at..at + 4].try_into().expect("4"));
    let f64_at = |b: &[u8], at: usize| {
        f64::from_bits(u64::from_le_bytes(b[at..at + 8].try_into().expect("8")))
    };
    let mut all = Vec::new();
    for part in &solver.comm().all_gather(&bytes) {
        for p in part.chunks_exact(size) {
            let (root, k) = (u32_at(p, 0) as usize, u32_at(p, 4) as usize);
            for q in 0..nvar {
                content[k][q] = f64_at(p, 8 + 8 * q);
            }
            all.push((root, k));
        }
    }
    all
}

/// The geometry of `surface` as a rank of `block` holds it, into `geom`, Λ and λ dense in
/// `held` (buffers reused). Collective: each rank computes the geometry of its own block only
/// ([`chained_block_part`]: no halo, the running sums of the cut axes passed along the pencils
/// of blocks), and one all-gather of every block's share gives every rank the whole grid's
/// sub-faces and cut cells, and Λ and λ dense in `held` and as runs elsewhere
/// (`CutGeometry::assemble_held_own`): the bits of one rank's `compute`, read anywhere. The
/// block's geometry is computed into the buffers of `reuse` and left there.
pub(super) fn assemble_by_block(
    geom: &mut Held,
    reuse: &mut BlockGeometry,
    solver: &FluidSolver,
    surface: &Surface,
    block: CellBox,
    held: CellBox,
) {
    let grid = &solver.slab().global;
    let (part, vertices) = chained_block_part(solver, surface, block, reuse);
    solver.comm().all_gather_into(&part, &mut geom.shares);
    let parts: Vec<&[u8]> = geom.shares.iter().collect();
    let fractions = (geom.fractions).get_or_insert_with(|| HeldFractions::new(grid, held));
    let own = (solver.comm().rank(), &vertices[..]);
    solver.install(|| geom.cut.assemble_held_own(grid, &parts, fractions, own));
}

/// The geometry of `surface` on this rank's `block` (no halo), with the whole grid's bits on
/// every cell and face of the block, as its share for [`crate::cutcell::CutGeometry::assemble`]
/// (collective along the pencils of blocks): the block's local part on the fluid's pool, then,
/// for each cut axis, the running sums passed up the pencil of blocks along it in rank order and
/// `above` passed down (`cutcell::BlockSweep`, module `chain`). No rank clips an element beyond
/// its cells and one cell around them. Traffic: 8 bytes per row whose cut cells cross a block
/// boundary, up, and as many down. The block's geometry is computed into the buffers of
/// `reuse` and left there.
pub(super) fn chained_block_part(
    solver: &FluidSolver,
    surface: &Surface,
    block: CellBox,
    reuse: &mut BlockGeometry,
) -> (Vec<u8>, Vec<[f64; 3]>) {
    let slab = solver.slab();
    let grid = &slab.global;
    debug_assert_eq!(block, CellBox::of_rank(grid, slab.dims, slab.rank));
    let buffers = std::mem::take(reuse);
    let mut sweep = solver.install(|| BlockSweep::reusing(grid, surface, block, buffers));
    let neighbour = |axis: usize, up: bool| {
        let c = slab.coords[axis];
        let to = if up {
            (c + 1 < slab.dims[axis]).then_some(c + 1)?
        } else {
            c.checked_sub(1)?
        };
        let mut coords = slab.coords;
        coords[axis] = to;
        Some(rank_of(slab.dims, coords))
    };
    let comm = solver.comm();
    let transfer = |axis: usize, up: bool, buf: &mut [f64], send: Option<&[f64]>| {
        // `up`: receive from below, send above; else receive from above, send below.
        let (from, to) = (neighbour(axis, !up), neighbour(axis, up));
        let from = from.filter(|_| !buf.is_empty());
        let to = to.zip(send).filter(|(_, m)| !m.is_empty());
        if from.is_none() && to.is_none() {
            return;
        }
        let (mut from_lo, mut from_hi, mut to_lo, mut to_hi) = (None, None, None, None);
        match up {
            true => (from_lo, to_hi) = (from.map(|r| (r, buf)), to),
            false => (from_hi, to_lo) = (from.map(|r| (r, buf)), to),
        }
        comm.exchange_halo(HaloExchange {
            to_lo,
            to_hi,
            from_lo,
            from_hi,
        });
    };
    for axis in 1..grid.dim {
        // The rows that need nothing from below first, while the block below sweeps its own.
        sweep.up_first(axis);
        let mut from_below = vec![0.0; sweep.up_in(axis)];
        transfer(axis, true, &mut from_below, None);
        let up = sweep.up_rest(axis, &from_below);
        transfer(axis, true, &mut [], Some(&up));
        let mut from_above = vec![0.0; sweep.down_in(axis)];
        transfer(axis, false, &mut from_above, None);
        let down = sweep.down(axis, &from_above);
        transfer(axis, false, &mut [], Some(&down));
    }
    *reuse = sweep.finish();
    block_part_shared(grid, reuse)
}
