//! One coupled step of the embedded solid against the fluid-only step, as the grid is refined:
//! a tilted polygon (a 48-sided ellipse) on 2-D grids and a tilted box on 3-D grids (OSMP order
//! 5, 1 thread), translating at a steady speed through gas at rest in a closed box. Not a
//! criterion bench: a driver that prints tables.
//!
//! Per step, on the same grid and state (the fluid-only twin gets a copy of the coupled state
//! before each step, so both sweep the same data in the same sweep order):
//! `FluidSolver::advance` (which includes the totals, timed alone too), `Embedded::predict`, one
//! `Embedded::loads` (geometry of the trial surface + integration; called 3 times per step, the
//! typical number of fixed-point iterations, each timed) and `Embedded::correct`. Also timed alone
//! on bench-owned buffers: `cutcell::compute` of the trial surface and `subface_swept_volumes`,
//! the geometry parts of loads and correct. Medians over the measured steps, after warm-up steps.
//!
//! Derived, paired within each step: sweeps = advance − totals; predict overhead = predict −
//! sweeps (ghosts, kept fluxes and pressures, near cells); interface = predict overhead plus 3
//! loads plus correct; and the ratio (predict + 3 loads + correct) / advance. The interface cost should
//! grow with the surface cell count (N^(1/2) in 2-D, N^(2/3) in 3-D for N cells): fitted
//! exponents are printed.
//!
//! Memory: the heap bytes held by the coupled and the fluid-only solver of each grid
//! (`FluidSolver::memory_bytes`, `Embedded::memory`, capacities), and the peak resident set
//! (`VmHWM`) of a child process per variant on the largest 3-D grid, which runs the same steps.
//!
//! `cargo bench -p fluid-node --no-default-features --bench coupled_step` (env: `STEPS` measured
//! steps, default 8; `WARMUP`, default 3; `GRIDS_2D`, `GRIDS_3D`: comma-separated cells per axis,
//! default `256,512,1024` and `64,96,128`, empty to skip).
//!
//! The predict overhead is a small difference of two large times; on a shared machine count
//! instructions instead (STYLE §8): with `COUPLED_BENCH_ONLY=dim,n` the binary runs `WARMUP`
//! steps (default 1) and one measured step on that grid, each part in its own `measured_*`
//! function. The sweeps run on each solver's pool thread, which `--toggle-collect` does not
//! follow, so collect everything per thread and subtract a run with one step less:
//!
//! ```text
//! COUPLED_BENCH_ONLY=3,64 WARMUP=1 valgrind --tool=callgrind --separate-threads=yes \
//!     --callgrind-out-file=w1.out target/release/deps/coupled_step-HASH   # and WARMUP=2: w2.out
//! callgrind_annotate --inclusive=yes w2.out-01 | grep measured_   # main thread: minus w1.out-01
//! callgrind_annotate --inclusive=yes w2.out-02 | grep sweep_axis  # coupled pool (-03: the twin)
//! ```

use std::hint::black_box;
use std::time::Instant;

#[path = "../tests/it/embedded_support/mod.rs"]
mod support;

use fluid_node::cutcell::{CutGeometry, SubfaceSwept, compute, subface_swept_volumes};
use fluid_node::embedded::{COVERED_TOLERANCE, Embedded, SolidFrame};
use fluid_node::fv::FluidSolver;
use fluid_node::grid::Grid;

/// Body speed [m/s] in gas at rest whose sound speed is 1 m/s.
const SPEED: [f64; 3] = [0.3, 0.12, 0.08];

/// Fixed-point iterations per coupled step (loads calls).
const ITERATIONS: usize = 3;

fn scene(dim: usize, n: usize) -> String {
    let v = |x: f64| vec![x; dim];
    let axes = ["x", "y", "z"];
    let boundary: Vec<String> = axes[..dim]
        .iter()
        .map(|a| format!("{a} = [\"wall\", \"wall\"]"))
        .collect();
    format!(
        r#"
        name = "coupled-step"
        [fluid]
        flux = {{ scheme = "osmp", order = 5 }}
        lower = {:?}
        upper = {:?}
        cells = {:?}
        boundary = {{ {} }}
        [[fluid.init]]
        region = "all"
        rho = 1.4
        p = 1.0
        "#,
        v(0.0),
        v(1.0),
        vec![n; dim],
        boundary.join(", ")
    )
}

fn body(dim: usize) -> SolidFrame {
    if dim == 2 {
        let (a, b, tilt) = (0.2f64, 0.1f64, 0.5f64);
        let (s, c) = tilt.sin_cos();
        let vertices: Vec<[f64; 2]> = (0..48)
            .map(|k| {
                let t = 2.0 * std::f64::consts::PI * k as f64 / 48.0;
                let (x, y) = (a * t.cos(), b * t.sin());
                [0.4513 + c * x - s * y, 0.4987 + s * x + c * y]
            })
            .collect();
        support::polygon_2d(&vertices, [SPEED[0], SPEED[1]], 0.0)
    } else {
        support::box_3d(
            [0.4513, 0.4987, 0.5021],
            [0.2, 0.12, 0.1],
            support::rotation([0.48, 0.6, 0.64], 0.5),
            SPEED,
        )
    }
}

/// Wall times of one step's parts [s].
#[derive(Clone, Copy, Default)]
struct StepTimes {
    advance: f64,
    totals: f64,
    predict: f64,
    /// Median of the step's `ITERATIONS` loads calls.
    loads: f64,
    correct: f64,
    geometry: f64,
    swept: f64,
    /// Paired within the step: predict − (advance − totals).
    overhead: f64,
    /// Paired: overhead + `ITERATIONS` loads + correct.
    interface: f64,
    /// Paired: (predict + `ITERATIONS` loads + correct) / advance.
    ratio: f64,
}

struct Row {
    dim: usize,
    n: usize,
    n_cells: usize,
    cut_cells: usize,
    /// Cells with Λ = 1 (the geometry fills their runs too: a volume term).
    covered_cells: usize,
    near_cells: usize,
    t: StepTimes,
    /// Heap bytes: fluid-only solver; coupled solver; embedded parts.
    fluid_bytes: usize,
    coupled_solver_bytes: usize,
    embedded: fluid_node::embedded::EmbeddedMemory,
    state_bytes: usize,
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let m = v.len() / 2;
    if v.len() % 2 == 1 {
        v[m]
    } else {
        0.5 * (v[m - 1] + v[m])
    }
}

fn seconds(f: impl FnOnce()) -> f64 {
    let t = Instant::now();
    f();
    t.elapsed().as_secs_f64()
}

fn env_usize(name: &str, default: usize) -> usize {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn env_grids(name: &str, default: &str) -> Vec<usize> {
    std::env::var(name)
        .unwrap_or_else(|_| default.into())
        .split(',')
        .filter_map(|s| s.trim().parse().ok())
        .collect()
}

// The timed calls, kept out of line so that `valgrind --tool=callgrind --toggle-collect` can
// count each one's instructions (see the module doc).

#[inline(never)]
fn measured_advance(twin: &mut FluidSolver, dt: f64, step: u64) {
    assert!(twin.advance(dt).ok(), "fluid-only step {step}");
}

#[inline(never)]
fn measured_totals(twin: &FluidSolver) {
    black_box(twin.totals());
}

#[inline(never)]
fn measured_predict(embedded: &mut Embedded, solver: &mut FluidSolver, dt: f64, step: u64) {
    let rep = embedded.predict(solver, dt);
    assert!(rep.ok(), "predict {step}: {:?}", rep.troubles);
}

#[inline(never)]
fn measured_loads(embedded: &mut Embedded, solver: &FluidSolver, trial: &SolidFrame) {
    black_box(embedded.loads(solver, trial).expect("loads"));
}

#[inline(never)]
fn measured_geometry(grid: &Grid, trial: &SolidFrame, geometry: &mut CutGeometry) {
    compute(grid, &black_box(trial).surface(), geometry);
}

#[inline(never)]
fn measured_swept(
    grid: &Grid,
    before: &SolidFrame,
    after: &SolidFrame,
    geometry: &CutGeometry,
    swept: &mut SubfaceSwept,
) {
    subface_swept_volumes(grid, &before.surface(), &after.surface(), geometry, swept);
}

#[inline(never)]
fn measured_correct(
    embedded: &mut Embedded,
    solver: &mut FluidSolver,
    dt: f64,
    accepted: SolidFrame,
    step: u64,
) {
    embedded
        .correct(solver, dt, accepted, step, false)
        .unwrap_or_else(|e| panic!("correct: {e}"));
}

/// One coupled step of `solver` and `embedded` (predict, `ITERATIONS` loads on the next frame,
/// correct) beside the fluid-only step of `twin` from a copy of the same state (before the
/// predict on even steps, after it on odd ones, so that a drift of the machine's speed does not
/// favour one); the times of the parts.
fn coupled_step(
    solver: &mut FluidSolver,
    embedded: &mut Embedded,
    twin: &mut FluidSolver,
    scratch: &mut (CutGeometry, SubfaceSwept),
    step: u64,
) -> StepTimes {
    let mut t = StepTimes::default();
    let dt = solver.max_dt().min(embedded.one_cell_dt());
    let next = support::translated(embedded.surface(), dt);
    twin.state_mut().u.copy_from_slice(&solver.state().u);
    // The fluid-only loop asks for its step first, so the CFL check inside is cached.
    assert_eq!(twin.max_dt(), solver.max_dt());
    let mut fluid_only = |t: &mut StepTimes| {
        t.advance = seconds(|| measured_advance(twin, dt, step));
        t.totals = seconds(|| measured_totals(twin));
    };
    if step.is_multiple_of(2) {
        fluid_only(&mut t);
    }
    t.predict = seconds(|| measured_predict(embedded, solver, dt, step));
    if !step.is_multiple_of(2) {
        fluid_only(&mut t);
    }
    let loads: Vec<f64> = (0..ITERATIONS)
        .map(|_| seconds(|| measured_loads(embedded, solver, &next)))
        .collect();
    t.loads = median(loads);
    let grid = solver.grid().clone();
    let (geometry, swept) = scratch;
    // As often as the loads, on the same surface, so the geometry's share compares like for like.
    let geometry_times: Vec<f64> = (0..ITERATIONS)
        .map(|_| seconds(|| measured_geometry(&grid, &next, geometry)))
        .collect();
    t.geometry = median(geometry_times);
    t.swept = seconds(|| measured_swept(&grid, embedded.surface(), &next, geometry, swept));
    t.correct = seconds(|| measured_correct(embedded, solver, dt, next, step));
    let iterations = ITERATIONS as f64;
    t.overhead = t.predict - (t.advance - t.totals);
    t.interface = t.overhead + iterations * t.loads + t.correct;
    t.ratio = (t.predict + iterations * t.loads + t.correct) / t.advance;
    t
}

fn run_grid(dim: usize, n: usize, warmup: usize, steps: usize) -> Row {
    let text = scene(dim, n);
    let mut solver = support::solver(&text);
    let mut twin = support::solver(&text);
    let mut embedded = Embedded::new(&solver, body(dim)).expect("embedded");
    let mut scratch = (CutGeometry::new(), SubfaceSwept::new());
    let mut times = Vec::new();
    for k in 0..warmup + steps {
        let t = coupled_step(
            &mut solver,
            &mut embedded,
            &mut twin,
            &mut scratch,
            k as u64,
        );
        if k >= warmup {
            times.push(t);
        }
    }
    let pick = |f: fn(&StepTimes) -> f64| median(times.iter().map(f).collect());
    Row {
        dim,
        n,
        n_cells: solver.grid().n_cells(),
        cut_cells: embedded.geometry().cut_cells.len(),
        covered_cells: embedded
            .solid_fraction()
            .iter()
            .filter(|&&l| l >= 1.0 - COVERED_TOLERANCE)
            .count(),
        near_cells: embedded.near_cells().len(),
        t: StepTimes {
            advance: pick(|t| t.advance),
            totals: pick(|t| t.totals),
            predict: pick(|t| t.predict),
            loads: pick(|t| t.loads),
            correct: pick(|t| t.correct),
            geometry: pick(|t| t.geometry),
            swept: pick(|t| t.swept),
            overhead: pick(|t| t.overhead),
            interface: pick(|t| t.interface),
            ratio: pick(|t| t.ratio),
        },
        fluid_bytes: twin.memory_bytes(),
        coupled_solver_bytes: solver.memory_bytes(),
        embedded: embedded.memory(),
        state_bytes: solver.state().u.capacity() * size_of::<f64>(),
    }
}

/// Least-squares slope of `ln y` against `ln x`.
fn slope(points: &[(f64, f64)]) -> f64 {
    let pts: Vec<(f64, f64)> = points.iter().map(|&(x, y)| (x.ln(), y.ln())).collect();
    let m = pts.len() as f64;
    let (mx, my) = pts
        .iter()
        .fold((0.0, 0.0), |a, p| (a.0 + p.0 / m, a.1 + p.1 / m));
    let num: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let den: f64 = pts.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
    num / den
}

/// Peak and current resident set of this process [bytes] from `/proc/self/status`.
fn resident() -> (usize, usize) {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    let field = |key: &str| {
        status
            .lines()
            .find_map(|l| l.strip_prefix(key))
            .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<usize>().ok())
            .map_or(0, |kb| kb * 1024)
    };
    (field("VmHWM:"), field("VmRSS:"))
}

/// Child process: builds one variant on an `n³` grid, runs the steps, prints its resident set.
fn rss_child(variant: &str, n: usize, steps: usize) {
    let text = scene(3, n);
    let mut solver = support::solver(&text);
    let (hwm, rss) = if variant == "fluid" {
        for k in 0..steps {
            let dt = solver.max_dt();
            assert!(solver.advance(dt).ok(), "fluid-only step {k}");
        }
        resident()
    } else {
        // The same calls as the timed steps, without the bench's own geometry buffers.
        let mut embedded = Embedded::new(&solver, body(3)).expect("embedded");
        for k in 0..steps {
            let dt = solver.max_dt().min(embedded.one_cell_dt());
            let next = support::translated(embedded.surface(), dt);
            assert!(embedded.predict(&mut solver, dt).ok(), "predict {k}");
            for _ in 0..ITERATIONS {
                black_box(embedded.loads(&solver, &next).expect("loads"));
            }
            embedded
                .correct(&mut solver, dt, next, k as u64, false)
                .unwrap_or_else(|e| panic!("correct: {e}"));
        }
        black_box(&embedded);
        resident()
    };
    println!("rss {variant} {hwm} {rss}");
}

fn rss_of(variant: &str, n: usize, steps: usize) -> Option<(usize, usize)> {
    let exe = std::env::current_exe().ok()?;
    let out = std::process::Command::new(exe)
        .env("COUPLED_BENCH_RSS", format!("{variant},{n},{steps}"))
        .output()
        .ok()?;
    let text = String::from_utf8_lossy(&out.stdout);
    let line = text.lines().find(|l| l.starts_with("rss "))?;
    let mut it = line.split_whitespace().skip(2);
    Some((it.next()?.parse().ok()?, it.next()?.parse().ok()?))
}

fn mib(bytes: usize) -> f64 {
    bytes as f64 / (1024.0 * 1024.0)
}

fn main() {
    if let Ok(spec) = std::env::var("COUPLED_BENCH_RSS") {
        let parts: Vec<&str> = spec.split(',').collect();
        rss_child(
            parts[0],
            parts[1].parse().unwrap(),
            parts[2].parse().unwrap(),
        );
        return;
    }
    if let Ok(spec) = std::env::var("COUPLED_BENCH_ONLY") {
        // One measured step (for callgrind) after `WARMUP` steps (default 1).
        let parts: Vec<usize> = spec.split(',').filter_map(|s| s.parse().ok()).collect();
        let row = run_grid(parts[0], parts[1], env_usize("WARMUP", 1), 1);
        println!(
            "{}-D {}: {} cells, {} cut cells, {} covered cells, {} near cells",
            row.dim, row.n, row.n_cells, row.cut_cells, row.covered_cells, row.near_cells
        );
        return;
    }
    let warmup = env_usize("WARMUP", 3);
    let steps = env_usize("STEPS", 8).max(1);
    let mut rows = Vec::new();
    for (dim, grids) in [
        (2, env_grids("GRIDS_2D", "256,512,1024")),
        (3, env_grids("GRIDS_3D", "64,96,128")),
    ] {
        for n in grids {
            let row = run_grid(dim, n, warmup, steps);
            eprintln!(
                "{dim}-D {n}: advance {:.2} ms, predict {:.2} ms, loads {:.3} ms, correct {:.3} ms",
                row.t.advance * 1e3,
                row.t.predict * 1e3,
                row.t.loads * 1e3,
                row.t.correct * 1e3
            );
            rows.push(row);
        }
    }
    print_times(&rows, steps, warmup);
    print_geometry(&rows);
    print_exponents(&rows);
    print_memory(&rows);
    print_rss(&rows, warmup);
}

/// The table of step times, coupled against fluid-only.
fn print_times(rows: &[Row], steps: usize, warmup: usize) {
    println!(
        "\ncoupled step vs fluid-only step (OSMP 5, 1 thread; medians of {steps} steps after {warmup}; times in ms; ratio, overhead and interface paired per step)"
    );
    println!(
        "dim     n         N  cut cells  covered  near cells   advance  (totals)   predict     loads   correct  ratio P+3L+C/A  pred.overhead  interface  interface/A"
    );
    for r in rows {
        let t = &r.t;
        println!(
            "{:3} {:5} {:9} {:10} {:8} {:11} {:9.2} {:9.2} {:9.2} {:9.3} {:9.3} {:15.3} {:14.3} {:10.3} {:12.4}",
            r.dim,
            r.n,
            r.n_cells,
            r.cut_cells,
            r.covered_cells,
            r.near_cells,
            t.advance * 1e3,
            t.totals * 1e3,
            t.predict * 1e3,
            t.loads * 1e3,
            t.correct * 1e3,
            t.ratio,
            t.overhead * 1e3,
            t.interface * 1e3,
            t.interface / t.advance
        );
    }
}

/// The table of the geometry's share of loads and correct.
fn print_geometry(rows: &[Row]) {
    println!(
        "\ngeometry inside loads and correct (ms; geometry = cutcell::compute of the trial surface)"
    );
    println!(
        "dim     n  geometry  loads-geometry  swept  correct-geometry-swept  geometry share of loads, correct"
    );
    for r in rows {
        let t = &r.t;
        println!(
            "{:3} {:5} {:9.3} {:15.3} {:6.3} {:23.3} {:12.2} {:8.2}",
            r.dim,
            r.n,
            t.geometry * 1e3,
            (t.loads - t.geometry) * 1e3,
            t.swept * 1e3,
            (t.correct - t.geometry - t.swept) * 1e3,
            t.geometry / t.loads,
            (t.geometry + t.swept) / t.correct
        );
    }
}

/// The exponents of counts and times against the cell count.
fn print_exponents(rows: &[Row]) {
    println!("\nfitted exponents against N (least squares over the grids)");
    for dim in [2, 3] {
        let of = |f: &dyn Fn(&Row) -> f64| -> Vec<(f64, f64)> {
            rows.iter()
                .filter(|r| r.dim == dim)
                .map(|r| (r.n_cells as f64, f(r)))
                .collect()
        };
        if of(&|_| 1.0).len() < 2 {
            continue;
        }
        println!(
            "{dim}-D: cut cells {:.3}, covered cells {:.3}, near cells {:.3}, loads {:.3}, correct {:.3}, 3 loads + correct {:.3}, interface {:.3}, advance {:.3} (surface: {})",
            slope(&of(&|r| r.cut_cells as f64)),
            slope(&of(&|r| r.covered_cells as f64)),
            slope(&of(&|r| r.near_cells as f64)),
            slope(&of(&|r| r.t.loads)),
            slope(&of(&|r| r.t.correct)),
            slope(&of(&|r| ITERATIONS as f64 * r.t.loads + r.t.correct)),
            slope(&of(&|r| r.t.interface.max(1e-9))),
            slope(&of(&|r| r.t.advance)),
            if dim == 2 { "1/2" } else { "2/3" }
        );
    }
}

/// The table of heap bytes held.
fn print_memory(rows: &[Row]) {
    println!("\nheap bytes held (capacities; MiB)");
    println!(
        "dim     n   fluid-only  (state)  coupled solver  dense geometry  slot_of  near-surface  sparse geometry  coupled total  coupled/fluid"
    );
    for r in rows {
        let e = &r.embedded;
        let coupled = r.coupled_solver_bytes + e.total();
        println!(
            "{:3} {:5} {:12.2} {:8.2} {:15.2} {:15.2} {:8.2} {:13.3} {:16.3} {:14.2} {:14.3}",
            r.dim,
            r.n,
            mib(r.fluid_bytes),
            mib(r.state_bytes),
            mib(r.coupled_solver_bytes),
            mib(e.dense_geometry),
            mib(e.slot_of),
            mib(e.near_surface),
            mib(e.sparse_geometry),
            mib(coupled),
            coupled as f64 / r.fluid_bytes as f64
        );
    }
}

/// The peak resident set of child processes on the largest 3-D grid.
fn print_rss(rows: &[Row], warmup: usize) {
    if let Some(r) = rows.iter().filter(|r| r.dim == 3).max_by_key(|r| r.n) {
        let n_steps = warmup + 1;
        match (
            rss_of("fluid", r.n, n_steps),
            rss_of("coupled", r.n, n_steps),
        ) {
            (Some((hf, rf)), Some((hc, rc))) => {
                let counted = r.embedded.total() as f64;
                println!(
                    "\npeak resident set (VmHWM) of a child running {n_steps} steps on {}³: fluid-only {:.2} MiB, coupled {:.2} MiB, difference {:.2} MiB (embedded heap counted by the accessors: {:.2} MiB); VmRSS after the steps {:.2} / {:.2} MiB",
                    r.n,
                    mib(hf),
                    mib(hc),
                    mib(hc.saturating_sub(hf)),
                    counted / (1024.0 * 1024.0),
                    mib(rf),
                    mib(rc)
                );
            }
            _ => println!("\npeak resident set: the child processes gave no reading"),
        }
    }
}
