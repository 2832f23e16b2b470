//! The MCAP recorder as the driver's [`RecordSink`], writing `exchange.mcap`.

use std::fs::File;
use std::io::BufWriter;
use std::path::Path;

use anyhow::Context;
use protocol::scene::{RecordLevel, Scene};
use protocol::wire::NodeKind;

use crate::driver::RecordSink;
use crate::record::Recorder;

/// A recorder writing to a file.
pub struct FileSink {
    recorder: Option<Recorder<BufWriter<File>>>,
    frames: bool,
}

impl FileSink {
    /// Creates `path` and writes the scene as metadata.
    pub fn create(path: &Path, level: RecordLevel, scene: &Scene) -> anyhow::Result<FileSink> {
        let file = File::create(path).with_context(|| format!("creating {}", path.display()))?;
        let recorder = Recorder::new(BufWriter::new(file), level, &scene.name, &scene.to_toml())
            .with_context(|| format!("starting the record {}", path.display()))?;
        Ok(FileSink {
            recorder: Some(recorder),
            frames: matches!(level, RecordLevel::All | RecordLevel::Exchange),
        })
    }

    fn recorder(&mut self) -> Result<&mut Recorder<BufWriter<File>>, String> {
        self.recorder
            .as_mut()
            .ok_or_else(|| "the record is already finished".to_string())
    }

    /// Writes the summary and footer.
    pub fn finish(&mut self) -> anyhow::Result<()> {
        if let Some(recorder) = self.recorder.take() {
            use std::io::Write;
            let mut w = recorder.finish().context("finishing the MCAP record")?;
            w.flush().context("flushing the MCAP record")?;
        }
        Ok(())
    }
}

impl RecordSink for FileSink {
    fn frame(
        &mut self,
        from: NodeKind,
        to: NodeKind,
        step: u64,
        wall_ns: u64,
        frame: &[u8],
    ) -> Result<(), String> {
        if !self.frames {
            return Ok(());
        }
        self.recorder()?
            .record_frame(from, to, step, wall_ns, frame)
            .map_err(|e| e.to_string())
    }

    fn checkpoint(
        &mut self,
        node: NodeKind,
        step: u64,
        wall_ns: u64,
        frame: &[u8],
    ) -> Result<(), String> {
        if !self.frames {
            return Ok(());
        }
        self.recorder()?
            .record_checkpoint(node, step, wall_ns, frame)
            .map_err(|e| e.to_string())
    }

    fn diagnostics(&mut self, step: u64, wall_ns: u64, json: &[u8]) -> Result<(), String> {
        self.recorder()?
            .record_diagnostics(step, wall_ns, json)
            .map_err(|e| e.to_string())
    }

    fn end_step(&mut self) -> Result<(), String> {
        self.recorder()?.end_step().map_err(|e| e.to_string())
    }
}
