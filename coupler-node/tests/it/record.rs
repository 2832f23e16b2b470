//! MCAP record: frames read back byte for byte with their channels, schemas and encodings;
//! record levels; files cut short after a step read up to that step and recover into complete
//! files; garbage is an error; the same run records the same bytes; inspection tables and
//! exports.

use std::cell::RefCell;
use std::io::{Cursor, Seek, SeekFrom, Write};
use std::rc::Rc;

use coupler_node::inspect::{
    ExportFormat, TABLE_HEADER, TableFilter, TableSummary, export_step, export_table, list_steps,
    stream_table,
};
use coupler_node::ledger::LedgerEntry;
use coupler_node::record::{
    DIAGNOSTICS_TOPIC, Diagnostics, RecordError, Recorder, Recording, diagnostics_schema,
    read_recording, recover,
};
use proptest::prelude::*;
use protocol::codec;
use protocol::mcap_read::{End, PROVISIONAL_END, ScanError};
use protocol::scene::{RecordCompression, RecordLevel};
use protocol::wire::*;

mod background;
mod damaged;
mod export;

const SCENE: &str = "[run]\nt_end = 0.01\n";

fn loads(step: u64, iteration: u32, n: usize) -> Message {
    Message::InterfaceLoads(InterfaceLoads {
        stamp: Stamp { step, iteration },
        dim: 3,
        force: (0..3 * n).map(|i| i as f64 * 0.5 + step as f64).collect(),
        torque: (0..3 * n).map(|i| -(i as f64)).collect(),
        particles: Vec::new(),
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
        particles: Vec::new(),
        changed_only: false,
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
        rec.record_frame(
            *from,
            *to,
            step_start(step),
            1_700_000_000_000_000_000 + step,
            frame,
        )
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
            step_start(step),
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
        ledger: Some(LedgerEntry {
            step,
            t: step_start(step + 1),
            mass_rel_err: 1e-15,
            fluid_mass: 1.5,
            ..LedgerEntry::default()
        }),
        ..Diagnostics::default()
    };
    rec.record_diagnostics(step_start(step + 1), 0, &serde_json::to_vec(&diag).unwrap())
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

/// Records `n_steps` steps and returns the bytes, the recorded frames per step and where each
/// step's data end in the finished file (where the next step's chunk starts).
fn record_run(n_steps: u64, level: RecordLevel) -> (Vec<u8>, Frames, Vec<usize>) {
    let (bytes, per_step, snapshots) = record_run_with_snapshots(n_steps, level);
    let ends = snapshots
        .iter()
        .map(|s| s.len() - PROVISIONAL_END.len())
        .collect();
    (bytes, per_step, ends)
}

/// [`record_run`], with the file as it is on disk after every `end_step` (what a kill right
/// then, or at any moment during the next step, leaves).
fn record_run_with_snapshots(n_steps: u64, level: RecordLevel) -> (Vec<u8>, Frames, Vec<Vec<u8>>) {
    record_run_compressed(n_steps, level, RecordCompression::Lz4)
}

/// [`record_run_with_snapshots`] with chunks compressed by `compression`.
fn record_run_compressed(
    n_steps: u64,
    level: RecordLevel,
    compression: RecordCompression,
) -> (Vec<u8>, Frames, Vec<Vec<u8>>) {
    let shared = Shared::default();
    let mut rec = Recorder::new(shared.clone(), level, compression, "unit-scene", SCENE).unwrap();
    let mut per_step = Vec::new();
    let mut snapshots = Vec::new();
    for step in 0..n_steps {
        per_step.push(record_step(&mut rec, step));
        rec.end_step().unwrap();
        snapshots.push(shared.0.borrow().get_ref().clone());
    }
    drop(rec.finish().unwrap());
    let bytes = shared.0.borrow().get_ref().clone();
    (bytes, per_step, snapshots)
}

fn frame_topic(from: NodeKind, to: NodeKind) -> String {
    format!("/{from}-to-{to}")
}

/// Start time of `step` in these records \[s\]: steps of 1 ms.
fn step_start(step: u64) -> f64 {
    step as f64 * 1e-3
}

#[test]
fn frames_read_back_byte_identical_with_channels_and_metadata() {
    let (bytes, per_step, _) = record_run(3, RecordLevel::Exchange);
    let rec = read_recording(&bytes).unwrap();
    assert!(!rec.truncated());
    assert_eq!(rec.unreadable_bytes(), 0);
    assert_eq!(
        rec.end,
        End::Finished {
            summary_damage: None
        }
    );
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
        // The step comes from the payload; the log time is the step's start in ns (1 ms steps).
        assert_eq!(got.step, header.stamp.step);
        assert_eq!(got.log_time, header.stamp.step * 1_000_000);
        assert_eq!(
            got.publish_time,
            1_700_000_000_000_000_000 + header.stamp.step
        );
    }
    // Sequence numbers count per channel from 0.
    let seqs: Vec<u32> = rec.topic("/coupler-to-fluid").map(|m| m.sequence).collect();
    assert_eq!(seqs, (0..seqs.len() as u32).collect::<Vec<_>>());
    assert_eq!(rec.topic("/checkpoint/fluid").count(), 2);
    // Diagnostics: the step from the JSON, the log time the step's end.
    let diag: Vec<(u64, u64)> = rec
        .topic(DIAGNOSTICS_TOPIC)
        .map(|m| (m.step, m.log_time))
        .collect();
    assert_eq!(diag, [(0, 1_000_000), (1, 2_000_000), (2, 3_000_000)]);
    assert!(rec.messages.iter().all(|m| m.topic.starts_with('/')));
    assert_eq!(rec.metadata["run"]["record_layout"], "2");
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
        } else if let Some(view) = channel.topic.strip_prefix("/foxglove/") {
            // Issue 39 item 2: the Foxglove views, last (ids 9 and 10), empty here (no outputs).
            let (id, name) = match view {
                "solid" => (9, "foxglove.SceneUpdate"),
                "fluid" => (10, "foxglove.Grid"),
                other => panic!("unknown view {other}"),
            };
            assert_eq!(channel.id, id);
            assert_eq!(channel.message_encoding, "json");
            assert_eq!(
                (schema.name.as_str(), schema.encoding.as_str()),
                (name, "jsonschema")
            );
            let doc: serde_json::Value = serde_json::from_slice(&schema.data).unwrap();
            assert_eq!(doc["title"], name);
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

/// The Python `mcap` package (`$COSIM_PYTHON`, else a venv made on first use; see
/// `tests/py/python-with-mcap.sh`)
/// reads a finished record, the record of a run killed after step 2 (with `make_reader`, the
/// standard reader, not a salvaging one), a file cut in the middle of step 3 (streaming reader)
/// and a recovered file. Always runs: a missing Python or `mcap` package fails it, loudly.
#[test]
fn python_mcap_reads_finished_killed_cut_and_recovered_records() {
    let (bytes, _, snapshots) = record_run_with_snapshots(5, RecordLevel::Exchange);
    let dir = std::env::temp_dir().join(format!("cosim-record-samples-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let killed = &snapshots[2];
    let cut_at = killed.len() - PROVISIONAL_END.len() + 100;
    let samples = [
        ("sample.mcap", bytes.clone(), vec![]),
        ("sample-killed.mcap", killed.clone(), vec!["--unfinished"]),
        (
            "sample-cut.mcap",
            bytes[..cut_at].to_vec(),
            vec!["--truncated"],
        ),
        (
            "sample-recovered.mcap",
            recover(&bytes[..cut_at]).unwrap().bytes,
            vec![],
        ),
        // Issue 15, item 8: the other values of `run.record_compression`, finished and killed.
        (
            "sample-none.mcap",
            record_run_compressed(5, RecordLevel::Exchange, RecordCompression::None).0,
            vec![],
        ),
        (
            "sample-none-killed.mcap",
            record_run_compressed(5, RecordLevel::Exchange, RecordCompression::None).2[2].clone(),
            vec!["--unfinished"],
        ),
        (
            "sample-zstd.mcap",
            record_run_compressed(5, RecordLevel::Exchange, RecordCompression::Zstd).0,
            vec![],
        ),
    ];
    let py = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/py");
    // `$COSIM_PYTHON`, or a venv with the package made on first use under the target folder.
    let found = std::process::Command::new("sh")
        .arg(py.join("python-with-mcap.sh"))
        .arg(env!("CARGO_TARGET_TMPDIR"))
        .output()
        .expect("sh runs");
    assert!(
        found.status.success(),
        "setting up a Python with the mcap package: {}",
        String::from_utf8_lossy(&found.stderr)
    );
    let python = String::from_utf8_lossy(&found.stdout).trim().to_string();
    let script = py.join("check_mcap.py");
    for (name, data, flags) in samples {
        let path = dir.join(name);
        std::fs::write(&path, &data).unwrap();
        let want = read_recording(&data).unwrap().messages.len();
        let out = std::process::Command::new(&python)
            .arg(&script)
            .arg(&path)
            .args(&flags)
            .output()
            .unwrap_or_else(|e| panic!("running {python}: {e}"));
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success(),
            "{name}: {stdout}{}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(
            stdout.starts_with(&format!("ok {want} messages")),
            "{name}: {stdout}"
        );
    }
    let _ = std::fs::remove_dir_all(dir);
}

/// Issue 15, item 8: `run.record_compression` = none, lz4 and zstd give the same messages
/// (topics, times, sequence numbers, payloads) through [`read_recording`], each chunk says the
/// compression it was written with, and a killed run's file reads up to its last step for each.
#[test]
fn issue_15_each_record_compression_reads_back_the_same_messages() {
    let reference = read_recording(&record_run(3, RecordLevel::Exchange).0).unwrap();
    // The default scene value and the recorder's default agree: zstd (issue 39, a compact
    // record by default).
    assert_eq!(RecordCompression::default(), RecordCompression::Zstd);
    for (compression, name) in [
        (RecordCompression::None, ""),
        (RecordCompression::Lz4, "lz4"),
        (RecordCompression::Zstd, "zstd"),
    ] {
        let (bytes, per_step, snapshots) =
            record_run_compressed(3, RecordLevel::Exchange, compression);
        let rec = read_recording(&bytes).unwrap();
        assert_eq!(
            rec.end,
            End::Finished {
                summary_damage: None
            },
            "{compression:?}"
        );
        assert_eq!(
            rec.messages.len(),
            reference.messages.len(),
            "{compression:?}"
        );
        for (got, want) in rec.messages.iter().zip(&reference.messages) {
            assert_eq!(
                (
                    &got.topic,
                    got.sequence,
                    got.log_time,
                    got.publish_time,
                    &got.data
                ),
                (
                    &want.topic,
                    want.sequence,
                    want.log_time,
                    want.publish_time,
                    &want.data
                ),
                "{compression:?}"
            );
        }
        let frames: Vec<&Vec<u8>> = rec
            .messages
            .iter()
            .filter(|m| m.topic.contains("-to-"))
            .map(|m| &m.data)
            .collect();
        let expected: Vec<&Vec<u8>> = per_step.iter().flatten().map(|(_, _, f)| f).collect();
        assert_eq!(frames, expected, "{compression:?}");
        // Every chunk, read by the mcap crate itself, names the compression.
        let summary = mcap::Summary::read(&bytes).unwrap().expect("summary");
        assert!(!summary.chunk_indexes.is_empty());
        assert!(
            summary.chunk_indexes.iter().all(|c| c.compression == name),
            "{compression:?}: {:?}",
            summary
                .chunk_indexes
                .iter()
                .map(|c| &c.compression)
                .collect::<Vec<_>>()
        );
        // A run killed after step 1 reads up to there.
        let killed = read_recording(&snapshots[1]).unwrap();
        assert_eq!(killed.end, End::Unfinished, "{compression:?}");
        assert_eq!(
            killed.topic(DIAGNOSTICS_TOPIC).count(),
            2,
            "{compression:?}"
        );
    }
    // Uncompressed frames are the largest file. (Which of lz4 and zstd at `--fast=5` is smaller
    // depends on the data: on these frames lz4, 30 009 bytes against 31 035 and 47 375
    // uncompressed; on the record of `clamped-beam-2d` zstd, 34 MB against 53 and 99.)
    let size = |c| record_run_compressed(3, RecordLevel::Exchange, c).0.len();
    let (none, lz4, zstd) = (
        size(RecordCompression::None),
        size(RecordCompression::Lz4),
        size(RecordCompression::Zstd),
    );
    assert!(
        none > lz4 && none > zstd,
        "none {none}, lz4 {lz4}, zstd {zstd}"
    );
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
    let err = Recorder::new(
        Cursor::new(Vec::new()),
        RecordLevel::None,
        RecordCompression::Lz4,
        "s",
        SCENE,
    )
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
            .filter(|m| m.step < steps_done)
            .cloned()
            .collect();
        let frames_expected: usize = per_step[..=k].iter().map(Vec::len).sum();
        // Cut exactly at the flush point, and a little and a lot into the next step.
        // One byte short of the next flush, the next step's chunk is complete (only its
        // trailing message index is cut), so its messages are readable too.
        let rec = read_recording(&full[..next - 1]).unwrap();
        assert!(rec.truncated());
        assert!(rec.messages.starts_with(&expected));
        for cut in [end, end + 1, end + 20, (end + next) / 2] {
            let rec = read_recording(&full[..cut]).unwrap();
            assert!(rec.truncated(), "cut at {cut}");
            assert_eq!(rec.unreadable_bytes(), cut - end.min(cut), "cut at {cut}");
            assert!(
                matches!(rec.end, End::CutShort { offset, .. } if offset == end),
                "cut at {cut}: {:?}",
                rec.end
            );
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
            assert!(fixed.dropped.is_empty(), "{:?}", fixed.dropped);
            let fixed = fixed.bytes;
            let summary = mcap::Summary::read(&fixed).unwrap().expect("summary");
            assert_eq!(summary.stats.unwrap().message_count, expected.len() as u64);
            let again = read_recording(&fixed).unwrap();
            assert!(!again.truncated());
            assert_eq!(again.messages, expected);
            assert_eq!(again.metadata, complete.metadata);
        }
    }
}

#[test]
fn recover_of_a_complete_file_keeps_everything() {
    let (full, _, _) = record_run(2, RecordLevel::Exchange);
    let fixed = recover(&full).unwrap();
    assert!(fixed.dropped.is_empty());
    assert_eq!(fixed.recording, read_recording(&full).unwrap());
    assert_eq!(
        read_recording(&fixed.bytes).unwrap(),
        read_recording(&full).unwrap()
    );
}

#[test]
fn garbage_is_an_error() {
    assert!(matches!(
        read_recording(b""),
        Err(RecordError::Read(ScanError::NotMcap { len: 0 }))
    ));
    assert!(matches!(
        read_recording(b"hello world, not mcap"),
        Err(RecordError::Read(ScanError::NotMcap { .. }))
    ));
    assert!(recover(b"\x00\x01").is_err());
    // The magic followed by a complete record of nonsense.
    let mut bad = mcap::MAGIC.to_vec();
    bad.push(0x06); // a chunk
    bad.extend_from_slice(&4u64.to_le_bytes());
    bad.extend_from_slice(&[1, 2, 3, 4]);
    assert!(matches!(
        read_recording(&bad),
        Err(RecordError::Read(ScanError::Chunk {
            index: 0,
            offset: 8,
            ..
        }))
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
    assert!(table.contains("\n3 steps completed, "), "{table}");
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
        step: 9,
        log_time: 10_000_000,
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
    assert_eq!(loads["topic"], "/fluid-to-coupler");
    let state = messages.iter().find(|m| m["kind"] == "SolidState").unwrap();
    assert_eq!(state["fields"]["position"][1], 3.0);
    assert_eq!(state["fields"]["surface"]["vertices"][2], 1.0);
    let csv = export_step(&rec, 1, ExportFormat::Csv).unwrap();
    assert_eq!(csv, export_table(&rec, Some(1)).unwrap());
    assert!(
        csv.starts_with("step,iteration,channel,field,index,value\n"),
        "{csv}"
    );
    assert!(
        csv.contains("\n1,0,/fluid-to-coupler,dim,0,3\n1,0,/fluid-to-coupler,force,0,1.0\n1,0,/fluid-to-coupler,force,1,1.5\n"),
        "{csv}"
    );
    assert!(
        csv.contains("\n1,1,/solid-to-coupler,surface.vertices,2,1.0\n"),
        "{csv}"
    );
    let err = export_step(&rec, 99, ExportFormat::Json).unwrap_err();
    assert!(err.to_string().contains("step 99"), "{err}");
}

/// Issue 11, item 4: a run killed at any moment between two writes leaves a complete MCAP file
/// without summary, which the mcap crate's standard readers read up to the last completed step
/// (the Python reader: `python_mcap_reads_finished_killed_cut_and_recovered_records`).
#[test]
fn issue_11_a_killed_run_reads_with_standard_readers_up_to_its_last_completed_step() {
    let shared = Shared::default();
    let mut rec = Recorder::new(
        shared.clone(),
        RecordLevel::Exchange,
        RecordCompression::Lz4,
        "unit-scene",
        SCENE,
    )
    .unwrap();
    // Killed before the first step ends: an empty but readable record.
    let empty = shared.0.borrow().get_ref().clone();
    assert_eq!(mcap::MessageStream::new(&empty).unwrap().count(), 0);
    assert_eq!(read_recording(&empty).unwrap().end, End::Unfinished);
    let mut n_expected = 0;
    for step in 0..4 {
        let before = shared.0.borrow().get_ref().clone();
        // Mid-step: the frames are in the open chunk, in memory; the file is as it was.
        let frames = record_step(&mut rec, step);
        assert_eq!(
            *shared.0.borrow().get_ref(),
            before,
            "step {step}: written mid-step"
        );
        rec.end_step().unwrap();
        n_expected += frames.len() + 1 + usize::from(step.is_multiple_of(2));
        let killed = shared.0.borrow().get_ref().clone();
        assert!(killed.ends_with(&PROVISIONAL_END));
        // The mcap crate's strict reader: needs the end magic, refuses a file cut short.
        let streamed: Vec<_> = mcap::MessageStream::new(&killed)
            .unwrap()
            .collect::<Result<_, _>>()
            .unwrap_or_else(|e| panic!("step {step}: {e}"));
        assert_eq!(streamed.len(), n_expected, "step {step}");
        // The last message is the step's diagnostics, at the step's end time (1 ms steps).
        assert_eq!(streamed.last().unwrap().log_time, (step + 1) * 1_000_000);
        assert!(mcap::Summary::read(&killed).unwrap().is_none());
        let ours = read_recording(&killed).unwrap();
        assert_eq!(ours.end, End::Unfinished);
        assert_eq!(ours.messages.len(), n_expected);
        assert_eq!(ours.topic(DIAGNOSTICS_TOPIC).count() as u64, step + 1);
    }
    let done = rec.finish().unwrap();
    let bytes = done.0.borrow().get_ref().clone();
    let finished = read_recording(&bytes).unwrap();
    assert_eq!(
        finished.end,
        End::Finished {
            summary_damage: None
        }
    );
    assert_eq!(finished.messages.len(), n_expected);
    let summary = mcap::Summary::read(&bytes).unwrap().expect("summary");
    assert_eq!(summary.stats.unwrap().message_count, n_expected as u64);
}
