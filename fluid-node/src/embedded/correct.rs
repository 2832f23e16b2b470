//! Steps 6–7 of paper 003 §3.4: eq. (12) in every cell near the solid, with the fluid fluxes
//! weighted by the face apertures of `F^{n+1}` (eq. 13), the solid flux (eq. 26) and the
//! amounts swept by the prisms of the sub-faces (paper 000 eq. 12); then the mixing
//! ([`super::mix`]) and the check of what was written.

use protocol::sum::OddSum;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::beyond::{outside_domain, sweep_beyond};
use super::cells::{
    CellKind, across, domain_face, fluid_part, full_state, overlap_scale, pressure_cell,
    touches_gas,
};
use super::error::Reach;
use super::gather::{
    CellUpdate, Updates, assemble_by_block, gather_solid_flux, gather_swept, gather_updates,
};
use super::levers::Levers;
use super::loads::{add_loads, push_moment};
use super::mix::{Mixed, WrittenCheck};
use super::pool_sum::add_on_pool;
use super::{COVERED_TOLERANCE, Embedded, EmbeddedError, SolidFrame};
use crate::cutcell::{
    SubFace, Surface, compute, face_index, subface_swept_volumes, subface_swept_volumes_of,
};
use crate::fv::euler::NQ;
use crate::fv::{BoundaryKind, FluidSolver};

/// What one [`Embedded::correct`] did (diagnostics).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CorrectReport {
    /// Cells updated by eq. (12).
    pub cut_cells: usize,
    /// Cells mixed into a neighbour.
    pub mixed_cells: usize,
    /// Of those, cells the solid uncovered in this step.
    pub uncovered_cells: usize,
    /// Energy the fluid received through the interface in this step \[J\].
    pub work_received: f64,
    /// Mixing groups that had to take in neighbours to become physical.
    pub widened_groups: usize,
    /// Mixing groups merged into a neighbouring group (their mixture was not physical).
    pub merged_groups: usize,
    /// Cells those groups took in.
    pub widened_cells: usize,
    /// Cells the widest of them took in.
    pub widest_group: usize,
    /// Largest round-off residue dropped from a covered cell (content per unit volume, any
    /// component; at most 1e-13 of that cell's state).
    pub dropped: f64,
}

/// Near cells one task of [`Embedded::fluid_fluxes`] updates at least, and at most four times
/// as many, so that no thread waits long for the other's last task (any split gives the same
/// bits).
const CELLS_PER_TASK: usize = 256;

/// What the solid flux gave the fluid in one step.
struct Exchanged {
    /// Work \[J\].
    work: f64,
    /// Momentum [kg m/s].
    impulse: [f64; 3],
}

impl Exchanged {
    /// Adds one sub-face's `[work, impulse]` (`dim` components of the impulse).
    fn add(&mut self, dim: usize, exchange: &[f64; 4]) {
        for a in 0..dim {
            self.impulse[a] += exchange[1 + a];
        }
        self.work += exchange[0];
    }
}

impl Embedded {
    /// Steps 6–7 of paper 003 §3.4 with the accepted surface and kinematics `accepted`
    /// (`F^{n+1}`, `X^{n+1}`, `V^{n+1/2}`, `Ω^{n+1/2}`), after [`Embedded::predict`] with the
    /// same `dt`. `explicit`: the solid's loads came from `F^n` (one pass), so the solid flux
    /// is taken there too (paper 000 eq. 11) and the exchange balances exactly; the price is
    /// identity (19–21) at `t^{n+1}`, which a tangentially deforming wall then breaks (paper
    /// 003 §4.2). On success the accepted frame becomes the start of the next step.
    pub fn correct(
        &mut self,
        solver: &mut FluidSolver,
        dt: f64,
        accepted: SolidFrame,
        step: u64,
        explicit: bool,
    ) -> Result<CorrectReport, EmbeddedError> {
        let folded = self.sweep(solver, &accepted, step)?;
        let opening = self.opening_cells(solver, &accepted);
        let swept_mass = self.displaced(solver, step, folded)?;
        let mut report = CorrectReport::default();
        let mut leaving = self.fluid_fluxes(solver, dt, step, explicit, &opening, &mut report)?;
        // What the solid flux and the swept amounts add to each near cell's content (slots
        // `k NQ + q`), summed apart from the sub-faces' order.
        let mut gained = std::mem::take(&mut self.scratch.odd_content);
        gained.clear();
        let exchanged = self.solid_flux(solver, dt, &accepted, explicit, &mut gained);
        let swept = self.swept_amounts(step, &mut gained);
        if swept.is_ok() {
            let content = self.scratch.content.as_flattened_mut();
            solver.install(|| add_on_pool(&mut gained, content));
        }
        self.scratch.odd_content = gained;
        swept?;
        let mixed = self.mix(solver, &mut report)?;
        report.mixed_cells = mixed.cells;
        report.work_received = exchanged.work;
        let budget = &mut self.state.budget;
        budget.work_given -= exchanged.work;
        budget.swept_mass += swept_mass;
        for a in 0..3 {
            budget.impulse_given[a] -= exchanged.impulse[a];
        }
        self.check_written(step, &mixed)?;
        for q in 0..NQ {
            leaving[q] += mixed.leaving[q];
        }
        solver.add_outflow(&leaving);
        std::mem::swap(&mut self.state.geom, &mut self.scratch.trial);
        self.state.current = accepted;
        Ok(report)
    }

    /// The geometry of `F^{n+1}` and the prisms its sub-faces sweep back to `F^n`, checked
    /// against identity (3). On the fluid's pool. On a decomposed grid each rank checks its own
    /// near cells, and returns the first of them that fails, for [`Embedded::displaced`] to
    /// agree on with the other ranks.
    ///
    /// Collective on a decomposed grid: each rank computes the geometry of its own block only
    /// (`chained_block_part`: no halo, the running sums of the cut axes passed along the pencils
    /// of blocks, no row swept whole) and one all-gather of every block's share (`block_part`: Λ
    /// and λ as runs of equal values, the sub-faces of its cells) gives every rank the whole
    /// grid's sub-faces and cut cells, and Λ and λ dense in its block and the hooks' halo and
    /// as runs elsewhere (`CutGeometry::assemble_held`, `held.rs`): the bits of one rank, read
    /// anywhere, without the whole grid's dense arrays; each rank clips the prisms of the
    /// sub-faces of its own cells only (`subface_swept_volumes_of`), and the entries of every
    /// rank are gathered on every rank in sub-face order ([`gather_swept`]), so every rank
    /// holds the entries of one rank (docs/mpi.md, step 4 (a)).
    fn sweep(
        &mut self,
        solver: &FluidSolver,
        accepted: &SolidFrame,
        step: u64,
    ) -> Result<Option<usize>, EmbeddedError> {
        let grid = &self.config.grid;
        let dim = grid.dim;
        let current = &self.state.current;
        // NOTE: when links break, shared vertices split and the elements are renumbered onto the
        // new vertices; each element keeps its identity, so `F^n` is re-expressed on the new
        // connectivity (a split vertex starts where the shared one was) for the prisms.
        let remapped;
        let before = if accepted.elements == current.elements {
            current.surface()
        } else {
            remapped = current
                .on_connectivity(accepted)
                .map_err(|e| e.at_step(step))?;
            Surface {
                dim,
                vertices: &remapped,
                elements: &accepted.elements,
                element_particle: &accepted.element_particle,
            }
        };
        outside_domain(grid, &self.config.boundary, &accepted.surface())
            .map_err(|e| e.at_step(step))?;
        let held = self.config.held_box();
        let scratch = &mut self.scratch;
        let block = self.config.block;
        match block {
            None => solver.install(|| compute(grid, &accepted.surface(), &mut scratch.trial.cut)),
            Some(block) => {
                let (trial, reuse) = (&mut scratch.trial, &mut scratch.block);
                assemble_by_block(trial, reuse, solver, &accepted.surface(), block, held);
            }
        }
        solver.install(|| {
            let (after, geom) = (&accepted.surface(), &scratch.trial.cut);
            match block {
                None => subface_swept_volumes(grid, &before, after, geom, &mut scratch.swept),
                Some(block) => {
                    let mine = |s: &SubFace| block.contains(grid.ijk(s.cell as usize));
                    subface_swept_volumes_of(grid, &before, after, geom, mine, &mut scratch.swept);
                }
            }
        });
        if block.is_some() {
            gather_swept(solver, &mut scratch.swept);
        }
        if scratch.swept.n_skipped_subfaces > 0 {
            // The swept amounts would miss volume: mass would not be conserved.
            return Err(EmbeddedError::NoSweptPrism {
                step,
                count: scratch.swept.n_skipped_subfaces,
            });
        }
        solver.install(|| {
            sweep_beyond(
                grid,
                &before,
                &accepted.surface(),
                &mut scratch.beyond_geom,
                &mut scratch.beyond_swept,
                &mut scratch.beyond,
            )
        });
        self.check_swept(step)
    }

    /// Content `(1 − Λ^{n+1}) U^n` plus the fluid fluxes of every near cell the solid touches
    /// (eq. 12–13); marks those cells [`CellKind::Updated`]. Returns what those weights change
    /// in what left through the open sides (see [`FluidSolver::add_outflow`]).
    ///
    /// Collective on a decomposed grid: each rank updates its own near cells, and every rank
    /// receives every rank's updates but their contents ([`gather_updates`]), so every rank
    /// holds the kinds, count and outflow of one rank; a rank then holds the contents of its
    /// own cells, which the mixing completes with those of the sources
    /// (`Embedded::mix`).
    ///
    /// NOTE: the sweeps count the whole flux through a domain face as leaving; a body at rest
    /// against an outflow side (its face flush with it, gas streaming out past it) lost 1.3e-4
    /// of the mass in the ledger at its first step, the correct applying that flux times the
    /// face's fluid part (0 where the body covers it).
    fn fluid_fluxes(
        &mut self,
        solver: &FluidSolver,
        dt: f64,
        step: u64,
        explicit: bool,
        opening: &[bool],
        report: &mut CorrectReport,
    ) -> Result<[f64; NQ], EmbeddedError> {
        let mut leaving = [0.0; NQ];
        let n_near = self.near.cells.len();
        self.scratch.content.clear();
        self.scratch.content.resize(n_near, [0.0; NQ]);
        self.scratch.kind.clear();
        self.scratch.kind.resize(n_near, CellKind::Predicted);
        let flush = self.flush_faces();
        self.mark_surface_cells(step, explicit)?;
        let cracking = opening.contains(&true);
        // NOTE: each cell's update reads only its own kind and the fluxes kept by the predict,
        // so the cells are updated in parallel on the fluid's pool; what leaves through open
        // sides is then added up cell by cell in the cells' order, as one thread did: the
        // same bits on any number of threads. On a decomposed grid each rank updates its own
        // near cells, and the updates of every rank are gathered on every rank in the cells'
        // order (`gather_updates`): the same list, so the same bits, as one rank's, but the
        // contents of other ranks' cells, which the mixing reads only once it has gathered
        // them (the sources', or every updated cell's when groups merge or widen).
        let this = &*self;
        let (grid, block, cells) = (&self.config.grid, self.config.block, &self.near.cells);
        let mut updates: Updates = solver.install(|| {
            (this.near.own.range())
                .into_par_iter()
                .with_min_len(CELLS_PER_TASK)
                .with_max_len(4 * CELLS_PER_TASK)
                .filter(|&k| this.own_slot(k))
                .filter_map(|k| {
                    let update = this.cell_update(k, dt, step, &flush, opening, cracking);
                    update.transpose().map(|u| (k, u.map_err(Box::new)))
                })
                .collect()
        });
        if block.is_some() {
            updates = gather_updates(solver, updates, |k| EmbeddedError::FluxNotKept {
                step,
                cell: grid.ijk(cells[k] as usize),
            });
        }
        for (k, update) in updates {
            let u = update.map_err(|e| *e)?;
            self.scratch.kind[k] = CellKind::Updated;
            report.cut_cells += 1;
            for v in &u.leaving {
                for q in 0..NQ {
                    leaving[q] += v[q];
                }
            }
            self.scratch.content[k] = u.content;
        }
        Ok(leaving)
    }

    /// Eq. (12–13) for near cell `k`, if the solid touches it: its content and what its
    /// weighted fluxes through open domain sides change in the outflow (see
    /// [`Embedded::fluid_fluxes`]).
    fn cell_update(
        &self,
        k: usize,
        dt: f64,
        step: u64,
        flush: &[(usize, usize, f64)],
        opening: &[bool],
        cracking: bool,
    ) -> Result<Option<CellUpdate>, EmbeddedError> {
        let volume = self.config.grid.cell_volume();
        let grid = &self.config.grid;
        let c = self.near.cells[k] as usize;
        let Some(faces) = self.touched_faces(k, flush, opening, cracking) else {
            return Ok(None);
        };
        let mut update = CellUpdate {
            content: [0.0; NQ],
            leaving: Vec::new(),
        };
        let ijk = grid.ijk(c);
        let nvar = grid.dim + 2;
        let alpha = fluid_part(self.scratch.trial.lambda(c));
        let covered_at_n = self.state.geom.lambda(c) >= 1.0 - COVERED_TOLERANCE;
        let u0 = self.near.saved(k, nvar);
        let acc = &mut update.content;
        for q in 0..nvar {
            acc[q] = alpha * u0[q];
        }
        for a in 0..grid.dim {
            let Some((fl, fr)) = self.face_fluxes(a, c, dt, opening, cracking) else {
                return Err(EmbeddedError::FluxNotKept { step, cell: ijk });
            };
            let sigma = dt / grid.dx[a];
            let (wl, wr) = (fluid_part(faces[a][0]), fluid_part(faces[a][1]));
            // (The sweeps counted the flux of a cell that was not covered at t^n.)
            let counted = f64::from(u8::from(!covered_at_n));
            let open = self.config.boundary[a].map(BoundaryKind::is_open);
            if ijk[a] == 0 && open[0] {
                let mut v = [0.0; NQ];
                for q in 0..NQ {
                    v[q] = -((wl - counted) * fl[q] * sigma * volume);
                }
                update.leaving.push(v);
            }
            if ijk[a] + 1 == grid.cells[a] && open[1] {
                let mut v = [0.0; NQ];
                for q in 0..NQ {
                    v[q] = (wr - counted) * fr[q] * sigma * volume;
                }
                update.leaving.push(v);
            }
            let dim = grid.dim;
            acc[0] += sigma * (wl * fl[0] - wr * fr[0]);
            for b in 0..dim {
                acc[1 + b] += sigma * (wl * fl[1 + b] - wr * fr[1 + b]);
            }
            acc[dim + 1] += sigma * (wl * fl[4] - wr * fr[4]);
        }
        Ok(Some(update))
    }

    /// Solid faces flush against the domain boundary: `(cell, 2 axis + side, area)`, sorted.
    fn flush_faces(&self) -> Vec<(usize, usize, f64)> {
        let mut pieces: Vec<(usize, usize, f64)> = Vec::new();
        for s in &self.scratch.trial.subfaces {
            if let Some((a, side)) = domain_face(&self.config.grid, s) {
                pieces.push((s.cell as usize, 2 * a + side, s.area));
            }
        }
        // NOTE: the pieces of one domain face need not be consecutive (two triangles of a flush
        // box face, and the flush faces of a body in a corner, in one cell): merging only
        // consecutive ones before sorting left duplicates, of which the search took one, and a
        // box at rest in a 3-D corner set the gas moving at 0.24 c in its first step (corpus
        // seed 2003).
        pieces.sort_by_key(|f| (f.0, f.1));
        let mut flush: Vec<(usize, usize, f64)> = Vec::with_capacity(pieces.len());
        for (cell, face, area) in pieces {
            match flush.last_mut() {
                Some(f) if f.0 == cell && f.1 == face => f.2 += area,
                _ => flush.push((cell, face, area)),
            }
        }
        flush
    }

    /// Marks the cells holding sub-faces of `F^{n+1}` (and, explicit, of `F^n`) updated; each
    /// must be a near cell. So are the cells holding pieces of prisms beyond the domain.
    ///
    /// NOTE: such a piece stays in the cell it lies in (see [`Embedded::swept_amounts`]), which
    /// may hold no sub-face at either time: a body leaving through a wall uncovers a boundary
    /// cell from beyond it (Λ from 0.3 to 0). Left predicted, the cell kept the sweeps' state
    /// over its whole volume and the piece went nowhere: a square turning out through a wall
    /// gained 2.3e-5 of the box's mass (issue 35 item 3, the fragments of `burst-shell-2d`).
    fn mark_surface_cells(&mut self, step: u64, explicit: bool) -> Result<(), EmbeddedError> {
        let flux_subfaces = if explicit {
            &self.state.geom.subfaces[..]
        } else {
            &[][..]
        };
        for s in self.scratch.trial.subfaces.iter().chain(flux_subfaces) {
            match self.near.slot(s.cell as usize) {
                None => return Err(self.outside_near(Some(step), Reach::AcceptedSurface, s.cell)),
                Some(k) => self.scratch.kind[k] = CellKind::Updated,
            }
        }
        for &(cell, _) in &self.scratch.beyond {
            match self.near.slot(cell as usize) {
                None => return Err(self.outside_near(Some(step), Reach::SweptPrism, cell)),
                Some(k) => self.scratch.kind[k] = CellKind::Updated,
            }
        }
        Ok(())
    }

    /// The face fractions `[axis][low, high]` of near cell `k` (flush solid faces counted), if
    /// the solid touches the cell in this step: a sub-face in it, solid in it at either time,
    /// a face partly solid, or a face to a cell a crack opens.
    fn touched_faces(
        &self,
        k: usize,
        flush: &[(usize, usize, f64)],
        opening: &[bool],
        cracking: bool,
    ) -> Option<[[f64; 2]; 3]> {
        let grid = &self.config.grid;
        let volume = grid.cell_volume();
        let c = self.near.cells[k] as usize;
        let ijk = grid.ijk(c);
        let (new, old) = (&self.scratch.trial, &self.state.geom);
        // (A cell holding a piece of a prism beyond the domain is `Updated` already, see
        // `mark_surface_cells`: a wall or an open side, the same leak.)
        let mut touched = self.scratch.kind[k] == CellKind::Updated
            || new.lambda(c) > 0.0
            || old.lambda(c) >= 1.0 - COVERED_TOLERANCE;
        let mut faces = [[0.0f64; 2]; 3];
        for a in 0..grid.dim {
            let face_area = volume / grid.dx[a];
            let lo = face_index(grid, a, ijk);
            let mut up = ijk;
            up[a] += 1;
            let hi = face_index(grid, a, up);
            faces[a] = [new.face(a, lo), new.face(a, hi)];
            // A domain face under a solid face flush against it is solid where that face
            // is (the tie rule gives it λ = 0 on the low side); its sub-face is left out.
            for side in 0..2 {
                if let Ok(i) = flush.binary_search_by_key(&(c, 2 * a + side), |f| (f.0, f.1)) {
                    faces[a][side] = faces[a][side].max(flush[i].2 / face_area);
                }
            }
            touched |= faces[a][0] > 0.0 || faces[a][1] > 0.0;
            // A fluid cell beside a crack that opens: its face to the crack takes the
            // Lax–Friedrichs flux (`crack_flux`), which the cell must give up too.
            if cracking {
                let beside = |side: usize| {
                    across(grid, &self.config.boundary, c, a, side)
                        .and_then(|q| self.near.slot(q))
                        .is_some_and(|kq| opening[kq])
                };
                touched |= beside(0) || beside(1);
            }
        }
        touched.then_some(faces)
    }

    /// The fluxes through the low and high faces of near cell `c` along axis `a`: the sweeps',
    /// the Lax–Friedrichs flux against a crack that opens, or none between two cells covered at
    /// t^n where cracks may open. `None` if the sweeps did not keep them (a bug).
    fn face_fluxes(
        &self,
        a: usize,
        c: usize,
        dt: f64,
        opening: &[bool],
        cracking: bool,
    ) -> Option<([f64; NQ], [f64; NQ])> {
        let grid = &self.config.grid;
        let ijk = grid.ijk(c);
        let sigma = dt / grid.dx[a];
        let mut up = ijk;
        up[a] += 1;
        let (Some(&fl), Some(&fr)) = (
            self.near.face_flux(grid, a, ijk),
            self.near.face_flux(grid, a, up),
        ) else {
            return None;
        };
        let below = across(grid, &self.config.boundary, c, a, 0);
        let above = across(grid, &self.config.boundary, c, a, 1);
        let (fl, fr) = if cracking {
            // A domain side of a cell that holds vacuum at t^n carries nothing: a wall mirrors
            // the vacuum, an open side extrapolates it.
            let vacuum = self.near.slot(c).is_some_and(|k| opening[k]);
            let side = |q: Option<usize>, f: [f64; NQ], left: bool| match q {
                Some(q) => {
                    let (l, r) = if left { (q, c) } else { (c, q) };
                    self.crack_flux(a, l, r, opening, sigma).unwrap_or(f)
                }
                None if vacuum => [0.0; NQ],
                None => f,
            };
            (side(below, fl, true), side(above, fr, false))
        } else {
            (fl, fr)
        };
        // NOTE: a face between two cells covered at t^n carries the sweeps' flux between
        // ghost states of the sweep along `a`, mirrors of whatever fluid that pencil meets.
        // Beside a crack that can be the gas outside the particle's far side (seen in
        // `opening-fracture-3d`: a cell opening into the crack took the z flux of the gas
        // mirrored through the particle's bottom face, and went negative). No fluid was
        // there at t^n, so where cracks may open (fracture, or separate bodies) such
        // faces carry nothing. Otherwise they keep the sweeps' flux, which keeps a
        // uniform flow past a moving body uniform to round-off (zero there moved the
        // swept mass of a carried box by 2e-8).
        let old = &self.state.geom;
        let covered_at_n = |q: usize| old.lambda(q) >= 1.0 - COVERED_TOLERANCE;
        let shut = self.config.fracture && covered_at_n(c);
        let fl = match below {
            Some(q) if shut && covered_at_n(q) => [0.0; NQ],
            _ => fl,
        };
        let fr = match above {
            Some(q) if shut && covered_at_n(q) => [0.0; NQ],
            _ => fr,
        };
        Some((fl, fr))
    }

    /// Solid flux (eq. 26) into `gained`, and the loads it implies into `last_loads`.
    ///
    /// Collective on a decomposed grid: each rank takes the sub-faces of its own cells only,
    /// so `gained` takes the terms of its own near cells (each slot's terms are all there, so
    /// its sum is one rank's: [`OddSum`]); one all-gather of every rank's load terms and of
    /// each sub-face's work and impulse ([`gather_solid_flux`]) gives every rank the work and
    /// impulse summed in the sub-faces' order, as one rank sums them, and the loads of one rank
    /// ([`OddSum`] again), each rank adding up a share of the slots ([`add_loads`]).
    /// Semi-implicit: on the wet sub-faces of F^{n+1}, torques about X^{n+1} (paper 003 step
    /// 7), or with the levers at `t^n` of [`Levers`] (the same as the loads'). Explicit: on
    /// those of F^n about X^n (paper 000 eq. 11), the surface the solid's loads came from, so
    /// that the exchange balances exactly.
    fn solid_flux(
        &mut self,
        solver: &FluidSolver,
        dt: f64,
        accepted: &SolidFrame,
        explicit: bool,
        gained: &mut OddSum,
    ) -> Exchanged {
        let grid = &self.config.grid;
        let dim = grid.dim;
        let volume = grid.cell_volume();
        let mut exchanged = Exchanged {
            work: 0.0,
            impulse: [0.0; 3],
        };
        let nr = if dim == 2 { 1 } else { 3 };
        let np = accepted.n_particles();
        let last_loads = &mut self.state.last_loads;
        last_loads.force.clear();
        last_loads.force.resize(np * dim, 0.0);
        last_loads.torque.clear();
        last_loads.torque.resize(np * nr, 0.0);
        let (flux_geom, flux_frame) = if explicit {
            (&self.state.geom, &self.state.current)
        } else {
            (&self.scratch.trial, accepted)
        };
        // Explicit: on `F^n`, the surface of the solid's loads, at its end.
        let start = self.config.start_levers && !explicit;
        let levers = Levers::new(start, &self.state.current, flux_frame);
        let mut sum = std::mem::take(&mut self.scratch.odd);
        sum.clear();
        // A rank takes the sub-faces of its own cells, whose near slots are its own, and keeps
        // each one's work and impulse by its index, summed in the sub-faces' order (once every
        // rank's are gathered, on a decomposed grid).
        let mut by_subface: Vec<(u32, [f64; 4])> = Vec::new();
        for (i, s) in self.own_subfaces(&flux_geom.subfaces) {
            if !flux_frame.wet[s.element as usize]
                || domain_face(grid, s).is_some()
                || self.opening(s, flux_frame)
                || !touches_gas(grid, flux_geom, s)
            {
                continue;
            }
            let k = self.near.slot_of[s.cell as usize] as usize - 1;
            debug_assert!(
                self.own_slot(k),
                "a rank's sub-faces are in its own near cells"
            );
            // The neighbour a face takes `p̄` from is near: one of the two holds F^n's wall.
            let kp = self.near.slot_of[pressure_cell(grid, &self.state.geom, s)] as usize - 1;
            let mut pi = [0.0; 3];
            let p_bar = self.near.wall_pressure[kp];
            for a in 0..dim {
                pi[a] = p_bar * s.normal[a] * s.area;
            }
            let p = s.particle as usize;
            let r = levers.lever(s);
            let w = accepted.rigid_velocity(p, r);
            let power: f64 = (0..dim).map(|a| w[a] * pi[a]).sum();
            for a in 0..dim {
                gained.push(k * NQ + 1 + a, dt * pi[a] / volume);
            }
            gained.push(k * NQ + dim + 1, dt * power / volume);
            by_subface.push((i as u32, [dt * power, dt * pi[0], dt * pi[1], dt * pi[2]]));
            let f = [-pi[0], -pi[1], -pi[2]];
            for a in 0..dim {
                sum.push(p * dim + a, f[a]);
            }
            push_moment(&mut sum, np * dim, dim, p, r, f);
        }
        if self.config.block.is_some() {
            gather_solid_flux(solver, dim, &mut by_subface, &mut sum);
        }
        for (_, exchange) in &by_subface {
            exchanged.add(dim, exchange);
        }
        let last_loads = &mut self.state.last_loads;
        add_loads(solver, &mut sum, last_loads, np * dim);
        self.scratch.odd = sum;
        exchanged
    }

    /// Swept amounts (paper 000 eq. 12) into `gained`: the prism of every sub-face of F^{n+1},
    /// wet or not (Λ counts every element), gives its cell the content it sweeps at t^n. On a
    /// decomposed grid only the terms of this rank's near cells are pushed (each rank holds
    /// every entry, so every term of its cells, and the checks for every cell).
    ///
    /// NOTE: a sub-face in a cell that held no fluid at t^n (inside two overlapping bodies at
    /// both times, or, where cracks may open, covered at t^n) has nothing to pay for its prism
    /// with: the part of the prism in a neighbour the face uncovers left it -2e-7 of mass per
    /// unit volume (the flush cube at 100^3, in a crack of such cells with no fluid to mix it
    /// into). Each piece of such a prism goes to the cell it lies in instead: the same sums, so
    /// just as conservative, and that cell keeps `(1 − Λ^n) U^n` of its own.
    fn swept_amounts(&self, step: u64, gained: &mut OddSum) -> Result<(), EmbeddedError> {
        let grid = &self.config.grid;
        let nvar = grid.dim + 2;
        let volume = grid.cell_volume();
        let (near, kind) = (&self.near, &self.scratch.kind);
        let (new, old) = (&self.scratch.trial, &self.state.geom);
        // Each near cell's [`overlap_scale`], where a term of this rank's cells needs it.
        let source_scale = |k: usize| {
            let c = near.cells[k] as usize;
            overlap_scale(old.lambda(c), new.lambda(c))
        };
        let mut entry = 0;
        let entries = &self.scratch.swept.entries;
        for (s_idx, s) in self.scratch.trial.subfaces.iter().enumerate() {
            let k = near.slot_of[s.cell as usize] as usize - 1;
            let inside = std::cell::OnceCell::new();
            let inside = || {
                *inside.get_or_init(|| {
                    source_scale(k) == 0.0
                        || (self.config.fracture
                            && old.lambda(s.cell as usize) >= 1.0 - COVERED_TOLERANCE)
                })
            };
            while entry < entries.len() && (entries[entry].subface as usize) < s_idx {
                entry += 1;
            }
            while entry < entries.len() && entries[entry].subface as usize == s_idx {
                let e = entries[entry];
                let Some(kp) = near.slot(e.cell as usize) else {
                    return Err(self.outside_near(Some(step), Reach::SweptPrism, e.cell));
                };
                entry += 1;
                // NOTE: a term goes to the piece's cell or the sub-face's; where this rank owns
                // neither, it takes no term, and reads none of the two cells' Λ for it.
                if !self.own_slot(kp) && !self.own_slot(k) {
                    continue;
                }
                // (Only into a cell the correct writes: a piece in a cell it leaves predicted,
                // fluid at both times, stays with the sub-face's cell.)
                let to = if kind[kp] == CellKind::Updated && inside() {
                    kp
                } else {
                    k
                };
                if self.own_slot(to) {
                    let f = e.volume / volume * source_scale(kp);
                    for q in 0..nvar {
                        gained.push(to * NQ + q, f * near.saved[kp * nvar + q]);
                    }
                }
            }
        }
        // The pieces of prisms of sub-faces beyond the domain stay in the cell they lie in, as
        // the pieces above of a sub-face in a cell without fluid do.
        for &(cell, v) in &self.scratch.beyond {
            let kp = near.slot_of[cell as usize] as usize - 1;
            if self.own_slot(kp) {
                let f = v / volume * source_scale(kp);
                for q in 0..nvar {
                    gained.push(kp * NQ + q, f * near.saved[kp * nvar + q]);
                }
            }
        }
        Ok(())
    }

    /// Stops on a cell the correct left uncovered with a state that is not physical: the first
    /// in the near cells' order, as the ranks agreed on it while mixing, or as found among every
    /// written cell (see [`WrittenCheck`]).
    fn check_written(&self, step: u64, mixed: &Mixed) -> Result<(), EmbeddedError> {
        let written = match mixed.check {
            WrittenCheck::Agreed(None) => return Ok(()),
            WrittenCheck::Agreed(Some((c, state))) => {
                return Err(self.non_physical(step, c as usize, &state));
            }
            WrittenCheck::Whole => &mixed.written,
        };
        let new = &self.scratch.trial;
        for (k, &c) in self.near.cells.iter().enumerate() {
            if self.scratch.kind[k] == CellKind::Predicted
                || new.lambda(c as usize) >= 1.0 - COVERED_TOLERANCE
            {
                continue;
            }
            let w = written
                .binary_search_by_key(&c, |w| w.0)
                .expect("the correct wrote every updated cell it left uncovered");
            if !self.config.written_ok(&written[w].1) {
                return Err(self.non_physical(step, c as usize, &written[w].1));
            }
        }
        Ok(())
    }

    /// The refusal of cell `c`, written `state`, which is not physical.
    fn non_physical(&self, step: u64, c: usize, state: &[f64; NQ]) -> EmbeddedError {
        let grid = &self.config.grid;
        let dim = grid.dim;
        let full = full_state(&state[..dim + 2], dim, 1.0);
        let w = crate::fv::euler::primitive(&full, self.config.gamma);
        let ijk = grid.ijk(c);
        EmbeddedError::NonPhysical {
            step,
            cell: ijk,
            center: grid.cell_center(ijk),
            fluid_fraction: 1.0 - self.scratch.trial.lambda(c),
            rho: w.rho,
            p: w.p,
            velocity: w.vel,
        }
    }
}
