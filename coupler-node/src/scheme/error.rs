//! Why the coupler stops a run ([`CouplerError`]), and why a checkpoint does not fit the
//! scene ([`RestoreError`]).

use protocol::wire::{NodeKind, Stamp};

/// Why the coupler stops a run.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum CouplerError {
    /// A node was refused at hello.
    #[error("{node} node refused at hello: {reason}")]
    Refused {
        /// The node.
        node: NodeKind,
        /// Why.
        reason: String,
    },
    /// A message that does not fit the handshake.
    #[error("{from} node sent {got} at step {} iteration {} while the coupler expected {expected}", stamp.step, stamp.iteration)]
    Unexpected {
        /// Sender.
        from: NodeKind,
        /// Kind of message.
        got: String,
        /// Its stamp.
        stamp: Stamp,
        /// What was expected.
        expected: String,
    },
    /// The fixed point did not converge.
    #[error(
        "fixed point not converged at step {step} (t = {t:e}) after {iterations} iterations (tolerance {tolerance:e}); residual history {residuals:?}"
    )]
    NotConverged {
        /// Step.
        step: u64,
        /// Time at the start of the step.
        t: f64,
        /// Iterations done.
        iterations: u32,
        /// Tolerance.
        tolerance: f64,
        /// Residual after each trial.
        residuals: Vec<f64>,
    },
    /// `run.solid_substeps = "auto"` would need more sub-steps than allowed.
    #[error(
        "step {step} (t = {t:e}): dt {dt:e} s needs {needed} solid sub-steps of at most {bound:e} s \
         (half the stable step of {limiter}), more than {max}"
    )]
    TooManySubsteps {
        /// Step.
        step: u64,
        /// Time at its start.
        t: f64,
        /// The agreed step \[s\].
        dt: f64,
        /// The solid's stable step \[s\].
        bound: f64,
        /// What sets it (the particle).
        limiter: String,
        /// Sub-steps it would need.
        needed: u64,
        /// Most allowed.
        max: u32,
    },
    /// A node reported numerical trouble.
    #[error("{node} node failed at step {} iteration {}: {report}", stamp.step, stamp.iteration)]
    NodeFailure {
        /// The node.
        node: NodeKind,
        /// Where.
        stamp: Stamp,
        /// Its report.
        report: String,
    },
    /// A node ended the run.
    #[error("{node} node shut down: {reason}")]
    NodeShutdown {
        /// The node.
        node: NodeKind,
        /// Its reason.
        reason: String,
    },
    /// The ledger found a balance out of tolerance.
    #[error(
        "conservation ledger at step {step} (t = {t:e}): {what} = {value:e} exceeds the tolerance {tolerance:e}"
    )]
    Ledger {
        /// Step.
        step: u64,
        /// Time.
        t: f64,
        /// Which balance.
        what: String,
        /// Its value.
        value: f64,
        /// The tolerance.
        tolerance: f64,
    },
    /// No positive step could be agreed.
    #[error("no finite positive time step can be agreed at t = {t:e} (proposals {proposals})")]
    NoStep {
        /// Time.
        t: f64,
        /// The proposals.
        proposals: String,
    },
    /// A message whose content is inconsistent.
    #[error("{from} node sent an invalid {what}")]
    Invalid {
        /// Sender.
        from: NodeKind,
        /// What is wrong.
        what: String,
    },
}

/// Why a checkpoint cannot be restored into the scene's coupler.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum RestoreError {
    /// IQN-ILS columns in the checkpoint or in the scene's relaxation, not both.
    #[error("the checkpoint's relaxation is not the scene's (IQN-ILS columns present in one only)")]
    Relaxation,
    /// The restart's nodes are not the scene's.
    #[error("the restart has checkpoints of {checkpoints:?}, the scene runs {scene:?}")]
    Nodes {
        /// The nodes with a checkpoint, in order.
        checkpoints: Vec<NodeKind>,
        /// The scene's nodes, fluid first.
        scene: Vec<NodeKind>,
    },
}
