//! What a step returns: diagnostics as data (never a panic), broken links, energies, momentum.

use serde::{Deserialize, Serialize};

use crate::dem::contact::DEEP_OVERLAP;
use crate::dem::model::{LinkId, ParticleId};

/// Numerical trouble found at the end of a step (the step is still committed; the caller decides).
///
/// Its text names the particle(s) or link and gives the numbers (floats as `{:?}` prints them,
/// to the last bit).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, thiserror::Error)]
pub enum Diagnostic {
    /// A position, velocity, orientation or momentum is NaN or infinite.
    #[error("particle {}: non-finite {quantity}", particle.0)]
    NonFinite {
        /// The particle.
        particle: ParticleId,
        /// Which quantity (`"position"`, `"velocity"`, `"orientation"`, `"angular momentum"`).
        quantity: String,
    },
    /// The particle moved more than its size h_s in one step (003 §2.2).
    #[error(
        "particle {}: displacement {displacement:?} m in one step, more than its size {size:?} m",
        particle.0
    )]
    DisplacementTooLarge {
        /// The particle.
        particle: ParticleId,
        /// Displacement over the step \[m\].
        displacement: f64,
        /// Its size h_s \[m\].
        size: f64,
    },
    /// The particle turned more than π/8 in one step (003 §2.2).
    #[error(
        "particle {}: rotation {angle:?} rad in one step, more than π/8",
        particle.0
    )]
    RotationTooLarge {
        /// The particle.
        particle: ParticleId,
        /// Rotation angle over the step \[rad\].
        angle: f64,
    },
    /// Two linked particles came closer than half their rest distance (deep interpenetration).
    #[error(
        "link {} of particles {} and {}: interpenetration, centre distance {distance:?} m below \
         half the rest distance {rest_distance:?} m",
        link.0,
        particles[0].0,
        particles[1].0
    )]
    Interpenetration {
        /// The link.
        link: LinkId,
        /// Its particles.
        particles: [ParticleId; 2],
        /// Current centre distance \[m\].
        distance: f64,
        /// Rest distance \[m\].
        rest_distance: f64,
    },
    /// The step exceeds the elastic stability bound of the explicit scheme.
    #[error(
        "dt {dt:?} s above the stability bound {limit:?} s set by particle {}",
        particle.0
    )]
    DtAboveElasticLimit {
        /// Step used \[s\].
        dt: f64,
        /// Bound \[s\] (see [`crate::dem::Solid::elastic_dt_limit`]).
        limit: f64,
        /// The particle whose stiffness sets the bound.
        particle: ParticleId,
    },
    /// Two particles in contact overlap by more than
    /// [`crate::dem::contact::DEEP_OVERLAP`] of the smaller one's volume (a step too long for
    /// the pair's approach: deeper than [`crate::dem::contact::hold::HOLD_OVERLAP`] the pair
    /// holds).
    #[error(
        "particles {} and {}: deep contact, overlap {overlap:?} above {} of the smaller one's \
         volume {volume:?}",
        particles[0].0,
        particles[1].0,
        DEEP_OVERLAP
    )]
    DeepContact {
        /// The particles.
        particles: [ParticleId; 2],
        /// Overlap volume \[m³\] (2-D: area).
        overlap: f64,
        /// Volume of the smaller particle \[m³\] (2-D: area).
        volume: f64,
    },
    /// The RATTLE fixed point did not converge.
    #[error(
        "particle {}: the RATTLE fixed point did not converge, last correction {residual:?}",
        particle.0
    )]
    RattleNotConverged {
        /// The particle.
        particle: ParticleId,
        /// Last correction of the fixed point.
        residual: f64,
    },
}

/// A link broken during a step.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BrokenLink {
    /// The link.
    pub link: LinkId,
    /// Its particles.
    pub particles: [ParticleId; 2],
    /// Relative elongation `(|X_I − X_J| − D⁰)/D⁰` when it broke \[-\].
    pub elongation: f64,
    /// Time at which it broke: the end of the (sub-)step whose commit found it stretched \[s\].
    pub time: f64,
    /// The sub-step (1 to K) of its coupling step at whose end it broke: 1 without sub-steps
    /// (`Solid::begin_substeps`).
    pub substep: u32,
}

/// Energies of the solid \[J\] (2-D: per unit depth).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Energies {
    /// `Σ ½ m |V|²`.
    pub kinetic_translation: f64,
    /// `Σ ½ ω·I ω`.
    pub kinetic_rotation: f64,
    /// Elastic energy of the unbroken links (potential of eq. (29)–(30)).
    pub elastic: f64,
    /// Contact potential `Σ ½ κ V²` of the overlapping pairs (0 without contact).
    pub contact: f64,
    /// Elastic energy released by broken links and work of the contact dashpots and friction,
    /// counted as dissipated.
    pub dissipated: f64,
    /// Potential of gravity `−Σ m g·X` (free particles).
    pub gravity: f64,
    /// Work of the external loads so far, `Σ F·ΔX + τ·Δθ` with the loads held over each step.
    pub external_work: f64,
    /// Work the prescribed motions (`motion = { velocity }`) did so far: minus the work of every
    /// load on the driven particles (external, internal and contact, trapezoidal over each
    /// step), which their constraint cancels to hold the velocity.
    pub driven_work: f64,
}

impl Energies {
    /// Kinetic + elastic + contact + dissipated + gravity potential, less the work of the
    /// prescribed motions (conserved without external loads).
    pub fn total(&self) -> f64 {
        self.kinetic_translation
            + self.kinetic_rotation
            + self.elastic
            + self.contact
            + self.dissipated
            + self.gravity
            - self.driven_work
    }
}

/// Linear and angular momentum of the solid.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Momentum {
    /// `Σ m V` \[kg m/s\] (2-D: z = 0).
    pub linear: [f64; 3],
    /// `Σ X × m V + Q I ω` about the origin \[kg m²/s\] (2-D: only z).
    pub angular: [f64; 3],
}

/// Result of [`crate::dem::Solid::commit`].
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StepReport {
    /// Steps committed so far (this one included).
    pub step: u64,
    /// Simulated time after the step \[s\].
    pub time: f64,
    /// Links broken in this step.
    pub broken_links: Vec<BrokenLink>,
    /// Trouble found, empty when all is well.
    pub diagnostics: Vec<Diagnostic>,
    /// Energies after the step.
    pub energies: Energies,
    /// Wet-surface revision after the step.
    pub wet_revision: u64,
}
