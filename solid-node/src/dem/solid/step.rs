//! The splittable step: `begin_step`, repeatable `trial`, `commit` (003 eq. (4)–(11), loads
//! held over the step as in eq. (14)–(17)), and the per-particle kick–drift kernel.

use nalgebra::Vector3;

use crate::dem::model::{LinkId, Model, ParticleId, ParticleMotion, to3};
use crate::dem::rattle::{compose, dmv_drift};
use crate::dem::report::{BrokenLink, Diagnostic, StepReport};
use crate::dem::solid::{
    MAX_ROTATION, ParticleTrial, Solid, State, Trial, par_fill, quat, quat_arr, rotate_body,
};
use crate::dem::wet::{write_connectivity, write_geometry};

impl Solid {
    /// Starts the step `tⁿ → tⁿ + dt`: internal forces at `Xⁿ` (cached from the last commit).
    pub fn begin_step(&mut self, dt: f64) {
        assert!(
            dt > 0.0 && dt.is_finite(),
            "begin_step needs a finite dt > 0, got {dt}"
        );
        if !self.forces_valid {
            self.update_forces();
        }
        self.dt = dt;
        self.trial_valid = false;
    }

    /// Trial positions and velocities for external loads `force` (`dim` per particle, \[N\]) and
    /// `torque` (1 per particle in 2-D, 3 in 3-D, space frame, about the centre \[N m\]), held
    /// fixed over the step. May be called repeatedly; nothing is committed.
    pub fn trial(&mut self, force: &[f64], torque: &[f64]) -> &Trial {
        assert!(self.dt > 0.0, "begin_step must precede trial");
        let dim = self.model.dim;
        let n = self.n_particles();
        let n_rot = if dim == 3 { 3 } else { 1 };
        assert_eq!(
            force.len(),
            dim * n,
            "force needs {dim} components per particle"
        );
        assert_eq!(
            torque.len(),
            n_rot * n,
            "torque needs {n_rot} components per particle"
        );
        for p in 0..n {
            self.ext_force[p] = to3(&force[p * dim..(p + 1) * dim]);
            self.ext_torque[p] = if dim == 3 {
                to3(&torque[p * 3..p * 3 + 3])
            } else {
                [0.0, 0.0, torque[p]]
            };
        }
        let dt = self.dt;
        let model = &self.model;
        let state = &self.state;
        let (fi, ti, fe, te, g) = (
            &self.force_int,
            &self.torque_int,
            &self.ext_force,
            &self.ext_torque,
            self.gravity,
        );
        let damping = &self.state.contact_damping;
        par_fill(self.pool.as_ref(), &mut self.particle_trial, |p| {
            let (f, t) = with_damping(damping, p, fi[p], ti[p]);
            trial_particle(model, state, p, dt, f, t, fe[p], te[p], g)
        });
        // Flat views and the wet surface at the trial configuration.
        let t = &mut self.trial;
        t.dim = dim;
        t.position.clear();
        t.orientation.clear();
        t.velocity_half.clear();
        t.omega_half.clear();
        for (p, pt) in self.particle_trial.iter().enumerate() {
            t.position.extend_from_slice(&pt.x[..dim]);
            t.velocity_half.extend_from_slice(&pt.v_half[..dim]);
            if dim == 3 {
                let q = quat(&pt.rot) * self.model.particles[p].axes0.inverse();
                t.orientation.extend_from_slice(&quat_arr(&q));
                t.omega_half.extend_from_slice(&pt.omega);
            } else {
                t.orientation.push(pt.rot[0]);
                t.omega_half.push(pt.omega[2]);
            }
        }
        let (xs, vs, ws, rots) = &mut self.kin;
        xs.clear();
        vs.clear();
        ws.clear();
        rots.clear();
        for pt in &self.particle_trial {
            xs.push(pt.x);
            vs.push(pt.v_half);
            ws.push(pt.omega);
            rots.push(pt.rot);
        }
        write_connectivity(&self.model, &self.state.broken, &self.topo, &mut t.wet);
        t.wet.revision = self.state.wet_revision;
        let rotate = |p: usize, v: &Vector3<f64>| rotate_body(dim, &rots[p], v);
        write_geometry(
            &self.model,
            &self.topo,
            xs,
            &rotate,
            vs,
            ws,
            &mut self.sums,
            &mut t.wet,
        );
        self.trial_valid = true;
        &self.trial
    }

    /// Accepts the last trial: positions at n+1, internal forces at n+1, fracture, second half
    /// kick, diagnostics, wet surface at n+1.
    pub fn commit(&mut self) -> StepReport {
        assert!(self.trial_valid, "commit needs a trial");
        let dt = self.dt;
        let dim = self.model.dim;
        let mut diagnostics = Vec::new();
        let mut external_work = 0.0;
        if self.elongation_at_break.is_some() {
            self.before_step.0.clone_from(&self.state.x);
            self.before_step.1.clone_from(&self.state.rot);
        }
        // Internal loads at n on the driven particles (for the work of their constraints).
        let driven: Vec<(usize, Vector3<f64>)> = (0..self.n_particles())
            .filter(|&p| matches!(self.model.particles[p].motion, ParticleMotion::Velocity(_)))
            .map(|p| (p, Vector3::from(self.force_int[p])))
            .collect();
        for (p, pt) in self.particle_trial.iter().enumerate() {
            let dx = Vector3::from(pt.x) - Vector3::from(self.state.x[p]);
            let size = self.model.particles[p].size;
            if dx.norm() > size {
                diagnostics.push(Diagnostic::DisplacementTooLarge {
                    particle: ParticleId(p as u32),
                    displacement: dx.norm(),
                    size,
                });
            }
            if pt.angle > MAX_ROTATION {
                diagnostics.push(Diagnostic::RotationTooLarge {
                    particle: ParticleId(p as u32),
                    angle: pt.angle,
                });
            }
            if pt.residual > 1e-10 {
                diagnostics.push(Diagnostic::RattleNotConverged {
                    particle: ParticleId(p as u32),
                    residual: pt.residual,
                });
            }
            let w = Vector3::from(pt.omega) * dt;
            external_work += Vector3::from(self.ext_force[p]).dot(&dx)
                + Vector3::from(self.ext_torque[p]).dot(&w);
            self.motion[p] = [dx.into(), w.into()];
            for a in 0..3 {
                self.state.external_impulse[a] += self.ext_force[p][a] * dt;
            }
            self.state.x[p] = pt.x;
            self.state.rot[p] = pt.rot;
        }
        self.state.external_work += external_work;
        self.update_forces();
        let mut broken_links = Vec::new();
        if let Some(limit) = self.elongation_at_break {
            for (l, link) in self.model.links.iter().enumerate() {
                if self.state.broken[l] {
                    continue;
                }
                // 000 §3.1: A_IJ = (|X_I − X_J| − |X⁰_I − X⁰_J|)/|X⁰_I − X⁰_J| (as a fraction).
                let elongation = (self.scratch.link_out[l].distance - link.d0) / link.d0;
                if elongation > limit {
                    broken_links.push(BrokenLink {
                        link: LinkId(l as u32),
                        particles: [ParticleId(link.i), ParticleId(link.j)],
                        elongation,
                    });
                }
            }
            if !broken_links.is_empty() {
                let fresh: Vec<usize> = broken_links.iter().map(|b| b.link.0 as usize).collect();
                self.state.dissipated += self.break_dissipation(&fresh);
                self.state.wet_revision += 1;
                self.rebuild_wet_topology();
                self.limit = self.stability_limit();
            }
        }
        // A driven particle keeps its velocity: its constraint does minus the work of the loads
        // on it (they do not rotate, so only forces).
        for &(p, f_n) in &driven {
            let f =
                Vector3::from(self.ext_force[p]) + 0.5 * (f_n + Vector3::from(self.force_int[p]));
            self.state.driven_work -= f.dot(&Vector3::from(self.motion[p][0]));
        }
        if self.contact.is_some() {
            self.update_contact_damping();
        }
        // Second half kick with the forces at n+1 and the same external loads.
        for (p, part) in self.model.particles.iter().enumerate() {
            let pt = &self.particle_trial[p];
            match part.motion {
                ParticleMotion::Free => {}
                ParticleMotion::Fixed | ParticleMotion::Velocity(_) => {
                    self.state.v[p] = pt.v_half;
                    self.state.ang[p] = [0.0; 3];
                    continue;
                }
            }
            let (f_int, t_int) = with_damping(
                &self.state.contact_damping,
                p,
                self.force_int[p],
                self.torque_int[p],
            );
            let f = Vector3::from(f_int)
                + Vector3::from(self.ext_force[p])
                + Vector3::from(self.gravity) * part.mass;
            let v = Vector3::from(pt.v_half) + f * (0.5 * dt / part.mass);
            self.state.v[p] = v.into();
            let tau = Vector3::from(t_int) + Vector3::from(self.ext_torque[p]);
            if dim == 3 {
                let tau_body = quat(&self.state.rot[p]).inverse_transform_vector(&tau);
                self.state.ang[p] = (Vector3::from(pt.ang) + tau_body * (0.5 * dt)).into();
            } else {
                self.state.ang[p] = [0.0, 0.0, pt.ang[2] + 0.5 * dt * tau.z / part.inertia[0]];
            }
        }
        // Chokepoint checks.
        for p in 0..self.n_particles() {
            let checks: [(&str, bool); 4] = [
                ("position", self.state.x[p].iter().all(|v| v.is_finite())),
                ("velocity", self.state.v[p].iter().all(|v| v.is_finite())),
                (
                    "orientation",
                    self.state.rot[p].iter().all(|v| v.is_finite()),
                ),
                (
                    "angular momentum",
                    self.state.ang[p].iter().all(|v| v.is_finite()),
                ),
            ];
            for (quantity, ok) in checks {
                if !ok {
                    diagnostics.push(Diagnostic::NonFinite {
                        particle: ParticleId(p as u32),
                        quantity: quantity.to_string(),
                    });
                }
            }
        }
        for (l, link) in self.model.links.iter().enumerate() {
            if !self.state.broken[l] && self.scratch.link_out[l].distance < 0.5 * link.d0 {
                diagnostics.push(Diagnostic::Interpenetration {
                    link: LinkId(l as u32),
                    particles: [ParticleId(link.i), ParticleId(link.j)],
                    distance: self.scratch.link_out[l].distance,
                    rest_distance: link.d0,
                });
            }
        }
        if let Some(contact) = &self.contact {
            for pair in contact.pairs() {
                let volume = self.model.particles[pair.a as usize]
                    .volume
                    .min(self.model.particles[pair.b as usize].volume);
                if pair.overlap.volume > crate::dem::contact::DEEP_OVERLAP * volume {
                    diagnostics.push(Diagnostic::DeepContact {
                        particles: [ParticleId(pair.a), ParticleId(pair.b)],
                        overlap: pair.overlap.volume,
                        volume,
                    });
                }
            }
        }
        if dt > self.limit.0 {
            diagnostics.push(Diagnostic::DtAboveElasticLimit {
                dt,
                limit: self.limit.0,
                particle: ParticleId(self.limit.1),
            });
        }
        self.state.step += 1;
        self.state.time += dt;
        self.trial_valid = false;
        self.update_wet();
        StepReport {
            step: self.state.step,
            time: self.state.time,
            broken_links,
            diagnostics,
            energies: self.energies(),
            wet_revision: self.state.wet_revision,
        }
    }

    /// Dissipative contact loads at n+1 (positions at n+1, velocities at n+½) replace those at
    /// n; the work of both over the step (trapezoidal) goes to `dissipated`.
    fn update_contact_damping(&mut self) {
        let n = self.n_particles();
        let mut v = std::mem::take(&mut self.kin.1);
        let mut omega = std::mem::take(&mut self.kin.2);
        v.clear();
        omega.clear();
        v.extend(self.particle_trial.iter().map(|pt| pt.v_half));
        omega.extend(self.particle_trial.iter().map(|pt| pt.omega));
        let mut work = 0.0;
        let mut on_driven = 0.0;
        let driven =
            |p: usize| matches!(self.model.particles[p].motion, ParticleMotion::Velocity(_));
        for p in 0..n {
            let w = load_work(&self.state.contact_damping[p], &self.motion[p]);
            work += w;
            if driven(p) {
                on_driven += w;
            }
        }
        let contact = self.contact.as_mut().expect("called with contact");
        contact.damping_loads(
            &self.model,
            self.pool.as_ref(),
            &self.state.x,
            &v,
            &omega,
            &mut self.state.contact_damping,
        );
        for p in 0..n {
            let w = load_work(&self.state.contact_damping[p], &self.motion[p]);
            work += w;
            if driven(p) {
                on_driven += w;
            }
        }
        self.state.dissipated -= 0.5 * work;
        // The dashpots' pull on a driven particle is held by its constraint too.
        self.state.driven_work -= 0.5 * on_driven;
        self.kin.1 = v;
        self.kin.2 = omega;
    }

    /// One whole step with the given external loads (`begin_step`, `trial`, `commit`).
    pub fn step(&mut self, dt: f64, force: &[f64], torque: &[f64]) -> StepReport {
        self.begin_step(dt);
        self.trial(force, torque);
        self.commit()
    }

    /// One whole step without external loads.
    pub fn step_free(&mut self, dt: f64) -> StepReport {
        let n = self.n_particles();
        let dim = self.model.dim;
        let force = vec![0.0; n * dim];
        let torque = vec![0.0; n * if dim == 3 { 3 } else { 1 }];
        self.step(dt, &force, &torque)
    }
}

/// Internal loads of particle `p` plus its dissipative contact loads (none without contact).
fn with_damping(
    damping: &[[[f64; 3]; 2]],
    p: usize,
    force: [f64; 3],
    torque: [f64; 3],
) -> ([f64; 3], [f64; 3]) {
    match damping.get(p) {
        Some([f, t]) => (
            (Vector3::from(force) + Vector3::from(*f)).into(),
            (Vector3::from(torque) + Vector3::from(*t)).into(),
        ),
        None => (force, torque),
    }
}

/// `F·ΔX + τ·Ω Δt` of one particle's loads over the step's motion.
fn load_work(load: &[[f64; 3]; 2], motion: &[[f64; 3]; 2]) -> f64 {
    Vector3::from(load[0]).dot(&Vector3::from(motion[0]))
        + Vector3::from(load[1]).dot(&Vector3::from(motion[1]))
}

/// First half kick and drift of one particle (003 eq. (4)–(7)).
#[allow(clippy::too_many_arguments)]
fn trial_particle(
    model: &Model,
    state: &State,
    p: usize,
    dt: f64,
    f_int: [f64; 3],
    t_int: [f64; 3],
    f_ext: [f64; 3],
    t_ext: [f64; 3],
    gravity: [f64; 3],
) -> ParticleTrial {
    let part = &model.particles[p];
    let x = Vector3::from(state.x[p]);
    match part.motion {
        ParticleMotion::Fixed => {
            return ParticleTrial {
                x: state.x[p],
                rot: state.rot[p],
                ..ParticleTrial::default()
            };
        }
        ParticleMotion::Velocity(v) => {
            return ParticleTrial {
                x: (x + Vector3::from(v) * dt).into(),
                v_half: v,
                rot: state.rot[p],
                ..ParticleTrial::default()
            };
        }
        ParticleMotion::Free => {}
    }
    let f = Vector3::from(f_int) + Vector3::from(f_ext) + Vector3::from(gravity) * part.mass;
    let v_half = Vector3::from(state.v[p]) + f * (0.5 * dt / part.mass);
    let x_new = x + v_half * dt;
    let tau = Vector3::from(t_int) + Vector3::from(t_ext);
    if model.dim == 3 {
        let q = quat(&state.rot[p]);
        let m_half = Vector3::from(state.ang[p]) + q.inverse_transform_vector(&tau) * (0.5 * dt);
        let drift = dmv_drift(&m_half, &part.inertia, dt);
        let q_new = compose(&q, &drift.increment);
        let size = drift.increment.vector().norm().max(1e-300);
        ParticleTrial {
            x: x_new.into(),
            v_half: v_half.into(),
            rot: quat_arr(&q_new),
            ang: drift.momentum.into(),
            omega: (q * drift.mean_omega_body).into(),
            angle: drift.mean_omega_body.norm() * dt,
            residual: if drift.residual <= 1e-13 * size {
                0.0
            } else {
                drift.residual
            },
        }
    } else {
        let w_half = state.ang[p][2] + 0.5 * dt * tau.z / part.inertia[0];
        let theta = state.rot[p][0] + dt * w_half;
        ParticleTrial {
            x: x_new.into(),
            v_half: v_half.into(),
            rot: [theta, 0.0, 0.0, 0.0],
            ang: [0.0, 0.0, w_half],
            omega: [0.0, 0.0, w_half],
            angle: (dt * w_half).abs(),
            residual: 0.0,
        }
    }
}

impl Solid {
    /// Breaks the links `fresh` in the step being committed (positions at n+1 in the state,
    /// at n in `before_step`) and returns the energy they take out of the discrete balance,
    /// leaving the forces at n+1 without them.
    ///
    /// The step's first half kick ran with the links, the second runs without, so the kinetic
    /// energy has received only half the links' trapezoidal work `½ ΔFⁿ·ΔX` (ΔF the load with
    /// minus without them, torques with `Ω Δt`), while the potential loses their whole energy
    /// at n, `ΔUⁿ` (link, volumetric and contact terms evaluated with and without them). Verlet
    /// with the remaining forces closes over the step to O(Δt³), so `ΔUⁿ − ½ ΔFⁿ·ΔX` is what
    /// kinetic + potential loses, to that order; counted as dissipated, the ledger closes. The
    /// sum runs over every particle: a driven particle's share is the part of its constraint's
    /// work (`driven_work`, taken with the loads at n with the links) that the links did.
    /// (Taking `ΔU` at n+1 instead counts energy the kinetic energy never paid: a link
    /// stretched past its limit in one step dissipated its whole `½ k x²` while no force had
    /// acted.)
    fn break_dissipation(&mut self, fresh: &[usize]) -> f64 {
        let potential = |s: &Solid| s.elastic + s.contact.as_ref().map_or(0.0, |c| c.energy());
        std::mem::swap(&mut self.state.x, &mut self.before_step.0);
        std::mem::swap(&mut self.state.rot, &mut self.before_step.1);
        self.update_forces();
        let with = potential(self);
        let (force, torque) = (self.force_int.clone(), self.torque_int.clone());
        for &l in fresh {
            self.state.broken[l] = true;
        }
        self.update_forces();
        let without = potential(self);
        let mut work = 0.0;
        for (p, [dx, w]) in self.motion.iter().enumerate() {
            let df = Vector3::from(force[p]) - Vector3::from(self.force_int[p]);
            let dt = Vector3::from(torque[p]) - Vector3::from(self.torque_int[p]);
            work += df.dot(&Vector3::from(*dx)) + dt.dot(&Vector3::from(*w));
        }
        std::mem::swap(&mut self.state.x, &mut self.before_step.0);
        std::mem::swap(&mut self.state.rot, &mut self.before_step.1);
        self.update_forces();
        with - without - 0.5 * work
    }
}
