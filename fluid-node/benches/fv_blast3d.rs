//! Runs `scenes/blast-3d.toml` to its end time (release) and prints steps, wall time, cell
//! updates per second, extreme density and pressure seen, and the relative drift of mass and
//! energy. Not a criterion bench: a driver for the measurement the issue asks for.
//!
//! `cargo bench -p fluid-node --no-default-features --bench fv_blast3d` (env: `THREADS`,
//! default 1; `CELLS`, per axis, default the scene's; `ORDER`, default the scene's; `STEPS`,
//! stop after that many steps, for throughput measurements; `DIM` = 1 or 2, the same blast in
//! fewer dimensions; `ISA` = baseline, avx2 or avx512, the instruction set of the line kernel,
//! default the CPU's best).

use std::time::Instant;

use fluid_node::fv::{FluidSolver, Isa};

fn main() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/blast-3d.toml");
    let text = std::fs::read_to_string(&path).expect("scenes/blast-3d.toml is readable");
    let scene = protocol::scene::Scene::from_toml_str(&text, "blast-3d.toml").expect("valid scene");
    let mut fluid = scene.fluid.clone().expect("a [fluid] table");
    if let Some(n) = std::env::var("CELLS")
        .ok()
        .and_then(|v| v.parse::<u32>().ok())
    {
        fluid.cells = vec![n; 3];
    }
    // DIM = 1 or 2: the same blast cut to the first axes (ball → disc → interval).
    if let Some(dim) = std::env::var("DIM")
        .ok()
        .and_then(|v| v.parse::<usize>().ok())
        && (1..3).contains(&dim)
    {
        fluid.lower.truncate(dim);
        fluid.upper.truncate(dim);
        fluid.cells.truncate(dim);
        if dim < 3 {
            fluid.boundary.z = None;
        }
        if dim < 2 {
            fluid.boundary.y = None;
        }
        for entry in &mut fluid.init {
            if let protocol::scene::Region::Ball { center, .. } = &mut entry.region {
                center.truncate(dim);
            }
        }
    }
    if let Some(order) = std::env::var("ORDER")
        .ok()
        .and_then(|v| v.parse::<u32>().ok())
    {
        fluid.flux.order = order;
    }
    let max_steps: u64 = std::env::var("STEPS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(u64::MAX);
    let threads = std::env::var("THREADS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1);
    let mut solver = FluidSolver::from_scene(&fluid, threads).expect("solver");
    let isa = match std::env::var("ISA").as_deref() {
        Ok("baseline") => Isa::Baseline,
        Ok("avx2") => Isa::Avx2,
        Ok("avx512") => Isa::Avx512,
        _ => Isa::best(),
    };
    solver.set_isa(isa);
    let t0 = solver.totals();
    let n_cells = solver.grid().n_cells();
    let start = Instant::now();
    let (mut min_rho, mut min_p) = (f64::INFINITY, f64::INFINITY);
    let mut steps = 0u64;
    let t_end = scene.run.t_end;
    while solver.time() < t_end * (1.0 - 1e-14) && steps < max_steps {
        let dt = solver.max_dt().min(t_end - solver.time());
        let rep = solver.advance(dt);
        steps += 1;
        if !rep.ok() {
            println!("TROUBLE at step {steps}: {:?}", rep.troubles);
            std::process::exit(1);
        }
        if steps.is_multiple_of(10) {
            for idx in 0..n_cells {
                let (rho, _, p) = solver.primitive(idx);
                min_rho = min_rho.min(rho);
                min_p = min_p.min(p);
            }
        }
    }
    let wall = start.elapsed().as_secs_f64();
    let t1 = solver.totals();
    println!(
        "blast-3d {:?} osmp{} threads {threads} {isa:?}: t = {:.6} in {steps} steps, wall {wall:.2} s, {:.3e} cell updates/s",
        fluid.cells,
        fluid.flux.order,
        solver.time(),
        (steps as f64) * n_cells as f64 / wall
    );
    println!("min rho {min_rho:.4e}, min p {min_p:.4e} (sampled every 10 steps)");
    println!(
        "mass drift {:.3e}, energy drift {:.3e} (relative); outflow mass {:.1e} energy {:.1e}",
        (t1.mass - t0.mass) / t0.mass,
        (t1.energy - t0.energy) / t0.energy,
        t1.outflow_mass,
        t1.outflow_energy
    );
}
