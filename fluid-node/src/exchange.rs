//! The finite-volume solver as a [`FluidModel`]: conversions between the solver and the wire,
//! outputs and probes.
//!
//! Fluid-only scenes run here. A coupled run with the real fluid needs the cut-cell update of
//! the embedded solid in the node loop, which is a later piece of work: such a scene is refused
//! at start with that reason, not run wrong.

use std::io::Write;
use std::path::Path;

use protocol::scene::{OutputFormat, Scene};
use protocol::session::NodeModel;
use protocol::wire::{ConservedTotals, InterfaceLoads, NodeKind, SolidState, Stamp, StepPlan};

use crate::fv::{FluidSolver, Trouble};
use crate::node::FluidModel;

/// The real fluid.
pub struct RealFluid {
    solver: FluidSolver,
    gamma: f64,
    formats: Vec<OutputFormat>,
    name: String,
    probes: Vec<Probe>,
}

struct Probe {
    name: String,
    cell: usize,
    rows: Vec<String>,
}

impl RealFluid {
    /// Builds the solver of a fluid-only scene.
    pub fn from_scene(scene: &Scene) -> Result<RealFluid, String> {
        let cfg = scene
            .fluid
            .as_ref()
            .ok_or("the scene has no [fluid] section")?;
        if scene.solid.is_some() {
            return Err("the real fluid coupled with a solid needs the cut-cell update, which is not wired yet: run it with --fluid pressure, or drop [solid]".into());
        }
        let solver = FluidSolver::from_scene(cfg, scene.run.threads as usize)?;
        let mut probes = Vec::new();
        for probe in &scene.output.probes {
            if let Some(point) = &probe.point {
                let ijk = solver.grid().locate(point).ok_or_else(|| {
                    format!(
                        "probe {:?}: point {point:?} is outside the grid",
                        probe.name
                    )
                })?;
                probes.push(Probe {
                    name: probe.name.clone(),
                    cell: solver.grid().index(ijk[0], ijk[1], ijk[2]),
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
        })
    }
}

fn describe(troubles: &[Trouble], step: u64) -> String {
    let list: Vec<String> = troubles
        .iter()
        .map(|t| {
            format!(
                "{:?} in cell {:?} at {:?} after the sweep along axis {}: rho = {:e}, p = {:e}, velocity = {:?}",
                t.kind, t.cell, t.position, t.axis, t.rho, t.p, t.velocity
            )
        })
        .collect();
    format!("step {step}: {}", list.join("; "))
}

impl NodeModel for RealFluid {
    fn implementation(&self) -> &'static str {
        "real"
    }

    fn dt_max(&self) -> (f64, String) {
        (self.solver.max_dt(), "cfl".into())
    }

    fn totals(&self, stamp: Stamp, t: f64) -> ConservedTotals {
        let totals = self.solver.totals();
        let dim = self.dim();
        ConservedTotals {
            stamp,
            node: NodeKind::Fluid,
            t,
            mass: totals.mass,
            momentum: totals.momentum[..dim].to_vec(),
            energy: totals.energy,
            dissipated: 0.0,
            interface_work: 0.0,
            interface_impulse: vec![0.0; dim],
            boundary_mass_out: totals.outflow_mass,
            boundary_energy_out: totals.outflow_energy,
            links_broken: 0,
            energy_scale: totals.energy.abs(),
        }
    }

    fn checkpoint(&self) -> Vec<u8> {
        self.solver.to_checkpoint()
    }

    fn restore(&mut self, bytes: &[u8]) -> Result<(), String> {
        self.solver.restore_checkpoint(bytes)
    }

    fn write_output(&mut self, k: u32, t: f64, out: &Path) -> std::io::Result<()> {
        let grid = self.solver.grid();
        let state = self.solver.state();
        if self.formats.contains(&OutputFormat::Csv) {
            let mut w =
                std::io::BufWriter::new(std::fs::File::create(out.join(format!("fluid_{k}.csv")))?);
            crate::output::write_fluid_csv(&mut w, grid, state, self.gamma, None)?;
            w.flush()?;
        }
        if self.formats.contains(&OutputFormat::Vtk) {
            let mut w =
                std::io::BufWriter::new(std::fs::File::create(out.join(format!("fluid_{k}.vtk")))?);
            let title = format!("{} fluid output {k} t = {t:e}", self.name);
            crate::output::write_fluid_vtk(&mut w, grid, state, self.gamma, None, &title)?;
            w.flush()?;
        }
        Ok(())
    }

    fn record_probes(&mut self, t: f64) {
        let dim = self.dim();
        for probe in &mut self.probes {
            let (rho, u, p) = self.solver.primitive(probe.cell);
            let vel: Vec<String> = u[..dim].iter().map(|v| format!("{v:e}")).collect();
            probe
                .rows
                .push(format!("{t:e},{rho:e},{},{p:e}", vel.join(",")));
        }
    }

    fn write_probes(&self, out: &Path) -> std::io::Result<()> {
        let vel = ["u", "v", "w"][..self.dim()].join(",");
        for probe in &self.probes {
            let mut text = format!("t,rho,{vel},p\n");
            for row in &probe.rows {
                text.push_str(row);
                text.push('\n');
            }
            std::fs::write(out.join(format!("probe_{}.csv", probe.name)), text)?;
        }
        Ok(())
    }
}

impl FluidModel for RealFluid {
    fn dim(&self) -> usize {
        self.solver.grid().dim
    }

    fn predict(&mut self, _plan: &StepPlan) -> Result<(), String> {
        Ok(())
    }

    fn loads(&mut self, plan: &StepPlan, state: &SolidState) -> InterfaceLoads {
        // Unreachable: a coupled scene is refused in `from_scene`.
        InterfaceLoads {
            stamp: plan.stamp,
            dim: state.dim,
            force: vec![0.0; state.position.len()],
            torque: vec![0.0; state.n_particles() * protocol::wire::n_rot(state.dim)],
        }
    }

    fn correct(&mut self, plan: &StepPlan, _state: Option<&SolidState>) -> Result<(), String> {
        let allowed = self.solver.max_dt();
        // NOTE: the coupler's step is the minimum of the proposals, so it can only exceed the
        // CFL step through a bug or a tampered message; refuse rather than run unstable.
        if plan.dt > allowed * (1.0 + 1e-12) {
            return Err(format!(
                "step {}: CFL violated: dt = {:e} exceeds the CFL step {:e}",
                plan.stamp.step, plan.dt, allowed
            ));
        }
        let report = self.solver.advance(plan.dt);
        if report.ok() {
            Ok(())
        } else {
            Err(describe(&report.troubles, plan.stamp.step))
        }
    }
}
