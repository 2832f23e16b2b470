//! The pressure double (`fluid-node --double pressure`): loads from a prescribed pressure field
//! integrated over the received wet surface, no grid, no flow.
//!
//! `p(x, v) = value + gradient · x + impedance (v · n)` at each element's centroid; for a flat
//! element and a linear field the centroid value times the area is the exact integral. The
//! double accounts the work its loads do on the solid (`Σ F · ΔX + τ · Δθ`) so the ledger can
//! check that the solid receives exactly what the "fluid" gives.

use std::path::Path;

use protocol::scene::PressureField;
use protocol::session::{NodeModel, StepLimit};
use protocol::wire::{ConservedTotals, InterfaceLoads, NodeKind, SolidState, Stamp, StepPlan};

use crate::Error;
use crate::model::FluidModel;

/// The pressure double's state.
#[derive(Clone, Debug)]
pub struct PressureDouble {
    dim: usize,
    field: PressureField,
    last_loads: Option<InterfaceLoads>,
    previous: Option<SolidState>,
    work: f64,
    impulse: Vec<f64>,
}

impl PressureDouble {
    /// A double for a `dim`-D scene (2 or 3).
    pub fn new(dim: usize, field: PressureField) -> PressureDouble {
        PressureDouble {
            dim,
            field,
            last_loads: None,
            previous: None,
            work: 0.0,
            impulse: vec![0.0; dim],
        }
    }

    fn pressure(&self, x: &[f64], v_n: f64) -> f64 {
        let gx: f64 = self.field.gradient.iter().zip(x).map(|(g, x)| g * x).sum();
        self.field.value + gx + self.field.impedance * v_n
    }
}

/// Force and torque per particle of a pressure field over a wet surface.
pub fn integrate_pressure(
    state: &SolidState,
    pressure: impl Fn(&[f64], f64) -> f64,
    force: &mut Vec<f64>,
    torque: &mut Vec<f64>,
) {
    let dim = state.dim as usize;
    let n_rot = protocol::wire::n_rot(state.dim);
    let n = state.n_particles();
    force.clear();
    force.resize(n * dim, 0.0);
    torque.clear();
    torque.resize(n * n_rot, 0.0);
    let s = &state.surface;
    let vertex = |v: u32| &s.vertices[v as usize * dim..v as usize * dim + dim];
    for (e, &particle) in s.element_particle.iter().enumerate() {
        if !s.wet[e] {
            continue;
        }
        let ids = &s.elements[e * dim..e * dim + dim];
        let (c, area_normal) = if dim == 2 {
            let (a, b) = (vertex(ids[0]), vertex(ids[1]));
            // Length times the fluid-side normal (dy, −dx).
            (
                [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0, 0.0],
                [b[1] - a[1], -(b[0] - a[0]), 0.0],
            )
        } else {
            let (a, b, cc) = (vertex(ids[0]), vertex(ids[1]), vertex(ids[2]));
            let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            let w = [cc[0] - a[0], cc[1] - a[1], cc[2] - a[2]];
            // Half the cross product: area times unit normal.
            (
                [
                    (a[0] + b[0] + cc[0]) / 3.0,
                    (a[1] + b[1] + cc[1]) / 3.0,
                    (a[2] + b[2] + cc[2]) / 3.0,
                ],
                [
                    0.5 * (u[1] * w[2] - u[2] * w[1]),
                    0.5 * (u[2] * w[0] - u[0] * w[2]),
                    0.5 * (u[0] * w[1] - u[1] * w[0]),
                ],
            )
        };
        let area = area_normal[..dim].iter().map(|x| x * x).sum::<f64>().sqrt();
        if area == 0.0 {
            continue;
        }
        let i = particle as usize;
        let x_i = &state.position[i * dim..i * dim + dim];
        let mut r = [0.0; 3];
        for d in 0..dim {
            r[d] = c[d] - x_i[d];
        }
        let v_i = &state.velocity[i * dim..i * dim + dim];
        let w_i = &state.angular_velocity[i * n_rot..i * n_rot + n_rot];
        let v_c = if dim == 2 {
            [v_i[0] - w_i[0] * r[1], v_i[1] + w_i[0] * r[0], 0.0]
        } else {
            [
                v_i[0] + w_i[1] * r[2] - w_i[2] * r[1],
                v_i[1] + w_i[2] * r[0] - w_i[0] * r[2],
                v_i[2] + w_i[0] * r[1] - w_i[1] * r[0],
            ]
        };
        let v_n: f64 = (0..dim).map(|d| v_c[d] * area_normal[d]).sum::<f64>() / area;
        let p = pressure(&c[..dim], v_n);
        let f = [
            -p * area_normal[0],
            -p * area_normal[1],
            -p * area_normal[2],
        ];
        for d in 0..dim {
            force[i * dim + d] += f[d];
        }
        if dim == 2 {
            torque[i] += r[0] * f[1] - r[1] * f[0];
        } else {
            torque[i * 3] += r[1] * f[2] - r[2] * f[1];
            torque[i * 3 + 1] += r[2] * f[0] - r[0] * f[2];
            torque[i * 3 + 2] += r[0] * f[1] - r[1] * f[0];
        }
    }
}

impl NodeModel for PressureDouble {
    fn implementation(&self) -> &'static str {
        "pressure"
    }

    fn dt_max(&self) -> StepLimit {
        StepLimit::none()
    }

    fn totals(&self, stamp: Stamp, t: f64) -> ConservedTotals {
        ConservedTotals {
            stamp,
            node: NodeKind::Fluid,
            t,
            mass: 0.0,
            momentum: self.impulse.iter().map(|p| -p).collect(),
            // NOTE: the double is a reservoir: its energy is what it has given away.
            energy: -self.work,
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
            kinetic: 0.0,
            energy_scale: self.work.abs(),
        }
    }

    fn checkpoint(&self) -> Vec<u8> {
        protocol::codec::encode_blob(&(
            self.work,
            &self.impulse,
            self.previous.as_ref().map(|s| {
                protocol::codec::encode(
                    NodeKind::Solid,
                    &protocol::wire::Message::SolidState(s.clone()),
                )
            }),
        ))
    }

    fn restore(&mut self, bytes: &[u8]) -> Result<(), String> {
        let (work, impulse, previous): (f64, Vec<f64>, Option<Vec<u8>>) =
            protocol::codec::decode_blob(bytes)?;
        self.work = work;
        self.impulse = impulse;
        self.previous = match previous {
            Some(frame) => match protocol::codec::decode(&frame).map_err(|e| e.to_string())? {
                (_, protocol::wire::Message::SolidState(s)) => Some(s),
                _ => return Err("checkpoint holds no solid state".into()),
            },
            None => None,
        };
        Ok(())
    }

    fn write_output(&mut self, _k: u32, _t: f64, _out: &Path) -> std::io::Result<()> {
        Ok(())
    }

    fn record_probes(&mut self, _t: f64) {}

    fn write_probes(&mut self, _out: &Path, _end: bool) -> std::io::Result<()> {
        Ok(())
    }
}

impl FluidModel for PressureDouble {
    fn dim(&self) -> usize {
        self.dim
    }

    fn set_initial_surface(&mut self, state: &SolidState) -> Result<(), Error> {
        self.previous = Some(state.clone());
        Ok(())
    }

    fn predict(&mut self, _plan: &StepPlan) -> Result<(), Error> {
        Ok(())
    }

    fn loads(&mut self, plan: &StepPlan, state: &SolidState) -> Result<InterfaceLoads, Error> {
        let mut loads = InterfaceLoads {
            stamp: plan.stamp,
            dim: state.dim,
            force: Vec::new(),
            torque: Vec::new(),
            particles: state.particles.clone(),
        };
        integrate_pressure(
            state,
            |x, v_n| self.pressure(x, v_n),
            &mut loads.force,
            &mut loads.torque,
        );
        self.last_loads = Some(loads.clone());
        Ok(loads)
    }

    fn correct(&mut self, plan: &StepPlan, state: Option<&SolidState>) -> Result<(), Error> {
        let (Some(state), Some(loads)) = (state, &self.last_loads) else {
            return Ok(());
        };
        let dim = self.dim;
        let n_rot = protocol::wire::n_rot(dim as u32);
        let previous = self.previous.as_ref().unwrap_or(state);
        for i in 0..state.n_particles() {
            for d in 0..dim {
                let dx = state.position[i * dim + d] - previous.position[i * dim + d];
                self.work += loads.force[i * dim + d] * dx;
                self.impulse[d] += loads.force[i * dim + d] * plan.dt;
            }
            for r in 0..n_rot {
                // NOTE: the rotation increment over the step is Ω^{n+1/2} dt (exact for the
                // 2-D angle, the RATTLE mid-step rate in 3-D).
                let dtheta = state.angular_velocity[i * n_rot + r] * plan.dt;
                self.work += loads.torque[i * n_rot + r] * dtheta;
            }
        }
        self.previous = Some(state.clone());
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use protocol::wire::WetSurface;

    fn unit_square(x0: f64, y0: f64) -> SolidState {
        SolidState {
            stamp: Stamp::step(0),
            dim: 2,
            position: vec![x0 + 0.5, y0 + 0.5],
            orientation: vec![0.0],
            velocity: vec![0.0, 0.0],
            angular_velocity: vec![0.0],
            diameter: vec![2f64.sqrt()],
            surface: WetSurface {
                revision: 0,
                dim: 2,
                vertices: vec![x0, y0, x0 + 1.0, y0, x0 + 1.0, y0 + 1.0, x0, y0 + 1.0],
                elements: vec![0, 1, 1, 2, 2, 3, 3, 0],
                element_particle: vec![0; 4],
                wet: vec![true; 4],
            },
            particles: Vec::new(),
            changed_only: false,
        }
    }

    #[test]
    fn linear_field_gives_buoyancy_exactly() {
        // p = 5 − 2 y: the net force on a unit square is −∇p · area = (0, 2), no torque.
        let state = unit_square(0.3, -0.7);
        let (mut f, mut t) = (Vec::new(), Vec::new());
        integrate_pressure(&state, |x, _| 5.0 - 2.0 * x[1], &mut f, &mut t);
        assert!((f[0]).abs() < 1e-14 && (f[1] - 2.0).abs() < 1e-14, "{f:?}");
        assert!(t[0].abs() < 1e-14, "{t:?}");
    }

    #[test]
    fn impedance_opposes_motion() {
        let mut state = unit_square(0.0, 0.0);
        state.velocity = vec![0.5, 0.0];
        let (mut f, mut t) = (Vec::new(), Vec::new());
        // p = Z v·n with Z = 4: the right face (n = +x) sees p = 2, the left one p = −2.
        integrate_pressure(&state, |_, v_n| 4.0 * v_n, &mut f, &mut t);
        assert!((f[0] + 4.0).abs() < 1e-14 && f[1].abs() < 1e-14, "{f:?}");
    }

    #[test]
    fn uniform_pressure_on_a_closed_3d_box_has_no_resultant() {
        // A unit cube as 12 outward triangles.
        let v = [
            [0., 0., 0.],
            [1., 0., 0.],
            [1., 1., 0.],
            [0., 1., 0.],
            [0., 0., 1.],
            [1., 0., 1.],
            [1., 1., 1.],
            [0., 1., 1.],
        ];
        let tris: [[u32; 3]; 12] = [
            [0, 2, 1],
            [0, 3, 2],
            [4, 5, 6],
            [4, 6, 7],
            [0, 1, 5],
            [0, 5, 4],
            [1, 2, 6],
            [1, 6, 5],
            [2, 3, 7],
            [2, 7, 6],
            [3, 0, 4],
            [3, 4, 7],
        ];
        let state = SolidState {
            stamp: Stamp::step(0),
            dim: 3,
            position: vec![0.5; 3],
            orientation: vec![1.0, 0.0, 0.0, 0.0],
            velocity: vec![0.0; 3],
            angular_velocity: vec![0.0; 3],
            diameter: vec![3f64.sqrt()],
            surface: WetSurface {
                revision: 0,
                dim: 3,
                vertices: v.iter().flatten().copied().collect(),
                elements: tris.iter().flatten().copied().collect(),
                element_particle: vec![0; 12],
                wet: vec![true; 12],
            },
            particles: Vec::new(),
            changed_only: false,
        };
        let (mut f, mut t) = (Vec::new(), Vec::new());
        integrate_pressure(&state, |_, _| 3.0, &mut f, &mut t);
        assert!(f.iter().chain(&t).all(|x| x.abs() < 1e-14), "{f:?} {t:?}");
        // p = z: the resultant −∫ p n dA = −∇p V = (0, 0, −1).
        integrate_pressure(&state, |x, _| x[2], &mut f, &mut t);
        assert!((f[2] + 1.0).abs() < 1e-14 && f[0].abs() < 1e-14, "{f:?}");
    }
}
