//! The grid cut into slabs along its slowest axis (z in 3-D, y in 2-D, x in 1-D), one per rank:
//! which planes a rank owns, its neighbours, and how deep the halo is.
//!
//! Because the slab axis is the slowest one, a rank's cells are one contiguous range of the
//! global x-fastest numbering (global index = local index + `offset × plane`), its pencils along
//! the other axes are a contiguous range of the global pencils, and gathering the slabs in rank
//! order gives the global arrays.
//!
//! Halo depth: a face flux reads `ng` cells on each side, and the a-posteriori positivity fix
//! (`line.rs`, at most [`MAX_FIXES`] rounds) lets a cell's badness change the faces of its
//! neighbours, one cell per round. A rank therefore updates [`MAX_FIXES`] cells of each
//! neighbour's side as well (and throws them away), so that its own boundary faces see the
//! same fixes as on one rank, and it needs `ng + MAX_FIXES` halo planes.

use crate::fv::line::MAX_FIXES;
use crate::fv::state::BoundaryKind;
use crate::grid::Grid;

/// Why a grid cannot be decomposed over the ranks.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SlabError {
    /// A rank would own fewer planes than its halo is deep.
    #[error(
        "fluid.ranks = {ranks}: {cells} cells along axis {axis} give a rank {planes} planes, \
         fewer than the {depth} planes of its halo (at most {} ranks for this grid)",
        (cells / depth).max(1)
    )]
    TooThin {
        /// Ranks asked for.
        ranks: usize,
        /// Cells along the slab axis.
        cells: usize,
        /// The slab axis.
        axis: usize,
        /// Planes of the smallest share.
        planes: usize,
        /// Planes of a halo.
        depth: usize,
    },
}

/// One rank's part of the grid.
#[derive(Clone, Debug, PartialEq)]
pub struct Slab {
    /// The whole grid.
    pub global: Grid,
    /// The rank's own cells (same `dx` bits as `global`; `cells[axis]` its planes).
    pub local: Grid,
    /// The decomposed axis (`dim − 1`).
    pub axis: usize,
    /// First plane of the rank along `axis`.
    pub offset: usize,
    /// This rank.
    pub rank: usize,
    /// Number of ranks.
    pub ranks: usize,
    /// Rank below (`None` at a non-periodic domain face, or on one rank).
    pub lo: Option<usize>,
    /// Rank above.
    pub hi: Option<usize>,
    /// Halo planes exchanged with each neighbour.
    pub depth: usize,
    /// Extra cells of a neighbour's side each pencil along `axis` updates ([`MAX_FIXES`]).
    pub overlap: usize,
}

impl Slab {
    /// Rank `rank` of `ranks` on `global` with `ng` ghost cells and the boundary kinds of the
    /// slab axis. Planes are shared out evenly, the first ranks taking one more when the count
    /// does not divide. Errors when a rank would own fewer planes than the halo is deep.
    pub fn new(
        global: &Grid,
        rank: usize,
        ranks: usize,
        ng: usize,
        boundary: [BoundaryKind; 2],
    ) -> Result<Slab, SlabError> {
        assert!(rank < ranks, "rank {rank} of {ranks}");
        let axis = global.dim - 1;
        let n = global.cells[axis];
        let (share, extra) = (n / ranks, n % ranks);
        let own = share + usize::from(rank < extra);
        let offset = rank * share + rank.min(extra);
        let depth = ng + MAX_FIXES;
        if ranks > 1 && share < depth {
            return Err(SlabError::TooThin {
                ranks,
                cells: n,
                axis,
                planes: share,
                depth,
            });
        }
        let periodic = boundary[0] == BoundaryKind::Periodic;
        let (lo, hi) = if ranks == 1 {
            (None, None)
        } else {
            (
                if rank > 0 {
                    Some(rank - 1)
                } else {
                    periodic.then_some(ranks - 1)
                },
                if rank + 1 < ranks {
                    Some(rank + 1)
                } else {
                    periodic.then_some(0)
                },
            )
        };
        let mut local = global.clone();
        local.cells[axis] = own;
        local.lower[axis] = global.lower[axis] + offset as f64 * global.dx[axis];
        local.upper[axis] = global.lower[axis] + (offset + own) as f64 * global.dx[axis];
        Ok(Slab {
            global: global.clone(),
            local,
            axis,
            offset,
            rank,
            ranks,
            lo,
            hi,
            depth,
            overlap: MAX_FIXES,
        })
    }

    /// The whole grid on one rank.
    pub fn whole(global: &Grid) -> Slab {
        Slab {
            global: global.clone(),
            local: global.clone(),
            axis: global.dim - 1,
            offset: 0,
            rank: 0,
            ranks: 1,
            lo: None,
            hi: None,
            depth: 0,
            overlap: MAX_FIXES,
        }
    }

    /// Cells of one plane normal to the slab axis.
    pub fn plane(&self) -> usize {
        self.global.n_cells() / self.global.cells[self.axis]
    }

    /// Global index of local cell `idx`.
    #[inline]
    pub fn to_global(&self, idx: usize) -> usize {
        idx + self.offset * self.plane()
    }

    /// The range of global cells this rank owns.
    pub fn global_range(&self) -> std::ops::Range<usize> {
        let start = self.to_global(0);
        start..start + self.local.n_cells()
    }

    /// Whether this rank has neighbours (halos are exchanged).
    pub fn decomposed(&self) -> bool {
        self.lo.is_some() || self.hi.is_some()
    }
}
