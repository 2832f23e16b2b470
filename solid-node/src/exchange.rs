//! The DEM solid as a [`SolidModel`]: conversions between the solver and the wire, outputs and
//! probes.

use std::io::Write;
use std::path::Path;

use protocol::scene::{
    AUTO_SUBSTEP_FRACTION, MAX_SOLID_SUBSTEPS, OutputFormat, Scene, SolidSubsteps, SolidWalls,
};
use protocol::session::{NodeModel, StepLimit};
use protocol::vtk::Series;
use protocol::wire::{
    ConservedTotals, InterfaceLoads, NodeKind, SolidState, Stamp, StepPlan, WetSurface,
};

use crate::dem::{ParticleId, Solid, WetSurfaceData};
use crate::error::{BuildError, StepError};
use crate::model::SolidModel;

/// The real solid.
pub struct RealSolid {
    solid: Solid,
    /// Largest displacement per step allowed by the fluid (one cell) [m].
    displacement_cap: f64,
    formats: Vec<OutputFormat>,
    name: String,
    probes: Vec<Probe>,
    /// The probe files exist: later rows are appended (`NodeModel::write_probes`).
    probes_started: bool,
    links_broken: u64,
    /// Particle ids of the links broken in the last committed step, two per link, in break
    /// order (the totals of that step carry them to the coupler's `links_broken.csv`).
    last_broken: Vec<u32>,
    /// The sub-step (1 to K) in which each of them broke.
    last_broken_substeps: Vec<u32>,
    zero_force: Vec<f64>,
    zero_torque: Vec<f64>,
    /// Loads of only some particles spread onto all of them (`InterfaceLoads::particles`).
    spread: (Vec<f64>, Vec<f64>),
    /// The `.vtp` files written so far: `particles.pvd`, `solid.pvd`, `wet.pvd`.
    vtk_series: [Series; 3],
    /// `run.solid_substeps` (`None`: one step per coupling step, bounded by the solid's).
    substeps: Option<SolidSubsteps>,
}

struct Probe {
    name: String,
    particle: ParticleId,
    /// `t, x, y[, z], vx, vy[, vz], sigma_n` per recorded step, formatted.
    rows: Vec<Vec<String>>,
}

impl RealSolid {
    /// Builds the DEM of a scene.
    pub fn from_scene(scene: &Scene) -> Result<RealSolid, BuildError> {
        let cfg = scene.solid.as_ref().ok_or(BuildError::NoSolidSection)?;
        let dim = scene.dim();
        let mut solid = Solid::from_scene(cfg, dim, scene.run.threads as usize)?;
        if let (Some(fluid), SolidWalls::Hold) = (&scene.fluid, cfg.walls.unwrap_or_default()) {
            solid.set_walls(&fluid.lower, &fluid.upper, &fluid.boundary);
        }
        if cfg.face_inertia == Some(protocol::scene::FaceInertia::Unweighted) {
            tracing::warn!(
                "solid.face_inertia = \"unweighted\": the link faces' second moments are the \
                 authors' pre-2017 sum (m^2, not m^4), which stiffens flexion and torsion; for \
                 reproducing papers 003 and 000 only"
            );
        }
        let displacement_cap = scene.fluid.as_ref().map_or(f64::INFINITY, |f| {
            (0..dim)
                .map(|a| (f.upper[a] - f.lower[a]) / f64::from(f.cells[a]))
                .fold(f64::INFINITY, f64::min)
        });
        let n = solid.n_particles();
        let mut probes = Vec::new();
        for probe in &scene.output.probes {
            let particle = if let Some(id) = probe.particle {
                if id as usize >= n {
                    return Err(BuildError::ProbeParticle {
                        name: probe.name.clone(),
                        particle: id,
                        n_particles: n,
                    });
                }
                ParticleId(id)
            } else if let Some(at) = &probe.particle_at {
                let nearest = (0..n)
                    .min_by(|&a, &b| {
                        let d = |p: usize| {
                            let x = solid.position(ParticleId(p as u32));
                            (0..dim).map(|k| (x[k] - at[k]).powi(2)).sum::<f64>()
                        };
                        d(a).total_cmp(&d(b))
                    })
                    .ok_or(BuildError::NoParticlesToProbe)?;
                ParticleId(nearest as u32)
            } else {
                continue;
            };
            probes.push(Probe {
                name: probe.name.clone(),
                particle,
                rows: Vec::new(),
            });
        }
        let n_rot = protocol::wire::n_rot(dim as u32);
        Ok(RealSolid {
            solid,
            displacement_cap,
            formats: scene.output.formats.clone(),
            name: scene.name.clone(),
            probes,
            probes_started: false,
            links_broken: 0,
            last_broken: Vec::new(),
            last_broken_substeps: Vec::new(),
            zero_force: vec![0.0; n * dim],
            zero_torque: vec![0.0; n * n_rot],
            spread: (vec![0.0; n * dim], vec![0.0; n * n_rot]),
            vtk_series: Default::default(),
            substeps: scene.run.solid_substeps,
        })
    }

    fn surface(wet: &WetSurfaceData) -> WetSurface {
        WetSurface {
            revision: wet.revision,
            dim: wet.dim as u32,
            vertices: wet.vertices.clone(),
            elements: wet.elements.clone(),
            element_particle: wet.element_particle.clone(),
            wet: wet.wet.clone(),
        }
    }

    fn diameters(&self) -> Vec<f64> {
        self.solid
            .model()
            .particles
            .iter()
            .map(|p| p.size)
            .collect()
    }
}

impl NodeModel for RealSolid {
    fn implementation(&self) -> &'static str {
        "real"
    }

    fn dt_max(&self) -> StepLimit {
        if self.substeps.is_some() {
            // The coupling step is bounded by the motion; the stability bound goes to the
            // sub-steps (`substep_bound`).
            let dt = self.solid.motion_dt(self.displacement_cap);
            return StepLimit {
                dt_max: dt,
                limiter: if dt.is_finite() {
                    "dem motion bound (a particle moves or turns fast)".into()
                } else {
                    "none".into()
                },
            };
        }
        let dt = self.solid.max_dt(self.displacement_cap);
        // Which particle limits the step, so that a collapsing step names it.
        let (elastic, particle) = self.solid.elastic_dt_limit();
        let why = if dt >= crate::dem::solid::ELASTIC_SAFETY * elastic {
            format!("dem elastic bound at particle {}", particle.0)
        } else {
            "dem motion bound (a particle moves or turns fast)".to_string()
        };
        StepLimit {
            dt_max: dt,
            limiter: why,
        }
    }

    fn substep_bound(&self) -> Option<StepLimit> {
        self.substeps?;
        let (_, particle) = self.solid.elastic_dt_limit();
        Some(StepLimit {
            dt_max: self.solid.stable_dt(),
            limiter: format!("dem elastic bound at particle {}", particle.0),
        })
    }

    fn totals(&self, stamp: Stamp, t: f64) -> ConservedTotals {
        let e = self.solid.energies();
        let m = self.solid.momentum();
        let dim = self.solid.dim();
        let mass: f64 = self.solid.model().particles.iter().map(|p| p.mass).sum();
        ConservedTotals {
            stamp,
            node: NodeKind::Solid,
            t,
            mass,
            momentum: m.linear[..dim].to_vec(),
            energy: e.kinetic_translation + e.kinetic_rotation + e.elastic + e.contact + e.gravity,
            // The prescribed motions' work enters as negative dissipation: energy put in.
            dissipated: e.dissipated - e.driven_work,
            interface_work: e.external_work,
            interface_impulse: self.solid.external_impulse()[..dim].to_vec(),
            boundary_mass_out: 0.0,
            boundary_energy_out: 0.0,
            links_broken: self.links_broken,
            broken_pairs: self.last_broken.clone(),
            broken_substeps: self.last_broken_substeps.clone(),
            swept_mass: 0.0,
            vacuum_cells: 0,
            kinetic: e.kinetic_translation + e.kinetic_rotation,
            energy_scale: e.kinetic_translation
                + e.kinetic_rotation
                + e.elastic.abs()
                + e.contact
                + e.gravity.abs()
                + e.dissipated.abs()
                + e.driven_work.abs(),
        }
    }

    fn checkpoint(&self) -> Vec<u8> {
        protocol::codec::encode_blob(&(self.links_broken, self.solid.to_checkpoint()))
    }

    fn restore(&mut self, bytes: &[u8]) -> Result<(), String> {
        let (links_broken, inner): (u64, Vec<u8>) = protocol::codec::decode_blob(bytes)?;
        self.solid
            .restore_checkpoint(&inner)
            .map_err(|e| e.to_string())?;
        self.links_broken = links_broken;
        // A checkpoint is the state at the start of a step: nothing has broken in it yet.
        self.last_broken.clear();
        self.last_broken_substeps.clear();
        Ok(())
    }

    fn write_output(&mut self, k: u32, t: f64, out: &Path) -> std::io::Result<()> {
        if self.formats.contains(&OutputFormat::Csv) {
            let mut w =
                std::io::BufWriter::new(std::fs::File::create(out.join(format!("solid_{k}.csv")))?);
            crate::output::write_particles_csv(&mut w, &self.solid)?;
            w.flush()?;
        }
        let title = format!("{} solid output {k} t = {t:e}", self.name);
        if self.formats.contains(&OutputFormat::Vtk) {
            let files = [
                (
                    "particles",
                    crate::output::particles_vtp(&self.solid, &title),
                ),
                ("solid", crate::output::solid_faces_vtp(&self.solid, &title)),
                (
                    "wet",
                    crate::output::wet_surface_vtp(self.solid.wet_surface(), &title),
                ),
            ];
            for ((kind, bytes), series) in files.into_iter().zip(&mut self.vtk_series) {
                let file = format!("{kind}_{k}.vtp");
                std::fs::write(out.join(&file), bytes)?;
                let pvd = series.record(k, t, &file);
                crate::output::replace_file(&out.join(format!("{kind}.pvd")), pvd.as_bytes())?;
            }
        }
        if self.formats.contains(&OutputFormat::VtkLegacy) {
            let mut w =
                std::io::BufWriter::new(std::fs::File::create(out.join(format!("solid_{k}.vtk")))?);
            crate::output::write_particles_vtk(&mut w, &self.solid, &title)?;
            w.flush()?;
            let mut w =
                std::io::BufWriter::new(std::fs::File::create(out.join(format!("wet_{k}.vtk")))?);
            crate::output::write_wet_surface_vtk(&mut w, self.solid.wet_surface(), &title)?;
            w.flush()?;
        }
        Ok(())
    }

    fn record_probes(&mut self, t: f64) {
        let dim = self.solid.dim();
        let sigma = if self.probes.is_empty() {
            Vec::new()
        } else {
            self.solid.normal_stress()
        };
        for probe in &mut self.probes {
            let x = self.solid.position(probe.particle);
            let v = self.solid.velocity(probe.particle);
            let s = sigma[probe.particle.0 as usize];
            let row = [&t]
                .into_iter()
                .chain(&x[..dim])
                .chain(&v[..dim])
                .chain([&s]);
            probe.rows.push(row.map(|c| format!("{c:e}")).collect());
        }
    }

    fn write_probes(&mut self, out: &Path, end: bool) -> std::io::Result<()> {
        let held = self.probes.iter().map(|p| p.rows.len()).max().unwrap_or(0);
        if !end && held < protocol::session::PROBE_ROWS_HELD {
            return Ok(());
        }
        let dim = self.solid.dim();
        let started = std::mem::replace(&mut self.probes_started, true);
        for probe in &mut self.probes {
            let mut table = csv::Writer::from_writer(Vec::new());
            if !started {
                let (axes, vels) = (&["x", "y", "z"][..dim], &["vx", "vy", "vz"][..dim]);
                table.write_record(["t"].iter().chain(axes).chain(vels).chain(&["sigma_n"]))?;
            }
            for row in probe.rows.drain(..) {
                table.write_record(row)?;
            }
            table.flush()?;
            let path = out.join(format!("probe_{}.csv", probe.name));
            crate::output::append_or_create(&path, started, table.get_ref())?;
        }
        Ok(())
    }
}

impl SolidModel for RealSolid {
    fn begin_step(&mut self, plan: &StepPlan) -> Result<(), StepError> {
        let Some(setting) = self.substeps else {
            self.solid.begin_step(plan.dt);
            return Ok(());
        };
        // The bound proposed for this step (the state has not moved since): the coupler
        // computes the same K from the same two numbers.
        let bound = self.solid.stable_dt();
        let k = setting
            .for_step(plan.dt, bound)
            .map_err(|needed| StepError::TooManySubsteps {
                step: plan.stamp.step,
                dt: plan.dt,
                // Only "auto" runs out: its sub-steps stay within this part of the bound.
                bound: bound * AUTO_SUBSTEP_FRACTION,
                needed,
                max: MAX_SOLID_SUBSTEPS,
                particle: self.solid.elastic_dt_limit().1.0,
            })?;
        self.solid.begin_substeps(plan.dt, k);
        Ok(())
    }

    fn trial(
        &mut self,
        plan: &StepPlan,
        loads: Option<&InterfaceLoads>,
    ) -> Result<SolidState, StepError> {
        let (force, torque) = match loads {
            Some(l) if l.particles.is_empty() => {
                if l.force.len() != self.zero_force.len()
                    || l.torque.len() != self.zero_torque.len()
                {
                    return Err(StepError::LoadsSize {
                        step: plan.stamp.step,
                        n_force: l.force.len(),
                        n_torque: l.torque.len(),
                        n_force_expected: self.zero_force.len(),
                        n_torque_expected: self.zero_torque.len(),
                    });
                }
                (l.force.as_slice(), l.torque.as_slice())
            }
            Some(l) => {
                spread_loads(l, &mut self.spread).map_err(|what| StepError::LoadsOf {
                    step: plan.stamp.step,
                    what,
                })?;
                (self.spread.0.as_slice(), self.spread.1.as_slice())
            }
            None => (self.zero_force.as_slice(), self.zero_torque.as_slice()),
        };
        let diameter = self.diameters();
        let trial = self.solid.trial(force, torque);
        Ok(SolidState {
            stamp: plan.stamp,
            dim: trial.dim as u32,
            position: trial.position.clone(),
            orientation: trial.orientation.clone(),
            velocity: trial.velocity_half.clone(),
            angular_velocity: trial.omega_half.clone(),
            diameter,
            surface: Self::surface(&trial.wet),
            particles: Vec::new(),
            changed_only: false,
        })
    }

    fn commit(&mut self, plan: &StepPlan) -> Result<(), StepError> {
        let report = self.solid.commit();
        self.links_broken += report.broken_links.len() as u64;
        self.last_broken.clear();
        self.last_broken_substeps.clear();
        for b in &report.broken_links {
            self.last_broken
                .extend([b.particles[0].0, b.particles[1].0]);
            self.last_broken_substeps.push(b.substep);
        }
        if report.diagnostics.is_empty() {
            Ok(())
        } else {
            Err(StepError::Numerical {
                step: plan.stamp.step,
                diagnostics: report.diagnostics,
            })
        }
    }

    fn state(&self) -> SolidState {
        let dim = self.solid.dim();
        let n = self.solid.n_particles();
        let mut s = SolidState {
            stamp: Stamp::default(),
            dim: dim as u32,
            position: Vec::with_capacity(n * dim),
            orientation: Vec::new(),
            velocity: Vec::with_capacity(n * dim),
            angular_velocity: Vec::new(),
            diameter: self.diameters(),
            surface: Self::surface(self.solid.wet_surface()),
            particles: Vec::new(),
            changed_only: false,
        };
        for p in 0..n {
            let id = ParticleId(p as u32);
            s.position
                .extend_from_slice(&self.solid.position(id)[..dim]);
            s.velocity
                .extend_from_slice(&self.solid.velocity(id)[..dim]);
            let q = self.solid.orientation(id);
            let w = self.solid.angular_velocity(id);
            if dim == 3 {
                s.orientation.extend_from_slice(&q);
                s.angular_velocity.extend_from_slice(&w);
            } else {
                s.orientation.push(q[0]);
                s.angular_velocity.push(w[2]);
            }
        }
        s
    }
}

/// Loads of some particles (`loads.particles`, as the fluid computes them on the particles its
/// surface's elements belong to) into `(force, torque)` of every particle, zero for the others:
/// the values the solid took when the loads came whole. An error says what does not fit.
fn spread_loads(
    loads: &InterfaceLoads,
    (force, torque): &mut (Vec<f64>, Vec<f64>),
) -> Result<(), String> {
    let k = loads.particles.len();
    let dim = loads.dim as usize;
    let rot = protocol::wire::n_rot(loads.dim);
    let n = force.len() / dim.max(1);
    if loads.force.len() != k * dim || loads.torque.len() != k * rot || torque.len() != n * rot {
        return Err(format!(
            "{} force and {} torque values in {dim}-D for {k} particles",
            loads.force.len(),
            loads.torque.len()
        ));
    }
    if let Some(w) = loads.particles.windows(2).find(|w| w[0] >= w[1]) {
        return Err(format!(
            "particle numbers not ascending: {} then {}",
            w[0], w[1]
        ));
    }
    if let Some(&p) = loads.particles.last().filter(|&&p| p as usize >= n) {
        return Err(format!("particle {p}, the solid has {n}"));
    }
    force.fill(0.0);
    torque.fill(0.0);
    for (i, &p) in loads.particles.iter().enumerate() {
        let p = p as usize;
        force[p * dim..(p + 1) * dim].copy_from_slice(&loads.force[i * dim..(i + 1) * dim]);
        torque[p * rot..(p + 1) * rot].copy_from_slice(&loads.torque[i * rot..(i + 1) * rot]);
    }
    Ok(())
}

#[cfg(test)]
mod spread_tests {
    use protocol::wire::{InterfaceLoads, Stamp};

    use super::spread_loads;

    fn loads(particles: Vec<u32>, force: Vec<f64>, torque: Vec<f64>) -> InterfaceLoads {
        InterfaceLoads {
            stamp: Stamp::step(1),
            dim: 2,
            force,
            torque,
            particles,
        }
    }

    #[test]
    fn loads_of_some_particles_land_on_them_and_the_rest_get_none() {
        // Four particles in 2-D; the buffers hold last call's values, which must not survive.
        let mut spread = (vec![9.0; 8], vec![9.0; 4]);
        let l = loads(vec![1, 3], vec![1.5, -2.0, 0.25, 1e-300], vec![-0.0, 7.0]);
        spread_loads(&l, &mut spread).unwrap();
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(
            bits(&spread.0),
            bits(&[0.0, 0.0, 1.5, -2.0, 0.0, 0.0, 0.25, 1e-300])
        );
        assert_eq!(bits(&spread.1), bits(&[0.0, -0.0, 0.0, 7.0]));
    }

    #[test]
    fn loads_that_do_not_fit_are_refused_with_the_reason() {
        let mut spread = (vec![0.0; 8], vec![0.0; 4]);
        let cases = [
            (loads(vec![1, 3], vec![1.0; 3], vec![0.0; 2]), "3 force"),
            (
                loads(vec![3, 1], vec![1.0; 4], vec![0.0; 2]),
                "not ascending",
            ),
            (
                loads(vec![1, 4], vec![1.0; 4], vec![0.0; 2]),
                "particle 4, the solid has 4",
            ),
        ];
        for (l, why) in cases {
            let err = spread_loads(&l, &mut spread).unwrap_err();
            assert!(err.contains(why), "{err}");
        }
    }
}
