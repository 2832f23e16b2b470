//! The commit of a step: the trial's positions accepted, forces at n+1, fracture, the work of
//! the driven particles and of the contact dashpots, the second half kick and the chokepoint
//! checks (003 eq. (8)–(11)).

use nalgebra::Vector3;

use crate::dem::contact::DEEP_OVERLAP;
use crate::dem::model::{LinkId, ParticleId, ParticleMotion};
use crate::dem::report::{BrokenLink, Diagnostic, StepReport};
use crate::dem::solid::limits::MAX_ROTATION;
use crate::dem::solid::orientation::quat;
use crate::dem::solid::state::Solid;
use crate::dem::solid::step::{hold, hold_pairs, with_damping};

impl Solid {
    /// Accepts the last trial: positions at n+1, internal forces at n+1, fracture, second half
    /// kick, diagnostics, wet surface at n+1.
    ///
    /// With K > 1 sub-steps the last trial already committed its sub-steps: the step is
    /// accepted as it stands (`substep.rs`).
    pub fn commit(&mut self) -> StepReport {
        if self.substeps.k > 1 {
            return self.commit_substeps();
        }
        self.commit_one()
    }

    /// Commits the last trial of one (sub-)step of `self.dt`.
    pub(super) fn commit_one(&mut self) -> StepReport {
        assert!(self.trial_valid, "commit needs a trial");
        let dt = self.dt;
        let mut diagnostics = Vec::new();
        if self.elongation_at_break.is_some() {
            self.before_step.0.clone_from(&self.state.x);
            self.before_step.1.clone_from(&self.state.rot);
        }
        // Internal loads at n on the driven particles (for the work of their constraints).
        let driven: Vec<(usize, Vector3<f64>)> = (0..self.n_particles())
            .filter(|&p| matches!(self.model.particles[p].motion, ParticleMotion::Velocity(_)))
            .map(|p| (p, Vector3::from(self.force_int[p])))
            .collect();
        self.accept_trial_positions(&mut diagnostics);
        self.update_forces();
        let broken_links = self.break_overstretched_links();
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
        self.second_half_kick();
        self.check_chokepoints(&mut diagnostics);
        self.state.step += 1;
        self.state.time += dt;
        self.trial_valid = false;
        // Inside a trial of sub-steps only the last sub-step's surface is kept (`substep.rs`).
        if !self.substeps.inner {
            self.update_wet();
        }
        StepReport {
            step: self.state.step,
            time: self.state.time,
            broken_links,
            diagnostics,
            energies: self.energies(),
            wet_revision: self.state.wet_revision,
        }
    }

    /// Moves every particle to its trial position and orientation at n+1, recording its motion
    /// `[ΔX, Ω Δt]`, the external loads' work and impulse, and the motion bounds of 003 §2.2
    /// and the RATTLE residual it breaks.
    fn accept_trial_positions(&mut self, diagnostics: &mut Vec<Diagnostic>) {
        let dt = self.dt;
        let mut external_work = 0.0;
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
    }

    /// 000 §3.1: breaks the unbroken links stretched past the elongation at break at n+1 (none
    /// without fracture), with the energy they take out counted as dissipated, and returns them.
    fn break_overstretched_links(&mut self) -> Vec<BrokenLink> {
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
                        time: self.state.time + self.dt,
                        substep: 1,
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
        broken_links
    }

    /// Second half kick of every free particle with the loads at n+1 (a fixed or driven particle
    /// keeps its prescribed velocity and no spin), the walls' hold, and the pairs' past the
    /// hold depth (`contact::hold`, at the configuration n+1).
    fn second_half_kick(&mut self) {
        let dt = self.dt;
        let dim = self.model.dim;
        let n = self.n_particles();
        // Per free particle: velocities at n+1, whether the walls acted, and the kick's loads.
        let mut ends: Vec<Option<End>> = Vec::with_capacity(n);
        for (p, part) in self.model.particles.iter().enumerate() {
            let pt = &self.particle_trial[p];
            match part.motion {
                ParticleMotion::Free => {}
                ParticleMotion::Fixed | ParticleMotion::Velocity(_) => {
                    self.state.v[p] = pt.v_half;
                    self.state.ang[p] = [0.0; 3];
                    ends.push(None);
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
            let mut v = Vector3::from(pt.v_half) + f * (0.5 * dt / part.mass);
            let tau = Vector3::from(t_int) + Vector3::from(self.ext_torque[p]);
            let mut ang = if dim == 3 {
                let tau_body = quat(&self.state.rot[p]).inverse_transform_vector(&tau);
                Vector3::from(pt.ang) + tau_body * (0.5 * dt)
            } else {
                Vector3::new(0.0, 0.0, pt.ang[2] + 0.5 * dt * tau.z / part.inertia[0])
            };
            let x = Vector3::from(self.state.x[p]);
            let mut held = pt.held;
            if let Some(h) = hold(
                &self.model,
                &self.walls,
                p,
                &x,
                &self.state.rot[p],
                (v, ang),
            ) {
                (v, ang, held) = (h.v, h.ang, true);
            }
            ends.push(Some((v, ang, held, [f, tau])));
        }
        let holds = self
            .contact
            .as_ref()
            .map_or_else(Vec::new, |c| c.holds(&self.model));
        if !holds.is_empty() {
            let zero = Vector3::zeros();
            let (mut v, mut ang): (Vec<Vector3<f64>>, Vec<Vector3<f64>>) = ends
                .iter()
                .map(|e| e.map_or((zero, zero), |e| (e.0, e.1)))
                .unzip();
            let touched = hold_pairs(
                &self.model,
                &self.walls,
                &self.state,
                &holds,
                &mut v,
                &mut ang,
            );
            for (p, e) in ends.iter_mut().enumerate() {
                if let Some(e) = e {
                    (e.0, e.1) = (v[p], ang[p]);
                    e.2 |= touched[p];
                }
            }
        }
        for (p, end) in ends.into_iter().enumerate() {
            let Some((v, ang, held, loads)) = end else {
                continue;
            };
            if held {
                self.state.dissipated += self.wall_loss(p, dt, (v, ang, loads));
            }
            self.state.v[p] = v.into();
            self.state.ang[p] = ang.into();
        }
    }

    /// The kinetic energy the walls took from particle `p` over the step \[J\], from its
    /// velocities at n (the state) and n+1 (`end`, with the second kick's force and torque):
    /// what Verlet's identity gives for the loads without the walls,
    /// `½ (F₁ + F₂)·ΔX + Δt²/(8m) (|F₂|² − |F₁|²)`, and the same for rotation, less the change
    /// of kinetic energy. Zero for a body held at rest; `½ m v²` for one stopped dead.
    /// (3-D rotation by DMV splitting has no such identity: its term is the trapezoid alone.)
    fn wall_loss(
        &self,
        p: usize,
        dt: f64,
        (v, ang, [f2, tau2]): (Vector3<f64>, Vector3<f64>, [Vector3<f64>; 2]),
    ) -> f64 {
        let part = &self.model.particles[p];
        let pt = &self.particle_trial[p];
        let (f1, tau1) = (Vector3::from(pt.load[0]), Vector3::from(pt.load[1]));
        let [dx, w] = self.motion[p].map(Vector3::from);
        let (m, inertia) = (part.mass, part.inertia);
        let v0 = Vector3::from(self.state.v[p]);
        let a0 = Vector3::from(self.state.ang[p]);
        let mut expected = 0.5 * (f1 + f2).dot(&dx)
            + dt * dt / (8.0 * m) * (f2.norm_squared() - f1.norm_squared())
            + 0.5 * (tau1 + tau2).dot(&w);
        let kinetic = |v: &Vector3<f64>, a: &Vector3<f64>| {
            let rot = if self.model.dim == 3 {
                (0..3).map(|k| a[k] * a[k] / inertia[k]).sum::<f64>()
            } else {
                inertia[0] * a.z * a.z
            };
            0.5 * (m * v.norm_squared() + rot)
        };
        if self.model.dim == 2 {
            expected += dt * dt / (8.0 * inertia[0]) * (tau2.z * tau2.z - tau1.z * tau1.z);
        }
        expected - (kinetic(&v, &ang) - kinetic(&v0, &a0))
    }

    /// Chokepoint checks at n+1: non-finite state, interpenetrating links, deep contacts, a
    /// step above the stability bound.
    fn check_chokepoints(&self, diagnostics: &mut Vec<Diagnostic>) {
        let dt = self.dt;
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
                if pair.overlap.volume > DEEP_OVERLAP * volume {
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

/// `F·ΔX + τ·Ω Δt` of one particle's loads over the step's motion.
fn load_work(load: &[[f64; 3]; 2], motion: &[[f64; 3]; 2]) -> f64 {
    Vector3::from(load[0]).dot(&Vector3::from(motion[0]))
        + Vector3::from(load[1]).dot(&Vector3::from(motion[1]))
}

/// A free particle at the end of its second half kick: velocity, angular velocity in the
/// state's convention, whether the walls or holds acted, and the kick's force and torque.
type End = (Vector3<f64>, Vector3<f64>, bool, [Vector3<f64>; 2]);
