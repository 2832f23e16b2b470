//! Costs of the coupling machinery (run by hand, numbers in the issue notes):
//! - one semi-implicit iteration round trip with 10^4 wet triangles (trial state to the fluid,
//!   loads back, both encoded and decoded), over the iceoryx2 bus and in memory;
//! - the doubles scene in one process (memory transport) and through the three processes
//!   (binaries from the same target folder), with and without recording.
//!
//! `cargo bench -p cosim-tests --bench coupling` (build the binaries first: `cargo build --release`).

use std::time::{Duration, Instant};

use protocol::codec;
use protocol::transport::{MemoryTransport, Transport};
use protocol::wire::{
    Decision, FixedPointDecision, InterfaceLoads, Message, NodeKind, SolidState, Stamp, WetSurface,
};

fn trial_state(n_triangles: usize) -> SolidState {
    // A strip of triangles, 6 per particle.
    let n_particles = n_triangles / 6;
    let n_vertices = n_triangles / 2 + 2;
    SolidState {
        stamp: Stamp {
            step: 7,
            iteration: 3,
        },
        dim: 3,
        position: (0..3 * n_particles).map(|i| i as f64 * 1e-3).collect(),
        orientation: (0..n_particles)
            .flat_map(|_| [1.0, 0.0, 0.0, 0.0])
            .collect(),
        velocity: vec![0.25; 3 * n_particles],
        angular_velocity: vec![0.5; 3 * n_particles],
        diameter: vec![0.01; n_particles],
        surface: WetSurface {
            revision: 1,
            dim: 3,
            vertices: (0..3 * n_vertices).map(|i| i as f64 * 1e-4).collect(),
            elements: (0..n_triangles as u32)
                .flat_map(|t| [t / 2, t / 2 + 1, t / 2 + 2])
                .collect(),
            element_particle: (0..n_triangles as u32).map(|t| t / 6).collect(),
            wet: vec![true; n_triangles],
        },
        particles: Vec::new(),
        changed_only: false,
    }
}

fn iteration_round_trips(
    coupler: &mut dyn Transport,
    fluid: &mut (dyn Transport + Send),
    n: usize,
    trial: &SolidState,
) -> Duration {
    let n_particles = trial.n_particles();
    std::thread::scope(|scope| {
        scope.spawn(|| {
            for _ in 0..n {
                let (_, frame) = fluid
                    .recv(Some(NodeKind::Coupler), Duration::from_secs(10))
                    .expect("state");
                let Ok((_, Message::SolidState(s))) = codec::decode(&frame) else {
                    panic!("state")
                };
                let (_, frame) = fluid
                    .recv(Some(NodeKind::Coupler), Duration::from_secs(10))
                    .expect("decision");
                let _ = codec::decode(&frame).expect("decision");
                let loads = Message::InterfaceLoads(InterfaceLoads {
                    stamp: s.stamp,
                    dim: 3,
                    force: vec![1.0; 3 * n_particles],
                    torque: vec![0.1; 3 * n_particles],
                    particles: Vec::new(),
                });
                fluid
                    .send(NodeKind::Coupler, &codec::encode(NodeKind::Fluid, &loads))
                    .expect("send");
            }
        });
        let start = Instant::now();
        let decision = Message::FixedPointDecision(FixedPointDecision {
            stamp: trial.stamp,
            residual: 1e-6,
            decision: Decision::Iterate,
        });
        let mut buf = Vec::new();
        for _ in 0..n {
            codec::encode_into(
                NodeKind::Coupler,
                &Message::SolidState(trial.clone()),
                &mut buf,
            );
            coupler.send(NodeKind::Fluid, &buf).expect("send");
            coupler
                .send(
                    NodeKind::Fluid,
                    &codec::encode(NodeKind::Coupler, &decision),
                )
                .expect("send");
            let (_, frame) = coupler
                .recv(Some(NodeKind::Fluid), Duration::from_secs(10))
                .expect("loads");
            let _ = codec::decode(&frame).expect("loads");
        }
        start.elapsed() / n as u32
    })
}

fn main() {
    let trial = trial_state(10_000);
    let bytes = codec::encode(NodeKind::Solid, &Message::SolidState(trial.clone())).len();
    let n = 200;
    let (mut c, mut ends) = MemoryTransport::star(&[NodeKind::Fluid]);
    let mut f = ends.pop().expect("fluid end");
    let mem = iteration_round_trips(&mut c, &mut f, n, &trial);
    let run_id = format!("benchit{}", std::process::id());
    protocol::bus::cleanup_run(&run_id).expect("cleanup");
    let mut bus_c =
        protocol::bus::Bus::open(&run_id, NodeKind::Coupler, &[NodeKind::Fluid]).expect("bus");
    let mut bus_f =
        protocol::bus::Bus::open(&run_id, NodeKind::Fluid, &[NodeKind::Coupler]).expect("bus");
    let _ = iteration_round_trips(&mut bus_c, &mut bus_f, 10, &trial);
    let bus = iteration_round_trips(&mut bus_c, &mut bus_f, n, &trial);
    drop((bus_c, bus_f));
    let _ = protocol::bus::cleanup_run(&run_id);
    println!(
        "semi-implicit iteration round trip, 10^4 triangles ({bytes} B trial state): memory {mem:?}, bus {bus:?}"
    );

    // The doubles scene: in one process, then through the three processes.
    let scene = cosim_tests::scene("backbone-doubles.toml");
    let reps = 5;
    let start = Instant::now();
    for _ in 0..reps {
        let run = cosim_tests::run_in_process(&scene);
        assert_eq!(run.summary.status, "completed");
    }
    let in_process = start.elapsed() / reps;
    let exe = std::env::current_exe().expect("exe");
    let dir = exe.parent().and_then(|d| d.parent()).expect("target dir");
    let coupler = dir.join("coupler-node");
    if !coupler.exists() {
        println!(
            "doubles scene in one process: {in_process:?} per run; {} missing (cargo build --release) for the bus run",
            coupler.display()
        );
        return;
    }
    let out = std::env::temp_dir().join(format!("cosim-bench-{}", std::process::id()));
    let scene_path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../scenes/backbone-doubles.toml"
    );
    let timed = |record: &str| -> (Duration, f64) {
        let text = std::fs::read_to_string(scene_path)
            .expect("scene")
            .replace("record = \"exchange\"", &format!("record = \"{record}\""));
        let path = out.join(format!("{record}.toml"));
        std::fs::create_dir_all(&out).expect("dir");
        std::fs::write(&path, text).expect("scene");
        let start = Instant::now();
        let mut wall = 0.0;
        for _ in 0..reps {
            let status = std::process::Command::new(&coupler)
                .args(["run", "--quiet", "--overwrite", "--out"])
                .arg(out.join(record))
                .arg(&path)
                .status()
                .expect("coupler");
            assert!(status.success());
            let summary: serde_json::Value = serde_json::from_str(
                &std::fs::read_to_string(out.join(record).join("summary.json")).expect("summary"),
            )
            .expect("json");
            wall += summary["wall_s"].as_f64().expect("wall");
        }
        (start.elapsed() / reps, wall / f64::from(reps))
    };
    let (proc_none, loop_none) = timed("none");
    let (proc_rec, loop_rec) = timed("exchange");
    let size = std::fs::metadata(out.join("exchange").join("exchange.mcap")).map_or(0, |m| m.len());
    println!(
        "doubles scene (128 steps, ~8 iterations each): in one process {in_process:?}; three processes over the bus: whole command {proc_none:?}, coupling loop {loop_none:.4} s without record, {loop_rec:.4} s with record ({size} B, whole command {proc_rec:?})"
    );
    let _ = std::fs::remove_dir_all(out);
}
