//! The MCAP record of a run (DESIGN §4–5): every bus frame exactly as it crossed the bus, node
//! checkpoints, and a JSON diagnostics channel; plus a reader that tolerates files cut short by a
//! kill, and a recovery that rewrites such a file into a complete one.
//!
//! # Channels
//!
//! | topic | message encoding | schema (name, encoding) |
//! |---|---|---|
//! | `fluid-to-coupler`, `coupler-to-fluid`, `solid-to-coupler`, `coupler-to-solid` | `bincode` | `protocol::wire::Message`, `bincode-serde` |
//! | `checkpoint/fluid`, `checkpoint/solid` | `bincode` | `protocol::wire::Message`, `bincode-serde` |
//! | `diagnostics` | `json` | `cosim.Diagnostics`, `jsonschema` ([`DIAGNOSTICS_SCHEMA`]) |
//! | `checkpoint/coupler` | `bincode` | `protocol::wire::Message`, `bincode-serde` (a `Checkpoint` whose bytes are a `CouplerCheckpoint`) |
//!
//! Frames are the bytes of `protocol::codec` (24-byte header + bincode payload), so a reader
//! decodes them with `protocol::codec::decode`. Channel ids are fixed (1 to 8 in the order of the
//! table; only `diagnostics` at level `Diagnostics`), sequence numbers count per channel from 0,
//! `log_time` is the coupling step and `publish_time` the wall clock in ns since the UNIX epoch
//! given by the caller. Everything but `publish_time` is a function of the recorded run.
//!
//! Metadata records: `scene` {`name`, `toml`} and `run` {`protocol_version`, `record_level`,
//! `recorder`}.
//!
//! # Diagnostics JSON
//!
//! One object per completed step, serialized by the coupler (see [`Diagnostics`]):
//!
//! ```json
//! {"step": 12, "t": 0.0012, "dt": 1e-4, "iterations": 3, "residuals": [1e-3, 2e-7, 4e-13],
//!  "converged": true,
//!  "ledger": {"fluid_mass": 1.2, "fluid_energy": 250.0, "solid_energy": 3.5,
//!             "mass_rel_err": 1e-15, "energy_rel_err": 2e-12},
//!  "busy_s": {"fluid": 0.010, "solid": 0.002, "coupler": 0.0001}}
//! ```
//!
//! `step` is required; every other field may be missing (readers must cope); more ledger keys
//! may be added.
//!
//! # Durability
//!
//! [`Recorder::end_step`] closes the open chunk and flushes the writer, so a killed run leaves a
//! file whose messages are all readable up to the last completed step ([`read_recording`]), and
//! [`recover`] turns it into a complete file with summary and footer.

use std::collections::BTreeMap;
use std::io::{Cursor, Seek, Write};

use mcap::records::{MessageHeader, Metadata, Record, op};
use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};
use mcap::{Compression, WriteOptions, Writer};
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

/// Target uncompressed chunk size; [`Recorder::end_step`] closes chunks earlier.
const CHUNK_SIZE: u64 = 4 << 20;

/// Largest uncompressed chunk the reader accepts (1 GiB).
const MAX_CHUNK_LEN: u64 = 1 << 30;

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

/// Why recording or reading a record failed.
#[derive(Debug, thiserror::Error)]
pub enum RecordError {
    /// The MCAP library failed (IO included).
    #[error("mcap: {0}")]
    Mcap(#[from] mcap::McapError),
    /// A recorder was asked for with level `none`.
    #[error("record level none makes no recording")]
    Disabled,
    /// The bytes do not start with the MCAP magic.
    #[error("not an mcap file: {len} bytes without the mcap magic at the start")]
    NotMcap {
        /// Length of the input.
        len: usize,
    },
    /// A complete record could not be parsed.
    #[error("corrupt mcap record (opcode 0x{opcode:02X}) at byte {offset}: {reason}")]
    Corrupt {
        /// Offset of the record in the file.
        offset: usize,
        /// Its opcode.
        opcode: u8,
        /// The parser's message.
        reason: String,
    },
    /// A message names a channel that was never defined.
    #[error("message at byte {offset} uses undefined channel {channel_id}")]
    UnknownChannel {
        /// Offset of the record holding the message.
        offset: usize,
        /// The channel id.
        channel_id: u16,
    },
    /// A recorded frame or diagnostics message does not decode (inspection).
    #[error("{topic} message of step {step} does not decode: {reason}")]
    Decode {
        /// Topic.
        topic: String,
        /// Its log time (step).
        step: u64,
        /// The decoder's message.
        reason: String,
    },
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

/// Records a run into MCAP.
pub struct Recorder<W: Write + Seek> {
    writer: Writer<W>,
    level: RecordLevel,
    /// Channel id and next sequence number per topic.
    channels: BTreeMap<&'static str, (u16, u32)>,
}

impl<W: Write + Seek> Recorder<W> {
    /// `level`: `All` | `Exchange`: all bus frames, checkpoints and diagnostics; `Diagnostics`:
    /// only the diagnostics JSON channel; `None` is refused ([`RecordError::Disabled`]).
    /// `scene_toml` is stored as metadata `scene` (key `toml`) with the scene name; metadata
    /// `run` holds the protocol version.
    pub fn new(
        writer: W,
        level: RecordLevel,
        scene_name: &str,
        scene_toml: &str,
    ) -> Result<Self, RecordError> {
        if level == RecordLevel::None {
            return Err(RecordError::Disabled);
        }
        // NOTE: lz4 is fast enough not to slow the coupler, and `compression_threads(0)` keeps
        // the writer on the caller's thread (pitfall 13; it only matters for zstd).
        let mut writer = WriteOptions::new()
            .compression(Some(Compression::Lz4))
            .compression_threads(0)
            .chunk_size(Some(CHUNK_SIZE))
            .profile("")
            .create(writer)?;
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
            "cosim.Diagnostics",
            "jsonschema",
            DIAGNOSTICS_SCHEMA.as_bytes(),
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
        Ok(Recorder {
            writer,
            level,
            channels,
        })
    }

    /// The level this recorder was made with.
    pub fn level(&self) -> RecordLevel {
        self.level
    }

    /// Records one bus frame exactly as it crossed the bus, on topic `<from>-to-<to>`; log time =
    /// `step`, publish time = `wall_ns`. A no-op at level `Diagnostics`.
    pub fn record_frame(
        &mut self,
        from: NodeKind,
        to: NodeKind,
        step: u64,
        wall_ns: u64,
        frame: &[u8],
    ) -> Result<(), RecordError> {
        if self.level == RecordLevel::Diagnostics {
            return Ok(());
        }
        let topic = frame_topic(from, to).ok_or_else(|| RecordError::Decode {
            topic: format!("{from}-to-{to}"),
            step,
            reason: "no such bus channel (frames go between the coupler and a node)".into(),
        })?;
        self.write(topic, step, wall_ns, frame)
    }

    /// Records a checkpoint frame on `checkpoint/fluid` or `checkpoint/solid`. A no-op at level
    /// `Diagnostics`.
    pub fn record_checkpoint(
        &mut self,
        node: NodeKind,
        step: u64,
        wall_ns: u64,
        frame: &[u8],
    ) -> Result<(), RecordError> {
        if self.level == RecordLevel::Diagnostics {
            return Ok(());
        }
        let topic = checkpoint_topic(node).ok_or_else(|| RecordError::Decode {
            topic: format!("checkpoint/{node}"),
            step,
            reason: "only the fluid and solid nodes have checkpoints".into(),
        })?;
        self.write(topic, step, wall_ns, frame)
    }

    /// Records the diagnostics object of a step (`json` is the serialized object).
    pub fn record_diagnostics(
        &mut self,
        step: u64,
        wall_ns: u64,
        json: &[u8],
    ) -> Result<(), RecordError> {
        self.write(DIAGNOSTICS_TOPIC, step, wall_ns, json)
    }

    /// Called after each completed step: closes the open chunk and flushes the writer, so a
    /// killed run leaves a file readable up to here (pitfall 12).
    pub fn end_step(&mut self) -> Result<(), RecordError> {
        self.writer.flush()?;
        Ok(())
    }

    /// Writes the summary and footer and returns the inner writer.
    pub fn finish(mut self) -> Result<W, RecordError> {
        self.writer.finish()?;
        Ok(self.writer.into_inner())
    }

    fn write(
        &mut self,
        topic: &'static str,
        step: u64,
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
            log_time: step,
            publish_time: wall_ns,
        };
        *sequence = sequence.wrapping_add(1);
        self.writer.write_to_known_channel(&header, data)?;
        Ok(())
    }
}

/// One recorded message.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Recorded {
    /// Topic of its channel.
    pub topic: String,
    /// Coupling step.
    pub log_time: u64,
    /// Wall clock \[ns since the UNIX epoch\].
    pub publish_time: u64,
    /// Sequence number within its channel.
    pub sequence: u32,
    /// The bytes (a bus frame, or JSON on `diagnostics`).
    pub data: Vec<u8>,
}

/// Everything readable in a recording.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Recording {
    /// Messages in file order.
    pub messages: Vec<Recorded>,
    /// Metadata records by name.
    pub metadata: BTreeMap<String, BTreeMap<String, String>>,
    /// The file ends early (no footer and end magic): the run was killed or the file cut.
    pub truncated: bool,
    /// Bytes after the last complete record (lost; 0 for a complete file).
    pub unreadable_bytes: usize,
}

impl Recording {
    /// Messages of one topic, in file order.
    pub fn topic<'a>(&'a self, topic: &'a str) -> impl Iterator<Item = &'a Recorded> + 'a {
        self.messages.iter().filter(move |m| m.topic == topic)
    }
}

/// Reads every message in file order. Works on complete files and on files cut short by a kill
/// (it stops cleanly at the first incomplete record and reports the unreadable bytes); bad
/// input gives an error, never a panic.
pub fn read_recording(bytes: &[u8]) -> Result<Recording, RecordError> {
    let scan = scan(bytes)?;
    let messages = scan
        .messages
        .into_iter()
        .map(|m| Recorded {
            topic: scan.channels[&m.channel_id].topic.clone(),
            log_time: m.log_time,
            publish_time: m.publish_time,
            sequence: m.sequence,
            data: m.data,
        })
        .collect();
    Ok(Recording {
        messages,
        metadata: scan.metadata.into_iter().collect(),
        truncated: scan.truncated,
        unreadable_bytes: scan.unreadable_bytes,
    })
}

/// Rewrites a (possibly truncated) file into a complete one with summary and footer: the same
/// metadata, schemas, channels and messages (every message that [`read_recording`] returns).
pub fn recover(bytes: &[u8]) -> Result<Vec<u8>, RecordError> {
    let scan = scan(bytes)?;
    let mut writer = WriteOptions::new()
        .compression(Some(Compression::Lz4))
        .compression_threads(0)
        .chunk_size(Some(CHUNK_SIZE))
        .profile("")
        .create(Cursor::new(Vec::new()))?;
    for (name, metadata) in &scan.metadata {
        writer.write_metadata(&Metadata {
            name: name.clone(),
            metadata: metadata.clone(),
        })?;
    }
    let mut new_ids = BTreeMap::new();
    for (id, channel) in &scan.channels {
        let schema_id = match &channel.schema {
            Some(s) => writer.add_schema(&s.name, &s.encoding, &s.data)?,
            None => 0,
        };
        let new_id = writer.add_channel(
            schema_id,
            &channel.topic,
            &channel.message_encoding,
            &channel.metadata,
        )?;
        new_ids.insert(*id, new_id);
    }
    for m in &scan.messages {
        let header = MessageHeader {
            channel_id: new_ids[&m.channel_id],
            sequence: m.sequence,
            log_time: m.log_time,
            publish_time: m.publish_time,
        };
        writer.write_to_known_channel(&header, &m.data)?;
    }
    writer.finish()?;
    Ok(writer.into_inner().into_inner())
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

fn level_name(level: RecordLevel) -> &'static str {
    match level {
        RecordLevel::All => "all",
        RecordLevel::Exchange => "exchange",
        RecordLevel::Diagnostics => "diagnostics",
        RecordLevel::None => "none",
    }
}

fn frame_schema_text() -> String {
    format!(
        "{FRAME_SCHEMA_NAME} (protocol version {PROTOCOL_VERSION}): a 24-byte header (magic \
         \"FSI\\0\", version u32, message kind u16, sender u8, reserved u8, step u64, iteration \
         u32; little endian) followed by the bincode 2 serde encoding of the Rust enum \
         {FRAME_SCHEMA_NAME} (little endian, fixed-width integers); decode with \
         protocol::codec::decode"
    )
}

struct SchemaInfo {
    name: String,
    encoding: String,
    data: Vec<u8>,
}

struct ChannelInfo {
    topic: String,
    message_encoding: String,
    metadata: BTreeMap<String, String>,
    schema: Option<SchemaInfo>,
}

struct RawMessage {
    channel_id: u16,
    sequence: u32,
    log_time: u64,
    publish_time: u64,
    data: Vec<u8>,
}

struct Scan {
    channels: BTreeMap<u16, ChannelInfo>,
    messages: Vec<RawMessage>,
    metadata: Vec<(String, BTreeMap<String, String>)>,
    truncated: bool,
    unreadable_bytes: usize,
}

/// Walks the top-level records of a file (opcode u8, length u64, body), opening chunks; stops
/// at the first record that is not complete.
fn scan(bytes: &[u8]) -> Result<Scan, RecordError> {
    let magic = mcap::MAGIC;
    if bytes.len() < magic.len() || &bytes[..magic.len()] != magic {
        return Err(RecordError::NotMcap { len: bytes.len() });
    }
    let mut out = Scan {
        channels: BTreeMap::new(),
        messages: Vec::new(),
        metadata: Vec::new(),
        truncated: true,
        unreadable_bytes: 0,
    };
    let mut schemas: BTreeMap<u16, SchemaInfo> = BTreeMap::new();
    let mut offset = magic.len();
    let mut footer_seen = false;
    loop {
        let rest = &bytes[offset..];
        if footer_seen {
            out.truncated = rest != magic;
            out.unreadable_bytes = if out.truncated { rest.len() } else { 0 };
            break;
        }
        if rest.len() < 9 {
            out.unreadable_bytes = rest.len();
            break;
        }
        let opcode = rest[0];
        let len = u64::from_le_bytes(rest[1..9].try_into().expect("8 bytes"));
        let Some(body) = usize::try_from(len)
            .ok()
            .and_then(|len| rest.get(9..9usize.checked_add(len)?))
        else {
            out.unreadable_bytes = rest.len();
            break;
        };
        let corrupt = |err: mcap::McapError| RecordError::Corrupt {
            offset,
            opcode,
            reason: err.to_string(),
        };
        let record = mcap::parse_record(opcode, body).map_err(corrupt)?;
        if let Record::Chunk { header, data } = record {
            check_chunk_size(&header, data.len()).map_err(|reason| RecordError::Corrupt {
                offset,
                opcode,
                reason,
            })?;
            let limit = usize::try_from(header.uncompressed_size).unwrap_or(usize::MAX);
            // NOTE: the mcap crate's ChunkReader has no record length limit, so a corrupt
            // length inside a chunk would make it allocate that much; the sans-io reader,
            // limited to the chunk's size, refuses it instead.
            let mut reader = LinearReader::new_with_options(
                LinearReaderOptions::default()
                    .with_skip_start_magic(true)
                    .with_skip_end_magic(true)
                    .with_record_length_limit(limit.max(body.len())),
            );
            let mut input = &rest[..9 + body.len()];
            while let Some(event) = reader.next_event() {
                match event.map_err(corrupt)? {
                    LinearReadEvent::ReadRequest(need) => {
                        let n = need.min(input.len());
                        reader.insert(n).copy_from_slice(&input[..n]);
                        reader.notify_read(n);
                        input = &input[n..];
                    }
                    LinearReadEvent::Record { data, opcode } => {
                        let inner = mcap::parse_record(opcode, data).map_err(corrupt)?;
                        take_record(inner, offset, &mut schemas, &mut out)?;
                    }
                }
            }
        } else {
            footer_seen = opcode == op::FOOTER;
            take_record(record, offset, &mut schemas, &mut out)?;
        }
        offset += 9 + body.len();
    }
    Ok(out)
}

/// Refuses chunks whose announced uncompressed size cannot be right, before the mcap reader
/// allocates that much (a corrupt size would abort the process).
fn check_chunk_size(header: &mcap::records::ChunkHeader, compressed: usize) -> Result<(), String> {
    let size = header.uncompressed_size;
    let compressed = compressed as u64;
    // NOTE: lz4's worst-case ratio is about 255:1; zstd's is unbounded, so only the cap holds.
    let plausible = match header.compression.as_str() {
        "" => size == compressed,
        "lz4" => size <= compressed.saturating_mul(256).saturating_add(4096),
        _ => true,
    };
    if !plausible || size > MAX_CHUNK_LEN {
        return Err(format!(
            "chunk announces {size} uncompressed bytes from {compressed} {} bytes (limit {MAX_CHUNK_LEN})",
            if header.compression.is_empty() {
                "uncompressed"
            } else {
                &header.compression
            }
        ));
    }
    Ok(())
}

fn take_record(
    record: Record<'_>,
    offset: usize,
    schemas: &mut BTreeMap<u16, SchemaInfo>,
    out: &mut Scan,
) -> Result<(), RecordError> {
    match record {
        Record::Schema { header, data } => {
            schemas.insert(
                header.id,
                SchemaInfo {
                    name: header.name,
                    encoding: header.encoding,
                    data: data.into_owned(),
                },
            );
        }
        Record::Channel(channel) => {
            // Channels repeated in the summary section are the same; keep the first.
            out.channels
                .entry(channel.id)
                .or_insert_with(|| ChannelInfo {
                    schema: schemas.get(&channel.schema_id).map(|s| SchemaInfo {
                        name: s.name.clone(),
                        encoding: s.encoding.clone(),
                        data: s.data.clone(),
                    }),
                    topic: channel.topic,
                    message_encoding: channel.message_encoding,
                    metadata: channel.metadata,
                });
        }
        Record::Message { header, data } => {
            if !out.channels.contains_key(&header.channel_id) {
                return Err(RecordError::UnknownChannel {
                    offset,
                    channel_id: header.channel_id,
                });
            }
            out.messages.push(RawMessage {
                channel_id: header.channel_id,
                sequence: header.sequence,
                log_time: header.log_time,
                publish_time: header.publish_time,
                data: data.into_owned(),
            });
        }
        Record::Metadata(meta) => out.metadata.push((meta.name, meta.metadata)),
        _ => {}
    }
    Ok(())
}
