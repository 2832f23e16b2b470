//! A rigid piston withdrawn at constant speed V from gas at rest (ρ0 = p0 = 1, γ = 1.4) in a
//! 2-D channel with slip walls, against the exact solution (issue 35 item 2): a rarefaction
//! fan into the gas, a uniform state between its tail and the piston, and, when V exceeds the
//! escape speed 2c0/(γ − 1), a vacuum between the gas's front and the piston.

use crate::embedded_support;

use embedded_support::*;
use fluid_node::embedded::Embedded;

const GAMMA: f64 = 1.4;
/// The gas at rest of `channel` (ρ = p = 1).
const RHO0: f64 = 1.0;
const P0: f64 = 1.0;
/// Channel length and width \[m\].
const LENGTH: f64 = 1.0;
const WIDTH: f64 = 0.1;
const N_ACROSS: usize = 4;
/// `fluid.vacuum.rho`, the scene's default [kg/m³].
const VACUUM_RHO: f64 = 1e-10;
/// Piston face at t = 0 \[m\], on no grid face of the grids used; the gas lies beyond it.
const X_P0: f64 = 0.6037;

fn c0() -> f64 {
    (GAMMA * P0 / RHO0).sqrt()
}

/// Exact density at `x` and time `t` for a piston withdrawn at speed `v` (towards −x).
fn exact_rho(x: f64, t: f64, v: f64) -> f64 {
    let c0 = c0();
    let xi = (x - X_P0) / t;
    if xi >= c0 {
        return RHO0;
    }
    // Behind the head: u − 2c/(γ − 1) = −2 c0/(γ − 1) and x = (u + c) t in the fan.
    let u_fan = 2.0 * (xi - c0) / (GAMMA + 1.0);
    let u = u_fan.max(-v);
    if xi < -v {
        return 0.0; // inside the piston
    }
    let c = c0 + 0.5 * (GAMMA - 1.0) * u;
    if c <= 0.0 {
        return 0.0;
    }
    RHO0 * (c / c0).powf(2.0 / (GAMMA - 1.0))
}

/// Exact mass of `[a, b]` at `t` (midpoint rule on 400 pieces: the profile is continuous and
/// piecewise smooth, so the rule's error is ~1e-6 of the cell's mass, far below the scheme's).
fn exact_mass(a: f64, b: f64, t: f64, v: f64) -> f64 {
    let n = 400;
    let h = (b - a) / n as f64;
    (0..n)
        .map(|i| exact_rho(a + (i as f64 + 0.5) * h, t, v))
        .sum::<f64>()
        * h
}

struct Outcome {
    l1: f64,
    steps: u64,
    mass_drift: f64,
    energy_imbalance: f64,
    min_rho: f64,
    min_p: f64,
    /// Largest density of the cells wholly between the piston and the exact front of the gas
    /// (none for a piston slower than the escape speed) [kg/m³].
    vacuum_rho: f64,
    /// Mean density of the cells wholly between the piston and the exact tail of the fan, and
    /// their count (none beyond the escape speed).
    plateau: (f64, usize),
}

/// The piston withdrawn at `v` for `t_end` on `n` cells along the channel.
fn run(v: f64, n: usize, t_end: f64) -> Result<Outcome, String> {
    run_with(v, n, t_end, -3.0, -0.05 * WIDTH, 1.05 * WIDTH)
}

fn run_with(v: f64, n: usize, t_end: f64, back: f64, lo: f64, hi: f64) -> Result<Outcome, String> {
    let scene = channel(0, LENGTH, WIDTH, n, N_ACROSS);
    let mut solver = solver(&scene);
    let body = polygon_2d(
        &[[back, lo], [X_P0, lo], [X_P0, hi], [back, hi]],
        [-v, 0.0],
        0.0,
    );
    let mut embedded = Embedded::new(&solver, body).map_err(|e| e.to_string())?;
    let start = embedded.totals(&solver);
    let (mut t, mut steps) = (0.0, 0u64);
    let (mut mass_drift, mut energy_imbalance) = (0.0f64, 0.0f64);
    while t < t_end {
        let cfl = solver.max_dt();
        let one = embedded.one_cell_dt();
        let courant = 0.5;
        let dt = (courant / (courant / cfl + 2.0 / one)).min(t_end - t);
        let next = translated(embedded.surface(), dt);
        let report = embedded.predict(&mut solver, dt);
        if !report.ok() {
            return Err(format!("step {steps}: predict {:?}", report.troubles));
        }
        let current = embedded.surface().clone();
        embedded
            .loads(&solver, &current)
            .map_err(|e| e.to_string())?;
        embedded
            .correct(&mut solver, dt, next, steps, false)
            .map_err(|e| format!("step {steps}: {e}"))?;
        t += dt;
        steps += 1;
        let now = embedded.totals(&solver);
        mass_drift = mass_drift.max((now.mass - start.mass).abs() / start.mass);
        let received = -embedded.budget().work_given;
        energy_imbalance =
            energy_imbalance.max((now.energy - start.energy - received).abs() / start.energy);
    }
    let grid = solver.grid().clone();
    let dx = grid.dx[0];
    let lambda = embedded.solid_fraction();
    let (mut min_rho, mut min_p) = (f64::INFINITY, f64::INFINITY);
    let mut mass = vec![0.0; n];
    for (c, l) in lambda.iter().enumerate() {
        if *l >= 1.0 {
            continue;
        }
        let (rho, vel, p) = solver.primitive(c);
        // Below the vacuum density the product reads a cell's velocity as `ρu / ρ_vacuum`
        // (`euler::primitive_floored`): its ρ and ρu are what the fluxes left, and `ρu / ρ` is
        // no velocity (gas expanded 1e-47 times has no internal energy that `E − ½ρ|u|²` can
        // resolve). Read the pressure as the product does.
        let p = if rho < VACUUM_RHO {
            let speed2: f64 = vel.iter().map(|v| v * v).sum();
            p + (GAMMA - 1.0) * 0.5 * rho * speed2 * (1.0 - rho / VACUUM_RHO)
        } else {
            p
        };
        min_rho = min_rho.min(rho);
        min_p = min_p.min(p);
        let m = grid.ijk(c)[0];
        mass[m] += rho * (1.0 - l) * dx * grid.dx[1] / WIDTH;
    }
    let x_piston = X_P0 - v * t;
    let escape = 2.0 * c0() / (GAMMA - 1.0);
    let x_front = X_P0 - escape.min(v) * t;
    let x_tail = X_P0 + (c0() - 0.5 * (GAMMA + 1.0) * v) * t;
    let (mut vacuum_rho, mut plateau) = (0.0f64, (0.0, 0usize));
    for (m, cell_mass) in mass.iter().enumerate() {
        let (a, b) = (m as f64 * dx, (m + 1) as f64 * dx);
        let rho = cell_mass / dx;
        if v > escape && a > x_piston && b < x_front {
            vacuum_rho = vacuum_rho.max(rho);
        }
        if v < escape && a > x_piston && b < x_tail {
            plateau = (plateau.0 + rho, plateau.1 + 1);
        }
    }
    if plateau.1 > 0 {
        plateau.0 /= plateau.1 as f64;
    }
    let mut l1 = 0.0;
    for (m, cell_mass) in mass.iter().enumerate() {
        let (a, b) = ((m as f64 * dx).max(x_piston), (m + 1) as f64 * dx);
        if b <= a {
            continue;
        }
        l1 += (cell_mass - exact_mass(a, b, t, v)).abs();
    }
    Ok(Outcome {
        l1,
        steps,
        mass_drift,
        energy_imbalance,
        min_rho,
        min_p,
        vacuum_rho,
        plateau,
    })
}

fn print(v: f64, n: usize, o: &Outcome) {
    println!(
        "V = {v}, N = {n}: {} steps, L1 {:.3e}, mass {:.1e}, energy {:.1e}, min rho {:.2e}, \
         min p {:.2e}, vacuum rho {:.2e}, plateau {:?}",
        o.steps,
        o.l1,
        o.mass_drift,
        o.energy_imbalance,
        o.min_rho,
        o.min_p,
        o.vacuum_rho,
        o.plateau
    );
}

/// Walls everywhere: the fluid keeps its mass, its energy changes by the piston's work only,
/// and no cell holds ρ < 0 or p < 0.
fn conserving_and_physical(o: &Outcome) {
    assert!(o.mass_drift <= 1e-13, "mass {:e}", o.mass_drift);
    assert!(
        o.energy_imbalance <= 1e-13,
        "energy {:e}",
        o.energy_imbalance
    );
    assert!(
        o.min_rho >= 0.0 && o.min_p >= 0.0,
        "rho {} p {}",
        o.min_rho,
        o.min_p
    );
}

/// The L1 errors of the density on 50, 100 and 200 cells, each run checked for conservation
/// (walls everywhere: the fluid keeps its mass, and its energy changes by the piston's work
/// only) and positivity.
fn converging(v: f64, t_end: f64) -> Vec<Outcome> {
    let runs: Vec<Outcome> = [50, 100, 200]
        .into_iter()
        .map(|n| {
            let o = run(v, n, t_end).unwrap_or_else(|e| panic!("V = {v}, N = {n}: {e}"));
            print(v, n, &o);
            // NOTE: measured 1.8e-16 (mass) and 3.0e-16 (energy) at most.
            conserving_and_physical(&o);
            o
        })
        .collect();
    // NOTE: first order (the fan's corners and the piston's start-up layer). Measured: ratios
    // 2.04 and 2.23 (V = 2), 1.61 and 2.08 (V = 10, coarse grids still pre-asymptotic), orders
    // 1.09 and 0.87 from N = 50 to 200.
    for w in runs.windows(2) {
        let ratio = w[0].l1 / w[1].l1;
        assert!(
            ratio >= 1.5,
            "L1 {:e} -> {:e}: ratio {ratio}",
            w[0].l1,
            w[1].l1
        );
    }
    let order = 0.5 * (runs[0].l1 / runs[2].l1).log2();
    assert!(order >= 0.8, "L1 order {order} from N = 50 to 200");
    runs
}

#[test]
fn piston_withdrawn_slower_than_the_escape_speed_gives_the_exact_rarefaction() {
    // V = 2 against an escape speed of 5.92: the gas at the piston has ρ = (1 − (γ − 1) V / 2 c0)^5.
    let v = 2.0;
    let runs = converging(v, 0.25);
    let c = c0() - 0.5 * (GAMMA - 1.0) * v;
    let rho_star = RHO0 * (c / c0()).powf(2.0 / (GAMMA - 1.0));
    let fine = runs.last().expect("three runs");
    let (rho, cells) = fine.plateau;
    println!("plateau: {rho} over {cells} cells, exact {rho_star}");
    // NOTE: measured 0.1237 against 0.1271 over 38 cells (0.107 and 0.118 on 50 and 100 cells:
    // the start-up layer at the piston thins as the grid does).
    assert!(cells >= 30, "{cells} plateau cells");
    assert!(
        (rho - rho_star).abs() <= 0.04 * rho_star,
        "plateau {rho}, exact {rho_star}"
    );
}

#[test]
fn piston_withdrawn_faster_than_the_escape_speed_leaves_a_vacuum() {
    // V = 10 against an escape speed of 5.92: the gas expands into vacuum, its front moving at
    // −5.92 m/s, and nothing lies between that front and the piston.
    let runs = converging(10.0, 0.045);
    for o in &runs {
        // NOTE: measured 9.9e-9, 2.6e-15 and 1.5e-12 (N = 50, 100, 200): what the scheme's
        // dissipation spreads ahead of the front (7.1e-8, 2.3e-8 and 4.8e-9 with the classical
        // Lax–Friedrichs flux at the vacuum faces).
        assert!(
            o.vacuum_rho <= 1e-6 * RHO0,
            "density {:e} in the vacuum",
            o.vacuum_rho
        );
    }
}

#[test]
fn piston_withdrawn_faster_than_the_escape_speed_keeps_the_vacuum_positive_on_a_fine_grid() {
    // On 400 cells, with the classical Lax–Friedrichs flux at the vacuum faces, this run stopped
    // at step 1213 (t = 0.0424) on the cut cell at the piston (fluid fraction 0.16, rho = 4e-12,
    // velocity (−7, ±79) m/s, p = −5e-9): an odd–even mode of round-off across the channel,
    // which that flux leaves undamped and each cut cell the piston opens amplified by
    // 2 − (1 − Λ^n)/(1 − Λ^{n+1}), 1.2 to 1.3 per step (docs/cut-cells.md §4).
    let o = run(10.0, 400, 0.045).unwrap_or_else(|e| panic!("N = 400: {e}"));
    print(10.0, 400, &o);
    // NOTE: measured in 1030 steps: mass 0, energy 1.3e-16, min rho 1.3e-28, min p 3.3e-27,
    // L1 1.59e-3 (ratio 1.79 to N = 200), vacuum rho 1.4e-10.
    conserving_and_physical(&o);
    assert!(
        o.min_rho > 0.0 && o.min_p > 0.0,
        "rho {} p {}",
        o.min_rho,
        o.min_p
    );
    assert!(o.vacuum_rho <= 1e-6 * RHO0, "density {:e}", o.vacuum_rho);
}

#[test]
fn piston_leaving_the_wall_it_was_flush_against_leaves_vacuum_behind() {
    // The piston fills the channel's end, flush against the end wall and both side walls, and
    // moves into the gas: the cells it uncovers have no gas beside them (issue 35: it stopped at
    // step 0 on the corner cell, rho = 0, p = -0.4).
    for v in [0.01, 1.0] {
        let o = run_with(-v, 50, 0.05, 0.0, 0.0, WIDTH).unwrap_or_else(|e| panic!("V = {v}: {e}"));
        print(-v, 50, &o);
        assert!(o.mass_drift <= 1e-13, "mass {:e}", o.mass_drift);
        assert!(
            o.energy_imbalance <= 1e-13,
            "energy {:e}",
            o.energy_imbalance
        );
        assert_eq!(o.min_rho, 0.0, "the cells behind the piston hold vacuum");
        assert_eq!(o.min_p, 0.0);
    }
}
