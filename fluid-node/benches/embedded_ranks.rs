//! The embedded part's predict, loads and correct per rank (issue 40 item 1, steps 2 to 4):
//! `Embedded::predict`, `Embedded::loads` (on the trial surface) and `Embedded::correct` on K = 1,
//! 2, 4 thread ranks (`fluid_node::ranks::threads`, one rayon thread each, cut as
//! `protocol::decomp::choose` cuts the grid, and K = 4 also as `1 × 2 × 2`), each rank timing its
//! own predicts, loads and corrects (a rank's time includes its waits for the others at the
//! collectives, and with more ranks than cores, for a core), and counting the sub-faces of
//! `F^{n+1}` in its own cells (whose prisms it clips) and its near cells (whose updates it makes),
//! the work of the correct that is shared out by rank, the steps whose mixing groups merged or
//! widened (the mixing then merges and mixes every group on every rank), and the heap bytes its
//! `Embedded` holds after the last step, by part (`Embedded::memory`). Each rank also counts the
//! CPU time of its predicts, loads and corrects: its own thread's and its solver pool's thread's
//! (`/proc/self/task/TID/schedstat`, Linux), which leaves out the waits at the collectives (the
//! thread ranks block in a channel's `recv`) and the waits for a core, so with more ranks than
//! cores it is still each rank's own work.
//!
//! ```text
//! cargo bench -p fluid-node --no-default-features --bench embedded_ranks --no-run
//! RANKS_BENCH_N=64 RANKS_BENCH_STEPS=6 target/release/deps/embedded_ranks-HASH
//! ```
//!
//! Only the public API of `fluid_node` is used, so the same file runs on an earlier commit.
//! The body: the two particles of `scenes/opening-fracture-3d.toml` (the box `[0.6, 1.4]³` of
//! its 2 m domain, split at x = 1, 12 triangles each), moving apart along x at 20 m/s, so that
//! the crack between them opens (vacuum cells), in air at rest (ρ = 1.2, p = 1e5), OSMP 5
//! (`ng` = 3), walls on every side, fracture on.

use std::time::Instant;

#[path = "../tests/it/cutcell_support/mod.rs"]
mod cutcell_support;

use fluid_node::embedded::{Embedded, SolidFrame};
use fluid_node::fv::{BoundaryKind, FluidParams, FluidSolver, FluidState, FluxKind};
use fluid_node::grid::Grid;
use fluid_node::ranks::threads::ThreadRanks;

/// Speed of each box along x, away from the other \[m/s\].
const SPEED: f64 = 20.0;

fn params() -> FluidParams {
    FluidParams {
        gamma: 1.4,
        cfl: 0.5,
        flux: FluxKind::Osmp(5),
        boundary: [[BoundaryKind::Wall; 2]; 3],
        vacuum_rho: 1e-10,
        vacuum_p: 1e-10,
    }
}

/// The two boxes of opening-fracture-3d as one frame, particle 0 below x = 1, 1 above.
fn boxes() -> SolidFrame {
    let left = cutcell_support::box_mesh([0.6, 0.6, 0.6], [1.0, 1.4, 1.4]);
    let right = cutcell_support::box_mesh([1.0, 0.6, 0.6], [1.4, 1.4, 1.4]);
    let mut frame = SolidFrame {
        dim: 3,
        position: vec![0.8, 1.0, 1.0, 1.2, 1.0, 1.0],
        velocity: vec![-SPEED, 0.0, 0.0, SPEED, 0.0, 0.0],
        angular_velocity: vec![0.0; 6],
        ..SolidFrame::default()
    };
    for (p, mesh) in [left, right].iter().enumerate() {
        let first = (frame.vertices.len() / 3) as u32;
        frame.vertices.extend_from_slice(&mesh.vertices);
        frame
            .elements
            .extend(mesh.elements.iter().map(|v| v + first));
        let n = mesh.elements.len() / 3;
        frame
            .element_particle
            .extend(std::iter::repeat_n(p as u32, n));
        frame.wet.extend(std::iter::repeat_n(true, n));
    }
    frame
}

/// The frame moved by its velocities over `dt` (each vertex with its particle's velocity).
fn moved(frame: &SolidFrame, dt: f64) -> SolidFrame {
    let mut next = frame.clone();
    for (k, x) in next.position.iter_mut().enumerate() {
        *x += dt * frame.velocity[k];
    }
    let mut particle_of = vec![0usize; frame.vertices.len() / 3];
    for (e, nodes) in frame.elements.chunks_exact(3).enumerate() {
        for &v in nodes {
            particle_of[v as usize] = frame.element_particle[e] as usize;
        }
    }
    for (k, x) in next.vertices.iter_mut().enumerate() {
        *x += dt * frame.velocity[3 * particle_of[k / 3] + k % 3];
    }
    next
}

/// Steps of the fluid alone that each rank times before the coupled steps.
const FLUID_STEPS: usize = 6;

/// CPU time \[s\] a thread of this process has run (`/proc/self/task/TID/schedstat`, its
/// first field, nanoseconds on a CPU); 0 where the file cannot be read (not Linux).
fn thread_cpu(tid: i32) -> f64 {
    std::fs::read_to_string(format!("/proc/self/task/{tid}/schedstat"))
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<u64>().ok())
        .map_or(0.0, |ns| ns as f64 * 1e-9)
}

/// What one rank measured over the steps.
struct RankTimes {
    /// Predict and correct times \[s\], one per step.
    predict: Vec<f64>,
    correct: Vec<f64>,
    /// CPU time of the predicts and corrects \[s\], one per step: the rank's thread and its
    /// solver pool's thread together.
    predict_cpu: Vec<f64>,
    correct_cpu: Vec<f64>,
    /// Wall and CPU time of the loads on each step's trial surface \[s\] (`Embedded::loads`,
    /// between the predict and the correct).
    loads: Vec<f64>,
    loads_cpu: Vec<f64>,
    /// CPU time of the fluid's step alone \[s\] (`FluidSolver::advance`, no body), one per
    /// step, taken before the coupled steps.
    fluid_cpu: Vec<f64>,
    /// Sub-faces of the accepted surface in the rank's cells, after the last step.
    subfaces: usize,
    /// Cells of the rank's block.
    cells: usize,
    /// Steps whose mixing groups merged or widened (which the mixing does on every rank).
    merged_or_widened: usize,
    /// Heap bytes its `Embedded` holds after the last step, by part.
    memory: fluid_node::embedded::EmbeddedMemory,
}

/// Each rank's predict and correct times over `steps` coupled steps on `ranks` thread ranks.
/// `dims`: the process grid (`None`: `protocol::decomp::choose`'s).
fn rank_times(
    grid: &Grid,
    state: &FluidState,
    ranks: usize,
    dims: Option<[usize; 3]>,
    steps: u64,
) -> Vec<RankTimes> {
    let handles: Vec<_> = ThreadRanks::new(ranks)
        .into_iter()
        .map(|comm| {
            let (grid, state) = (grid.clone(), state.clone());
            std::thread::spawn(move || {
                let mut s =
                    FluidSolver::decomposed_as(grid, params(), state, 1, Box::new(comm), dims)
                        .expect("solver");
                // SAFETY: `gettid` has no preconditions.
                let tids = [
                    unsafe { libc::gettid() },
                    s.install(|| unsafe { libc::gettid() }),
                ];
                let cpu = || tids.iter().map(|&tid| thread_cpu(tid)).sum::<f64>();
                // The fluid's step alone (no body, the gas at rest stays at rest), for the
                // share of the predict that is the sweeps.
                let fluid_cpu = (0..FLUID_STEPS)
                    .map(|_| {
                        let (dt, c) = (s.max_dt(), cpu());
                        s.advance(dt);
                        cpu() - c
                    })
                    .collect();
                let mut e = Embedded::new(&s, boxes()).expect("embedded");
                e.set_fracture(true);
                let mut times = RankTimes {
                    fluid_cpu,
                    predict: Vec::new(),
                    correct: Vec::new(),
                    predict_cpu: Vec::new(),
                    correct_cpu: Vec::new(),
                    loads: Vec::new(),
                    loads_cpu: Vec::new(),
                    subfaces: 0,
                    cells: 0,
                    merged_or_widened: 0,
                    memory: Default::default(),
                };
                for n in 0..steps {
                    let dt = s.max_dt().min(0.5 * e.one_cell_dt());
                    let (t, c) = (Instant::now(), cpu());
                    let report = e.predict(&mut s, dt);
                    times.predict.push(t.elapsed().as_secs_f64());
                    times.predict_cpu.push(cpu() - c);
                    assert!(report.ok(), "step {n}: {:?}", report.troubles);
                    let next = moved(e.surface(), dt);
                    // The loads on the trial surface, as each iteration of the fixed point
                    // takes them.
                    let (t, c) = (Instant::now(), cpu());
                    e.loads(&s, &next).expect("loads");
                    times.loads.push(t.elapsed().as_secs_f64());
                    times.loads_cpu.push(cpu() - c);
                    let (t, c) = (Instant::now(), cpu());
                    let report = e.correct(&mut s, dt, next, n, false).expect("correct");
                    times.correct.push(t.elapsed().as_secs_f64());
                    times.correct_cpu.push(cpu() - c);
                    if report.merged_groups + report.widened_groups > 0 {
                        times.merged_or_widened += 1;
                    }
                }
                let slab = s.slab();
                let own = |c: u32| slab.to_local(c as usize).is_some();
                times.subfaces = e.geometry().subfaces.iter().filter(|f| own(f.cell)).count();
                times.cells = slab.local.n_cells();
                times.memory = e.memory();
                times
            })
        })
        .collect();
    handles
        .into_iter()
        .map(|h| h.join().expect("rank thread"))
        .collect()
}

fn median(v: &[f64]) -> f64 {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let env = |key: &str, default: usize| {
        std::env::var(key)
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(default)
    };
    let n = env("RANKS_BENCH_N", 64);
    let steps = env("RANKS_BENCH_STEPS", 6) as u64;
    let grid = Grid::new(&[0.0; 3], &[2.0; 3], &[n; 3]).unwrap();
    let mut state = FluidState::zeros(3, grid.n_cells());
    for c in 0..grid.n_cells() {
        state.set_primitive(c, 1.2, [0.0; 3], 1e5, 1.4);
    }
    println!(
        "opening-fracture-3d boxes, {n}^3, {steps} steps: predict, loads on the trial surface and correct per rank, ms (median of the steps after the first; wall, and CPU of the rank's threads); sub-faces of F^(n+1) in the rank's cells"
    );
    println!("| K | part | rank 0 | rank 1 | rank 2 | rank 3 |");
    println!("| --- | --- | --- | --- | --- | --- |");
    // K = 4 also as 2 × 2 blocks across y and z, which cut the body four ways (the slabs that
    // `choose` takes leave it in the two middle ones).
    for (k, dims) in [(1, None), (2, None), (4, None), (4, Some([1, 2, 2]))] {
        let times = rank_times(&grid, &state, k, dims, steps);
        let k = match dims {
            Some([a, b, c]) => format!("{k} ({a} × {b} × {c})"),
            None => k.to_string(),
        };
        let row = |f: &dyn Fn(&RankTimes) -> String| -> String {
            times.iter().map(f).collect::<Vec<_>>().join(" | ")
        };
        let ms = |t: &[f64]| format!("{:.2}", 1e3 * median(&t[1..]));
        println!("| {k} | predict | {} |", row(&|t| ms(&t.predict)));
        println!("| {k} | correct | {} |", row(&|t| ms(&t.correct)));
        println!("| {k} | predict, CPU | {} |", row(&|t| ms(&t.predict_cpu)));
        println!("| {k} | correct, CPU | {} |", row(&|t| ms(&t.correct_cpu)));
        println!("| {k} | loads | {} |", row(&|t| ms(&t.loads)));
        println!("| {k} | loads, CPU | {} |", row(&|t| ms(&t.loads_cpu)));
        println!(
            "| {k} | fluid step alone, CPU | {} |",
            row(&|t| ms(&t.fluid_cpu))
        );
        println!("| {k} | sub-faces | {} |", row(&|t| t.subfaces.to_string()));
        println!("| {k} | cells | {} |", row(&|t| t.cells.to_string()));
        let merged = |t: &RankTimes| t.merged_or_widened.to_string();
        println!(
            "| {k} | steps merging or widening groups | {} |",
            row(&merged)
        );
        let mb = |b: usize| format!("{:.1}", b as f64 / 1e6);
        let part = |name: &str, f: &dyn Fn(&RankTimes) -> usize| {
            println!("| {k} | {name}, MB | {} |", row(&|t| mb(f(t))));
        };
        part("dense geometry", &|t| t.memory.dense_geometry);
        part("near cells' slots", &|t| t.memory.slot_of);
        part("near surface", &|t| t.memory.near_surface);
        part("sparse geometry", &|t| t.memory.sparse_geometry);
        part("block geometry kept", &|t| t.memory.block_buffers);
        part("blocks' shares kept", &|t| t.memory.shares);
        part("embedded, total", &|t| t.memory.total());
    }
}
