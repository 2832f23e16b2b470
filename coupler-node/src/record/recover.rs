//! `inspect --recover`: keep what verifies, say what was dropped, rewrite it as a complete file.

use std::collections::BTreeMap;
use std::io::Cursor;

use mcap::records::{MessageHeader, Metadata};
use mcap::{Compression, WriteOptions};
use protocol::mcap_read::{self, Dropped, Mode};

use crate::record::error::RecordError;
use crate::record::reader::Recording;
use crate::record::reader::{check_layout, recording};

/// What [`recover`] made.
#[derive(Clone, Debug)]
pub struct Recovered {
    /// A complete MCAP file with summary and footer.
    pub bytes: Vec<u8>,
    /// What it holds (the same as reading `bytes` back).
    pub recording: Recording,
    /// What was left out, and why (chunks that do not verify, bytes skipped to the next chunk
    /// that does, messages whose channel was lost).
    pub dropped: Vec<Dropped>,
}

/// Rewrites a record (finished, from a killed run, or damaged) into a complete one with summary
/// and footer: the same metadata, schemas and channels, and every message of every chunk that
/// verifies. Only bytes that are not MCAP at all are an error.
pub fn recover(bytes: &[u8]) -> Result<Recovered, RecordError> {
    let scan = mcap_read::scan(bytes, Mode::Salvage)?;
    check_layout(&scan)?;
    let mut writer = WriteOptions::new()
        .compression(Some(Compression::Lz4))
        .compression_threads(0)
        .chunk_size(Some(4 << 20))
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
    let dropped = scan.dropped.clone();
    let mut recording = recording(scan)?;
    recording.end = mcap_read::End::Finished {
        summary_damage: None,
    };
    recording.dropped.clear();
    Ok(Recovered {
        bytes: writer.into_inner().into_inner(),
        recording,
        dropped,
    })
}
