//! The recorder: writes the frames, checkpoints and diagnostics of a run into MCAP, so that the
//! file stays readable by standard readers up to the last completed step at every moment
//! between two writes (module docs of [`crate::record`], "Durability").

use std::collections::BTreeMap;
use std::io::{Seek, SeekFrom, Write};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use mcap::records::{MessageHeader, Metadata};
use mcap::{Compression, WriteOptions, Writer};
use protocol::PROTOCOL_VERSION;
use protocol::mcap_read::PROVISIONAL_END;
use protocol::scene::{RecordCompression, RecordLevel};
use protocol::topics::{self, RECORD_LAYOUT};
use protocol::wire::NodeKind;

use crate::record::channels::{
    DIAGNOSTICS_SCHEMA_NAME, DIAGNOSTICS_TOPIC, FRAME_MESSAGE_ENCODING, FRAME_SCHEMA_ENCODING,
    FRAME_SCHEMA_NAME, checkpoint_topic, diagnostics_schema, frame_schema_text, frame_topic,
    level_name,
};
use crate::record::error::RecordError;
use crate::record::foxglove::{
    self, FLUID_TOPIC, GRID_SCHEMA_NAME, SCENE_UPDATE_SCHEMA_NAME, SOLID_TOPIC, grid_schema,
    scene_update_schema,
};

/// zstd's level for `record_compression = "zstd"`: `-5` (zstd's `--fast=5`). On the record of
/// `clamped-beam-2d` since the smaller messages (99.2 MB raw, in 4 MiB blocks, `zstd -b`):
/// level -1 3.22 times smaller at 1.56 GB/s, -3 3.05 at 1.76 GB/s, -5 2.87 at 2.09 GB/s, -10
/// 2.72 at 2.30 GB/s (lz4 1.89 at 1.62 GB/s); in the run the record's thread took 0.154 s of
/// CPU at -5 against 0.176 s at -1, for a record of 34 MB against 30 (issue 39 item 4: the
/// record's CPU lands on the run's wall time when the run fills the cores). Level 3, the
/// library's default, was 2.5 times slower than -1 on the larger messages of before.
pub(crate) const ZSTD_LEVEL: i32 = -5;

/// Largest uncompressed chunk [`Recorder`] holds in memory before it writes it (4 MiB).
const CHUNK_SIZE: u64 = 4 << 20;

/// Records a run into MCAP.
pub struct Recorder<W: Write + Seek> {
    writer: Writer<ProvisionalEnd<W>>,
    level: RecordLevel,
    /// Set by [`Recorder::close_chunk`] just before it flushes the writer: the next flush of
    /// [`ProvisionalEnd`] writes the provisional end.
    end_due: Arc<AtomicBool>,
    /// Where the provisional end after the last complete write of a chunk begins (bytes).
    committed: Arc<AtomicU64>,
    /// Uncompressed bytes written into the open chunk.
    open_chunk_bytes: u64,
    /// Channel id and next sequence number per topic.
    channels: BTreeMap<&'static str, (u16, u32)>,
}

impl<W: Write + Seek> Recorder<W> {
    /// `level`: `All` | `Exchange`: all bus frames, checkpoints and diagnostics; `Diagnostics`:
    /// only the diagnostics JSON channel; `None` is refused ([`RecordError::Disabled`]).
    /// `compression`: of every chunk (`run.record_compression`). `scene_toml` is stored as
    /// metadata `scene` (key `toml`) with the scene name; metadata `run` holds the protocol
    /// version.
    pub fn new(
        writer: W,
        level: RecordLevel,
        compression: RecordCompression,
        scene_name: &str,
        scene_toml: &str,
    ) -> Result<Self, RecordError> {
        if level == RecordLevel::None {
            return Err(RecordError::Disabled);
        }
        // NOTE: `compression_threads(0)` keeps zstd on the caller's thread (pitfall 13): one
        // thread, the record's own in a run (`record::Background`), not one per core.
        // NOTE: the writer takes the level as a `u32` and hands it to zstd as an `i32`
        // (`as i32`), so a negative level goes through as its two's complement; lz4 keeps its
        // default (0).
        let (compression, compression_level) = match compression {
            RecordCompression::None => (None, 0),
            RecordCompression::Lz4 => (Some(Compression::Lz4), 0),
            RecordCompression::Zstd => (Some(Compression::Zstd), ZSTD_LEVEL as u32),
        };
        let end_due = Arc::new(AtomicBool::new(false));
        let committed = Arc::new(AtomicU64::new(0));
        // NOTE: `disable_seeking` makes the writer build each chunk in memory and write it
        // whole, so nothing reaches the file mid-step and the provisional end stays the last
        // thing in it; `chunk_size(None)` leaves closing chunks to `close_chunk`.
        let mut writer = WriteOptions::new()
            .compression(compression)
            .compression_level(compression_level)
            .compression_threads(0)
            .chunk_size(None)
            .disable_seeking(true)
            .profile("")
            .create(ProvisionalEnd {
                inner: writer,
                pos: 0,
                len: 0,
                end_due: end_due.clone(),
                committed: committed.clone(),
            })?;
        writer.write_metadata(&Metadata {
            name: "scene".into(),
            metadata: BTreeMap::from([
                ("name".to_string(), scene_name.to_string()),
                ("toml".to_string(), scene_toml.to_string()),
            ]),
        })?;
        writer.write_metadata(&Metadata {
            name: "run".into(),
            metadata: BTreeMap::from([
                ("protocol_version".to_string(), PROTOCOL_VERSION.to_string()),
                ("record_layout".to_string(), RECORD_LAYOUT.to_string()),
                ("record_level".to_string(), level_name(level).to_string()),
                (
                    "recorder".to_string(),
                    format!("coupler-node {}", env!("CARGO_PKG_VERSION")),
                ),
            ]),
        })?;
        let mut channels = BTreeMap::new();
        let mut frame_schema = None;
        if level != RecordLevel::Diagnostics {
            let schema = writer.add_schema(
                FRAME_SCHEMA_NAME,
                FRAME_SCHEMA_ENCODING,
                frame_schema_text().as_bytes(),
            )?;
            let links = [
                (NodeKind::Fluid, NodeKind::Coupler),
                (NodeKind::Coupler, NodeKind::Fluid),
                (NodeKind::Solid, NodeKind::Coupler),
                (NodeKind::Coupler, NodeKind::Solid),
            ];
            for (from, to) in links {
                let topic = frame_topic(from, to).expect("links of the star");
                let meta = BTreeMap::from([
                    ("from".to_string(), from.name().to_string()),
                    ("to".to_string(), to.name().to_string()),
                    ("protocol_version".to_string(), PROTOCOL_VERSION.to_string()),
                ]);
                let id = writer.add_channel(schema, topic, FRAME_MESSAGE_ENCODING, &meta)?;
                channels.insert(topic, (id, 0));
            }
            for node in [NodeKind::Fluid, NodeKind::Solid] {
                let topic = checkpoint_topic(node).expect("a solver node");
                let meta = BTreeMap::from([
                    ("node".to_string(), node.name().to_string()),
                    ("protocol_version".to_string(), PROTOCOL_VERSION.to_string()),
                ]);
                let id = writer.add_channel(schema, topic, FRAME_MESSAGE_ENCODING, &meta)?;
                channels.insert(topic, (id, 0));
            }
            frame_schema = Some(schema);
        }
        let schema = writer.add_schema(
            DIAGNOSTICS_SCHEMA_NAME,
            "jsonschema",
            diagnostics_schema().as_bytes(),
        )?;
        let id = writer.add_channel(schema, DIAGNOSTICS_TOPIC, "json", &BTreeMap::new())?;
        channels.insert(DIAGNOSTICS_TOPIC, (id, 0));
        if let Some(frames) = frame_schema {
            // After `diagnostics`, so the ids of the older channels stay as they were.
            let topic = checkpoint_topic(NodeKind::Coupler).expect("the coupler's topic");
            let meta = BTreeMap::from([
                ("node".to_string(), NodeKind::Coupler.name().to_string()),
                ("protocol_version".to_string(), PROTOCOL_VERSION.to_string()),
            ]);
            let id = writer.add_channel(frames, topic, FRAME_MESSAGE_ENCODING, &meta)?;
            channels.insert(topic, (id, 0));
        }
        // Last, so the ids of the older channels stay as they were.
        for (topic, name, schema) in [
            (SOLID_TOPIC, SCENE_UPDATE_SCHEMA_NAME, scene_update_schema()),
            (FLUID_TOPIC, GRID_SCHEMA_NAME, grid_schema()),
        ] {
            let schema = writer.add_schema(name, "jsonschema", schema.as_bytes())?;
            let id = writer.add_channel(schema, topic, "json", &BTreeMap::new())?;
            channels.insert(topic, (id, 0));
        }
        let mut recorder = Recorder {
            writer,
            level,
            end_due,
            committed,
            open_chunk_bytes: 0,
            channels,
        };
        // A run killed before its first step ends leaves a readable (empty) record.
        recorder.close_chunk()?;
        Ok(recorder)
    }

    /// The level this recorder was made with.
    pub fn level(&self) -> RecordLevel {
        self.level
    }

    /// Records one bus frame exactly as it crossed the bus, on topic `/<from>-to-<to>`; log time
    /// = simulated time `t` \[s\] in ns ([`topics::log_time`]; the caller passes the start time
    /// of the frame's step), publish time = `wall_ns`. The step stays in the frame's header. A
    /// no-op at level `Diagnostics`.
    pub fn record_frame(
        &mut self,
        from: NodeKind,
        to: NodeKind,
        t: f64,
        wall_ns: u64,
        frame: &[u8],
    ) -> Result<(), RecordError> {
        if self.level == RecordLevel::Diagnostics {
            return Ok(());
        }
        let topic = frame_topic(from, to).ok_or_else(|| RecordError::Decode {
            topic: format!("/{from}-to-{to}"),
            step: topics::frame_step(frame).unwrap_or(0),
            reason: "no such bus channel (frames go between the coupler and a node)".into(),
        })?;
        self.write(topic, t, wall_ns, frame)
    }

    /// Records a checkpoint frame on `/checkpoint/fluid`, `/checkpoint/solid` or
    /// `/checkpoint/coupler`, log time as [`Recorder::record_frame`]. A no-op at level
    /// `Diagnostics`.
    pub fn record_checkpoint(
        &mut self,
        node: NodeKind,
        t: f64,
        wall_ns: u64,
        frame: &[u8],
    ) -> Result<(), RecordError> {
        if self.level == RecordLevel::Diagnostics {
            return Ok(());
        }
        let topic = checkpoint_topic(node).expect("every node has a checkpoint topic");
        self.write(topic, t, wall_ns, frame)
    }

    /// Records the diagnostics object of a step (`json` is the serialized object, whose `step`
    /// key holds the step); log time = `t` (the step's end time) in ns.
    pub fn record_diagnostics(
        &mut self,
        t: f64,
        wall_ns: u64,
        json: &[u8],
    ) -> Result<(), RecordError> {
        self.write(DIAGNOSTICS_TOPIC, t, wall_ns, json)
    }

    /// Records the Foxglove views of output `k` of the files in `dir` (module
    /// [`crate::record::foxglove`]): the solid's scene update and the fluid's grid, each when
    /// its files are there; log and publish time = `t` (the output's simulated time), so the
    /// messages are a function of the run. `broken`: the links broken so far. A file that is
    /// there and does not read is logged and left out (the views are not the run's data).
    pub fn record_views(
        &mut self,
        dir: &std::path::Path,
        k: u32,
        t: f64,
        broken: &[[u32; 2]],
    ) -> Result<(), RecordError> {
        let views = [
            (
                SOLID_TOPIC,
                foxglove::solid_scene(dir, k, t, broken).map(|m| serde_json::to_vec(&m)),
            ),
            (
                FLUID_TOPIC,
                foxglove::fluid_grid(dir, k, t).map(|m| serde_json::to_vec(&m)),
            ),
        ];
        for (topic, view) in views {
            match view {
                Ok(json) => {
                    let json = json.expect("a Foxglove message serializes");
                    self.write(topic, t, topics::log_time(t), &json)?;
                }
                Err(foxglove::ViewError::Missing(_)) => {}
                Err(err) => tracing::warn!("{topic} lacks output {k}: {err}"),
            }
        }
        Ok(())
    }

    /// Called after each completed step: closes the open chunk, writes it and the provisional
    /// end, and flushes the writer, so a killed run leaves a file that standard readers read up
    /// to here (pitfall 12; module docs, "Durability").
    pub fn end_step(&mut self) -> Result<(), RecordError> {
        self.close_chunk()
    }

    /// Bytes of the record up to its last complete step (the provisional end starts there):
    /// where [`cut_back`] cuts a record whose writing failed.
    pub fn committed(&self) -> u64 {
        self.committed.load(Ordering::Relaxed)
    }

    /// Writes the summary and footer over the provisional end and returns the inner writer.
    pub fn finish(mut self) -> Result<W, RecordError> {
        self.writer.finish()?;
        let out = self.writer.into_inner();
        // The summary is longer than the provisional end, so nothing of it is left behind.
        if out.pos < out.len {
            return Err(RecordError::Mcap(mcap::McapError::Io(
                std::io::Error::other(format!(
                    "the finished record ({} bytes) is shorter than what was written ({} bytes)",
                    out.pos, out.len
                )),
            )));
        }
        Ok(out.inner)
    }

    fn close_chunk(&mut self) -> Result<(), RecordError> {
        self.end_due.store(true, Ordering::Relaxed);
        let res = self.writer.flush();
        self.end_due.store(false, Ordering::Relaxed);
        self.open_chunk_bytes = 0;
        res?;
        Ok(())
    }

    fn write(
        &mut self,
        topic: &'static str,
        t: f64,
        wall_ns: u64,
        data: &[u8],
    ) -> Result<(), RecordError> {
        let (channel_id, sequence) = self
            .channels
            .get_mut(topic)
            .expect("every topic has a channel at this level");
        let header = MessageHeader {
            channel_id: *channel_id,
            sequence: *sequence,
            log_time: topics::log_time(t),
            publish_time: wall_ns,
        };
        *sequence = sequence.wrapping_add(1);
        self.writer.write_to_known_channel(&header, data)?;
        // NOTE: a chunk is held in memory until it is closed; past CHUNK_SIZE it is closed
        // mid-step (then a kill keeps the messages of part of a step as well).
        self.open_chunk_bytes += data.len() as u64;
        if self.open_chunk_bytes >= CHUNK_SIZE {
            self.close_chunk()?;
        }
        Ok(())
    }
}

/// The file under the MCAP writer: passes writes through, and when asked (`end_due`), writes
/// [`PROVISIONAL_END`] after the last byte on flush and steps back over it, so that the next
/// write overwrites it.
///
/// With seeking disabled the MCAP writer only asks it for its position, never seeks it.
struct ProvisionalEnd<W: Write + Seek> {
    inner: W,
    /// Where the writer's next byte goes.
    pos: u64,
    /// Bytes in the file (`pos`, plus a provisional end after it).
    len: u64,
    end_due: Arc<AtomicBool>,
    /// `pos` after the last provisional end that reached the file.
    committed: Arc<AtomicU64>,
}

/// Cuts a record whose writing failed (a full disk, a write error) back to its last complete
/// step: the provisional end written at `committed` again, over bytes the file already has (so
/// no new space is needed), and the file truncated after it. Standard readers then read it up
/// to that step, as the record of a killed run.
pub fn cut_back(file: &mut std::fs::File, committed: u64) -> std::io::Result<()> {
    file.seek(SeekFrom::Start(committed))?;
    file.write_all(&PROVISIONAL_END)?;
    file.set_len(committed + PROVISIONAL_END.len() as u64)?;
    file.sync_data()
}

impl<W: Write + Seek> Write for ProvisionalEnd<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.pos += n as u64;
        self.len = self.len.max(self.pos);
        Ok(n)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        if self.end_due.load(Ordering::Relaxed) {
            self.inner.write_all(&PROVISIONAL_END)?;
            self.len = self.len.max(self.pos + PROVISIONAL_END.len() as u64);
            self.inner.seek(SeekFrom::Start(self.pos))?;
            self.inner.flush()?;
            self.committed.store(self.pos, Ordering::Relaxed);
            return Ok(());
        }
        self.inner.flush()
    }
}

impl<W: Write + Seek> Seek for ProvisionalEnd<W> {
    fn seek(&mut self, pos: SeekFrom) -> std::io::Result<u64> {
        self.pos = self.inner.seek(pos)?;
        Ok(self.pos)
    }

    fn stream_position(&mut self) -> std::io::Result<u64> {
        Ok(self.pos)
    }
}
