//! The crate's error, [`Error`]: what building or running the fluid node fails with. Each
//! module's typed error converts into it with `#[from]`; it is formatted once, where it is
//! reported (the node loop sends its text to the coupler in a `Failure`).

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
    /// The embedded solid's error, with the coupling step when a step met it.
    // NOTE(issue 34): embedded's typed error lands with the split; until then its `String`.
    #[error("{0}")]
    Embedded(String),
}
