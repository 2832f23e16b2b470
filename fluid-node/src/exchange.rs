//! The finite-volume solver as a [`FluidModel`]: conversions between the solver, the embedded
//! solid ([`crate::embedded`]) and the wire, outputs and probes.
//!
//! A fluid-only scene advances the solver in `correct`. A coupled scene runs the three parts of
//! paper 003 §3.4: `predict` (split sweeps, kept fluxes and pressures), `loads` on each trial
//! surface, `correct` with the accepted one; this file only converts the wire's `SolidState`
//! into a [`SolidFrame`] and back.

use std::io::Write;
use std::path::Path;

use rayon::prelude::*;

use protocol::scene::{OutputFormat, Scene, SchemeName, SolidSubsteps};
use protocol::session::{NodeModel, StepLimit};
use protocol::vtk::Series;
use protocol::wire::{
    ConservedTotals, InterfaceLoads, NodeKind, SolidState, Stamp, StepPlan, n_rot,
};

use crate::Error;
use crate::embedded::{COVERED_TOLERANCE, Embedded, EmbeddedError, InterfaceBudget, SolidFrame};
use crate::fv::FluidSolver;
use crate::fv::comm::{Comm, Serial};
use crate::fv::solver::items_per_task;
use crate::model::FluidModel;

/// The real fluid.
pub struct RealFluid {
    solver: FluidSolver,
    gamma: f64,
    formats: Vec<OutputFormat>,
    name: String,
    probes: Vec<Probe>,
    /// The probe files exist: later rows are appended (`NodeModel::write_probes`).
    probes_started: bool,
    /// Whether the scene has a solid (the embedded part is built from the first surface).
    coupled: bool,
    /// Whether cracks may open in that solid (`[solid] fracture`, or several bodies).
    fracture: bool,
    /// Whether the semi-implicit loads take their lever arms on `F^n` (`run.solid_substeps`
    /// other than 1 with the semi-implicit scheme; `embedded/levers.rs`).
    start_levers: bool,
    embedded: Option<Embedded>,
    /// Budget restored from a checkpoint before the surface arrived.
    pending_budget: Option<InterfaceBudget>,
    /// The solid's numbers of the frame's particles (`SolidState::particles` of the last
    /// accepted state: the coupler sends only the particles the elements belong to); empty:
    /// the frame's own numbers. For what the outputs and the errors name.
    particle_ids: Vec<u32>,
    /// The `.vti` files written so far (`fluid.pvd`).
    vtk_series: Series,
}

struct Probe {
    name: String,
    /// Cell of the whole grid.
    cell: usize,
    /// `t, ρ, u, v, w, p` per recorded step (formatted when written: formatting every step
    /// cost 1 % of a coupled beam's fluid time).
    rows: Vec<[f64; 6]>,
}

impl RealFluid {
    /// Builds the solver of a scene on one rank.
    pub fn from_scene(scene: &Scene) -> Result<RealFluid, Error> {
        RealFluid::from_scene_on(scene, Box::new(Serial))
    }

    /// Builds this rank's part of the fluid of a scene on the ranks of `comm` (issue 16). With
    /// several ranks every [`NodeModel`] and [`FluidModel`] method is collective (all ranks call
    /// it in the same order, `crate::ranks::node`) and only rank 0 writes files.
    pub fn from_scene_on(scene: &Scene, comm: Box<dyn Comm>) -> Result<RealFluid, Error> {
        let cfg = scene.fluid.as_ref().ok_or(Error::NoFluid)?;
        if scene.solid.is_some() && scene.dim() == 1 {
            return Err(Error::CoupledOneD);
        }
        let solver = FluidSolver::from_scene_on(cfg, scene.run.threads as usize, comm)?;
        let mut probes = Vec::new();
        for probe in &scene.output.probes {
            if let Some(point) = &probe.point {
                let global = solver.global_grid();
                let ijk = global.locate(point).ok_or_else(|| Error::ProbeOutside {
                    name: probe.name.clone(),
                    point: point.clone(),
                })?;
                probes.push(Probe {
                    name: probe.name.clone(),
                    cell: global.index(ijk[0], ijk[1], ijk[2]),
                    rows: Vec::new(),
                });
            }
        }
        Ok(RealFluid {
            solver,
            gamma: cfg.gamma,
            formats: scene.output.formats.clone(),
            name: scene.name.clone(),
            probes,
            probes_started: false,
            coupled: scene.solid.is_some(),
            // Cracks open where links break, and between separate bodies that touch and part.
            fracture: scene
                .solid
                .as_ref()
                .is_some_and(|s| s.fracture.is_some() || s.bodies.len() > 1),
            // Issue 37: the levers of the loads held over sub-cycled steps lag by dt/2 (on F^n);
            // K = 1 keeps paper 003's levers and its payloads.
            start_levers: scene.run.scheme == SchemeName::SemiImplicit
                && scene
                    .run
                    .solid_substeps
                    .is_some_and(|k| k != SolidSubsteps::Fixed(1)),
            embedded: None,
            pending_budget: None,
            particle_ids: Vec::new(),
            vtk_series: Series::default(),
        })
    }

    /// Whether this rank writes the files (rank 0).
    fn writes(&self) -> bool {
        self.solver.comm().rank() == 0
    }

    /// Cells holding fluid whose density or pressure is below the `fluid.vacuum` thresholds
    /// (the test that picks the Lax–Friedrichs flux); a cell the solid covers holds a ghost
    /// state and is left out. Summed over the ranks (collective).
    fn vacuum_cells(&self) -> u64 {
        let mine = self.vacuum_cells_here();
        let comm = self.solver.comm();
        if comm.size() == 1 {
            return mine;
        }
        comm.all_gather(&mine.to_le_bytes())
            .iter()
            .map(|b| u64::from_le_bytes(b[..8].try_into().expect("8 bytes")))
            .sum()
    }

    /// [`RealFluid::vacuum_cells`] of this rank's cells.
    fn vacuum_cells_here(&self) -> u64 {
        let params = self.solver.params();
        // Λ of this rank's cells, in their order (`Embedded::solid_fraction`).
        let lambda = self.embedded.as_ref().map(Embedded::solid_fraction);
        let lambda = lambda.as_deref();
        let slab = self.solver.slab();
        let first = slab.slabs().then(|| slab.global_range().start);
        let n_cells = self.solver.grid().n_cells();
        let (state, gamma) = (self.solver.state(), params.gamma);
        let empty = |cell: &[f64]| {
            let (rho, _, p) = crate::fv::state::primitive_of(cell, gamma);
            !(rho >= params.vacuum_rho && p >= params.vacuum_p)
        };
        let covered = |l: f64| l >= 1.0 - COVERED_TOLERANCE;
        // A count, so the same on any number of threads; on the fluid's pool (every step: a
        // 64³ blast spent 4 % of its run here on one thread).
        let count = match first {
            // NOTE: a rank's cells are a range of the global numbering: runs of cells taken
            // straight from the state's and Λ's slices. Indexing them a cell at a time, with
            // the global index of each, took about 1.5 times as long (3.9 % of the fluid
            // node's samples in `clamped-beam-3d`, against 2.7 % now).
            Some(_) => {
                let nvar = state.nvar;
                let lambda = lambda.map(|l| &l[..n_cells]);
                let run = |(k, u): (usize, &[f64])| {
                    let cells = u.chunks_exact(nvar);
                    match lambda {
                        Some(l) => (cells.zip(&l[k * VACUUM_RUN..]))
                            .filter(|&(cell, &l)| !covered(l) && empty(cell))
                            .count(),
                        None => cells.filter(|&cell| empty(cell)).count(),
                    }
                };
                let u = &state.u[..n_cells * nvar];
                (self.solver).install(|| {
                    (u.par_chunks(VACUUM_RUN * nvar).enumerate())
                        .with_max_len(items_per_task(VACUUM_RUN))
                        .map(run)
                        .sum()
                })
            }
            None => (self.solver).install(|| {
                (0..n_cells)
                    .into_par_iter()
                    .filter(|&c| !lambda.is_some_and(|l| covered(l[c])))
                    .filter(|&c| empty(state.cell(c)))
                    .count()
            }),
        };
        count as u64
    }
}

/// Cells a task of [`RealFluid::vacuum_cells`] counts.
const VACUUM_RUN: usize = 4096;

impl NodeModel for RealFluid {
    fn implementation(&self) -> &'static str {
        "real"
    }

    /// NOTE: beside a moving body the sweeps read ghost states, the gas mirrored about the
    /// wall: normal velocity `2 w − u`, so speeds up to `|u| + 2|w|` with the gas's sound
    /// speed. The CFL step of the cells alone does not see them, and the one-cell step lets
    /// `|w| Δt` reach a whole cell, which puts the faces beside a fast body at Courant numbers
    /// of 2 to 2.5: behind a wall receding faster than the escape speed the flux there left
    /// negative pressures (issue 35: a block at Mach 2, 6 or 30 stopped at step 0; 26 of 1,000
    /// generated scenes). So a moving body bounds the step by `cfl / (R + 2 W)`, with
    /// `R = cfl / Δt_cfl` the cells' rate `max (|u_a| + c)/Δx_a` and `W = 1/Δt_one-cell` the
    /// surface's `max |w_a|/Δx_a`: every ghost state then runs at the scene's Courant number
    /// at most, and the one-cell bound follows (it is at least `2 / cfl` times longer). A body
    /// at rest leaves the step as it was.
    fn dt_max(&self) -> StepLimit {
        let cfl = self.solver.max_dt();
        let one_cell = self
            .embedded
            .as_ref()
            .map_or(f64::INFINITY, |e| e.one_cell_dt());
        if one_cell.is_finite() {
            let courant = self.solver.params().cfl;
            let ghost = courant / (courant / cfl + 2.0 / one_cell);
            if ghost < cfl {
                return StepLimit {
                    dt_max: ghost,
                    limiter: "ghost states beside the moving body (cfl with twice its speed)"
                        .into(),
                };
            }
        }
        // The cell that limits the step, so that a collapsing step names it.
        let grid = self.solver.global_grid();
        let ijk = grid.ijk(self.solver.limiting_cell());
        let centre = grid.cell_center(ijk);
        let dim = grid.dim;
        StepLimit {
            dt_max: cfl,
            limiter: format!(
                "cfl at cell {:?} (centre {:?})",
                &ijk[..dim],
                &centre[..dim]
            ),
        }
    }

    fn totals(&self, stamp: Stamp, t: f64) -> ConservedTotals {
        let dim = self.dim();
        let (totals, budget) = match &self.embedded {
            Some(e) => (e.totals(&self.solver), e.budget()),
            None => (self.solver.totals(), InterfaceBudget::default()),
        };
        ConservedTotals {
            stamp,
            node: NodeKind::Fluid,
            t,
            mass: totals.mass,
            momentum: totals.momentum[..dim].to_vec(),
            energy: totals.energy,
            dissipated: 0.0,
            interface_work: budget.work_given,
            interface_impulse: budget.impulse_given[..dim].to_vec(),
            boundary_mass_out: totals.outflow_mass,
            boundary_energy_out: totals.outflow_energy,
            links_broken: 0,
            broken_pairs: Vec::new(),
            broken_substeps: Vec::new(),
            swept_mass: budget.swept_mass,
            vacuum_cells: self.vacuum_cells(),
            kinetic: 0.0,
            energy_scale: totals.energy.abs(),
        }
    }

    fn checkpoint(&self) -> Vec<u8> {
        let budget = self.embedded.as_ref().map(Embedded::budget);
        protocol::codec::encode_blob(&(self.solver.to_checkpoint(), budget))
    }

    fn restore(&mut self, bytes: &[u8]) -> Result<(), String> {
        let (solver, budget): (Vec<u8>, Option<InterfaceBudget>) =
            protocol::codec::decode_blob(bytes)?;
        // The wire boundary: `NodeModel` is the protocol's trait and takes the text.
        self.solver
            .restore_checkpoint(&solver)
            .map_err(|e| e.to_string())?;
        // The surface comes next (`set_initial_surface`), which rebuilds the geometry.
        self.pending_budget = budget;
        if let (Some(e), Some(b)) = (&mut self.embedded, budget) {
            e.set_budget(b);
        }
        Ok(())
    }

    fn write_output(&mut self, k: u32, t: f64, out: &Path) -> std::io::Result<()> {
        // Collective: the whole grid on rank 0, which writes what one rank would.
        let Some(gathered) = self.solver.gather_state() else {
            return Ok(());
        };
        let grid = self.solver.global_grid();
        let state = &gathered;
        let alpha = self.embedded.as_ref().map(Embedded::fluid_fraction);
        if self.formats.contains(&OutputFormat::Csv) {
            let mut w =
                std::io::BufWriter::new(std::fs::File::create(out.join(format!("fluid_{k}.csv")))?);
            // On the fluid's pool: the rows are formatted in parallel (the same bytes).
            let (gamma, alpha) = (self.gamma, alpha.as_deref());
            (self.solver)
                .install(|| crate::output::write_fluid_csv(&mut w, grid, state, gamma, alpha))?;
            w.flush()?;
            if let Some(e) = &self.embedded {
                let mut w = std::io::BufWriter::new(std::fs::File::create(
                    out.join(format!("surface_{k}.csv")),
                )?);
                crate::output::write_surface_csv(&mut w, e.surface(), &self.particle_ids)?;
                w.flush()?;
                let mut w = std::io::BufWriter::new(std::fs::File::create(
                    out.join(format!("loads_{k}.csv")),
                )?);
                crate::output::write_loads_csv(
                    &mut w,
                    grid.dim,
                    e.last_loads(),
                    &self.particle_ids,
                )?;
                w.flush()?;
            }
        }
        let title = format!("{} fluid output {k} t = {t:e}", self.name);
        if self.formats.contains(&OutputFormat::Vtk) {
            let file = format!("fluid_{k}.vti");
            let (gamma, alpha) = (self.gamma, alpha.as_deref());
            let bytes = (self.solver)
                .install(|| crate::output::fluid_vti(grid, state, gamma, alpha, &title));
            std::fs::write(out.join(&file), bytes)?;
            let pvd = self.vtk_series.record(k, t, &file);
            crate::output::replace_file(&out.join("fluid.pvd"), pvd.as_bytes())?;
        }
        if self.formats.contains(&OutputFormat::VtkLegacy) {
            let mut w =
                std::io::BufWriter::new(std::fs::File::create(out.join(format!("fluid_{k}.vtk")))?);
            crate::output::write_fluid_vtk(
                &mut w,
                grid,
                state,
                self.gamma,
                alpha.as_deref(),
                &title,
            )?;
            w.flush()?;
        }
        Ok(())
    }

    fn record_probes(&mut self, t: f64) {
        // Each probe's cell is read on the rank that owns it and gathered on rank 0 (collective).
        let slab = self.solver.slab();
        let owned: Vec<(u64, f64, [f64; 3], f64)> = self
            .probes
            .iter()
            .enumerate()
            .filter_map(|(k, probe)| {
                let (rho, u, p) = self.solver.primitive(slab.to_local(probe.cell)?);
                Some((k as u64, rho, u, p))
            })
            .collect();
        let comm = self.solver.comm();
        let values = if comm.size() == 1 {
            owned
        } else {
            let Some(parts) = comm.gather(0, &protocol::codec::encode_blob(&owned)) else {
                return;
            };
            let mut all: Vec<(u64, f64, [f64; 3], f64)> = parts
                .iter()
                .flat_map(|b| {
                    protocol::codec::decode_blob::<Vec<(u64, f64, [f64; 3], f64)>>(b)
                        .expect("ranks send valid probe values")
                })
                .collect();
            all.sort_by_key(|v| v.0);
            all
        };
        for (k, rho, u, p) in values {
            self.probes[k as usize]
                .rows
                .push([t, rho, u[0], u[1], u[2], p]);
        }
    }

    fn write_probes(&mut self, out: &Path, end: bool) -> std::io::Result<()> {
        let held = self.probes.iter().map(|p| p.rows.len()).max().unwrap_or(0);
        if !self.writes() || (!end && held < protocol::session::PROBE_ROWS_HELD) {
            return Ok(());
        }
        let dim = self.dim();
        let started = std::mem::replace(&mut self.probes_started, true);
        for probe in &mut self.probes {
            let mut table = csv::Writer::from_writer(Vec::new());
            if !started {
                let vel = &["u", "v", "w"][..dim];
                table.write_record(["t", "rho"].iter().chain(vel).chain(&["p"]))?;
            }
            for [t, rho, u @ .., p] in &probe.rows {
                let row = [t, rho].into_iter().chain(&u[..dim]).chain([p]);
                table.write_record(row.map(|x| format!("{x:e}")))?;
            }
            table.flush()?;
            probe.rows.clear();
            let path = out.join(format!("probe_{}.csv", probe.name));
            crate::output::append_or_create(&path, started, table.get_ref())?;
        }
        Ok(())
    }
}

impl FluidModel for RealFluid {
    fn dim(&self) -> usize {
        self.solver.grid().dim
    }

    fn set_initial_surface(&mut self, state: &SolidState) -> Result<(), Error> {
        if !self.coupled {
            return Ok(());
        }
        let frame = solid_frame(state)?;
        self.particle_ids.clone_from(&state.particles);
        let named = |e| named_particles(e, state);
        match &mut self.embedded {
            Some(e) => e.set_surface(&self.solver, frame).map_err(named)?,
            None => {
                let mut e = Embedded::new(&self.solver, frame).map_err(named)?;
                e.set_fracture(self.fracture);
                e.set_start_levers(self.start_levers);
                self.embedded = Some(e);
            }
        }
        if let (Some(e), Some(b)) = (&mut self.embedded, self.pending_budget.take()) {
            e.set_budget(b);
        }
        Ok(())
    }

    fn predict(&mut self, plan: &StepPlan) -> Result<(), Error> {
        if !self.coupled {
            return Ok(());
        }
        let step = plan.stamp.step;
        let solver = &mut self.solver;
        let embedded = self.embedded.as_mut().ok_or(Error::NoSurface { step })?;
        // The solver checks the time step (the one CFL check, `FluidSolver::predict`).
        embedded.predict(solver, plan.dt).check(step)?;
        Ok(())
    }

    fn loads(&mut self, plan: &StepPlan, state: &SolidState) -> Result<InterfaceLoads, Error> {
        let step = plan.stamp.step;
        let frame = solid_frame(state)?;
        let embedded = self.embedded.as_mut().ok_or(Error::NoSurface { step })?;
        let loads = embedded
            .loads(&self.solver, &frame)
            .map_err(|e| named_particles(e.at_step(step), state))?;
        Ok(InterfaceLoads {
            stamp: plan.stamp,
            dim: state.dim,
            force: loads.force,
            torque: loads.torque,
            particles: state.particles.clone(),
        })
    }

    fn correct(&mut self, plan: &StepPlan, state: Option<&SolidState>) -> Result<(), Error> {
        let step = plan.stamp.step;
        if let Some(state) = state {
            let frame = solid_frame(state)?;
            let solver = &mut self.solver;
            let embedded = self.embedded.as_mut().ok_or(Error::NoSurface { step })?;
            let explicit = plan.scheme == protocol::wire::Scheme::Explicit;
            (embedded.correct(solver, plan.dt, frame, step, explicit))
                .map_err(|e| named_particles(e, state))?;
            self.particle_ids.clone_from(&state.particles);
            return Ok(());
        }
        // The solver checks the time step (the one CFL check, `FluidSolver::advance`).
        self.solver.advance(plan.dt).check(step)?;
        Ok(())
    }
}

/// `e` naming the solid's number of its particle rather than the frame's (see
/// [`SolidState::particles`]).
fn named_particles(mut e: EmbeddedError, state: &SolidState) -> EmbeddedError {
    if let EmbeddedError::OutsideDomain { particle, .. } = &mut e {
        *particle = state.particle_id(*particle as usize);
    }
    e
}

/// Copies the parts of a wire [`SolidState`] the fluid uses, checking their lengths.
fn solid_frame(s: &SolidState) -> Result<SolidFrame, Error> {
    let dim = s.dim as usize;
    let n = s.n_particles();
    let surface = &s.surface;
    let ne = surface.n_elements();
    let step = s.stamp.step;
    if s.changed_only {
        return Err(Error::ChangesOnly {
            step,
            iteration: s.stamp.iteration,
        });
    }
    if !(dim == 2 || dim == 3)
        || surface.dim != s.dim
        || s.velocity.len() != n * dim
        || s.angular_velocity.len() != n * n_rot(s.dim)
        || !surface.vertices.len().is_multiple_of(dim)
        || surface.elements.len() != ne * dim
        || surface.wet.len() != ne
        || !(s.particles.is_empty() || s.particles.len() == n)
    {
        return Err(Error::MalformedSolid {
            step,
            dim: s.dim,
            surface_dim: surface.dim,
            positions: s.position.len(),
            velocities: s.velocity.len(),
            angular_velocities: s.angular_velocity.len(),
            vertex_values: surface.vertices.len(),
            element_indices: surface.elements.len(),
            elements: ne,
            wet_flags: surface.wet.len(),
            particle_ids: s.particles.len(),
        });
    }
    if let Some(&p) = surface.element_particle.iter().find(|&&p| p as usize >= n) {
        return Err(Error::ElementParticle {
            step,
            particle: p,
            particles: n,
        });
    }
    let nv = (surface.vertices.len() / dim) as u32;
    if let Some(&v) = surface.elements.iter().find(|&&v| v >= nv) {
        return Err(Error::ElementVertex {
            step,
            vertex: v,
            vertices: nv,
        });
    }
    Ok(SolidFrame {
        dim,
        position: s.position.clone(),
        velocity: s.velocity.clone(),
        angular_velocity: s.angular_velocity.clone(),
        vertices: surface.vertices.clone(),
        elements: surface.elements.clone(),
        element_particle: surface.element_particle.clone(),
        wet: surface.wet.clone(),
    })
}
