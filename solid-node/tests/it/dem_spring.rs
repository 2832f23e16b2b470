//! Spring links (`[[solid.bodies]] links = { spring = k }`, paper 003 §5.3): a particle on a
//! spring to a fixed one oscillates with the period 2π √(m/k) and conserves energy; a chain with
//! fixed ends under a uniform transverse load settles at the exact static shape of the discrete
//! (nonlinear) string; results do not depend on the thread count.

use crate::dem_support;

use dem_support::*;
use protocol::scene::{LinksConfig, Motion, SolidConfig};
use solid_node::dem::ParticleId;

const K: f64 = 2000.0;
const D0: f64 = 0.005;

/// `n` square particles of side D0 in a row along x from x = 0, spring links, the first (and
/// with `fix_both` the last) fixed; ν = 0.3 so that a volumetric term would show.
fn chain(n: u32, density: f64, rotation: f64, fix_both: bool) -> SolidConfig {
    let l = D0 * n as f64;
    let mut cfg = box_config(
        vec![0.5 * l, 0.0],
        vec![l, D0],
        vec![n, 1],
        1e6,
        0.3,
        density,
    );
    cfg.bodies[0].links = Some(LinksConfig {
        spring: K,
        rotation,
    });
    constrain(&mut cfg, vec![-1.0, -1.0], vec![D0, 1.0], Motion::Fixed);
    if fix_both {
        constrain(&mut cfg, vec![l - D0, -1.0], vec![2.0, 1.0], Motion::Fixed);
    }
    cfg
}

#[test]
fn two_particle_spring_has_the_harmonic_period_and_conserves_energy() {
    let density = 1000.0;
    let mut solid = build(&chain(2, density, 0.0, false), 2, 1);
    let m = density * D0 * D0;
    let omega = (K / m).sqrt();
    let period = 2.0 * std::f64::consts::PI / omega;
    // The stability bound of a particle on one spring is 2/√(2k/m).
    let (limit, who) = solid.elastic_dt_limit();
    assert_eq!(who, ParticleId(1));
    assert!(
        (limit - 2.0 / (2.0 * K / m).sqrt()).abs() < 1e-12 * limit,
        "{limit}"
    );
    let free = ParticleId(1);
    let x0 = solid.position(free)[0];
    // Amplitude v/ω = 1e-4 D0.
    solid.set_velocity(free, &[1e-4 * D0 * omega, 0.0]);
    let e0 = solid.energies().total();
    let steps_per_period = 200;
    let dt = period / steps_per_period as f64;
    let periods = 100;
    let (mut t, mut y, mut e) = (vec![0.0], vec![0.0], vec![e0]);
    for _ in 0..periods * steps_per_period {
        let report = solid.step_free(dt);
        assert!(report.diagnostics.is_empty(), "{:?}", report.diagnostics);
        t.push(solid.time());
        y.push(solid.position(free)[0] - x0);
        e.push(solid.energies().total());
    }
    // Verlet: ω_h = (2/dt) asin(ω dt / 2), relative period error (ω dt)²/24 = 4e-5 here.
    let measured = mean_period(&upward_crossings(&t, &y)[1..]);
    let rel = (measured - period).abs() / period;
    assert!(rel < 1e-3, "period {measured} vs {period}: {rel:e}");
    // Bounded energy error (velocity Verlet on an oscillator: at most (ω dt)²/4 = 2.5e-4 of the
    // energy) and no drift: the mean energy of the last period equals the first's.
    let bound = (omega * dt).powi(2) / 4.0;
    let worst = e.iter().map(|x| (x - e0).abs()).fold(0.0, f64::max) / e0;
    assert!(worst < 1.01 * bound, "energy error {worst:e} > {bound:e}");
    let mean = |r: std::ops::Range<usize>| {
        let len = r.len() as f64;
        e[r].iter().sum::<f64>() / len
    };
    let n = steps_per_period;
    let drift = (mean(e.len() - n..e.len()) - mean(0..n)).abs() / e0;
    assert!(
        drift < 1e-7,
        "energy drift over {periods} periods {drift:e}"
    );
}

/// Exact static shape of a chain of `n_links` springs (stiffness k, rest length D0, no rest
/// tension) with fixed ends at the same height, span `n_links · D0`, under a transverse load
/// `f` on each free particle: every link carries the same horizontal tension H and the
/// vertical tension `V_l = f (n_free/2 − l)`; its length is `D0 + |T_l|/k`; H closes the span.
/// Returns the height of every particle.
fn exact_string(n_links: usize, f: f64) -> Vec<f64> {
    let half = (n_links - 1) as f64 / 2.0;
    let vertical: Vec<f64> = (0..n_links).map(|l| f * (half - l as f64)).collect();
    let span = |h: f64| -> f64 {
        vertical
            .iter()
            .map(|v| {
                let t = (h * h + v * v).sqrt();
                (D0 + t / K) * h / t
            })
            .sum::<f64>()
            - n_links as f64 * D0
    };
    // span(H) increases with H; bisection on [0, large].
    let (mut lo, mut hi) = (1e-12, 1e6);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if span(mid) > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let h = 0.5 * (lo + hi);
    let mut y = vec![0.0];
    for v in &vertical {
        let t = (h * h + v * v).sqrt();
        let last = *y.last().unwrap();
        y.push(last + (D0 + t / K) * v / t);
    }
    y
}

#[test]
fn twenty_particle_chain_reaches_the_static_shape_of_a_discrete_string() {
    let n = 20;
    let density = 1000.0;
    let mut solid = build(&chain(n, density, 0.0, true), 2, 1);
    let f = 0.05; // N per particle (per unit depth), along +y
    let exact = exact_string(n as usize - 1, f);
    let (limit, _) = solid.elastic_dt_limit();
    let dt = 0.5 * limit;
    let mut force = vec![0.0; 2 * n as usize];
    for p in 1..n as usize - 1 {
        force[2 * p + 1] = f;
    }
    let torque = vec![0.0; n as usize];
    // Dynamic relaxation: velocities scaled by (1 − 2e-3) after each step.
    for _ in 0..200_000 {
        solid.step(dt, &force, &torque);
        for p in 1..n - 1 {
            let v = solid.velocity(ParticleId(p));
            solid.set_velocity(ParticleId(p), &[v[0] * 0.998, v[1] * 0.998]);
        }
    }
    let y_mid = exact[9];
    assert!(y_mid > 1e-3, "{y_mid}");
    let mut worst: f64 = 0.0;
    for (p, y_exact) in exact.iter().enumerate() {
        let y = solid.position(ParticleId(p as u32))[1];
        worst = worst.max((y - y_exact).abs());
    }
    assert!(worst < 1e-6 * y_mid, "worst {worst:e} of {y_mid:e}");
    let v_max = (0..n)
        .map(|p| solid.velocity(ParticleId(p)))
        .fold(0.0f64, |m, v| m.max(v[0].abs()).max(v[1].abs()));
    assert!(v_max < 1e-9, "{v_max}");
}

#[test]
fn spring_chain_is_bit_identical_for_any_thread_count() {
    let run = |threads: usize| {
        let mut solid = build(&chain(20, 1000.0, 1e-3, true), 2, threads);
        for p in 1..19 {
            solid.set_velocity(ParticleId(p), &[0.01 * p as f64, 0.02]);
        }
        let dt = 0.5 * solid.elastic_dt_limit().0;
        for _ in 0..500 {
            solid.step_free(dt);
        }
        let mut out: Vec<u64> = (0..20)
            .flat_map(|p| solid.position(ParticleId(p)))
            .map(f64::to_bits)
            .collect();
        out.push(solid.energies().total().to_bits());
        out
    };
    assert_eq!(run(1), run(3));
}
