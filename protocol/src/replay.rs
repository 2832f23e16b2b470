//! The replay double: a node that plays back its recorded messages in step with the coupler.
//!
//! [`Script::from_mcap`] reads, from the bytes of a record, the two channels between the coupler
//! and one node, in record order. [`play`] walks that script: a recorded node → coupler frame is
//! sent as it was; a recorded coupler → node frame must be matched by what the coupler sends now
//! (same kind, step and iteration), otherwise the double stops with a clear error naming what was
//! asked and what the record holds. The coupler cannot tell it from the real node.

use std::time::Duration;

use crate::codec;
use crate::mcap_read::{self, End, Mode, ScanError};
use crate::topics;
use crate::transport::{Transport, TransportError};
use crate::wire::{Failure, Message, MessageKind, NodeKind, Stamp};

/// Which way a recorded frame went.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Direction {
    /// Node → coupler.
    FromNode,
    /// Coupler → node.
    ToNode,
}

/// One node's recorded frames in order.
#[derive(Clone, Debug, Default)]
pub struct Script {
    /// The frames, in record order.
    pub frames: Vec<(Direction, Vec<u8>)>,
    /// Whether the record ended early (a killed run).
    pub truncated: bool,
}

/// Why a record cannot be replayed.
#[derive(Debug, thiserror::Error)]
pub enum ReplayError {
    /// The bytes are not a readable MCAP record (damage is named by chunk and offset). Not a
    /// `source`: the message already holds it, and error chains would print it twice.
    #[error("not a readable MCAP record: {0}")]
    Mcap(ScanError),
    /// The record was written with an older layout (topic names, log-time convention).
    #[error("{0}")]
    Layout(String),
    /// The record holds nothing for this node.
    #[error(
        "the record holds no messages of the {0} node (was it recorded with record = \"exchange\" or \"all\"?)"
    )]
    Empty(NodeKind),
    /// The coupler asked for something the record does not hold.
    #[error("replay double ({node}): {what}")]
    Mismatch {
        /// The replayed node.
        node: NodeKind,
        /// What differs.
        what: String,
    },
    /// A transport failure.
    #[error(transparent)]
    Transport(#[from] TransportError),
}

impl From<ScanError> for ReplayError {
    fn from(err: ScanError) -> Self {
        ReplayError::Mcap(err)
    }
}

impl Script {
    /// Reads the frames exchanged with `node` from MCAP bytes (complete or truncated).
    pub fn from_mcap(bytes: &[u8], node: NodeKind) -> Result<Script, ReplayError> {
        let from_topic = topics::frame(node, NodeKind::Coupler).unwrap_or_default();
        let to_topic = topics::frame(NodeKind::Coupler, node).unwrap_or_default();
        let checkpoint_topic = topics::checkpoint(node);
        // NOTE: a bounded, CRC-checked read: a damaged record is an error naming the chunk and
        // offset, never a panic or a huge allocation (the mcap crate's MessageStream has no
        // limit on the lengths inside a chunk).
        let scan = mcap_read::scan(bytes, Mode::Strict)?;
        let version = scan
            .metadata
            .iter()
            .find(|(name, _)| name == "run")
            .and_then(|(_, run)| run.get("protocol_version"))
            .map(String::as_str);
        if let Some(why) =
            topics::legacy_layout(scan.channels.values().map(|c| c.topic.as_str()), version)
        {
            return Err(ReplayError::Layout(why));
        }
        let mut script = Script {
            frames: Vec::new(),
            truncated: !matches!(scan.end, End::Finished { .. }),
        };
        for msg in scan.messages {
            let topic = &scan.channels[&msg.channel_id].topic;
            let dir = if topic == from_topic || topic == checkpoint_topic {
                Direction::FromNode
            } else if topic == to_topic {
                Direction::ToNode
            } else {
                continue;
            };
            script.frames.push((dir, msg.data));
        }
        if script.frames.is_empty() {
            return Err(ReplayError::Empty(node));
        }
        Ok(script)
    }
}

fn describe(frame: &[u8]) -> String {
    match codec::decode_header(frame) {
        Ok(h) => format!(
            "{:?} step {} iteration {}",
            h.kind, h.stamp.step, h.stamp.iteration
        ),
        Err(e) => format!("an undecodable frame ({e})"),
    }
}

/// Plays `script` as node `me` over `transport`; returns when the coupler says shutdown or the
/// script ends with the coupler's shutdown. A script that cannot go on (the record ends, or the
/// coupler asks for something else) is reported to the coupler as this node's failure, so the
/// run's status says why, before the error ends the node.
pub fn play(
    transport: &mut dyn Transport,
    script: &Script,
    timeout: Duration,
) -> Result<(), ReplayError> {
    let mut stamp = Stamp::step(0);
    let played = play_frames(transport, script, timeout, &mut stamp);
    if let Err(err @ ReplayError::Mismatch { .. }) = &played {
        let failure = Message::Failure(Failure {
            stamp,
            node: transport.me(),
            report: err.to_string(),
        });
        let _ = transport.send(NodeKind::Coupler, &codec::encode(transport.me(), &failure));
    }
    played
}

/// [`play`] without the report; `stamp` follows the frames played.
fn play_frames(
    transport: &mut dyn Transport,
    script: &Script,
    timeout: Duration,
    stamp: &mut Stamp,
) -> Result<(), ReplayError> {
    let me = transport.me();
    for (dir, frame) in &script.frames {
        if let Ok(head) = codec::decode_header(frame) {
            *stamp = head.stamp;
        }
        match dir {
            Direction::FromNode => transport.send(NodeKind::Coupler, frame)?,
            Direction::ToNode => {
                let (_, got) = transport.recv(Some(NodeKind::Coupler), timeout)?;
                let want = codec::decode_header(frame).map_err(|e| ReplayError::Mismatch {
                    node: me,
                    what: format!("recorded frame does not decode: {e}"),
                })?;
                let head = codec::decode_header(&got).map_err(|e| ReplayError::Mismatch {
                    node: me,
                    what: format!("the coupler sent a frame that does not decode: {e}"),
                })?;
                if head.kind == MessageKind::Shutdown {
                    return Ok(());
                }
                if (head.kind, head.stamp) != (want.kind, want.stamp) {
                    return Err(ReplayError::Mismatch {
                        node: me,
                        what: format!(
                            "the coupler sent {} but the record holds {} at this point",
                            describe(&got),
                            describe(frame)
                        ),
                    });
                }
            }
        }
    }
    // The script is over. If it ends on a coupler → node frame, the coupler now waits for an
    // answer the record does not hold: say so at once instead of waiting out the deadline.
    // A record cut short (a killed run) holds nothing more either, and the coupler may be waiting
    // for this node's next message: stop now too.
    if let Some((dir, last)) = script.frames.last()
        && (script.truncated || *dir == Direction::ToNode)
        && codec::decode_header(last).is_ok_and(|h| h.kind != MessageKind::Shutdown)
    {
        return Err(ReplayError::Mismatch {
            node: me,
            what: format!(
                "the record ends after {}: nothing more to replay, after the end of the record{}",
                describe(last),
                if script.truncated {
                    " (the record was cut short)"
                } else {
                    ""
                }
            ),
        });
    }
    // Otherwise only a shutdown may follow.
    let (_, got) = transport.recv(Some(NodeKind::Coupler), timeout)?;
    match codec::decode(&got) {
        Ok((_, Message::Shutdown(_))) => Ok(()),
        _ => Err(ReplayError::Mismatch {
            node: me,
            what: format!(
                "the coupler asked for {} after the end of the record{}",
                describe(&got),
                if script.truncated {
                    " (the record was cut short)"
                } else {
                    ""
                }
            ),
        }),
    }
}
