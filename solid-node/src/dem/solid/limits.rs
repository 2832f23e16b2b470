//! The time-step limits of a [`Solid`]: the stability bound of the explicit scheme (links and
//! contact springs) and the motion bounds of 003 §2.2.

use nalgebra::Vector3;

use crate::dem::model::ParticleId;
use crate::dem::solid::state::Solid;
use crate::dem::stability::elastic_limit;

/// Safety factor applied to the elastic bound in [`Solid::max_dt`].
pub const ELASTIC_SAFETY: f64 = 0.9;

/// Rotation allowed per step (003 §2.2) \[rad\].
pub const MAX_ROTATION: f64 = std::f64::consts::PI / 8.0;

impl Solid {
    /// The stability bound now: links and contact.
    pub(super) fn stability_limit(&self) -> (f64, u32) {
        min_limit(
            elastic_limit(&self.model, &self.state.broken),
            self.contact_limit,
        )
    }

    /// The largest step allowed now \[s\]: `ELASTIC_SAFETY ×` the stability bound (links and,
    /// with `[solid.contact]`, the contact springs: [`Solid::elastic_dt_limit`]), the step that
    /// moves a particle by its size h_s or by `displacement_cap` (the caller's limit, e.g. one
    /// fluid cell), and the step that turns a particle by π/8 (003 §2.2).
    pub fn max_dt(&self, displacement_cap: f64) -> f64 {
        self.motion_dt(displacement_cap).min(self.stable_dt())
    }

    /// The stable step, `ELASTIC_SAFETY ×` the stability bound \[s\]: what a sub-step of
    /// `run.solid_substeps` must stay within.
    pub fn stable_dt(&self) -> f64 {
        ELASTIC_SAFETY * self.limit.0
    }

    /// The motion bounds alone (003 §2.2) \[s\]: the step that moves a particle by its size
    /// or by `displacement_cap`, and the step that turns it by π/8 (∞ at rest). With
    /// sub-steps they bound the coupling step, whose surface the fluid sees at both ends.
    pub fn motion_dt(&self, displacement_cap: f64) -> f64 {
        let mut dt = f64::INFINITY;
        for (i, p) in self.model.particles.iter().enumerate() {
            let speed = Vector3::from(self.state.v[i]).norm();
            if speed > 0.0 {
                dt = dt.min(p.size / speed).min(displacement_cap / speed);
            }
            let w = Vector3::from(self.angular_velocity(ParticleId(i as u32))).norm();
            if w > 0.0 {
                dt = dt.min(MAX_ROTATION / w);
            }
        }
        dt
    }

    /// Stability bound of the explicit scheme \[s\] and the particle that sets it: the links'
    /// (see [`crate::dem::stability`]) and, with contact, the contact springs'
    /// ([`crate::dem::contact::Contact::stability_limit`]).
    pub fn elastic_dt_limit(&self) -> (f64, ParticleId) {
        (self.limit.0, ParticleId(self.limit.1))
    }
}

/// The smaller of two bounds `(dt, particle)` (the first on a tie).
pub(super) fn min_limit(a: (f64, u32), b: (f64, u32)) -> (f64, u32) {
    if b.0 < a.0 { b } else { a }
}
