//! The Cartesian grid: 1, 2 or 3 active axes chosen at run time.
//!
//! Cells are numbered with x fastest: `idx = i + n_x (j + n_y k)`. Inactive axes have one cell
//! and unit width, so a 2-D grid holds `n_x n_y` cells and its "volume" is an area.

/// A uniform Cartesian grid.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    /// Number of active axes (1, 2 or 3).
    pub dim: usize,
    /// Lower corner \[m\] (inactive axes: 0).
    pub lower: [f64; 3],
    /// Upper corner \[m\] (inactive axes: 1).
    pub upper: [f64; 3],
    /// Cells per axis (inactive axes: 1).
    pub cells: [usize; 3],
    /// Cell width per axis \[m\] (inactive axes: 1).
    pub dx: [f64; 3],
}

/// Why a grid cannot be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum GridError {
    /// Not 1 to 3 axes, or corners and counts of different lengths.
    #[error(
        "grid needs 1 to 3 axes with matching lengths, got lower {lower:?}, upper {upper:?}, \
         cells {cells:?}"
    )]
    Axes {
        /// Lower corner given \[m\].
        lower: Vec<f64>,
        /// Upper corner given \[m\].
        upper: Vec<f64>,
        /// Cells per axis given.
        cells: Vec<usize>,
    },
    /// An axis with `upper <= lower` (or NaN) or no cells.
    #[error(
        "axis {axis}: need upper > lower and cells > 0, got {lower} .. {upper} with {cells} cells"
    )]
    Axis {
        /// The axis (0, 1, 2).
        axis: usize,
        /// Its lower bound \[m\].
        lower: f64,
        /// Its upper bound \[m\].
        upper: f64,
        /// Its cell count.
        cells: usize,
    },
}

impl Grid {
    /// Builds a grid from per-axis corners and counts (all of the same length 1, 2 or 3).
    pub fn new(lower: &[f64], upper: &[f64], cells: &[usize]) -> Result<Grid, GridError> {
        let dim = lower.len();
        if !(1..=3).contains(&dim) || upper.len() != dim || cells.len() != dim {
            return Err(GridError::Axes {
                lower: lower.to_vec(),
                upper: upper.to_vec(),
                cells: cells.to_vec(),
            });
        }
        let mut grid = Grid {
            dim,
            lower: [0.0; 3],
            upper: [1.0; 3],
            cells: [1; 3],
            dx: [1.0; 3],
        };
        for axis in 0..dim {
            if upper[axis].partial_cmp(&lower[axis]) != Some(std::cmp::Ordering::Greater)
                || cells[axis] == 0
            {
                return Err(GridError::Axis {
                    axis,
                    lower: lower[axis],
                    upper: upper[axis],
                    cells: cells[axis],
                });
            }
            grid.lower[axis] = lower[axis];
            grid.upper[axis] = upper[axis];
            grid.cells[axis] = cells[axis];
            grid.dx[axis] = (upper[axis] - lower[axis]) / cells[axis] as f64;
        }
        Ok(grid)
    }

    /// Total number of cells.
    pub fn n_cells(&self) -> usize {
        self.cells[0] * self.cells[1] * self.cells[2]
    }

    /// Linear index of cell `(i, j, k)`.
    #[inline]
    pub fn index(&self, i: usize, j: usize, k: usize) -> usize {
        debug_assert!(i < self.cells[0] && j < self.cells[1] && k < self.cells[2]);
        i + self.cells[0] * (j + self.cells[1] * k)
    }

    /// Inverse of [`Grid::index`].
    #[inline]
    pub fn ijk(&self, idx: usize) -> [usize; 3] {
        let i = idx % self.cells[0];
        let rest = idx / self.cells[0];
        [i, rest % self.cells[1], rest / self.cells[1]]
    }

    /// Coordinate along `axis` at `s` cell widths from the lower corner (`s` in `0..=n`, a
    /// multiple of 1/2: a grid plane or a cell centre) \[m\].
    ///
    /// Measured from the nearer corner (the middle is the corners' mean), so that on a grid
    /// symmetric about 0 (`lower = -upper`) mirrored positions are exact negatives,
    /// `coord(n - s) == -coord(s)` bit for bit: a symmetric scene then stays symmetric to the
    /// last bit instead of being seeded with the round-off of `lower + s dx`.
    #[inline]
    pub fn coord(&self, axis: usize, s: f64) -> f64 {
        let n = self.cells[axis] as f64;
        if 2.0 * s < n {
            self.lower[axis] + s * self.dx[axis]
        } else if 2.0 * s > n {
            self.upper[axis] - (n - s) * self.dx[axis]
        } else {
            0.5 * (self.lower[axis] + self.upper[axis])
        }
    }

    /// Centre of cell `(i, j, k)`; inactive coordinates are 0.
    pub fn cell_center(&self, ijk: [usize; 3]) -> [f64; 3] {
        let mut x = [0.0; 3];
        for axis in 0..self.dim {
            x[axis] = self.coord(axis, ijk[axis] as f64 + 0.5);
        }
        x
    }

    /// Volume of one cell (area in 2-D, length in 1-D).
    pub fn cell_volume(&self) -> f64 {
        self.dx[..self.dim].iter().product()
    }

    /// The cell holding point `x` (only the first `dim` coordinates are read), if inside.
    pub fn locate(&self, x: &[f64]) -> Option<[usize; 3]> {
        let mut ijk = [0; 3];
        for axis in 0..self.dim {
            let s = (x[axis] - self.lower[axis]) / self.dx[axis];
            if !(s >= 0.0 && s <= self.cells[axis] as f64) {
                return None;
            }
            ijk[axis] = (s.floor() as usize).min(self.cells[axis] - 1);
        }
        Some(ijk)
    }
}

#[cfg(test)]
mod tests {
    use super::Grid;

    #[test]
    fn a_grid_centred_on_zero_has_mirror_exact_coordinates() {
        let g = Grid::new(&[0.0, -7.5], &[30.0, 7.5], &[800, 400]).unwrap();
        let n = 400;
        for half in 0..=2 * n {
            let s = half as f64 / 2.0;
            assert_eq!(g.coord(1, n as f64 - s), -g.coord(1, s), "s = {s}");
        }
        assert_eq!(g.coord(1, 200.0), 0.0);
        assert_eq!(g.coord(1, 0.0), -7.5);
        assert_eq!(g.coord(1, 400.0), 7.5);
        // `lower + s dx` is not mirror-exact there: the reason for measuring from the nearer end.
        let plain = |s: f64| g.lower[1] + s * g.dx[1];
        assert!((0..=2 * n).any(|h| {
            let s = h as f64 / 2.0;
            plain(n as f64 - s) != -plain(s)
        }));
    }
}
