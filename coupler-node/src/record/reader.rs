//! Reading a record back: every message in file order, with how the file ends.

use std::collections::BTreeMap;

use protocol::mcap_read::{self, Dropped, End, Mode, Scan};
use protocol::topics;

use crate::record::channels::DIAGNOSTICS_TOPIC;

/// Topics of the Foxglove channels begin so ([`crate::record::foxglove`]).
pub const FOXGLOVE_PREFIX: &str = "/foxglove/";
use crate::record::error::RecordError;

/// One recorded message.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Recorded {
    /// Topic of its channel.
    pub topic: String,
    /// Coupling step, from the payload (a frame's header, the `step` of a diagnostics object).
    pub step: u64,
    /// Simulated time \[ns\] (frames: the start of their step; diagnostics: its end).
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
/// naming the chunk and byte offset ([`protocol::mcap_read`]), never a panic. A record of the
/// older layout (topics without `/`, written before record layout 2) is refused with
/// [`RecordError::Layout`], naming both versions.
pub fn read_recording(bytes: &[u8]) -> Result<Recording, RecordError> {
    recording(mcap_read::scan(bytes, Mode::Strict)?)
}

pub(crate) fn check_layout(scan: &Scan) -> Result<(), RecordError> {
    let version = scan
        .metadata
        .iter()
        .find(|(name, _)| name == "run")
        .and_then(|(_, run)| run.get("protocol_version"))
        .map(String::as_str);
    match topics::legacy_layout(scan.channels.values().map(|c| c.topic.as_str()), version) {
        Some(why) => Err(RecordError::Layout(why)),
        None => Ok(()),
    }
}

/// The coupling step a message's payload holds.
fn payload_step(topic: &str, data: &[u8], log_time: u64) -> Result<u64, RecordError> {
    #[derive(serde::Deserialize)]
    struct Step {
        step: u64,
    }
    let step = if topic == DIAGNOSTICS_TOPIC {
        serde_json::from_slice::<Step>(data)
            .map(|s| s.step)
            .map_err(|e| format!("no integer \"step\" in the diagnostics object: {e}"))
    } else {
        topics::frame_step(data).ok_or_else(|| {
            format!(
                "{} bytes is too short for a frame (24-byte header)",
                data.len()
            )
        })
    };
    step.map_err(|reason| RecordError::Decode {
        topic: topic.to_string(),
        step: log_time,
        reason: format!("{reason} (log time {log_time} ns)"),
    })
}

/// A scanned message of `channel` as a [`Recorded`] (its step read from the payload); `None`
/// for the Foxglove channels (`/foxglove/...`: views of the output files, not the exchange,
/// and without a step), which the readers here leave out.
pub(crate) fn recorded(
    channel: &mcap_read::ScannedChannel,
    m: mcap_read::ScannedMessage,
) -> Result<Option<Recorded>, RecordError> {
    if channel.topic.starts_with(FOXGLOVE_PREFIX) {
        return Ok(None);
    }
    Ok(Some(Recorded {
        step: payload_step(&channel.topic, &m.data, m.log_time)?,
        topic: channel.topic.clone(),
        log_time: m.log_time,
        publish_time: m.publish_time,
        sequence: m.sequence,
        data: m.data,
    }))
}

pub(crate) fn recording(scan: Scan) -> Result<Recording, RecordError> {
    check_layout(&scan)?;
    let messages = scan
        .messages
        .into_iter()
        .filter_map(|m| recorded(&scan.channels[&m.channel_id], m).transpose())
        .collect::<Result<_, RecordError>>()?;
    Ok(Recording {
        messages,
        metadata: scan.metadata.into_iter().collect(),
        end: scan.end,
        dropped: scan.dropped,
    })
}
