//! What the fluid and the solid node loops share: their configuration, their errors, and the
//! small exchanges every node makes (proposals, failure reports). Pure: the loops pass a
//! [`Link`] in; nothing here opens files or reads clocks.

use std::path::{Path, PathBuf};

use crate::transport::{Link, LinkError};
use crate::wire::{DtProposal, Failure, Message, Stamp};

/// What a node loop needs from the scene.
#[derive(Clone, Debug)]
pub struct LoopConfig {
    /// Hash of the resolved scene.
    pub scene_hash: u64,
    /// The other side takes part (the loads / trial-state exchange runs each step).
    pub coupled: bool,
    /// Where outputs go (`None`: write nothing).
    pub out: Option<PathBuf>,
}

/// How a node's run ended.
#[derive(Debug, thiserror::Error)]
pub enum NodeError {
    /// Exchange with the coupler failed.
    #[error(transparent)]
    Link(#[from] LinkError),
    /// Numerical trouble, already reported to the coupler.
    #[error("numerical failure at step {step}: {report}")]
    Numerical {
        /// Step.
        step: u64,
        /// Report.
        report: String,
    },
    /// Writing outputs failed.
    #[error("writing outputs to {dir}: {source}")]
    Output {
        /// The output directory.
        dir: String,
        /// The IO error.
        source: std::io::Error,
    },
}

impl NodeError {
    /// An output error in `dir`.
    pub fn output(dir: &Path, source: std::io::Error) -> NodeError {
        NodeError::Output {
            dir: dir.display().to_string(),
            source,
        }
    }
}

/// Sends this node's time-step proposal for `step`.
pub fn propose(
    link: &mut Link<'_>,
    step: u64,
    (dt_max, limiter): (f64, String),
) -> Result<(), NodeError> {
    link.send(&Message::DtProposal(DtProposal {
        stamp: Stamp::step(step),
        dt_max,
        limiter,
    }))?;
    Ok(())
}

/// The error for a message that does not fit the handshake.
pub fn unexpected(msg: &Message, expected: &str) -> NodeError {
    NodeError::Link(LinkError::Unexpected(format!(
        "{:?} (step {}, iteration {}) while waiting for {expected}",
        msg.kind(),
        msg.stamp().step,
        msg.stamp().iteration
    )))
}

/// Reports numerical trouble to the coupler, then returns the error that ends the node.
pub fn fail(link: &mut Link<'_>, stamp: Stamp, report: String) -> NodeError {
    // The coupler may already be gone; the local error is what matters then.
    let _ = link.send(&Message::Failure(Failure {
        stamp,
        node: link.me(),
        report: report.clone(),
    }));
    NodeError::Numerical {
        step: stamp.step,
        report,
    }
}
