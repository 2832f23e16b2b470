//! [`BlockSweep`]: the geometry of one block of a decomposed grid (no halo) with the bits of the
//! whole grid's [`crate::cutcell::compute`], from the elements that reach the block only and two
//! small messages per cut axis along the pencil of blocks (issue 40, docs/mpi.md step 1, "What
//! would fix that").
//!
//! λ along a cut axis is a running sum from the row's lower end. Along a row, the whole grid's
//! sweep ([`crate::cutcell::sweep`]) gathers clusters of adjacent cut cells; a cluster's faces
//! take the running sum from below (`below`), and, when its exit is snapped to an integer, its
//! inner faces in the grid's upper half take the sum from the exit down (`above`; the mean of
//! both on the middle face). A cluster that crosses a block boundary needs what lies beyond:
//! - up (blocks in ascending order along the axis): the running sum on the block's lower face,
//!   where its first cell is cut: the sweep's state there, from the block below
//!   ([`BlockSweep::up`]);
//! - down (then in descending order): `above` on the block's upper face, where a cluster crosses
//!   it, from the block above (NaN where that cluster's exit was not snapped: no `above` there)
//!   ([`BlockSweep::down`]).
//!
//! Every block continues the same operations, in the same order, from the same values as the
//! whole row's sweep, so every face of its cells gets the whole grid's bits, and no block clips
//! an element beyond its cells and one cell around them. Where a row's first cell in the block is
//! uncut, the sweep enters it with that cell's Λ (the closed surface's winding number, the value
//! the whole row's sweep snaps to there), as [`crate::cutcell::compute_block`] does.
//!
//! The messages of a boundary list the rows in ascending order: up, those whose cell just above
//! the boundary is cut; down, those whose cells on both sides of it are cut. Both blocks see those
//! cells (each clips the pieces of one cell beyond its own), so both know the count.

use protocol::sum::odd_sum;

use crate::cutcell::block::{
    BlockGeometry, CellBox, CoveredRun, block_cells, fill_covered_faces, record,
};
use crate::cutcell::geometry::{SNAP_TOLERANCE, face_area, other_axes, row_ijk};
use crate::cutcell::surface::Surface;
use crate::cutcell::sweep::sort_records_in_rows;
use crate::grid::Grid;

/// One row of a cut axis with cut cells in the block (or on its boundary).
#[derive(Clone, Debug)]
struct ChainRow {
    row: u64,
    /// `(position, summed flux)` of the cut cells in `p0..hi` (ascending).
    cells: Vec<(i32, f64)>,
    /// The cell below the block's first one is cut (a cluster may come from below).
    below_cut: bool,
    /// The cell above the block's last one is cut (`hi < n`).
    above_cut: bool,
    /// The sweep's state entering position `p0`.
    entry: f64,
    /// Whether the faces are written (the row needs nothing from above).
    done: bool,
    /// `above` on the block's lower face (NaN where none), once known.
    above_lo: f64,
    /// The sweep's state on the block's upper face, once the up pass has swept the row.
    up_state: f64,
}

/// What a cut axis of the block has to finish.
#[derive(Clone, Debug, Default)]
struct AxisChain {
    rows: Vec<ChainRow>,
}

/// A block's geometry in the making: the local part done, the cut axes' rows to finish with the
/// messages of the pencil of blocks along each cut axis (module docs). Call, for each cut axis
/// `1..dim` in turn, [`BlockSweep::up`] in ascending block order along it, then
/// [`BlockSweep::down`] in descending order, then [`BlockSweep::finish`].
#[derive(Clone, Debug)]
pub struct BlockSweep {
    geom: BlockGeometry,
    covered_runs: Vec<CoveredRun>,
    axes: Vec<AxisChain>,
    area: [f64; 3],
    n: [i32; 3],
    grid: Grid,
}

impl BlockSweep {
    /// The local part of block `block`'s geometry (no halo): clipping, Λ, λ along x, the
    /// sub-faces, and the rows of each cut axis with their cut cells. Pure.
    pub fn new(grid: &Grid, surface: &Surface, block: CellBox) -> BlockSweep {
        BlockSweep::reusing(grid, surface, block, BlockGeometry::default())
    }

    /// [`BlockSweep::new`] into the buffers of `reuse`, an earlier block geometry of any block
    /// and window (or the default; what [`BlockSweep::finish`] returns): the same bits.
    pub fn reusing(
        grid: &Grid,
        surface: &Surface,
        block: CellBox,
        reuse: BlockGeometry,
    ) -> BlockSweep {
        let (geom, pieces, covered_runs) = block_cells(grid, surface, block, 0, true, reuse);
        let mut axes = vec![AxisChain::default(); 3];
        for (axis, chain) in axes.iter_mut().enumerate().take(grid.dim).skip(1) {
            chain.rows = axis_rows(grid, axis, &geom, &pieces);
        }
        BlockSweep {
            geom,
            covered_runs,
            axes,
            area: std::array::from_fn(|a| {
                if a < grid.dim {
                    face_area(grid, a)
                } else {
                    0.0
                }
            }),
            n: std::array::from_fn(|a| grid.cells[a] as i32),
            grid: grid.clone(),
        }
    }

    /// Rows of `axis` the message from the block below carries (its length).
    pub fn up_in(&self, axis: usize) -> usize {
        let rows = &self.axes[axis].rows;
        rows.iter()
            .filter(|r| self.entered_from_below(axis, r))
            .count()
    }

    /// Whether the message from the block below enters row `r` of `axis`: the block is not the
    /// grid's lowest along `axis` and the row's first cell in it is cut.
    fn entered_from_below(&self, axis: usize, r: &ChainRow) -> bool {
        let lo = self.geom.block.lo[axis] as i32;
        lo > 0 && r.cells.first().is_some_and(|c| c.0 == lo)
    }

    /// Rows of `axis` the message from the block above carries (its length).
    pub fn down_in(&self, axis: usize) -> usize {
        self.axes[axis]
            .rows
            .iter()
            .filter(|r| self.crosses_top(axis, r))
            .count()
    }

    /// The up pass of `axis`: `from_below` is the message of the block below (empty at the
    /// grid's lower end, else [`BlockSweep::up_in`] values); returns the message to the block
    /// above (the sweep's state on the block's upper face, for each row whose cell above it is
    /// cut). Writes the faces of the rows that need nothing from above.
    /// [`BlockSweep::up_first`] then [`BlockSweep::up_rest`].
    pub fn up(&mut self, axis: usize, from_below: &[f64]) -> Vec<f64> {
        self.up_first(axis);
        self.up_rest(axis, from_below)
    }

    /// The rows of [`BlockSweep::up`] that the message from below does not enter (their entry
    /// is Λ of their first cell in the block, or 0 at the grid's lower end): a rank sweeps them
    /// before it waits for that message, while the block below sweeps its own.
    ///
    /// NOTE: a row's sweep reads only its own entry and cells, so the rows may be swept in any
    /// order with the same bits. Entered all after the message, the two ranks of `1 × 1 × 2`
    /// swept their rows one after the other: 5.4–5.8 ms of a rank's step at 128³ in the passes,
    /// against 6.5–6.8 ms for the block's whole local part.
    pub fn up_first(&mut self, axis: usize) {
        let lo = self.geom.block.lo[axis];
        let mut rows = std::mem::take(&mut self.axes[axis].rows);
        for r in &mut rows {
            if self.entered_from_below(axis, r) {
                continue;
            }
            r.entry = if lo == 0 {
                0.0
            } else {
                let mut at = row_ijk(&self.grid, axis, r.row, lo as i32);
                at[axis] = lo;
                self.geom.solid_fraction_at(at)
            };
            self.sweep_up(axis, r);
        }
        self.axes[axis].rows = rows;
    }

    /// The rest of [`BlockSweep::up`] after [`BlockSweep::up_first`]: sweeps the rows
    /// `from_below` enters and returns the message to the block above, in the rows' order.
    pub fn up_rest(&mut self, axis: usize, from_below: &[f64]) -> Vec<f64> {
        assert_eq!(
            from_below.len(),
            self.up_in(axis),
            "up message of axis {axis}"
        );
        let mut incoming = from_below.iter();
        let mut rows = std::mem::take(&mut self.axes[axis].rows);
        for r in &mut rows {
            if self.entered_from_below(axis, r) {
                r.entry = *incoming.next().expect("counted");
                self.sweep_up(axis, r);
            }
        }
        let out = rows
            .iter()
            .filter(|r| r.above_cut)
            .map(|r| r.up_state)
            .collect();
        self.axes[axis].rows = rows;
        out
    }

    /// The up pass's sweep of row `r` from its entry.
    fn sweep_up(&mut self, axis: usize, r: &mut ChainRow) {
        let crosses = self.crosses_top(axis, r);
        let (state, above_lo) = self.sweep_row(axis, r, None, !crosses);
        (r.done, r.above_lo, r.up_state) = (!crosses, above_lo, state);
    }

    /// The down pass of `axis`: `from_above` is the message of the block above (empty at the
    /// grid's upper end, else [`BlockSweep::down_in`] values); writes the remaining faces and
    /// returns the message to the block below (`above` on the block's lower face, NaN where
    /// none, for each row whose cells on both sides of that face are cut).
    pub fn down(&mut self, axis: usize, from_above: &[f64]) -> Vec<f64> {
        assert_eq!(
            from_above.len(),
            self.down_in(axis),
            "down message of axis {axis}"
        );
        let mut incoming = from_above.iter();
        let mut rows = std::mem::take(&mut self.axes[axis].rows);
        let mut out = Vec::new();
        for r in &mut rows {
            if !r.done {
                let top = *incoming.next().expect("counted");
                r.above_lo = self.sweep_row(axis, r, Some(top), true).1;
                r.done = true;
            }
            if r.below_cut && self.entered_from_below(axis, r) {
                out.push(r.above_lo);
            }
        }
        self.axes[axis].rows = rows;
        out
    }

    /// The block's geometry (after every cut axis's passes).
    pub fn finish(mut self) -> BlockGeometry {
        fill_covered_faces(&self.grid, &self.covered_runs, &mut self.geom);
        self.geom
    }

    /// Whether a cluster of `r` crosses the block's upper face (cells on both sides cut).
    fn crosses_top(&self, axis: usize, r: &ChainRow) -> bool {
        let hi = self.geom.block.hi[axis] as i32;
        r.above_cut && r.cells.last().is_some_and(|c| c.0 == hi - 1)
    }

    /// Sweeps row `r` of `axis` over the block from its entry, as
    /// [`crate::cutcell::sweep::sweep_rows`] does the whole row: returns the state on the
    /// block's upper face and `above` on its lower face (NaN where none), and with `write` the
    /// faces of the block's cells. `top`: `above` on the upper face of a cluster crossing it
    /// (NaN: its exit not snapped; `None`: not known yet, the faces are not written).
    fn sweep_row(
        &mut self,
        axis: usize,
        r: &ChainRow,
        top: Option<f64>,
        write: bool,
    ) -> (f64, f64) {
        let (n, area) = (self.n[axis], self.area[axis]);
        let (lo, hi) = (
            self.geom.block.lo[axis] as i32,
            self.geom.block.hi[axis] as i32,
        );
        let window = self.geom.window;
        let (grid, faces) = (&self.grid, &mut self.geom.face_fraction[axis]);
        let written = &mut self.geom.written;
        let mut put = |pos: i32, lambda: f64| {
            let ijk = row_ijk(grid, axis, r.row, pos);
            if write && lambda != 0.0 && window.has_face(axis, ijk) {
                let f = window.face_index(axis, ijk);
                faces[f] = lambda;
                written.mark(1 + axis, f);
            }
        };
        let mut lambda = r.entry;
        let mut above_lo = f64::NAN;
        let mut below = Vec::new();
        let cells = &r.cells;
        let mut i = 0;
        while i < cells.len() {
            let s = i;
            while i + 1 < cells.len() && cells[i + 1].0 == cells[i].0 + 1 {
                i += 1;
            }
            let cluster = &cells[s..=i];
            i += 1;
            let from_below = s == 0 && r.below_cut && lo > 0 && cluster[0].0 == lo;
            let last = cluster[cluster.len() - 1].0;
            let to_above = r.above_cut && last == hi - 1;
            below.clear();
            for c in cluster {
                below.push(lambda);
                lambda -= c.1 / area;
            }
            // Where `above` starts: the snapped exit, or the block above's value.
            let mut start = None;
            if to_above {
                start = top.filter(|t| !t.is_nan());
            } else if last + 1 < n {
                let rounded = lambda.round();
                if (lambda - rounded).abs() <= SNAP_TOLERANCE {
                    lambda = rounded;
                    start = Some(rounded);
                }
            }
            let mut face_values = below.clone();
            let mut top_face = lambda;
            if let Some(mut above) = start {
                let mix = |face: i32, below: f64, above: f64| match (2 * face).cmp(&n) {
                    std::cmp::Ordering::Less => below,
                    std::cmp::Ordering::Greater => above,
                    std::cmp::Ordering::Equal => 0.5 * (below + above),
                };
                if to_above {
                    top_face = mix(hi, lambda, above);
                }
                for k in (0..cluster.len()).rev() {
                    if k == 0 && !from_below {
                        break;
                    }
                    above += cluster[k].1 / area;
                    face_values[k] = mix(cluster[k].0, below[k], above);
                }
                if from_below {
                    above_lo = above;
                }
            }
            for (k, c) in cluster.iter().enumerate() {
                if c.0 >= 0 {
                    put(c.0, face_values[k]);
                }
            }
            // The upper face of the cluster's last cell (the next block's, if it goes on).
            if last >= 0 && last < n && (to_above || last + 1 < n) {
                put(last + 1, top_face);
            }
            if !write && to_above {
                break;
            }
        }
        // The grid's last face, after the row's last cut cell.
        let next = cells.last().map_or(lo, |c| c.0 + 1);
        if hi == n && next <= n {
            put(n, lambda);
        }
        (lambda, above_lo)
    }
}

/// The rows of `axis` in the block with their cut cells in the block (and at `-1` at the grid's
/// lower end, `n` at its upper end), and whether the cells just beyond it are cut; ascending.
fn axis_rows(
    grid: &Grid,
    axis: usize,
    geom: &BlockGeometry,
    pieces: &[crate::cutcell::measure::Piece],
) -> Vec<ChainRow> {
    let block = geom.block;
    let n = grid.cells[axis] as i32;
    let (b, c) = other_axes(axis);
    let (lo, hi) = (block.lo[axis] as i32, block.hi[axis] as i32);
    let first = if lo == 0 { -1 } else { lo - 1 };
    let last = if hi == n { n } else { hi };
    let in_rows = |cell: [i32; 3]| {
        [b, c]
            .iter()
            .all(|&a| block.lo[a] as i32 <= cell[a] && cell[a] < block.hi[a] as i32)
    };
    let mut records = Vec::new();
    for (order, piece) in pieces.iter().enumerate() {
        let p = piece.cell[axis];
        if in_rows(piece.cell) && first <= p && p <= last {
            let row = piece.cell[b] as u64 + grid.cells[b] as u64 * piece.cell[c] as u64;
            records.push(record(row, p, order, piece.area_vector[axis]));
        }
    }
    sort_records_in_rows(&mut records);
    let mut rows = Vec::new();
    let mut terms = Vec::new();
    for row_records in records.chunk_by(|x, y| x.row == y.row) {
        let mut r = ChainRow {
            row: row_records[0].row,
            cells: Vec::new(),
            below_cut: false,
            above_cut: false,
            entry: 0.0,
            done: false,
            above_lo: f64::NAN,
            up_state: f64::NAN,
        };
        for cell in row_records.chunk_by(|x, y| x.pos == y.pos) {
            let pos = cell[0].pos;
            if lo > 0 && pos == lo - 1 {
                r.below_cut = true;
            } else if hi < n && pos == hi {
                r.above_cut = true;
            } else {
                terms.clear();
                terms.extend(cell.iter().map(|x| x.flux));
                r.cells.push((pos, odd_sum(&mut terms)));
            }
        }
        if !r.cells.is_empty() || r.above_cut {
            rows.push(r);
        }
    }
    rows
}

/// The geometry of every block of the process grid `dims` (`CellBox::of_rank` order), their
/// messages passed in one process: what the ranks of a decomposed grid compute together. Pure
/// (tests and benches; the solver passes the messages between ranks).
pub fn compute_blocks(grid: &Grid, surface: &Surface, dims: [usize; 3]) -> Vec<BlockGeometry> {
    let n_blocks = dims.iter().product::<usize>();
    let mut sweeps: Vec<BlockSweep> = (0..n_blocks)
        .map(|r| BlockSweep::new(grid, surface, CellBox::of_rank(grid, dims, r)))
        .collect();
    for axis in 1..grid.dim {
        pass_messages(dims, axis, &mut sweeps, |_, _, _, m| m);
    }
    sweeps.into_iter().map(BlockSweep::finish).collect()
}

/// Passes the messages of `axis` between `sweeps` (one per rank of `dims`): up in ascending
/// order along the axis, then down. `tamper(up, rank, axis, message)` sees each message on its
/// way (tests change one to check that a wrong boundary sum shows).
pub fn pass_messages(
    dims: [usize; 3],
    axis: usize,
    sweeps: &mut [BlockSweep],
    mut tamper: impl FnMut(bool, usize, usize, Vec<f64>) -> Vec<f64>,
) {
    let stride: usize = dims[..axis].iter().product();
    let step = |r: usize| (r / stride) % dims[axis];
    let mut order: Vec<usize> = (0..sweeps.len()).collect();
    order.sort_by_key(|&r| step(r));
    let mut carried = vec![Vec::new(); sweeps.len()];
    for &r in &order {
        let m = sweeps[r].up(axis, &std::mem::take(&mut carried[r]));
        if step(r) + 1 < dims[axis] {
            carried[r + stride] = tamper(true, r, axis, m);
        }
    }
    for &r in order.iter().rev() {
        let m = sweeps[r].down(axis, &std::mem::take(&mut carried[r]));
        if step(r) > 0 {
            carried[r - stride] = tamper(false, r, axis, m);
        }
    }
}
