//! The run's files the loop writes as it goes: the MCAP record `exchange.mcap`, the
//! conservation history `ledger.csv` and, with fracture, `links_broken.csv`, all durable at the
//! end of every step.

use std::fs::File;
use std::io::BufWriter;
use std::path::Path;

use anyhow::Context;
use protocol::scene::{RecordLevel, Scene};
use protocol::wire::NodeKind;

use crate::driver::{RecordSink, SinkError};
use crate::ledger::{CSV_HEADER, LedgerEntry};
use crate::record::Recorder;

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
    pub fn append(&mut self, rows: &str) -> Result<(), SinkError> {
        use std::io::Write;
        if rows.is_empty() {
            return Ok(());
        }
        self.file
            .write_all(rows.as_bytes())
            .map_err(|source| SinkError::Csv {
                path: self.path.clone(),
                source,
            })
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

/// What `coupler-node run` writes as it goes: the record `exchange.mcap` (none at level
/// `none`), `ledger.csv` (always) and `links_broken.csv` (scenes with `solid.fracture`). One
/// layer over the files: each call goes straight to the file it concerns.
pub struct RunSink {
    /// The MCAP record (`None` at level `none`, and once [`RunSink::finish`]ed).
    record: Option<Recorder<BufWriter<File>>>,
    /// Frames and checkpoints are recorded (levels `all` and `exchange`).
    frames: bool,
    /// The conservation history, `ledger.csv`.
    ledger: CsvFile,
    /// The broken links, `links_broken.csv`, when the scene can break any.
    links_broken: Option<CsvFile>,
}

impl RunSink {
    /// Creates the run's files in `out`, the record first (with the scene as its metadata).
    pub fn create(out: &Path, scene: &Scene) -> anyhow::Result<RunSink> {
        let level = scene.run.record;
        let record = match level {
            RecordLevel::None => None,
            level => {
                let path = out.join("exchange.mcap");
                let file =
                    File::create(&path).with_context(|| format!("creating {}", path.display()))?;
                let recorder = Recorder::new(
                    BufWriter::new(file),
                    level,
                    scene.run.record_compression,
                    &scene.name,
                    &scene.to_toml(),
                )
                .with_context(|| format!("starting the record {}", path.display()))?;
                Some(recorder)
            }
        };
        Ok(RunSink {
            record,
            frames: matches!(level, RecordLevel::All | RecordLevel::Exchange),
            ledger: CsvFile::create(&out.join("ledger.csv"), CSV_HEADER)?,
            links_broken: scene
                .solid
                .as_ref()
                .is_some_and(|s| s.fracture.is_some())
                .then(|| CsvFile::create(&out.join("links_broken.csv"), LINKS_BROKEN_HEADER))
                .transpose()?,
        })
    }

    /// Writes the record's summary and footer (nothing without a record). Later calls of the
    /// sink write nothing more into the record.
    pub fn finish(&mut self) -> anyhow::Result<()> {
        if let Some(recorder) = self.record.take() {
            use std::io::Write;
            let mut w = recorder.finish().context("finishing the MCAP record")?;
            w.flush().context("flushing the MCAP record")?;
        }
        Ok(())
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
    ) -> Result<(), SinkError> {
        match &mut self.record {
            Some(recorder) if self.frames => {
                Ok(recorder.record_frame(from, to, t, wall_ns, frame)?)
            }
            _ => Ok(()),
        }
    }

    fn checkpoint(
        &mut self,
        node: NodeKind,
        t: f64,
        wall_ns: u64,
        frame: &[u8],
    ) -> Result<(), SinkError> {
        match &mut self.record {
            Some(recorder) if self.frames => {
                Ok(recorder.record_checkpoint(node, t, wall_ns, frame)?)
            }
            _ => Ok(()),
        }
    }

    fn diagnostics(&mut self, t: f64, wall_ns: u64, json: &[u8]) -> Result<(), SinkError> {
        match &mut self.record {
            Some(recorder) => Ok(recorder.record_diagnostics(t, wall_ns, json)?),
            None => Ok(()),
        }
    }

    fn ledger(&mut self, entry: &LedgerEntry) -> Result<(), SinkError> {
        self.ledger.append(&entry.csv_row())
    }

    fn links_broken(&mut self, t: f64, step: u64, pairs: &[[u32; 2]]) -> Result<(), SinkError> {
        self.links_broken
            .as_mut()
            .map_or(Ok(()), |csv| csv.append(&links_broken_rows(t, step, pairs)))
    }

    fn end_step(&mut self) -> Result<(), SinkError> {
        match &mut self.record {
            Some(recorder) => Ok(recorder.end_step()?),
            None => Ok(()),
        }
    }
}
