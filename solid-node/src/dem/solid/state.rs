//! What a [`Solid`] holds: the checkpointed dynamic state ([`State`]), the trial of the step
//! being computed ([`Trial`], [`ParticleTrial`]) and the caches and scratch recomputed from
//! them.

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::dem::contact::Contact;
use crate::dem::model::Model;
use crate::dem::solid::forces::ForceScratch;
use crate::dem::walls::Walls;
use crate::dem::wet::{WetSurfaceData, WetTopology};

/// Serializable dynamic state (the checkpoint).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(super) struct State {
    pub(super) n_particles: u64,
    pub(super) n_links: u64,
    pub(super) step: u64,
    pub(super) time: f64,
    pub(super) x: Vec<[f64; 3]>,
    pub(super) v: Vec<[f64; 3]>,
    /// 3-D: quaternion (w, x, y, z) of the principal frame; 2-D: `\[θ, 0, 0, 0\]`.
    pub(super) rot: Vec<[f64; 4]>,
    /// 3-D: body angular momentum `I ω`; 2-D: `\[0, 0, ω\]`.
    pub(super) ang: Vec<[f64; 3]>,
    pub(super) broken: Vec<bool>,
    pub(super) dissipated: f64,
    pub(super) external_work: f64,
    /// Work the prescribed motions did on the solid so far \[J\]: what their constraints put in
    /// to hold the motion against the loads, internal and external, on the driven particles.
    pub(super) driven_work: f64,
    /// Impulse of the external loads so far, `Σ F Δt` over all particles (fixed ones too).
    pub(super) external_impulse: [f64; 3],
    pub(super) wet_revision: u64,
    /// Dissipative contact loads `[force, torque]` per particle at n (empty without contact).
    pub(super) contact_damping: Vec<[[f64; 3]; 2]>,
}

/// One particle's share of a trial.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct ParticleTrial {
    pub(super) x: [f64; 3],
    pub(super) v_half: [f64; 3],
    pub(super) rot: [f64; 4],
    /// 3-D: `m⁻ = Ωᵀ m½`; 2-D: `\[0, 0, ω½\]`.
    pub(super) ang: [f64; 3],
    /// Mean angular velocity over the step, space frame.
    pub(super) omega: [f64; 3],
    pub(super) angle: f64,
    pub(super) residual: f64,
    /// The walls acted at the first half kick ([`crate::dem::walls`]); then `load` holds that
    /// kick's force and torque (space frame), for the energy they took (`commit.rs`).
    pub(super) held: bool,
    pub(super) load: [[f64; 3]; 2],
}

/// Positions and velocities of a trial step (not yet committed).
#[derive(Clone, Debug, Default)]
pub struct Trial {
    /// Spatial dimension.
    pub dim: usize,
    /// Centres `X^{n+1}` \[m\], `dim` each.
    pub position: Vec<f64>,
    /// Orientation at n+1 relative to t = 0: 2-D the angle \[rad\], 3-D the unit quaternion
    /// `(w, x, y, z)` of `Q^{n+1}` (identity at t = 0).
    pub orientation: Vec<f64>,
    /// `V^{n+1/2}` \[m/s\], `dim` each.
    pub velocity_half: Vec<f64>,
    /// Mean angular velocity `Ω^{n+1/2}` over the step, space frame \[rad/s\] (2-D: 1 each).
    pub omega_half: Vec<f64>,
    /// Wet surface at n+1; element velocities are `V^{n+1/2} + Ω^{n+1/2} × (x − X^{n+1})`.
    pub wet: WetSurfaceData,
}

/// The discrete-element solid.
///
/// ```
/// use protocol::scene::Scene;
/// use solid_node::dem::Solid;
/// let scene = Scene::from_toml_str(r#"
///     name = "bar"
///     [solid]
///     density = 1000.0
///     young = 1e6
///     poisson = 0.0
///     [[solid.bodies]]
///     shape = { box = { center = [0.0, 0.0], size = [0.4, 0.1] } }
///     divisions = [4, 1]
/// "#, "doc").unwrap();
/// let mut solid = Solid::from_scene(scene.solid.as_ref().unwrap(), 2, 1).unwrap();
/// let dt = solid.max_dt(f64::INFINITY);
/// solid.begin_step(dt);
/// let n = solid.n_particles();
/// solid.trial(&vec![0.0; 2 * n], &vec![0.0; n]);
/// let report = solid.commit();
/// assert!(report.diagnostics.is_empty());
/// ```
pub struct Solid {
    pub(super) model: Model,
    pub(super) gravity: [f64; 3],
    pub(super) elongation_at_break: Option<f64>,
    pub(super) pool: Option<rayon::ThreadPool>,
    pub(super) state: State,
    // Scratch and caches (not in the checkpoint; recomputed from the state).
    pub(super) scratch: ForceScratch,
    pub(super) force_int: Vec<[f64; 3]>,
    pub(super) torque_int: Vec<[f64; 3]>,
    pub(super) elastic: f64,
    pub(super) forces_valid: bool,
    pub(super) dt: f64,
    pub(super) ext_force: Vec<[f64; 3]>,
    pub(super) ext_torque: Vec<[f64; 3]>,
    pub(super) particle_trial: Vec<ParticleTrial>,
    pub(super) trial: Trial,
    pub(super) trial_valid: bool,
    pub(super) topo: WetTopology,
    pub(super) wet: WetSurfaceData,
    pub(super) sums: Vec<(Vector3<f64>, u32)>,
    /// Reused per-particle buffers for the wet-surface geometry (x, v, ω, orientation).
    pub(super) kin: KinematicsScratch,
    pub(super) limit: (f64, u32),
    /// Contact model (absent: `[solid.contact]` absent, nothing computed).
    pub(super) contact: Option<Contact>,
    /// Stability bound of the contact springs (∞ without contact).
    pub(super) contact_limit: (f64, u32),
    /// Per particle `[ΔX, Ω Δt]` of the step being committed.
    pub(super) motion: Vec<[[f64; 3]; 2]>,
    /// Output of [`Solid::evaluate_contact`].
    pub(super) bench_loads: (Vec<[f64; 3]>, Vec<[f64; 3]>),
    /// Centres and orientations at n of the step being committed (with fracture only: the
    /// energy a breaking link takes is evaluated there, [`Solid::break_dissipation`]).
    pub(super) before_step: (Vec<[f64; 3]>, Vec<[f64; 4]>),
    /// The sub-steps of the step being computed (K = 1: none; `substep.rs`).
    pub(super) substeps: Substeps,
    /// The fluid domain's walls, where they hold the solid (none: [`Solid::set_walls`]).
    pub(super) walls: Walls,
}

/// The sub-steps of one coupling step (`Solid::begin_substeps`).
#[derive(Clone, Debug, Default)]
pub(super) struct Substeps {
    /// Sub-steps per step (0 or 1: the step is one Verlet + RATTLE step).
    pub(super) k: u32,
    /// The state at the start of the step: every trial starts from it.
    pub(super) start: Option<State>,
    /// The state has moved since `start` (a trial ran): the next trial restores it first.
    pub(super) dirty: bool,
    /// A trial's sub-steps are being committed: the committed wet surface waits for the last.
    pub(super) inner: bool,
    /// Per particle, the sum of the sub-steps' rotation vectors `Σ Ω_k h` (space frame).
    pub(super) turned: Vec<[f64; 3]>,
    /// Links broken and trouble found in the last trial's sub-steps (reported by the commit).
    pub(super) report: crate::dem::report::StepReport,
}

/// Per-particle buffers `(x, v, ω, orientation)` reused by the wet-surface geometry.
pub(super) type KinematicsScratch = (Vec<[f64; 3]>, Vec<[f64; 3]>, Vec<[f64; 3]>, Vec<[f64; 4]>);
