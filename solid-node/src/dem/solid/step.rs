//! The splittable step: `begin_step`, repeatable `trial` (003 eq. (4)–(7), loads held over the
//! step as in eq. (14)–(17)), the per-particle kick–drift kernel, and whole steps; the commit
//! is in `commit.rs`.

use nalgebra::Vector3;

use crate::dem::contact::hold::{Kinematics, PairHold, project};
use crate::dem::model::{Model, ParticleMotion, to3};
use crate::dem::parallel::par_fill;
use crate::dem::rattle::{compose, dmv_drift};
use crate::dem::report::StepReport;
use crate::dem::solid::orientation::{quat, quat_arr, rotate_body};
use crate::dem::solid::state::{ParticleTrial, Solid, State, Trial};
use crate::dem::walls::{Held, Walls};
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
        self.substeps.k = 1;
        self.trial_valid = false;
    }

    /// Trial positions and velocities for external loads `force` (`dim` per particle, \[N\]) and
    /// `torque` (1 per particle in 2-D, 3 in 3-D, space frame, about the centre \[N m\]), held
    /// fixed over the step. May be called repeatedly; nothing is committed.
    ///
    /// With [`Solid::begin_substeps`] of K > 1, the trial is K whole sub-steps from the step's
    /// start state (`substep.rs`).
    pub fn trial(&mut self, force: &[f64], torque: &[f64]) -> &Trial {
        assert!(self.dt > 0.0, "begin_step must precede trial");
        if self.substeps.k > 1 {
            return self.trial_substeps(force, torque);
        }
        self.kick_drift(force, torque);
        self.write_trial();
        self.trial_valid = true;
        &self.trial
    }

    /// The loads held over the (sub-)step and every particle's first half kick and drift.
    pub(super) fn kick_drift(&mut self, force: &[f64], torque: &[f64]) {
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
        let walls = &self.walls;
        let holds = self
            .contact
            .as_ref()
            .map_or_else(Vec::new, |c| c.holds(model));
        if holds.is_empty() {
            par_fill(self.pool.as_ref(), &mut self.particle_trial, |p| {
                let (f, t) = with_damping(damping, p, fi[p], ti[p]);
                trial_particle(model, state, walls, p, dt, (f, t), (fe[p], te[p]), g)
            });
            return;
        }
        // Pairs past the hold depth (`contact::hold`): every kick first, then the pairs' and
        // the walls' projections, then the drifts.
        let mut kicks: Vec<Kick> = (0..model.particles.len())
            .map(|p| {
                let (f, t) = with_damping(damping, p, fi[p], ti[p]);
                kick_particle(model, state, walls, p, dt, (f, t), (fe[p], te[p]), g)
            })
            .collect();
        let (mut v, mut ang): (Vec<Vector3<f64>>, Vec<Vector3<f64>>) = kicks
            .iter()
            .map(|k| match k {
                Kick::Free(k) => (k.v_half, k.ang_half),
                Kick::Done(_) => (Vector3::zeros(), Vector3::zeros()),
            })
            .unzip();
        let touched = hold_pairs(model, walls, state, &holds, &mut v, &mut ang);
        for (p, k) in kicks.iter_mut().enumerate() {
            if let Kick::Free(k) = k {
                k.v_half = v[p];
                k.ang_half = ang[p];
                k.held |= touched[p];
            }
        }
        for (p, k) in kicks.into_iter().enumerate() {
            self.particle_trial[p] = match k {
                Kick::Free(k) => drift_particle(model, state, p, dt, k),
                Kick::Done(done) => done,
            };
        }
    }

    /// Flat views of the particles' trial and the wet surface at the trial configuration.
    fn write_trial(&mut self) {
        let dim = self.model.dim;
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
pub(super) fn with_damping(
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

/// A free particle's first half kick (walls applied), before its drift.
#[derive(Clone, Copy, Debug)]
pub(super) struct Kicked {
    v_half: Vector3<f64>,
    /// In the state's convention (3-D body-frame angular momentum, 2-D `[0, 0, ω]`).
    ang_half: Vector3<f64>,
    held: bool,
    load: [[f64; 3]; 2],
}

/// First half kick and drift of one particle (003 eq. (4)–(7)).
/// The walls act on the half-step velocities at `Xⁿ` ([`Walls::hold`]).
#[allow(clippy::too_many_arguments)]
fn trial_particle(
    model: &Model,
    state: &State,
    walls: &Walls,
    p: usize,
    dt: f64,
    internal: ([f64; 3], [f64; 3]),
    external: ([f64; 3], [f64; 3]),
    gravity: [f64; 3],
) -> ParticleTrial {
    match kick_particle(model, state, walls, p, dt, internal, external, gravity) {
        Kick::Free(kicked) => drift_particle(model, state, p, dt, kicked),
        Kick::Done(done) => done,
    }
}

/// A particle's first half kick: a free particle's velocities, or a fixed or driven particle's
/// whole trial.
pub(super) enum Kick {
    Free(Kicked),
    Done(ParticleTrial),
}

/// The first half kick of particle `p` with the walls' hold.
#[allow(clippy::too_many_arguments)]
fn kick_particle(
    model: &Model,
    state: &State,
    walls: &Walls,
    p: usize,
    dt: f64,
    (f_int, t_int): ([f64; 3], [f64; 3]),
    (f_ext, t_ext): ([f64; 3], [f64; 3]),
    gravity: [f64; 3],
) -> Kick {
    let part = &model.particles[p];
    let x = Vector3::from(state.x[p]);
    match part.motion {
        ParticleMotion::Fixed => {
            return Kick::Done(ParticleTrial {
                x: state.x[p],
                rot: state.rot[p],
                ..ParticleTrial::default()
            });
        }
        ParticleMotion::Velocity(v) => {
            return Kick::Done(ParticleTrial {
                x: (x + Vector3::from(v) * dt).into(),
                v_half: v,
                rot: state.rot[p],
                ..ParticleTrial::default()
            });
        }
        ParticleMotion::Free => {}
    }
    let f = Vector3::from(f_int) + Vector3::from(f_ext) + Vector3::from(gravity) * part.mass;
    let mut v_half = Vector3::from(state.v[p]) + f * (0.5 * dt / part.mass);
    let tau = Vector3::from(t_int) + Vector3::from(t_ext);
    let mut ang_half = if model.dim == 3 {
        let q = quat(&state.rot[p]);
        Vector3::from(state.ang[p]) + q.inverse_transform_vector(&tau) * (0.5 * dt)
    } else {
        Vector3::new(
            0.0,
            0.0,
            state.ang[p][2] + 0.5 * dt * tau.z / part.inertia[0],
        )
    };
    let mut held = false;
    if let Some(h) = hold(model, walls, p, &x, &state.rot[p], (v_half, ang_half)) {
        (v_half, ang_half, held) = (h.v, h.ang, true);
    }
    Kick::Free(Kicked {
        v_half,
        ang_half,
        held,
        load: [f.into(), tau.into()],
    })
}

/// The drift of a free particle from its kicked velocities.
fn drift_particle(model: &Model, state: &State, p: usize, dt: f64, k: Kicked) -> ParticleTrial {
    let part = &model.particles[p];
    let x = Vector3::from(state.x[p]);
    let Kicked {
        v_half,
        ang_half,
        held,
        load,
    } = k;
    let x_new = x + v_half * dt;
    if model.dim == 3 {
        let q = quat(&state.rot[p]);
        let m_half = ang_half;
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
            held,
            load,
        }
    } else {
        let w_half = ang_half.z;
        let theta = state.rot[p][0] + dt * w_half;
        ParticleTrial {
            x: x_new.into(),
            v_half: v_half.into(),
            rot: [theta, 0.0, 0.0, 0.0],
            ang: [0.0, 0.0, w_half],
            omega: [0.0, 0.0, w_half],
            angle: (dt * w_half).abs(),
            residual: 0.0,
            held,
            load,
        }
    }
}

/// Projects the velocities `v`, `ang` (state convention) at the configuration of `state` so
/// that no pair of `holds` approaches and no particle goes further into a wall: the pairs'
/// projection ([`crate::dem::contact::hold::project`]), then the walls' on the particles it
/// changed, until the walls change nothing (at most [`HOLD_ROUNDS`] rounds). Returns which
/// particles changed.
pub(super) fn hold_pairs(
    model: &Model,
    walls: &Walls,
    state: &State,
    holds: &[PairHold],
    v: &mut [Vector3<f64>],
    ang: &mut [Vector3<f64>],
) -> Vec<bool> {
    let dim = model.dim;
    let turn = |p: usize, r: &Vector3<f64>| rotate_body(dim, &state.rot[p], r);
    let to_body = |p: usize, r: &Vector3<f64>| {
        if dim == 3 {
            quat(&state.rot[p]).inverse_transform_vector(r)
        } else {
            *r
        }
    };
    let kin = Kinematics {
        dim,
        x: &state.x,
        turn: &turn,
        to_body: &to_body,
    };
    let mut touched = vec![false; model.particles.len()];
    for _ in 0..HOLD_ROUNDS {
        let mut moved = vec![false; model.particles.len()];
        project(model, &kin, holds, v, ang, &mut moved);
        let mut walls_acted = false;
        for p in 0..moved.len() {
            if !moved[p] {
                continue;
            }
            touched[p] = true;
            let x = Vector3::from(state.x[p]);
            if let Some(h) = hold(model, walls, p, &x, &state.rot[p], (v[p], ang[p])) {
                (v[p], ang[p]) = (h.v, h.ang);
                walls_acted = true;
            }
        }
        if !walls_acted {
            break;
        }
    }
    touched
}

/// Rounds of the pairs' and the walls' projections at most ([`hold_pairs`]).
const HOLD_ROUNDS: usize = 20;

/// [`Walls::hold`] for particle `p` at centre `x` and stored orientation `rot`, velocities
/// `(v, ang)` in the state's convention.
pub(super) fn hold(
    model: &Model,
    walls: &Walls,
    p: usize,
    x: &Vector3<f64>,
    rot: &[f64; 4],
    (v, ang): (Vector3<f64>, Vector3<f64>),
) -> Option<Held> {
    if walls.is_empty() {
        return None;
    }
    let part = &model.particles[p];
    let dim = model.dim;
    let q = quat(rot);
    let turn = |r: &Vector3<f64>| rotate_body(dim, rot, r);
    let to_body = |n: &Vector3<f64>| q.inverse_transform_vector(n);
    walls.hold(
        dim,
        p,
        x,
        &turn,
        &to_body,
        (part.mass, part.inertia, part.size),
        (v, ang),
    )
}
