//! The grid cut into blocks over the ranks (issue 40; slabs along the slowest axis before):
//! a Cartesian process grid `dims` ([`protocol::decomp`]: only the last two axes are cut),
//! which cells a rank owns, its neighbours along each axis, and how deep the halo is.
//!
//! Ranks are numbered x fastest over the process grid (`rank = cx + kx (cy + ky cz)`), so
//! the ranks that share a pencil along an axis come in the order of their blocks along it, and
//! with slabs (only the last axis cut) a rank's cells are one contiguous range of the global
//! x-fastest numbering, as before.
//!
//! Halo depth: a face flux reads `ng` cells on each side, and the a-posteriori positivity fix
//! (`line.rs`, at most [`MAX_FIXES`] rounds) lets a cell's badness change the faces of its
//! neighbours, one cell per round. A rank therefore updates [`MAX_FIXES`] cells of each
//! neighbour's side as well (and throws them away), so that its own boundary faces see the
//! same fixes as on one rank, and it needs `ng + MAX_FIXES` halo planes along each cut axis.

use protocol::decomp::DecompError;

use crate::fv::line::MAX_FIXES;
use crate::fv::state::BoundaryKind;
use crate::grid::Grid;

/// Why a grid cannot be decomposed over the ranks.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SlabError {
    /// The process grid does not fit the grid (`fluid.ranks`, `fluid.decomposition`).
    #[error("fluid.ranks = {ranks}: {source}")]
    Decomposition {
        /// Ranks asked for.
        ranks: usize,
        /// Why.
        source: DecompError,
    },
}

/// One rank's block of the grid.
#[derive(Clone, Debug, PartialEq)]
pub struct Slab {
    /// The whole grid.
    pub global: Grid,
    /// The rank's own cells (same `dx` bits as `global`).
    pub local: Grid,
    /// Blocks along each axis (1 on the axes not cut).
    pub dims: [usize; 3],
    /// This rank's block along each axis.
    pub coords: [usize; 3],
    /// First cell of the rank along each axis.
    pub offset: [usize; 3],
    /// This rank.
    pub rank: usize,
    /// Number of ranks.
    pub ranks: usize,
    /// Rank below along each axis (`None` at a non-periodic domain face, or uncut).
    pub lo: [Option<usize>; 3],
    /// Rank above along each axis.
    pub hi: [Option<usize>; 3],
    /// Halo planes exchanged with each neighbour.
    pub depth: usize,
    /// Extra cells of a neighbour's side each pencil along a cut axis updates ([`MAX_FIXES`]).
    pub overlap: usize,
}

/// First cell and cell count of block `c` of `k` along an axis of `n` cells: shared out
/// evenly, the first blocks taking one more when `k` does not divide `n`.
pub fn share(n: usize, k: usize, c: usize) -> (usize, usize) {
    let (share, extra) = (n / k, n % k);
    (c * share + c.min(extra), share + usize::from(c < extra))
}

impl Slab {
    /// Rank `rank` of the process grid `dims` on `global` with `ng` ghost cells and the
    /// boundary kinds of each axis. Errors when `dims` does not fit ([`protocol::decomp::check`]).
    pub fn new(
        global: &Grid,
        rank: usize,
        dims: [usize; 3],
        ng: usize,
        boundary: [[BoundaryKind; 2]; 3],
    ) -> Result<Slab, SlabError> {
        let ranks: usize = dims.iter().product();
        assert!(rank < ranks, "rank {rank} of {ranks}");
        let depth = ng + MAX_FIXES;
        protocol::decomp::check(&global.cells[..global.dim], ranks, dims, depth)
            .map_err(|source| SlabError::Decomposition { ranks, source })?;
        let coords = coords_of(dims, rank);
        let mut local = global.clone();
        let mut offset = [0; 3];
        let (mut lo, mut hi) = ([None; 3], [None; 3]);
        for a in 0..3 {
            let (first, own) = share(global.cells[a], dims[a], coords[a]);
            offset[a] = first;
            local.cells[a] = own;
            local.lower[a] = global.lower[a] + first as f64 * global.dx[a];
            local.upper[a] = global.lower[a] + (first + own) as f64 * global.dx[a];
            if dims[a] == 1 {
                local.lower[a] = global.lower[a];
                local.upper[a] = global.upper[a];
                continue;
            }
            let periodic = boundary[a][0] == BoundaryKind::Periodic;
            let at = |c: usize| {
                let mut x = coords;
                x[a] = c;
                rank_of(dims, x)
            };
            let c = coords[a];
            lo[a] = if c > 0 {
                Some(at(c - 1))
            } else {
                periodic.then(|| at(dims[a] - 1))
            };
            hi[a] = if c + 1 < dims[a] {
                Some(at(c + 1))
            } else {
                periodic.then(|| at(0))
            };
        }
        Ok(Slab {
            global: global.clone(),
            local,
            dims,
            coords,
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
            dims: [1; 3],
            coords: [0; 3],
            offset: [0; 3],
            rank: 0,
            ranks: 1,
            lo: [None; 3],
            hi: [None; 3],
            depth: 0,
            overlap: MAX_FIXES,
        }
    }

    /// Whether the grid is cut along `axis` (halos are exchanged before a sweep along it).
    pub fn cut(&self, axis: usize) -> bool {
        self.lo[axis].is_some() || self.hi[axis].is_some()
    }

    /// Whether this rank has neighbours (halos are exchanged).
    pub fn decomposed(&self) -> bool {
        (0..3).any(|a| self.cut(a))
    }

    /// Whether only the last axis is cut (slabs: a rank's cells are one contiguous range of
    /// the global numbering, [`Slab::global_range`]).
    pub fn slabs(&self) -> bool {
        let last = self.global.dim - 1;
        (0..3).all(|a| a == last || self.dims[a] == 1)
    }

    /// Global index of local cell `idx`.
    #[inline]
    pub fn to_global(&self, idx: usize) -> usize {
        let l = self.local.ijk(idx);
        let o = self.offset;
        self.global.index(l[0] + o[0], l[1] + o[1], l[2] + o[2])
    }

    /// Local index of global cell `idx`, `None` when another rank owns it.
    #[inline]
    pub fn to_local(&self, idx: usize) -> Option<usize> {
        let g = self.global.ijk(idx);
        let mut l = [0; 3];
        for a in 0..3 {
            l[a] = g[a].checked_sub(self.offset[a])?;
            if l[a] >= self.local.cells[a] {
                return None;
            }
        }
        Some(self.local.index(l[0], l[1], l[2]))
    }

    /// The rank owning global cell `idx`.
    pub fn owner(&self, idx: usize) -> usize {
        let g = self.global.ijk(idx);
        // An axis not cut is block 0 without the divisions of `block_of` (the gathers of the
        // near cells ask for each cell's owner: 1 % of a rank's samples on slabs).
        let coords = std::array::from_fn(|a| match self.dims[a] {
            1 => 0,
            k => block_of(self.global.cells[a], k, g[a]),
        });
        rank_of(self.dims, coords)
    }

    /// The range of global cells this rank owns (slabs only, [`Slab::slabs`]).
    pub fn global_range(&self) -> std::ops::Range<usize> {
        assert!(
            self.slabs(),
            "a block's cells are no range of the global numbering"
        );
        let start = self.to_global(0);
        start..start + self.local.n_cells()
    }

    /// The global pencil along `axis` of this rank's pencil `p` (numbered as
    /// [`crate::fv::sweep::Pencils`] numbers them).
    pub fn global_pencil(&self, axis: usize, p: usize) -> usize {
        let stride: usize = self.local.cells[..axis].iter().product();
        let base = p % stride + (p / stride) * stride * self.local.cells[axis];
        let g = self.to_global(base);
        let gstride: usize = self.global.cells[..axis].iter().product();
        g % gstride + (g / (gstride * self.global.cells[axis])) * gstride
    }

    /// This rank's pencil of the global pencil `gp` along `axis` (`None` when its cells are
    /// another rank's).
    pub fn local_pencil(&self, axis: usize, gp: usize) -> Option<usize> {
        let gstride: usize = self.global.cells[..axis].iter().product();
        let base = gp % gstride + (gp / gstride) * gstride * self.global.cells[axis];
        let mut g = self.global.ijk(base);
        g[axis] = self.offset[axis];
        let l = self.to_local(self.global.index(g[0], g[1], g[2]))?;
        let stride: usize = self.local.cells[..axis].iter().product();
        Some(l % stride + (l / (stride * self.local.cells[axis])) * stride)
    }

    /// First cell and cells per axis of rank `r`'s block.
    pub fn block_of_rank(&self, r: usize) -> ([usize; 3], [usize; 3]) {
        let c = coords_of(self.dims, r);
        let mut first = [0; 3];
        let mut own = [0; 3];
        for a in 0..3 {
            (first[a], own[a]) = share(self.global.cells[a], self.dims[a], c[a]);
        }
        (first, own)
    }
}

/// The block along an axis of `n` cells in `k` blocks holding cell `i` ([`share`]).
fn block_of(n: usize, k: usize, i: usize) -> usize {
    let (share, extra) = (n / k, n % k);
    let big = extra * (share + 1);
    if i < big {
        i / (share + 1)
    } else {
        extra + (i - big) / share
    }
}

/// Block coordinates of `rank` (x fastest).
pub fn coords_of(dims: [usize; 3], rank: usize) -> [usize; 3] {
    [
        rank % dims[0],
        (rank / dims[0]) % dims[1],
        rank / (dims[0] * dims[1]),
    ]
}

/// Rank of block `c` (x fastest).
pub fn rank_of(dims: [usize; 3], c: [usize; 3]) -> usize {
    c[0] + dims[0] * (c[1] + dims[1] * c[2])
}

/// The values (`per` each) of the block of `first`/`own` cells per axis, taken out of the
/// whole grid's array `whole` (x-fastest) into a block array.
pub fn take_block(
    global: &Grid,
    (first, own): ([usize; 3], [usize; 3]),
    per: usize,
    whole: &[f64],
) -> Vec<f64> {
    let mut out = Vec::with_capacity(own.iter().product::<usize>() * per);
    for k in 0..own[2] {
        for j in 0..own[1] {
            let g = global.index(first[0], first[1] + j, first[2] + k) * per;
            out.extend_from_slice(&whole[g..g + own[0] * per]);
        }
    }
    out
}

/// The inverse of [`take_block`]: writes the block array `block` into `whole`.
pub fn put_block(
    global: &Grid,
    (first, own): ([usize; 3], [usize; 3]),
    per: usize,
    block: &[f64],
    whole: &mut [f64],
) {
    let row = own[0] * per;
    for k in 0..own[2] {
        for j in 0..own[1] {
            let g = global.index(first[0], first[1] + j, first[2] + k) * per;
            let l = (j + own[1] * k) * row;
            whole[g..g + row].copy_from_slice(&block[l..l + row]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{Slab, block_of, share};
    use crate::fv::state::BoundaryKind;
    use crate::grid::Grid;

    #[test]
    fn cells_pencils_and_owners_map_both_ways() {
        let global = Grid::new(&[0.0; 3], &[1.0; 3], &[7, 13, 14]).expect("grid");
        let bc = [
            [BoundaryKind::Wall; 2],
            [BoundaryKind::Periodic; 2],
            [BoundaryKind::Wall; 2],
        ];
        let dims = [1, 2, 2];
        let mut owned = vec![usize::MAX; global.n_cells()];
        for r in 0..4 {
            let s = Slab::new(&global, r, dims, 3, bc).expect("block");
            for c in 0..s.local.n_cells() {
                let g = s.to_global(c);
                assert_eq!(s.to_local(g), Some(c));
                assert_eq!(s.owner(g), r);
                assert_eq!(owned[g], usize::MAX, "cell {g} owned twice");
                owned[g] = r;
            }
            for axis in 0..3 {
                let count = s.local.n_cells() / s.local.cells[axis];
                for p in 0..count {
                    assert_eq!(s.local_pencil(axis, s.global_pencil(axis, p)), Some(p));
                }
            }
            // Periodic along y: two blocks are each other's neighbours on both sides.
            assert_eq!(s.lo[1], s.hi[1]);
            assert_eq!(s.lo[0], None);
        }
        assert!(owned.iter().all(|&r| r < 4));
        for n in [12, 13, 14] {
            for k in 1..4 {
                for c in 0..k {
                    let (first, own) = share(n, k, c);
                    for i in first..first + own {
                        assert_eq!(block_of(n, k, i), c);
                    }
                }
            }
        }
    }
}
