//! MCAP recording (placeholder until the recorder lands).

use std::io::{Seek, Write};

use protocol::scene::RecordLevel;
use protocol::wire::NodeKind;

/// Recording failure.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct RecordError(String);

/// The recorder.
pub struct Recorder<W: Write + Seek> {
    w: W,
}

impl<W: Write + Seek> Recorder<W> {
    /// New recorder.
    pub fn new(
        writer: W,
        _level: RecordLevel,
        _scene_name: &str,
        _scene_toml: &str,
    ) -> Result<Self, RecordError> {
        Ok(Recorder { w: writer })
    }
    /// Records a frame.
    pub fn record_frame(
        &mut self,
        _from: NodeKind,
        _to: NodeKind,
        _step: u64,
        _wall_ns: u64,
        _frame: &[u8],
    ) -> Result<(), RecordError> {
        Ok(())
    }
    /// Records a checkpoint.
    pub fn record_checkpoint(
        &mut self,
        _node: NodeKind,
        _step: u64,
        _wall_ns: u64,
        _frame: &[u8],
    ) -> Result<(), RecordError> {
        Ok(())
    }
    /// Records diagnostics.
    pub fn record_diagnostics(
        &mut self,
        _step: u64,
        _wall_ns: u64,
        _json: &[u8],
    ) -> Result<(), RecordError> {
        Ok(())
    }
    /// Ends a step.
    pub fn end_step(&mut self) -> Result<(), RecordError> {
        Ok(())
    }
    /// Finishes.
    pub fn finish(self) -> Result<W, RecordError> {
        Ok(self.w)
    }
}
