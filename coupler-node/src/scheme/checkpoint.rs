//! What the coupler carries between steps ([`CouplerCheckpoint`]) and what a restarted run
//! resumes from ([`Resume`]).

use protocol::wire::{Checkpoint, Message, NodeKind};
use serde::{Deserialize, Serialize};

use crate::dt::Agreed;
use crate::ledger::Ledger;
use crate::scheme::accel::AccelerationState;

/// What the coupler carries from one step to the next, taken when it asks the nodes for their
/// checkpoints (the step's plan agreed, the requests sent): the accepted states the predictors
/// extrapolate, IQN-ILS's secant columns, the ledger. Restored with the nodes' checkpoints, the
/// coupler iterates the next steps exactly as the original run did. Aitken's factor restarts
/// from `run.relaxation_initial` every step, so it carries nothing.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CouplerCheckpoint {
    /// The step whose plan is agreed.
    pub step: u64,
    /// Its start time \[s\].
    pub t: f64,
    pub(super) next_output: usize,
    /// The step agreed for `step`, when the checkpoint was taken after the agreement.
    pub(super) plan: Option<Agreed>,
    /// The accepted states and IQN-ILS's columns.
    pub acceleration: AccelerationState,
    pub(super) ledger: Ledger,
    pub(super) iteration_total: u64,
    pub(super) iteration_max: u32,
    pub(super) queue: Vec<(NodeKind, Message)>,
}

/// What a restarted run resumes from: the coupler's checkpoint and the nodes' of the same step.
#[derive(Clone, Debug)]
pub struct Resume {
    /// The coupler's.
    pub coupler: CouplerCheckpoint,
    /// One per node of the scene, fluid first.
    pub nodes: Vec<Checkpoint>,
}
