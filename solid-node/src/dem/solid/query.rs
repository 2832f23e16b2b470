//! What a [`Solid`] answers about its committed state: particles' kinematics, internal loads,
//! the wet surface, energies, momentum, normal stress; and the initial velocities it accepts.

use nalgebra::Vector3;

use crate::dem::model::{LinkId, Model, ParticleId, ParticleMotion, to3};
use crate::dem::report::{Energies, Momentum};
use crate::dem::solid::orientation::{quat, quat_arr};
use crate::dem::solid::state::Solid;
use crate::dem::wet::WetSurfaceData;

impl Solid {
    /// Number of particles.
    pub fn n_particles(&self) -> usize {
        self.model.particles.len()
    }

    /// Spatial dimension (2 or 3).
    pub fn dim(&self) -> usize {
        self.model.dim
    }

    /// The model (particles, links, faces).
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// Steps committed so far.
    pub fn step_count(&self) -> u64 {
        self.state.step
    }

    /// Simulated time \[s\].
    pub fn time(&self) -> f64 {
        self.state.time
    }

    /// Centre of particle `p` \[m\] (`dim` components used).
    pub fn position(&self, p: ParticleId) -> [f64; 3] {
        self.state.x[p.0 as usize]
    }

    /// Velocity of particle `p` \[m/s\].
    pub fn velocity(&self, p: ParticleId) -> [f64; 3] {
        self.state.v[p.0 as usize]
    }

    /// Orientation relative to t = 0: 2-D `\[θ, 0, 0, 0\]`, 3-D the quaternion `(w, x, y, z)`.
    pub fn orientation(&self, p: ParticleId) -> [f64; 4] {
        let i = p.0 as usize;
        if self.model.dim == 3 {
            quat_arr(&(quat(&self.state.rot[i]) * self.model.particles[i].axes0.inverse()))
        } else {
            self.state.rot[i]
        }
    }

    /// Rotation matrix `Q` of particle `p` relative to t = 0, row-major (2-D: about z).
    pub fn rotation_matrix(&self, p: ParticleId) -> [[f64; 3]; 3] {
        let i = p.0 as usize;
        let m = if self.model.dim == 3 {
            (quat(&self.state.rot[i]) * self.model.particles[i].axes0.inverse())
                .to_rotation_matrix()
                .into_inner()
        } else {
            nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), self.state.rot[i][0])
                .into_inner()
        };
        [
            [m[(0, 0)], m[(0, 1)], m[(0, 2)]],
            [m[(1, 0)], m[(1, 1)], m[(1, 2)]],
            [m[(2, 0)], m[(2, 1)], m[(2, 2)]],
        ]
    }

    /// Angular velocity of particle `p`, space frame \[rad/s\] (2-D: z only).
    pub fn angular_velocity(&self, p: ParticleId) -> [f64; 3] {
        let i = p.0 as usize;
        if self.model.dim == 3 {
            let inertia = self.model.particles[i].inertia;
            let m = self.state.ang[i];
            let w = Vector3::new(m[0] / inertia[0], m[1] / inertia[1], m[2] / inertia[2]);
            (quat(&self.state.rot[i]) * w).into()
        } else {
            self.state.ang[i]
        }
    }

    /// Sets the velocity of a free particle \[m/s\] (initial conditions).
    pub fn set_velocity(&mut self, p: ParticleId, v: &[f64]) {
        let i = p.0 as usize;
        if self.model.particles[i].motion == ParticleMotion::Free {
            self.state.v[i] = to3(v);
        }
        self.trial_valid = false;
    }

    /// Sets the angular velocity of a free particle, space frame \[rad/s\] (2-D: one value).
    pub fn set_angular_velocity(&mut self, p: ParticleId, omega: &[f64]) {
        let i = p.0 as usize;
        if self.model.particles[i].motion != ParticleMotion::Free {
            return;
        }
        if self.model.dim == 3 {
            let w_body =
                quat(&self.state.rot[i]).inverse_transform_vector(&Vector3::from(to3(omega)));
            let inertia = self.model.particles[i].inertia;
            self.state.ang[i] = [
                inertia[0] * w_body.x,
                inertia[1] * w_body.y,
                inertia[2] * w_body.z,
            ];
        } else {
            self.state.ang[i] = [0.0, 0.0, omega[0]];
        }
        self.trial_valid = false;
    }

    /// Whether link `l` is broken.
    pub fn is_broken(&self, l: LinkId) -> bool {
        self.state.broken[l.0 as usize]
    }

    /// Internal force on particle `p` at the current configuration \[N\].
    pub fn internal_force(&self, p: ParticleId) -> [f64; 3] {
        self.force_int[p.0 as usize]
    }

    /// Internal torque on particle `p` (space frame) \[N m\].
    pub fn internal_torque(&self, p: ParticleId) -> [f64; 3] {
        self.torque_int[p.0 as usize]
    }

    /// The wet surface at the committed state (velocities at n).
    pub fn wet_surface(&self) -> &WetSurfaceData {
        &self.wet
    }

    /// Impulse the external loads gave the particles so far, `Σ_steps Σ_p F_p Δt` (fixed
    /// particles included: what they receive goes to their constraint).
    pub fn external_impulse(&self) -> [f64; 3] {
        self.state.external_impulse
    }

    /// Energies at the committed state.
    pub fn energies(&self) -> Energies {
        let mut e = Energies {
            elastic: self.elastic,
            contact: self.contact.as_ref().map_or(0.0, |c| c.energy()),
            dissipated: self.state.dissipated,
            external_work: self.state.external_work,
            driven_work: self.state.driven_work,
            ..Energies::default()
        };
        for (p, part) in self.model.particles.iter().enumerate() {
            let v = Vector3::from(self.state.v[p]);
            e.kinetic_translation += 0.5 * part.mass * v.norm_squared();
            let m = self.state.ang[p];
            if self.model.dim == 3 {
                for (mk, ik) in m.iter().zip(&part.inertia) {
                    e.kinetic_rotation += 0.5 * mk * mk / ik;
                }
            } else {
                e.kinetic_rotation += 0.5 * part.inertia[0] * m[2] * m[2];
            }
            if part.motion == ParticleMotion::Free {
                e.gravity -=
                    part.mass * Vector3::from(self.gravity).dot(&Vector3::from(self.state.x[p]));
            }
        }
        e
    }

    /// Linear and angular momentum (about the origin) at the committed state.
    pub fn momentum(&self) -> Momentum {
        let mut lin = Vector3::zeros();
        let mut ang = Vector3::zeros();
        for (p, part) in self.model.particles.iter().enumerate() {
            let mv = Vector3::from(self.state.v[p]) * part.mass;
            lin += mv;
            ang += Vector3::from(self.state.x[p]).cross(&mv);
            if self.model.dim == 3 {
                ang += quat(&self.state.rot[p]) * Vector3::from(self.state.ang[p]);
            } else {
                ang.z += part.inertia[0] * self.state.ang[p][2];
            }
        }
        Momentum {
            linear: lin.into(),
            angular: ang.into(),
        }
    }

    /// Normal stress of each particle \[Pa\]: the mean over its unbroken links of the normal
    /// traction `F_J→I · (X_J − X_I)/|X_J − X_I| / S_IJ` (positive in tension, 0 without links),
    /// the quantity plotted in 000 Fig. 16.
    pub fn normal_stress(&self) -> Vec<f64> {
        let mut out = vec![0.0; self.n_particles()];
        for (p, value) in out.iter_mut().enumerate() {
            let range =
                self.model.incidence_start[p] as usize..self.model.incidence_start[p + 1] as usize;
            let mut sum = 0.0;
            let mut count = 0;
            for &(l, is_i) in &self.model.incidence[range] {
                if self.state.broken[l as usize] {
                    continue;
                }
                let link = &self.model.links[l as usize];
                let other = if is_i { link.j } else { link.i } as usize;
                let dir = (Vector3::from(self.state.x[other]) - Vector3::from(self.state.x[p]))
                    .normalize();
                let f = self.scratch.link_out[l as usize].force_i * if is_i { 1.0 } else { -1.0 };
                sum += f.dot(&dir) / link.area;
                count += 1;
            }
            if count > 0 {
                *value = sum / count as f64;
            }
        }
        out
    }
}
