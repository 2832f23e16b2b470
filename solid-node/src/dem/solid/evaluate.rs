//! Evaluations at the committed configuration: link and contact forces (cached until the next
//! commit), the contact alone for benchmarks, and the wet surface's topology and geometry.

use nalgebra::Vector3;

use crate::dem::contact::Contact;
use crate::dem::model::ParticleId;
use crate::dem::solid::forces::internal_forces;
use crate::dem::solid::orientation::rotate_body;
use crate::dem::solid::state::Solid;
use crate::dem::wet::{group_slots, write_connectivity, write_geometry};

impl Solid {
    /// Test hook: mutable positions and orientations (internal representation), forces then
    /// recomputed by [`Solid::recompute_for_tests`].
    #[cfg(test)]
    pub(crate) fn pose_mut_for_tests(&mut self) -> (&mut Vec<[f64; 3]>, &mut Vec<[f64; 4]>) {
        (&mut self.state.x, &mut self.state.rot)
    }

    /// Test hook: recomputes forces and energy; returns the elastic energy.
    #[cfg(test)]
    pub(crate) fn recompute_for_tests(&mut self) -> f64 {
        self.recompute_internal_forces()
    }

    /// Evaluates every unbroken link (and, with `[solid.contact]`, every contact) at the
    /// committed configuration again (the step does this itself; exposed for benchmarks and
    /// diagnostics). Returns the elastic energy of the links \[J\].
    pub fn recompute_internal_forces(&mut self) -> f64 {
        self.update_forces();
        self.elastic
    }

    /// Link and contact forces at the committed configuration (cached until the next
    /// commit).
    pub(super) fn update_forces(&mut self) {
        self.elastic = internal_forces(
            &self.model,
            self.pool.as_ref(),
            &self.state.x,
            &self.state.rot,
            &self.state.broken,
            &mut self.scratch,
            &mut self.force_int,
            &mut self.torque_int,
        );
        if let Some(contact) = self.contact.as_mut() {
            let dim = self.model.dim;
            let rot = &self.state.rot;
            let rotate = |p: usize, v: &Vector3<f64>| rotate_body(dim, &rot[p], v);
            contact.add_forces(
                &self.model,
                self.pool.as_ref(),
                &self.state.x,
                &rotate,
                &self.state.broken,
                &mut self.force_int,
                &mut self.torque_int,
            );
        }
        self.forces_valid = true;
    }

    /// The contact model, if `[solid.contact]` is on.
    pub fn contact(&self) -> Option<&Contact> {
        self.contact.as_ref()
    }

    /// Evaluates the contact alone (broad phase, narrow phase, law) at the committed
    /// configuration into scratch buffers, leaving the solid unchanged (for benchmarks).
    /// Returns the pairs the narrow phase examined and those overlapping; `(0, 0)` without
    /// contact.
    pub fn evaluate_contact(&mut self) -> (usize, usize) {
        let Some(contact) = self.contact.as_mut() else {
            return (0, 0);
        };
        let n = self.model.particles.len();
        let (force, torque) = &mut self.bench_loads;
        force.clear();
        force.resize(n, [0.0; 3]);
        torque.clear();
        torque.resize(n, [0.0; 3]);
        let dim = self.model.dim;
        let rot = &self.state.rot;
        let rotate = |p: usize, v: &Vector3<f64>| rotate_body(dim, &rot[p], v);
        contact.add_forces(
            &self.model,
            self.pool.as_ref(),
            &self.state.x,
            &rotate,
            &self.state.broken,
            force,
            torque,
        );
        let pairs = contact.pairs();
        (pairs.len(), pairs.iter().filter(|p| p.energy > 0.0).count())
    }

    /// The wet surface's connectivity after the links broken so far.
    pub(super) fn rebuild_wet_topology(&mut self) {
        group_slots(&self.model, &self.state.broken, &mut self.topo);
        write_connectivity(&self.model, &self.state.broken, &self.topo, &mut self.wet);
        self.wet.revision = self.state.wet_revision;
    }

    /// The wet surface's geometry and velocities at the committed state.
    pub(super) fn update_wet(&mut self) {
        let n = self.n_particles();
        let mut omega = std::mem::take(&mut self.kin.2);
        omega.clear();
        omega.extend((0..n).map(|p| self.angular_velocity(ParticleId(p as u32))));
        let dim = self.model.dim;
        let rot = &self.state.rot;
        let rotate = |p: usize, v: &Vector3<f64>| rotate_body(dim, &rot[p], v);
        write_geometry(
            &self.model,
            &self.topo,
            &self.state.x,
            &rotate,
            &self.state.v,
            &omega,
            &mut self.sums,
            &mut self.wet,
        );
        self.kin.2 = omega;
    }
}
