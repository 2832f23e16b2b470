//! The reader of [`super::scan`] fed piece by piece: a record of any size read in bounded memory
//! (`coupler-node inspect --export csv`), in [`Mode::Strict`](super::Mode::Strict).
//!
//! The caller feeds the file's bytes in order ([`Stream::feed`]) and takes the messages each
//! piece completed ([`Stream::take_messages`]); only the record being read is held (a chunk:
//! at most [`MAX_CHUNK_LEN`](super::MAX_CHUNK_LEN), plus the piece). Every check of the strict
//! scan holds: lengths before allocation, chunk sizes and CRCs, channels defined before use,
//! the data section's CRC (computed as the bytes pass). The summary section is not read.

use std::collections::BTreeMap;

use mcap::records::{Record, op};

use super::{End, MAX_CHUNK_LEN, Mode, PROVISIONAL_END, ScanError, ScannedChannel, ScannedMessage};

/// Longest record accepted outside a chunk's limit: a chunk's header and the chunk.
const MAX_RECORD_LEN: u64 = MAX_CHUNK_LEN + (1 << 20);

/// Bytes after the data-end record in the recorder's provisional end (footer and end magic).
const PROVISIONAL_TAIL: usize = PROVISIONAL_END.len() - 13;

/// A strict MCAP reader fed piece by piece (see the module docs).
pub struct Stream {
    state: super::State,
    /// Bytes not yet read as records; `buf[at..]` are pending, from file offset `offset`.
    buf: Vec<u8>,
    at: usize,
    offset: usize,
    /// CRC of the data section so far (everything before the data-end record).
    crc: crc32fast::Hasher,
    /// After the data end: its CRC field, and the bytes after it (counted; the first few kept).
    after_end: Option<(u32, usize, Vec<u8>)>,
}

impl Default for Stream {
    fn default() -> Stream {
        Stream::new()
    }
}

impl Stream {
    /// A reader at the start of a file.
    pub fn new() -> Stream {
        Stream {
            state: super::State {
                mode: Mode::Strict,
                schemas: BTreeMap::new(),
                channels: BTreeMap::new(),
                messages: Vec::new(),
                metadata: Vec::new(),
                dropped: Vec::new(),
                end: None,
                n_chunks: 0,
                summary_channels: BTreeMap::new(),
            },
            buf: Vec::new(),
            at: 0,
            offset: 0,
            crc: crc32fast::Hasher::new(),
            after_end: None,
        }
    }

    /// Reads the next `bytes` of the file: every record they complete.
    pub fn feed(&mut self, bytes: &[u8]) -> Result<(), ScanError> {
        if let Some((_, count, first)) = &mut self.after_end {
            *count += bytes.len();
            let keep = PROVISIONAL_TAIL
                .saturating_sub(first.len())
                .min(bytes.len());
            first.extend_from_slice(&bytes[..keep]);
            return Ok(());
        }
        if self.at > 0 && self.at >= self.buf.len() / 2 {
            self.buf.drain(..self.at);
            self.at = 0;
        }
        self.buf.extend_from_slice(bytes);
        if self.offset == 0 {
            let magic = mcap::MAGIC;
            if self.buf.len() < magic.len() {
                return Ok(());
            }
            if &self.buf[..magic.len()] != magic {
                return Err(ScanError::NotMcap {
                    len: self.buf.len(),
                });
            }
            self.crc.update(magic);
            self.at = magic.len();
            self.offset = magic.len();
        }
        while self.after_end.is_none() {
            let pending = &self.buf[self.at..];
            let Some(head) = pending.get(..9) else {
                break;
            };
            let (opcode, len) = (
                head[0],
                u64::from_le_bytes(head[1..9].try_into().expect("8")),
            );
            if len > MAX_RECORD_LEN {
                return Err(ScanError::Record {
                    offset: self.offset,
                    opcode,
                    reason: format!("a record of {len} bytes (limit {MAX_RECORD_LEN})"),
                });
            }
            let total = 9 + len as usize;
            let Some(record) = pending.get(..total) else {
                break;
            };
            let (record_offset, body) = (self.offset, &record[9..]);
            if opcode == op::DATA_END || opcode == op::FOOTER {
                let crc = match mcap::parse_record(opcode, body) {
                    Ok(Record::DataEnd(end)) => end.data_section_crc,
                    // A footer before any data end: an older writer's file, not checked.
                    Ok(_) => 0,
                    Err(e) => {
                        return Err(ScanError::Record {
                            offset: record_offset,
                            opcode,
                            reason: e.to_string(),
                        });
                    }
                };
                let calculated = self.crc.clone().finalize();
                if crc != 0 && crc != calculated {
                    return Err(ScanError::DataCrc {
                        saved: crc,
                        calculated,
                    });
                }
                let rest = pending[total..].to_vec();
                let mut first = rest.clone();
                first.truncate(PROVISIONAL_TAIL);
                let tail = if opcode == op::DATA_END { crc } else { 1 };
                self.after_end = Some((tail, rest.len(), first));
                self.buf = Vec::new();
                self.at = 0;
                break;
            }
            self.state
                .data_record(opcode, body, record, record_offset)?;
            self.crc.update(record);
            self.at += total;
            self.offset += total;
        }
        Ok(())
    }

    /// The messages read so far and not taken yet, in file order.
    pub fn take_messages(&mut self) -> Vec<ScannedMessage> {
        std::mem::take(&mut self.state.messages)
    }

    /// Channels by id, as defined so far.
    pub fn channels(&self) -> &BTreeMap<u16, ScannedChannel> {
        &self.state.channels
    }

    /// Metadata records read so far, in file order.
    pub fn metadata(&self) -> &[(String, BTreeMap<String, String>)] {
        &self.state.metadata
    }

    /// How the file ended, once every byte was fed: finished (data end and more), the
    /// recorder's provisional end (a killed or running run), or cut short inside a record. Bytes
    /// shorter than the magic are not MCAP; a record that runs past the end of bytes that end
    /// with the end magic is damage, not a cut (as [`super::scan`] says).
    pub fn finish(self) -> Result<End, ScanError> {
        let magic = mcap::MAGIC;
        if self.offset == 0 {
            return Err(ScanError::NotMcap {
                len: self.buf.len(),
            });
        }
        Ok(match self.after_end {
            Some((0, count, first))
                if count == PROVISIONAL_TAIL && first[..] == PROVISIONAL_END[13..] =>
            {
                End::Unfinished
            }
            Some(_) => End::Finished {
                summary_damage: None,
            },
            None => {
                let rest = &self.buf[self.at..];
                if rest.len() >= magic.len() && rest.ends_with(magic) {
                    return Err(ScanError::Record {
                        offset: self.offset,
                        opcode: rest[0],
                        reason: format!(
                            "the record runs past the end of the file ({} bytes left), which \
                             ends with the end magic: damaged, not cut short",
                            rest.len()
                        ),
                    });
                }
                End::CutShort {
                    offset: self.offset,
                    unreadable_bytes: rest.len(),
                }
            }
        })
    }
}
