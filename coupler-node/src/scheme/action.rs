//! What the state machine asks of its driver: the [`Action`]s, the end of a run, the report of
//! a finished step.

use protocol::wire::{Checkpoint, Message, NodeKind};

use crate::ledger::LedgerEntry;

/// Something the driver must do.
#[derive(Clone, Debug, PartialEq)]
pub enum Action {
    /// Send this message to that node.
    Send(NodeKind, Message),
    /// A step is complete: record its diagnostics, update progress.
    StepDone(StepReport),
    /// A node's checkpoint arrived: record it.
    Checkpoint(Checkpoint),
    /// The coupler's own checkpoint (node `coupler`, bytes: a [`CouplerCheckpoint`](crate::scheme::CouplerCheckpoint)), taken
    /// when it asks the nodes for theirs: record it.
    CouplerCheckpoint(Checkpoint),
    /// The run is over (the shutdown messages were emitted just before).
    Finished(Finish),
}

/// How a run ended normally.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Finish {
    /// `t_end` reached.
    Completed,
    /// `run.max_steps` reached before `t_end`.
    MaxSteps,
}

/// What happened in one coupling step.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct StepReport {
    /// Step index.
    pub step: u64,
    /// Time at the end of the step \[s\].
    pub t: f64,
    /// Step size \[s\].
    pub dt: f64,
    /// Who limited the step.
    pub limiter: String,
    /// Solid trials in this step (0 without a coupled solid).
    pub iterations: u32,
    /// Residual of criterion (22) after each trial.
    pub residuals: Vec<f64>,
    /// Relaxation factors used after each non-final trial (Aitken), empty otherwise.
    pub relaxation: Vec<f64>,
    /// IQN-ILS: columns the quasi-Newton update used after each non-final trial (0: the
    /// constant first relaxation or the predictor), empty otherwise.
    pub columns: Vec<u32>,
    /// IQN-ILS: columns the QR2 filter dropped in this step.
    pub columns_dropped: u32,
    /// The predictor gave the input of iteration 1.
    pub predicted: bool,
    /// Output index written at the end of the step.
    pub output: Option<u32>,
    /// The balance.
    pub ledger: LedgerEntry,
    /// With `run.solid_substeps`: the solid's sub-steps in this step.
    pub solid_substeps: Option<u32>,
    /// Fluid cells below the vacuum thresholds at the end of the step (0 without a fluid).
    pub vacuum_cells: u64,
    /// The links broken in this step, in the order they broke: the end of the solid sub-step
    /// that broke each (`tⁿ + j dt/K`, [`crate::scheme::substep_end`]) and its particle ids
    /// `[a, b]`.
    pub broken_links: Vec<(f64, [u32; 2])>,
}
