//! What the coupler takes from the scene.

use protocol::scene::{Predictor, RecordLevel, Relaxation, Scene, SchemeName, SolidSubsteps};
use protocol::wire::{NodeKind, Scheme};

/// What the coupler needs from the scene.
#[derive(Clone, Debug, PartialEq)]
pub struct CouplerConfig {
    /// A fluid node takes part.
    pub fluid: bool,
    /// A solid node takes part.
    pub solid: bool,
    /// Coupling scheme (explicit when one side is absent).
    pub scheme: Scheme,
    /// Fixed-point tolerance ε of criterion (22) \[m\].
    pub tolerance: f64,
    /// Fixed-point iterations allowed per step.
    pub max_iterations: u32,
    /// Relaxation of the solid trial states.
    pub relaxation: Relaxation,
    /// First relaxation factor of Aitken and IQN-ILS.
    pub relaxation_initial: f64,
    /// IQN-ILS: earlier steps whose columns are reused.
    pub iqn_reuse: u32,
    /// IQN-ILS: QR2 filter limit.
    pub iqn_filter: f64,
    /// Predictor of a semi-implicit step's first inputs.
    pub predictor: Predictor,
    /// Steps between checkpoints (0: none).
    pub checkpoint_every: u64,
    /// Scene cap on the step \[s\].
    pub dt_cap: Option<f64>,
    /// Output times, increasing, the last one is `t_end`.
    pub outputs: Vec<f64>,
    /// Optional cap on the number of steps.
    pub max_steps: Option<u64>,
    /// Hash of the resolved scene the nodes must have read.
    pub scene_hash: u64,
    /// Largest relative mass error accepted.
    pub mass_tolerance: f64,
    /// Largest relative energy error accepted, if checked.
    pub energy_tolerance: Option<f64>,
    /// `run.solid_substeps` of a solid that sub-steps (real, or the replay of one; not the
    /// prescribed double): the solid then proposes its stable step as a second proposal, and
    /// the coupler agrees on K with it (`None`: one proposal, K = 1).
    pub substeps: Option<SolidSubsteps>,
}

impl CouplerConfig {
    /// The coupler's view of a validated scene.
    pub fn from_scene(scene: &Scene) -> CouplerConfig {
        let both = scene.fluid.is_some() && scene.solid.is_some();
        CouplerConfig {
            fluid: scene.fluid.is_some(),
            solid: scene.solid.is_some(),
            scheme: match scene.run.scheme {
                SchemeName::SemiImplicit if both => Scheme::SemiImplicit,
                _ => Scheme::Explicit,
            },
            tolerance: scene.run.tolerance,
            max_iterations: scene.run.max_iterations,
            relaxation: scene.run.relaxation,
            relaxation_initial: scene.run.relaxation_initial,
            iqn_reuse: scene.run.iqn_reuse,
            iqn_filter: scene.run.iqn_filter,
            predictor: scene.run.predictor,
            checkpoint_every: match scene.run.record {
                RecordLevel::All => 1,
                _ => scene.run.checkpoint_every,
            },
            dt_cap: scene.run.dt_max,
            outputs: scene.output_times(),
            max_steps: scene.run.max_steps,
            scene_hash: scene.hash(),
            mass_tolerance: scene.run.mass_tolerance,
            energy_tolerance: scene.run.energy_tolerance,
            substeps: scene
                .solid
                .as_ref()
                .filter(|s| s.node != "prescribed")
                .and(scene.run.solid_substeps),
        }
    }

    pub(super) fn nodes(&self) -> Vec<NodeKind> {
        let mut nodes = Vec::new();
        if self.fluid {
            nodes.push(NodeKind::Fluid);
        }
        if self.solid {
            nodes.push(NodeKind::Solid);
        }
        nodes
    }
}
