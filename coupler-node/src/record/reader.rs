//! Reading a record back: every message in file order, with how the file ends.

use std::collections::BTreeMap;

use protocol::mcap_read::{self, Dropped, End, Mode, Scan};

use crate::record::RecordError;

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
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Recording {
    /// Messages in file order.
    pub messages: Vec<Recorded>,
    /// Metadata records by name.
    pub metadata: BTreeMap<String, BTreeMap<String, String>>,
    /// How the file ends: finished, or a killed run (provisional end, or cut short).
    pub end: End,
    /// What a salvaging read left out (empty for [`read_recording`]).
    pub dropped: Vec<Dropped>,
}

impl Recording {
    /// Messages of one topic, in file order.
    pub fn topic<'a>(&'a self, topic: &'a str) -> impl Iterator<Item = &'a Recorded> + 'a {
        self.messages.iter().filter(move |m| m.topic == topic)
    }

    /// The run did not finish its record (it was killed, or is still running).
    pub fn truncated(&self) -> bool {
        !matches!(self.end, End::Finished { .. })
    }

    /// Bytes after the last complete record (lost; 0 unless the file was cut short).
    pub fn unreadable_bytes(&self) -> usize {
        match self.end {
            End::CutShort {
                unreadable_bytes, ..
            } => unreadable_bytes,
            _ => 0,
        }
    }
}

/// Reads every message in file order. Works on finished files and on the records of killed runs
/// (up to the last completed step, or to where the file was cut); a damaged file is an error
/// naming the chunk and byte offset ([`protocol::mcap_read`]), never a panic.
pub fn read_recording(bytes: &[u8]) -> Result<Recording, RecordError> {
    Ok(recording(mcap_read::scan(bytes, Mode::Strict)?))
}

pub(crate) fn recording(scan: Scan) -> Recording {
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
    Recording {
        messages,
        metadata: scan.metadata.into_iter().collect(),
        end: scan.end,
        dropped: scan.dropped,
    }
}
