//! Why recording or reading a record failed.

use protocol::mcap_read::ScanError;

/// Why recording or reading a record failed.
#[derive(Debug, thiserror::Error)]
pub enum RecordError {
    /// The MCAP library failed (IO included).
    #[error("mcap: {0}")]
    Mcap(#[from] mcap::McapError),
    /// A recorder was asked for with level `none`.
    #[error("record level none makes no recording")]
    Disabled,
    /// The bytes are not a readable record (not MCAP, damaged: chunk and offset named).
    #[error(transparent)]
    Read(#[from] ScanError),
    /// The record was written with an older layout (record layout and protocol version named).
    #[error("{0}")]
    Layout(String),
    /// A recorded frame or diagnostics message does not decode (inspection).
    #[error("{topic} message of step {step} does not decode: {reason}")]
    Decode {
        /// Topic.
        topic: String,
        /// Its coupling step (its log time when the step itself is unreadable).
        step: u64,
        /// The decoder's message.
        reason: String,
    },
    /// Reading or writing a stream failed (`inspect --export csv`).
    #[error("{0}")]
    Io(String),
    /// The requested step is not in the recording.
    #[error("step {step} is not in the recording (it holds {n_steps} steps, {first} to {last})")]
    NoSuchStep {
        /// Requested step.
        step: u64,
        /// Number of steps recorded.
        n_steps: usize,
        /// First step.
        first: u64,
        /// Last step.
        last: u64,
    },
}
