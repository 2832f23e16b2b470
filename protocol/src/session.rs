//! What the fluid and the solid node loops share: the loop itself ([`run_node`]: hello,
//! checkpoints, step plans, outputs, totals, proposals, shutdown), its configuration, its errors,
//! and the small exchanges every node makes. Each node brings only its side of a step. Pure: the
//! loops pass a [`Link`] in; nothing here opens files or reads clocks (the models write their
//! outputs themselves). The loop's `tracing` events (greeting, checkpoints, steps at debug,
//! shutdown) go wherever the binary's subscriber sends them.

use std::path::{Path, PathBuf};

use tracing::{debug, warn};

use crate::transport::{Link, LinkError};
use crate::wire::{
    Checkpoint, ConservedTotals, DtProposal, Failure, Hello, Message, NodeKind, PROTOCOL_VERSION,
    Stamp, StepPlan,
};

/// What every node implementation (real solver or double) gives the loop, whichever side it is.
pub trait NodeModel {
    /// `"real"` or the double's name, sent in the hello.
    fn implementation(&self) -> &'static str;
    /// Largest stable step and what limits it.
    fn dt_max(&self) -> StepLimit;
    /// With `run.solid_substeps` (the solid): the stable step a sub-step must stay within and
    /// what sets it, proposed after [`NodeModel::dt_max`] as a second `DtProposal` of
    /// iteration 1 ([`SUBSTEP_BOUND_ITERATION`]); `dt_max` then bounds the coupling step by the
    /// motion alone. `None` (the default): one proposal.
    fn substep_bound(&self) -> Option<StepLimit> {
        None
    }
    /// Conserved totals after the last step.
    fn totals(&self, stamp: Stamp, t: f64) -> ConservedTotals;
    /// Node-private state bytes.
    fn checkpoint(&self) -> Vec<u8>;
    /// Restores a checkpoint.
    fn restore(&mut self, bytes: &[u8]) -> Result<(), String>;
    /// Writes output `k` at time `t` into `out` (fields, VTK).
    fn write_output(&mut self, k: u32, t: f64, out: &Path) -> std::io::Result<()>;
    /// Appends one row to each probe after a step ending at `t`.
    fn record_probes(&mut self, t: f64);
    /// Writes the probe rows recorded since the last call into the probe files in `out` and
    /// forgets them, so that a node's memory does not grow with the steps (issue 38): the first
    /// call that writes creates the files with their header, later ones append. A node may keep
    /// rows back until it holds [`PROBE_ROWS_HELD`] of them, except at the `end` of the run,
    /// which writes every file (its header at least).
    fn write_probes(&mut self, out: &Path, end: bool) -> std::io::Result<()>;
}

/// Probe rows a node holds at most before it writes them out ([`NodeModel::write_probes`]).
pub const PROBE_ROWS_HELD: usize = 1024;

/// Runs node `kind` until the coupler's shutdown (DESIGN §3 from a node's side).
///
/// The loop greets, calls `open` in a coupled run (the initial wet-surface exchange), sends the
/// initial totals, proposes a step, then answers checkpoint requests and restores, and
/// for each step plan calls `advance` (the node's side of the step, coupling iterations
/// included), records probes, writes the planned output, sends the totals and the next
/// proposal. Probe files are written at the end, also when the run fails: they then hold the
/// steps completed before the failure (what a user debugging it needs first).
pub fn run_node<N: NodeModel + ?Sized>(
    kind: NodeKind,
    node: &mut N,
    link: &mut Link<'_>,
    cfg: &LoopConfig,
    open: impl FnMut(&mut N, &mut Link<'_>) -> Result<(), NodeError>,
    advance: impl FnMut(&mut N, &mut Link<'_>, &StepPlan) -> Result<(), NodeError>,
) -> Result<(), NodeError> {
    let run = node_loop(kind, node, link, cfg, open, advance);
    let probes = finish(node, cfg);
    match (run, probes) {
        (Err(e), Err(lost)) => {
            warn!("the probe files of the failed run were not written: {lost}");
            Err(e)
        }
        (Err(e), Ok(())) => Err(e),
        (Ok(()), Err(lost)) => {
            // The coupler reads it from the bus once this node has exited, so that the run
            // does not end as completed with a file missing.
            let _ = link.send(&Message::Failure(Failure {
                stamp: Stamp::step(0),
                node: kind,
                report: lost.to_string(),
            }));
            Err(lost)
        }
        (Ok(()), Ok(())) => Ok(()),
    }
}

/// Writes output `k`; a failure is reported to the coupler (its status then names the file and
/// the error) before it ends the node.
fn write_output<N: NodeModel + ?Sized>(
    node: &mut N,
    link: &mut Link<'_>,
    out: &Path,
    (k, step, t): (u32, u64, f64),
) -> Result<(), NodeError> {
    node.write_output(k, t, out).map_err(|source| {
        let err = NodeError::output(out, source);
        let _ = link.send(&Message::Failure(Failure {
            stamp: Stamp::step(step),
            node: link.me(),
            report: err.to_string(),
        }));
        err
    })
}

/// [`run_node`] without the probe files.
fn node_loop<N: NodeModel + ?Sized>(
    kind: NodeKind,
    node: &mut N,
    link: &mut Link<'_>,
    cfg: &LoopConfig,
    mut open: impl FnMut(&mut N, &mut Link<'_>) -> Result<(), NodeError>,
    mut advance: impl FnMut(&mut N, &mut Link<'_>, &StepPlan) -> Result<(), NodeError>,
) -> Result<(), NodeError> {
    let greeted = link.greet(Hello {
        node: kind,
        protocol_version: PROTOCOL_VERSION,
        scene_hash: cfg.scene_hash,
        implementation: node.implementation().to_string(),
        capabilities: vec!["checkpoint".into()],
    });
    if let Err(LinkError::ShutDown) = greeted {
        debug!("shut down by the coupler before it welcomed this node");
        return Ok(());
    }
    greeted?;
    debug!(
        "greeted the coupler: {} {kind}, protocol {PROTOCOL_VERSION}, scene hash {:016x}, {}",
        node.implementation(),
        cfg.scene_hash,
        if cfg.coupled { "coupled" } else { "alone" }
    );
    if cfg.coupled {
        match open(node, link) {
            Err(NodeError::Stopped { step }) => {
                debug!("shut down by the coupler before step {step}");
                return Ok(());
            }
            other => other?,
        }
    }
    // NOTE: after `open`, so the initial output and the fluid's initial totals already weigh its
    // cells by the fluid fraction of the initial wet surface.
    let first_planned = u32::from(cfg.initial_output);
    if let (true, Some(out)) = (cfg.initial_output, &cfg.out) {
        write_output(node, link, out, (0, 0, 0.0))?;
    }
    link.send(&Message::ConservedTotals(node.totals(Stamp::step(0), 0.0)))?;
    let mut step = 0;
    propose_node(link, step, node)?;
    loop {
        match link.recv()? {
            Message::Shutdown(shutdown) => {
                debug!(
                    "shutdown at step {}: {:?}",
                    shutdown.stamp.step, shutdown.reason
                );
                break;
            }
            Message::CheckpointRequest(r) => {
                let bytes = node.checkpoint();
                debug!("checkpoint of step {}: {} bytes", r.stamp.step, bytes.len());
                link.send(&Message::Checkpoint(Checkpoint {
                    stamp: r.stamp,
                    node: kind,
                    bytes,
                }))?;
            }
            Message::Checkpoint(c) => {
                node.restore(&c.bytes).map_err(|e| fail(link, c.stamp, e))?;
                step = c.stamp.step;
                debug!(
                    "restored the checkpoint of step {step} ({} bytes)",
                    c.bytes.len()
                );
                propose_node(link, step, node)?;
            }
            Message::StepPlan(plan) => {
                step = plan.stamp.step;
                match advance(node, link, &plan) {
                    // The coupler ended the run inside the step (Ctrl-C, a failure elsewhere).
                    Err(NodeError::Stopped { .. }) => {
                        debug!("shut down by the coupler inside step {step}");
                        break;
                    }
                    other => other?,
                }
                let t_end = plan.t_end();
                node.record_probes(t_end);
                if let Some(out) = &cfg.out {
                    node.write_probes(out, false).map_err(|source| {
                        let err = NodeError::output(out, source);
                        let _ = link.send(&Message::Failure(Failure {
                            stamp: Stamp::step(step),
                            node: link.me(),
                            report: err.to_string(),
                        }));
                        err
                    })?;
                }
                if let (Some(k), Some(out)) = (plan.output, &cfg.out) {
                    write_output(node, link, out, (k + first_planned, step, t_end))?;
                    debug!("output {} at t = {t_end:.6e} s", k + first_planned);
                }
                debug!(
                    "step {step} done: t = {t_end:.6e} s, dt = {:.4e} s",
                    plan.dt
                );
                link.send(&Message::ConservedTotals(
                    node.totals(Stamp::step(step), t_end),
                ))?;
                step += 1;
                propose_node(link, step, node)?;
            }
            other => {
                return Err(unexpected(
                    &other,
                    "StepPlan, CheckpointRequest or Shutdown",
                ));
            }
        }
    }
    Ok(())
}

/// The end of a node's run: the probe files.
fn finish<N: NodeModel + ?Sized>(node: &mut N, cfg: &LoopConfig) -> Result<(), NodeError> {
    if let Some(out) = &cfg.out {
        node.write_probes(out, true)
            .map_err(|source| NodeError::output(out, source))?;
        debug!("probes written into {}", out.display());
    }
    Ok(())
}

/// What a node loop needs from the scene.
#[derive(Clone, Debug)]
pub struct LoopConfig {
    /// Hash of the resolved scene.
    pub scene_hash: u64,
    /// The other side takes part (the loads / trial-state exchange runs each step).
    pub coupled: bool,
    /// Where outputs go (`None`: write nothing).
    pub out: Option<PathBuf>,
    /// The scene asks for an output at t = 0 ([`crate::scene::Scene::initial_output`]): the
    /// initial state is written as output 0 before the first step, and the output `k` of a step
    /// plan is written as output `k + 1`.
    pub initial_output: bool,
}

/// How a node's run ended.
#[derive(Debug, thiserror::Error)]
pub enum NodeError {
    /// Exchange with the coupler failed.
    #[error(transparent)]
    Link(#[from] LinkError),
    /// Numerical trouble, already reported to the coupler.
    #[error("numerical failure at step {step}: {report}")]
    Numerical {
        /// Step.
        step: u64,
        /// Report.
        report: String,
    },
    /// The coupler's shutdown arrived inside a step (the run was interrupted or failed
    /// elsewhere): not a failure of this node, whose loop ends cleanly.
    #[error("shut down by the coupler inside step {step}")]
    Stopped {
        /// The step the node was in.
        step: u64,
    },
    /// Writing outputs failed.
    #[error("writing outputs to {dir}: {source}")]
    Output {
        /// The output directory.
        dir: String,
        /// The IO error.
        source: std::io::Error,
    },
}

impl NodeError {
    /// An output error in `dir`.
    pub fn output(dir: &Path, source: std::io::Error) -> NodeError {
        NodeError::Output {
            dir: dir.display().to_string(),
            source,
        }
    }
}

/// A node's largest stable step and what limits it: the proposal it sends for a step
/// ([`DtProposal`]), and what the coupler's agreement (`coupler-node`'s `dt::Proposal`) names.
#[derive(Clone, Debug, PartialEq)]
pub struct StepLimit {
    /// Largest stable time step \[s\]; `f64::INFINITY` when the node sets no limit.
    pub dt_max: f64,
    /// What limits it (for example `"cfl at cell [3, 4]"`, `"ghost states beside the moving body ..."`), for the diagnostics
    /// and the report of a step that collapses.
    pub limiter: String,
}

impl StepLimit {
    /// No limit from this node.
    pub fn none() -> StepLimit {
        StepLimit {
            dt_max: f64::INFINITY,
            limiter: "none".into(),
        }
    }
}

/// Sends this node's time-step proposal for `step`.
pub fn propose(link: &mut Link<'_>, step: u64, limit: StepLimit) -> Result<(), NodeError> {
    link.send(&Message::DtProposal(DtProposal {
        stamp: Stamp::step(step),
        dt_max: limit.dt_max,
        limiter: limit.limiter,
    }))?;
    Ok(())
}

/// The `stamp.iteration` of a solid's second proposal, the bound of its sub-steps
/// ([`NodeModel::substep_bound`]); a node's proposal for the coupling step has iteration 0.
pub const SUBSTEP_BOUND_ITERATION: u32 = 1;

/// Sends `node`'s proposal for `step`, then its sub-step bound if it has one.
pub fn propose_node<N: NodeModel + ?Sized>(
    link: &mut Link<'_>,
    step: u64,
    node: &N,
) -> Result<(), NodeError> {
    propose(link, step, node.dt_max())?;
    if let Some(bound) = node.substep_bound() {
        link.send(&Message::DtProposal(DtProposal {
            stamp: Stamp {
                step,
                iteration: SUBSTEP_BOUND_ITERATION,
            },
            dt_max: bound.dt_max,
            limiter: bound.limiter,
        }))?;
    }
    Ok(())
}

/// The error for a message that does not fit the handshake; for a `Shutdown` inside a step,
/// [`NodeError::Stopped`] (the loop ends cleanly).
pub fn unexpected(msg: &Message, expected: &str) -> NodeError {
    if let Message::Shutdown(shutdown) = msg {
        return NodeError::Stopped {
            step: shutdown.stamp.step,
        };
    }
    NodeError::Link(LinkError::Unexpected(format!(
        "{:?} (step {}, iteration {}) while waiting for {expected}",
        msg.kind(),
        msg.stamp().step,
        msg.stamp().iteration
    )))
}

/// Reports numerical trouble to the coupler, then returns the error that ends the node.
pub fn fail(link: &mut Link<'_>, stamp: Stamp, report: String) -> NodeError {
    // The coupler may already be gone; the local error is what matters then.
    let _ = link.send(&Message::Failure(Failure {
        stamp,
        node: link.me(),
        report: report.clone(),
    }));
    NodeError::Numerical {
        step: stamp.step,
        report,
    }
}

/// Longest deadline a command line accepts for one message, in seconds (11.6 days).
pub const MAX_TIMEOUT_S: f64 = 1e6;

/// Reads a `--timeout-s` value: a number of seconds in (0, [`MAX_TIMEOUT_S`]]. Negative, zero,
/// NaN, infinite and absurdly large values are refused with the reason (a `Duration` cannot
/// hold them).
pub fn parse_timeout_s(text: &str) -> Result<std::time::Duration, String> {
    let secs: f64 = text
        .trim()
        .parse()
        .map_err(|_| format!("expected a number of seconds, found {text:?}"))?;
    if secs.is_finite() && secs > 0.0 && secs <= MAX_TIMEOUT_S {
        Ok(std::time::Duration::from_secs_f64(secs))
    } else {
        Err(format!(
            "expected a number of seconds in (0, {MAX_TIMEOUT_S:e}], found {text}"
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn timeouts_outside_the_range_are_refused() {
        assert_eq!(
            parse_timeout_s("2.5"),
            Ok(std::time::Duration::from_millis(2500))
        );
        for bad in ["-1", "nan", "NaN", "inf", "-inf", "1e30", "0", "ten", ""] {
            let err = parse_timeout_s(bad).expect_err(bad);
            assert!(err.contains("seconds"), "{bad}: {err}");
        }
    }
}
