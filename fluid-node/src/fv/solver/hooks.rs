//! What a coupled step asks of the split sweeps ([`SplitHooks`]), on one rank or on one block of
//! a decomposed grid: the hooks name cells, pencils and faces of the whole grid, each rank
//! applies the ghost states and vacuum of its own cells and keeps the pressures and fluxes of
//! its own cells and faces, and the fluxes of the faces on each block's low side go to every
//! rank, so that each rank ends with those of every face of its own cells, bit for bit those of
//! one rank (issue 16; issue 40 item 1: every output went to every rank before).
//!
//! Ownership: cell `c` belongs to the rank holding its block; face `m` along a cut axis (the
//! low face of cell `m`) to the rank holding cell `m`, the last face to the last block. A ghost
//! state along a cut axis may mirror a cell of the neighbour (at most `2 ng − 1` cells away,
//! within the `ng + 3` halo planes), so those ghosts are written after an exchange of the halo.

use crate::fv::slab::Slab;
use crate::fv::sweep::{FaceTap, Wall, WallRun};

/// A ghost state written into a cell the solid covers before a sweep: the state of the fluid
/// cell at the mirror position along the sweep line, its velocity reflected about the wall
/// relative to the wall's (paper 003 §2.3, numerics §2.6; see
/// [`mirror`](crate::fv::sweep::mirror)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GhostFill {
    /// The covered cell written (index into the whole grid).
    pub cell: u32,
    /// The fluid cell mirrored into it (index into the whole grid).
    pub mirror_of: u32,
    /// The wall between them (storage axes).
    pub wall: Wall,
}

/// What a coupled step asks of the split sweeps besides the update (paper 003 §3.4 step 1):
/// ghost states in the covered cells before each sweep, the directional pressures `p̄` of the
/// cells near the wet surface and the fluxes of their faces. Only these cells and faces are
/// kept, not the whole grid. Cells, pencils and face positions are those of the whole grid.
#[derive(Clone, Debug, Default)]
pub struct SplitHooks {
    /// Per axis: the ghost states written before the sweep along it, in order (a rank writes
    /// those of its own cells; the others may be left out).
    pub ghosts: [Vec<GhostFill>; 3],
    /// Cells whose `p̄` is recorded, ascending.
    pub pressure_cells: Vec<u32>,
    /// Output: `p̄_axis` \[Pa\] of `pressure_cells[k]` in `pressures[axis][k]`: the pressure of
    /// the state the sweep along `axis` starts from; on a decomposed grid, of this rank's cells
    /// only (0 for the others').
    pub pressures: [Vec<f64>; 3],
    /// Per axis: the faces whose fluxes are kept (pencils of the whole grid, positions along
    /// the whole pencil). On a decomposed grid the ranks' taps may differ: a rank's `flux` holds
    /// those of its own faces and those of the faces on its block's high sides (the high faces
    /// of its cells there, which belong to the block above) that the block above keeps too, 0
    /// for the others.
    pub taps: [FaceTap; 3],
    /// Per axis: the walls thinner than two stencils, where the sweep cuts its pencils, sorted
    /// by pencil and position (on a decomposed grid, those of the rank's pencils that reach its
    /// line or its ghost cells suffice: `embedded::WallHooks::restricted`).
    pub walls: [Vec<WallRun>; 3],
    /// Covered cells that hold no fluid yet beside a wet face (a crack that has just opened,
    /// paper 000 §3.2): set to vacuum (all zero) before each sweep, after the ghosts, so the
    /// faces beside them take the Lax–Friedrichs flux.
    pub vacuum: Vec<u32>,
}

/// This rank's part of the [`SplitHooks`] of the sweep under way (scratch of the solver).
#[derive(Debug, Default)]
pub(super) struct LocalHooks {
    /// Per axis: the kept faces of this rank's pencils, positions along its lines.
    pub(super) taps: [FaceTap; 3],
    /// Per axis: the slot of [`SplitHooks::taps`] of each kept face of `taps`.
    pub(super) slots: [Vec<u32>; 3],
    /// Per axis: the wall runs of this rank's pencils (all of a pencil along a cut axis).
    pub(super) walls: [Vec<WallRun>; 3],
}

impl LocalHooks {
    /// This rank's part of the taps and wall runs of the sweep along `axis`: the pencils of its
    /// block (numbered along its lines), the faces of its cells along them (and the last face
    /// on the last block), and every wall run of those pencils, at positions along the whole
    /// pencil.
    pub(super) fn localize(&mut self, slab: &Slab, axis: usize, tap: &FaceTap, walls: &[WallRun]) {
        let local = &mut self.taps[axis];
        let slots = &mut self.slots[axis];
        let global = &slab.global;
        let count = slab.local.n_cells() / slab.local.cells[axis];
        local.clear(count);
        slots.clear();
        let out = &mut self.walls[axis];
        out.clear();
        let first = slab.offset[axis];
        let below = if slab.lo[axis].is_some() {
            slab.overlap
        } else {
            0
        };
        let start = first as i64 - below as i64;
        let own = slab.local.cells[axis];
        let last = first + own == global.cells[axis];
        for p in 0..count {
            let gp = slab.global_pencil(axis, p);
            if !tap.pencil_offsets.is_empty() {
                let (lo, hi) = (
                    tap.pencil_offsets[gp] as usize,
                    tap.pencil_offsets[gp + 1] as usize,
                );
                let mut kept = 0;
                for slot in lo..hi {
                    let m = tap.positions[slot] as usize;
                    if (first..first + own).contains(&m) || (last && m == first + own) {
                        local.positions.push((m as i64 - start) as u32);
                        slots.push(slot as u32);
                        kept += 1;
                    }
                }
                local.pencil_offsets[p + 1] = local.pencil_offsets[p] + kept;
            }
            let lo = walls.partition_point(|w| (w.pencil as usize) < gp);
            let hi = walls.partition_point(|w| (w.pencil as usize) <= gp);
            out.extend(walls[lo..hi].iter().map(|w| WallRun {
                pencil: p as u32,
                ..*w
            }));
        }
    }
}
