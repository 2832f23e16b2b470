//! K sub-steps per coupling step (`run.solid_substeps`, docs/subcycling.md).
//!
//! A step of `dt` begun by [`Solid::begin_substeps`] with K > 1 is taken as K whole Verlet +
//! RATTLE steps of `h = dt/K` (each with its forces, fracture, contact dashpots and checks) under
//! the step's external loads, held over all of them. A trial runs the K sub-steps from the
//! step's start state (restored first when an earlier trial of the step moved it), so every
//! trial of the fixed point is a function of its loads alone; the commit accepts the last
//! trial as it stands.
//!
//! What the fluid sees of the step is its ends: the surface at `tⁿ⁺¹`, and as the velocity of
//! the solid flux the step's mean motion, `V̄ = (Xⁿ⁺¹ − Xⁿ)/dt` and `Ω̄ = Σ_k φ_k / dt` (`φ_k` the
//! space-frame rotation vector of sub-step k, the one whose product with the torque is the work
//! the solid books at K = 1). With loads `F`, `τ` held over the step, the work the solid receives
//! over the K sub-steps is `Σ_k F·ΔX_k + τ·φ_k = F·(Xⁿ⁺¹ − Xⁿ) + τ·Σ_k φ_k`, which is what the
//! fluid gives, `dt (F·V̄ + τ·Ω̄)`, to round-off: the solid books it in that form once per
//! step, so that both sides multiply the same numbers.

use nalgebra::Vector3;

use crate::dem::report::{BrokenLink, StepReport};
use crate::dem::solid::orientation::{quat, quat_arr, rotate_body};
use crate::dem::solid::state::{Solid, Trial};
use crate::dem::wet::{write_connectivity, write_geometry};

impl Solid {
    /// Starts the step `tⁿ → tⁿ + dt`, to be taken as `k ≥ 1` sub-steps of `dt/k` under the
    /// loads of each trial (k = 1: [`Solid::begin_step`], the same bits).
    pub fn begin_substeps(&mut self, dt: f64, k: u32) {
        assert!(k >= 1, "begin_substeps needs k >= 1");
        self.begin_step(dt);
        self.substeps.k = k;
        if k > 1 {
            match &mut self.substeps.start {
                Some(start) => start.clone_from(&self.state),
                None => self.substeps.start = Some(self.state.clone()),
            }
            self.substeps.dirty = false;
        }
    }

    /// Sub-steps of the step being computed (1 outside [`Solid::begin_substeps`]).
    pub fn substeps(&self) -> u32 {
        self.substeps.k.max(1)
    }

    /// The trial of a step of K > 1 sub-steps: the K sub-steps from the start state under the
    /// held loads, then the step's trial (end positions, mean velocities, surface at `tⁿ⁺¹`).
    pub(super) fn trial_substeps(&mut self, force: &[f64], torque: &[f64]) -> &Trial {
        let (dt, k) = (self.dt, self.substeps.k);
        if self.substeps.dirty {
            self.restore_start();
        }
        let n = self.n_particles();
        let mut turned = std::mem::take(&mut self.substeps.turned);
        turned.clear();
        turned.resize(n, [0.0; 3]);
        let mut report = StepReport::default();
        self.dt = dt / f64::from(k);
        self.substeps.inner = true;
        for j in 1..=k {
            self.kick_drift(force, torque);
            self.trial_valid = true;
            let sub = self.commit_one();
            for (sum, [_, phi]) in turned.iter_mut().zip(&self.motion) {
                *sum = (Vector3::from(*sum) + Vector3::from(*phi)).into();
            }
            report.broken_links.extend(
                sub.broken_links
                    .into_iter()
                    .map(|b| BrokenLink { substep: j, ..b }),
            );
            report.diagnostics.extend(sub.diagnostics);
        }
        self.substeps.inner = false;
        self.update_wet();
        self.dt = dt;
        self.substeps.dirty = true;
        self.substeps.turned = turned;
        self.substeps.report = report;
        self.book_step_exchange();
        self.write_substeps_trial();
        self.trial_valid = true;
        &self.trial
    }

    /// Accepts the last trial of a step of K > 1 sub-steps: its sub-steps are already committed.
    pub(super) fn commit_substeps(&mut self) -> StepReport {
        assert!(self.trial_valid, "commit needs a trial");
        self.trial_valid = false;
        self.substeps.dirty = false;
        let sub = std::mem::take(&mut self.substeps.report);
        StepReport {
            step: self.state.step,
            time: self.state.time,
            broken_links: sub.broken_links,
            diagnostics: sub.diagnostics,
            energies: self.energies(),
            wet_revision: self.state.wet_revision,
        }
    }

    /// Back to the step's start state (an earlier trial of the step moved the solid), with the
    /// caches a checkpoint restore rebuilds: the same bits as at `begin_substeps`.
    fn restore_start(&mut self) {
        let start = self.substeps.start.as_ref().expect("set by begin_substeps");
        let cracked = start.wet_revision != self.state.wet_revision;
        self.state.clone_from(start);
        if cracked {
            self.limit = self.stability_limit();
            self.rebuild_wet_topology();
        }
        self.update_forces();
    }

    /// The step's count, time, and exchange with the fluid booked once over the whole step: the
    /// held loads' work `F·(Xⁿ⁺¹ − Xⁿ) + τ·Σ_k φ_k` and impulse `F dt` replace the sub-steps' sums
    /// (equal to round-off), so that they are the products the fluid's solid flux forms.
    fn book_step_exchange(&mut self) {
        let dt = self.dt;
        let start = self.substeps.start.as_ref().expect("set by begin_substeps");
        self.state.step = start.step + 1;
        self.state.time = start.time + dt;
        let mut external_work = 0.0;
        let mut impulse = start.external_impulse;
        for p in 0..self.n_particles() {
            let dx = Vector3::from(self.state.x[p]) - Vector3::from(start.x[p]);
            external_work += Vector3::from(self.ext_force[p]).dot(&dx)
                + Vector3::from(self.ext_torque[p]).dot(&Vector3::from(self.substeps.turned[p]));
            for (i, f) in impulse.iter_mut().zip(&self.ext_force[p]) {
                *i += f * dt;
            }
        }
        self.state.external_work = start.external_work + external_work;
        self.state.external_impulse = impulse;
    }

    /// The step's trial from the committed sub-steps: positions and orientations at `tⁿ⁺¹`, the
    /// mean velocities `V̄ = (Xⁿ⁺¹ − Xⁿ)/dt`, `Ω̄ = Σ_k φ_k / dt`, and the wet surface at `tⁿ⁺¹`
    /// (with the links broken in the sub-steps) moving with them.
    fn write_substeps_trial(&mut self) {
        let dim = self.model.dim;
        let dt = self.dt;
        let start = self.substeps.start.as_ref().expect("set by begin_substeps");
        let (xs, vs, ws, rots) = &mut self.kin;
        xs.clone_from(&self.state.x);
        rots.clone_from(&self.state.rot);
        vs.clear();
        ws.clear();
        for (p, x) in self.state.x.iter().enumerate() {
            let x0 = start.x[p];
            vs.push([
                (x[0] - x0[0]) / dt,
                (x[1] - x0[1]) / dt,
                (x[2] - x0[2]) / dt,
            ]);
            let phi = self.substeps.turned[p];
            ws.push([phi[0] / dt, phi[1] / dt, phi[2] / dt]);
        }
        let t = &mut self.trial;
        t.dim = dim;
        t.position.clear();
        t.orientation.clear();
        t.velocity_half.clear();
        t.omega_half.clear();
        for p in 0..xs.len() {
            t.position.extend_from_slice(&xs[p][..dim]);
            t.velocity_half.extend_from_slice(&vs[p][..dim]);
            if dim == 3 {
                let q = quat(&rots[p]) * self.model.particles[p].axes0.inverse();
                t.orientation.extend_from_slice(&quat_arr(&q));
                t.omega_half.extend_from_slice(&ws[p]);
            } else {
                t.orientation.push(rots[p][0]);
                t.omega_half.push(ws[p][2]);
            }
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
}
