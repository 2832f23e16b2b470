//! The record written on a thread of its own: the coupler hands each message over and goes on,
//! while the thread compresses and writes the chunks (issue 39 item 4: compression off the
//! coupler's thread).
//!
//! The calls are those of [`Recorder`], in the same order, so the file holds the same bytes.
//! [`Background::end_step`] lets at most one step be in flight: it returns once the step
//! before it is written (the step's chunk and the provisional end), so a killed run loses at
//! most the step it was writing, as before plus one, and [`Background::committed`] is the end
//! of the last step written. A write error ends the thread and comes back at the next call,
//! with the committed bytes to cut the record back to.

use std::io::{BufWriter, Write};
use std::sync::mpsc::{Receiver, SyncSender, sync_channel};
use std::thread::JoinHandle;

use protocol::wire::NodeKind;

use super::{RecordError, Recorder};

/// Messages handed over and not yet written, at most (about one step of the largest scenes:
/// a step of `clamped-beam-2d` records 27).
const QUEUE: usize = 64;

enum Job {
    Frame(NodeKind, NodeKind, f64, u64, Vec<u8>),
    Checkpoint(NodeKind, f64, u64, Vec<u8>),
    Diagnostics(f64, u64, Vec<u8>),
    Views(std::path::PathBuf, u32, f64, Vec<[u32; 2]>),
    EndStep,
    Finish,
}

/// What the thread says after each step, and at the end.
enum Done {
    /// A step written: the record's committed bytes.
    Step(u64),
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
    /// Steps handed over and not yet written.
    in_flight: usize,
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
            in_flight: 0,
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
        self.send(Job::Frame(from, to, t, wall_ns, frame.to_vec()))
    }

    /// [`Recorder::record_checkpoint`].
    pub fn record_checkpoint(
        &mut self,
        node: NodeKind,
        t: f64,
        wall_ns: u64,
        frame: &[u8],
    ) -> Result<(), RecordError> {
        self.send(Job::Checkpoint(node, t, wall_ns, frame.to_vec()))
    }

    /// [`Recorder::record_diagnostics`].
    pub fn record_diagnostics(
        &mut self,
        t: f64,
        wall_ns: u64,
        json: &[u8],
    ) -> Result<(), RecordError> {
        self.send(Job::Diagnostics(t, wall_ns, json.to_vec()))
    }

    /// [`Recorder::record_views`]: the files are read and converted on the record's thread.
    pub fn record_views(
        &mut self,
        dir: &std::path::Path,
        k: u32,
        t: f64,
        broken: &[[u32; 2]],
    ) -> Result<(), RecordError> {
        self.send(Job::Views(dir.to_path_buf(), k, t, broken.to_vec()))
    }

    /// [`Recorder::end_step`], handed over; returns once the step before it is written.
    pub fn end_step(&mut self) -> Result<(), RecordError> {
        self.send(Job::EndStep)?;
        self.in_flight += 1;
        while self.in_flight > 1 {
            self.wait()?;
        }
        Ok(())
    }

    /// Bytes of the record up to its last step written.
    pub fn committed(&self) -> u64 {
        self.committed
    }

    /// Writes every step handed over, then the summary and footer; returns the writer.
    pub fn finish(mut self) -> Result<W, RecordError> {
        self.send(Job::Finish)?;
        self.jobs = None;
        loop {
            match self.done.recv() {
                Ok(Done::Step(bytes)) => self.committed = bytes,
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
            Done::Step(bytes) => {
                self.committed = bytes;
                self.in_flight = self.in_flight.saturating_sub(1);
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
    while let Ok(job) = queue.recv() {
        let done = match job {
            Job::Frame(from, to, t, wall, bytes) => recorder
                .record_frame(from, to, t, wall, &bytes)
                .map(|()| None),
            Job::Checkpoint(node, t, wall, bytes) => recorder
                .record_checkpoint(node, t, wall, &bytes)
                .map(|()| None),
            Job::Diagnostics(t, wall, bytes) => {
                recorder.record_diagnostics(t, wall, &bytes).map(|()| None)
            }
            Job::Views(dir, k, t, broken) => {
                recorder.record_views(&dir, k, t, &broken).map(|()| None)
            }
            Job::EndStep => recorder
                .end_step()
                .map(|()| Some(Done::Step(recorder.committed()))),
            Job::Finish => break,
        };
        match done {
            Ok(None) => {}
            Ok(Some(step)) => {
                let _ = tell.send(step);
            }
            Err(err) => {
                let committed = recorder.committed();
                std::mem::forget(recorder);
                let _ = tell.send(Done::Failed(err, committed));
                return None;
            }
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
