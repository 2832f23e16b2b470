//! Pure cut-cell geometry of the embedded boundary (no IO, no clock).
//!
//! Given a Cartesian [`Grid`](crate::grid::Grid) (2 or 3 active axes) and the wet surface of the
//! solid (oriented triangles in 3-D, oriented segments of closed loops in 2-D, normals out of the
//! solid), this module computes, exactly up to round-off:
//!
//! 1. [`compute`]: the solid volume fraction Λ of every cell, the solid area fraction λ of every
//!    face, and the sub-faces (element ∩ cell) with area, unit normal and centroid;
//! 2. by construction, the geometric conservation identities (19)–(21) of Puscas et al. 2015
//!    (paper 003): in every cell and along every axis `a`,
//!    `A_a (λ_{a,+} − λ_{a,−}) = − Σ_{sub-faces in the cell} area · n_a`;
//! 3. [`swept_volumes`]: the signed volume swept by every element between two positions, split
//!    among the cells (paper 000 eq. 12), with `Σ swept = (Λ^{n+1} − Λ^n) V` in every cell;
//! 4. [`subface_swept_volumes`]: the same per *sub-face* of the surface at `t^{n+1}` (the prism
//!    of each element ∩ cell, down to its preimage at `t^n`), which for a translation gives every
//!    sub-face exactly `Δt (w · n) area`, as the conservative update of a uniform flow needs;
//! 5. [`stl`]: a small STL (ASCII and binary) and 2-D loop-CSV reader over bytes.
//! 6. [`compute_block`]: Λ, λ and the sub-faces of one block of a decomposed grid and a halo,
//!    from the elements that reach them only, with the bits of [`compute`] on the block's cells
//!    (issue 40, docs/mpi.md); [`BlockSweep`] (no halo): the same without sweeping any row whole,
//!    the running sums along the cut axes passed along the pencils of blocks ([`compute_blocks`]
//!    passes them in one process), what the embedded part calls on a decomposed grid.
//! 7. [`block_part`] and [`CutGeometry::assemble`]: the whole grid's geometry put together, bit
//!    for bit, from every block's own cells (issue 40 item 1, step 4 (a), docs/mpi.md);
//!    [`block_part_shared`] and [`CutGeometry::assemble_held_own`]: the same without the other
//!    ranks' sub-face vertices.
//!
//! # Method
//!
//! Every element is clipped into the cells of an *extended* grid (one unbounded slab beyond each
//! side of the domain) by successive axis-aligned splits (module `clip`), with a fixed tie rule (a point
//! on a grid plane belongs to the cell above it) and canonical edge intersections. From the
//! pieces, row sweeps (module `sweep`) integrate the divergence theorem: λ along each axis from the
//! projected areas (so identity (19)–(21) holds by construction), Λ along x from the moments
//! `∫ (x − x_lo) n_x dA`. Covered cells (Λ = 1) get their value from the x sweep of their row, and
//! their y and z faces from the covered runs of that sweep, so only cut cells and covered cells are
//! visited: the cost is O(P log P + covered cells) for P pieces, and the dense outputs are reset
//! sparsely. The surface must be closed (possibly crossing the domain boundary; several bodies;
//! internal faces carried on both sides cancel); an open surface is reported by
//! [`CutDiagnostics::max_uncut_defect`].
//!
//! Swept volumes: the prism of each element (its two positions plus lateral quads split along a
//! canonical diagonal) is a closed surface, so the same clipping and x sweep give its signed volume
//! in each cell; the prisms of a closed surface telescope, hence identity (3) to round-off for any
//! motion (see [`swept_volumes`]). The sub-face prisms are built by the same code (module
//! `prism`), their bottoms from a second clip that carries each vertex's earlier position.
//!
//! # Conventions
//!
//! - Λ, λ are *solid* fractions (paper 003 notation); the fluid aperture is `1 − λ`.
//! - A face lying exactly in a grid plane belongs to the cell above that plane. Hence a grid face
//!   coinciding with the lower (−e_a) face of a solid has λ = 0 and one coinciding with its upper
//!   face has λ = 1: a measure-zero choice, applied the same way everywhere.
//! - Λ and λ are integrals of the surface's winding number, not clamped: one body leaves
//!   `[0, 1]` by round-off only, overlapping bodies (a penalty contact) count the overlap twice,
//!   so that identities (19)–(21) and (3) hold for them too (the fluid clamps only the fluid it
//!   keeps, `embedded::fluid_part`). A running λ entering an uncut cell is snapped to the nearest
//!   integer within [`SNAP_TOLERANCE`].
//! - 2-D: the grid's z axis is inactive, `face_fraction[2]` is empty, "areas" are lengths and
//!   "volumes" areas.

//! # Example
//!
//! ```
//! use fluid_node::cutcell::{CutGeometry, Surface, compute};
//! use fluid_node::grid::Grid;
//!
//! // The unit square [0.25, 0.75]² (counter-clockwise) on a 4 × 4 grid of [0, 1]².
//! let grid = Grid::new(&[0.0, 0.0], &[1.0, 1.0], &[4, 4]).unwrap();
//! let vertices = [0.25, 0.25, 0.75, 0.25, 0.75, 0.75, 0.25, 0.75];
//! let elements = [0, 1, 1, 2, 2, 3, 3, 0];
//! let surface = Surface { dim: 2, vertices: &vertices, elements: &elements, element_particle: &[] };
//! let mut geometry = CutGeometry::new();
//! compute(&grid, &surface, &mut geometry);
//! assert!((geometry.solid_volume(&grid) - 0.25).abs() < 1e-15);
//! assert_eq!(geometry.solid_fraction[grid.index(1, 1, 0)], 1.0);
//! ```

mod assemble;
mod block;
mod chain;
pub(crate) mod clip;
mod geometry;
mod held_fractions;
mod measure;
mod prism;
pub mod stl;
mod subface_swept;
mod surface;
pub(crate) mod sweep;
mod swept;
#[cfg(test)]
mod tests;
mod written;

pub use assemble::{block_part, block_part_shared};
pub use block::{
    BlockGeometry, CellBox, compute_block, compute_block_cells, compute_block_cells_reusing,
    compute_block_reusing,
};
pub use chain::{BlockSweep, compute_blocks, pass_messages};
pub use geometry::{
    CutDiagnostics, CutGeometry, SNAP_TOLERANCE, SubFace, compute, face_index, n_faces,
};
pub use held_fractions::HeldFractions;
pub use subface_swept::{
    SubfaceSwept, SubfaceSweptEntry, subface_swept_volumes, subface_swept_volumes_of,
};
pub use surface::Surface;
pub use swept::{SweptEntry, SweptVolumes, swept_volumes};
