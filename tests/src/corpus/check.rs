//! Running a generated case and judging its invariants (see the parent module's docs).

use std::path::Path;

use protocol::scene::Scene;

use super::{
    Case, EXCHANGE_BOUND, FLUID_ENERGY_BOUND, GAMMA, HALVED_STEP_RATIO, Kept, MASS_BOUND, Outcome,
    P, RHO, ROUND_OFF_FLOOR, SOLID_ENERGY_BOUND, STATE_BOUND,
};
use crate::{InProcess, run_in_process_to};

/// Runs `case` in one process (its outputs in `out`) and checks its invariants.
pub fn check(case: &Case, out: &Path) -> Outcome {
    let scene = match Scene::from_toml_str(&case.toml, &format!("corpus-{}", case.seed)) {
        Ok(scene) => scene,
        Err(e) => return Outcome::Refused(e.to_string()),
    };
    if let Err(e) = std::fs::create_dir_all(out) {
        return Outcome::Stopped(format!("{}: {e}", out.display()));
    }
    let run = run_in_process_to(&scene, Some(out));
    match judge(case, &run, out) {
        Outcome::SolidEnergy(e) => halved(scene, &run, out, e),
        outcome => outcome,
    }
}

/// Reruns a case whose solid energy balance drifted by `error` to the time `run` reached with
/// every step at most half the smallest step it took, and says whether the drift converges as
/// the integrator's error does ([`HALVED_STEP_RATIO`]).
fn halved(mut scene: Scene, run: &InProcess, out: &Path, error: f64) -> Outcome {
    let dt_min = run
        .sink
        .diagnostics
        .iter()
        .filter_map(|d| serde_json::from_slice::<serde_json::Value>(d).ok())
        .filter_map(|v| v["dt"].as_f64())
        .fold(f64::INFINITY, f64::min);
    if !dt_min.is_finite() || run.summary.steps == 0 {
        return Outcome::SolidEnergy(error);
    }
    scene.run.t_end = run.summary.t_end;
    scene.run.dt_max = Some(0.5 * dt_min);
    // Enough steps to reach the same time at the halved step (the run stopped at its
    // `max_steps`, the rerun at `t_end`).
    scene.run.max_steps = Some((run.summary.t_end / (0.5 * dt_min)).ceil() as u64 + 2);
    let out = out.join("halved");
    if std::fs::create_dir_all(&out).is_err() {
        return Outcome::SolidEnergy(error);
    }
    let rerun = run_in_process_to(&scene, Some(&out));
    if rerun.error.is_some() || !rerun.node_errors.is_empty() {
        return Outcome::SolidEnergy(error);
    }
    let (_, energy) = balances(&rerun);
    if energy.solid <= HALVED_STEP_RATIO * error {
        Outcome::Converging(error, energy.solid)
    } else {
        Outcome::SolidEnergy(error)
    }
}

/// The three energy balances of a run (see the module docs), each as a relative error.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Balances {
    /// The fluid's energy plus the work it gave: largest drift over its energy.
    pub fluid: f64,
    /// Largest difference of the two sides' works over the largest work.
    pub exchange: f64,
    /// The solid's energy plus dissipated less received: largest drift over its energies.
    pub solid: f64,
}

/// The largest relative mass error and the energy balances over the ledger of every step.
fn balances(run: &InProcess) -> (f64, Balances) {
    let mut mass: f64 = 0.0;
    let field = |l: &serde_json::Value, k: &str| l[k].as_f64().unwrap_or(0.0);
    // Per step: fluid energy + work it gave, solid energy + dissipated − work received, and
    // the scales.
    let mut fluid: Vec<f64> = Vec::new();
    let mut solid: Vec<f64> = Vec::new();
    let (mut fluid_scale, mut work_scale, mut solid_scale, mut mismatch) =
        (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for d in &run.sink.diagnostics {
        let Ok(v) = serde_json::from_slice::<serde_json::Value>(d) else {
            continue;
        };
        let l = &v["ledger"];
        if l.is_null() {
            continue;
        }
        mass = mass.max(field(l, "mass_rel_err").abs());
        let (ef, es, ks) = (
            field(l, "fluid_energy"),
            field(l, "solid_energy"),
            field(l, "solid_kinetic"),
        );
        let (wf, ws, ds) = (
            field(l, "work_fluid"),
            field(l, "work_solid"),
            field(l, "solid_dissipated"),
        );
        fluid.push(ef + wf);
        solid.push(es + ds - ws);
        fluid_scale = fluid_scale.max(ef.abs());
        work_scale = work_scale.max(wf.abs()).max(ws.abs());
        solid_scale = solid_scale
            .max(ks.abs())
            .max((es - ks).abs())
            .max(ws.abs())
            .max(ds.abs());
        mismatch = mismatch.max((wf - ws).abs());
    }
    let drift = |v: &[f64]| {
        v.first().map_or(0.0, |&a| {
            v.iter().fold(0.0f64, |m, &x| m.max((x - a).abs()))
        })
    };
    let ratio = |x: f64, scale: f64| if scale > 0.0 { x / scale } else { x };
    let b = Balances {
        fluid: ratio(drift(&fluid), fluid_scale),
        exchange: ratio(mismatch, work_scale.max(ROUND_OFF_FLOOR * fluid_scale)),
        solid: ratio(
            drift(&solid),
            solid_scale.max(ROUND_OFF_FLOOR * fluid_scale),
        ),
    };
    (mass, b)
}

fn judge(case: &Case, run: &InProcess, out: &Path) -> Outcome {
    let (mass, energy) = balances(run);
    let error = run
        .error
        .clone()
        .or_else(|| run.node_errors.first().cloned());
    if let Some(e) = error {
        if e.contains("non-physical") || e.contains("rho = ") || e.contains("NonPhysical") {
            return Outcome::NonPhysical(e);
        }
        if e.contains("mass error") {
            // The step that stopped has no diagnostics: its error is in the message.
            let stated = e
                .split("relative mass error = ")
                .nth(1)
                .and_then(|r| r.split_whitespace().next())
                .and_then(|x| x.parse::<f64>().ok());
            return Outcome::Mass(stated.unwrap_or(mass).max(mass));
        }
        return Outcome::Stopped(e);
    }
    if mass > MASS_BOUND {
        return Outcome::Mass(mass);
    }
    if case.kept != Kept::None {
        match drift(case, out) {
            Ok(d) if d > STATE_BOUND => return Outcome::Drift(d),
            Ok(_) => {}
            Err(e) => return Outcome::Stopped(e),
        }
    }
    if energy.fluid > FLUID_ENERGY_BOUND {
        return Outcome::FluidEnergy(energy.fluid);
    }
    if energy.exchange > EXCHANGE_BOUND {
        return Outcome::Exchange(energy.exchange);
    }
    if energy.solid > SOLID_ENERGY_BOUND {
        return Outcome::SolidEnergy(energy.solid);
    }
    Outcome::Ok
}

/// The largest deviation of the last fluid output from the state that must stay.
fn drift(case: &Case, out: &Path) -> Result<f64, String> {
    let last = (0..1000)
        .rev()
        .map(|k| out.join(format!("fluid_{k}.csv")))
        .find(|p| p.exists())
        .ok_or("no fluid output")?;
    let text = std::fs::read_to_string(&last).map_err(|e| e.to_string())?;
    let table = coupler_node::report::data::Table::parse(&text, &last.display().to_string())
        .map_err(|e| e.to_string())?;
    let stream = velocity_of(&case.toml);
    let c_sound = (GAMMA * P / RHO).sqrt();
    let dim = case.dim;
    if table.header.len() != 2 * dim + 3 {
        return Err(format!(
            "{}: {} columns",
            last.display(),
            table.header.len()
        ));
    }
    let mut worst: f64 = 0.0;
    for v in &table.rows {
        let rho = v[dim];
        worst = worst.max((rho - RHO).abs() / RHO);
        for a in 0..dim {
            worst = worst.max((v[dim + 1 + a] - stream[a]).abs() / c_sound);
        }
        worst = worst.max((v[2 * dim + 1] - P).abs() / P);
    }
    Ok(worst)
}

/// The gas's initial velocity in a case's text (zero if none).
fn velocity_of(toml: &str) -> [f64; 3] {
    let mut out = [0.0; 3];
    let fluid = toml.split("[solid]").next().unwrap_or("");
    if let Some(line) = fluid.lines().find(|l| l.starts_with("velocity = ")) {
        let inner = line
            .trim_start_matches("velocity = [")
            .trim_end_matches(']');
        for (a, x) in inner.split(',').enumerate().take(3) {
            out[a] = x.trim().parse().unwrap_or(0.0);
        }
    }
    out
}
