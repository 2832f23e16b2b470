//! [`WallHooks`]: what the sweeps write into a rank's own cells in a coupled step (the ghost
//! states, the walls where they cut their pencils, the vacuum cells), derived from a geometry of
//! those cells and the cells around them: the whole grid's on one rank, on a decomposed grid
//! the block's and a halo of [`hook_halo`] cells (`cutcell::compute_block_cells`), bit for bit
//! those of the whole grid on the rank's cells (issue 40 item 1, step 2; docs/mpi.md).
//!
//! How far a rank's hooks reach, along a sweep axis, from its block (`ng` ghost cells of the
//! sweeps, `overlap` = [`MAX_FIXES`] extra cells a decomposed line updates on each side):
//! - a ghost fill of an own cell starts at a covered cell at most `ng − 1` cells beyond the block
//!   and mirrors a fluid cell at most `2 ng − 1` cells beyond it;
//! - the decomposed sweep reads the wall runs that reach its line and its ghost cells, `overlap
//!   + ng` cells beyond the block (a run further away puts no mirror ghost into the line: see
//!   [`WallHooks::restricted`]); a run is shorter than `2 ng` cells, so its cells and the fluid
//!   cells at its ends lie within `overlap + 3 ng − 1` cells of the block;
//! - whether a cell there is covered, near, a vacuum cell, and the wall it holds come from its
//!   sub-faces, the solid fractions of its face neighbours and the cut cells within
//!   [`NEAR_RADIUS`] of it; so a halo of `overlap + 3 ng + NEAR_RADIUS + 1` cells holds all of
//!   it (Λ and the sub-faces of a block's geometry are exact in all of its window).

use protocol::sum::OddSum;
use rayon::prelude::*;

use super::cells::{domain_face, mark_run, marked_cells, touches_gas_with};
use super::near_wall::{
    NEAR_WALL_SUMS, NW_AREA, NW_FACING, NW_FACING_LEN, NW_NORMAL, NW_VELOCITY, NW_WET_AREA,
    NW_WET_NORMAL, NearWall, NearWalls,
};
use super::{COVERED_TOLERANCE, NEAR_RADIUS, SolidFrame};
use crate::cutcell::{CellBox, CutGeometry, HeldFractions, SubFace, compute, compute_block_cells};
use crate::fv::line::MAX_FIXES;
use crate::fv::{GhostFill, Wall, WallRun};
use crate::grid::Grid;

/// What the sweeps of a coupled step write into a rank's cells (the inputs of
/// [`crate::fv::SplitHooks`]); cells and pencils of the whole grid.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct WallHooks {
    /// Per axis: the ghost states of the covered cells written before the sweep along it, in
    /// order (a later fill of a cell wins).
    pub ghosts: [Vec<GhostFill>; 3],
    /// Per axis: the walls thinner than `2 ng` cells where the sweep along it cuts its pencils,
    /// sorted by pencil and position.
    pub walls: [Vec<WallRun>; 3],
    /// Covered cells that hold no fluid yet beside a wet face (a crack that has just opened),
    /// ascending.
    pub vacuum: Vec<u32>,
}

/// Cells' runs of sub-faces one task of [`HookGeometry::near_walls`] sums at least, and at
/// most four times as many, so that no thread waits long for the other's last task (any split
/// gives the same walls).
const RUNS_PER_TASK: usize = 64;

/// Cells of halo around a block whose geometry gives its [`WallHooks`] exactly, for sweeps with
/// `ng` ghost cells (module docs): `MAX_FIXES + 3 ng + NEAR_RADIUS + 1` (15 for OSMP 5, 18 for
/// OSMP 7).
pub fn hook_halo(ng: usize) -> usize {
    MAX_FIXES + 3 * ng + NEAR_RADIUS + 1
}

/// The [`WallHooks`] of the cells of `block` (`None`: the whole grid) for the surface and
/// kinematics `frame` on `grid`, with `ng` ghost cells: from the whole grid's geometry
/// (`cutcell::compute`) without a block, else from the block's and a halo of [`hook_halo`]
/// cells (`cutcell::compute_block_cells`). With a block, bit for bit the whole grid's
/// [`WallHooks::restricted`] to it.
///
/// Pure; what an [`super::Embedded`] on a decomposed grid does in each predict, exposed for the
/// tests and the benches.
pub fn wall_hooks(grid: &Grid, ng: usize, frame: &SolidFrame, block: Option<CellBox>) -> WallHooks {
    match block {
        None => {
            let mut geom = crate::cutcell::CutGeometry::new();
            compute(grid, &frame.surface(), &mut geom);
            let view = HookGeometry {
                grid,
                window: CellBox::whole(grid),
                held: CellBox::whole(grid),
                solid_fraction: &geom.solid_fraction,
                subfaces: &geom.subfaces,
            };
            let near = NearOfView::new(&view, &geom.cut_cells);
            view.wall_hooks(&near.as_ref(), frame, ng, CellBox::whole(grid))
        }
        Some(block) => block_wall_hooks(grid, ng, frame, block),
    }
}

/// The [`WallHooks`] of the cells of `block` for the surface and kinematics `frame` on `grid`,
/// with `ng` ghost cells, from `geom`, the whole grid's geometry of `frame`'s surface
/// (`cutcell::compute`): only its window of `block` and [`hook_halo`] cells is read (Λ, the
/// sub-faces and the cut cells there). Bit for bit [`wall_hooks`] with the block, which
/// computes that window's geometry itself: Λ and the sub-faces of a block's geometry are the
/// whole grid's on every cell of its window (`cutcell::compute_block_cells`).
///
/// What a rank of a decomposed grid does in each predict while it holds the whole grid's
/// geometry of `F^n` (issue 40 item 1; docs/mpi.md): that geometry is computed once a step, in
/// the correct before, so the predict need not compute its window again.
pub fn wall_hooks_in(
    grid: &Grid,
    ng: usize,
    frame: &SolidFrame,
    geom: &CutGeometry,
    block: CellBox,
) -> WallHooks {
    window_hooks(
        grid,
        ng,
        frame,
        geom,
        block,
        CellBox::whole(grid),
        &geom.solid_fraction,
        None,
    )
}

/// [`wall_hooks_in`] from the Λ a rank of a decomposed grid holds (`embedded::held`: dense in
/// its block and the halo of [`hook_halo`] cells, the window the hooks read) and the whole
/// grid's sub-faces and cut cells of `geom` (its dense arrays unused): the same bits. `near`:
/// the near cells of `geom` the rank lists, their slots over the held box.
///
/// NOTE (issue 40 item 4): the window's near cells are the rank's near cells there, but in the
/// window's outer [`NEAR_RADIUS`] cells, which may also be near a cut cell beyond it; a hook
/// from those cells lies [`hook_halo`] − [`NEAR_RADIUS`] cells or more from the block, and
/// [`WallHooks::restricted`] drops it. Finding them again from the window's cut cells
/// (`NearOfView::new`) was about 1 ms of a rank's step at 128³ on 2 ranks.
pub(super) fn wall_hooks_held(
    grid: &Grid,
    ng: usize,
    frame: &SolidFrame,
    fractions: &HeldFractions,
    geom: &CutGeometry,
    block: CellBox,
    near: &NearView,
) -> WallHooks {
    let window = block.grown(grid, hook_halo(ng));
    assert!(
        (0..3)
            .all(|a| fractions.held.lo[a] <= window.lo[a] && window.hi[a] <= fractions.held.hi[a]),
        "the hooks' window is held dense"
    );
    window_hooks(
        grid,
        ng,
        frame,
        geom,
        block,
        fractions.held,
        &fractions.solid_fraction,
        Some(near),
    )
}

/// The hooks of `block` from the sub-faces and cut cells of `geom` in the window of
/// [`hook_halo`] cells around it and Λ of the cells of `held` (`solid_fraction`, by
/// [`CellBox::index`]), which holds that window; with `near` (see [`wall_hooks_held`]), the
/// near cells it gives, else the window's.
#[allow(clippy::too_many_arguments)]
fn window_hooks(
    grid: &Grid,
    ng: usize,
    frame: &SolidFrame,
    geom: &CutGeometry,
    block: CellBox,
    held: CellBox,
    solid_fraction: &[f64],
    near: Option<&NearView>,
) -> WallHooks {
    let window = block.grown(grid, hook_halo(ng));
    let inside = |c: u32| window.contains(grid.ijk(c as usize));
    // NOTE: the sub-faces and cut cells of the window's cells, in the whole grid's order (by
    // cell, then element), which is the order of a block's geometry; with slabs they are one
    // stretch of the whole lists, with blocks several.
    let subfaces: Vec<SubFace> = (geom.subfaces.iter())
        .filter(|s| inside(s.cell))
        .copied()
        .collect();
    let view = HookGeometry {
        grid,
        window,
        held,
        solid_fraction,
        subfaces: &subfaces,
    };
    if let Some(near) = near {
        return view.wall_hooks(near, frame, ng, block);
    }
    let cut_cells: Vec<u32> = (geom.cut_cells.iter().copied())
        .filter(|&c| inside(c))
        .collect();
    let near = NearOfView::new(&view, &cut_cells);
    view.wall_hooks(&near.as_ref(), frame, ng, block)
}

/// The [`WallHooks`] of the cells of `block`, from the geometry of `frame`'s surface on the
/// block and a halo of [`hook_halo`] cells.
pub(super) fn block_wall_hooks(
    grid: &Grid,
    ng: usize,
    frame: &SolidFrame,
    block: CellBox,
) -> WallHooks {
    let geom = compute_block_cells(grid, &frame.surface(), block, hook_halo(ng));
    let view = HookGeometry {
        grid,
        window: geom.window,
        held: geom.window,
        solid_fraction: &geom.solid_fraction,
        subfaces: &geom.subfaces,
    };
    let near = NearOfView::new(&view, &geom.cut_cells);
    view.wall_hooks(&near.as_ref(), frame, ng, block)
}

impl WallHooks {
    /// What a rank of block `block` takes of these hooks (of the whole grid, or of a window
    /// around the block), for sweeps with `ng` ghost cells: the ghost fills and vacuum cells of
    /// its cells, and the wall runs of its pencils that reach its line (its cells and the
    /// [`MAX_FIXES`] cells it updates on each side) or the `ng` ghost cells around it.
    ///
    /// NOTE: a segment between two runs is swept as a line of its own, its mirror ghosts taken
    /// from its whole length; a decomposed line holds the part of it that it reaches, and the
    /// segment's mirror ghosts only where they fall into the line's ghost cells
    /// (`fv::sweep::advance_segments`). A run that ends `ng` or more cells below the line (or
    /// starts as far above it) puts no ghost there, and without it the segment beside it still
    /// starts below the line's ghost cells: the line's bits are the same without it.
    pub fn restricted(&self, grid: &Grid, ng: usize, block: CellBox) -> WallHooks {
        let reach = MAX_FIXES + ng;
        let own = |c: u32| block.contains(grid.ijk(c as usize));
        let mut out = WallHooks {
            vacuum: self.vacuum.iter().copied().filter(|&c| own(c)).collect(),
            ..WallHooks::default()
        };
        for axis in 0..grid.dim {
            out.ghosts[axis] = (self.ghosts[axis].iter())
                .filter(|g| own(g.cell))
                .copied()
                .collect();
            let stride: usize = grid.cells[..axis].iter().product();
            let n = grid.cells[axis];
            out.walls[axis] = (self.walls[axis].iter())
                .filter(|w| {
                    let p = w.pencil as usize;
                    let ijk = grid.ijk(p % stride + (p / stride) * stride * n);
                    let across =
                        (0..3).all(|a| a == axis || block.lo[a] <= ijk[a] && ijk[a] < block.hi[a]);
                    across
                        && w.hi as usize + reach > block.lo[axis]
                        && (w.lo as usize) < block.hi[axis] + reach
                })
                .copied()
                .collect();
        }
        out
    }
}

/// The geometry the hooks are derived from: that of the cells of `window` (the whole grid on
/// one rank), exact there (Λ and the sub-faces).
pub(super) struct HookGeometry<'a> {
    pub(super) grid: &'a Grid,
    /// The cells whose geometry the hooks read (a block's window: beyond it they read Λ as 0).
    pub(super) window: CellBox,
    /// The cells `solid_fraction` holds: the window, or the whole grid around it.
    pub(super) held: CellBox,
    /// Λ per cell of `held` ([`CellBox::index`]).
    pub(super) solid_fraction: &'a [f64],
    /// The sub-faces of the window's cells, by cell (global cell indices).
    pub(super) subfaces: &'a [SubFace],
}

/// The near cells of a [`HookGeometry`] (cells of its window within [`NEAR_RADIUS`] of one of
/// its cut cells), ascending, and `slot + 1` of each by index in `slot_box`, a box of the
/// window that holds them all (0 elsewhere).
pub(super) struct NearView<'a> {
    pub(super) cells: &'a [u32],
    pub(super) slot_of: &'a [u32],
    pub(super) slot_box: CellBox,
}

impl NearView<'_> {
    /// `slot + 1` of cell `ijk` if it is a near cell, else 0.
    #[inline]
    pub(super) fn slot_of(&self, ijk: [usize; 3]) -> u32 {
        if self.slot_box.contains(ijk) {
            self.slot_of[self.slot_box.index(ijk)]
        } else {
            0
        }
    }
}

/// The near cells of a block's window, owned ([`NearView`] borrows them).
struct NearOfView {
    cells: Vec<u32>,
    slot_of: Vec<u32>,
    slot_box: CellBox,
}

impl NearOfView {
    /// The cells of `view`'s window within [`NEAR_RADIUS`] of one of `cut_cells` (global).
    ///
    /// NOTE: marked in a bit set of the box that holds them (the neighbourhoods' bounding box
    /// within the window), a row of each neighbourhood at a time, and read out in order (a
    /// box's order of its cells is the grid's): the ascending list that marking each offset of
    /// each cut cell and sorting gave, in a tenth of the time (that took 2.4 ms of the 9–12 ms
    /// of a rank's hooks at 64³ on 2 ranks, `embedded_ranks`). The slots are held over that
    /// box too: over the whole window (the block and [`hook_halo`] cells around it) they were
    /// an array of 5.2 MB zeroed in each predict at 128³ on 2 ranks, about 1.5 ms a step
    /// (issue 40 item 4).
    fn new(view: &HookGeometry, cut_cells: &[u32]) -> NearOfView {
        let (grid, window) = (view.grid, view.window);
        // Each cut cell's neighbourhood within the window, `(lo, hi)` per axis (both included).
        let span = |c: u32| -> Option<[(usize, usize); 3]> {
            let ijk = grid.ijk(c as usize);
            let span: [(usize, usize); 3] = std::array::from_fn(|a| {
                let r = if a < grid.dim { NEAR_RADIUS } else { 0 };
                let lo = ijk[a].saturating_sub(r).max(window.lo[a]);
                (lo, (ijk[a] + r).min(window.hi[a] - 1))
            });
            span.iter().all(|&(lo, hi)| lo <= hi).then_some(span)
        };
        let spans: Vec<[(usize, usize); 3]> = cut_cells.iter().filter_map(|&c| span(c)).collect();
        let mut slot_box: Option<CellBox> = None;
        for s in &spans {
            let b = slot_box.get_or_insert(CellBox {
                lo: s.map(|a| a.0),
                hi: s.map(|a| a.1 + 1),
            });
            for a in 0..3 {
                b.lo[a] = b.lo[a].min(s[a].0);
                b.hi[a] = b.hi[a].max(s[a].1 + 1);
            }
        }
        let slot_box = slot_box.unwrap_or_default();
        let mut marked = vec![0u64; slot_box.n_cells().div_ceil(64)];
        for s in &spans {
            let (x, y, z) = (s[0], s[1], s[2]);
            for k in z.0..=z.1 {
                for j in y.0..=y.1 {
                    mark_run(
                        &mut marked,
                        slot_box.index([x.0, j, k]),
                        slot_box.index([x.1, j, k]),
                    );
                }
            }
        }
        let size = [slot_box.size(0), slot_box.size(1)];
        let mut slot_of = vec![0u32; slot_box.n_cells()];
        let mut cells = Vec::new();
        for w in marked_cells(&marked) {
            let (i, j, k) = (
                w % size[0],
                (w / size[0]) % size[1],
                w / (size[0] * size[1]),
            );
            let lo = slot_box.lo;
            cells.push(grid.index(lo[0] + i, lo[1] + j, lo[2] + k) as u32);
            slot_of[w] = cells.len() as u32;
        }
        NearOfView {
            cells,
            slot_of,
            slot_box,
        }
    }

    fn as_ref(&self) -> NearView<'_> {
        NearView {
            cells: &self.cells,
            slot_of: &self.slot_of,
            slot_box: self.slot_box,
        }
    }
}

impl HookGeometry<'_> {
    /// The [`WallHooks`] of the cells of `own` (within the window, at [`hook_halo`] cells
    /// from its edges unless those are the grid's), with the kinematics of `frame`.
    pub(super) fn wall_hooks(
        &self,
        near: &NearView,
        frame: &SolidFrame,
        ng: usize,
        own: CellBox,
    ) -> WallHooks {
        let (mut walls, closed) = self.near_walls(near, frame);
        let vacuum = self.vacuum_cells(near, &mut walls, &closed);
        let mut out = WallHooks::default();
        // (Each axis's fills and runs are its own: the axes run in parallel on the pool.)
        let dim = self.grid.dim;
        (out.ghosts.par_iter_mut().zip(&mut out.walls))
            .enumerate()
            .take(dim)
            .for_each(|(axis, (fills, runs))| {
                self.ghost_fills(near, &walls, &vacuum, ng, axis, own, fills, runs);
            });
        out.vacuum = vacuum;
        if own == CellBox::whole(self.grid) {
            out
        } else {
            out.restricted(self.grid, ng, own)
        }
    }

    /// Λ of cell `ijk` (0 beyond the window: only hooks that a rank drops read it).
    fn lambda(&self, ijk: [usize; 3]) -> f64 {
        if self.window.contains(ijk) {
            self.solid_fraction[self.held.index(ijk)]
        } else {
            0.0
        }
    }

    /// The wall of the near cells that hold sub-faces, summed apart from the sub-faces' order
    /// (the sub-faces come in cell order; slots are the fields of `NearWall::from_sums`), per
    /// near cell, and whether a covered near cell holds a wet face with no gas in front (see
    /// `touches_gas`). The walls' velocities are still sums (see `vacuum_cells`).
    ///
    /// NOTE: each cell's wall is summed from its own run of sub-faces alone, so the runs are
    /// summed in parallel on the pool the call runs in and the walls put in place in the runs'
    /// order: the same walls on any number of threads. In `cube-mobile-walls` on 50³ these sums
    /// were 4 % of the fluid node's time, on one thread while the other waited.
    fn near_walls(&self, near: &NearView, current: &SolidFrame) -> (NearWalls, Vec<bool>) {
        let grid = self.grid;
        let slot = |c: u32| near.slot_of(grid.ijk(c as usize)) as usize - 1;
        let subfaces = self.subfaces;
        // Where each cell's run of sub-faces starts, and the end of the last.
        let mut bounds: Vec<usize> = (0..subfaces.len())
            .filter(|&i| i == 0 || subfaces[i].cell != subfaces[i - 1].cell)
            .collect();
        bounds.push(subfaces.len());
        let n_runs = bounds.len() - 1;
        let (runs, shut): (Vec<NearWall>, Vec<bool>) = (0..n_runs)
            .into_par_iter()
            .with_min_len(RUNS_PER_TASK)
            .with_max_len(4 * RUNS_PER_TASK)
            .map_init(OddSum::default, |sum, r| {
                self.near_wall(current, &subfaces[bounds[r]..bounds[r + 1]], sum)
            })
            .unzip();
        let mut run_of = vec![0u32; near.cells.len()];
        let mut closed = vec![false; near.cells.len()];
        for (r, shut) in shut.into_iter().enumerate() {
            let k = slot(subfaces[bounds[r]].cell);
            run_of[k] = r as u32 + 1;
            closed[k] |= shut;
        }
        (NearWalls { runs, run_of }, closed)
    }

    /// The wall of one cell from its run of sub-faces `run` (see [`HookGeometry::near_walls`]),
    /// and whether one of them is a wet face with no gas in front; `sum` is scratch.
    fn near_wall(
        &self,
        current: &SolidFrame,
        run: &[SubFace],
        sum: &mut OddSum,
    ) -> (NearWall, bool) {
        let grid = self.grid;
        let dim = grid.dim;
        let lambda = |c: usize| self.lambda(grid.ijk(c));
        let mut closed = false;
        sum.clear();
        for s in run {
            let w = current.point_velocity(s.particle as usize, s.centroid);
            for a in 0..3 {
                sum.push(NW_VELOCITY + a, s.area * w[a]);
                for b in 0..3 {
                    let slot = NW_NORMAL + 3 * a + b;
                    sum.push(slot, s.area * s.normal[a].abs() * s.normal[b]);
                }
            }
            sum.push(NW_AREA, s.area);
            for a in 0..dim {
                if s.normal[a] != 0.0 {
                    let side = usize::from(s.normal[a] < 0.0);
                    let f = NW_FACING + NW_FACING_LEN * (2 * a + side);
                    sum.push(f, s.area);
                    for b in 0..3 {
                        sum.push(f + 1 + b, s.area * w[b]);
                        sum.push(f + 4 + b, s.area * s.normal[a].abs() * s.normal[b]);
                    }
                }
            }
            if current.wet[s.element as usize] && domain_face(grid, s).is_none() {
                sum.push(NW_WET_AREA, s.area);
                for a in 0..3 {
                    sum.push(NW_WET_NORMAL + a, s.area * s.normal[a]);
                }
                if !touches_gas_with(grid, lambda, s) {
                    closed = true;
                }
            }
        }
        let mut fields = [0.0; NEAR_WALL_SUMS];
        sum.add_into(&mut fields);
        (NearWall::from_sums(&fields), closed)
    }

    /// Covered cells between the two faces of a crack that has just opened hold no fluid yet:
    /// vacuum (paper 000 §3.2), not ghost states. Where the two faces lie on either side of a
    /// grid plane (pressed walls whose faces were on it), each cell holds one, with the other's
    /// covered cell in front (`closed`). Then the walls' velocities become area averages.
    fn vacuum_cells(&self, near: &NearView, walls: &mut NearWalls, closed: &[bool]) -> Vec<u32> {
        let grid = self.grid;
        let mut vacuum = Vec::new();
        for (k, &c) in near.cells.iter().enumerate() {
            if self.lambda(grid.ijk(c as usize)) >= 1.0 - COVERED_TOLERANCE
                && (walls.get(k).is_crack() || closed[k])
            {
                vacuum.push(c);
            }
        }
        // (A cell's runs but its last are read by no one: their velocities do not matter.)
        for nw in walls.runs.iter_mut() {
            if nw.area > 0.0 {
                for x in nw.velocity.iter_mut() {
                    *x /= nw.area;
                }
            }
        }
        vacuum
    }

    /// The ghost states of the covered near cells on the pencils through `own` for the sweep
    /// along `axis`, and the walls thinner than `2 ng` cells where that sweep cuts them
    /// (before [`WallHooks::restricted`]).
    #[allow(clippy::too_many_arguments)]
    fn ghost_fills(
        &self,
        near: &NearView,
        near_walls: &NearWalls,
        vacuum: &[u32],
        ng: usize,
        axis: usize,
        own: CellBox,
        fills: &mut Vec<GhostFill>,
        walls: &mut Vec<WallRun>,
    ) {
        let grid = self.grid;
        let n = grid.cells[axis] as isize;
        let ng = ng as isize;
        let slot_of = |q: [usize; 3]| -> usize { near.slot_of(q) as usize };
        // A crack cell is vacuum fluid to the sweeps, not a covered cell.
        let covered = |q: [usize; 3]| {
            self.lambda(q) >= 1.0 - COVERED_TOLERANCE
                && vacuum
                    .binary_search(&(grid.index(q[0], q[1], q[2]) as u32))
                    .is_err()
        };
        let stride: usize = grid.cells[..axis].iter().product();
        // The wall seen along the axis from `fluid` beside the covered cell `covered`: the fluid
        // cell's sub-faces, else the covered cell's, else a wall at rest normal to the axis.
        // The sub-faces turned towards the fluid first: a thin gap between a wall at rest and a
        // moving one must mirror each side about its own wall.
        let wall_seen = |fluid: [usize; 3], covered: [usize; 3], dir: isize| -> Wall {
            let walls = [fluid, covered]
                .map(slot_of)
                .map(|k| (k > 0).then(|| near_walls.get(k - 1)));
            walls
                .iter()
                .flatten()
                .find_map(|w| w.facing(axis, dir))
                .or_else(|| {
                    walls
                        .iter()
                        .flatten()
                        .find(|w| w.area > 0.0)
                        .map(|w| w.along(axis))
                })
                .unwrap_or(Wall::at_rest(axis))
        };
        let index = |q: [usize; 3]| grid.index(q[0], q[1], q[2]);
        for &c in near.cells {
            let c = c as usize;
            let ijk = grid.ijk(c);
            let on_own_pencil =
                (0..3).all(|a| a == axis || own.lo[a] <= ijk[a] && ijk[a] < own.hi[a]);
            if !on_own_pencil || !covered(ijk) {
                continue;
            }
            let at = |m: isize| -> Option<[usize; 3]> {
                (0..n).contains(&m).then(|| {
                    let mut q = ijk;
                    q[axis] = m as usize;
                    q
                })
            };
            let is_covered = |m: isize| at(m).is_some_and(covered);
            let m0 = ijk[axis] as isize;
            for dir in [1isize, -1] {
                // `c` starts a covered run seen from the fluid cell at `m0 − dir`.
                let Some(fluid) = at(m0 - dir) else { continue };
                if is_covered(m0 - dir) {
                    continue;
                }
                let mut len = 0;
                while len < 2 * ng && is_covered(m0 + dir * len) {
                    len += 1;
                }
                let closed = len < 2 * ng && at(m0 + dir * len).is_some();
                let wall = wall_seen(fluid, ijk, dir);
                if closed && dir == 1 {
                    let far = at(m0 + len).expect("closed");
                    let last = at(m0 + len - 1).expect("in the run");
                    walls.push(WallRun {
                        pencil: (c % stride + (c / (stride * n as usize)) * stride) as u32,
                        lo: m0 as u32,
                        hi: (m0 + len) as u32,
                        walls: [wall, wall_seen(far, last, -1)],
                    });
                }
                // NOTE: the middle cell of an odd closed run takes the ghost of the side that
                // faces the grid's middle along the axis (the lower side above the middle), so
                // that the mirror image of a scene about that middle gets the mirrored fills.
                let count = if closed {
                    let mid = m0 + dir * ((len - 1) / 2);
                    let lower_side_fills_middle = 2 * mid + 1 > n;
                    if (dir == 1) == lower_side_fills_middle {
                        (len + 1) / 2
                    } else {
                        len / 2
                    }
                } else {
                    len.min(ng)
                }
                .min(ng);
                let mut src = fluid;
                for m in 0..count {
                    let dst = at(m0 + dir * m).expect("inside the run");
                    if let Some(s) = at(m0 - dir * (m + 1))
                        && !is_covered(m0 - dir * (m + 1))
                    {
                        src = s;
                    }
                    fills.push(GhostFill {
                        cell: index(dst) as u32,
                        mirror_of: index(src) as u32,
                        wall,
                    });
                }
            }
        }
        walls.sort_unstable_by_key(|w| (w.pencil, w.lo));
    }
}
