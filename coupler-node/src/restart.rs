//! `coupler-node run SCENE --restart FILE.mcap --step N`: a run resumed from the checkpoints a
//! record holds at step N (the coupler's and every node's), which goes on exactly as the
//! recorded run did from there.

use std::path::Path;

use anyhow::Context;
use protocol::codec;
use protocol::scene::Scene;
use protocol::wire::{Checkpoint, Message, NodeKind};

use crate::record;
use crate::scheme::{CouplerCheckpoint, Resume};

/// Reads the checkpoints of `step` from the record `file` of a run of `scene`.
pub fn load(file: &Path, step: u64, scene: &Scene) -> anyhow::Result<Resume> {
    let what = || format!("restarting from {} at step {step}", file.display());
    let bytes =
        std::fs::read(file).with_context(|| format!("reading record {}", file.display()))?;
    let rec = record::read_recording(&bytes)
        .with_context(|| format!("reading record {}", file.display()))?;
    let recorded = rec
        .metadata
        .get("scene")
        .and_then(|m| m.get("toml"))
        .with_context(|| format!("{}: the record holds no scene", what()))?;
    let recorded = Scene::from_toml_str(recorded, "the record's scene")
        .map_err(|e| anyhow::anyhow!("{}: {e}", what()))?;
    anyhow::ensure!(
        recorded.hash() == scene.hash(),
        "{}: the scene differs from the recorded one (hash {:016x}, recorded {:016x}); restart with the scene the record holds (its `scene.toml`) and the same --fluid/--solid",
        what(),
        scene.hash(),
        recorded.hash()
    );
    let checkpoint = |node: NodeKind| -> anyhow::Result<Checkpoint> {
        let topic = record::checkpoint_topic(node).expect("every node has a checkpoint topic");
        let Some(m) = rec.topic(topic).find(|m| m.step == step) else {
            let steps: Vec<u64> = rec
                .topic(record::checkpoint_topic(NodeKind::Coupler).expect("a topic"))
                .map(|m| m.step)
                .collect();
            anyhow::bail!(
                "{}: the record has no {topic} at that step (steps with a coupler checkpoint: {steps:?}; `run.checkpoint_every` sets them)",
                what()
            );
        };
        match codec::decode(&m.data) {
            Ok((_, Message::Checkpoint(c))) if c.node == node && c.stamp.step == step => Ok(c),
            Ok((_, other)) => {
                anyhow::bail!("{}: {topic} holds a {:?}", what(), other.kind())
            }
            Err(e) => anyhow::bail!("{}: {topic} does not decode: {e}", what()),
        }
    };
    let own = checkpoint(NodeKind::Coupler)?;
    let coupler: CouplerCheckpoint = codec::decode_blob(&own.bytes)
        .map_err(|e| anyhow::anyhow!("{}: /checkpoint/coupler: {e}", what()))?;
    let mut nodes = Vec::new();
    for (node, present) in [
        (NodeKind::Fluid, scene.fluid.is_some()),
        (NodeKind::Solid, scene.solid.is_some()),
    ] {
        if present {
            nodes.push(checkpoint(node)?);
        }
    }
    Ok(Resume { coupler, nodes })
}
