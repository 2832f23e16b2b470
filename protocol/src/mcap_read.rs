//! Bounded, CRC-checked reading of the bytes of an MCAP record: the one reader behind the replay
//! double, `coupler-node inspect` and `coupler-node replay`.
//!
//! The data section is walked record by record (opcode `u8`, length `u64`, body). Every length
//! is checked against the bytes that follow before anything is sliced or allocated, a chunk's
//! announced uncompressed size is checked against its compressed size, and a chunk's CRC is
//! checked before any of its records is used. The summary section is never needed, so damage
//! confined to it loses nothing (it is reported in [`End::Finished`]).
//!
//! How the bytes end tells three cases apart:
//! - [`End::Finished`]: a data-end record, a summary and the footer: the writer finished.
//! - [`End::Unfinished`]: the recorder's provisional end ([`PROVISIONAL_END`]), which it writes
//!   after every completed step and overwrites with the next: the run was killed (or is still
//!   running) after its last completed step. Standard readers read such a file as it is.
//! - [`End::CutShort`]: the bytes stop inside a record and there is no end magic: a run killed
//!   while it wrote, or a file cut.
//!
//! A record that runs past the end of a file that does end with the end magic, a CRC failure or
//! a record that does not parse is damage, not a kill: [`Mode::Strict`] refuses it with the
//! chunk index and byte offset, [`Mode::Salvage`] drops what does not verify, says what it
//! dropped ([`Dropped`]) and reads on from the next chunk that verifies.
//!
//! [`Stream`] is the same strict reader fed piece by piece, in bounded memory.

use std::collections::BTreeMap;

use mcap::McapError;
use mcap::records::{ChunkHeader, Record, op};
use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};

mod stream;
pub use stream::Stream;

/// What the recorder writes after every completed step, and overwrites with the next one: a
/// data-end record without CRC, a footer without summary, and the end magic. A file that ends
/// here is a complete MCAP file without summary, which every standard reader reads linearly.
pub const PROVISIONAL_END: [u8; 50] = provisional_end();

/// Largest uncompressed chunk accepted (1 GiB).
pub const MAX_CHUNK_LEN: u64 = 1 << 30;

const fn provisional_end() -> [u8; 50] {
    let mut out = [0u8; 50];
    // Data end: opcode, length 4, CRC 0 (not computed).
    out[0] = op::DATA_END;
    out[1] = 4;
    // Footer: opcode, length 20, summary start 0, summary offset start 0, CRC 0.
    out[13] = op::FOOTER;
    out[14] = 20;
    let mut i = 0;
    while i < 8 {
        out[42 + i] = mcap::MAGIC[i];
        i += 1;
    }
    out
}

/// How strictly [`scan`] treats damage.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// Any damage is an error (replay, inspect).
    Strict,
    /// Damaged chunks and records are dropped and listed; reading goes on (`inspect --recover`).
    Salvage,
}

/// A schema record.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ScannedSchema {
    /// Schema name.
    pub name: String,
    /// Schema encoding.
    pub encoding: String,
    /// Schema text.
    pub data: Vec<u8>,
}

/// A channel record, with its schema.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ScannedChannel {
    /// Topic.
    pub topic: String,
    /// Message encoding.
    pub message_encoding: String,
    /// Channel metadata.
    pub metadata: BTreeMap<String, String>,
    /// Its schema, `None` for schema id 0 (or a schema not found).
    pub schema: Option<ScannedSchema>,
}

/// A message record.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ScannedMessage {
    /// Channel id (a key of [`Scan::channels`]).
    pub channel_id: u16,
    /// Sequence number.
    pub sequence: u32,
    /// Log time.
    pub log_time: u64,
    /// Publish time.
    pub publish_time: u64,
    /// Payload.
    pub data: Vec<u8>,
}

/// How the bytes end.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum End {
    /// Data end, summary and footer: the writer finished. `summary_damage` says what is wrong
    /// with the summary section, if anything (it is not needed to read the data).
    Finished {
        /// What is wrong with the summary section, if anything.
        summary_damage: Option<String>,
    },
    /// The recorder's provisional end after a completed step: a killed (or running) run.
    Unfinished,
    /// The bytes stop inside the record at `offset`, without end magic.
    CutShort {
        /// Offset of the incomplete record.
        offset: usize,
        /// Bytes from there to the end of the input.
        unreadable_bytes: usize,
    },
}

/// Something [`Mode::Salvage`] left out.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Dropped {
    /// What: `chunk 3`, `record (opcode 0x0C)`, `bytes`, `4 messages`.
    pub what: String,
    /// Byte offset where it starts.
    pub offset: usize,
    /// Its length in bytes (0 for messages dropped for their channel).
    pub len: usize,
    /// Why.
    pub reason: String,
}

impl std::fmt::Display for Dropped {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} at byte {} ({} bytes): {}",
            self.what, self.offset, self.len, self.reason
        )
    }
}

/// Everything readable in the bytes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Scan {
    /// Channels by id.
    pub channels: BTreeMap<u16, ScannedChannel>,
    /// Messages in file order.
    pub messages: Vec<ScannedMessage>,
    /// Metadata records in file order.
    pub metadata: Vec<(String, BTreeMap<String, String>)>,
    /// How the bytes end.
    pub end: End,
    /// What [`Mode::Salvage`] left out (always empty in [`Mode::Strict`]).
    pub dropped: Vec<Dropped>,
}

/// Why the bytes cannot be read (in [`Mode::Strict`]; [`Mode::Salvage`] only refuses bytes that
/// are not MCAP at all).
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum ScanError {
    /// The bytes do not start with the MCAP magic.
    #[error("not an mcap file: {len} bytes without the mcap magic at the start")]
    NotMcap {
        /// Length of the input.
        len: usize,
    },
    /// A record outside the chunks does not parse, or does not belong in the data section.
    #[error("corrupt mcap record (opcode 0x{opcode:02X}) at byte {offset}: {reason}")]
    Record {
        /// Offset of the record.
        offset: usize,
        /// Its opcode.
        opcode: u8,
        /// What is wrong.
        reason: String,
    },
    /// A chunk's CRC does not match its contents.
    #[error(
        "chunk {index} at byte {offset}: CRC failed (expected {saved:08X}, got {calculated:08X})"
    )]
    ChunkCrc {
        /// Index of the chunk in the file (from 0).
        index: usize,
        /// Offset of the chunk record.
        offset: usize,
        /// CRC in the chunk header.
        saved: u32,
        /// CRC of the contents.
        calculated: u32,
    },
    /// A chunk is damaged otherwise (sizes, compression, records inside).
    #[error("chunk {index} at byte {offset}: {reason}")]
    Chunk {
        /// Index of the chunk in the file (from 0).
        index: usize,
        /// Offset of the chunk record.
        offset: usize,
        /// What is wrong.
        reason: String,
    },
    /// A message names a channel that was never defined.
    #[error("message at byte {offset} uses undefined channel {channel_id}")]
    UnknownChannel {
        /// Offset of the record holding the message (its chunk).
        offset: usize,
        /// The channel id.
        channel_id: u16,
    },
    /// The data-end record's CRC does not match the data section: a record outside the chunks
    /// (metadata, schema, channel, message index) is damaged.
    #[error(
        "data section CRC failed (expected {saved:08X}, got {calculated:08X}): a record outside the chunks is damaged"
    )]
    DataCrc {
        /// CRC in the data-end record.
        saved: u32,
        /// CRC of the data section.
        calculated: u32,
    },
}

/// Reads `bytes` (see the module docs).
pub fn scan(bytes: &[u8], mode: Mode) -> Result<Scan, ScanError> {
    let magic = mcap::MAGIC;
    if bytes.len() < magic.len() || &bytes[..magic.len()] != magic {
        return Err(ScanError::NotMcap { len: bytes.len() });
    }
    let ends_with_magic = bytes.len() >= 2 * magic.len() && bytes.ends_with(magic);
    let mut state = State {
        mode,
        schemas: BTreeMap::new(),
        channels: BTreeMap::new(),
        messages: Vec::new(),
        metadata: Vec::new(),
        dropped: Vec::new(),
        end: None,
        n_chunks: 0,
        summary_channels: match mode {
            Mode::Strict => BTreeMap::new(),
            Mode::Salvage => summary_channels(bytes),
        },
    };
    let mut offset = magic.len();
    let end = loop {
        if let Some(end) = state.end.take() {
            break end;
        }
        match state.record_at(bytes, offset, ends_with_magic) {
            Ok(Step::Next(next)) => offset = next,
            Ok(Step::Done) => {}
            Err(err) if mode == Mode::Strict => return Err(err),
            Err(err) => {
                let next = resync(bytes, offset + 1);
                state.dropped.push(Dropped {
                    what: "bytes".into(),
                    offset,
                    len: next.unwrap_or(bytes.len()) - offset,
                    reason: err.to_string(),
                });
                match next {
                    Some(next) => offset = next,
                    None => {
                        state.end = Some(End::CutShort {
                            offset,
                            unreadable_bytes: bytes.len() - offset,
                        })
                    }
                }
            }
        }
    };
    Ok(Scan {
        channels: state.channels,
        messages: state.messages,
        metadata: state.metadata,
        end,
        dropped: state.dropped,
    })
}

struct State {
    mode: Mode,
    schemas: BTreeMap<u16, ScannedSchema>,
    channels: BTreeMap<u16, ScannedChannel>,
    messages: Vec<ScannedMessage>,
    metadata: Vec<(String, BTreeMap<String, String>)>,
    dropped: Vec<Dropped>,
    end: Option<End>,
    n_chunks: usize,
    /// Channels repeated in a summary section that verifies (salvage only): they stand in for
    /// channel records lost with a damaged chunk.
    summary_channels: BTreeMap<u16, ScannedChannel>,
}

enum Step {
    Next(usize),
    Done,
}

/// Opcode and body of the record at `offset`, `None` if it does not fit in the bytes.
fn record_bounds(bytes: &[u8], offset: usize) -> Option<(u8, &[u8])> {
    let rest = bytes.get(offset..)?;
    let head = rest.get(..9)?;
    let len = u64::from_le_bytes(head[1..9].try_into().expect("8 bytes"));
    let len = usize::try_from(len).ok()?;
    let body = rest.get(9..9usize.checked_add(len)?)?;
    Some((head[0], body))
}

impl State {
    fn record_at(
        &mut self,
        bytes: &[u8],
        offset: usize,
        ends_with_magic: bool,
    ) -> Result<Step, ScanError> {
        let rest = &bytes[offset..];
        let Some((opcode, body)) = record_bounds(bytes, offset) else {
            let opcode = rest.first().copied().unwrap_or(0);
            if ends_with_magic {
                return Err(ScanError::Record {
                    offset,
                    opcode,
                    reason: format!(
                        "the record runs past the end of the file ({} bytes left), which ends \
                         with the end magic: damaged, not cut short",
                        rest.len()
                    ),
                });
            }
            self.end = Some(End::CutShort {
                offset,
                unreadable_bytes: rest.len(),
            });
            return Ok(Step::Done);
        };
        let next = offset + 9 + body.len();
        let corrupt = |reason: String| ScanError::Record {
            offset,
            opcode,
            reason,
        };
        match opcode {
            op::DATA_END => {
                let record =
                    mcap::parse_record(opcode, body).map_err(|e| corrupt(e.to_string()))?;
                if rest == &PROVISIONAL_END[..] {
                    self.end = Some(End::Unfinished);
                    return Ok(Step::Done);
                }
                if let Record::DataEnd(end) = record
                    && end.data_section_crc != 0
                {
                    let calculated = crc32fast::hash(&bytes[..offset]);
                    if calculated != end.data_section_crc {
                        let err = ScanError::DataCrc {
                            saved: end.data_section_crc,
                            calculated,
                        };
                        if self.mode == Mode::Strict {
                            return Err(err);
                        }
                        // A dropped part explains the mismatch; otherwise the damage is in a
                        // record that cannot be verified on its own, which is kept but named.
                        if self.dropped.is_empty() {
                            self.dropped.push(Dropped {
                                what: "nothing".into(),
                                offset: 0,
                                len: offset,
                                reason: format!(
                                    "{err} (metadata, schemas and channels have no CRC of their own: kept)"
                                ),
                            });
                        }
                    }
                }
                self.end = Some(End::Finished {
                    summary_damage: summary_damage(bytes, next),
                });
                return Ok(Step::Done);
            }
            // A footer before any data end: a file from an older writer (no data end) or damage.
            op::FOOTER if rest.len() == 9 + 20 + 8 && ends_with_magic => {
                self.end = Some(End::Finished {
                    summary_damage: Some("no data-end record before the footer".into()),
                });
                return Ok(Step::Done);
            }
            _ => self.data_record(opcode, body, &bytes[offset..next], offset)?,
        }
        Ok(Step::Next(next))
    }

    /// A record of the data section other than the data end and the footer: `record` is the
    /// whole record (opcode, length, `body`) at `offset`.
    fn data_record(
        &mut self,
        opcode: u8,
        body: &[u8],
        record: &[u8],
        offset: usize,
    ) -> Result<(), ScanError> {
        let corrupt = |reason: String| ScanError::Record {
            offset,
            opcode,
            reason,
        };
        match opcode {
            op::CHUNK => {
                let index = self.n_chunks;
                self.n_chunks += 1;
                match read_chunk(record, offset, index) {
                    Ok(records) => {
                        for record in records {
                            self.take(record, offset)?;
                        }
                    }
                    Err(err) if self.mode == Mode::Salvage => {
                        self.dropped.push(Dropped {
                            what: format!("chunk {index}"),
                            offset,
                            len: record.len(),
                            reason: err.to_string(),
                        });
                    }
                    Err(err) => return Err(err),
                }
            }
            // NOTE: message indexes only speed up seeking, which this reader does not do; the
            // data-end CRC covers their bytes.
            op::MESSAGE_INDEX => {}
            op::HEADER | op::SCHEMA | op::CHANNEL | op::MESSAGE | op::METADATA => {
                let record =
                    mcap::parse_record(opcode, body).map_err(|e| corrupt(e.to_string()))?;
                self.take(record, offset)?;
            }
            op::ATTACHMENT => {}
            _ => {
                return Err(corrupt(
                    "not a record of the data section (opcode unknown or misplaced)".into(),
                ));
            }
        }
        Ok(())
    }

    fn take(&mut self, record: Record<'_>, offset: usize) -> Result<(), ScanError> {
        match record {
            Record::Schema { header, data } => {
                self.schemas.insert(
                    header.id,
                    ScannedSchema {
                        name: header.name,
                        encoding: header.encoding,
                        data: data.into_owned(),
                    },
                );
            }
            Record::Channel(channel) => {
                let schema = self.schemas.get(&channel.schema_id).cloned();
                self.channels.entry(channel.id).or_insert(ScannedChannel {
                    topic: channel.topic,
                    message_encoding: channel.message_encoding,
                    metadata: channel.metadata,
                    schema,
                });
            }
            Record::Message { header, data } => {
                if !self.channels.contains_key(&header.channel_id)
                    && let Some(channel) = self.summary_channels.get(&header.channel_id)
                {
                    self.channels.insert(header.channel_id, channel.clone());
                }
                if !self.channels.contains_key(&header.channel_id) {
                    let err = ScanError::UnknownChannel {
                        offset,
                        channel_id: header.channel_id,
                    };
                    if self.mode == Mode::Strict {
                        return Err(err);
                    }
                    self.dropped.push(Dropped {
                        what: "a message".into(),
                        offset,
                        len: 0,
                        reason: err.to_string(),
                    });
                    return Ok(());
                }
                self.messages.push(ScannedMessage {
                    channel_id: header.channel_id,
                    sequence: header.sequence,
                    log_time: header.log_time,
                    publish_time: header.publish_time,
                    data: data.into_owned(),
                });
            }
            Record::Metadata(meta) => self.metadata.push((meta.name, meta.metadata)),
            _ => {}
        }
        Ok(())
    }
}

/// The records inside the chunk record `record` (opcode, length, body), parsed, after its sizes
/// and CRC are checked: all of them or an error.
fn read_chunk(
    record: &[u8],
    offset: usize,
    index: usize,
) -> Result<Vec<Record<'static>>, ScanError> {
    let chunk_err = |reason: String| ScanError::Chunk {
        index,
        offset,
        reason,
    };
    let (header, data) = match mcap::parse_record(op::CHUNK, &record[9..]) {
        Ok(Record::Chunk { header, data }) => (header, data),
        Ok(_) => return Err(chunk_err("not a chunk".into())),
        Err(e) => return Err(chunk_err(e.to_string())),
    };
    check_chunk_size(&header, data.len()).map_err(chunk_err)?;
    let limit = usize::try_from(header.uncompressed_size).unwrap_or(usize::MAX);
    // NOTE: the mcap crate's ChunkReader has no record length limit, so a corrupt length inside
    // a chunk would make it allocate that much; the sans-io reader, limited to the chunk's
    // size, refuses it instead. Prevalidation checks the CRC before any record is yielded.
    let mut reader = LinearReader::new_with_options(
        LinearReaderOptions::default()
            .with_skip_start_magic(true)
            .with_skip_end_magic(true)
            .with_prevalidate_chunk_crcs(true)
            .with_record_length_limit(limit.max(record.len())),
    );
    let mut input = record;
    let mut records = Vec::new();
    while let Some(event) = reader.next_event() {
        match event {
            Ok(LinearReadEvent::ReadRequest(need)) => {
                let n = need.min(input.len());
                reader.insert(n).copy_from_slice(&input[..n]);
                reader.notify_read(n);
                input = &input[n..];
            }
            Ok(LinearReadEvent::Record { data, opcode }) => {
                let inner = mcap::parse_record(opcode, data).map_err(|e| {
                    chunk_err(format!("record (opcode 0x{opcode:02X}) inside: {e}"))
                })?;
                records.push(inner.into_owned());
            }
            Err(McapError::BadChunkCrc { saved, calculated }) => {
                return Err(ScanError::ChunkCrc {
                    index,
                    offset,
                    saved,
                    calculated,
                });
            }
            Err(e) => return Err(chunk_err(e.to_string())),
        }
    }
    Ok(records)
}

/// Refuses chunks whose announced uncompressed size cannot be right, before the reader
/// allocates that much (a corrupt size would abort the process).
fn check_chunk_size(header: &ChunkHeader, compressed: usize) -> Result<(), String> {
    let size = header.uncompressed_size;
    let compressed = compressed as u64;
    // NOTE: lz4's worst-case ratio is about 255:1; zstd's is unbounded, so only the cap holds.
    let plausible = match header.compression.as_str() {
        "" => size == compressed,
        "lz4" => size <= compressed.saturating_mul(256).saturating_add(4096),
        "zstd" => true,
        _ => false,
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

/// What is wrong with the summary section that starts at `at` (after the data end), if anything.
fn summary_damage(bytes: &[u8], at: usize) -> Option<String> {
    const FOOTER_LEN: usize = 9 + 20;
    let magic = mcap::MAGIC;
    let len = bytes.len();
    if len < at + FOOTER_LEN + magic.len() || !bytes.ends_with(magic) {
        return Some("no footer and end magic after the data section".into());
    }
    let footer_at = len - magic.len() - FOOTER_LEN;
    let footer = &bytes[footer_at..len - magic.len()];
    if footer[0] != op::FOOTER || footer[1..9] != 20u64.to_le_bytes() {
        return Some(format!("no footer record at byte {footer_at}"));
    }
    let summary_start = u64::from_le_bytes(footer[9..17].try_into().expect("8 bytes"));
    let summary_crc = u32::from_le_bytes(footer[25..29].try_into().expect("4 bytes"));
    if summary_start == 0 {
        return None;
    }
    match usize::try_from(summary_start) {
        Ok(start) if start == at => {}
        _ => {
            return Some(format!(
                "the footer puts the summary at byte {summary_start}, the data section ends at {at}"
            ));
        }
    }
    if summary_crc != 0 {
        let calculated = crc32fast::hash(&bytes[at..footer_at + 25]);
        if calculated != summary_crc {
            return Some(format!(
                "summary section CRC failed (expected {summary_crc:08X}, got {calculated:08X})"
            ));
        }
    }
    None
}

/// The schemas and channels of the summary section, if it is there and its CRC verifies.
fn summary_channels(bytes: &[u8]) -> BTreeMap<u16, ScannedChannel> {
    const FOOTER_LEN: usize = 9 + 20;
    let mut channels = BTreeMap::new();
    let len = bytes.len();
    if len < 8 + FOOTER_LEN + 8 || !bytes.ends_with(mcap::MAGIC) {
        return channels;
    }
    let footer_at = len - 8 - FOOTER_LEN;
    let Ok(start) = usize::try_from(u64::from_le_bytes(
        bytes[footer_at + 9..footer_at + 17]
            .try_into()
            .expect("8 bytes"),
    )) else {
        return channels;
    };
    if start < 8 || start > footer_at || summary_damage(bytes, start).is_some() {
        return channels;
    }
    let mut schemas = BTreeMap::new();
    let mut at = start;
    while at < footer_at {
        let Some((opcode, body)) = record_bounds(bytes, at) else {
            break;
        };
        match mcap::parse_record(opcode, body) {
            Ok(Record::Schema { header, data }) => {
                schemas.insert(
                    header.id,
                    ScannedSchema {
                        name: header.name,
                        encoding: header.encoding,
                        data: data.into_owned(),
                    },
                );
            }
            Ok(Record::Channel(channel)) => {
                channels.insert(
                    channel.id,
                    ScannedChannel {
                        schema: schemas.get(&channel.schema_id).cloned(),
                        topic: channel.topic,
                        message_encoding: channel.message_encoding,
                        metadata: channel.metadata,
                    },
                );
            }
            _ => {}
        }
        at += 9 + body.len();
    }
    channels
}

/// The next offset after `from` where a chunk that verifies, or a data end, starts.
fn resync(bytes: &[u8], from: usize) -> Option<usize> {
    (from..bytes.len()).find(|&at| match record_bounds(bytes, at) {
        Some((op::CHUNK, body)) => read_chunk(&bytes[at..at + 9 + body.len()], at, 0).is_ok(),
        Some((op::DATA_END, body)) => body.len() == 4,
        _ => false,
    })
}
