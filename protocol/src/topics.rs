//! Topic names of the MCAP record, shared by the coupler (which writes it) and the replay
//! doubles (which read it), and how a message's coupling step is found in its payload.
//!
//! Record layout 2 (this one): topics are `/`-rooted (`/fluid-to-coupler`, `/checkpoint/fluid`,
//! `/diagnostics`, ...), log time is the simulated time in nanoseconds and publish time the
//! wall clock. The coupling step is in every payload: bytes 12..20 of a frame's header, and the
//! `step` key of a diagnostics object. Layout 1 (records written before it) named topics without
//! the leading `/` and put the step in the log time; its frames are also of an older protocol
//! version, so it is refused with [`legacy_layout`] rather than misread.

use crate::wire::NodeKind;

/// Version of the record layout (topic names, log-time convention), stored in the record's
/// `run` metadata under the key `record_layout`.
pub const RECORD_LAYOUT: u32 = 2;

/// Topic of the diagnostics JSON channel.
pub const DIAGNOSTICS: &str = "/diagnostics";

/// Topic of a bus link (`/fluid-to-coupler` ...), `None` for a pair that is not a link of the
/// star.
pub fn frame(from: NodeKind, to: NodeKind) -> Option<&'static str> {
    match (from, to) {
        (NodeKind::Fluid, NodeKind::Coupler) => Some("/fluid-to-coupler"),
        (NodeKind::Coupler, NodeKind::Fluid) => Some("/coupler-to-fluid"),
        (NodeKind::Solid, NodeKind::Coupler) => Some("/solid-to-coupler"),
        (NodeKind::Coupler, NodeKind::Solid) => Some("/coupler-to-solid"),
        _ => None,
    }
}

/// Topic of a node's (or the coupler's own) checkpoints.
pub fn checkpoint(node: NodeKind) -> &'static str {
    match node {
        NodeKind::Fluid => "/checkpoint/fluid",
        NodeKind::Solid => "/checkpoint/solid",
        NodeKind::Coupler => "/checkpoint/coupler",
    }
}

/// The log time of a message at simulated time `t` \[s\]: `t` in nanoseconds, rounded to the
/// nearest (negative or non-finite times give 0). A pure function of `t`, so deterministic.
pub fn log_time(t: f64) -> u64 {
    if t.is_finite() && t > 0.0 {
        // `as` saturates past u64::MAX (584 years of simulated time).
        (t * 1e9).round() as u64
    } else {
        0
    }
}

/// The coupling step of a recorded frame, read from its header (any protocol version: the
/// header layout has not changed); `None` when the bytes are too short to be a frame.
pub fn frame_step(frame: &[u8]) -> Option<u64> {
    let bytes: [u8; 8] = frame.get(12..20)?.try_into().ok()?;
    Some(u64::from_le_bytes(bytes))
}

/// When `topics` are those of a layout-1 record (no leading `/`), the error to give: which
/// layout and protocol version wrote it and what to do.
pub fn legacy_layout<'a>(
    topics: impl IntoIterator<Item = &'a str>,
    protocol_version: Option<&str>,
) -> Option<String> {
    let old = topics.into_iter().find(|t| {
        matches!(
            *t,
            "fluid-to-coupler"
                | "coupler-to-fluid"
                | "solid-to-coupler"
                | "coupler-to-solid"
                | "checkpoint/fluid"
                | "checkpoint/solid"
                | "checkpoint/coupler"
                | "diagnostics"
        )
    })?;
    Some(format!(
        "the record has layout 1 (topic {old:?} without the leading '/', log time = step; written \
         with protocol version {}); this build reads record layout {RECORD_LAYOUT} and protocol \
         version {}: run the scene again to record it, or read it with the build that wrote it",
        protocol_version.unwrap_or("unknown"),
        crate::PROTOCOL_VERSION
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_time_is_nanoseconds_of_simulated_time() {
        assert_eq!(log_time(0.0), 0);
        assert_eq!(log_time(1.5e-3), 1_500_000);
        assert_eq!(log_time(2.0), 2_000_000_000);
        assert_eq!(log_time(-1.0), 0);
        assert_eq!(log_time(f64::NAN), 0);
    }

    #[test]
    fn every_topic_is_rooted_and_old_names_are_recognised() {
        let nodes = [NodeKind::Fluid, NodeKind::Solid, NodeKind::Coupler];
        let mut topics = vec![DIAGNOSTICS];
        for a in nodes {
            topics.push(checkpoint(a));
            for b in nodes {
                topics.extend(frame(a, b));
            }
        }
        assert_eq!(topics.len(), 8);
        assert!(topics.iter().all(|t| t.starts_with('/')));
        assert_eq!(legacy_layout(topics.iter().copied(), None), None);
        let old: Vec<&str> = topics.iter().map(|t| &t[1..]).collect();
        let err = legacy_layout(old, Some("2")).expect("layout 1 is recognised");
        assert!(
            err.contains("layout 1") && err.contains("protocol version 2"),
            "{err}"
        );
    }
}
