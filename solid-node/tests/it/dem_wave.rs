//! Compression wave speed in a bar (ν = 0, and ν = 0.3 one particle thick): the first axial mode of a clamped–free bar of
//! length l has f = c/(4l); the measured c = 4 l f must be within 2% of √(E/ρ).
//!
//! The bar is a chain of cubes with the clamp at the centre of a fixed particle (see
//! `dem_cantilever.rs` for why).

use crate::dem_support;

use dem_support::*;
use protocol::scene::Motion;
use solid_node::dem::ParticleId;

#[test]
fn compression_wave_speed_matches_sqrt_e_over_rho() {
    wave_speed(0.0);
}

/// With ν ≠ 0 a one-particle-thick bar must still have Young's modulus E: the free volume
/// `V + 3ν/(1−2ν) V^f` is built for that (and it pins the reading of the volumetric term in
/// `link_force.rs`: the printed sum would give 1.23 E at ν = 0.3, c 11% too high).
#[test]
fn compression_wave_speed_with_poisson_effect_in_a_thin_bar() {
    wave_speed(0.3);
}

fn wave_speed(poisson: f64) {
    let (young, rho, side) = (1e8, 1000.0, 0.1);
    let n: u32 = if slow() { 200 } else { 50 };
    let h = side;
    let l = h * (n as f64 + 0.5);
    let mut cfg = box_config(
        vec![(l - 0.5 * h) / 2.0, 0.0, 0.0],
        vec![l + 0.5 * h, side, side],
        vec![n + 1, 1, 1],
        young,
        poisson,
        rho,
    );
    constrain(
        &mut cfg,
        vec![-1.0, -1.0, -1.0],
        vec![1e-9, 1.0, 1.0],
        Motion::Fixed,
    );
    let mut solid = build(&cfg, 3, 1);
    let c_exact = (young / rho).sqrt();
    for p in 0..solid.n_particles() {
        let x = solid.model().particles[p].x0.x;
        let v = 1e-3 * (std::f64::consts::PI * x / (2.0 * l)).sin();
        solid.set_velocity(ParticleId(p as u32), &[v, 0.0, 0.0]);
    }
    let last = ParticleId(n);
    let x_end0 = solid.position(last)[0];
    let dt = 0.9 * solid.max_dt(f64::INFINITY);
    let f_exact = c_exact / (4.0 * l);
    let (mut t, mut y) = (vec![0.0], vec![0.0]);
    while solid.time() < 3.3 / f_exact {
        let report = solid.step_free(dt);
        assert!(report.diagnostics.is_empty(), "{:?}", report.diagnostics);
        t.push(solid.time());
        // Displacement is a sine starting upward: follow its negative's upward crossings.
        y.push(-(solid.position(last)[0] - x_end0));
    }
    let f = 1.0 / mean_period(&upward_crossings(&t, &y));
    let c = 4.0 * l * f;
    let err = (c - c_exact).abs() / c_exact;
    println!(
        "bar of {n} particles, nu = {poisson}: c = {c:.3} m/s, sqrt(E/rho) = {c_exact:.3} m/s, error {:.3}%",
        100.0 * err
    );
    assert!(err < 0.02, "wave speed {c} vs {c_exact}");
}
