//! The record written on a thread of its own: the coupler hands each step over whole and goes
//! on, while the thread serialises, compresses and writes its chunk (issue 39 item 4:
//! recording off the coupler's thread).
//!
//! The calls are those of [`Recorder`], in the same order, so the file holds the same bytes.
//! The coupler's thread only copies each message into the open step ([`Batch`], one buffer for
//! the step's bytes, reused from step to step, so a run allocates and faults in its pages once)
//! and hands the step over at [`Background::end_step`]: one hand-over and one wake-up of the
//! record's thread per step, not one per message. [`Background::end_step`] lets the record fall
//! behind the run by up to [`MAX_LAG_STEPS`] steps and [`MAX_LAG_BYTES`] bytes (and always by
//! one step): it returns at once unless the steps handed over and not yet written pass either
//! bound, and then once they are back within both. So the coupler waits for the record only when
//! the record's thread cannot keep up, not at every step whose predecessor is still being
//! compressed; a killed run loses at most the steps in flight, and [`Background::committed`] is
//! the end of the last step written. A write error ends the thread and comes back at the next
//! step, with the committed bytes to cut the record back to.
//!
//! NOTE (issue 39 item 4): with at most one step in flight, the coupler of `clamped-beam-2d`
//! waited 0.15-0.43 s a run at the ends of steps for the step before to be compressed (its
//! `record_s`; 0.012-0.016 s without a record), on the run's critical path: every node waits for
//! the coupler.

use std::io::{BufWriter, Write};
use std::ops::Range;
use std::sync::mpsc::{Receiver, SyncSender, sync_channel};
use std::thread::JoinHandle;

use protocol::wire::NodeKind;

use super::{RecordError, Recorder};

/// Steps handed over and not yet written, at most (beyond the first; see the module docs).
pub const MAX_LAG_STEPS: usize = 16;

/// Bytes of the steps handed over and not yet written, at most (beyond the first step's).
pub const MAX_LAG_BYTES: usize = 64 << 20;

/// Capacity of the channels to and from the thread: every step in flight, the messages of a step
/// that did not end, and the finish.
const QUEUE: usize = MAX_LAG_STEPS + 3;

/// Emptied batches kept for the next steps, at most (each holds the capacity of the largest
/// step it carried).
const SPARES: usize = 2;

/// One message of a step: what [`Recorder`] is called with, its bytes a range of
/// [`Batch::bytes`].
enum Item {
    Frame(NodeKind, NodeKind, f64, u64, Range<usize>),
    Checkpoint(NodeKind, f64, u64, Range<usize>),
    Diagnostics(f64, u64, Range<usize>),
    Views(std::path::PathBuf, u32, f64, Vec<[u32; 2]>),
}

/// The messages of one step, in the order they were handed over, and their bytes end to end.
#[derive(Default)]
struct Batch {
    items: Vec<Item>,
    bytes: Vec<u8>,
}

impl Batch {
    /// Copies `data` to the end of the step's bytes; returns where it lies.
    fn push(&mut self, data: &[u8]) -> Range<usize> {
        let at = self.bytes.len();
        self.bytes.extend_from_slice(data);
        at..self.bytes.len()
    }

    fn clear(&mut self) {
        self.items.clear();
        self.bytes.clear();
    }
}

enum Job {
    /// A step's messages; `true`: then [`Recorder::end_step`] (a step's end), `false`: the
    /// messages of a step that will not end (before a finish).
    Step(Batch, bool),
    Finish,
}

/// What the thread says after each step, and at the end.
enum Done {
    /// A step written: the record's committed bytes, and the step's emptied batch for reuse.
    Step(u64, Batch),
    /// The record finished (summary and footer written).
    Finished,
    /// A write failed: the error, and the bytes of the last complete step.
    Failed(RecordError, u64),
}

/// A [`Recorder`] on its own thread (see the module docs).
pub struct Background<W: Write + std::io::Seek + Send + 'static> {
    jobs: Option<SyncSender<Job>>,
    done: Receiver<Done>,
    worker: Option<JoinHandle<Option<W>>>,
    /// The step being handed over.
    open: Batch,
    /// Emptied batches back from the thread, for the next steps.
    spares: Vec<Batch>,
    /// Bytes of each step handed over and not yet written, oldest first.
    in_flight: std::collections::VecDeque<usize>,
    /// Steps and bytes the record may fall behind by (besides the oldest step in flight).
    max_lag: (usize, usize),
    committed: u64,
}

impl<W: Write + std::io::Seek + Send + 'static> Background<W> {
    /// Moves `recorder` onto a thread of its own.
    pub fn start(recorder: Recorder<BufWriter<W>>) -> Background<W> {
        let (jobs, queue) = sync_channel(QUEUE);
        let (tell, done) = sync_channel(QUEUE);
        let worker = std::thread::Builder::new()
            .name("record".into())
            .spawn(move || work(recorder, &queue, &tell))
            .expect("spawning the record's thread");
        Background {
            jobs: Some(jobs),
            done,
            worker: Some(worker),
            open: Batch::default(),
            spares: Vec::new(),
            in_flight: std::collections::VecDeque::new(),
            max_lag: (MAX_LAG_STEPS, MAX_LAG_BYTES),
            committed: 0,
        }
    }

    /// [`Recorder::record_frame`].
    pub fn record_frame(
        &mut self,
        from: NodeKind,
        to: NodeKind,
        t: f64,
        wall_ns: u64,
        frame: &[u8],
    ) -> Result<(), RecordError> {
        let bytes = self.open.push(frame);
        self.open
            .items
            .push(Item::Frame(from, to, t, wall_ns, bytes));
        Ok(())
    }

    /// [`Recorder::record_checkpoint`].
    pub fn record_checkpoint(
        &mut self,
        node: NodeKind,
        t: f64,
        wall_ns: u64,
        frame: &[u8],
    ) -> Result<(), RecordError> {
        let bytes = self.open.push(frame);
        self.open
            .items
            .push(Item::Checkpoint(node, t, wall_ns, bytes));
        Ok(())
    }

    /// [`Recorder::record_diagnostics`].
    pub fn record_diagnostics(
        &mut self,
        t: f64,
        wall_ns: u64,
        json: &[u8],
    ) -> Result<(), RecordError> {
        let bytes = self.open.push(json);
        self.open.items.push(Item::Diagnostics(t, wall_ns, bytes));
        Ok(())
    }

    /// [`Recorder::record_views`]: the files are read and converted on the record's thread.
    pub fn record_views(
        &mut self,
        dir: &std::path::Path,
        k: u32,
        t: f64,
        broken: &[[u32; 2]],
    ) -> Result<(), RecordError> {
        self.open
            .items
            .push(Item::Views(dir.to_path_buf(), k, t, broken.to_vec()));
        Ok(())
    }

    /// [`Recorder::end_step`]: hands the step over; returns once the steps in flight are within
    /// [`MAX_LAG_STEPS`] and [`MAX_LAG_BYTES`] (besides the oldest).
    pub fn end_step(&mut self) -> Result<(), RecordError> {
        let next = self.spares.pop().unwrap_or_default();
        let step = std::mem::replace(&mut self.open, next);
        let bytes = step.bytes.len();
        self.send(Job::Step(step, true))?;
        self.in_flight.push_back(bytes);
        while self.lagging() {
            self.wait()?;
        }
        Ok(())
    }

    /// Lets the record fall behind by at most `steps` steps and `bytes` bytes besides the oldest
    /// step in flight (`0, 0`: each end of a step returns once the step before it is written).
    pub fn max_lag(mut self, steps: usize, bytes: usize) -> Self {
        self.max_lag = (steps.min(MAX_LAG_STEPS), bytes);
        self
    }

    /// Steps handed over and not yet written.
    pub fn in_flight(&self) -> usize {
        self.in_flight.len()
    }

    /// The steps in flight pass a bound (the oldest one not counted).
    fn lagging(&self) -> bool {
        let lag = self.in_flight.len().saturating_sub(1);
        let lag_bytes: usize = self.in_flight.iter().skip(1).sum();
        lag > self.max_lag.0 || lag_bytes > self.max_lag.1
    }

    /// Bytes of the record up to its last step written.
    pub fn committed(&self) -> u64 {
        self.committed
    }

    /// Writes every step handed over (and the messages of a step not ended), then the summary
    /// and footer; returns the writer.
    pub fn finish(mut self) -> Result<W, RecordError> {
        self.hand_over_the_rest()?;
        self.send(Job::Finish)?;
        self.jobs = None;
        loop {
            match self.done.recv() {
                Ok(Done::Step(bytes, _)) => self.committed = bytes,
                Ok(Done::Finished) => break,
                Ok(Done::Failed(err, bytes)) => {
                    self.committed = bytes;
                    return Err(err);
                }
                Err(_) => return Err(gone()),
            }
        }
        self.worker
            .take()
            .and_then(|w| w.join().ok())
            .flatten()
            .ok_or_else(gone)
    }

    /// Hands over the messages of a step that did not end, if any.
    fn hand_over_the_rest(&mut self) -> Result<(), RecordError> {
        if self.open.items.is_empty() {
            return Ok(());
        }
        let rest = std::mem::take(&mut self.open);
        self.send(Job::Step(rest, false))
    }

    fn send(&mut self, job: Job) -> Result<(), RecordError> {
        // A failure already reported by the thread comes back first.
        while let Ok(done) = self.done.try_recv() {
            self.take(done)?;
        }
        let sent = self
            .jobs
            .as_ref()
            .is_some_and(|jobs| jobs.send(job).is_ok());
        if sent {
            return Ok(());
        }
        // The thread stopped: its last word says why.
        loop {
            match self.done.recv() {
                Ok(done) => self.take(done)?,
                Err(_) => return Err(gone()),
            }
        }
    }

    fn wait(&mut self) -> Result<(), RecordError> {
        match self.done.recv() {
            Ok(done) => self.take(done),
            Err(_) => Err(gone()),
        }
    }

    fn take(&mut self, done: Done) -> Result<(), RecordError> {
        match done {
            Done::Step(bytes, batch) => {
                self.committed = bytes;
                self.in_flight.pop_front();
                if self.spares.len() < SPARES {
                    self.spares.push(batch);
                }
                Ok(())
            }
            Done::Finished => Ok(()),
            Done::Failed(err, bytes) => {
                self.committed = bytes;
                self.jobs = None;
                Err(err)
            }
        }
    }
}

impl<W: Write + std::io::Seek + Send + 'static> Drop for Background<W> {
    fn drop(&mut self) {
        // Dropped without `finish` (a run that ends on an error): the thread writes what it was
        // handed, then the summary, as the recorder's own drop did.
        let _ = self.hand_over_the_rest();
        self.jobs = None;
        if let Some(worker) = self.worker.take() {
            let _ = worker.join();
        }
    }
}

fn gone() -> RecordError {
    RecordError::Io("the record's thread stopped without saying why".into())
}

/// The thread: writes each job in order; on a write error says so and forgets the recorder
/// (dropped, the MCAP writer would write its summary after the failure).
fn work<W: Write + std::io::Seek>(
    mut recorder: Recorder<BufWriter<W>>,
    queue: &Receiver<Job>,
    tell: &SyncSender<Done>,
) -> Option<W> {
    while let Ok(Job::Step(mut batch, end)) = queue.recv() {
        let mut done = batch
            .items
            .drain(..)
            .try_for_each(|item| write_item(&mut recorder, &batch.bytes, item));
        if end {
            done = done.and_then(|()| recorder.end_step());
        }
        if let Err(err) = done {
            let committed = recorder.committed();
            std::mem::forget(recorder);
            let _ = tell.send(Done::Failed(err, committed));
            return None;
        }
        if end {
            batch.clear();
            let _ = tell.send(Done::Step(recorder.committed(), batch));
        }
    }
    let committed = recorder.committed();
    match recorder.finish().and_then(|mut w| {
        w.flush()
            .map(|()| w)
            .map_err(|e| RecordError::Io(e.to_string()))
    }) {
        Ok(w) => {
            let _ = tell.send(Done::Finished);
            w.into_inner().ok()
        }
        Err(err) => {
            let _ = tell.send(Done::Failed(err, committed));
            None
        }
    }
}

/// Writes one message of a step.
fn write_item<W: Write + std::io::Seek>(
    recorder: &mut Recorder<W>,
    bytes: &[u8],
    item: Item,
) -> Result<(), RecordError> {
    match item {
        Item::Frame(from, to, t, wall, at) => recorder.record_frame(from, to, t, wall, &bytes[at]),
        Item::Checkpoint(node, t, wall, at) => {
            recorder.record_checkpoint(node, t, wall, &bytes[at])
        }
        Item::Diagnostics(t, wall, at) => recorder.record_diagnostics(t, wall, &bytes[at]),
        Item::Views(dir, k, t, broken) => recorder.record_views(&dir, k, t, &broken),
    }
}
