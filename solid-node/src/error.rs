//! The node's typed errors: why a solid implementation could not be built from its scene
//! ([`BuildError`]) and why a step failed ([`StepError`]). The coupler receives their text
//! (`to_string`) in the protocol's `Failure` message or the launch error, formatted once here.

use crate::dem::{Diagnostic, SetupError};

/// Why the solid implementation a scene names could not be built.
#[derive(Debug, thiserror::Error)]
pub enum BuildError {
    /// The scene has no `[solid]` table.
    #[error("the scene has no [solid] section")]
    NoSolidSection,
    /// `--double prescribed` without `[solid.prescribed]`.
    #[error("the prescribed double needs a [solid.prescribed] table in the scene")]
    NoPrescribedTable,
    /// The implementation name is not known.
    #[error("unknown solid implementation {0:?} (expected real, prescribed or replay:FILE.mcap)")]
    UnknownImplementation(String),
    /// A probe names a particle the solid does not have.
    #[error("probe {name:?}: particle {particle} of {n_particles}")]
    ProbeParticle {
        /// The probe's name.
        name: String,
        /// The particle it names.
        particle: u32,
        /// The solid's particles.
        n_particles: usize,
    },
    /// A probe asks for the particle nearest a point of a solid without particles.
    #[error("no particles to probe")]
    NoParticlesToProbe,
    /// The DEM could not be built from the scene.
    #[error(transparent)]
    Setup(#[from] SetupError),
}

/// Why a step of the solid failed (reported to the coupler, which ends the run).
#[derive(Debug, thiserror::Error)]
pub enum StepError {
    /// The loads received do not fit the solid.
    #[error(
        "step {step}: loads for {n_force} force and {n_torque} torque values, the solid has \
         {n_force_expected} and {n_torque_expected}"
    )]
    LoadsSize {
        /// Coupling step.
        step: u64,
        /// Force values received.
        n_force: usize,
        /// Torque values received.
        n_torque: usize,
        /// Force values the solid takes (`dim` per particle).
        n_force_expected: usize,
        /// Torque values the solid takes (1 or 3 per particle).
        n_torque_expected: usize,
    },
    /// Loads of some particles that do not fit them or the solid.
    #[error("step {step}: loads of some particles: {what}")]
    LoadsOf {
        /// Coupling step.
        step: u64,
        /// What does not fit.
        what: String,
    },
    /// `run.solid_substeps = "auto"` would need more sub-steps than allowed.
    #[error(
        "step {step}: dt {dt:?} s needs {needed} solid sub-steps of at most {bound:?} s (half \
         the stable step set by particle {particle}), more than {max}"
    )]
    TooManySubsteps {
        /// Coupling step.
        step: u64,
        /// Its size \[s\].
        dt: f64,
        /// The solid's stable step \[s\].
        bound: f64,
        /// Sub-steps it would need.
        needed: u64,
        /// Most allowed.
        max: u32,
        /// The particle that sets the bound.
        particle: u32,
    },
    /// The committed step is numerically broken: what went wrong, particle by particle.
    #[error("step {step}: {}", join(.diagnostics))]
    Numerical {
        /// Coupling step.
        step: u64,
        /// What went wrong, in the order the step found it.
        diagnostics: Vec<Diagnostic>,
    },
    /// The prescribed double received loads of the wrong length.
    #[error("loads for {n_force} values, the double has one particle in {dim}-D")]
    DoubleLoadsSize {
        /// Force values received.
        n_force: usize,
        /// The scene's dimension.
        dim: usize,
    },
    /// The prescribed double's motion gave a non-finite position or velocity.
    #[error("particle 0: non-finite position or velocity {value}")]
    DoubleNonFinite {
        /// The first non-finite value.
        value: f64,
    },
}

/// The diagnostics' texts, `; `-separated.
fn join(diagnostics: &[Diagnostic]) -> String {
    let texts: Vec<String> = diagnostics.iter().map(Diagnostic::to_string).collect();
    texts.join("; ")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dem::{LinkId, ParticleId};

    /// The coupler's failure text names the step, each particle or link, and its numbers to
    /// the last bit.
    #[test]
    fn a_numerical_failure_names_step_particles_and_numbers() {
        let err = StepError::Numerical {
            step: 12,
            diagnostics: vec![
                Diagnostic::DisplacementTooLarge {
                    particle: ParticleId(3),
                    displacement: 0.1 + 0.2,
                    size: 0.25,
                },
                Diagnostic::Interpenetration {
                    link: LinkId(7),
                    particles: [ParticleId(3), ParticleId(4)],
                    distance: 1e-7,
                    rest_distance: 0.5,
                },
            ],
        };
        assert_eq!(
            err.to_string(),
            "step 12: particle 3: displacement 0.30000000000000004 m in one step, more than its \
             size 0.25 m; link 7 of particles 3 and 4: interpenetration, centre distance 1e-7 m \
             below half the rest distance 0.5 m"
        );
    }
}
