//! Strong scaling of the fluid over MPI ranks (issue 16): the 3-D blast of
//! `scenes/blast-3d.toml` on `CELLS`³ cells (default 128), one thread per rank, `STEPS` steps
//! (default 4) after one warm-up step, cut as `protocol::decomp::choose` cuts it or as
//! `DECOMP=kx,ky,kz` says (issue 40); rank 0 prints one JSON line with the wall time per step,
//! the time each rank spent in halo exchanges (its share of the step) and the halo bytes.
//! Not a criterion bench: a driver for the measurement the issue asks for.
//!
//! ```text
//! cargo bench -p fluid-node --features mpi --bench mpi_scaling --no-run
//! mpirun -n 1 target/release/deps/mpi_scaling-*  # then -n 2 (OMPI_ALLOW_RUN_AS_ROOT... as root)
//! ```

use std::sync::atomic::Ordering;
use std::time::Instant;

use fluid_node::fv::FluidSolver;
use fluid_node::fv::comm::Comm;
use fluid_node::ranks::mpi::MpiComm;

fn env(name: &str, default: u32) -> u32 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn main() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/blast-3d.toml");
    let text = std::fs::read_to_string(&path).expect("scenes/blast-3d.toml is readable");
    let scene = protocol::scene::Scene::from_toml_str(&text, "blast-3d.toml").expect("valid scene");
    let mut fluid = scene.fluid.clone().expect("a [fluid] table");
    let n = env("CELLS", 128);
    fluid.cells = vec![n; 3];
    let steps = env("STEPS", 4);
    let (_universe, comm) = MpiComm::init().expect("MPI");
    let calls = comm.duplicate();
    let (rank, ranks) = (comm.rank(), comm.size());
    fluid.ranks = ranks as u32;
    if let Ok(d) = std::env::var("DECOMP") {
        let dims: Vec<u32> = d
            .split(',')
            .map(|k| k.trim().parse().expect("DECOMP=kx,ky,kz"))
            .collect();
        fluid.decomposition = Some(dims);
    }
    let dims = fluid.process_grid().expect("a process grid that fits");
    let clock = comm.clock();
    let mut solver = FluidSolver::from_scene_on(&fluid, 1, Box::new(comm)).expect("solver");
    let warm = solver.advance(solver.max_dt());
    assert!(warm.ok());
    clock.nanos.store(0, Ordering::Relaxed);
    clock.bytes.store(0, Ordering::Relaxed);
    let mut sync = vec![0u8];
    calls.broadcast(0, &mut sync);
    let start = Instant::now();
    for _ in 0..steps {
        let report = solver.advance(solver.max_dt());
        assert!(report.ok(), "{:?}", report.troubles);
    }
    calls.broadcast(0, &mut sync);
    let wall = start.elapsed().as_secs_f64() / f64::from(steps);
    let halo = clock.nanos.load(Ordering::Relaxed) as f64 * 1e-9 / f64::from(steps);
    let bytes = clock.bytes.load(Ordering::Relaxed) as f64 / f64::from(steps);
    let mine = fluid_node::fv::comm::f64_bytes(&[halo, bytes]);
    let all = calls.all_gather(&mine);
    if rank == 0 {
        let per_rank: Vec<Vec<f64>> = all.iter().map(fluid_node::fv::comm::bytes_f64).collect();
        let halo_s: Vec<f64> = per_rank.iter().map(|v| v[0]).collect();
        let halo_bytes: Vec<f64> = per_rank.iter().map(|v| v[1]).collect();
        let cells = f64::from(n).powi(3);
        println!(
            "{{\"ranks\": {ranks}, \"dims\": {dims:?}, \"cells\": {n}, \"steps\": {steps}, \
             \"s_per_step\": {wall:.4}, \
             \"cell_updates_per_s\": {:.4e}, \"halo_s_per_step\": {halo_s:?}, \
             \"halo_share\": {:?}, \"halo_bytes_sent_per_step\": {halo_bytes:?}}}",
            cells / wall,
            halo_s
                .iter()
                .map(|h| (h / wall * 1e4).round() / 1e4)
                .collect::<Vec<_>>(),
        );
    }
}
