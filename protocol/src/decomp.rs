//! The Cartesian process grid of a fluid on K ranks (issue 40): how many blocks each axis is
//! cut into (pure; the scene's validation and the fluid's ranks use the same rule, so thread
//! ranks, MPI ranks and the check of a scene agree).
//!
//! Which axes may be cut: the last two (z and y in 3-D; y and x in 2-D; x in 1-D). The
//! fluid's conserved totals are compensated sums over each plane of the last axis in the
//! one-rank order (x fastest); a block boundary across the second-to-last axis splits each
//! plane into whole rows, whose running sums the blocks continue one after the other, but a
//! cut of x in 3-D would split every row, and no fixed number of exchanges keeps those sums'
//! bits (see `docs/mpi.md`).
//!
//! The choice for K ranks: among the grids `[1, ky, kz]` (3-D) or `[kx, ky, 1]` (2-D) with
//! `kx ky kz = K` whose every block holds at least `depth` cells along each cut axis, the one
//! with the least halo (the sum over the cut axes of a block's cross-section normal to them),
//! and among equal halos the one that cuts the last axis most (slabs when they cost no more).

/// Why a grid cannot be cut as asked.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum DecompError {
    /// The blocks' counts do not multiply to the ranks, or do not fit the grid's axes.
    #[error(
        "{dims:?} gives {product} blocks for {ranks} ranks (one count per axis of the grid, product = ranks)"
    )]
    Product {
        /// The counts given.
        dims: Vec<usize>,
        /// Their product.
        product: usize,
        /// Ranks asked for.
        ranks: usize,
    },
    /// An axis that may not be cut is.
    #[error(
        "{dims:?} cuts axis {axis} of a {dim}-D grid: only the last two axes are cut (the \
         totals' one-rank sums run along the first)"
    )]
    Axis {
        /// The counts given.
        dims: Vec<usize>,
        /// The axis.
        axis: usize,
        /// Dimension of the grid.
        dim: usize,
    },
    /// A block would hold fewer cells along a cut axis than a halo is deep.
    #[error(
        "{dims:?} gives a block {cells_per_block} cells along axis {axis} ({cells} cells in {blocks} \
         blocks), fewer than the {depth} of its halo"
    )]
    TooThin {
        /// The counts given.
        dims: Vec<usize>,
        /// The axis.
        axis: usize,
        /// Cells along it.
        cells: usize,
        /// Blocks along it.
        blocks: usize,
        /// Cells of the smallest block along it.
        cells_per_block: usize,
        /// Depth of a halo.
        depth: usize,
    },
    /// No process grid of K ranks fits the grid.
    #[error(
        "{ranks} ranks: no cut of the {cells:?} cells along the last two axes gives every block \
         {depth} cells along each cut axis"
    )]
    NoFit {
        /// Ranks asked for.
        ranks: usize,
        /// Cells per axis.
        cells: Vec<usize>,
        /// Depth of a halo.
        depth: usize,
    },
}

/// Whether `axis` of a `dim`-D grid may be cut (see the module doc).
pub fn cuttable(dim: usize, axis: usize) -> bool {
    axis < dim && axis + 2 >= dim
}

/// Checks `dims` (one count per axis, 1 beyond `cells.len()`) for `ranks` ranks on a grid of
/// `cells` with halos `depth` cells deep.
pub fn check(
    cells: &[usize],
    ranks: usize,
    dims: [usize; 3],
    depth: usize,
) -> Result<(), DecompError> {
    let dim = cells.len();
    let product: usize = dims.iter().product();
    if product != ranks || dims.iter().skip(dim).any(|&k| k != 1) || dims.contains(&0) {
        return Err(DecompError::Product {
            dims: dims.to_vec(),
            product,
            ranks,
        });
    }
    for axis in 0..dim {
        let k = dims[axis];
        if k == 1 {
            continue;
        }
        if !cuttable(dim, axis) {
            return Err(DecompError::Axis {
                dims: dims.to_vec(),
                axis,
                dim,
            });
        }
        if cells[axis] / k < depth {
            return Err(DecompError::TooThin {
                dims: dims.to_vec(),
                axis,
                cells: cells[axis],
                blocks: k,
                cells_per_block: cells[axis] / k,
                depth,
            });
        }
    }
    Ok(())
}

/// The process grid of `ranks` ranks on a grid of `cells` with halos `depth` cells deep (the
/// rule of the module doc).
pub fn choose(cells: &[usize], ranks: usize, depth: usize) -> Result<[usize; 3], DecompError> {
    let dim = cells.len();
    let (a, b) = if dim >= 2 { (dim - 2, dim - 1) } else { (0, 0) };
    let mut best: Option<(usize, [usize; 3])> = None;
    for ka in (1..=ranks).filter(|k| ranks.is_multiple_of(*k)) {
        let mut dims = [1; 3];
        if a == b {
            if ka != ranks {
                continue;
            }
            dims[a] = ranks;
        } else {
            dims[a] = ka;
            dims[b] = ranks / ka;
        }
        if check(cells, ranks, dims, depth).is_err() {
            continue;
        }
        let block: Vec<usize> = (0..dim).map(|x| cells[x].div_ceil(dims[x])).collect();
        let halo: usize = (0..dim)
            .filter(|&x| dims[x] > 1)
            .map(|x| {
                (0..dim)
                    .filter(|&y| y != x)
                    .map(|y| block[y])
                    .product::<usize>()
            })
            .sum();
        // Among equal halos the last axis cut most: `ka` ascending, so the first one found.
        if best.is_none_or(|(h, _)| halo < h) {
            best = Some((halo, dims));
        }
    }
    best.map(|(_, dims)| dims)
        .ok_or_else(|| DecompError::NoFit {
            ranks,
            cells: cells.to_vec(),
            depth,
        })
}

#[cfg(test)]
mod tests {
    use super::{DecompError, check, choose};

    #[test]
    fn slabs_when_they_cost_no_more_blocks_when_they_do() {
        assert_eq!(choose(&[128, 128, 128], 1, 6), Ok([1, 1, 1]));
        assert_eq!(choose(&[128, 128, 128], 2, 6), Ok([1, 1, 2]));
        // 4 slabs: a halo of 128² per block; 2 × 2: 2 × 128 × 64, the same: slabs.
        assert_eq!(choose(&[128, 128, 128], 4, 6), Ok([1, 1, 4]));
        // 8 slabs: 128²; 2 × 4: 128 × 32 + 128 × 64 = 12288.
        assert_eq!(choose(&[128, 128, 128], 8, 6), Ok([1, 2, 4]));
        // 64 × 48 on 4: 4 × 1 (a halo of 48 cells) beats 2 × 2 (24 + 32) and 1 × 4 (64).
        assert_eq!(choose(&[64, 48], 4, 6), Ok([4, 1, 1]));
        assert_eq!(choose(&[64, 48], 3, 6), Ok([3, 1, 1]));
        assert_eq!(choose(&[60], 3, 6), Ok([3, 1, 1]));
        // 512³ on 512 ranks: 16 × 32 blocks of 512 × 32 × 16.
        assert_eq!(choose(&[512, 512, 512], 512, 6), Ok([1, 16, 32]));
        // Too thin for slabs, blocks fit.
        assert_eq!(choose(&[16, 16, 24], 8, 6), Ok([1, 2, 4]));
        assert!(matches!(
            choose(&[16, 16, 11], 8, 6),
            Err(DecompError::NoFit { .. })
        ));
    }

    #[test]
    fn check_names_what_is_wrong() {
        assert_eq!(check(&[32, 16, 24], 4, [1, 2, 2], 6), Ok(()));
        assert!(matches!(
            check(&[32, 16, 24], 4, [2, 2, 1], 6),
            Err(DecompError::Axis { axis: 0, .. })
        ));
        assert!(matches!(
            check(&[32, 16, 24], 4, [1, 2, 1], 6),
            Err(DecompError::Product { product: 2, .. })
        ));
        assert!(matches!(
            check(&[32, 16, 24], 4, [1, 4, 1], 6),
            Err(DecompError::TooThin {
                axis: 1,
                cells_per_block: 4,
                ..
            })
        ));
        assert!(matches!(
            check(&[64, 48], 4, [2, 1, 2], 6),
            Err(DecompError::Product { .. })
        ));
    }
}
