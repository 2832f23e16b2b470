//! `fluid-node` under `mpirun -n K` (feature `mpi`): MPI set up, the scene shared from rank 0,
//! rank 0 serving the bus with a [`Leader`], the others following it.

use anyhow::Context;
use protocol::scene::Scene;
use protocol::serve::{ServeOptions, serve};
use protocol::wire::NodeKind;

use crate::exchange::RealFluid;
use crate::fv::comm::Comm;
use crate::ranks::mpi::MpiComm;
use crate::ranks::node::{Leader, follow, stop};

/// What the first broadcast of rank 0 starts with when it carries the scene (otherwise it is
/// [`crate::ranks::node::Call::Stop`]).
const SCENE: &[u8] = b"scene\n";

/// Runs this process's rank of a fluid of `ranks` ranks (`fluid.ranks` of the scene).
pub fn serve_ranks(opts: &ServeOptions, ranks: u32) -> anyhow::Result<()> {
    let (_universe, comm) = MpiComm::init()?;
    let calls = comm.duplicate();
    let rank = comm.rank();
    anyhow::ensure!(
        comm.size() == ranks as usize,
        "fluid.ranks = {ranks} but this MPI job has {} rank(s) (the coupler starts the fluid \
         with mpirun -n {ranks}; rank {rank})",
        comm.size()
    );
    tracing::debug!("rank {rank} of {ranks}, pid {}", std::process::id());
    if rank == 0 {
        let calls: &dyn Comm = &calls;
        let result = serve(
            NodeKind::Fluid,
            opts,
            |scene, implementation| {
                // The other ranks build from the same text.
                let mut text = [SCENE, scene.to_toml().as_bytes()].concat();
                calls.broadcast(0, &mut text);
                if implementation != "real" {
                    return Err(format!(
                        "fluid.ranks = {ranks} runs the real fluid only, not {implementation:?}"
                    ));
                }
                // The wire boundary: `serve` reports the text to the coupler.
                let inner =
                    RealFluid::from_scene_on(scene, Box::new(comm)).map_err(|e| e.to_string())?;
                Ok(Leader { inner, calls })
            },
            |mut model, link, cfg| crate::node::run(&mut model, link, cfg),
        );
        // NOTE: a rank 0 that failed before building its model has not sent the scene: the
        // others then take this first message for it, and stop.
        stop(calls);
        result?;
        return Ok(());
    }
    let mut first = Vec::new();
    calls.broadcast(0, &mut first);
    let Some(text) = first.strip_prefix(SCENE) else {
        // Rank 0 stopped before it had a scene (its error is the one reported).
        return Ok(());
    };
    let text = std::str::from_utf8(text).context("the scene from rank 0")?;
    let scene = Scene::from_toml_str(text, &opts.scene.display().to_string())?;
    let model = RealFluid::from_scene_on(&scene, Box::new(comm));
    follow(model, || {
        let mut bytes = Vec::new();
        calls.broadcast(0, &mut bytes);
        bytes
    })
    .map_err(|e| anyhow::anyhow!("rank {rank}: {e}"))
}
