//! The channels of a record: topics, schemas, encodings, and the diagnostics JSON object.

use std::collections::BTreeMap;

use protocol::PROTOCOL_VERSION;
use protocol::scene::RecordLevel;
use protocol::wire::NodeKind;
use serde::{Deserialize, Serialize};

/// Schema name of the bincode frames.
pub const FRAME_SCHEMA_NAME: &str = "protocol::wire::Message";
/// Schema encoding of the bincode frames.
pub const FRAME_SCHEMA_ENCODING: &str = "bincode-serde";
/// Message encoding of the bincode frames.
pub const FRAME_MESSAGE_ENCODING: &str = "bincode";
/// Topic of the diagnostics channel.
pub const DIAGNOSTICS_TOPIC: &str = "diagnostics";

/// JSON schema of the diagnostics messages.
pub const DIAGNOSTICS_SCHEMA: &str = r#"{
  "$schema": "https://json-schema.org/draft/2020-12/schema",
  "title": "cosim.Diagnostics",
  "description": "Per-step diagnostics of the fluid-structure coupler",
  "type": "object",
  "required": ["step"],
  "properties": {
    "step": {"type": "integer", "minimum": 0, "description": "coupling step n"},
    "t": {"type": "number", "description": "time at the end of the step [s]"},
    "dt": {"type": "number", "description": "step size [s]"},
    "iterations": {"type": "integer", "minimum": 0, "description": "fixed-point iterations"},
    "residuals": {"type": "array", "items": {"type": "number"}, "description": "residual of each iteration"},
    "converged": {"type": "boolean"},
    "ledger": {
      "type": "object",
      "description": "conservation ledger at the end of the step",
      "properties": {
        "fluid_mass": {"type": "number"},
        "fluid_energy": {"type": "number"},
        "solid_mass": {"type": "number"},
        "solid_energy": {"type": "number"},
        "dissipated": {"type": "number"},
        "interface_work": {"type": "number"},
        "boundary_mass_out": {"type": "number"},
        "boundary_energy_out": {"type": "number"},
        "mass_rel_err": {"type": "number"},
        "energy_rel_err": {"type": "number"}
      },
      "additionalProperties": {"type": "number"}
    },
    "busy_s": {
      "type": "object",
      "description": "seconds each process computed during the step",
      "properties": {
        "fluid": {"type": "number"},
        "solid": {"type": "number"},
        "coupler": {"type": "number"}
      }
    }
  }
}"#;

/// The diagnostics object of one step, as documented in the module docs (the coupler may use
/// its own type as long as it serializes to the same JSON).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Diagnostics {
    /// Coupling step.
    pub step: u64,
    /// Time at the end of the step \[s\].
    pub t: f64,
    /// Step size \[s\].
    pub dt: f64,
    /// Fixed-point iterations.
    pub iterations: u32,
    /// Residual of each iteration.
    pub residuals: Vec<f64>,
    /// Whether the fixed point converged.
    pub converged: bool,
    /// Conservation ledger: totals and relative errors, by name.
    pub ledger: BTreeMap<String, f64>,
    /// Busy seconds per process during the step.
    pub busy_s: BusySeconds,
}

/// Seconds each process computed during a step.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BusySeconds {
    /// Fluid node \[s\].
    pub fluid: f64,
    /// Solid node \[s\].
    pub solid: f64,
    /// Coupler \[s\].
    pub coupler: f64,
}
/// Topic of a bus channel (`fluid-to-coupler` ...), `None` for a pair that is not a link.
pub fn frame_topic(from: NodeKind, to: NodeKind) -> Option<&'static str> {
    match (from, to) {
        (NodeKind::Fluid, NodeKind::Coupler) => Some("fluid-to-coupler"),
        (NodeKind::Coupler, NodeKind::Fluid) => Some("coupler-to-fluid"),
        (NodeKind::Solid, NodeKind::Coupler) => Some("solid-to-coupler"),
        (NodeKind::Coupler, NodeKind::Solid) => Some("coupler-to-solid"),
        _ => None,
    }
}

/// Topic of a node's (or the coupler's own) checkpoints.
pub fn checkpoint_topic(node: NodeKind) -> Option<&'static str> {
    match node {
        NodeKind::Fluid => Some("checkpoint/fluid"),
        NodeKind::Solid => Some("checkpoint/solid"),
        NodeKind::Coupler => Some("checkpoint/coupler"),
    }
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
