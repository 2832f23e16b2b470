//! MCAP record written on the record's thread ([`Background`]): the same bytes as the recorder
//! called directly.

use std::io::{BufWriter, Read};
use std::sync::{Arc, Condvar, Mutex};
use std::time::Duration;

use coupler_node::record::{Background, MAX_LAG_BYTES, MAX_LAG_STEPS};

use super::*;

/// The calls of a run's steps, on a direct recorder or on the record's thread.
trait Calls {
    fn frame(&mut self, from: NodeKind, to: NodeKind, t: f64, frame: &[u8]);
    fn checkpoint(&mut self, t: f64, frame: &[u8]);
    fn diagnostics(&mut self, t: f64, json: &[u8]);
    fn views(&mut self, dir: &std::path::Path, k: u32, t: f64);
    /// Ends the step; returns the record's committed bytes after it.
    fn end_step(&mut self) -> u64;
}

impl<W: Write + Seek> Calls for Recorder<W> {
    fn frame(&mut self, from: NodeKind, to: NodeKind, t: f64, frame: &[u8]) {
        self.record_frame(from, to, t, 1, frame).unwrap();
    }
    fn checkpoint(&mut self, t: f64, frame: &[u8]) {
        self.record_checkpoint(NodeKind::Fluid, t, 2, frame)
            .unwrap();
    }
    fn diagnostics(&mut self, t: f64, json: &[u8]) {
        self.record_diagnostics(t, 3, json).unwrap();
    }
    fn views(&mut self, dir: &std::path::Path, k: u32, t: f64) {
        self.record_views(dir, k, t, &[[0, 1]]).unwrap();
    }
    fn end_step(&mut self) -> u64 {
        Recorder::end_step(self).unwrap();
        self.committed()
    }
}

impl<W: Write + Seek + Send + 'static> Calls for Background<W> {
    fn frame(&mut self, from: NodeKind, to: NodeKind, t: f64, frame: &[u8]) {
        self.record_frame(from, to, t, 1, frame).unwrap();
    }
    fn checkpoint(&mut self, t: f64, frame: &[u8]) {
        self.record_checkpoint(NodeKind::Fluid, t, 2, frame)
            .unwrap();
    }
    fn diagnostics(&mut self, t: f64, json: &[u8]) {
        self.record_diagnostics(t, 3, json).unwrap();
    }
    fn views(&mut self, dir: &std::path::Path, k: u32, t: f64) {
        self.record_views(dir, k, t, &[[0, 1]]).unwrap();
    }
    fn end_step(&mut self) -> u64 {
        Background::end_step(self).unwrap();
        self.committed()
    }
}

/// `n_steps` steps of loads, states, a checkpoint every other step and diagnostics, and the
/// messages of one more step that does not end. Returns the committed bytes after each step.
fn run(calls: &mut impl Calls, n_steps: u64) -> Vec<u64> {
    let mut committed = Vec::new();
    let views = std::env::temp_dir().join("no-such-output-folder");
    for step in 0..=n_steps {
        let t = step_start(step);
        for iteration in 0..3 {
            let loads = codec::encode(NodeKind::Fluid, &loads(step, iteration, 5000));
            calls.frame(NodeKind::Fluid, NodeKind::Coupler, t, &loads);
            let state = codec::encode(NodeKind::Solid, &solid_state(step, iteration));
            calls.frame(NodeKind::Solid, NodeKind::Coupler, t, &state);
        }
        if step.is_multiple_of(2) {
            let cp = Message::Checkpoint(Checkpoint {
                stamp: Stamp::step(step),
                node: NodeKind::Fluid,
                bytes: vec![step as u8; 100_000],
            });
            calls.checkpoint(t, &codec::encode(NodeKind::Fluid, &cp));
        }
        if step == n_steps {
            break;
        }
        calls.views(&views, step as u32, t);
        calls.diagnostics(t + 1e-3, format!("{{\"step\":{step}}}").as_bytes());
        committed.push(calls.end_step());
    }
    committed
}

/// Issue 39, item 4: the record's thread gets each step whole from the coupler and writes the
/// same bytes as the recorder called directly, the messages of a step that did not end
/// included; held to no lag (as with `run.record_max_bytes`), each step is committed by the
/// time the next one ends.
#[test]
fn the_records_thread_writes_the_bytes_of_the_direct_recorder() {
    for compression in [RecordCompression::None, RecordCompression::Zstd] {
        let mut direct = Recorder::new(
            Cursor::new(Vec::new()),
            RecordLevel::Exchange,
            compression,
            "unit-scene",
            SCENE,
        )
        .unwrap();
        let direct_committed = run(&mut direct, 6);
        let direct = direct.finish().unwrap().into_inner();

        let path = std::env::temp_dir().join(format!(
            "cosim-background-{}-{}.mcap",
            compression.name(),
            std::process::id()
        ));
        let file = std::fs::File::create(&path).unwrap();
        let recorder = Recorder::new(
            BufWriter::new(file),
            RecordLevel::Exchange,
            compression,
            "unit-scene",
            SCENE,
        )
        .unwrap();
        let mut background = Background::start(recorder).max_lag(0, 0);
        let committed = run(&mut background, 6);
        drop(background.finish().unwrap());
        let mut written = Vec::new();
        std::fs::File::open(&path)
            .unwrap()
            .read_to_end(&mut written)
            .unwrap();
        let _ = std::fs::remove_file(&path);
        assert!(
            written == direct,
            "{}: the bytes differ",
            compression.name()
        );
        // Each end of a step returns with the step before it written (at most one in flight).
        for k in 1..committed.len() {
            assert!(
                (direct_committed[k - 1]..=direct_committed[k]).contains(&committed[k]),
                "step {k}: {committed:?} against {direct_committed:?}"
            );
        }
    }
}

/// A file whose writes wait while its gate is shut (a record's thread that cannot keep up).
struct Gated {
    file: std::fs::File,
    open: Arc<(Mutex<bool>, Condvar)>,
}

impl Write for Gated {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let (open, changed) = &*self.open;
        let mut guard = open.lock().unwrap();
        while !*guard {
            guard = changed.wait(guard).unwrap();
        }
        self.file.write(buf)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.file.flush()
    }
}

impl Seek for Gated {
    fn seek(&mut self, pos: SeekFrom) -> std::io::Result<u64> {
        self.file.seek(pos)
    }
}

fn set_gate(gate: &Arc<(Mutex<bool>, Condvar)>, open: bool) {
    *gate.0.lock().unwrap() = open;
    gate.1.notify_all();
}

/// Issue 39, item 4: while the record's thread is stuck in its first write, the coupler hands
/// over `MAX_LAG_STEPS + 1` steps without waiting (it waited at every step's end before, on
/// the run's critical path), all of them in flight; once the thread goes on, the record holds
/// the bytes of the recorder called directly.
#[test]
fn the_coupler_goes_on_while_the_record_falls_behind_within_its_bound() {
    let steps = MAX_LAG_STEPS as u64 + 1;
    let compression = RecordCompression::Zstd;
    let mut direct = Recorder::new(
        Cursor::new(Vec::new()),
        RecordLevel::Exchange,
        compression,
        "unit-scene",
        SCENE,
    )
    .unwrap();
    run(&mut direct, steps);
    let direct = direct.finish().unwrap().into_inner();

    let path = std::env::temp_dir().join(format!("cosim-lag-{}.mcap", std::process::id()));
    let gate = Arc::new((Mutex::new(true), Condvar::new()));
    let file = Gated {
        file: std::fs::File::create(&path).unwrap(),
        open: gate.clone(),
    };
    let recorder = Recorder::new(
        BufWriter::new(file),
        RecordLevel::Exchange,
        compression,
        "unit-scene",
        SCENE,
    )
    .unwrap();
    set_gate(&gate, false);
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let mut background = Background::start(recorder);
        run(&mut background, steps);
        let _ = tx.send(background);
    });
    let handed_over = rx.recv_timeout(Duration::from_secs(60));
    set_gate(&gate, true);
    let background = handed_over.expect("the coupler waited for a record behind within its bound");
    // (The steps here take about 1 MB each, far under MAX_LAG_BYTES.)
    const { assert!(MAX_LAG_BYTES > 32 << 20) };
    assert_eq!(background.in_flight(), MAX_LAG_STEPS + 1);
    drop(background.finish().unwrap());
    let mut written = Vec::new();
    std::fs::File::open(&path)
        .unwrap()
        .read_to_end(&mut written)
        .unwrap();
    let _ = std::fs::remove_file(&path);
    assert!(written == direct, "the bytes differ");
}
