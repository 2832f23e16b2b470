//! Step 1 of paper 003 §3.4: the split sweeps over the whole grid, with the ghost states of the
//! covered cells, keeping `U^n`, `p̄` and the face fluxes of the cells near the wet surface.

use rayon::prelude::*;

use super::cells::{BoxMarks, bounding_box, cells_around, full_state, pencil_axes};
use super::hooks::{HookGeometry, NearView, wall_hooks_held, wall_hooks_in};
use super::state::{NearCells, OwnSlots};
use super::{COVERED_TOLERANCE, Embedded, NEAR_RADIUS};
use crate::cutcell::CellBox;
use crate::fv::euler::NQ;
use crate::fv::state::extend_cell;
use crate::fv::sweep::{frame, from_local, to_local};
use crate::fv::{FluidSolver, GhostFill, StepReport, mirror};

impl Embedded {
    /// Step 1 of paper 003 §3.4: the split sweeps, keeping what the correct needs.
    pub fn predict(&mut self, solver: &mut FluidSolver, dt: f64) -> StepReport {
        self.prepare(solver);
        let geom = &self.state.geom;
        let covered = |c: usize| geom.lambda(c) >= 1.0 - COVERED_TOLERANCE;
        let report = solver.predict(dt, &mut self.near.hooks, &covered);
        self.wall_pressures(solver, report.sweeps[0]);
        report
    }

    /// `p̄` of every near cell, the pressure of the wet faces it holds (or, covered at `t^n`,
    /// faces): the mean of its pressure at `t^n` (what the first sweep starts from) and after
    /// the sweeps, on every axis; in a covered cell the mirrored fluid's at `t^n`; 0 in a cell
    /// that held vacuum at `t^n` ([`Embedded::vacuum_wall`]).
    ///
    /// Each rank takes those of its own near cells, from the pressures and the predicted states
    /// of its own cells, and one all-gather gives every rank all of them (collective; 8 bytes
    /// per near cell). Before issue 40 item 1 every rank gathered the pressures of every near
    /// cell on every axis and their predicted states, and computed all of them.
    ///
    /// NOTE: paper 003 (§3.4 step 1; CELIA3D's `pdtx`, `pdty`, `pdtz`) takes along each axis
    /// the pressure the sweep along it starts from. A face's work `Σ_a p̄_a V_a ν_a` then need
    /// not have the sign of its normal velocity `V·ν`: a square at Mach 850 in cold gas (12²
    /// cells, p = 1e-6) pushed on its lower face (`V·ν = 0.11`) with `p̄_x` = 1e-6 and a
    /// `p̄_y` the x sweep had raised to 1e-3 against it, so that face took energy out, and the
    /// whole gas was left at `p = −7.9e-7` (docs/cut-cells.md §3). With one pressure per face
    /// its work has the sign of `V·ν`. Of the single pressures tried, `tⁿ`'s alone lags the
    /// compression the sweeps make in front of a body (mixing groups up to 3,650 cells at Mach
    /// 850 on 16³), the mean of the sweeps' start pressures depends on their order (a piston
    /// along y no longer gave the flow of one along x), the pressure of the sweep along the
    /// axis nearest the normal left such squares non-physical again; this mean of `tⁿ` and the
    /// predicted state is independent of the order and brought the piston's L1(ρ) on 400 cells
    /// from 1.53e-3 to 1.31e-3.
    fn wall_pressures(&mut self, solver: &FluidSolver, first: usize) {
        let (dim, nvar) = (self.config.grid.dim, self.config.grid.dim + 2);
        let (gamma, (vr, _)) = (self.config.gamma, self.config.vacuum);
        let geom = &self.state.geom;
        let own: Vec<usize> = self.near.own.iter().collect();
        let own_cells: Vec<u32> = own.iter().map(|&k| self.near.cells[k]).collect();
        let predicted = solver.own_cells_at(&own_cells);
        let near = &self.near;
        let mut mine = Vec::with_capacity(own.len());
        for (i, &k) in own.iter().enumerate() {
            let start = near.hooks.pressures[first][k];
            let c = near.cells[k] as usize;
            let p = if geom.lambda(c) >= 1.0 - COVERED_TOLERANCE {
                start
            } else if self.vacuum_wall(k) {
                0.0
            } else {
                let u = full_state(&predicted[i * nvar..(i + 1) * nvar], dim, 1.0);
                let end = crate::fv::euler::primitive_floored(&u, gamma, vr).p;
                0.5 * (start + end)
            };
            mine.push(p);
        }
        let near = &mut self.near;
        solver.gather_owned_into(&near.cells, mine, 1, &mut near.wall_pressure);
    }

    /// Whether the uncovered near cell in slot `k` held vacuum at `t^n`: a wet face there takes
    /// no gas pressure.
    ///
    /// NOTE: the sweeps give that cell the gas they bring in from its neighbours, and a later
    /// sweep starts from it; but the faces to the cell's other vacuum neighbours carry nothing
    /// (Lax–Friedrichs of vacuum against vacuum, or a crack's flux from `U^n`), so that pressure
    /// on the wall had nothing to balance it. Seen in a crack opening across a grid plane (the
    /// flush cube at 100^3, step 72): the cell above the plane took 0.016 Pa from its y sweep on
    /// a whole cell face, the vacuum cell below 0, and the gap's 1e-4 of mass was left at -12
    /// m/s.
    fn vacuum_wall(&self, k: usize) -> bool {
        let (dim, nvar) = (self.config.grid.dim, self.config.grid.dim + 2);
        let (vr, vp) = self.config.vacuum;
        let u = full_state(&self.near.saved[k * nvar..(k + 1) * nvar], dim, 1.0);
        let w = crate::fv::euler::primitive_floored(&u, self.config.gamma, vr);
        !(w.rho >= vr && w.p >= vp)
    }

    /// Near cells, their faces, the ghost fills, and `U^n` (after the first sweep's ghosts).
    fn prepare(&mut self, solver: &mut FluidSolver) {
        self.collect_near_cells();
        self.wall_hooks(solver);
        self.taps(solver);
        self.near.hooks.pressure_cells.clone_from(&self.near.cells);
        self.save_states(solver);
    }

    /// The ghost fills, wall runs and vacuum cells of this rank's cells: from the whole grid's
    /// geometry on one rank, from its block and a halo around it on a decomposed grid (the
    /// same bits on the rank's cells; `hooks.rs`). On the fluid's pool (the cells' walls are
    /// summed in parallel, the same bits on any number of threads).
    ///
    /// NOTE: a decomposed grid's rank reads the window of its block in the whole grid's geometry
    /// of `F^n` it holds (`wall_hooks_in`), which the correct before computed, rather than
    /// computing that window's geometry again (`cutcell::compute_block_cells`, about a sixth of
    /// a rank's hooks on `opening-fracture-3d` at 100³ on 2 ranks).
    fn wall_hooks(&mut self, solver: &FluidSolver) {
        let (grid, ng) = (&self.config.grid, self.config.ng);
        let (geom, current) = (&self.state.geom, &self.state.current);
        let (block, near, held) = (self.config.block, &self.near, self.config.held_box());
        let hooks = solver.install(|| match block {
            None => {
                let view = HookGeometry {
                    grid,
                    window: CellBox::whole(grid),
                    held: CellBox::whole(grid),
                    solid_fraction: &geom.solid_fraction,
                    subfaces: &geom.subfaces,
                };
                let near = NearView {
                    cells: &near.cells,
                    slot_of: near.slot_of.whole_grid(),
                    slot_box: CellBox::whole(grid),
                };
                view.wall_hooks(&near, current, ng, CellBox::whole(grid))
            }
            Some(block) => match &geom.fractions {
                Some(f) => {
                    // The slots are dense over the held box, as Λ is.
                    debug_assert_eq!(f.held, held);
                    let near = NearView {
                        cells: &near.cells,
                        slot_of: near.slot_of.held_dense(),
                        slot_box: held,
                    };
                    wall_hooks_held(grid, ng, current, f, &geom.cut, block, &near)
                }
                None => wall_hooks_in(grid, ng, current, geom, block),
            },
        });
        let h = &mut self.near.hooks;
        (h.ghosts, h.walls, h.vacuum) = (hooks.ghosts, hooks.walls, hooks.vacuum);
    }

    /// The cut cells of `F^n` dilated by [`NEAR_RADIUS`] cells, ascending, and their slots.
    fn collect_near_cells(&mut self) {
        let grid = &self.config.grid;
        let near = &mut self.near;
        near.slot_of.clear(&near.cells);
        // NOTE: marked in a bit set, a row of each neighbourhood at a time, and read out in
        // order (`cells_around`): the ascending list that sorting them gave (that sort was
        // 1.2 % of the fluid node's time in `cube-mobile-walls` on 50³).
        let cut: Vec<[usize; 3]> = (self.state.geom.cut_cells.iter())
            .map(|&c| grid.ijk(c as usize))
            .collect();
        near.cells = cells_around(grid, &cut, NEAR_RADIUS);
        for (slot, &c) in near.cells.iter().enumerate() {
            near.slot_of.set(c as usize, slot as u32 + 1);
        }
        near.own = OwnSlots::of(grid, &near.cells, self.config.block);
    }

    /// Taps: the faces of the near cells, per axis, grouped by pencil. The axes are their own
    /// (their taps and face slots): they run in parallel on the fluid's pool.
    ///
    /// On a decomposed grid, those a rank's sweeps compute or its correct reads (issue 40 item
    /// 1): the faces of its own near cells, and along a cut axis the faces on its block's low
    /// side of the near cells below it (the block below reads them; the solver sends them,
    /// `FluidSolver::predict`). A face's flux does not depend on which faces are kept.
    ///
    /// NOTE: the second rule matters where the cell across that face is no near cell, so that
    /// the block above keeps the face for none of its own cells: after a surface moved more than
    /// a cell in a step (the `fv_ranks` test `a_surface_jumping_towards_a_cut_...`: without the
    /// rule the block below reads 0 there).
    fn taps(&mut self, solver: &FluidSolver) {
        let grid = &self.config.grid;
        let block = self.config.block;
        let NearCells { cells, hooks, .. } = &mut self.near;
        let cells: Vec<[usize; 3]> = cells.iter().map(|&c| grid.ijk(c as usize)).collect();
        // No near cell: an empty box, no face kept.
        let bounds = bounding_box(&cells).unwrap_or(CellBox {
            lo: [0; 3],
            hi: [0; 3],
        });
        let cells = &cells;
        let axes = hooks.taps.par_iter_mut().enumerate();
        solver.install(|| {
            axes.take(grid.dim).for_each(|(axis, tap)| {
                let n = grid.cells[axis];
                let count = grid.n_cells() / n;
                // NOTE: the faces `(pencil, position)` are marked in a bit set of the faces of
                // the near cells' bounding box along `axis`, rows along `axis`, the other axes
                // in the pencils' order, and read out in order: the ascending list without
                // duplicates that sorting them gave (that sort was 1.3 % of the fluid node's
                // time in `cube-mobile-walls`). A bit set of every face of the grid was zeroed
                // and read out in every predict on every rank (issue 40 item 1).
                let (o1, o2) = pencil_axes(axis);
                let mut size = [0, 1, 2].map(|a| bounds.size(a));
                size[axis] += 1;
                let mut marks = BoxMarks::new([axis, o1, o2], bounds.lo, size);
                for &ijk in cells {
                    let m = ijk[axis];
                    let faces = match block {
                        None => m..m + 2,
                        Some(b) => {
                            let across =
                                (0..3).all(|a| a == axis || b.lo[a] <= ijk[a] && ijk[a] < b.hi[a]);
                            if !across {
                                continue;
                            } else if b.lo[axis] <= m && m < b.hi[axis] {
                                m..m + 2
                            } else if m + 1 == b.lo[axis] {
                                m + 1..m + 2
                            } else {
                                continue;
                            }
                        }
                    };
                    let mut first = ijk;
                    first[axis] = faces.start;
                    marks.mark_row(first, faces.end - 1);
                }
                let mut keys: Vec<(u32, u32)> = Vec::new();
                marks.for_each(|q| {
                    let p = q[o1] + grid.cells[o1] * q[o2];
                    keys.push((p as u32, q[axis] as u32));
                });
                tap.clear(count);
                for &(p, m) in &keys {
                    tap.pencil_offsets[p as usize + 1] += 1;
                    tap.positions.push(m);
                }
                for p in 0..count {
                    tap.pencil_offsets[p + 1] += tap.pencil_offsets[p];
                }
            });
        });
    }

    /// `U^n` of the near cells, with the ghosts of the first sweep in the covered ones (of a
    /// later sweep where the first gives none): each rank takes those of its own near cells,
    /// from its own ghost fills, and every rank gathers all of them (collective).
    fn save_states(&mut self, solver: &mut FluidSolver) {
        let dim = self.config.grid.dim;
        let order = crate::fv::sweep_order(dim, solver.steps());
        let first = order[0];
        solver.apply_ghosts(first, &self.near.hooks.ghosts[first]);
        solver.apply_vacuum(&self.near.hooks.vacuum);
        let nvar = dim + 2;
        let own: Vec<u32> = (self.near.own.iter()).map(|k| self.near.cells[k]).collect();
        let u = solver.own_cells_at(&own);
        let mut ghosted: Vec<u32> = (self.near.hooks.ghosts[first].iter())
            .map(|g| g.cell)
            .collect();
        ghosted.sort_unstable();
        // NOTE: a covered cell the first sweep gives no ghost (farther than the stencil from
        // any fluid along that axis) keeps a stale state. The solid can uncover it in this step
        // (a face parallel to that axis retreating): its `U^n` is then its content and the
        // source of the prisms reaching into it, and 0 there broke a uniform flow carried past
        // a box 12 cells long in 2-D by 3e-2 of its state. It takes the ghost of a later sweep
        // instead, which is the flow itself for a uniform flow at the wall's velocity. Where
        // cracks may open it is vacuum, so that a crack opening there in this step (its faces
        // are wet only at `t^{n+1}`) starts empty (as its faces to cells covered at `t^n` carry
        // nothing then, see `face_fluxes`).
        let later = if self.config.fracture {
            Vec::new()
        } else {
            self.later_ghosts(solver, &order[1..], &ghosted)
        };
        let geom = &self.state.geom;
        let mut mine = Vec::with_capacity(u.len());
        for (k, &c) in own.iter().enumerate() {
            let stale = geom.lambda(c as usize) >= 1.0 - COVERED_TOLERANCE
                && ghosted.binary_search(&c).is_err();
            if !stale {
                extend_cell(&mut mine, &u[k * nvar..(k + 1) * nvar]);
            } else if let Ok(i) = later.binary_search_by_key(&c, |g| g.0) {
                mine.extend_from_slice(&later[i].1[..nvar]);
            } else {
                mine.extend(std::iter::repeat_n(0.0, nvar));
            }
        }
        let near = &mut self.near;
        solver.gather_owned_into(&near.cells, mine, nvar, &mut near.saved);
    }

    /// The ghost state of each covered near cell of this rank that the first sweep leaves
    /// without one, from the first of the later sweeps (`axes`, in order) that gives it one, by
    /// cell (collective: the mirrored cells may lie on other ranks).
    fn later_ghosts(
        &self,
        solver: &FluidSolver,
        axes: &[usize],
        ghosted: &[u32],
    ) -> Vec<(u32, [f64; NQ])> {
        let dim = self.config.grid.dim;
        let geom = &self.state.geom;
        let stale = |c: u32| {
            geom.lambda(c as usize) >= 1.0 - COVERED_TOLERANCE
                && self.near.slot_of[c as usize] > 0
                && ghosted.binary_search(&c).is_err()
        };
        // (cell, axis, fill) of the first later fill of each such cell.
        let mut picked: Vec<(u32, usize, &GhostFill)> = Vec::new();
        for &axis in axes {
            for g in &self.near.hooks.ghosts[axis] {
                if stale(g.cell) {
                    picked.push((g.cell, axis, g));
                }
            }
        }
        picked.sort_by_key(|p| p.0);
        picked.dedup_by_key(|p| p.0);
        let mut wanted: Vec<u32> = picked.iter().map(|p| p.2.mirror_of).collect();
        wanted.sort_unstable();
        wanted.dedup();
        let (sources, values) = solver.cells_asked(&wanted);
        let nvar = dim + 2;
        picked
            .iter()
            .map(|&(cell, axis, g)| {
                let k = sources.binary_search(&g.mirror_of).expect("a source");
                let fr = frame(dim, axis);
                let local = to_local(&values[k * nvar..(k + 1) * nvar], dim, &fr);
                let ghost = mirror(&local, &g.wall.in_frame(&fr));
                let mut state = [0.0; NQ];
                from_local(&ghost, dim, &fr, &mut state[..nvar]);
                (cell, state)
            })
            .collect()
    }
}
