//! The run's files the loop writes as it goes: the MCAP record `exchange.mcap`, the
//! conservation history `ledger.csv` and, with fracture, `links_broken.csv`, all durable at the
//! end of every step.

use std::fs::File;
use std::io::BufWriter;
use std::path::Path;

use anyhow::Context;
use protocol::scene::{RecordLevel, Scene};
use protocol::wire::NodeKind;

use crate::driver::RecordSink;
use crate::ledger::LedgerEntry;
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
        let recorder = Recorder::new(
            BufWriter::new(file),
            level,
            scene.run.record_compression,
            &scene.name,
            &scene.to_toml(),
        )
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
        t: f64,
        wall_ns: u64,
        frame: &[u8],
    ) -> Result<(), String> {
        if !self.frames {
            return Ok(());
        }
        self.recorder()?
            .record_frame(from, to, t, wall_ns, frame)
            .map_err(|e| e.to_string())
    }

    fn checkpoint(
        &mut self,
        node: NodeKind,
        t: f64,
        wall_ns: u64,
        frame: &[u8],
    ) -> Result<(), String> {
        if !self.frames {
            return Ok(());
        }
        self.recorder()?
            .record_checkpoint(node, t, wall_ns, frame)
            .map_err(|e| e.to_string())
    }

    fn diagnostics(&mut self, t: f64, wall_ns: u64, json: &[u8]) -> Result<(), String> {
        self.recorder()?
            .record_diagnostics(t, wall_ns, json)
            .map_err(|e| e.to_string())
    }

    fn end_step(&mut self) -> Result<(), String> {
        self.recorder()?.end_step().map_err(|e| e.to_string())
    }
}

/// A CSV file written as the run goes: a header, then rows handed over whole and written with
/// one `write` on the unbuffered file, so a killed run keeps every row up to its last step.
/// `ledger.csv` (one row per accepted step, [`LedgerEntry::csv_row`]) and `links_broken.csv`
/// ([`links_broken_rows`]).
pub struct CsvFile {
    file: File,
    path: std::path::PathBuf,
}

impl CsvFile {
    /// Creates `path` and writes `header` (without its newline) as the first line.
    pub fn create(path: &Path, header: &str) -> anyhow::Result<CsvFile> {
        use std::io::Write;
        let mut file =
            File::create(path).with_context(|| format!("creating {}", path.display()))?;
        file.write_all(format!("{header}\n").as_bytes())
            .with_context(|| format!("writing {}", path.display()))?;
        Ok(CsvFile {
            file,
            path: path.to_path_buf(),
        })
    }

    /// Appends `rows` (each with its newline) in one write; nothing for no rows.
    pub fn append(&mut self, rows: &str) -> Result<(), String> {
        use std::io::Write;
        if rows.is_empty() {
            return Ok(());
        }
        self.file
            .write_all(rows.as_bytes())
            .map_err(|e| format!("writing {}: {e}", self.path.display()))
    }
}

/// Header line of `links_broken.csv` (DESIGN §7), without the newline.
pub const LINKS_BROKEN_HEADER: &str = "t,step,a,b";

/// The `links_broken.csv` rows of one accepted step (each with its newline): `t` the step's end
/// in shortest round-trip form, `step` from 0, `a, b` the particle ids of each link broken in
/// it, in the order they broke. Empty when none broke.
pub fn links_broken_rows(t: f64, step: u64, pairs: &[[u32; 2]]) -> String {
    pairs
        .iter()
        .map(|[a, b]| format!("{t:e},{step},{a},{b}\n"))
        .collect()
}

/// What `coupler-node run` writes as it goes: the record (none at level `none`),
/// `ledger.csv` (always) and `links_broken.csv` (scenes with `solid.fracture`).
pub struct RunSink {
    /// The MCAP record.
    pub record: Option<FileSink>,
    /// The conservation history, `ledger.csv`.
    pub ledger: CsvFile,
    /// The broken links, `links_broken.csv`, when the scene can break any.
    pub links_broken: Option<CsvFile>,
}

impl RunSink {
    fn record(&mut self) -> Option<&mut FileSink> {
        self.record.as_mut()
    }
}

impl RecordSink for RunSink {
    fn frame(
        &mut self,
        from: NodeKind,
        to: NodeKind,
        t: f64,
        wall_ns: u64,
        frame: &[u8],
    ) -> Result<(), String> {
        self.record()
            .map_or(Ok(()), |r| r.frame(from, to, t, wall_ns, frame))
    }

    fn checkpoint(
        &mut self,
        node: NodeKind,
        t: f64,
        wall_ns: u64,
        frame: &[u8],
    ) -> Result<(), String> {
        self.record()
            .map_or(Ok(()), |r| r.checkpoint(node, t, wall_ns, frame))
    }

    fn diagnostics(&mut self, t: f64, wall_ns: u64, json: &[u8]) -> Result<(), String> {
        self.record()
            .map_or(Ok(()), |r| r.diagnostics(t, wall_ns, json))
    }

    fn ledger(&mut self, entry: &LedgerEntry) -> Result<(), String> {
        self.ledger.append(&entry.csv_row())
    }

    fn links_broken(&mut self, t: f64, step: u64, pairs: &[[u32; 2]]) -> Result<(), String> {
        self.links_broken
            .as_mut()
            .map_or(Ok(()), |csv| csv.append(&links_broken_rows(t, step, pairs)))
    }

    fn end_step(&mut self) -> Result<(), String> {
        self.record().map_or(Ok(()), |r| r.end_step())
    }
}
