//! The prescribed double (`solid-node --double prescribed`): one rigid box whose motion the
//! scene prescribes (fixed, constant velocity, sinusoid), or a mass on a linear spring driven by
//! the received loads (`m x'' = −k (x − x0) + F`, velocity Verlet), so that the semi-implicit
//! fixed point has something to converge. Translation only: torques are received and ignored.

use std::path::Path;

use protocol::scene::{PrescribedConfig, PrescribedMotion};
use protocol::session::{NodeModel, StepLimit};
use protocol::wire::{
    ConservedTotals, InterfaceLoads, NodeKind, SolidState, Stamp, StepPlan, WetSurface,
};
use serde::{Deserialize, Serialize};

use crate::error::StepError;
use crate::model::SolidModel;

/// The double's state.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PrescribedDouble {
    #[serde(skip)]
    motion: Option<PrescribedMotion>,
    dim: usize,
    x0: Vec<f64>,
    half: Vec<f64>,
    x: Vec<f64>,
    v: Vec<f64>,
    /// Last trial: position, mid-step velocity, force.
    trial_x: Vec<f64>,
    trial_v_half: Vec<f64>,
    trial_force: Vec<f64>,
    work: f64,
    impulse: Vec<f64>,
}

impl PrescribedDouble {
    /// A double for a `dim`-D scene (2 or 3).
    pub fn new(dim: usize, cfg: &PrescribedConfig) -> PrescribedDouble {
        let x0 = cfg.r#box.center.clone();
        PrescribedDouble {
            motion: Some(cfg.motion.clone()),
            dim,
            half: cfg.r#box.size.iter().map(|s| s / 2.0).collect(),
            x: x0.clone(),
            v: match &cfg.motion {
                PrescribedMotion::Velocity(v) => v.clone(),
                PrescribedMotion::Sinusoid {
                    amplitude,
                    frequency,
                } => amplitude
                    .iter()
                    .map(|a| a * 2.0 * std::f64::consts::PI * frequency)
                    .collect(),
                _ => vec![0.0; dim],
            },
            trial_x: x0.clone(),
            trial_v_half: vec![0.0; dim],
            trial_force: vec![0.0; dim],
            x0,
            work: 0.0,
            impulse: vec![0.0; dim],
        }
    }

    fn motion(&self) -> &PrescribedMotion {
        self.motion
            .as_ref()
            .expect("the motion is set at construction")
    }

    fn surface(&self, x: &[f64]) -> WetSurface {
        let (dim, h) = (self.dim, &self.half);
        let (corners, elements): (Vec<[f64; 3]>, Vec<u32>) = if dim == 2 {
            (
                vec![[-1., -1., 0.], [1., -1., 0.], [1., 1., 0.], [-1., 1., 0.]],
                vec![0, 1, 1, 2, 2, 3, 3, 0],
            )
        } else {
            (
                vec![
                    [-1., -1., -1.],
                    [1., -1., -1.],
                    [1., 1., -1.],
                    [-1., 1., -1.],
                    [-1., -1., 1.],
                    [1., -1., 1.],
                    [1., 1., 1.],
                    [-1., 1., 1.],
                ],
                vec![
                    0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4, 1, 2, 6, 1, 6, 5, 2, 3,
                    7, 2, 7, 6, 3, 0, 4, 3, 4, 7,
                ],
            )
        };
        let vertices = corners
            .iter()
            .flat_map(|c| (0..dim).map(move |d| x[d] + c[d] * h[d]))
            .collect();
        let n_elements = elements.len() / dim;
        WetSurface {
            revision: 0,
            dim: dim as u32,
            vertices,
            elements,
            element_particle: vec![0; n_elements],
            wet: vec![true; n_elements],
        }
    }

    fn solid_state(&self, x: &[f64], v: &[f64]) -> SolidState {
        let n_rot = protocol::wire::n_rot(self.dim as u32);
        let n_ori = protocol::wire::n_orientation(self.dim as u32);
        let mut orientation = vec![0.0; n_ori];
        if self.dim == 3 {
            orientation[0] = 1.0;
        }
        SolidState {
            stamp: Stamp::default(),
            dim: self.dim as u32,
            position: x.to_vec(),
            orientation,
            velocity: v.to_vec(),
            angular_velocity: vec![0.0; n_rot],
            diameter: vec![2.0 * self.half.iter().map(|h| h * h).sum::<f64>().sqrt()],
            surface: self.surface(x),
            particles: Vec::new(),
            changed_only: false,
        }
    }

    fn spring_force(&self, x: &[f64], stiffness: f64) -> Vec<f64> {
        x.iter()
            .zip(&self.x0)
            .map(|(x, x0)| -stiffness * (x - x0))
            .collect()
    }
}

impl NodeModel for PrescribedDouble {
    fn implementation(&self) -> &'static str {
        "prescribed"
    }

    fn dt_max(&self) -> StepLimit {
        match self.motion() {
            // NOTE: velocity Verlet is stable for ω dt < 2; a 40th of the period keeps its
            // energy error near (ω dt)²/4 ≈ 6e-3 of the oscillator's energy.
            PrescribedMotion::Spring { mass, stiffness } => StepLimit {
                dt_max: 2.0 * std::f64::consts::PI * (mass / stiffness).sqrt() / 40.0,
                limiter: "spring-period".into(),
            },
            PrescribedMotion::Sinusoid { frequency, .. } => StepLimit {
                dt_max: 0.02 / frequency,
                limiter: "sinusoid-period".into(),
            },
            _ => StepLimit::none(),
        }
    }

    fn totals(&self, stamp: Stamp, t: f64) -> ConservedTotals {
        let (mass, energy, kinetic) = match self.motion() {
            PrescribedMotion::Spring { mass, stiffness } => {
                let v2: f64 = self.v.iter().map(|v| v * v).sum();
                let dx2: f64 = self
                    .x
                    .iter()
                    .zip(&self.x0)
                    .map(|(x, x0)| (x - x0) * (x - x0))
                    .sum();
                let kinetic = 0.5 * mass * v2;
                (*mass, kinetic + 0.5 * stiffness * dx2, kinetic)
            }
            // NOTE: a kinematic motion is driven from outside: what it receives is absorbed.
            _ => (0.0, self.work, 0.0),
        };
        ConservedTotals {
            stamp,
            node: NodeKind::Solid,
            t,
            mass,
            momentum: self.v.iter().map(|v| mass * v).collect(),
            energy,
            dissipated: 0.0,
            interface_work: self.work,
            interface_impulse: self.impulse.clone(),
            boundary_mass_out: 0.0,
            boundary_energy_out: 0.0,
            links_broken: 0,
            broken_pairs: Vec::new(),
            broken_substeps: Vec::new(),
            swept_mass: 0.0,
            vacuum_cells: 0,
            kinetic,
            energy_scale: energy.abs(),
        }
    }

    fn checkpoint(&self) -> Vec<u8> {
        protocol::codec::encode_blob(self)
    }

    fn restore(&mut self, bytes: &[u8]) -> Result<(), String> {
        let restored: PrescribedDouble = protocol::codec::decode_blob(bytes)?;
        let motion = self.motion.take();
        *self = PrescribedDouble { motion, ..restored };
        Ok(())
    }

    fn write_output(&mut self, k: u32, t: f64, out: &Path) -> std::io::Result<()> {
        use std::io::Write;
        let mut f =
            std::io::BufWriter::new(std::fs::File::create(out.join(format!("solid_{k}.csv")))?);
        let axes = &["x", "y", "z"][..self.dim];
        let vaxes = &["vx", "vy", "vz"][..self.dim];
        writeln!(f, "id,{},{},sigma_n", axes.join(","), vaxes.join(","))?;
        let fmt = |v: &[f64]| {
            v.iter()
                .map(|x| format!("{x:e}"))
                .collect::<Vec<_>>()
                .join(",")
        };
        writeln!(f, "0,{},{},0", fmt(&self.x), fmt(&self.v))?;
        let _ = t;
        f.flush()
    }

    fn record_probes(&mut self, _t: f64) {}

    fn write_probes(&mut self, _out: &Path, _end: bool) -> std::io::Result<()> {
        Ok(())
    }
}

impl SolidModel for PrescribedDouble {
    fn begin_step(&mut self, _plan: &StepPlan) -> Result<(), StepError> {
        Ok(())
    }

    fn trial(
        &mut self,
        plan: &StepPlan,
        loads: Option<&InterfaceLoads>,
    ) -> Result<SolidState, StepError> {
        let dim = self.dim;
        let force: Vec<f64> = match loads {
            // Loads of some particles without the first: none on it.
            Some(l) if l.particles.first().is_some_and(|&p| p != 0) => vec![0.0; dim],
            Some(l) if l.force.len() >= dim => l.force[..dim].to_vec(),
            Some(l) => {
                return Err(StepError::DoubleLoadsSize {
                    n_force: l.force.len(),
                    dim,
                });
            }
            None => vec![0.0; dim],
        };
        let t1 = plan.t_end();
        let (x1, v_half) = match self.motion().clone() {
            PrescribedMotion::Fixed => (self.x0.clone(), vec![0.0; dim]),
            PrescribedMotion::Velocity(v) => (
                self.x0.iter().zip(&v).map(|(x0, v)| x0 + v * t1).collect(),
                v,
            ),
            PrescribedMotion::Sinusoid {
                amplitude,
                frequency,
            } => {
                let w = 2.0 * std::f64::consts::PI * frequency;
                let x1: Vec<f64> = self
                    .x0
                    .iter()
                    .zip(&amplitude)
                    .map(|(x0, a)| x0 + a * (w * t1).sin())
                    .collect();
                let v_half = x1
                    .iter()
                    .zip(&self.x)
                    .map(|(x1, x)| (x1 - x) / plan.dt)
                    .collect();
                (x1, v_half)
            }
            PrescribedMotion::Spring { mass, stiffness } => {
                let spring = self.spring_force(&self.x, stiffness);
                let v_half: Vec<f64> = (0..dim)
                    .map(|d| self.v[d] + plan.dt / (2.0 * mass) * (spring[d] + force[d]))
                    .collect();
                let x1 = (0..dim).map(|d| self.x[d] + plan.dt * v_half[d]).collect();
                (x1, v_half)
            }
        };
        if let Some(bad) = x1.iter().chain(&v_half).find(|x| !x.is_finite()) {
            return Err(StepError::DoubleNonFinite { value: *bad });
        }
        let state = self.solid_state(&x1, &v_half);
        self.trial_x = x1;
        self.trial_v_half = v_half;
        self.trial_force = force;
        Ok(state)
    }

    fn commit(&mut self, plan: &StepPlan) -> Result<(), StepError> {
        let dim = self.dim;
        for d in 0..dim {
            self.work += self.trial_force[d] * (self.trial_x[d] - self.x[d]);
            self.impulse[d] += self.trial_force[d] * plan.dt;
        }
        self.v = match self.motion().clone() {
            PrescribedMotion::Spring { mass, stiffness } => {
                let spring = self.spring_force(&self.trial_x, stiffness);
                (0..dim)
                    .map(|d| {
                        self.trial_v_half[d]
                            + plan.dt / (2.0 * mass) * (spring[d] + self.trial_force[d])
                    })
                    .collect()
            }
            _ => self.trial_v_half.clone(),
        };
        self.x = self.trial_x.clone();
        Ok(())
    }

    fn state(&self) -> SolidState {
        self.solid_state(&self.x, &self.v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use protocol::scene::BoxSpec;
    use protocol::wire::Scheme;

    fn plan(step: u64, t: f64, dt: f64) -> StepPlan {
        StepPlan {
            stamp: Stamp::step(step),
            t,
            dt,
            scheme: Scheme::Explicit,
            output: None,
            predicted: false,
        }
    }

    #[test]
    fn free_spring_oscillates_at_its_frequency_with_bounded_energy() {
        let cfg = PrescribedConfig {
            r#box: BoxSpec {
                center: vec![0.0, 0.0],
                size: vec![1.0, 1.0],
            },
            motion: PrescribedMotion::Spring {
                mass: 2.0,
                stiffness: 8.0,
            },
        };
        let mut double = PrescribedDouble::new(2, &cfg);
        double.v = vec![1.0, 0.0];
        let e0 = double.totals(Stamp::step(0), 0.0).energy;
        // ω = 2: after one period π the state returns; Verlet's phase error is O(dt²).
        let n = 2000;
        let dt = std::f64::consts::PI / n as f64;
        let mut max_err: f64 = 0.0;
        for step in 0..n {
            let p = plan(step, step as f64 * dt, dt);
            double.trial(&p, None).expect("finite");
            double.commit(&p).expect("commit");
            let e = double.totals(Stamp::step(step), 0.0).energy;
            max_err = max_err.max((e - e0).abs() / e0);
        }
        assert!(double.x[0].abs() < 1e-5, "x after a period {}", double.x[0]);
        assert!(
            (double.v[0] - 1.0).abs() < 1e-5,
            "v after a period {}",
            double.v[0]
        );
        // Velocity Verlet on a harmonic oscillator keeps E/E0 within [1, 1/(1 − (ω dt)²/4)].
        let x = (2.0 * dt) * (2.0 * dt) / 4.0;
        let bound = x / (1.0 - x) * (1.0 + 1e-6);
        assert!(
            max_err < bound,
            "energy error {max_err:e} vs bound {bound:e}"
        );
    }

    #[test]
    fn box_surface_is_closed_and_outward() {
        let cfg = PrescribedConfig {
            r#box: BoxSpec {
                center: vec![1.0, 2.0, 3.0],
                size: vec![1.0, 2.0, 4.0],
            },
            motion: PrescribedMotion::Fixed,
        };
        let double = PrescribedDouble::new(3, &cfg);
        let s = double.state();
        // Divergence theorem: Σ (centroid · area normal) / 3 is the volume 8.
        let v = &s.surface.vertices;
        let mut volume = 0.0;
        for tri in s.surface.elements.chunks(3) {
            let p: Vec<&[f64]> = tri
                .iter()
                .map(|&i| &v[i as usize * 3..i as usize * 3 + 3])
                .collect();
            let det = p[0][0] * (p[1][1] * p[2][2] - p[1][2] * p[2][1])
                - p[0][1] * (p[1][0] * p[2][2] - p[1][2] * p[2][0])
                + p[0][2] * (p[1][0] * p[2][1] - p[1][1] * p[2][0]);
            volume += det / 6.0;
        }
        assert!((volume - 8.0).abs() < 1e-12, "{volume}");
    }
}
