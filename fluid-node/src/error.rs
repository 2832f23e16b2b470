//! The crate's error, [`Error`]: what building or running the fluid node fails with. Each
//! module's typed error converts into it with `#[from]`; it is formatted once, where it is
//! reported (the node loop sends its text to the coupler in a `Failure`).

use crate::embedded::EmbeddedError;
use crate::fv::{CheckpointError, SolverError, StepError};

/// What building or running the fluid node fails with.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The solver could not be built (the scene's `[fluid]` table, the ranks, the pool).
    #[error(transparent)]
    Solver(#[from] SolverError),
    /// A step failed: the time step refused, or cells left non-physical.
    #[error(transparent)]
    Step(#[from] StepError),
    /// The solver's checkpoint could not be restored.
    #[error(transparent)]
    Checkpoint(#[from] CheckpointError),
    /// The scene has no `[fluid]` section.
    #[error("the scene has no [fluid] section")]
    NoFluid,
    /// A coupled scene with a 1-D fluid.
    #[error("a coupled scene needs a 2-D or 3-D fluid (the embedded solid has no 1-D form)")]
    CoupledOneD,
    /// A probe outside the grid.
    #[error("probe {name:?}: point {point:?} is outside the grid")]
    ProbeOutside {
        /// The probe's name.
        name: String,
        /// Its point \[m\].
        point: Vec<f64>,
    },
    /// The pressure double without its field.
    #[error("the pressure double needs a [fluid.pressure] table in the scene")]
    NoPressureField,
    /// An implementation name the node does not know.
    #[error(
        "unknown fluid implementation {implementation:?} (expected real, pressure or \
         replay:FILE.mcap)"
    )]
    UnknownImplementation {
        /// The name given.
        implementation: String,
    },
    /// A coupled step before the initial wet surface arrived.
    #[error("step {step}: a coupled step before the initial wet surface")]
    NoSurface {
        /// Coupling step.
        step: u64,
    },
    /// The embedded solid's error (a step of the cut-cell method).
    #[error(transparent)]
    Embedded(#[from] EmbeddedError),
    /// A solid state of changed particles only (the solid's trials after a step's first, which
    /// the coupler puts back together and never forwards).
    #[error(
        "solid state of step {step} iteration {iteration} holds only the particles that changed since the step's first trial; the fluid takes whole states"
    )]
    ChangesOnly {
        /// Coupling step.
        step: u64,
        /// Fixed-point iteration.
        iteration: u32,
    },
    /// A solid state whose arrays do not fit together.
    #[error(
        "solid state of step {step} is malformed: dim {dim} (surface {surface_dim}), {positions} positions, {velocities} velocities, {angular_velocities} angular velocities, {vertex_values} vertex values, {element_indices} element indices for {elements} elements, {wet_flags} wet flags, {particle_ids} particle numbers (none, or one per particle)"
    )]
    MalformedSolid {
        /// Coupling step.
        step: u64,
        /// The state's dimension.
        dim: u32,
        /// Its surface's dimension.
        surface_dim: u32,
        /// Position values.
        positions: usize,
        /// Velocity values.
        velocities: usize,
        /// Angular velocity values.
        angular_velocities: usize,
        /// Vertex coordinates.
        vertex_values: usize,
        /// Element vertex indices.
        element_indices: usize,
        /// Elements (from the particle-of-element list).
        elements: usize,
        /// Wet flags.
        wet_flags: usize,
        /// The solid's numbers of the particles (`SolidState::particles`).
        particle_ids: usize,
    },
    /// An element of a solid state belongs to a particle that does not exist.
    #[error(
        "solid state of step {step}: an element belongs to particle {particle}, there are {particles}"
    )]
    ElementParticle {
        /// Coupling step.
        step: u64,
        /// The particle named.
        particle: u32,
        /// Particles in the state.
        particles: usize,
    },
    /// An element of a solid state uses a vertex that does not exist.
    #[error("solid state of step {step}: an element uses vertex {vertex}, there are {vertices}")]
    ElementVertex {
        /// Coupling step.
        step: u64,
        /// The vertex named.
        vertex: u32,
        /// Vertices in the state.
        vertices: u32,
    },
}
