//! A rigid piston pushed at constant speed V = 1 into gas at rest (ρ0 = p0 = 1, γ = 1.4) in a
//! 2-D channel with slip walls, against the exact moving-piston solution (numerics.md §4.3):
//! plateau density, shock position, piston pressure, first-order L1 convergence of the density,
//! the same flow along y, and conservation to round-off at every step (fluid mass constant, the
//! fluid's energy change equal to the piston's work).

use crate::embedded_support;

use embedded_support::*;
use fluid_node::embedded::Embedded;

const GAMMA: f64 = 1.4;
/// The gas at rest of `channel` (ρ = p = 1).
const RHO0: f64 = 1.0;
const P0: f64 = 1.0;
/// Piston speed [m/s].
const V: f64 = 1.0;
/// Channel length along the piston's motion and width across it \[m\].
const LENGTH: f64 = 1.0;
const WIDTH: f64 = 0.1;
/// Cells across the channel: the flow is 1-D, and the fluid does not need square cells (with
/// 40 square cells across instead, the N = 400 run gives the same profile; coarser grids differ
/// only through their time steps, which the finer y cells then limit).
const N_ACROSS: usize = 4;
/// Piston face at t = 0 \[m\], on no grid face of the grids used.
const X_P0: f64 = 0.1037;
/// Exact shock position at the end \[m\]: a face of every grid (44/50), 6 coarse cells from the
/// far wall.
// NOTE: the L1 error of a captured shock is `Δx f(φ)` with `f` depending on the sub-cell
// position `φ` of the shock, by a factor of up to 2 here: at an arbitrary end time the observed
// orders between successive grids scatter from −0.1 to 1.9 (measured at t = 0.39, 0.395, 0.4 and
// 0.41, N = 50 to 1600). Ending with the exact shock on a face of every grid fixes `φ`.
const X_SHOCK_END: f64 = 0.88;
/// Cells next to the piston left out of the plateau: the start-up (wall-heating) layer, up to
/// 0.9 % low and 0.6 % high over the first ~14 cells on every grid (measured N = 50 to 400).
const PLATEAU_SKIP_PISTON: usize = 16;
/// Cells behind the shock left out of the plateau (its profile spans ~3 cells).
const PLATEAU_SKIP_SHOCK: usize = 4;

/// Shock speed S, plateau pressure p1 and plateau density ρ1 (closed form for gas at rest).
fn exact() -> (f64, f64, f64) {
    let c0 = (GAMMA * P0 / RHO0).sqrt();
    let a = (GAMMA + 1.0) * V / 4.0;
    let s = a + (a * a + c0 * c0).sqrt();
    (s, P0 + RHO0 * s * V, RHO0 * s / (s - V))
}

/// End time \[s\] (≈ 0.4029: the piston has moved 0.40 m, the shock 0.78 m: 39 cells at N = 50,
/// 310 at N = 400).
fn t_end() -> f64 {
    (X_SHOCK_END - X_P0) / exact().0
}

/// What one run measured.
struct Outcome {
    /// Cells along the channel.
    n: usize,
    /// Density along the channel [kg/m³] and fluid fraction (cells with none hold a ghost state).
    profile: Vec<f64>,
    alpha: Vec<f64>,
    /// Plateau cells and the mean, min and max of their density (`None` if there are none).
    plateau: Option<(usize, f64, f64, f64)>,
    /// Position where ρ crosses (ρ0 + ρ1)/2 (linear between cell centres) minus `X_P0 + S t`,
    /// in cells.
    shock_error_cells: f64,
    /// `(1/W) ∫ |ρ − ρ_exact|` over the fluid, with the exact cell averages [kg/m²].
    l1: f64,
    /// Force on the piston along the motion over the last step, per unit width \[Pa\].
    piston_pressure: f64,
    /// Largest `|ρ − row mean|` and largest transverse `|u|` over the fluid cells at the end.
    transverse: (f64, f64),
    /// Largest relative mass drift and energy imbalance over the steps.
    conservation: (f64, f64),
    steps: u64,
    seconds: f64,
}

/// The piston moving along `axis` (0: a channel along x, 1: along y) on `n` cells along it.
/// Asserts conservation at every step.
fn run(axis: usize, n: usize) -> Outcome {
    let clock = std::time::Instant::now();
    let across = 1 - axis;
    let scene = channel(axis, LENGTH, WIDTH, n, N_ACROSS);
    let mut solver = solver(&scene);
    // NOTE: the piston sticks out of the domain behind and on both sides of the channel, so that
    // its only wet face inside the domain is the one pushing the gas (the geometry drops the
    // sub-faces outside the domain). A piston exactly as wide as the channel puts its face at
    // y = 0 into the cells above it (the tie rule of `cutcell`): the covered cells along that
    // wall then receive the wall's pressure flux, and the first correct fails ("no fluid volume
    // to mix cell [0, 0, 0] into"). Sticking out by 1e-9 m already works.
    let point = |along: f64, side: f64| {
        let mut x = [0.0; 2];
        x[axis] = along;
        x[across] = side;
        x
    };
    let (side_lo, side_hi) = (-0.05 * WIDTH, 1.05 * WIDTH);
    let mut vertices = [
        point(-0.5, side_lo),
        point(X_P0, side_lo),
        point(X_P0, side_hi),
        point(-0.5, side_hi),
    ];
    if axis == 1 {
        // Swapping the axes reverses the orientation.
        vertices.reverse();
    }
    let mut velocity = [0.0; 2];
    velocity[axis] = V;
    let body = polygon_2d(&vertices, velocity, 0.0);
    let mut embedded = Embedded::new(&solver, body).expect("embedded");
    let start = embedded.totals(&solver);
    let (mut mass_drift, mut energy_imbalance) = (0.0f64, 0.0f64);
    let (t_end, mut t, mut steps) = (t_end(), 0.0, 0);
    let mut piston_pressure = 0.0;
    while t < t_end {
        let dt = solver.max_dt().min(embedded.one_cell_dt()).min(t_end - t);
        let next = translated(embedded.surface(), dt);
        let loads = step(&mut solver, &mut embedded, dt, next, steps);
        piston_pressure = -loads.force[axis] / WIDTH;
        t += dt;
        steps += 1;
        // NOTE: walls everywhere, so the fluid keeps its mass, and its energy changes only by
        // the work the piston did on it (`work_given` is the fluid's loss). Measured: 1.5e-16
        // and 1.8e-15 relative (N up to 1600, 3108 steps); 1e-13 leaves a factor of 50.
        let now = embedded.totals(&solver);
        let dm = (now.mass - start.mass).abs() / start.mass;
        let received = -embedded.budget().work_given;
        let de = (now.energy - start.energy - received).abs() / start.energy;
        assert!(
            dm <= 1e-13,
            "N = {n}, axis {axis}, step {steps}: mass {} -> {} ({dm:e} relative)",
            start.mass,
            now.mass
        );
        assert!(
            de <= 1e-13,
            "N = {n}, axis {axis}, step {steps}: energy {} -> {}, piston work {received}, imbalance {de:e} relative",
            start.energy,
            now.energy
        );
        mass_drift = mass_drift.max(dm);
        energy_imbalance = energy_imbalance.max(de);
    }
    // Every row holds the same 1-D flow: average the rows.
    let (s, _, rho1) = exact();
    let grid = solver.grid().clone();
    let dx = grid.dx[axis];
    let x_piston = X_P0 + V * t;
    let x_shock = X_P0 + s * t;
    let lambda = embedded.solid_fraction();
    let mut profile = vec![0.0; n];
    let mut alpha = vec![0.0; n];
    for (c, l) in lambda.iter().enumerate() {
        let m = grid.ijk(c)[axis];
        profile[m] += solver.primitive(c).0 / N_ACROSS as f64;
        alpha[m] += (1.0 - l) / N_ACROSS as f64;
    }
    let (mut spread, mut v_across) = (0.0f64, 0.0f64);
    for (c, l) in lambda.iter().enumerate() {
        if *l < 1.0 {
            let (rho, u, _) = solver.primitive(c);
            spread = spread.max((rho - profile[grid.ijk(c)[axis]]).abs());
            v_across = v_across.max(u[across].abs());
        }
    }
    let mut l1 = 0.0;
    for m in 0..n {
        // Exact mass of the fluid part [a, b] of the cell, against the cell's (the fluid
        // length is α Δx, and equals b − a up to round-off).
        let (a, b) = ((m as f64 * dx).max(x_piston), (m + 1) as f64 * dx);
        if alpha[m] <= 0.0 || b <= a {
            continue;
        }
        let exact_mass =
            rho1 * (x_shock.min(b) - a).max(0.0) + RHO0 * (b - x_shock.max(a)).max(0.0);
        l1 += (alpha[m] * dx * profile[m] - exact_mass).abs();
    }
    let plateau = plateau(&profile, x_piston, x_shock, dx);
    // The shock: the last crossing of the mid density.
    let mid = 0.5 * (RHO0 + rho1);
    let from = (x_piston / dx).ceil() as usize;
    let crossing = last_crossing(&profile, from, mid);
    Outcome {
        n,
        profile,
        alpha,
        plateau,
        shock_error_cells: crossing - x_shock / dx,
        l1,
        piston_pressure,
        transverse: (spread, v_across),
        conservation: (mass_drift, energy_imbalance),
        steps,
        seconds: clock.elapsed().as_secs_f64(),
    }
}

/// The plateau cells of the row-averaged density `profile` between the piston at `x_piston`
/// and the shock at `x_shock` (cells of width `dx`), and the mean, min and max of their density.
fn plateau(
    profile: &[f64],
    x_piston: f64,
    x_shock: f64,
    dx: f64,
) -> Option<(usize, f64, f64, f64)> {
    let first = (x_piston / dx).ceil() as usize + PLATEAU_SKIP_PISTON;
    let last = (x_shock / dx).floor() as usize - PLATEAU_SKIP_SHOCK;
    (first < last).then(|| {
        let cells = &profile[first..last];
        let mean = cells.iter().sum::<f64>() / cells.len() as f64;
        let (min, max) = cells
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &r| {
                (lo.min(r), hi.max(r))
            });
        (cells.len(), mean, min, max)
    })
}

/// Where `profile` last falls through `mid` after cell `from`, in cells (linear between cell
/// centres).
fn last_crossing(profile: &[f64], from: usize, mid: f64) -> f64 {
    let n = profile.len();
    let m = (from..n - 1)
        .rev()
        .find(|&m| profile[m] >= mid && profile[m + 1] < mid)
        .expect("a shock in the channel");
    m as f64 + 0.5 + (profile[m] - mid) / (profile[m] - profile[m + 1])
}

fn print(label: &str, o: &Outcome) {
    let (_, p1, rho1) = exact();
    let plateau = match o.plateau {
        Some((cells, mean, min, max)) => format!(
            "plateau rho {mean:.6} over {cells} cells (exact {rho1:.6}, {:+.2e} relative; min {min:.6}, max {max:.6})",
            mean / rho1 - 1.0
        ),
        None => "no plateau cells".to_string(),
    };
    println!(
        "{label} N = {}: {} steps, {:.2} s; {plateau}; shock {:+.3} cells; L1(rho) {:.4e}; piston pressure {:.6} ({:+.2e} relative); |rho - row mean| {:.1e}, |u across| {:.1e}; mass drift {:.1e}, energy imbalance {:.1e}",
        o.n,
        o.steps,
        o.seconds,
        o.shock_error_cells,
        o.l1,
        o.piston_pressure,
        o.piston_pressure / p1 - 1.0,
        o.transverse.0,
        o.transverse.1,
        o.conservation.0,
        o.conservation.1
    );
}

/// The checks every grid passes, along either axis.
fn check(o: &Outcome) {
    let (_, p1, rho1) = exact();
    // NOTE: measured mean plateau errors +5.7e-5 (N = 100, 17 cells), +7.8e-5 (200, the same
    // along y), +2.8e-5 (400); with the wall pressure of paper 003 (each sweep's start) +7.9e-5,
    // +1.6e-4, +6.2e-5, +2.0e-5 (800), +1.0e-5 (1600); 5e-4 leaves a factor of 3. N = 50 has no
    // plateau cells (its 19 cells between piston and shock are all start-up layer).
    if let Some((_, mean, _, _)) = o.plateau {
        let err = mean / rho1 - 1.0;
        assert!(
            err.abs() <= 5e-4,
            "N = {}: plateau rho {mean} against {rho1} ({err:+e} relative)",
            o.n
        );
    }
    // NOTE: measured +0.058 (N = 50), +0.042, +0.038, +0.037 (N = 400); with paper 003's wall
    // pressure +0.087, +0.051, +0.034, +0.038, +0.039, +0.038 cells (N = 1600).
    assert!(
        o.shock_error_cells.abs() <= 0.25,
        "N = {}: shock {} cells from x_p0 + S t",
        o.n,
        o.shock_error_cells
    );
    // NOTE: measured −2.1e-4 (N = 50), +4.6e-5 (100), +1.7e-5 (200), −2.4e-6 (400); with paper
    // 003's wall pressure −1.3e-3, +9.5e-5, +3.5e-5, ≤ 2e-6 beyond.
    let err = o.piston_pressure / p1 - 1.0;
    assert!(
        err.abs() <= 3e-3,
        "N = {}: piston pressure {} against {p1} ({err:+e} relative)",
        o.n,
        o.piston_pressure
    );
    // NOTE: the rows start bitwise equal and differ only by the round-off of their cut-cell
    // geometry: measured |rho - row mean| ≤ 4e-14 and |u across| ≤ 1.4e-15 up to N = 400, but
    // 3.2e-8 and 7.7e-14 (N = 800), 6.4e-10 and 1.0e-11 (N = 1600). There the row differences jump
    // from 1e-14 to 1e-8 within a few hundred steps in one fluid parcel ~50 cells ahead of the
    // piston, then stay (no exponential growth), as when the rows take different branches of
    // the nonlinear flux.
    assert!(
        o.transverse.0 <= 1e-6 && o.transverse.1 <= 1e-9,
        "N = {}: the flow is not 1-D: |rho - row mean| {:e}, |u across| {:e}",
        o.n,
        o.transverse.0,
        o.transverse.1
    );
}

#[test]
fn exact_piston_solution_matches_the_reference_numbers() {
    let (s, p1, rho1) = exact();
    assert!((s - 1.926650).abs() < 1e-6, "S = {s}");
    assert!((p1 - 2.926650).abs() < 1e-6, "p1 = {p1}");
    assert!((rho1 - 2.079156).abs() < 1e-6, "rho1 = {rho1}");
}

#[test]
fn piston_along_x_matches_the_exact_solution_and_converges_at_first_order() {
    let slow = std::env::var("COSIM_SLOW_TESTS").is_ok_and(|v| v == "1");
    let sizes: &[usize] = if slow {
        &[50, 100, 200, 400, 800, 1600]
    } else {
        &[50, 100, 200, 400]
    };
    let outcomes: Vec<Outcome> = sizes.iter().map(|&n| run(0, n)).collect();
    for o in &outcomes {
        print("x", o);
    }
    println!("     N   L1(rho)     order");
    println!("{:6}   {:.4e}", outcomes[0].n, outcomes[0].l1);
    let mut orders = Vec::new();
    for pair in outcomes.windows(2) {
        let order = (pair[0].l1 / pair[1].l1).log2();
        println!("{:6}   {:.4e}  {order:.3}", pair[1].n, pair[1].l1);
        orders.push(order);
    }
    for o in &outcomes {
        check(o);
    }
    // NOTE: a shock limits the order to 1; measured 1.031, 0.983, 1.015 (N = 50 to 400; with
    // paper 003's wall pressure 1.075, 1.064, 0.906, 1.076, 1.050 up to 1600).
    for (pair, order) in outcomes.windows(2).zip(&orders) {
        assert!(
            *order >= 0.8,
            "L1 order {order:.3} from N = {} to {} ({:e} to {:e})",
            pair[0].n,
            pair[1].n,
            pair[0].l1,
            pair[1].l1
        );
    }
}

#[test]
fn piston_along_y_gives_the_flow_of_the_piston_along_x() {
    let n = 200;
    let along_x = run(0, n);
    let along_y = run(1, n);
    print("x", &along_x);
    print("y", &along_y);
    check(&along_y);
    // The plateau itself, to the same tolerance as along x (`check`), and the whole profile.
    let diff = along_x
        .profile
        .iter()
        .zip(&along_y.profile)
        .zip(&along_x.alpha)
        .filter(|(_, alpha)| **alpha > 0.0)
        .map(|((a, b), _)| (a - b).abs())
        .fold(0.0, f64::max);
    println!("max |rho_x - rho_y| along the channel: {diff:e}");
    // NOTE: the same 1-D flow up to round-off (the sweep order differs: the piston's axis is
    // swept first on even steps along x, on odd steps along y); measured 3.7e-14.
    assert!(
        diff <= 1e-12,
        "the profiles along x and y differ by {diff:e}"
    );
}
