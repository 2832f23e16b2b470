//! K sub-steps per coupling step (`run.solid_substeps`, docs/subcycling.md): a spring-mass
//! under a constant load follows the exact discrete Verlet trajectory of step dt/K, bit for bit
//! the K whole steps; a trial is a function of its loads alone (repeated trials from the step's
//! start); the work booked is `F·(Xⁿ⁺¹ − Xⁿ) + τ·Σφ`, which the trial's mean velocities give back;
//! a free body without loads stays at rest; a link breaks in the sub-step that stretches it.

use crate::dem_support;

use dem_support::*;
use protocol::scene::{LinksConfig, Motion, SolidConfig};
use solid_node::dem::{ParticleId, Solid};

const K: f64 = 2000.0;
const D0: f64 = 0.005;
const DENSITY: f64 = 1000.0;

/// Two square particles of side D0 along x joined by a spring of stiffness K, the first fixed.
fn spring_mass() -> SolidConfig {
    let mut cfg = box_config(
        vec![D0, 0.0],
        vec![2.0 * D0, D0],
        vec![2, 1],
        1e6,
        0.3,
        DENSITY,
    );
    cfg.bodies[0].links = Some(LinksConfig {
        spring: K,
        rotation: 0.0,
    });
    constrain(&mut cfg, vec![-1.0, -1.0], vec![D0, 1.0], Motion::Fixed);
    cfg
}

/// Loads: `fx` along x on particle 1, none on particle 0, no torque.
fn loads(fx: f64) -> (Vec<f64>, Vec<f64>) {
    (vec![0.0, 0.0, fx, 0.0], vec![0.0, 0.0])
}

fn state(solid: &Solid) -> Vec<u64> {
    let mut bits = Vec::new();
    for p in 0..solid.n_particles() {
        let id = ParticleId(p as u32);
        bits.extend(solid.position(id).iter().map(|x| x.to_bits()));
        bits.extend(solid.velocity(id).iter().map(|x| x.to_bits()));
        bits.extend(solid.orientation(id).iter().map(|x| x.to_bits()));
        bits.extend(solid.angular_velocity(id).iter().map(|x| x.to_bits()));
    }
    bits
}

#[test]
fn a_spring_mass_under_a_constant_load_follows_the_discrete_verlet_trajectory_for_each_k() {
    let m = DENSITY * D0 * D0;
    let f = 0.3;
    let omega = (K / m).sqrt();
    let dt = 0.5 / omega;
    for k in [1u32, 2, 3, 8, 64] {
        let h = dt / f64::from(k);
        let mut solid = build(&spring_mass(), 2, 1);
        let mut whole = build(&spring_mass(), 2, 1);
        let free = ParticleId(1);
        let x_rest = solid.position(free)[0];
        let (force, torque) = loads(f);
        // The discrete velocity Verlet of m x'' = f − K (x − x_rest), step h.
        let (mut x, mut v) = (0.0f64, 0.0f64);
        let accel = |x: f64| (f - K * x) / m;
        let mut worst: f64 = 0.0;
        for _ in 0..20 {
            solid.begin_substeps(dt, k);
            solid.trial(&force, &torque);
            let report = solid.commit();
            assert!(report.diagnostics.is_empty(), "{:?}", report.diagnostics);
            for _ in 0..k {
                let report = whole.step(h, &force, &torque);
                assert!(report.diagnostics.is_empty());
                let a = accel(x);
                let v_half = v + 0.5 * h * a;
                x += h * v_half;
                v = v_half + 0.5 * h * accel(x);
            }
            // K sub-steps are K whole steps of dt/K, bit for bit.
            assert_eq!(state(&solid), state(&whole), "K = {k}");
            let got = solid.position(free)[0] - x_rest;
            worst = worst.max((got - x).abs());
            assert_eq!(solid.velocity(free)[1], 0.0);
        }
        // Round-off of positions near x_rest = 1.5 D0 (the recurrence is in x − x_rest).
        let amplitude = 2.0 * f / K;
        println!("K = {k}: largest |x − x_Verlet| = {worst:e} m (amplitude {amplitude:e} m)");
        assert!(worst <= 1e-13 * x_rest, "K = {k}: {worst:e}");
    }
}

#[test]
fn a_trial_restarts_from_the_step_start_and_the_commit_takes_the_last() {
    let dt = 2e-4;
    let k = 7;
    let (force, torque) = loads(0.2);
    let (other, _) = loads(-5.0);
    let mut once = build(&spring_mass(), 2, 1);
    let mut again = build(&spring_mass(), 2, 1);
    for _ in 0..5 {
        once.begin_substeps(dt, k);
        let a = once.trial(&force, &torque).clone();
        once.commit();
        again.begin_substeps(dt, k);
        again.trial(&other, &torque);
        again.trial(&force, &torque);
        again.trial(&other, &torque);
        let b = again.trial(&force, &torque).clone();
        again.commit();
        assert_eq!(a.position, b.position);
        assert_eq!(a.velocity_half, b.velocity_half);
        assert_eq!(a.wet.vertices, b.wet.vertices);
        assert_eq!(state(&once), state(&again));
        assert_eq!(
            once.energies().external_work.to_bits(),
            again.energies().external_work.to_bits()
        );
    }
}

/// A free 3 x 2 block under a load and torque on each particle: the work booked over a step of
/// K sub-steps is what the trial's mean velocities give with the held loads, `dt (F·V̄ + τ·Ω̄)`
/// (the fluid's form), to round-off; the impulse is `F dt`.
#[test]
fn the_booked_work_is_the_held_loads_times_the_mean_motion() {
    let cfg = box_config(
        vec![0.0, 0.0],
        vec![0.3, 0.2],
        vec![3, 2],
        1e7,
        0.25,
        2000.0,
    );
    let mut solid = build(&cfg, 2, 1);
    let n = solid.n_particles();
    let force: Vec<f64> = (0..2 * n).map(|i| 50.0 * (1.0 + i as f64).sin()).collect();
    let torque: Vec<f64> = (0..n).map(|i| 3.0 * (2.0 + i as f64).cos()).collect();
    let stable = solid.stable_dt();
    for k in [1u32, 5, 33] {
        let dt = stable * f64::from(k);
        for _ in 0..3 {
            let w0 = solid.energies().external_work;
            let p0 = solid.external_impulse();
            solid.begin_substeps(dt, k);
            let trial = solid.trial(&force, &torque).clone();
            let report = solid.commit();
            assert!(report.diagnostics.is_empty(), "{:?}", report.diagnostics);
            let booked = solid.energies().external_work - w0;
            let (mut given, mut terms, mut at) = (0.0, 0.0, 0.0);
            for p in 0..n {
                for a in 0..2 {
                    let w = dt * force[2 * p + a] * trial.velocity_half[2 * p + a];
                    given += w;
                    terms += w.abs();
                    at += (force[2 * p + a] * trial.position[2 * p + a]).abs();
                }
                given += dt * torque[p] * trial.omega_half[p];
                terms += (dt * torque[p] * trial.omega_half[p]).abs();
            }
            // K > 1: both sides multiply the same displacement, a few ulps of each term. K = 1
            // keeps the mid-step velocity V^{n+1/2} (today's bits), whose product with dt is
            // the displacement up to the round-off of X^{n+1} = X^n + dt V^{n+1/2}: ulps of
            // F·X, not of F·ΔX.
            let bound = if k == 1 {
                8.0 * f64::EPSILON * at
            } else {
                8.0 * f64::EPSILON * terms
            };
            println!(
                "K = {k}: work booked {booked:e}, given {given:e}, difference {:e} (bound {bound:e})",
                booked - given
            );
            assert!(booked.abs() > 0.0);
            assert!((booked - given).abs() <= bound, "K = {k}");
            let impulse = solid.external_impulse();
            let fx: f64 = (0..n).map(|p| force[2 * p]).sum();
            assert!((impulse[0] - p0[0] - fx * dt).abs() <= 1e-13 * (fx * dt).abs());
        }
    }
}

#[test]
fn a_free_body_without_loads_stays_at_rest_for_any_k() {
    let cfg = box_config(
        vec![0.1, 0.2],
        vec![0.3, 0.2],
        vec![3, 2],
        1e7,
        0.25,
        2000.0,
    );
    let mut solid = build(&cfg, 2, 1);
    let before = state(&solid);
    let n = solid.n_particles();
    let (force, torque) = (vec![0.0; 2 * n], vec![0.0; n]);
    for k in [1u32, 2, 17, 64, 256] {
        solid.begin_substeps(solid.stable_dt() * f64::from(k), k);
        solid.trial(&force, &torque);
        assert!(solid.commit().diagnostics.is_empty());
    }
    assert_eq!(state(&solid), before);
}

/// A link that a sub-step stretches past its limit breaks in that sub-step: the step reports it
/// with the sub-step's end time, and the trial's surface at tⁿ⁺¹ already carries the crack.
#[test]
fn a_link_breaks_in_the_sub_step_that_stretches_it() {
    let mut cfg = spring_mass();
    with_fracture(&mut cfg, 0.01);
    let m = DENSITY * D0 * D0;
    let mut solid = build(&cfg, 2, 1);
    // Pulled at constant velocity from rest: the elongation first passes 1 % in sub-step j.
    let v = 2.0;
    solid.set_velocity(ParticleId(1), &[v, 0.0]);
    let k = 16;
    let dt = 0.02 * D0 / v;
    let h = dt / f64::from(k);
    let revision = solid.wet_surface().revision;
    solid.begin_substeps(dt, k);
    let trial = solid.trial(&loads(0.0).0, &loads(0.0).1).clone();
    assert!(trial.wet.revision > revision, "the trial carries the crack");
    let report = solid.commit();
    assert_eq!(report.broken_links.len(), 1);
    let t_break = report.broken_links[0].time;
    // The spring slows the particle a little: it breaks no earlier than the free motion would.
    let free = (0.01 * D0 / v / h).ceil() * h;
    println!("broke at {t_break:e} s (free motion {free:e} s, step end {dt:e} s, m {m:e} kg)");
    assert!(t_break < dt && t_break >= free * (1.0 - 1e-12));
    assert!(t_break <= free + 2.0 * h);
}
