//! Step 1 of paper 003 §3.4: the split sweeps over the whole grid, with the ghost states of the
//! covered cells, keeping `U^n`, `p̄` and the face fluxes of the cells near the wet surface.

use super::cells::{domain_face, full_state, offsets, shifted, touches_gas};
use super::near_wall::{
    NEAR_WALL_SUMS, NW_AREA, NW_FACING, NW_FACING_LEN, NW_NORMAL, NW_VELOCITY, NW_WET_AREA,
    NW_WET_NORMAL, NearWall,
};
use super::{COVERED_TOLERANCE, Embedded, NEAR_RADIUS};
use crate::cutcell::face_index;
use crate::fv::euler::NQ;
use crate::fv::sweep::{frame, from_local, to_local};
use crate::fv::{FluidSolver, GhostFill, StepReport, Wall, WallRun, mirror};

impl Embedded {
    /// Step 1 of paper 003 §3.4: the split sweeps, keeping what the correct needs.
    pub fn predict(&mut self, solver: &mut FluidSolver, dt: f64) -> StepReport {
        self.prepare(solver);
        let lambda = &self.state.geom.solid_fraction;
        let covered = |c: usize| lambda[c] >= 1.0 - COVERED_TOLERANCE;
        let report = solver.predict(dt, &mut self.near.hooks, &covered);
        self.wall_pressures(solver, report.sweeps[0]);
        self.vacuum_walls();
        report
    }

    /// `p̄` of every near cell, the pressure of the wet faces it holds (or, covered at `t^n`,
    /// faces): the mean of its pressure at `t^n` (what the first sweep starts from) and after
    /// the sweeps, on every axis; in a covered cell the mirrored fluid's at `t^n`.
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
        let lambda = &self.state.geom.solid_fraction;
        let predicted = solver.cells_at(&self.near.cells);
        let near = &mut self.near;
        near.wall_pressure.clear();
        for (k, &c) in near.cells.iter().enumerate() {
            let start = near.hooks.pressures[first][k];
            let p = if lambda[c as usize] >= 1.0 - COVERED_TOLERANCE {
                start
            } else {
                let u = full_state(&predicted[k * nvar..(k + 1) * nvar], dim, 1.0);
                let end = crate::fv::euler::primitive_floored(&u, gamma, vr).p;
                0.5 * (start + end)
            };
            near.wall_pressure.push(p);
        }
    }

    /// NOTE: a wet face in a cell that held vacuum at `t^n` takes no gas pressure. The sweeps
    /// give that cell the gas they bring in from its neighbours, and a later sweep starts from
    /// it; but the faces to the cell's other vacuum neighbours carry nothing (Lax–Friedrichs of
    /// vacuum against vacuum, or a crack's flux from `U^n`), so that pressure on the wall had
    /// nothing to balance it. Seen in a crack opening across a grid plane (the flush cube at
    /// 100^3, step 72): the cell above the plane took 0.016 Pa from its y sweep on a whole
    /// cell face, the vacuum cell below 0, and the gap's 1e-4 of mass was left at -12 m/s.
    fn vacuum_walls(&mut self) {
        let (dim, nvar) = (self.config.grid.dim, self.config.grid.dim + 2);
        let (vr, vp) = self.config.vacuum;
        let lambda = &self.state.geom.solid_fraction;
        let near = &mut self.near;
        for (k, &c) in near.cells.iter().enumerate() {
            if lambda[c as usize] >= 1.0 - COVERED_TOLERANCE {
                continue;
            }
            let u = full_state(&near.saved[k * nvar..(k + 1) * nvar], dim, 1.0);
            let w = crate::fv::euler::primitive_floored(&u, self.config.gamma, vr);
            if !(w.rho >= vr && w.p >= vp) {
                near.wall_pressure[k] = 0.0;
            }
        }
    }

    /// Near cells, their faces, the ghost fills, and `U^n` (after the first sweep's ghosts).
    fn prepare(&mut self, solver: &mut FluidSolver) {
        self.collect_near_cells();
        let closed = self.near_walls();
        self.vacuum_cells(&closed);
        self.taps();
        // Ghost fills per axis.
        for axis in 0..3 {
            self.near.hooks.ghosts[axis].clear();
            self.near.hooks.walls[axis].clear();
        }
        for axis in 0..self.config.grid.dim {
            self.ghost_fills(axis);
        }
        self.near.hooks.pressure_cells.clone_from(&self.near.cells);
        self.save_states(solver);
    }

    /// The cut cells of `F^n` dilated by [`NEAR_RADIUS`] cells, ascending, and their slots.
    fn collect_near_cells(&mut self) {
        let grid = &self.config.grid;
        let near = &mut self.near;
        for &c in &near.cells {
            near.slot_of[c as usize] = 0;
        }
        near.cells.clear();
        let r = NEAR_RADIUS as isize;
        let span: Vec<[isize; 3]> = offsets(grid.dim, r);
        for &c in &self.state.geom.cut_cells {
            let ijk = grid.ijk(c as usize);
            for d in std::iter::once(&[0isize; 3]).chain(&span) {
                if let Some(n) = shifted(grid, ijk, *d) {
                    let n = grid.index(n[0], n[1], n[2]);
                    if near.slot_of[n] == 0 {
                        near.slot_of[n] = 1;
                        near.cells.push(n as u32);
                    }
                }
            }
        }
        near.cells.sort_unstable();
        for (k, &c) in near.cells.iter().enumerate() {
            near.slot_of[c as usize] = k as u32 + 1;
        }
    }

    /// The wall of the near cells that hold sub-faces, summed apart from the sub-faces' order
    /// (the sub-faces come in cell order; slots are the fields of `NearWall::from_sums`).
    /// Returns, per slot, whether a covered near cell holds a wet face with no gas in front (see
    /// `touches_gas`). The walls' velocities are still sums (see [`Embedded::vacuum_cells`]).
    fn near_walls(&mut self) -> Vec<bool> {
        let grid = &self.config.grid;
        let dim = grid.dim;
        let near = &mut self.near;
        let current = &self.state.current;
        let geom = &self.state.geom;
        near.walls.clear();
        near.walls.resize(near.cells.len(), NearWall::default());
        let mut sum = std::mem::take(&mut self.scratch.odd);
        let subfaces = &geom.subfaces;
        let mut closed = vec![false; near.cells.len()];
        let mut first = 0;
        while first < subfaces.len() {
            let cell = subfaces[first].cell;
            let mut end = first;
            sum.clear();
            while end < subfaces.len() && subfaces[end].cell == cell {
                let s = &subfaces[end];
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
                    if !touches_gas(grid, &geom.solid_fraction, s) {
                        closed[near.slot_of[cell as usize] as usize - 1] = true;
                    }
                }
                end += 1;
            }
            let mut fields = [0.0; NEAR_WALL_SUMS];
            sum.add_into(&mut fields);
            let k = near.slot_of[cell as usize] as usize - 1;
            near.walls[k] = NearWall::from_sums(&fields);
            first = end;
        }
        self.scratch.odd = sum;
        closed
    }

    /// Covered cells between the two faces of a crack that has just opened hold no fluid yet:
    /// vacuum (paper 000 §3.2), not ghost states. Where the two faces lie on either side of a
    /// grid plane (pressed walls whose faces were on it), each cell holds one, with the other's
    /// covered cell in front (`closed`). Then the walls' velocities become area averages.
    fn vacuum_cells(&mut self, closed: &[bool]) {
        let near = &mut self.near;
        let lambda = &self.state.geom.solid_fraction;
        near.hooks.vacuum.clear();
        for (k, &c) in near.cells.iter().enumerate() {
            if lambda[c as usize] >= 1.0 - COVERED_TOLERANCE
                && (near.walls[k].is_crack() || closed[k])
            {
                near.hooks.vacuum.push(c);
            }
        }
        for nw in &mut near.walls {
            if nw.area > 0.0 {
                for x in nw.velocity.iter_mut() {
                    *x /= nw.area;
                }
            }
        }
    }

    /// Taps: the faces of the near cells, per axis, grouped by pencil.
    fn taps(&mut self) {
        let grid = &self.config.grid;
        let near = &mut self.near;
        for axis in 0..grid.dim {
            let stride: usize = grid.cells[..axis].iter().product();
            let n = grid.cells[axis];
            let count = grid.n_cells() / n;
            let mut keys: Vec<(u32, u32)> = Vec::with_capacity(2 * near.cells.len());
            for &c in &near.cells {
                let c = c as usize;
                let m = (c / stride) % n;
                let p = c % stride + (c / (stride * n)) * stride;
                keys.push((p as u32, m as u32));
                keys.push((p as u32, m as u32 + 1));
            }
            keys.sort_unstable();
            keys.dedup();
            let tap = &mut near.hooks.taps[axis];
            tap.clear(count);
            for &(p, m) in &keys {
                tap.pencil_offsets[p as usize + 1] += 1;
                tap.positions.push(m);
            }
            for p in 0..count {
                tap.pencil_offsets[p + 1] += tap.pencil_offsets[p];
            }
            let slots = &mut near.face_slots[axis];
            slots.clear();
            for (slot, &(p, m)) in keys.iter().enumerate() {
                let p = p as usize;
                let base = p % stride + (p / stride) * stride * n;
                let mut ijk = grid.ijk(base);
                ijk[axis] = m as usize;
                slots.push((face_index(grid, axis, ijk) as u32, slot as u32));
            }
            slots.sort_unstable();
        }
    }

    /// `U^n` of the near cells, with the ghosts of the first sweep in the covered ones (of a
    /// later sweep where the first gives none).
    fn save_states(&mut self, solver: &mut FluidSolver) {
        let dim = self.config.grid.dim;
        let order = crate::fv::sweep_order(dim, solver.steps());
        let first = order[0];
        solver.apply_ghosts(first, &self.near.hooks.ghosts[first]);
        solver.apply_vacuum(&self.near.hooks.vacuum);
        let nvar = dim + 2;
        let u = solver.cells_at(&self.near.cells);
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
        let lambda = &self.state.geom.solid_fraction;
        let near = &mut self.near;
        near.saved.clear();
        for (k, &c) in near.cells.iter().enumerate() {
            let stale =
                lambda[c as usize] >= 1.0 - COVERED_TOLERANCE && ghosted.binary_search(&c).is_err();
            if !stale {
                near.saved.extend_from_slice(&u[k * nvar..(k + 1) * nvar]);
            } else if let Ok(i) = later.binary_search_by_key(&c, |g| g.0) {
                near.saved.extend_from_slice(&later[i].1[..nvar]);
            } else {
                near.saved.extend(std::iter::repeat_n(0.0, nvar));
            }
        }
    }

    /// The ghost state of each covered near cell that the first sweep leaves without one, from
    /// the first of the later sweeps (`axes`, in order) that gives it one, by cell (collective:
    /// the mirrored cells may lie on other ranks).
    fn later_ghosts(
        &self,
        solver: &FluidSolver,
        axes: &[usize],
        ghosted: &[u32],
    ) -> Vec<(u32, [f64; NQ])> {
        let dim = self.config.grid.dim;
        let lambda = &self.state.geom.solid_fraction;
        let stale = |c: u32| {
            lambda[c as usize] >= 1.0 - COVERED_TOLERANCE
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
        let mut sources: Vec<u32> = picked.iter().map(|p| p.2.mirror_of).collect();
        sources.sort_unstable();
        sources.dedup();
        let values = solver.cells_at(&sources);
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

    /// The ghost states of the covered near cells for the sweep along `axis`, and the walls
    /// thinner than `2 ng` cells where that sweep cuts its pencils.
    fn ghost_fills(&mut self, axis: usize) {
        let grid = &self.config.grid;
        let lambda = &self.state.geom.solid_fraction;
        let n = grid.cells[axis] as isize;
        let ng = self.config.ng as isize;
        let near = &mut self.near;
        let fills = &mut near.hooks.ghosts[axis];
        let walls = &mut near.hooks.walls[axis];
        let (slot_of, near_walls, near_cells) = (&near.slot_of, &near.walls, &near.cells);
        // A crack cell is vacuum fluid to the sweeps, not a covered cell.
        let vacuum = &near.hooks.vacuum;
        let covered = |q: usize| {
            lambda[q] >= 1.0 - COVERED_TOLERANCE && vacuum.binary_search(&(q as u32)).is_err()
        };
        let stride: usize = grid.cells[..axis].iter().product();
        // The wall seen along the axis from `fluid` beside the covered cell `covered`: the fluid
        // cell's sub-faces, else the covered cell's, else a wall at rest normal to the axis.
        // The sub-faces turned towards the fluid first: a thin gap between a wall at rest and a
        // moving one must mirror each side about its own wall.
        let wall_seen = |fluid: usize, covered: usize, dir: isize| -> Wall {
            let walls = [fluid, covered]
                .map(|c| slot_of[c] as usize)
                .map(|k| (k > 0).then(|| &near_walls[k - 1]));
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
        for &c in near_cells {
            let c = c as usize;
            if !covered(c) {
                continue;
            }
            let ijk = grid.ijk(c);
            let at = |m: isize| -> Option<usize> {
                (0..n).contains(&m).then(|| {
                    let mut q = ijk;
                    q[axis] = m as usize;
                    grid.index(q[0], q[1], q[2])
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
                let wall = wall_seen(fluid, c, dir);
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
                        cell: dst as u32,
                        mirror_of: src as u32,
                        wall,
                    });
                }
            }
        }
        walls.sort_unstable_by_key(|w| (w.pencil, w.lo));
    }
}
