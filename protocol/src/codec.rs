//! Framing of messages: a fixed 24-byte header followed by the bincode 2 payload.
//!
//! Header layout (little endian): magic `b"FSI\0"` (4), protocol version `u32` (4), message kind
//! `u16` (2), sender `u8` (1), reserved `u8` (1), step `u64` (8), iteration `u32` (4).
//! The header is read before the payload, so a version mismatch is reported as such, with both
//! versions, instead of as a garbled payload.

use crate::wire::{Message, MessageKind, NodeKind, PROTOCOL_VERSION, Stamp};

/// Magic bytes opening every frame.
pub const MAGIC: [u8; 4] = *b"FSI\0";

/// Size of the header in bytes.
pub const HEADER_LEN: usize = 24;

/// The decoded fixed header of a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Header {
    /// Protocol version of the sender.
    pub version: u32,
    /// Message kind.
    pub kind: MessageKind,
    /// Sender.
    pub sender: NodeKind,
    /// Step and iteration.
    pub stamp: Stamp,
}

/// Why a frame could not be decoded.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum DecodeError {
    /// Fewer bytes than a header.
    #[error("frame too short: {len} bytes, a header needs {HEADER_LEN}")]
    TooShort {
        /// Bytes received.
        len: usize,
    },
    /// The first bytes are not the magic.
    #[error("bad magic {found:02X?} (expected {MAGIC:02X?}): not a co-simulation frame")]
    BadMagic {
        /// The bytes found.
        found: [u8; 4],
    },
    /// The sender speaks another protocol version.
    #[error(
        "protocol version mismatch: this build speaks version {expected}, the peer sent version {got}"
    )]
    VersionMismatch {
        /// Our version.
        expected: u32,
        /// Theirs.
        got: u32,
    },
    /// Unknown message kind code.
    #[error("unknown message kind {code}")]
    UnknownKind {
        /// The code found.
        code: u16,
    },
    /// Unknown sender code.
    #[error("unknown sender code {code}")]
    UnknownSender {
        /// The code found.
        code: u8,
    },
    /// The payload does not decode as the kind announced in the header.
    #[error("payload of {kind:?} does not decode: {reason}")]
    Payload {
        /// Kind announced in the header.
        kind: MessageKind,
        /// bincode's message.
        reason: String,
    },
    /// The payload decodes to another kind than the header says, or leaves bytes unread.
    #[error("header says {header:?} but the payload is {payload:?} ({trailing} trailing bytes)")]
    Inconsistent {
        /// Kind in the header.
        header: MessageKind,
        /// Kind of the decoded payload.
        payload: MessageKind,
        /// Bytes left after the payload.
        trailing: usize,
    },
}

/// Largest number of payload bytes a decode will claim (1 GiB).
///
/// NOTE: without a limit, a corrupt length prefix makes bincode allocate that many bytes
/// up front, which aborts the process (found by the decode-never-panics property test).
pub const MAX_DECODE_LEN: usize = 1 << 30;

/// The decoding configuration: [`bincode_config`] plus the [`MAX_DECODE_LEN`] limit (the limit
/// does not change the encoding).
fn bincode_decode_config() -> impl bincode::config::Config {
    bincode_config().with_limit::<MAX_DECODE_LEN>()
}

fn bincode_config()
-> bincode::config::Configuration<bincode::config::LittleEndian, bincode::config::Fixint> {
    // NOTE: fixed-width little-endian integers: the size of a frame depends only on the array
    // lengths, and f64 arrays are plain copies.
    bincode::config::standard()
        .with_little_endian()
        .with_fixed_int_encoding()
}

/// Encodes `msg` sent by `sender` into a new frame.
pub fn encode(sender: NodeKind, msg: &Message) -> Vec<u8> {
    let mut out = Vec::with_capacity(HEADER_LEN + 64);
    encode_into(sender, msg, &mut out);
    out
}

/// Encodes `msg` into `out` (cleared first), reusing its allocation.
pub fn encode_into(sender: NodeKind, msg: &Message, out: &mut Vec<u8>) {
    out.clear();
    let stamp = msg.stamp();
    out.extend_from_slice(&MAGIC);
    out.extend_from_slice(&PROTOCOL_VERSION.to_le_bytes());
    out.extend_from_slice(&(msg.kind() as u16).to_le_bytes());
    out.push(sender.code());
    out.push(0);
    out.extend_from_slice(&stamp.step.to_le_bytes());
    out.extend_from_slice(&stamp.iteration.to_le_bytes());
    debug_assert_eq!(out.len(), HEADER_LEN);
    bincode::serde::encode_into_std_write(msg, out, bincode_config())
        .expect("encoding into a Vec cannot fail");
}

/// Decodes only the header of a frame (any protocol version).
pub fn decode_header_any_version(frame: &[u8]) -> Result<(u32, Option<Header>), DecodeError> {
    if frame.len() < HEADER_LEN {
        return Err(DecodeError::TooShort { len: frame.len() });
    }
    let magic: [u8; 4] = frame[0..4].try_into().expect("4 bytes");
    if magic != MAGIC {
        return Err(DecodeError::BadMagic { found: magic });
    }
    let version = u32::from_le_bytes(frame[4..8].try_into().expect("4 bytes"));
    if version != PROTOCOL_VERSION {
        return Ok((version, None));
    }
    let code = u16::from_le_bytes(frame[8..10].try_into().expect("2 bytes"));
    let kind = MessageKind::from_code(code).ok_or(DecodeError::UnknownKind { code })?;
    let sender =
        NodeKind::from_code(frame[10]).ok_or(DecodeError::UnknownSender { code: frame[10] })?;
    let step = u64::from_le_bytes(frame[12..20].try_into().expect("8 bytes"));
    let iteration = u32::from_le_bytes(frame[20..24].try_into().expect("4 bytes"));
    Ok((
        version,
        Some(Header {
            version,
            kind,
            sender,
            stamp: Stamp { step, iteration },
        }),
    ))
}

/// Decodes the header of a frame, refusing other protocol versions.
pub fn decode_header(frame: &[u8]) -> Result<Header, DecodeError> {
    match decode_header_any_version(frame)? {
        (_, Some(header)) => Ok(header),
        (got, None) => Err(DecodeError::VersionMismatch {
            expected: PROTOCOL_VERSION,
            got,
        }),
    }
}

/// Decodes a whole frame.
pub fn decode(frame: &[u8]) -> Result<(Header, Message), DecodeError> {
    let header = decode_header(frame)?;
    let (msg, read): (Message, usize) =
        bincode::serde::decode_from_slice(&frame[HEADER_LEN..], bincode_decode_config()).map_err(
            |err| DecodeError::Payload {
                kind: header.kind,
                reason: err.to_string(),
            },
        )?;
    let trailing = frame.len() - HEADER_LEN - read;
    if msg.kind() != header.kind || trailing != 0 {
        return Err(DecodeError::Inconsistent {
            header: header.kind,
            payload: msg.kind(),
            trailing,
        });
    }
    Ok((header, msg))
}

/// Encodes a node-private value (checkpoints) with the same bincode configuration.
pub fn encode_blob<T: serde::Serialize>(value: &T) -> Vec<u8> {
    bincode::serde::encode_to_vec(value, bincode_config()).expect("encoding into a Vec cannot fail")
}

/// Decodes a node-private value written by [`encode_blob`].
pub fn decode_blob<T: serde::de::DeserializeOwned>(bytes: &[u8]) -> Result<T, String> {
    bincode::serde::decode_from_slice(bytes, bincode_decode_config())
        .map(|(v, _)| v)
        .map_err(|e| e.to_string())
}
