//! The channels of a record: topics, schemas, encodings, and the diagnostics JSON object.

use protocol::PROTOCOL_VERSION;
use protocol::scene::RecordLevel;
use protocol::topics;
use protocol::wire::NodeKind;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::ledger::LedgerEntry;

/// Schema name of the bincode frames.
pub const FRAME_SCHEMA_NAME: &str = "protocol::wire::Message";
/// Schema encoding of the bincode frames.
pub const FRAME_SCHEMA_ENCODING: &str = "bincode-serde";
/// Message encoding of the bincode frames.
pub const FRAME_MESSAGE_ENCODING: &str = "bincode";
/// Topic of the diagnostics channel.
pub const DIAGNOSTICS_TOPIC: &str = topics::DIAGNOSTICS;
/// Schema name of the diagnostics channel.
pub const DIAGNOSTICS_SCHEMA_NAME: &str = "cosim.Diagnostics";

/// JSON schema (draft 2020-12) of the diagnostics messages, derived from [`Diagnostics`] (so it
/// names every field the coupler writes), with the nested types inlined: Foxglove resolves no
/// `$ref`.
pub fn diagnostics_schema() -> String {
    let generator = schemars::generate::SchemaSettings::draft2020_12()
        .with(|s| s.inline_subschemas = true)
        .into_generator();
    let schema = generator.into_root_schema_for::<Diagnostics>();
    serde_json::to_string_pretty(&schema).expect("a JSON schema serializes")
}

/// The diagnostics object of one step, as the coupler writes it on `/diagnostics`. A step that
/// failed to converge has `converged: false`, its residual history, and no `ledger`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(default)]
#[schemars(
    title = "cosim.Diagnostics",
    description = "Per-step diagnostics of the fluid-structure coupler"
)]
pub struct Diagnostics {
    /// Coupling step n, from 0 (the frames' stamp and `ledger.step` count the same way).
    pub step: u64,
    /// Time at the end of the step \[s\].
    pub t: f64,
    /// Step size \[s\].
    pub dt: f64,
    /// What limited the step (`fluid:...`, `solid:...`, `scene`, `output`).
    pub limiter: String,
    /// Fixed-point iterations (solid trials).
    pub iterations: u32,
    /// Residual of each iteration.
    pub residuals: Vec<f64>,
    /// Relaxation factor of each iteration.
    pub relaxation: Vec<f64>,
    /// IQN-ILS columns in use at each iteration.
    pub columns: Vec<u32>,
    /// IQN-ILS columns dropped during the step.
    pub columns_dropped: u32,
    /// Whether the first trial was extrapolated from earlier steps.
    pub predicted: bool,
    /// Whether the fixed point converged.
    pub converged: bool,
    /// Output index written at the end of the step, if any.
    pub output: Option<u32>,
    /// Conservation ledger at the end of the step (missing for a step that failed).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ledger: Option<LedgerEntry>,
    /// Fluid cells whose density or pressure is below the `fluid.vacuum` thresholds at the end
    /// of the step, cells the solid covers left out (0 without a real fluid).
    pub vacuum_cells: u64,
    /// With `run.solid_substeps`: the solid sub-steps K of the step (absent without the key).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub solid_substeps: Option<u32>,
    /// Busy seconds per process during the run so far (wall clock: the one part of the
    /// record that differs between two runs of a scene).
    pub busy_s: BusySeconds,
}

/// Seconds each process computed.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct BusySeconds {
    /// Fluid node \[s\].
    pub fluid: f64,
    /// Solid node \[s\].
    pub solid: f64,
    /// Coupler \[s\].
    pub coupler: f64,
}

/// Topic of a bus link (`/fluid-to-coupler` ...), `None` for a pair that is not a link.
pub fn frame_topic(from: NodeKind, to: NodeKind) -> Option<&'static str> {
    topics::frame(from, to)
}

/// Topic of a node's (or the coupler's own) checkpoints.
pub fn checkpoint_topic(node: NodeKind) -> Option<&'static str> {
    Some(topics::checkpoint(node))
}

pub(crate) fn level_name(level: RecordLevel) -> &'static str {
    match level {
        RecordLevel::All => "all",
        RecordLevel::Exchange => "exchange",
        RecordLevel::Diagnostics => "diagnostics",
        RecordLevel::None => "none",
    }
}

pub(crate) fn frame_schema_text() -> String {
    format!(
        "{FRAME_SCHEMA_NAME} (protocol version {PROTOCOL_VERSION}): a 24-byte header (magic \
         \"FSI\\0\", version u32, message kind u16, sender u8, reserved u8, step u64, iteration \
         u32; little endian) followed by the bincode 2 serde encoding of the Rust enum \
         {FRAME_SCHEMA_NAME} (little endian, fixed-width integers); decode with \
         protocol::codec::decode"
    )
}
