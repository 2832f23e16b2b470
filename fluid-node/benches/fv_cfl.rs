//! The scheme's own CFL (issue 36 item 3): accuracy, steps and time against the Courant number
//! for OSMP 3/5/7, on the smooth periodic density wave and on the four shock tubes of
//! `scenes/` (sod, lax, toro-123, toro-3), one thread, release.
//!
//! For each case, order, Courant number and grid it prints the L1 error of the density against
//! the exact cell averages, the steps, the best wall time of two runs, and for the shock tubes
//! two monotonicity measures of the density against the exact solution's cell averages: the
//! overshoot (how far the numerical density leaves the exact solution's range, relative to the
//! range) and the excess of total variation (TV(ρ) − TV(ρ_exact), relative to TV(ρ_exact)).
//!
//! `cargo bench -p fluid-node --no-default-features --bench fv_cfl` (about a minute); writes
//! `fv_cfl.csv` into `$OUT_DIR` (default `target/cfl`).

use std::time::Instant;

use fluid_node::fv::study::{RiemannReference, solver_for};
use fluid_node::fv::{FluidSolver, FluidState, FluxKind, init};
use fluid_node::grid::Grid;

const COURANT: [f64; 8] = [0.5, 0.6, 0.7, 0.75, 0.8, 0.85, 0.9, 0.95];
const ORDERS: [u32; 3] = [3, 5, 7];

struct Row {
    case: String,
    order: u32,
    cfl: f64,
    cells: u32,
    steps: u64,
    wall_s: f64,
    l1: f64,
    overshoot: f64,
    tv_excess: f64,
}

/// Best of two wall times of `run` (deterministic runs: the spread is the machine's).
fn timed<T>(mut run: impl FnMut() -> T) -> (T, f64) {
    let mut best = f64::INFINITY;
    let mut out = None;
    for _ in 0..2 {
        let start = Instant::now();
        let r = run();
        best = best.min(start.elapsed().as_secs_f64());
        out = Some(r);
    }
    (out.expect("two runs"), best)
}

fn density_wave(order: u32, cfl: f64, n: usize) -> Row {
    let grid = Grid::new(&[0.0], &[1.0], &[n]).expect("grid");
    let mut state = FluidState::zeros(1, grid.n_cells());
    init::density_wave(
        &mut state,
        &grid,
        0.2,
        [1.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        1.0,
        1.4,
        0.0,
    );
    let exact = state.clone();
    let ((solver, steps), wall_s) = timed(|| {
        let text = std::fs::read_to_string(scene_path("density-wave")).expect("scene");
        let scene =
            protocol::scene::Scene::from_toml_str(&text, "density-wave.toml").expect("scene");
        let mut cfg = scene.fluid.expect("fluid");
        cfg.cfl = cfl;
        let mut solver = solver_for(&cfg, FluxKind::Osmp(order), n as u32, 1).expect("solver");
        let (steps, rep) = solver.run_until(1.0, u64::MAX);
        assert!(rep.ok(), "{:?}", rep.troubles);
        (solver, steps)
    });
    Row {
        case: "density-wave".into(),
        order,
        cfl,
        cells: n as u32,
        steps,
        wall_s,
        l1: init::l1_density(&grid, solver.state(), &exact),
        overshoot: 0.0,
        tv_excess: 0.0,
    }
}

fn scene_path(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../scenes")
        .join(format!("{name}.toml"))
}

/// Overshoot and total-variation excess of the density of `solver` against the exact averages.
fn monotonicity(reference: &RiemannReference, solver: &FluidSolver) -> (f64, f64) {
    let grid = solver.grid();
    let t = solver.time();
    let n = grid.cells[0];
    let mut exact = Vec::with_capacity(n);
    for i in 0..n {
        let xa = grid.lower[0] + i as f64 * grid.dx[0];
        exact.push(
            reference
                .exact
                .cell_average(xa, xa + grid.dx[0], reference.x0, t)[0],
        );
    }
    let rho: Vec<f64> = (0..n).map(|i| solver.state().u[i * 3]).collect();
    let (lo, hi) = exact
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let range = (hi - lo).max(f64::MIN_POSITIVE);
    let over = rho
        .iter()
        .map(|&r| (r - hi).max(lo - r).max(0.0))
        .fold(0.0, f64::max)
        / range;
    let tv = |v: &[f64]| v.windows(2).map(|w| (w[1] - w[0]).abs()).sum::<f64>();
    let (tv_num, tv_exact) = (tv(&rho), tv(&exact));
    (over, (tv_num - tv_exact) / tv_exact)
}

fn shock_tube(name: &str, order: u32, cfl: f64, cells: u32) -> Row {
    let text = std::fs::read_to_string(scene_path(name)).expect("scene");
    let scene = protocol::scene::Scene::from_toml_str(&text, name).expect("scene");
    let mut cfg = scene.fluid.expect("fluid");
    cfg.cfl = cfl;
    let reference = RiemannReference::from_config(&cfg).expect("a Riemann problem");
    let ((solver, steps), wall_s) = timed(|| {
        let mut solver = solver_for(&cfg, FluxKind::Osmp(order), cells, 1).expect("solver");
        let (steps, rep) = solver.run_until(scene.run.t_end, u64::MAX);
        assert!(
            rep.ok(),
            "{name} order {order} cfl {cfl}: {:?}",
            rep.troubles
        );
        (solver, steps)
    });
    let (overshoot, tv_excess) = monotonicity(&reference, &solver);
    Row {
        case: name.into(),
        order,
        cfl,
        cells,
        steps,
        wall_s,
        l1: reference.l1_density(&solver),
        overshoot,
        tv_excess,
    }
}

fn main() {
    let mut rows = Vec::new();
    for order in ORDERS {
        for cfl in COURANT {
            for n in [50, 100, 200] {
                rows.push(density_wave(order, cfl, n));
            }
            for case in ["sod", "lax", "toro-123", "toro-3"] {
                for n in [200, 400, 800] {
                    rows.push(shock_tube(case, order, cfl, n));
                }
            }
        }
    }
    let mut csv = String::from("case,order,cfl,cells,steps,wall_s,l1_rho,overshoot,tv_excess\n");
    for r in &rows {
        csv.push_str(&format!(
            "{},{},{},{},{},{:.6},{:.4e},{:.3e},{:.3e}\n",
            r.case, r.order, r.cfl, r.cells, r.steps, r.wall_s, r.l1, r.overshoot, r.tv_excess
        ));
    }
    print!("{csv}");
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let out = std::env::var("OUT_DIR")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|_| root.join("target/cfl"));
    std::fs::create_dir_all(&out).expect("out dir");
    std::fs::write(out.join("fv_cfl.csv"), csv).expect("csv");
    eprintln!("written to {}", out.join("fv_cfl.csv").display());
}
