//! One split step: the sweep order, the sweeps along each axis with their outflow, counters
//! and troubles, and their merge over the ranks in a fixed order.

use std::sync::OnceLock;

use rayon::prelude::*;

use crate::fv::euler::NQ;
use crate::fv::line::state_ok;
use crate::fv::solver::cell::{BLOCK_CELLS, cell_primitive, items_per_task, to_full};
use crate::fv::solver::{
    FluidSolver, MAX_TROUBLES, RefusedTimeStep, SplitHooks, StepReport, Trouble, TroubleKind,
};
use crate::fv::sweep::{Pencils, SlabHalo, sweep_axis};

/// Sweep orders of 3-D steps: each consecutive pair is a sequence and its reverse, and the six
/// steps cover all permutations.
///
/// NOTE: paper 003 §3.4 step 1 and Tenaud's `mr_chorus.f90` cycle through the 6 permutations
/// (second order every 6 steps); pairing each order with its reverse (`xyz`, `zyx`, ...) makes
/// every two consecutive steps a Strang-type symmetric product, so the splitting is second
/// order over each pair while all permutations are still visited.
const ORDERS_3D: [[usize; 3]; 6] = [
    [0, 1, 2],
    [2, 1, 0],
    [1, 2, 0],
    [0, 2, 1],
    [2, 0, 1],
    [1, 0, 2],
];

/// Sweep axes of step `step` in dimension `dim`.
pub fn sweep_order(dim: usize, step: u64) -> Vec<usize> {
    match dim {
        1 => vec![0],
        2 => {
            if step.is_multiple_of(2) {
                vec![0, 1]
            } else {
                vec![1, 0]
            }
        }
        _ => ORDERS_3D[(step % 6) as usize].to_vec(),
    }
}

/// What one rank's sweeps of a step found, gathered from every rank in rank order and merged
/// in a fixed order (so that the report does not depend on the number of ranks).
#[derive(Default, serde::Serialize, serde::Deserialize)]
struct SweepSummary {
    /// Outflow partial sums `dt × area × flux` (`outflow::partials`): per plane of the last
    /// axis for a sweep along another axis; for a sweep along the last axis one for the low and
    /// one for the high domain face, from the ranks that hold them (with blocks, all of them
    /// from rank 0).
    partials: Vec<[f64; NQ]>,
    lax_friedrichs: u64,
    hlle: u64,
    positivity_fixes: u64,
    /// `(global pencil, trouble)`, pencils ascending, at most [`MAX_TROUBLES`].
    troubles: Vec<(u64, Trouble)>,
}

impl FluidSolver {
    /// Advances by one split step of length `dt` \[s\]: one full-`dt` sweep per active axis, in
    /// the order [`sweep_order`] gives for the current step number. Never panics on numerical
    /// trouble: it is listed in the report and the caller stops the run.
    pub fn advance(&mut self, dt: f64) -> StepReport {
        let mut report = self.sweeps(dt, None);
        report.totals = self.totals_and_max_dt();
        report
    }

    /// The predict of a coupled step (paper 003 §3.4 step 1): the split sweeps of
    /// [`FluidSolver::advance`] over the whole grid, with the ghost states, pressures and face
    /// fluxes `hooks` asks for. Cells for which `covered` is true hold ghost states and are not
    /// checked. The report's totals are left empty: the embedded update corrects the cells near
    /// the solid afterwards, and its totals weigh cells by their fluid fraction.
    ///
    /// `hooks` and `covered` name cells of the whole grid ([`FluidSolver::global_grid`]): each
    /// rank applies the ghosts and vacuum of its own cells and keeps the pressures of its own
    /// cells and the fluxes of the faces of its own cells (those of the faces on its block's
    /// high sides from the blocks above, where they keep them too; collective).
    pub fn predict(
        &mut self,
        dt: f64,
        hooks: &mut SplitHooks,
        covered: &(dyn Fn(usize) -> bool + Sync),
    ) -> StepReport {
        self.sweeps(dt, Some((hooks, covered)))
    }

    fn sweeps(
        &mut self,
        dt: f64,
        mut hooks: Option<(&mut SplitHooks, &(dyn Fn(usize) -> bool + Sync))>,
    ) -> StepReport {
        let order = sweep_order(self.grid.dim, self.step);
        let mut report = StepReport {
            step: self.step,
            dt,
            time: self.time,
            sweeps: order.clone(),
            ..StepReport::default()
        };
        if let Some(refused) = self.refuse_time_step(dt) {
            report.refused = Some(refused);
            return report;
        }
        let area_dt: Vec<f64> = (0..self.grid.dim)
            .map(|a| dt * self.grid.cell_volume() / self.grid.dx[a])
            .collect();
        self.dt_cache = OnceLock::new();
        self.sums_cache = OnceLock::new();
        let mut summaries: Vec<SweepSummary> = Vec::with_capacity(order.len());
        for &axis in &order {
            self.prepare_sweep(axis, hooks.as_mut().map(|(h, _)| &mut **h));
            self.sweep_along(axis, dt, hooks.is_some());
            let covered = hooks.as_ref().map(|(_, covered)| *covered);
            summaries.push(self.summarize_sweep(axis, area_dt[axis], covered));
        }
        if let Some((h, _)) = hooks.as_mut() {
            self.gather_hook_outputs(h, &order);
        }
        self.merge_summaries(summaries, &mut report);
        for q in 0..NQ {
            self.outflow[q] += report.outflow[q];
        }
        self.step += 1;
        self.time += dt;
        report.time = self.time;
        report
    }

    /// The one check of the time step (the node's and the tests' alike): `dt` must be finite,
    /// positive and at most the CFL step at Courant number 1, `max_dt / cfl`, with a relative
    /// slack of 1e-12 for the rounding of that quotient.
    ///
    /// NOTE: the limit is Courant number 1, the stability bound of the directional sweeps, not
    /// the scene's `cfl`: [`FluidSolver::max_dt`] proposes steps at Courant number `cfl` ≤ 1,
    /// and the coupler takes the minimum of the proposals, so every run steps within it; the
    /// check catches a bug or a tampered plan, and a step the scheme cannot take stably.
    fn refuse_time_step(&self, dt: f64) -> Option<RefusedTimeStep> {
        let limit = self.max_dt() / self.params.cfl;
        if dt.is_finite() && dt > 0.0 && dt <= limit * (1.0 + 1e-12) {
            return None;
        }
        Some(RefusedTimeStep { dt, limit })
    }

    /// Before the sweep along `axis`: the directional pressures of the whole grid, then (a
    /// coupled step) the ghost states, vacuum and kept pressures `hooks` asks for and this
    /// rank's part of its taps and walls, and the halo of the neighbours along `axis` if cut.
    fn prepare_sweep(&mut self, axis: usize, hooks: Option<&mut SplitHooks>) {
        self.record_pressures(axis);
        if let Some(h) = hooks {
            self.apply_ghosts(axis, &h.ghosts[axis]);
            self.apply_vacuum(&h.vacuum);
            self.record_pressures_at(&h.pressure_cells, &mut h.pressures[axis]);
            self.local
                .localize(&self.slab, axis, &h.taps[axis], &h.walls[axis]);
        }
        if self.slab.cut(axis) {
            self.exchange_halo(axis);
        }
    }

    /// The sweep along `axis` over every pencil (with this rank's taps and walls in a coupled
    /// step), written back into the state.
    fn sweep_along(&mut self, axis: usize, dt: f64, coupled: bool) {
        let along_cut = self.slab.cut(axis);
        let grid = &self.grid;
        let params = &self.params;
        let (u, buffer) = (&self.state.u, &mut self.buffer);
        let (scratch, pencil_out) = (&self.scratch, &mut self.pencil_out);
        let (tap, walls) = if coupled {
            (
                Some(&mut self.local.taps[axis]),
                &self.local.walls[axis][..],
            )
        } else {
            (None, &[][..])
        };
        let slab = &self.slab;
        let halo = if along_cut {
            let below = if slab.lo[axis].is_some() {
                slab.overlap
            } else {
                0
            };
            SlabHalo {
                lo: slab.lo[axis].map(|_| &self.halo[axis][0][..]),
                hi: slab.hi[axis].map(|_| &self.halo[axis][1][..]),
                depth: slab.depth,
                overlap: slab.overlap,
                n_global: slab.global.cells[axis],
                start: slab.offset[axis] as isize - below as isize,
            }
        } else {
            SlabHalo::none(grid.cells[axis])
        };
        self.pool.install(|| {
            sweep_axis(
                grid, params, axis, dt, u, buffer, scratch, pencil_out, tap, walls, &halo,
            );
        });
        std::mem::swap(&mut self.state.u, &mut self.buffer);
    }

    /// What this rank's pencils of the sweep along `axis` found: the outflow partials (`area`
    /// is `dt × cell volume / Δx_axis`), the face counters and the troubled cells (in a coupled
    /// step the first one of each pencil that `covered` does not cover).
    fn summarize_sweep(
        &self,
        axis: usize,
        area: f64,
        covered: Option<&(dyn Fn(usize) -> bool + Sync)>,
    ) -> SweepSummary {
        let count = self.grid.n_cells() / self.grid.cells[axis];
        let mut summary = SweepSummary::default();
        let reps = &self.pencil_out[..count];
        let slab = &self.slab;
        // NOTE: a covered cell at the open end of a pencil holds a ghost state, not gas: the
        // flux through its domain face is not what left (a square at rest flush against an
        // outflow side lost 1.5e-3 of the mass in 10 steps through the covered cells there
        // that are not near its cut cells). The embedded solid counts the faces of the near
        // cells (`add_outflow`).
        let pencils = Pencils::new(&self.grid, axis);
        let sides = self.params.boundary[axis];
        let ends_in_gas = |p: usize, side: usize| {
            !sides[side].is_open()
                || covered.is_none_or(|covered| {
                    let c = pencils.base(p) + side * (pencils.n - 1) * pencils.stride;
                    !covered(slab.to_global(c))
                })
        };
        summary.partials = self.outflow_partials(axis, area, &ends_in_gas);
        for (p, rep) in reps.iter().enumerate() {
            summary.lax_friedrichs += u64::from(rep.stats.lax_friedrichs);
            summary.hlle += u64::from(rep.stats.hlle);
            summary.positivity_fixes += u64::from(rep.stats.positivity_fixes);
            if let Some(idx) = rep.trouble
                && summary.troubles.len() < MAX_TROUBLES
            {
                let found = match covered {
                    Some(covered) => self.first_checked_trouble(axis, idx, covered),
                    None => Some(idx),
                };
                if let Some(idx) = found {
                    let pencil = slab.global_pencil(axis, p) as u64;
                    summary.troubles.push((pencil, self.trouble_at(idx, axis)));
                }
            }
        }
        summary
    }

    /// Adds the sweeps' summaries of every rank to `report` in a fixed order: sweep by sweep,
    /// the partials in rank order (= plane order), the troubles by pencil (on a cut axis,
    /// the lowest rank's trouble of a pencil is the one nearest its start).
    fn merge_summaries(&self, mine: Vec<SweepSummary>, report: &mut StepReport) {
        let all: Vec<Vec<SweepSummary>> = if self.slab.ranks == 1 {
            vec![mine]
        } else {
            let bytes = protocol::codec::encode_blob(&mine);
            self.comm
                .all_gather(&bytes)
                .iter()
                .map(|b| protocol::codec::decode_blob(b).expect("ranks send valid summaries"))
                .collect()
        };
        let n_sweeps = all[0].len();
        for sweep in 0..n_sweeps {
            let mut troubles: Vec<(u64, Trouble)> = Vec::new();
            for rank in &all {
                let s = &rank[sweep];
                for partial in &s.partials {
                    for q in 0..NQ {
                        report.outflow[q] += partial[q];
                    }
                }
                report.lax_friedrichs_faces += s.lax_friedrichs;
                report.hlle_faces += s.hlle;
                report.positivity_fixes += s.positivity_fixes;
                troubles.extend(s.troubles.iter().copied());
            }
            // Stable: among equal pencils the lowest rank stays first.
            troubles.sort_by_key(|(pencil, _)| *pencil);
            troubles.dedup_by_key(|(pencil, _)| *pencil);
            for (_, t) in troubles {
                if report.troubles.len() < MAX_TROUBLES {
                    report.troubles.push(t);
                }
            }
        }
    }

    /// The first troubled cell of the pencil through `idx` along `axis` that is not covered
    /// (`idx` itself when it is not; `covered` takes cells of the whole grid).
    fn first_checked_trouble(
        &self,
        axis: usize,
        idx: usize,
        covered: &(dyn Fn(usize) -> bool + Sync),
    ) -> Option<usize> {
        let global = |c: usize| covered(self.slab.to_global(c));
        if !global(idx) {
            return Some(idx);
        }
        let pencils = Pencils::new(&self.grid, axis);
        let base = idx - self.grid.ijk(idx)[axis] * pencils.stride;
        let gamma = self.params.gamma;
        (0..pencils.n)
            .map(|m| base + m * pencils.stride)
            .filter(|&c| !global(c))
            .find(|&c| {
                let full = to_full(self.state.cell(c), self.grid.dim);
                !state_ok(&full, gamma, self.params.vacuum_rho, self.params.vacuum_p)
            })
    }

    /// Advances with CFL-limited steps until `t_end` \[s\] (the last step is shortened to land on
    /// it) or `max_steps` steps or the first trouble; returns the last report and the steps
    /// taken.
    pub fn run_until(&mut self, t_end: f64, max_steps: u64) -> (u64, StepReport) {
        let mut steps = 0;
        let mut last = StepReport::default();
        while self.time < t_end * (1.0 - 1e-14) && steps < max_steps {
            let dt = self.max_dt().min(t_end - self.time);
            last = self.advance(dt);
            steps += 1;
            if !last.ok() {
                break;
            }
        }
        (steps, last)
    }

    fn record_pressures(&mut self, axis: usize) {
        if self.pbar.is_empty() {
            return;
        }
        let nvar = self.state.nvar;
        let dim = self.grid.dim;
        let gamma = self.params.gamma;
        let (u, pbar) = (&self.state.u, &mut self.pbar[axis]);
        self.pool.install(|| {
            pbar.par_chunks_mut(BLOCK_CELLS)
                .zip(u.par_chunks(BLOCK_CELLS * nvar))
                .with_max_len(items_per_task(BLOCK_CELLS))
                .for_each(|(p, cells)| {
                    for (p, cell) in p.iter_mut().zip(cells.chunks_exact(nvar)) {
                        *p = cell_primitive(cell, dim, gamma).p;
                    }
                });
        });
    }

    fn trouble_at(&self, idx: usize, axis: usize) -> Trouble {
        let (rho, velocity, p) = self.primitive(idx);
        let cell = self.state.cell(idx);
        let kind = if cell.iter().any(|x| !x.is_finite()) || !p.is_finite() {
            TroubleKind::NonFinite
        } else if rho < 0.0 || (rho <= 0.0 && self.params.vacuum_rho <= 0.0) {
            TroubleKind::Density
        } else {
            TroubleKind::Pressure
        };
        let global = &self.slab.global;
        let ijk = global.ijk(self.slab.to_global(idx));
        Trouble {
            kind,
            axis,
            cell: ijk,
            position: global.cell_center(ijk),
            rho,
            velocity,
            p,
        }
    }

    /// Whether every cell of this rank is physical (see `line::state_ok`); the first bad cell
    /// otherwise.
    pub fn check_state(&self) -> Option<Trouble> {
        let gamma = self.params.gamma;
        (0..self.grid.n_cells())
            .find(|&idx| {
                let full = to_full(self.state.cell(idx), self.grid.dim);
                !state_ok(&full, gamma, self.params.vacuum_rho, self.params.vacuum_p)
            })
            .map(|idx| self.trouble_at(idx, 0))
    }
}
