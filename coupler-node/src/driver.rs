//! The coupler's loop: frames in from the transport → record → state machine → frames out.
//!
//! The same loop drives the iceoryx2 bus and the in-memory transport. Every frame that crosses
//! the coupler is handed to the [`RecordSink`] exactly as it crossed, before it is acted on;
//! diagnostics follow each completed step, and the record is flushed at each step's end so a
//! killed run leaves a file readable up to its last completed step.
//!
//! Logs: each node's greeting and each step at debug, each fixed-point decision at trace.

use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use protocol::codec::{self, DecodeError};
use protocol::transport::{Transport, TransportError};
use protocol::wire::{Message, MessageKind, NodeKind, Shutdown, ShutdownReason, Stamp};
use serde::Serialize;

mod abort;

pub use abort::Abort;

use crate::ledger::LedgerEntry;
use crate::progress::Progress;
use crate::record::Diagnostics;
use crate::scheme::{Action, Coupler, Finish, StepReport};

/// Why a [`RecordSink`] could not keep what the loop handed it.
#[derive(Debug, thiserror::Error)]
pub enum SinkError {
    /// The MCAP record failed.
    #[error(transparent)]
    Record(#[from] crate::record::RecordError),
    /// A write of the record failed: the message names the file, the error and what was kept.
    #[error("{0}")]
    Write(String),
    /// `run.record_max_bytes` is reached: the run ends cleanly after this step.
    #[error("{0}")]
    Limit(String),
    /// A CSV file of the run (`ledger.csv`, `links_broken.csv`) could not be written.
    #[error("writing {}: {source}", path.display())]
    Csv {
        /// The file.
        path: std::path::PathBuf,
        /// The IO error.
        source: std::io::Error,
    },
}

/// Where the loop writes what it sees. `t` is the simulated time a message belongs to \[s\]
/// (a frame's: the start of its step; diagnostics: the end of the step), a function of the
/// run; `wall_ns` the wall clock.
pub trait RecordSink {
    /// A frame that crossed the coupler (`from` → `to`), as bytes.
    fn frame(
        &mut self,
        from: NodeKind,
        to: NodeKind,
        t: f64,
        wall_ns: u64,
        frame: &[u8],
    ) -> Result<(), SinkError>;
    /// A node's checkpoint frame.
    fn checkpoint(
        &mut self,
        node: NodeKind,
        t: f64,
        wall_ns: u64,
        frame: &[u8],
    ) -> Result<(), SinkError>;
    /// One step's diagnostics as a JSON object.
    fn diagnostics(&mut self, t: f64, wall_ns: u64, json: &[u8]) -> Result<(), SinkError>;
    /// The ledger entry of an accepted step, before its `end_step` (`ledger.csv`); the
    /// default keeps nothing.
    fn ledger(&mut self, _entry: &LedgerEntry) -> Result<(), SinkError> {
        Ok(())
    }
    /// The links broken in accepted step `step` as (time of the sub-step that broke it \[s\],
    /// particle-id pair), in break order, before its `end_step` (`links_broken.csv`; called
    /// for every step, with an empty list when none broke); the default keeps nothing.
    fn links_broken(&mut self, _step: u64, _links: &[(f64, [u32; 2])]) -> Result<(), SinkError> {
        Ok(())
    }
    /// The views of an accepted step's output (`output`: the output index the step planned,
    /// if any), before its `end_step`: the record's Foxglove channels; the default keeps
    /// nothing.
    fn views(&mut self, _output: Option<u32>, _t: f64) -> Result<(), SinkError> {
        Ok(())
    }
    /// The step is complete: make it durable.
    fn end_step(&mut self) -> Result<(), SinkError>;
}

/// A sink that keeps nothing (`record = "none"`).
pub struct NoRecord;

impl RecordSink for NoRecord {
    fn frame(
        &mut self,
        _: NodeKind,
        _: NodeKind,
        _: f64,
        _: u64,
        _: &[u8],
    ) -> Result<(), SinkError> {
        Ok(())
    }
    fn checkpoint(&mut self, _: NodeKind, _: f64, _: u64, _: &[u8]) -> Result<(), SinkError> {
        Ok(())
    }
    fn diagnostics(&mut self, _: f64, _: u64, _: &[u8]) -> Result<(), SinkError> {
        Ok(())
    }
    fn end_step(&mut self) -> Result<(), SinkError> {
        Ok(())
    }
}

/// Settings of the loop.
#[derive(Clone, Debug)]
pub struct DriverConfig {
    /// Longest wait for any one message \[s\].
    pub timeout: Duration,
    /// Print a progress line on stderr.
    pub progress: bool,
    /// Scene name, for the progress line.
    pub name: String,
    /// End time \[s\], for the progress line.
    pub t_end: f64,
    /// `run.dt_min` \[s\]: a step a node limits to less stops the run (`None`: the default, the
    /// larger of [`protocol::scene::DT_MIN_RELATIVE`] times the smallest first proposal and
    /// [`protocol::scene::DT_MIN_OF_T_END`] times `t_end`).
    pub dt_min: Option<f64>,
}

/// Busy seconds per role: `fluid` and `solid` the waits for their answers (compute plus
/// transport), `coupler` its own work (state machine, encoding, recording).
pub type Busy = crate::record::BusySeconds;

/// Iteration statistics.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Iterations {
    /// Mean solid trials per step.
    pub mean: f64,
    /// Largest number in one step.
    pub max: u32,
}

/// `summary.json` (DESIGN §7).
#[derive(Clone, Debug, Default, Serialize)]
pub struct Summary {
    /// Scene name.
    pub scene: String,
    /// `"completed"`, `"max_steps"`, or the reason the run stopped.
    pub status: String,
    /// Coupling steps done.
    pub steps: u64,
    /// Time reached \[s\].
    pub t_end: f64,
    /// Wall-clock time of the loop \[s\].
    pub wall_s: f64,
    /// Busy seconds per node.
    pub busy_s: Busy,
    /// Seconds of the coupler's time spent in its sink: the MCAP record and `ledger.csv`
    /// (part of `busy_s.coupler`).
    pub record_s: f64,
    /// Fixed-point iterations.
    pub coupling_iterations: Iterations,
    /// Largest relative mass error of the ledger.
    pub mass_rel_err: f64,
    /// Fluid mass the solid's motion displaced over the run \[kg\] (2-D: per unit depth):
    /// `Σ_n Σ_cells ρⁿ max(0, Λ^{n+1} − Λⁿ) V`, the fluid that was, at the start of each
    /// step, in the volume the solid newly covers during it. 0 without a real fluid and a
    /// solid.
    pub swept_mass: f64,
    /// |M(t_end) − M(0)| \[kg\] of the fluid, counting the mass that left through open
    /// boundaries (the largest over the run is `mass_rel_err` × M(0));
    /// `mass_abs_err / swept_mass` is the mass error of paper 000 (Fig. 11a, 21a, 28a).
    pub mass_abs_err: f64,
    /// Largest relative energy error of the ledger.
    pub energy_rel_err: f64,
    /// Energy error relative to the largest interface exchange, at the end.
    pub energy_err_vs_exchange: f64,
    /// Links broken.
    pub links_broken: u64,
    /// Which implementation ran each side (`real`, `pressure`, `prescribed`, `replay:...`).
    pub nodes: std::collections::BTreeMap<String, String>,
    /// Output index and time of each output written (`outputs.csv`).
    #[serde(skip)]
    pub outputs: Vec<(u32, f64)>,
}

/// Why the loop stopped early.
#[derive(Debug, thiserror::Error)]
pub enum DriverError {
    /// The handshake found a problem.
    #[error(transparent)]
    Coupler(#[from] crate::scheme::CouplerError),
    /// The transport failed.
    #[error(transparent)]
    Transport(#[from] TransportError),
    /// A frame did not decode.
    #[error("undecodable frame from the {from} node: {source}")]
    Decode {
        /// Sender.
        from: NodeKind,
        /// The codec's error.
        source: DecodeError,
    },
    /// Recording failed.
    #[error("recording: {0}")]
    Record(SinkError),
    /// A node's process ended or the supervisor asked to stop.
    #[error("{0}")]
    Aborted(String),
    /// No message came from the node(s) waited for within the deadline, though their
    /// processes live (stopped, hung, or busy far beyond the deadline).
    #[error("{who} node stopped answering: no message within {timeout:?} at step {step}")]
    Silent {
        /// The node or nodes waited for (`fluid`, `fluid and solid`).
        who: String,
        /// The deadline.
        timeout: Duration,
        /// The step.
        step: u64,
    },
    /// A node limited the step to less than `run.dt_min`: a run without progress.
    #[error(
        "the time step collapsed at step {step}, t = {t:.4e} s: {node} limits dt to {dt:.4e} s ({why}), below run.dt_min = {dt_min:.4e} s{}",
        if *default_floor { " (the default: 1e-6 of the first step proposed or 1e-9 of t_end, whichever is larger; set run.dt_min to change it)" } else { "" }
    )]
    DtCollapsed {
        /// The step.
        step: u64,
        /// Its start time \[s\].
        t: f64,
        /// The step size \[s\].
        dt: f64,
        /// The node that limited it.
        node: String,
        /// What limits it there (the node's limiter: cell, particle).
        why: String,
        /// The floor \[s\].
        dt_min: f64,
        /// The floor is the default one.
        default_floor: bool,
    },
}

fn wall_ns() -> u64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos() as u64)
}

/// Runs the coupler until the run finishes or fails; returns the summary (its `status` says
/// which) and the error, if any. Nodes are told to shut down in both cases.
pub fn drive(
    transport: &mut dyn Transport,
    coupler: &mut Coupler,
    sink: &mut dyn RecordSink,
    cfg: &DriverConfig,
    abort: &Abort,
) -> (Summary, Option<DriverError>) {
    let started = Instant::now();
    let mut busy = Busy::default();
    let mut progress = Progress::new(cfg.progress, &cfg.name, cfg.t_end);
    let mut outputs = Vec::new();
    let sink = &mut TimedSink {
        inner: sink,
        seconds: 0.0,
    };
    let result = drive_inner(
        transport,
        coupler,
        sink,
        cfg,
        abort,
        &mut busy,
        &mut progress,
        &mut outputs,
    );
    progress.finish();
    let (mean, max) = coupler.iteration_stats();
    let ledger = coupler.ledger();
    let (status, error) = match result {
        Ok(Finish::Completed) => ("completed".to_string(), None),
        Ok(Finish::MaxSteps) => ("max_steps".to_string(), None),
        // `run.record_max_bytes`: a clean end after a complete step, like `max_steps`.
        Err(DriverError::Record(SinkError::Limit(status))) => {
            shut_down(transport, coupler, sink, abort, ShutdownReason::Completed);
            (status, None)
        }
        Err(err) => {
            let reason = err.to_string();
            if let DriverError::Coupler(crate::scheme::CouplerError::NotConverged {
                step,
                t,
                iterations,
                residuals,
                ..
            }) = &err
            {
                // The failed step's diagnostics, so the record shows its residual history too.
                let json = serde_json::to_vec(&Diagnostics {
                    step: *step,
                    t: *t,
                    dt: coupler
                        .planned_end()
                        .map_or(0.0, |end| end - coupler.time()),
                    iterations: *iterations,
                    residuals: residuals.clone(),
                    converged: false,
                    busy_s: busy.clone(),
                    ..Diagnostics::default()
                })
                .expect("diagnostics serialize");
                if let Err(err) = sink.diagnostics(*t, wall_ns(), &json) {
                    tracing::warn!("the record lacks the failed step's diagnostics: {err}");
                }
            }
            shut_down(
                transport,
                coupler,
                sink,
                abort,
                ShutdownReason::Failure(reason.clone()),
            );
            (reason, Some(err))
        }
    };
    let wall = started.elapsed().as_secs_f64();
    busy.coupler = (wall - busy.fluid - busy.solid).max(0.0);
    let summary = Summary {
        scene: cfg.name.clone(),
        status,
        steps: coupler.step(),
        t_end: coupler.time(),
        wall_s: wall,
        busy_s: busy,
        record_s: sink.seconds,
        coupling_iterations: Iterations { mean, max },
        mass_rel_err: ledger.max_mass_rel_err,
        swept_mass: ledger.last.as_ref().map_or(0.0, |l| l.swept_mass),
        mass_abs_err: ledger.last.as_ref().map_or(0.0, |l| l.mass_abs_err),
        energy_rel_err: ledger.max_energy_rel_err,
        energy_err_vs_exchange: ledger
            .last
            .as_ref()
            .map_or(0.0, |l| l.energy_err_vs_exchange),
        links_broken: ledger.last.as_ref().map_or(0, |l| l.links_broken),
        nodes: Default::default(),
        outputs,
    };
    (summary, error)
}

/// How long [`shut_down`] waits for each node to take its shutdown.
///
/// NOTE: a node whose process failed before it subscribed (a missing library, `mpirun` refusing
/// to run as root) never takes it: the coupler, having reported that node dead, waited for it
/// for the transport's whole send timeout (30 s; for good when the last slice of that wait fell
/// under 1 µs, see `Bus::block`). A node that is alive and misses its shutdown is ended by the
/// supervisor after its grace period.
const SHUTDOWN_SEND_TIMEOUT: Duration = Duration::from_secs(1);

/// Sends the nodes whose process has not ended a shutdown with `reason` (recorded too), waiting
/// at most [`SHUTDOWN_SEND_TIMEOUT`] for each, and makes the record's last step durable.
fn shut_down(
    transport: &mut dyn Transport,
    coupler: &Coupler,
    sink: &mut dyn RecordSink,
    abort: &Abort,
    reason: ShutdownReason,
) {
    let stamp = Stamp::step(coupler.step());
    let t = coupler.time();
    for node in [NodeKind::Fluid, NodeKind::Solid] {
        let present = match node {
            NodeKind::Fluid => coupler.config().fluid,
            _ => coupler.config().solid,
        };
        if present {
            let frame = codec::encode(
                NodeKind::Coupler,
                &Message::Shutdown(Shutdown {
                    stamp,
                    reason: reason.clone(),
                }),
            );
            if let Err(err) = sink.frame(NodeKind::Coupler, node, t, wall_ns(), &frame) {
                tracing::warn!("the record lacks the shutdown sent to the {node} node: {err}");
            }
            if abort.has_exited(node) {
                tracing::debug!("no shutdown sent to the {node} node: its process ended");
            } else {
                match transport.send_within(node, &frame, SHUTDOWN_SEND_TIMEOUT) {
                    Ok(()) => {
                        tracing::debug!("shutdown sent to the {node} node at step {}", stamp.step)
                    }
                    Err(err) => tracing::debug!("the {node} node did not take its shutdown: {err}"),
                }
            }
        }
    }
    if let Err(err) = sink.end_step() {
        tracing::warn!("the record's last step is not flushed: {err}");
    }
}

/// A sink that counts the seconds spent in it (`Summary::record_s`).
struct TimedSink<'a> {
    inner: &'a mut dyn RecordSink,
    seconds: f64,
}

impl TimedSink<'_> {
    fn timed<T>(&mut self, call: impl FnOnce(&mut dyn RecordSink) -> T) -> T {
        let start = Instant::now();
        let out = call(&mut *self.inner);
        self.seconds += start.elapsed().as_secs_f64();
        out
    }
}

impl RecordSink for TimedSink<'_> {
    fn frame(
        &mut self,
        from: NodeKind,
        to: NodeKind,
        t: f64,
        wall_ns: u64,
        frame: &[u8],
    ) -> Result<(), SinkError> {
        self.timed(|s| s.frame(from, to, t, wall_ns, frame))
    }

    fn checkpoint(
        &mut self,
        node: NodeKind,
        t: f64,
        wall_ns: u64,
        frame: &[u8],
    ) -> Result<(), SinkError> {
        self.timed(|s| s.checkpoint(node, t, wall_ns, frame))
    }

    fn diagnostics(&mut self, t: f64, wall_ns: u64, json: &[u8]) -> Result<(), SinkError> {
        self.timed(|s| s.diagnostics(t, wall_ns, json))
    }

    fn ledger(&mut self, entry: &LedgerEntry) -> Result<(), SinkError> {
        self.timed(|s| s.ledger(entry))
    }

    fn links_broken(&mut self, step: u64, links: &[(f64, [u32; 2])]) -> Result<(), SinkError> {
        self.timed(|s| s.links_broken(step, links))
    }

    fn views(&mut self, output: Option<u32>, t: f64) -> Result<(), SinkError> {
        self.timed(|s| s.views(output, t))
    }

    fn end_step(&mut self) -> Result<(), SinkError> {
        self.timed(|s| s.end_step())
    }
}

/// The start time of each step the loop has seen \[s\], so that a frame's log time is the
/// start of *its* step (from its stamp), whatever step the coupler is at when it arrives: a
/// node may answer for step n + 1 before the other node's totals close step n.
#[derive(Default)]
struct StepStarts(std::collections::BTreeMap<u64, f64>);

impl StepStarts {
    /// Notes what the coupler knows: the start of its current step and, once the step size is
    /// agreed, the start of the next.
    fn observe(&mut self, coupler: &Coupler) {
        self.0.insert(coupler.step(), coupler.time());
        if let Some(end) = coupler.planned_end() {
            self.0.insert(coupler.step() + 1, end);
        }
        // Only the last few steps are ever asked for.
        while self.0.len() > 8 {
            self.0.pop_first();
        }
    }

    /// Start time of `step`; a step the loop has not seen (a frame from a confused node, which
    /// the coupler then refuses) gets the latest known.
    fn of(&self, step: u64, coupler: &Coupler) -> f64 {
        self.0.get(&step).copied().unwrap_or_else(|| coupler.time())
    }
}

#[allow(clippy::too_many_arguments)]
fn drive_inner(
    transport: &mut dyn Transport,
    coupler: &mut Coupler,
    sink: &mut dyn RecordSink,
    cfg: &DriverConfig,
    abort: &Abort,
    busy: &mut Busy,
    progress: &mut Progress,
    outputs: &mut Vec<(u32, f64)>,
) -> Result<Finish, DriverError> {
    // NOTE: waits are sliced so the supervisor's abort (a node process died) is seen within
    // 100 ms even when the transport cannot tell.
    let slice = Duration::from_millis(100).min(cfg.timeout);
    let mut out = Vec::new();
    // The smallest step the nodes proposed for step 0, for the default `run.dt_min`.
    let mut first_proposal = f64::INFINITY;
    let mut starts = StepStarts::default();
    loop {
        starts.observe(coupler);
        let (from, frame) = receive(transport, coupler, cfg, abort, slice, busy)?;
        let (header, msg) = decode(from, &frame)?;
        let now = wall_ns();
        let t = starts.of(header.stamp.step, coupler);
        let record = if header.kind == MessageKind::Checkpoint {
            sink.checkpoint(from, t, now, &frame)
        } else {
            sink.frame(from, NodeKind::Coupler, t, now, &frame)
        };
        record.map_err(DriverError::Record)?;
        if let Message::DtProposal(p) = &msg
            && p.stamp.step == 0
            && p.stamp.iteration == 0
            && p.dt_max > 0.0
            && p.dt_max.is_finite()
        {
            first_proposal = first_proposal.min(p.dt_max);
        }
        if let Message::Hello(hello) = &msg {
            tracing::debug!(
                "the {from} node greeted: {}, protocol {}, scene hash {:016x}, capabilities {:?}",
                hello.implementation,
                hello.protocol_version,
                hello.scene_hash,
                hello.capabilities
            );
        }
        let actions = coupler.on_message(from, msg)?;
        starts.observe(coupler);
        let mut actions = actions.into_iter().peekable();
        while let Some(action) = actions.next() {
            match action {
                Action::Send(to, msg) => {
                    log_sent(to, &msg);
                    codec::encode_into(NodeKind::Coupler, &msg, &mut out);
                    let t = starts.of(msg.stamp().step, coupler);
                    sink.frame(NodeKind::Coupler, to, t, wall_ns(), &out)
                        .map_err(DriverError::Record)?;
                    // A trial and its decision, a plan and its predicted state: one wake-up.
                    if matches!(actions.peek(), Some(Action::Send(next, _)) if *next == to) {
                        transport.send_more(to, &out)?;
                    } else {
                        transport.send(to, &out)?;
                    }
                }
                Action::Checkpoint(_) => {}
                Action::CouplerCheckpoint(c) => {
                    let t = starts.of(c.stamp.step, coupler);
                    codec::encode_into(NodeKind::Coupler, &Message::Checkpoint(c), &mut out);
                    sink.checkpoint(NodeKind::Coupler, t, wall_ns(), &out)
                        .map_err(DriverError::Record)?;
                }
                Action::StepDone(report) => {
                    check_dt_min(&report, cfg.dt_min, first_proposal, cfg.t_end)?;
                    record_step(&report, sink, busy)?;
                    progress.update(&report);
                    if let Some(k) = report.output {
                        outputs.push((k, report.t));
                    }
                }
                Action::Finished(finish) => {
                    sink.end_step().map_err(DriverError::Record)?;
                    tracing::debug!("finished ({finish:?}) at step {}", coupler.step());
                    return Ok(finish);
                }
            }
        }
    }
}

/// The next frame from the node the coupler waits for (from either while it waits for both),
/// the wait booked to that node's busy time. Ends at the supervisor's abort, or when no frame
/// came within `cfg.timeout`.
fn receive(
    transport: &mut dyn Transport,
    coupler: &Coupler,
    cfg: &DriverConfig,
    abort: &Abort,
    slice: Duration,
    busy: &mut Busy,
) -> Result<(NodeKind, Vec<u8>), DriverError> {
    let waiting_since = Instant::now();
    // NOTE: waiting for one node, the transport watches that node alone (cheaper than a
    // wait set over both); the other node's early frames stay queued in the transport
    // until the state machine waits for them.
    let expected = match coupler.waiting_for().as_slice() {
        [one] => Some(*one),
        _ => None,
    };
    let (from, frame) = loop {
        if let Some(reason) = abort.check() {
            // A node that reported its failure before it exited: its report, not its exit.
            if let Ok((from, frame)) = transport.recv(None, Duration::ZERO)
                && codec::decode_header(&frame).is_ok_and(|h| h.kind == MessageKind::Failure)
            {
                break (from, frame);
            }
            return Err(DriverError::Aborted(reason));
        }
        match transport.recv(expected, slice) {
            Ok(got) => break got,
            Err(TransportError::Timeout { .. }) if waiting_since.elapsed() < cfg.timeout => {}
            Err(TransportError::Timeout { .. }) => {
                let who: Vec<&str> = coupler.silent().iter().map(|n| n.name()).collect();
                return Err(DriverError::Silent {
                    who: who.join(" and "),
                    timeout: cfg.timeout,
                    step: coupler.step(),
                });
            }
            Err(err) => return Err(err.into()),
        }
    };
    let waited = waiting_since.elapsed().as_secs_f64();
    match from {
        NodeKind::Fluid => busy.fluid += waited,
        NodeKind::Solid => busy.solid += waited,
        NodeKind::Coupler => {}
    }
    Ok((from, frame))
}

/// A frame from `from`, decoded; a frame of another protocol version is a refusal.
fn decode(from: NodeKind, frame: &[u8]) -> Result<(codec::Header, Message), DriverError> {
    match codec::decode(frame) {
        Ok(decoded) => Ok(decoded),
        Err(DecodeError::VersionMismatch { expected, got }) => {
            Err(DriverError::Coupler(crate::scheme::CouplerError::Refused {
                node: from,
                reason: format!(
                    "protocol version mismatch: coupler speaks version {expected}, {from} node speaks version {got}"
                ),
            }))
        }
        Err(source) => Err(DriverError::Decode { from, source }),
    }
}

/// A finished step into the sink: its diagnostics, ledger row and broken links, then made
/// durable; and its debug line.
fn record_step(
    report: &StepReport,
    sink: &mut dyn RecordSink,
    busy: &Busy,
) -> Result<(), DriverError> {
    let json = serde_json::to_vec(&Diagnostics {
        step: report.step,
        t: report.t,
        dt: report.dt,
        limiter: report.limiter.clone(),
        iterations: report.iterations,
        residuals: report.residuals.clone(),
        relaxation: report.relaxation.clone(),
        columns: report.columns.clone(),
        columns_dropped: report.columns_dropped,
        predicted: report.predicted,
        converged: true,
        output: report.output,
        ledger: Some(report.ledger.clone()),
        vacuum_cells: report.vacuum_cells,
        solid_substeps: report.solid_substeps,
        busy_s: busy.clone(),
    })
    .expect("diagnostics serialize");
    sink.diagnostics(report.t, wall_ns(), &json)
        .map_err(DriverError::Record)?;
    sink.ledger(&report.ledger).map_err(DriverError::Record)?;
    sink.links_broken(report.step, &report.broken_links)
        .map_err(DriverError::Record)?;
    sink.views(report.output, report.t)
        .map_err(DriverError::Record)?;
    sink.end_step().map_err(DriverError::Record)?;
    tracing::debug!(
        "step {} done: t = {:.6e} s, dt = {:.4e} s ({}), {} iteration{}, residual {:.3e}, mass err {:.2e}, energy err {:.2e}",
        report.step,
        report.t,
        report.dt,
        report.limiter,
        report.iterations,
        if report.iterations == 1 { "" } else { "s" },
        report.residuals.last().copied().unwrap_or(0.0),
        report.ledger.mass_rel_err,
        report.ledger.energy_rel_err
    );
    Ok(())
}

/// The log of a message the coupler sends: each fixed-point decision at trace (once, though
/// both nodes get it), checkpoint requests, restores and shutdowns; plans and the rest are in
/// the step's debug line.
fn log_sent(to: NodeKind, msg: &Message) {
    match msg {
        Message::FixedPointDecision(d) if to == NodeKind::Solid => tracing::trace!(
            "step {} iteration {}: residual {:.3e}, {:?}",
            d.stamp.step,
            d.stamp.iteration,
            d.residual,
            d.decision
        ),
        Message::CheckpointRequest(r) => {
            tracing::trace!("checkpoint of step {} asked of the {to} node", r.stamp.step)
        }
        Message::Checkpoint(c) => tracing::debug!(
            "checkpoint of step {} sent back to the {to} node to restore",
            c.stamp.step
        ),
        Message::Shutdown(s) => tracing::debug!(
            "shutdown sent to the {to} node at step {}: {:?}",
            s.stamp.step,
            s.reason
        ),
        _ => {}
    }
}

/// Stops the run when a node limited the step below `run.dt_min` (given, or the default
/// relative to the first proposal). Steps shortened by the scene's cap or by an output time
/// are not a collapse.
fn check_dt_min(
    report: &StepReport,
    dt_min: Option<f64>,
    first_proposal: f64,
    t_end: f64,
) -> Result<(), DriverError> {
    let Some((node, why)) = report.limiter.split_once(':') else {
        return Ok(());
    };
    // No finite first proposal (doubles at rest, a gas at rest): the floor from t_end alone.
    let relative = if first_proposal.is_finite() {
        protocol::scene::DT_MIN_RELATIVE * first_proposal
    } else {
        0.0
    };
    let default_floor = relative.max(protocol::scene::DT_MIN_OF_T_END * t_end);
    let floor = dt_min.unwrap_or(default_floor);
    if report.dt >= floor {
        return Ok(());
    }
    Err(DriverError::DtCollapsed {
        step: report.step,
        t: report.t,
        dt: report.dt,
        node: format!("the {node} node"),
        why: why.to_string(),
        dt_min: floor,
        default_floor: dt_min.is_none(),
    })
}
