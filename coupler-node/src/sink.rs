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
use crate::record::{Background, Recorder};

/// A CSV file written as the run goes: a header, then rows handed over whole and written with
/// one `write` on the unbuffered file, so a killed run keeps every row up to its last step.
/// `ledger.csv` (one row per accepted step, [`LedgerEntry::csv_record`]) and `links_broken.csv`
/// ([`links_broken_records`]).
pub struct CsvFile {
    file: File,
    path: std::path::PathBuf,
    /// Bytes of whole rows in the file.
    len: u64,
    /// The header's fields.
    header: Vec<String>,
}

impl CsvFile {
    /// Creates `path` and writes `header` as the first line.
    pub fn create(path: &Path, header: &[&str]) -> anyhow::Result<CsvFile> {
        let mut csv = CsvFile {
            file: File::create(path).with_context(|| format!("creating {}", path.display()))?,
            path: path.to_path_buf(),
            len: 0,
            header: header.iter().map(|h| h.to_string()).collect(),
        };
        // (The error names the file.)
        csv.append([header]).map_err(|e| anyhow::anyhow!("{e}"))?;
        Ok(csv)
    }

    /// Appends `records` in one write; nothing for no records. A write that fails (a full disk)
    /// is cut back, so the file ends on a whole row; a record of another length than the header
    /// fails before anything is written. Either error ends the run, so no row follows it.
    pub fn append<R: IntoIterator<Item = F>, F: AsRef<[u8]>>(
        &mut self,
        records: impl IntoIterator<Item = R>,
    ) -> Result<(), SinkError> {
        use std::io::{Seek, Write};
        let written = self
            .format(records)
            .map_err(std::io::Error::from)
            .and_then(|rows| self.file.write_all(&rows).map(|()| rows.len()));
        match written {
            Ok(bytes) => {
                self.len += bytes as u64;
                Ok(())
            }
            Err(source) => {
                let _ = self.file.set_len(self.len);
                let _ = self.file.seek(std::io::SeekFrom::Start(self.len));
                Err(SinkError::Csv {
                    path: self.path.clone(),
                    source,
                })
            }
        }
    }

    /// `records` as CSV rows.
    // NOTE: through a `csv` writer, which quotes a field that needs it and refuses a row of
    // another length than the header (a field left out of a row would otherwise shift the
    // columns silently). The header is written first, so the writer knows its length, and its
    // bytes are dropped.
    fn format<R: IntoIterator<Item = F>, F: AsRef<[u8]>>(
        &self,
        records: impl IntoIterator<Item = R>,
    ) -> csv::Result<Vec<u8>> {
        let mut table = csv::Writer::from_writer(Vec::new());
        table.write_record(&self.header)?;
        table.flush()?;
        let header_bytes = table.get_ref().len();
        for record in records {
            table.write_record(record)?;
        }
        table.flush()?;
        Ok(table.get_ref()[header_bytes..].to_vec())
    }
}

/// An error and its sources, `: `-separated (the MCAP library's IO error says only "I/O error";
/// its source says which).
fn with_sources(err: &dyn std::error::Error) -> String {
    let mut text = err.to_string();
    let mut source = err.source();
    while let Some(s) = source {
        let next = s.to_string();
        // The MCAP library's error repeats its source's text after its own prefix.
        if !text.ends_with(&next) {
            text.push_str(&format!(": {next}"));
        }
        source = s.source();
    }
    text
}

/// Bytes of a record's summary besides its chunk indexes (schemas, channels, statistics,
/// metadata indexes, footer), an upper estimate.
const SUMMARY_BASE_BYTES: u64 = 16 << 10;

/// Bytes of one chunk index in a record's summary (its message-index offsets of up to eight
/// channels included), an upper estimate.
const SUMMARY_BYTES_PER_CHUNK: u64 = 256;

/// Header of `links_broken.csv` (DESIGN §7).
pub const LINKS_BROKEN_HEADER: [&str; 4] = ["t", "step", "a", "b"];

/// The `links_broken.csv` rows of one accepted step: `t` the end of the solid sub-step that
/// broke the link (the step's end without sub-steps) in shortest round-trip form, `step` from 0,
/// `a, b` the particle ids of each link broken in it, in the order they broke. Empty when none
/// broke.
pub fn links_broken_records(step: u64, links: &[(f64, [u32; 2])]) -> Vec<[String; 4]> {
    links
        .iter()
        .map(|(t, [a, b])| {
            [
                format!("{t:e}"),
                format!("{step}"),
                format!("{a}"),
                format!("{b}"),
            ]
        })
        .collect()
}

/// What `coupler-node run` writes as it goes: the record `exchange.mcap` (none at level
/// `none`), `ledger.csv` (always) and `links_broken.csv` (scenes with `solid.fracture`). One
/// layer over the files: each call goes straight to the file it concerns.
pub struct RunSink {
    /// The MCAP record (`None` at level `none`, once [`RunSink::finish`]ed, and once a write
    /// failed).
    record: Option<Background<File>>,
    /// The record's path and a second handle on it, to cut it back after a failed write.
    record_file: Option<(std::path::PathBuf, File)>,
    /// `run.record_max_bytes`.
    cap: Option<u64>,
    /// The record's committed bytes at the end of the last step.
    last_bytes: u64,
    /// The largest step's bytes so far.
    largest_step: u64,
    /// Steps ended.
    steps: u64,
    /// Frames and checkpoints are recorded (levels `all` and `exchange`).
    frames: bool,
    /// The conservation history, `ledger.csv`.
    ledger: CsvFile,
    /// The broken links, `links_broken.csv`, when the scene can break any.
    links_broken: Option<CsvFile>,
    /// The run's folder, where the nodes write their outputs (the Foxglove views read them).
    out: std::path::PathBuf,
    /// File index of the first planned output (1 when the nodes wrote output 0 at t = 0).
    first_output: u32,
    /// Output 0 (t = 0) is written and its views not yet recorded.
    initial_view: bool,
    /// Links broken so far in this run, as particle-id pairs (the solid's view draws them).
    broken: Vec<[u32; 2]>,
}

impl RunSink {
    /// Creates the run's files in `out`, the record first (with the scene as its metadata).
    /// `resumed`: the run resumes from a checkpoint (no views of the initial output then).
    pub fn create(out: &Path, scene: &Scene, resumed: bool) -> anyhow::Result<RunSink> {
        let level = scene.run.record;
        let mut record_file = None;
        let record = match level {
            RecordLevel::None => None,
            level => {
                let path = out.join("exchange.mcap");
                let file =
                    File::create(&path).with_context(|| format!("creating {}", path.display()))?;
                let second = file
                    .try_clone()
                    .with_context(|| format!("opening {}", path.display()))?;
                record_file = Some((path.clone(), second));
                let recorder = Recorder::new(
                    BufWriter::new(file),
                    level,
                    scene.run.record_compression,
                    &scene.name,
                    &scene.to_toml(),
                )
                .with_context(|| format!("starting the record {}", path.display()))?;
                let background = Background::start(recorder);
                // NOTE: `record_max_bytes` is checked on the bytes written, so with a cap the
                // record keeps up step by step (one step in flight), as the check assumes.
                Some(match scene.run.record_max_bytes {
                    Some(_) => background.max_lag(0, 0),
                    None => background,
                })
            }
        };
        Ok(RunSink {
            record,
            record_file,
            cap: scene.run.record_max_bytes,
            last_bytes: 0,
            largest_step: 0,
            steps: 0,
            frames: matches!(level, RecordLevel::All | RecordLevel::Exchange),
            ledger: CsvFile::create(&out.join("ledger.csv"), &CSV_HEADER)?,
            links_broken: scene
                .solid
                .as_ref()
                .is_some_and(|s| s.fracture.is_some())
                .then(|| CsvFile::create(&out.join("links_broken.csv"), &LINKS_BROKEN_HEADER))
                .transpose()?,
            out: out.to_path_buf(),
            first_output: u32::from(scene.initial_output()),
            initial_view: scene.initial_output() && !resumed,
            broken: Vec::new(),
        })
    }

    /// Writes the record's summary and footer (nothing without a record). Later calls of the
    /// sink write nothing more into the record.
    pub fn finish(&mut self) -> anyhow::Result<()> {
        if let Some(recorder) = self.record.take() {
            use std::io::Write;
            let committed = recorder.committed();
            let done = recorder
                .finish()
                .map_err(|e| with_sources(&e))
                .and_then(|mut w| w.flush().map_err(|e| e.to_string()));
            if let Err(err) = done {
                anyhow::bail!("{}", self.cut_back(committed, &err));
            }
        }
        Ok(())
    }

    /// Runs `call` on the record (nothing without one); a failure cuts the record back to its
    /// last complete step and ends the recording.
    fn record_call(
        &mut self,
        call: impl FnOnce(&mut Background<File>) -> Result<(), crate::record::RecordError>,
    ) -> Result<(), SinkError> {
        let Some(recorder) = self.record.as_mut() else {
            return Ok(());
        };
        match call(recorder) {
            Ok(()) => Ok(()),
            Err(err) => {
                let committed = recorder.committed();
                // (The record's thread forgot its writer at the failure: no summary is written
                // after it.)
                self.record = None;
                Err(SinkError::Write(
                    self.cut_back(committed, &with_sources(&err)),
                ))
            }
        }
    }

    /// Cuts the record back to `committed` bytes after `err`; the message names the file, the
    /// error and what is left.
    fn cut_back(&mut self, committed: u64, err: &str) -> String {
        let Some((path, file)) = self.record_file.as_mut() else {
            return err.to_string();
        };
        match crate::record::cut_back(file, committed) {
            Ok(()) => format!(
                "writing {}: {err}; the record is cut back to its last complete step ({committed} bytes)",
                path.display()
            ),
            Err(cut) => format!(
                "writing {}: {err}; cutting it back to its last complete step failed too: {cut}",
                path.display()
            ),
        }
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
        if !self.frames {
            return Ok(());
        }
        self.record_call(|r| r.record_frame(from, to, t, wall_ns, frame))
    }

    fn checkpoint(
        &mut self,
        node: NodeKind,
        t: f64,
        wall_ns: u64,
        frame: &[u8],
    ) -> Result<(), SinkError> {
        if !self.frames {
            return Ok(());
        }
        self.record_call(|r| r.record_checkpoint(node, t, wall_ns, frame))
    }

    fn diagnostics(&mut self, t: f64, wall_ns: u64, json: &[u8]) -> Result<(), SinkError> {
        self.record_call(|r| r.record_diagnostics(t, wall_ns, json))
    }

    fn ledger(&mut self, entry: &LedgerEntry) -> Result<(), SinkError> {
        self.ledger.append([entry.csv_record()])
    }

    fn links_broken(&mut self, step: u64, links: &[(f64, [u32; 2])]) -> Result<(), SinkError> {
        self.broken.extend(links.iter().map(|(_, pair)| *pair));
        self.links_broken
            .as_mut()
            .map_or(Ok(()), |csv| csv.append(links_broken_records(step, links)))
    }

    fn views(&mut self, output: Option<u32>, t: f64) -> Result<(), SinkError> {
        let out = self.out.clone();
        if std::mem::take(&mut self.initial_view) {
            self.record_call(|r| r.record_views(&out, 0, 0.0, &[]))?;
        }
        let Some(k) = output else {
            return Ok(());
        };
        let (k, broken) = (k + self.first_output, std::mem::take(&mut self.broken));
        let done = self.record_call(|r| r.record_views(&out, k, t, &broken));
        self.broken = broken;
        done
    }

    fn end_step(&mut self) -> Result<(), SinkError> {
        self.record_call(|r| r.end_step())?;
        let (Some(cap), Some(recorder)) = (self.cap, self.record.as_ref()) else {
            return Ok(());
        };
        // (The bytes of the steps written: one step may still be on the record's thread.)
        let bytes = recorder.committed();
        self.largest_step = self.largest_step.max(bytes.saturating_sub(self.last_bytes));
        self.last_bytes = bytes;
        self.steps += 1;
        // The summary written at the end: a few kB and a chunk index per chunk.
        let chunks = self.steps + bytes / (4 << 20);
        let summary = SUMMARY_BASE_BYTES + SUMMARY_BYTES_PER_CHUNK * chunks;
        let next = self.largest_step;
        if bytes + 2 * next + summary > cap {
            // Reported once: the run ends here.
            self.cap = None;
            return Err(SinkError::Limit(format!(
                "record_max_bytes: the record holds {bytes} bytes and another step (up to {next} bytes) and its summary (about {summary} bytes) would pass run.record_max_bytes = {cap}"
            )));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_csv_file_holds_whole_rows_of_the_header_length_and_quotes_what_needs_it() {
        let dir = std::env::temp_dir().join(format!("cosim-sink-csv-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        let path = dir.join("links_broken.csv");
        let mut csv = CsvFile::create(&path, &LINKS_BROKEN_HEADER).expect("creates");
        csv.append(links_broken_records(3, &[(6e-4, [0, 1]), (6e-4, [3, 4])]))
            .expect("appends");
        csv.append(links_broken_records(4, &[])).expect("nothing");
        let read = || std::fs::read_to_string(&path).expect("reads");
        assert_eq!(read(), "t,step,a,b\n6e-4,3,0,1\n6e-4,3,3,4\n");
        // A row of another length is refused, and nothing of it reaches the file.
        let err = csv
            .append([["1e-3", "5", "2"]])
            .expect_err("three fields")
            .to_string();
        assert!(
            err.starts_with(&format!("writing {}: ", path.display()))
                && err.contains("found record with 3 fields"),
            "{err}"
        );
        assert_eq!(read(), "t,step,a,b\n6e-4,3,0,1\n6e-4,3,3,4\n");
        // A field with a comma or a quote is quoted (none of ours has one).
        let mut named = CsvFile::create(&dir.join("named.csv"), &["name", "x"]).expect("creates");
        named
            .append([["a,b", "1"], ["say \"hi\"", "2"]])
            .expect("appends");
        let text = std::fs::read_to_string(dir.join("named.csv")).expect("reads");
        assert_eq!(text, "name,x\n\"a,b\",1\n\"say \"\"hi\"\"\",2\n");
        let _ = std::fs::remove_dir_all(dir);
    }
}
