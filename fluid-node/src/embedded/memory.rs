//! [`EmbeddedMemory`]: the heap bytes an [`Embedded`] holds, by part (buffer capacities).

use crate::embedded::{Embedded, Loads, SolidFrame};
use crate::fv::FaceTap;
use crate::memory::vec_bytes;

/// Heap bytes held by an [`Embedded`], by part (capacities, so what was allocated, not what the
/// last step used).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct EmbeddedMemory {
    /// Dense outputs of the accepted and the trial geometry: Λ per cell, λ per face and axis.
    pub dense_geometry: usize,
    /// The per-cell slot of the near cells (`u32` per cell).
    pub slot_of: usize,
    /// Near-surface data: the near cells, their saved `U^n`, `p̄` and wall velocities, the kept
    /// face fluxes with their slots and per-pencil offsets, the ghost fills and the scratch of
    /// the correct (with the terms of its order-independent sums).
    pub near_surface: usize,
    /// Surface-sized geometry: sub-faces, cut-cell lists, clipping scratch and swept entries of
    /// both geometries, the accepted frame and the last loads.
    pub sparse_geometry: usize,
    /// On a decomposed grid, the last block geometry this rank computed (the loads' trial
    /// surface on the block and one cell around it, or the correct's block of `F^{n+1}`), kept
    /// for the buffers of the next: Λ and λ over the block, and its sub-faces. Zero on one rank.
    pub block_buffers: usize,
    /// On a decomposed grid, the blocks' shares each geometry was put together from (their
    /// all-gather's buffer, kept for the next). Zero on one rank.
    pub shares: usize,
}

impl EmbeddedMemory {
    /// All parts together.
    pub fn total(&self) -> usize {
        self.dense_geometry
            + self.slot_of
            + self.near_surface
            + self.sparse_geometry
            + self.block_buffers
            + self.shares
    }
}

impl Embedded {
    /// Heap bytes held, by part (see [`EmbeddedMemory`]).
    pub fn memory(&self) -> EmbeddedMemory {
        let (state, near, scratch) = (&self.state, &self.near, &self.scratch);
        let dense_geometry = state.geom.dense_bytes() + scratch.trial.dense_bytes();
        let h = &near.hooks;
        let near_surface = vec_bytes(&near.cells)
            + vec_bytes(&near.saved)
            + h.ghosts.iter().map(vec_bytes).sum::<usize>()
            + h.walls.iter().map(vec_bytes).sum::<usize>()
            + vec_bytes(&h.pressure_cells)
            + h.pressures.iter().map(vec_bytes).sum::<usize>()
            + vec_bytes(&near.wall_pressure)
            + h.taps.iter().map(tap_bytes).sum::<usize>()
            + vec_bytes(&scratch.content)
            + vec_bytes(&scratch.kind)
            + scratch.odd.capacity_bytes()
            + scratch.odd_content.capacity_bytes();
        let sparse_geometry = state.geom.memory_bytes() + scratch.trial.memory_bytes()
            - dense_geometry
            + scratch.swept.memory_bytes()
            + frame_bytes(&state.current)
            + loads_bytes(&state.last_loads);
        EmbeddedMemory {
            dense_geometry,
            slot_of: near.slot_of.memory_bytes(),
            near_surface,
            sparse_geometry,
            block_buffers: scratch.block.memory_bytes(),
            shares: state.geom.shares.capacity_bytes() + scratch.trial.shares.capacity_bytes(),
        }
    }

    /// Cells near the wet surface of the last predict (cut cells of `F^n` dilated by
    /// [`NEAR_RADIUS`](crate::embedded::NEAR_RADIUS) cells), ascending.
    pub fn near_cells(&self) -> &[u32] {
        &self.near.cells
    }
}

fn tap_bytes(tap: &FaceTap) -> usize {
    vec_bytes(&tap.pencil_offsets) + vec_bytes(&tap.positions) + vec_bytes(&tap.flux)
}

fn frame_bytes(f: &SolidFrame) -> usize {
    vec_bytes(&f.position)
        + vec_bytes(&f.velocity)
        + vec_bytes(&f.angular_velocity)
        + vec_bytes(&f.vertices)
        + vec_bytes(&f.elements)
        + vec_bytes(&f.element_particle)
        + vec_bytes(&f.wet)
}

fn loads_bytes(l: &Loads) -> usize {
    vec_bytes(&l.force) + vec_bytes(&l.torque)
}
