//! Frame codec: every `Message` variant round-trips bit for bit, a frame of another protocol
//! version is refused naming both versions, and truncated or random bytes give errors, never
//! panics.

use proptest::prelude::*;
use protocol::codec::{self, DecodeError, HEADER_LEN};
use protocol::wire::*;

fn surface() -> WetSurface {
    WetSurface {
        revision: 3,
        dim: 2,
        vertices: vec![0.0, 0.0, 1.0, 0.0, 1.0, 1.0],
        elements: vec![0, 1, 1, 2],
        element_particle: vec![0, 0],
        wet: vec![true, false],
    }
}

/// One message of every kind, with non-trivial values (NaN-free so `==` holds).
fn every_message() -> Vec<Message> {
    let stamp = Stamp {
        step: 7,
        iteration: 2,
    };
    vec![
        Message::Hello(Hello {
            node: NodeKind::Fluid,
            protocol_version: PROTOCOL_VERSION,
            scene_hash: 0xDEAD_BEEF_0123_4567,
            implementation: "real".into(),
            capabilities: vec!["checkpoint".into(), "fracture".into()],
        }),
        Message::Welcome(Welcome {
            accepted: false,
            reason: "scene hash 1 differs from 2".into(),
        }),
        Message::DtProposal(DtProposal {
            stamp,
            dt_max: f64::INFINITY,
            limiter: "cfl".into(),
        }),
        Message::StepPlan(StepPlan {
            stamp,
            t: 0.125,
            dt: 1e-4,
            scheme: Scheme::SemiImplicit,
            output: Some(3),
            predicted: true,
        }),
        Message::InterfaceLoads(InterfaceLoads {
            stamp,
            dim: 3,
            force: vec![1.0, -2.5, 3.25, 1e-300, -0.0, 6.0],
            torque: vec![0.5, 0.25, -0.125, 0.0, 1.0, 2.0],
            particles: Vec::new(),
        }),
        Message::SolidState(SolidState {
            stamp,
            dim: 2,
            position: vec![0.1, 0.2],
            orientation: vec![0.3],
            velocity: vec![-1.0, 2.0],
            angular_velocity: vec![0.7],
            diameter: vec![0.05],
            surface: surface(),
            particles: Vec::new(),
            changed_only: false,
        }),
        Message::FixedPointDecision(FixedPointDecision {
            stamp,
            residual: 3.5e-13,
            decision: Decision::Accept,
        }),
        Message::ConservedTotals(ConservedTotals {
            stamp,
            node: NodeKind::Solid,
            t: 1.5,
            mass: 2.0,
            momentum: vec![0.1, 0.2, 0.3],
            energy: 10.0,
            dissipated: 0.5,
            interface_work: -0.25,
            interface_impulse: vec![0.01, 0.02, 0.03],
            boundary_mass_out: 0.0,
            boundary_energy_out: 1e-9,
            links_broken: 12,
            broken_pairs: vec![3, 4, 0, 49],
            broken_substeps: vec![1, 4],
            swept_mass: 0.25,
            vacuum_cells: 7,
            kinetic: 3.5,
            energy_scale: 11.0,
        }),
        Message::CheckpointRequest(CheckpointRequest { stamp }),
        Message::Checkpoint(Checkpoint {
            stamp,
            node: NodeKind::Fluid,
            bytes: (0..=255u8).collect(),
        }),
        Message::Shutdown(Shutdown {
            stamp,
            reason: ShutdownReason::Failure("fluid node is gone".into()),
        }),
        Message::Failure(Failure {
            stamp,
            node: NodeKind::Fluid,
            report: "negative density -1e-3 in cell (4, 5, 6)".into(),
        }),
    ]
}

#[test]
fn every_message_kind_round_trips() {
    let messages = every_message();
    let mut kinds: Vec<MessageKind> = messages.iter().map(Message::kind).collect();
    kinds.dedup();
    assert_eq!(
        kinds,
        MessageKind::ALL.to_vec(),
        "one message per kind, in order"
    );
    for msg in messages {
        for sender in [NodeKind::Coupler, NodeKind::Fluid, NodeKind::Solid] {
            let frame = codec::encode(sender, &msg);
            let (header, back) = codec::decode(&frame).expect("decodes");
            assert_eq!(back, msg);
            assert_eq!(header.kind, msg.kind());
            assert_eq!(header.sender, sender);
            assert_eq!(header.version, PROTOCOL_VERSION);
            assert_eq!(header.stamp, msg.stamp());
            // Same message, same bytes.
            assert_eq!(codec::encode(sender, &back), frame);
        }
    }
}

#[test]
fn encode_into_reuses_the_buffer_and_matches_encode() {
    let mut buf = vec![0xAA; 3];
    for msg in every_message() {
        codec::encode_into(NodeKind::Solid, &msg, &mut buf);
        assert_eq!(buf, codec::encode(NodeKind::Solid, &msg));
    }
}

#[test]
fn another_version_is_refused_naming_both_versions() {
    let mut frame = codec::encode(
        NodeKind::Fluid,
        &Message::CheckpointRequest(CheckpointRequest {
            stamp: Stamp::step(1),
        }),
    );
    let other = PROTOCOL_VERSION + 1;
    frame[4..8].copy_from_slice(&other.to_le_bytes());
    let err = codec::decode(&frame).unwrap_err();
    assert_eq!(
        err,
        DecodeError::VersionMismatch {
            expected: PROTOCOL_VERSION,
            got: other
        }
    );
    let text = err.to_string();
    assert!(
        text.contains(&format!("version {PROTOCOL_VERSION}"))
            && text.contains(&format!("version {other}")),
        "{text}"
    );
}

#[test]
fn truncated_frames_are_errors() {
    for msg in every_message() {
        let frame = codec::encode(NodeKind::Coupler, &msg);
        for cut in 0..frame.len() {
            let res = codec::decode(&frame[..cut]);
            assert!(res.is_err(), "{:?} cut at {cut} decoded", msg.kind());
            if cut < HEADER_LEN {
                assert_eq!(res.unwrap_err(), DecodeError::TooShort { len: cut });
            }
        }
        let mut longer = frame.clone();
        longer.push(0);
        assert!(matches!(
            codec::decode(&longer),
            Err(DecodeError::Inconsistent { trailing: 1, .. })
        ));
    }
}

#[test]
fn bad_magic_kind_and_sender_are_named() {
    let frame = codec::encode(NodeKind::Fluid, &every_message()[0]);
    let mut bad = frame.clone();
    bad[0] = b'X';
    assert!(matches!(
        codec::decode(&bad),
        Err(DecodeError::BadMagic { .. })
    ));
    let mut bad = frame.clone();
    bad[8..10].copy_from_slice(&999u16.to_le_bytes());
    assert_eq!(
        codec::decode(&bad).unwrap_err(),
        DecodeError::UnknownKind { code: 999 }
    );
    let mut bad = frame.clone();
    bad[10] = 9;
    assert_eq!(
        codec::decode(&bad).unwrap_err(),
        DecodeError::UnknownSender { code: 9 }
    );
    // A header that names another kind than the payload holds.
    let mut bad = frame;
    bad[8..10].copy_from_slice(&(MessageKind::Welcome as u16).to_le_bytes());
    assert!(codec::decode(&bad).is_err());
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

    #[test]
    fn decoding_random_bytes_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..256)) {
        let _ = codec::decode(&bytes);
    }

    #[test]
    fn decoding_a_valid_header_with_random_payload_never_panics(
        kind in 1u16..=12,
        payload in proptest::collection::vec(any::<u8>(), 0..256),
    ) {
        let mut frame = codec::encode(NodeKind::Fluid, &every_message()[0]);
        frame.truncate(HEADER_LEN);
        frame[8..10].copy_from_slice(&kind.to_le_bytes());
        frame.extend_from_slice(&payload);
        let _ = codec::decode(&frame);
    }

    #[test]
    fn corrupting_one_byte_of_a_valid_frame_never_panics(
        which in 0usize..12, pos in any::<prop::sample::Index>(), value in any::<u8>(),
    ) {
        let mut frame = codec::encode(NodeKind::Solid, &every_message()[which]);
        let i = pos.index(frame.len());
        frame[i] = value;
        let _ = codec::decode(&frame);
    }
}

/// `Checkpoint` as it was declared before its bytes went through serde's bytes methods: a plain
/// `Vec<u8>`, which serde encodes one `u8` at a time.
#[derive(serde::Serialize, serde::Deserialize)]
struct CheckpointAsSequence {
    stamp: Stamp,
    node: NodeKind,
    bytes: Vec<u8>,
}

proptest! {
    /// A checkpoint's bytes copied whole are the same wire bytes as the sequence of `u8` they
    /// were encoded as before, both ways: the protocol did not change, and records written
    /// before read as they did.
    #[test]
    fn checkpoint_bytes_encode_as_the_sequence_of_u8_they_were(
        bytes in proptest::collection::vec(any::<u8>(), 0..600),
        step in any::<u64>(),
    ) {
        let stamp = Stamp { step, iteration: 0 };
        let now = Checkpoint { stamp, node: NodeKind::Solid, bytes: bytes.clone() };
        let before = CheckpointAsSequence { stamp, node: NodeKind::Solid, bytes };
        let wire = codec::encode_blob(&now);
        prop_assert_eq!(&wire, &codec::encode_blob(&before));
        let back: Checkpoint = codec::decode_blob(&wire).expect("decodes");
        prop_assert_eq!(back, now);
        let frame = codec::encode(NodeKind::Fluid, &Message::Checkpoint(Checkpoint {
            stamp,
            node: NodeKind::Fluid,
            bytes: before.bytes.clone(),
        }));
        let (_, msg) = codec::decode(&frame).expect("a frame decodes");
        prop_assert!(matches!(msg, Message::Checkpoint(c) if c.bytes == before.bytes));
    }
}
