//! [`swept_volumes`]: the signed volume swept by each element between two positions, split among
//! the grid cells (Puscas et al. 2015, paper 000 eq. 12).
//!
//! NOTE: the prism `K_f` of an element is the closed polyhedron of [`crate::cutcell::prism`]
//! between the element at `t^n` and at `t^{n+1}`, its lateral quads split along a canonical
//! diagonal. Two elements sharing an edge pick the same diagonal, so their lateral triangles cancel
//! exactly; summed over a closed surface the prisms then telescope to the surfaces at `t^{n+1}` and
//! `t^n`, and in every cell `Σ_f vol(K_f ∩ C) = (Λ^{n+1} − Λ^n) V` holds to round-off, for any
//! motion (rigid or deforming, any number of cells crossed). The planar split of the lateral quads
//! differs from the bilinear ruled surface of a linear-in-time motion by O(|motion|² · edge) per
//! edge; these differences cancel between neighbours, so only the attribution to elements, never a
//! cell total, depends on that choice. Positive volume: the solid gains it (the element moved along
//! its normal).

use crate::cutcell::measure::triangle_normal;
use crate::cutcell::prism::{PrismScratch, prism_volumes};
use crate::cutcell::surface::Surface;
use crate::grid::Grid;

/// Signed volume swept by one element inside one cell.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SweptEntry {
    /// Linear cell index ([`Grid::index`]).
    pub cell: u32,
    /// Element (triangle or segment).
    pub element: u32,
    /// Signed volume, in m³ (2-D: area, in m²); positive where the solid advances.
    pub volume: f64,
}

/// Swept volumes of all elements; buffers reused between calls.
#[derive(Clone, Debug, Default)]
pub struct SweptVolumes {
    /// One entry per (element, cell) pair with a non-zero volume, by element then cell.
    pub entries: Vec<SweptEntry>,
    /// Elements skipped: an index out of range or a non-finite coordinate at either time.
    pub n_skipped_elements: usize,
    /// Pieces clipped by the last call (prism faces × cells they cross): its cost.
    pub n_pieces: usize,
    prism: PrismScratch,
}

impl SweptVolumes {
    /// Empty buffers.
    pub fn new() -> SweptVolumes {
        SweptVolumes::default()
    }

    /// Total signed swept volume in the domain, in m³ (2-D: m²).
    pub fn total(&self) -> f64 {
        self.entries.iter().map(|e| e.volume).sum()
    }

    /// Adds the swept volume of every entry to `acc[cell]` (`acc.len()` = number of cells).
    pub fn accumulate(&self, acc: &mut [f64]) {
        for e in &self.entries {
            acc[e.cell as usize] += e.volume;
        }
    }
}

/// Asserts that two positions of a surface fit the grid and share their connectivity (a bug
/// in the caller otherwise).
pub(crate) fn check_pair(grid: &Grid, before: &Surface, after: &Surface) {
    assert!(
        before.dim == grid.dim && after.dim == grid.dim,
        "surface dimensions ({}, {}) differ from the grid's {}",
        before.dim,
        after.dim,
        grid.dim
    );
    before.check();
    after.check();
    assert!(
        before.elements == after.elements,
        "swept volumes need the same connectivity at both times"
    );
}

/// Computes the volume swept by every element of `before` moving to `after` (same connectivity,
/// vertices moved), split among the cells of `grid`, into `out`.
///
/// Pure; no allocation once the buffers have grown. Cost O(pieces of the prisms).
pub fn swept_volumes(grid: &Grid, before: &Surface, after: &Surface, out: &mut SweptVolumes) {
    check_pair(grid, before, after);
    out.entries.clear();
    out.n_skipped_elements = 0;
    out.n_pieces = 0;
    for e in 0..before.n_elements() {
        let (Some(t0), Some(t1)) = (before.element(e), after.element(e)) else {
            out.n_skipped_elements += 1;
            continue;
        };
        let (n, top_normal, bottom_normal) = if grid.dim == 3 {
            (3, triangle_normal(&t1), triangle_normal(&t0))
        } else {
            (2, [0.0; 3], [0.0; 3])
        };
        let entries = &mut out.entries;
        out.n_pieces += prism_volumes(
            grid,
            &t1[..n],
            &t0[..n],
            top_normal,
            bottom_normal,
            &mut out.prism,
            |cell, volume| {
                entries.push(SweptEntry {
                    cell,
                    element: e as u32,
                    volume,
                })
            },
        );
    }
}
