//! `coupler-node replay FILE --step N --node coupler`: re-run the coupler's state machine on the
//! recorded node messages and compare every frame it sends with the record.
//!
//! The coupler resumes from its nearest checkpoint at or before step N (`/checkpoint/coupler`:
//! the accepted states the predictors extrapolate, IQN-ILS's columns, the ledger), or starts
//! fresh at the greeting when there is none. From there every recorded node → coupler frame and
//! node checkpoint is fed to it in file order, and each frame it sends (and each checkpoint of
//! its own it takes) must equal the next recorded one of that destination, byte for byte, up to
//! the end of step N. The relaxed and predicted inputs are among those frames, so `identical`
//! means the iterates are bit for bit those of the run. No process is started: the state
//! machine is sans-IO.

use std::collections::VecDeque;

use anyhow::Context;
use protocol::codec;
use protocol::scene::Scene;
use protocol::wire::{Message, NodeKind};

use crate::frame_diff::{Outcome, compare};
use crate::record::{self, Recording};
use crate::scheme::{Action, Coupler, CouplerCheckpoint, CouplerConfig};

/// Where a frame of the record goes, from the coupler's side.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Leg {
    /// A node's message or checkpoint, fed to the coupler.
    In(NodeKind),
    /// A frame the coupler sent to that node.
    Out(NodeKind),
    /// The coupler's own checkpoint.
    Own,
}

fn leg(topic: &str) -> Option<Leg> {
    [NodeKind::Fluid, NodeKind::Solid]
        .into_iter()
        .find_map(|node| {
            if Some(topic) == record::frame_topic(node, NodeKind::Coupler)
                || Some(topic) == record::checkpoint_topic(node)
            {
                Some(Leg::In(node))
            } else if Some(topic) == record::frame_topic(NodeKind::Coupler, node) {
                Some(Leg::Out(node))
            } else {
                None
            }
        })
        .or_else(|| {
            (Some(topic) == record::checkpoint_topic(NodeKind::Coupler)).then_some(Leg::Own)
        })
}

/// Re-runs the coupler of `rec` (whose scene is `scene`) up to the end of `step`.
pub fn replay(rec: &Recording, scene: &Scene, step: u64) -> anyhow::Result<Outcome> {
    let frames: Vec<(Leg, u64, &[u8])> = rec
        .messages
        .iter()
        .filter_map(|m| Some((leg(&m.topic)?, m.step, m.data.as_slice())))
        .collect();
    let last_step = frames
        .iter()
        .filter(|(leg, _, _)| matches!(leg, Leg::In(_)))
        .map(|(_, s, _)| *s)
        .max()
        .context(
            "the record holds no node messages (record = \"exchange\" or \"all\" keeps them)",
        )?;
    anyhow::ensure!(
        step <= last_step,
        "step {step} is past the end of the record: its last step is {last_step}"
    );
    let cfg = CouplerConfig::from_scene(scene);
    // The nearest checkpoint of the coupler at or before the step.
    let resume = frames
        .iter()
        .enumerate()
        .rfind(|(_, (leg, s, _))| *leg == Leg::Own && *s <= step);
    let (mut coupler, start, from_step) = match resume {
        Some((at, (_, s, frame))) => {
            let checkpoint = match codec::decode(frame) {
                Ok((_, Message::Checkpoint(c))) if c.node == NodeKind::Coupler => c,
                Ok((_, other)) => {
                    anyhow::bail!("/checkpoint/coupler of step {s} holds a {:?}", other.kind())
                }
                Err(e) => anyhow::bail!("/checkpoint/coupler of step {s} does not decode: {e}"),
            };
            let state: CouplerCheckpoint = codec::decode_blob(&checkpoint.bytes)
                .map_err(|e| anyhow::anyhow!("/checkpoint/coupler of step {s}: {e}"))?;
            let coupler = Coupler::restore(cfg, &state)
                .map_err(|e| anyhow::anyhow!("/checkpoint/coupler of step {s}: {e}"))?;
            (coupler, at + 1, *s)
        }
        None => (Coupler::new(cfg), 0, 0),
    };
    // What the coupler must send from there, per destination, in file order.
    let slot = |leg: Leg| match leg {
        Leg::Out(NodeKind::Fluid) => Some(0),
        Leg::Out(NodeKind::Solid) => Some(1),
        Leg::Own => Some(2),
        Leg::In(_) | Leg::Out(NodeKind::Coupler) => None,
    };
    let mut expected: [VecDeque<&[u8]>; 3] = Default::default();
    for (leg, _, frame) in &frames[start..] {
        if let Some(k) = slot(*leg) {
            expected[k].push_back(frame);
        }
    }
    let mut compared = 0;
    let mut out = Vec::new();
    for (leg, s, frame) in &frames[start..] {
        let Leg::In(from) = *leg else { continue };
        if *s > step {
            break;
        }
        let (_, msg) = codec::decode(frame)
            .map_err(|e| anyhow::anyhow!("{from} frame of step {s} does not decode: {e}"))?;
        let actions = match coupler.on_message(from, msg) {
            Ok(actions) => actions,
            Err(e) => {
                return Ok(Outcome::Differs(format!(
                    "the replayed coupler stops at step {s}: {e}"
                )));
            }
        };
        for action in actions {
            let (to, msg) = match action {
                Action::Send(to, msg) => (Leg::Out(to), msg),
                Action::CouplerCheckpoint(c) => (Leg::Own, Message::Checkpoint(c)),
                Action::StepDone(_) | Action::Checkpoint(_) | Action::Finished(_) => continue,
            };
            codec::encode_into(NodeKind::Coupler, &msg, &mut out);
            let Some(recorded) = slot(to).and_then(|k| expected[k].pop_front()) else {
                return Ok(Outcome::Differs(format!(
                    "step {s}: the replayed coupler sends a {:?} ({to:?}) that the record does not have",
                    msg.kind()
                )));
            };
            let channel = match to {
                Leg::Own => "/checkpoint/coupler",
                Leg::Out(node) => record::frame_topic(NodeKind::Coupler, node).unwrap_or("?"),
                Leg::In(_) => unreachable!("only frames the coupler sends are compared"),
            };
            if let Some(diff) = compare(channel, recorded, &out) {
                return Ok(Outcome::Differs(diff));
            }
            compared += 1;
        }
    }
    anyhow::ensure!(compared > 0, "nothing to compare up to step {step}");
    Ok(Outcome::Identical {
        compared,
        from_step,
    })
}
