//! `coupler-node replay FILE --step N --node fluid|solid`: re-run one node on the recorded
//! inputs and compare every message it sends with the record (`--node coupler`: the coupler's
//! state machine, see [`crate::coupler_replay`]).
//!
//! The node's binary (real or double) is started on the recorded scene. The replay plays the
//! coupler: it sends the recorded coupler → node frames and compares each node → coupler frame
//! with the recorded one, byte for byte. With checkpoints in the record, the node is restored
//! from the nearest checkpoint at or before step N (after its greeting), and the comparison
//! starts there. The first difference is reported with the channel, step, iteration, field,
//! index and both values.

use std::path::PathBuf;
use std::time::Duration;

use crate::frame_diff::compare;
use crate::record::{self, Recording};
use anyhow::Context;
use protocol::codec;
use protocol::transport::Transport;
use protocol::wire::{Message, MessageKind, NodeKind, Shutdown, ShutdownReason, Stamp};

pub use crate::frame_diff::Outcome;

/// Options of `coupler-node replay`.
#[derive(Clone, Debug)]
pub struct ReplayOptions {
    /// The record.
    pub file: PathBuf,
    /// Last step compared.
    pub step: u64,
    /// The node to re-run.
    pub node: NodeKind,
    /// Implementation to run (default: the one in the recorded hello).
    pub implementation: Option<String>,
    /// Deadline for any one message.
    pub timeout: Duration,
    /// Explicit node binary.
    pub bin: Option<PathBuf>,
    /// `-v`/`-q` of the node's logs (the coupler's own).
    pub verbosity: protocol::logs::Verbosity,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Dir {
    FromNode,
    ToNode,
    Checkpoint,
}

fn script(rec: &Recording, node: NodeKind) -> Vec<(Dir, u64, Vec<u8>)> {
    let from = record::frame_topic(node, NodeKind::Coupler).expect("a node topic");
    let to = record::frame_topic(NodeKind::Coupler, node).expect("a node topic");
    let ckpt = record::checkpoint_topic(node).expect("a node topic");
    rec.messages
        .iter()
        .filter_map(|m| {
            let dir = if m.topic == from {
                Dir::FromNode
            } else if m.topic == to {
                Dir::ToNode
            } else if m.topic == ckpt {
                Dir::Checkpoint
            } else {
                return None;
            };
            Some((dir, m.step, m.data.clone()))
        })
        .collect()
}

/// Runs the replay.
pub fn replay(opts: &ReplayOptions) -> anyhow::Result<Outcome> {
    let bytes = std::fs::read(&opts.file)
        .with_context(|| format!("reading record {}", opts.file.display()))?;
    let rec = record::read_recording(&bytes)
        .with_context(|| format!("reading record {}", opts.file.display()))?;
    let scene_toml = rec
        .metadata
        .get("scene")
        .and_then(|m| m.get("toml"))
        .with_context(|| {
            format!(
                "the record {} holds no scene metadata (a run killed before its first step?)",
                opts.file.display()
            )
        })?;
    if opts.node == NodeKind::Coupler {
        let scene = protocol::scene::Scene::from_toml_str(scene_toml, "the record's scene")
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        return crate::coupler_replay::replay(&rec, &scene, opts.step);
    }
    let frames = script(&rec, opts.node);
    anyhow::ensure!(
        !frames.is_empty(),
        "the record {} holds no messages of the {} node (record = \"exchange\" or \"all\" keeps them)",
        opts.file.display(),
        opts.node
    );
    let recorded_impl = frames
        .iter()
        .find_map(|(dir, _, f)| match (dir, codec::decode(f)) {
            (Dir::FromNode, Ok((_, Message::Hello(h)))) => Some(h.implementation),
            _ => None,
        })
        .context("the record holds no hello of that node")?;
    let implementation = opts.implementation.clone().unwrap_or(recorded_impl);
    // NOTE: a step past the record's end would compare only the steps before it and report
    // `identical` for a step that never ran.
    let last_step = frames
        .iter()
        .filter(|(dir, _, _)| *dir == Dir::FromNode)
        .map(|(_, step, _)| *step)
        .max()
        .unwrap_or(0);
    anyhow::ensure!(
        opts.step <= last_step,
        "step {} is past the end of the record: its last step of the {} node is {last_step}",
        opts.step,
        opts.node
    );
    // Nearest checkpoint at or before the step.
    let checkpoint = frames
        .iter()
        .filter(|(dir, step, _)| *dir == Dir::Checkpoint && *step <= opts.step)
        .map(|(_, step, f)| (*step, f.clone()))
        .next_back();

    let dir = std::env::temp_dir().join(format!("cosim-replay-{}", std::process::id()));
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let scene_path = dir.join("scene.toml");
    std::fs::write(&scene_path, scene_toml)
        .with_context(|| format!("writing {}", scene_path.display()))?;
    let run_id = format!("replay{}", std::process::id());
    protocol::bus::cleanup_run(&run_id)?;
    let mut bus = protocol::bus::Bus::open(&run_id, NodeKind::Coupler, &[opts.node])?;
    let binary = crate::preflight::node_binary(opts.node, opts.bin.as_deref())?;
    let mut child = std::process::Command::new(&binary)
        .arg("--scene")
        .arg(&scene_path)
        .arg("--run-id")
        .arg(&run_id)
        .arg("--double")
        .arg(&implementation)
        .arg("--timeout-s")
        .arg(opts.timeout.as_secs_f64().to_string())
        .args(opts.verbosity.to_args())
        .stdin(std::process::Stdio::null())
        .spawn()
        .with_context(|| format!("starting {}", binary.display()))?;
    tracing::debug!(
        "replaying the {} node ({implementation}) to step {}{}: {} (pid {})",
        opts.node,
        opts.step,
        checkpoint
            .as_ref()
            .map_or(String::new(), |(step, _)| format!(
                " from its checkpoint of step {step}"
            )),
        binary.display(),
        child.id()
    );
    let result = drive(&mut bus, opts, &frames, checkpoint);
    // Tell the node to stop, whatever happened, then reap it.
    let bye = codec::encode(
        NodeKind::Coupler,
        &Message::Shutdown(Shutdown {
            stamp: Stamp::step(opts.step),
            reason: ShutdownReason::Completed,
        }),
    );
    let _ = bus.send(opts.node, &bye);
    let deadline = std::time::Instant::now() + Duration::from_secs(2);
    while std::time::Instant::now() < deadline {
        if let Ok(Some(_)) = child.try_wait() {
            break;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let _ = child.kill();
    let _ = child.wait();
    drop(bus);
    let _ = protocol::bus::cleanup_run(&run_id);
    let _ = std::fs::remove_dir_all(&dir);
    result
}

fn drive(
    bus: &mut dyn Transport,
    opts: &ReplayOptions,
    frames: &[(Dir, u64, Vec<u8>)],
    checkpoint: Option<(u64, Vec<u8>)>,
) -> anyhow::Result<Outcome> {
    let node = opts.node;
    let recv = |bus: &mut dyn Transport| -> anyhow::Result<Vec<u8>> {
        let (_, frame) = bus
            .recv(Some(node), opts.timeout)
            .with_context(|| format!("waiting for the {node} node"))?;
        Ok(frame)
    };
    let mut compared = 0;
    let mut at = 0;
    let from_step = checkpoint.as_ref().map_or(0, |c| c.0);
    // The greeting: compared as well, it depends only on the scene.
    while at < frames.len() {
        let (dir, _, frame) = &frames[at];
        let kind = codec::decode_header(frame).map(|h| h.kind).ok();
        if *dir == Dir::FromNode && kind == Some(MessageKind::DtProposal) {
            break;
        }
        match dir {
            Dir::ToNode => bus.send(node, frame)?,
            Dir::FromNode => {
                let got = recv(bus)?;
                if let Some(diff) = compare(&format!("{node}-to-coupler"), frame, &got) {
                    return Ok(Outcome::Differs(diff));
                }
                compared += 1;
            }
            Dir::Checkpoint => {}
        }
        at += 1;
    }
    if let Some((step, ckpt)) = &checkpoint {
        // The fresh node proposes for step 0 (a solid with `run.solid_substeps` twice, as the
        // record's first proposals show); restore it, then resume where the record has the
        // proposal for the checkpoint's step.
        let first = frames[at..]
            .iter()
            .filter(|(dir, s, f)| {
                *dir == Dir::FromNode
                    && *s == 0
                    && codec::decode_header(f).is_ok_and(|h| h.kind == MessageKind::DtProposal)
            })
            .count()
            .max(1);
        for _ in 0..first {
            let _ = recv(bus)?;
        }
        bus.send(node, ckpt)?;
        at = frames
            .iter()
            .position(|(dir, s, f)| {
                *dir == Dir::FromNode
                    && *s == *step
                    && codec::decode_header(f).is_ok_and(|h| h.kind == MessageKind::DtProposal)
            })
            .context("the record has no proposal at the checkpoint's step")?;
    }
    while at < frames.len() {
        let (dir, step, frame) = &frames[at];
        if *step > opts.step {
            break;
        }
        match dir {
            Dir::ToNode => {
                let kind = codec::decode_header(frame).map(|h| h.kind).ok();
                // Checkpoint requests are not replayed (the node's answer is a checkpoint,
                // compared only through the state it leads to).
                if kind != Some(MessageKind::CheckpointRequest)
                    && kind != Some(MessageKind::Shutdown)
                {
                    bus.send(node, frame)?;
                }
            }
            Dir::FromNode => {
                let got = recv(bus)?;
                if let Some(diff) = compare(&format!("{node}-to-coupler"), frame, &got) {
                    return Ok(Outcome::Differs(diff));
                }
                compared += 1;
            }
            Dir::Checkpoint => {}
        }
        at += 1;
    }
    anyhow::ensure!(compared > 0, "nothing to compare up to step {}", opts.step);
    Ok(Outcome::Identical {
        compared,
        from_step,
    })
}
