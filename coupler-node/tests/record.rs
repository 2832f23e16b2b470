//! MCAP record: frames read back byte for byte with their channels, schemas and encodings;
//! record levels; files cut short after a step read up to that step and recover into complete
//! files; garbage is an error; the same run records the same bytes; inspection tables and
//! exports.

use std::cell::RefCell;
use std::io::{Cursor, Seek, SeekFrom, Write};
use std::rc::Rc;

use coupler_node::inspect::{ExportFormat, export_step, list_steps};
use coupler_node::record::{
    DIAGNOSTICS_TOPIC, Diagnostics, RecordError, Recorder, Recording, read_recording, recover,
};
use proptest::prelude::*;
use protocol::codec;
use protocol::scene::RecordLevel;
use protocol::wire::*;

const SCENE: &str = "[run]\nt_end = 0.01\n";

fn loads(step: u64, iteration: u32, n: usize) -> Message {
    Message::InterfaceLoads(InterfaceLoads {
        stamp: Stamp { step, iteration },
        dim: 3,
        force: (0..3 * n).map(|i| i as f64 * 0.5 + step as f64).collect(),
        torque: (0..3 * n).map(|i| -(i as f64)).collect(),
    })
}

fn solid_state(step: u64, iteration: u32) -> Message {
    Message::SolidState(SolidState {
        stamp: Stamp { step, iteration },
        dim: 2,
        position: vec![1.0, 2.0 + step as f64],
        orientation: vec![0.1],
        velocity: vec![0.5, -0.5],
        angular_velocity: vec![0.0],
        diameter: vec![0.1],
        surface: WetSurface {
            revision: 1,
            dim: 2,
            vertices: vec![0.0, 0.0, 1.0, 0.0],
            elements: vec![0, 1],
            element_particle: vec![0],
            wet: vec![true],
        },
    })
}

/// What the coupler does in one step: plan, iterations of loads / state / decision,
/// totals, diagnostics. Returns every (from, to, frame) it recorded, in order.
fn record_step<W: Write + Seek>(
    rec: &mut Recorder<W>,
    step: u64,
) -> Vec<(NodeKind, NodeKind, Vec<u8>)> {
    let mut frames = Vec::new();
    let plan = Message::StepPlan(StepPlan {
        stamp: Stamp::step(step),
        t: step as f64 * 1e-3,
        dt: 1e-3,
        scheme: Scheme::SemiImplicit,
        output: None,
        predicted: false,
    });
    frames.push((
        NodeKind::Coupler,
        NodeKind::Fluid,
        codec::encode(NodeKind::Coupler, &plan),
    ));
    frames.push((
        NodeKind::Coupler,
        NodeKind::Solid,
        codec::encode(NodeKind::Coupler, &plan),
    ));
    let mut residuals = Vec::new();
    for iteration in 0..2u32 {
        frames.push((
            NodeKind::Fluid,
            NodeKind::Coupler,
            codec::encode(NodeKind::Fluid, &loads(step, iteration, 4)),
        ));
        frames.push((
            NodeKind::Solid,
            NodeKind::Coupler,
            codec::encode(NodeKind::Solid, &solid_state(step, iteration)),
        ));
        let residual = 10f64.powi(-3 - 6 * iteration as i32);
        residuals.push(residual);
        let decision = Message::FixedPointDecision(FixedPointDecision {
            stamp: Stamp { step, iteration },
            residual,
            decision: if iteration == 1 {
                Decision::Accept
            } else {
                Decision::Iterate
            },
        });
        frames.push((
            NodeKind::Coupler,
            NodeKind::Fluid,
            codec::encode(NodeKind::Coupler, &decision),
        ));
    }
    for (from, to, frame) in &frames {
        rec.record_frame(*from, *to, step, 1_700_000_000_000_000_000 + step, frame)
            .unwrap();
    }
    if step.is_multiple_of(2) {
        let cp = Message::Checkpoint(Checkpoint {
            stamp: Stamp::step(step),
            node: NodeKind::Fluid,
            bytes: vec![7; 100],
        });
        rec.record_checkpoint(
            NodeKind::Fluid,
            step,
            0,
            &codec::encode(NodeKind::Fluid, &cp),
        )
        .unwrap();
    }
    let diag = Diagnostics {
        step,
        t: (step + 1) as f64 * 1e-3,
        dt: 1e-3,
        iterations: 2,
        residuals,
        converged: true,
        ledger: [
            ("mass_rel_err".to_string(), 1e-15),
            ("fluid_mass".to_string(), 1.5),
        ]
        .into_iter()
        .collect(),
        ..Diagnostics::default()
    };
    rec.record_diagnostics(step, 0, &serde_json::to_vec(&diag).unwrap())
        .unwrap();
    frames
}

/// A `Write + Seek` whose bytes the test can look at while the recorder owns it.
#[derive(Clone, Default)]
struct Shared(Rc<RefCell<Cursor<Vec<u8>>>>);

impl Write for Shared {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.borrow_mut().write(buf)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

impl Seek for Shared {
    fn seek(&mut self, pos: SeekFrom) -> std::io::Result<u64> {
        self.0.borrow_mut().seek(pos)
    }
}

type Frames = Vec<Vec<(NodeKind, NodeKind, Vec<u8>)>>;

/// Records `n_steps` steps and returns the bytes, the recorded frames per step and the file
/// length after every `end_step` (what a kill right then would leave on disk).
fn record_run(n_steps: u64, level: RecordLevel) -> (Vec<u8>, Frames, Vec<usize>) {
    let shared = Shared::default();
    let mut rec = Recorder::new(shared.clone(), level, "unit-scene", SCENE).unwrap();
    let mut per_step = Vec::new();
    let mut ends = Vec::new();
    for step in 0..n_steps {
        per_step.push(record_step(&mut rec, step));
        rec.end_step().unwrap();
        ends.push(shared.0.borrow().get_ref().len());
    }
    drop(rec.finish().unwrap());
    let bytes = shared.0.borrow().get_ref().clone();
    (bytes, per_step, ends)
}

fn frame_topic(from: NodeKind, to: NodeKind) -> String {
    format!("{from}-to-{to}")
}

#[test]
fn frames_read_back_byte_identical_with_channels_and_metadata() {
    let (bytes, per_step, _) = record_run(3, RecordLevel::Exchange);
    let rec = read_recording(&bytes).unwrap();
    assert!(!rec.truncated);
    assert_eq!(rec.unreadable_bytes, 0);
    let frames: Vec<_> = rec
        .messages
        .iter()
        .filter(|m| m.topic.contains("-to-"))
        .collect();
    let expected: Vec<_> = per_step.iter().flatten().collect();
    assert_eq!(frames.len(), expected.len());
    for (got, (from, to, frame)) in frames.iter().zip(&expected) {
        assert_eq!(got.topic, frame_topic(*from, *to));
        assert_eq!(&got.data, frame);
        let (header, _) = codec::decode(&got.data).unwrap();
        assert_eq!(got.log_time, header.stamp.step);
    }
    // Sequence numbers count per channel from 0.
    let seqs: Vec<u32> = rec.topic("coupler-to-fluid").map(|m| m.sequence).collect();
    assert_eq!(seqs, (0..seqs.len() as u32).collect::<Vec<_>>());
    assert_eq!(rec.topic("checkpoint/fluid").count(), 2);
    assert_eq!(rec.topic(DIAGNOSTICS_TOPIC).count(), 3);
    assert_eq!(rec.metadata["scene"]["toml"], SCENE);
    assert_eq!(rec.metadata["scene"]["name"], "unit-scene");
    assert_eq!(
        rec.metadata["run"]["protocol_version"],
        PROTOCOL_VERSION.to_string()
    );

    // The mcap crate's own readers agree: summary, channels, schemas, encodings.
    let summary = mcap::Summary::read(&bytes).unwrap().expect("summary");
    assert_eq!(
        summary.stats.as_ref().unwrap().message_count,
        rec.messages.len() as u64
    );
    for channel in summary.channels.values() {
        let schema = channel.schema.as_ref().expect("every channel has a schema");
        if channel.topic == DIAGNOSTICS_TOPIC {
            assert_eq!(channel.message_encoding, "json");
            assert_eq!(schema.encoding, "jsonschema");
            let _: serde_json::Value = serde_json::from_slice(&schema.data).unwrap();
        } else {
            assert_eq!(channel.message_encoding, "bincode");
            assert_eq!(schema.name, "protocol::wire::Message");
            assert!(
                String::from_utf8_lossy(&schema.data)
                    .contains(&format!("protocol version {PROTOCOL_VERSION}"))
            );
        }
    }
    let streamed = mcap::MessageStream::new(&bytes).unwrap().count();
    assert_eq!(streamed, rec.messages.len());
}

/// Writes a complete and a cut sample recording into `$COSIM_RECORD_SAMPLE_DIR` (when set) for
/// `tests/py/check_mcap.py`.
#[test]
fn write_samples_for_the_python_check() {
    let Ok(dir) = std::env::var("COSIM_RECORD_SAMPLE_DIR") else {
        return;
    };
    let (bytes, _, ends) = record_run(5, RecordLevel::Exchange);
    let dir = std::path::Path::new(&dir);
    std::fs::write(dir.join("sample.mcap"), &bytes).unwrap();
    std::fs::write(
        dir.join("sample-cut.mcap"),
        &bytes[..(ends[2] + ends[3]) / 2],
    )
    .unwrap();
    std::fs::write(
        dir.join("sample-recovered.mcap"),
        recover(&bytes[..ends[3] - 5]).unwrap(),
    )
    .unwrap();
}

#[test]
fn same_run_records_the_same_message_bytes() {
    let (a, _, _) = record_run(4, RecordLevel::Exchange);
    let (b, _, _) = record_run(4, RecordLevel::Exchange);
    // Here even publish_time is equal, so the whole file is.
    assert_eq!(a, b);
}

#[test]
fn diagnostics_level_writes_no_frames_and_none_is_refused() {
    let (bytes, _, _) = record_run(3, RecordLevel::Diagnostics);
    let rec = read_recording(&bytes).unwrap();
    assert_eq!(rec.messages.len(), 3);
    assert!(rec.messages.iter().all(|m| m.topic == DIAGNOSTICS_TOPIC));
    let err = Recorder::new(Cursor::new(Vec::new()), RecordLevel::None, "s", SCENE)
        .err()
        .expect("refused");
    assert!(matches!(err, RecordError::Disabled));
    // The recorder writes the same for All and Exchange (All differs in the coupler, which
    // then asks every node for a checkpoint at every step: tests/it/doubles.rs).
    let (all, _, _) = record_run(2, RecordLevel::All);
    let (exchange, _, _) = record_run(2, RecordLevel::Exchange);
    let strip = |r: Recording| r.messages;
    assert_eq!(
        strip(read_recording(&all).unwrap()),
        strip(read_recording(&exchange).unwrap())
    );
}

#[test]
fn a_file_cut_after_a_step_reads_up_to_that_step_and_recovers() {
    let n_steps = 4;
    let (full, per_step, ends) = record_run(n_steps, RecordLevel::Exchange);
    let complete = read_recording(&full).unwrap();
    // The last step is followed by `finish`'s records, not by another step: skip it.
    for (k, pair) in ends.windows(2).enumerate() {
        let (end, next) = (pair[0], pair[1]);
        let steps_done = k as u64 + 1;
        let expected: Vec<_> = complete
            .messages
            .iter()
            .filter(|m| m.log_time < steps_done)
            .cloned()
            .collect();
        let frames_expected: usize = per_step[..=k].iter().map(Vec::len).sum();
        // Cut exactly at the flush point, and a little and a lot into the next step.
        // One byte short of the next flush, the next step's chunk is complete (only its
        // trailing message index is cut), so its messages are readable too.
        let rec = read_recording(&full[..next - 1]).unwrap();
        assert!(rec.truncated);
        assert!(rec.messages.starts_with(&expected));
        for cut in [end, end + 1, end + 20, (end + next) / 2] {
            let rec = read_recording(&full[..cut]).unwrap();
            assert!(rec.truncated, "cut at {cut}");
            assert_eq!(rec.unreadable_bytes, cut - end.min(cut), "cut at {cut}");
            assert_eq!(rec.messages, expected, "cut at {cut} after step {k}");
            assert_eq!(
                rec.messages
                    .iter()
                    .filter(|m| m.topic.contains("-to-"))
                    .count(),
                frames_expected
            );
            assert!(mcap::Summary::read(&full[..cut]).is_err());
            let fixed = recover(&full[..cut]).unwrap();
            let summary = mcap::Summary::read(&fixed).unwrap().expect("summary");
            assert_eq!(summary.stats.unwrap().message_count, expected.len() as u64);
            let again = read_recording(&fixed).unwrap();
            assert!(!again.truncated);
            assert_eq!(again.messages, expected);
            assert_eq!(again.metadata, complete.metadata);
        }
    }
}

#[test]
fn recover_of_a_complete_file_keeps_everything() {
    let (full, _, _) = record_run(2, RecordLevel::Exchange);
    let fixed = recover(&full).unwrap();
    assert_eq!(
        read_recording(&fixed).unwrap(),
        read_recording(&full).unwrap()
    );
}

#[test]
fn garbage_is_an_error() {
    assert!(matches!(
        read_recording(b""),
        Err(RecordError::NotMcap { len: 0 })
    ));
    assert!(matches!(
        read_recording(b"hello world, not mcap"),
        Err(RecordError::NotMcap { .. })
    ));
    assert!(recover(b"\x00\x01").is_err());
    // The magic followed by a complete record of nonsense.
    let mut bad = mcap::MAGIC.to_vec();
    bad.push(0x06); // a chunk
    bad.extend_from_slice(&4u64.to_le_bytes());
    bad.extend_from_slice(&[1, 2, 3, 4]);
    assert!(matches!(
        read_recording(&bad),
        Err(RecordError::Corrupt { .. })
    ));
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

    #[test]
    fn reading_mangled_recordings_never_panics(
        pos in any::<prop::sample::Index>(), value in any::<u8>(), cut in any::<prop::sample::Index>(),
    ) {
        let (mut bytes, _, _) = record_run(1, RecordLevel::Exchange);
        let i = pos.index(bytes.len());
        bytes[i] = value;
        let cut = cut.index(bytes.len() + 1);
        let _ = read_recording(&bytes[..cut]);
        let _ = recover(&bytes[..cut]);
    }

    #[test]
    fn reading_random_bytes_after_the_magic_never_panics(
        tail in proptest::collection::vec(any::<u8>(), 0..512),
    ) {
        let mut bytes = mcap::MAGIC.to_vec();
        bytes.extend_from_slice(&tail);
        let _ = read_recording(&bytes);
    }
}

#[test]
fn list_steps_reads_diagnostics_and_falls_back_to_frames() {
    let (bytes, _, _) = record_run(3, RecordLevel::Exchange);
    let rec = read_recording(&bytes).unwrap();
    let table = list_steps(&rec).unwrap();
    assert!(
        table.lines().next().unwrap().contains("residuals"),
        "{table}"
    );
    assert!(table.contains("1.00e-3 1.00e-9"), "{table}");
    assert!(table.contains("mass_rel_err=1.0"), "{table}");
    assert!(table.contains("3 steps"), "{table}");
    // Without diagnostics, the frames give t, dt and the residuals.
    let frames_only = Recording {
        messages: rec
            .messages
            .iter()
            .filter(|m| m.topic != DIAGNOSTICS_TOPIC)
            .cloned()
            .collect(),
        ..rec.clone()
    };
    let table = list_steps(&frames_only).unwrap();
    assert!(table.contains("1.00e-3 1.00e-9"), "{table}");
    assert!(table.contains("2.000000e-3"), "t of step 2: {table}");
    // Diagnostics with fields missing still list.
    let mut sparse = frames_only.clone();
    sparse.messages.push(coupler_node::record::Recorded {
        topic: DIAGNOSTICS_TOPIC.into(),
        log_time: 9,
        publish_time: 0,
        sequence: 0,
        data: br#"{"step": 9}"#.to_vec(),
    });
    let table = list_steps(&sparse).unwrap();
    assert!(
        table.lines().any(|l| l.trim_start().starts_with("9 ")),
        "{table}"
    );
}

#[test]
fn export_step_dumps_the_exchanged_arrays() {
    let (bytes, _, _) = record_run(2, RecordLevel::Exchange);
    let rec = read_recording(&bytes).unwrap();
    let json = export_step(&rec, 1, ExportFormat::Json).unwrap();
    let doc: serde_json::Value = serde_json::from_str(&json).unwrap();
    let messages = doc["messages"].as_array().unwrap();
    let loads = messages
        .iter()
        .find(|m| m["kind"] == "InterfaceLoads")
        .expect("loads at step 1");
    assert_eq!(loads["fields"]["force"][1], 1.5);
    assert_eq!(loads["topic"], "fluid-to-coupler");
    let state = messages.iter().find(|m| m["kind"] == "SolidState").unwrap();
    assert_eq!(state["fields"]["position"][1], 3.0);
    assert_eq!(state["fields"]["surface"]["vertices"][2], 1.0);
    let csv = export_step(&rec, 1, ExportFormat::Csv).unwrap();
    assert!(
        csv.contains("# topic=fluid-to-coupler sequence=2 kind=InterfaceLoads step=1"),
        "{csv}"
    );
    assert!(
        csv.contains("field,index,value\ndim,0,3\nforce,0,1.0\nforce,1,1.5"),
        "{csv}"
    );
    assert!(csv.contains("surface.vertices,2,1.0"), "{csv}");
    let err = export_step(&rec, 99, ExportFormat::Json).unwrap_err();
    assert!(err.to_string().contains("step 99"), "{err}");
}
