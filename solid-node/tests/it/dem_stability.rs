//! Elastic stability limit of the explicit scheme.
//!
//! Two free unit-depth squares (2-D, side h, ν = 0) linked by their common edge: k = E, m = ρh²,
//! I = ρh⁴/6, lever h/2. The linearised modes are compression (ω² = 2k/m), shear–rotation
//! (ω² = k/2 (4/m + h²/I) = 5E/(ρh²)) and flexion (ω² = 2(c_n + c_s)/I = E/(ρh²)), so Verlet/RATTLE
//! is stable for dt < dt_c = 2h/√(5E/ρ). Just below runs; just above blows up and the step
//! report names a particle. The computed bound must not exceed dt_c.

use crate::dem_support;

use dem_support::*;
use solid_node::dem::{Diagnostic, ParticleId, Solid};

const E: f64 = 1e7;
const RHO: f64 = 1000.0;
const H: f64 = 0.1;

fn pair() -> Solid {
    let cfg = box_config(vec![0.0, 0.0], vec![2.0 * H, H], vec![2, 1], E, 0.0, RHO);
    let mut solid = build(&cfg, 2, 1);
    let mut noise = Noise(7);
    for p in 0..2 {
        solid.set_velocity(ParticleId(p), &[1e-3 * noise.next(), 1e-3 * noise.next()]);
        solid.set_angular_velocity(ParticleId(p), &[1e-2 * noise.next()]);
    }
    solid
}

/// Runs `steps` steps; returns the first blow-up diagnostic, if any, and max E/E0.
fn run(dt: f64, steps: usize) -> (Option<Diagnostic>, f64) {
    let mut solid = pair();
    let e0 = solid.energies().total();
    let mut e_max: f64 = 0.0;
    for _ in 0..steps {
        let report = solid.step_free(dt);
        let blowup = report.diagnostics.into_iter().find(|d| {
            matches!(
                d,
                Diagnostic::DisplacementTooLarge { .. }
                    | Diagnostic::NonFinite { .. }
                    | Diagnostic::RotationTooLarge { .. }
                    | Diagnostic::Interpenetration { .. }
            )
        });
        if blowup.is_some() {
            return (blowup, e_max);
        }
        e_max = e_max.max(report.energies.total() / e0);
    }
    (None, e_max)
}

#[test]
fn just_below_the_elastic_limit_runs_and_just_above_blows_up_with_a_report() {
    let dt_c = 2.0 * H / (5.0 * E / RHO).sqrt();
    let (bound, _) = pair().elastic_dt_limit();
    println!(
        "exact limit {dt_c:e} s, computed bound {bound:e} s (ratio {:.4})",
        bound / dt_c
    );
    assert!(
        bound <= dt_c * (1.0 + 1e-12),
        "bound {bound} above the exact limit {dt_c}"
    );
    assert!(
        bound > 0.8 * dt_c,
        "bound {bound} too pessimistic vs {dt_c}"
    );

    let (diag, e_max) = run(0.98 * dt_c, 5000);
    println!("0.98 dt_c: {diag:?}, max E/E0 = {e_max:.3}");
    assert!(diag.is_none(), "{diag:?}");
    assert!(e_max < 100.0, "energy grew {e_max}x below the limit");

    let (diag, _) = run(1.02 * dt_c, 5000);
    println!("1.02 dt_c: {diag:?}");
    match diag {
        Some(Diagnostic::DisplacementTooLarge {
            particle,
            displacement,
            size,
        }) => {
            assert!(particle.0 < 2 && displacement > size);
        }
        Some(Diagnostic::NonFinite { particle, .. })
        | Some(Diagnostic::RotationTooLarge { particle, .. }) => assert!(particle.0 < 2),
        Some(Diagnostic::Interpenetration { particles, .. }) => assert!(particles[0].0 < 2),
        other => panic!("expected a blow-up report, got {other:?}"),
    }
}

#[test]
fn a_step_above_the_bound_is_reported() {
    let mut solid = pair();
    let (bound, particle) = solid.elastic_dt_limit();
    let report = solid.step_free(1.01 * bound);
    assert!(report.diagnostics.iter().any(|d| matches!(
        d,
        Diagnostic::DtAboveElasticLimit { limit, particle: p, .. } if *limit == bound && *p == particle
    )));
}

#[test]
fn max_dt_respects_the_displacement_cap_and_rotation_limit() {
    let mut solid = pair();
    solid.set_velocity(ParticleId(0), &[2.0, 0.0]);
    let dt = solid.max_dt(0.01);
    assert!(dt <= 0.01 / 2.0 + 1e-15);
    solid.set_velocity(ParticleId(0), &[0.0, 0.0]);
    solid.set_velocity(ParticleId(1), &[0.0, 0.0]);
    solid.set_angular_velocity(ParticleId(1), &[1000.0]);
    let dt = solid.max_dt(f64::INFINITY);
    assert!(dt <= std::f64::consts::PI / 8.0 / 1000.0 + 1e-15);
}

#[test]
fn non_finite_loads_are_reported_as_data_naming_the_particle() {
    let mut solid = pair();
    solid.begin_step(1e-5);
    solid.trial(&[0.0, 0.0, f64::NAN, 0.0], &[0.0, 0.0]);
    let report = solid.commit();
    assert!(
        report.diagnostics.iter().any(|d| matches!(
            d,
            Diagnostic::NonFinite { particle, .. } if *particle == ParticleId(1)
        )),
        "{:?}",
        report.diagnostics
    );
}

/// The computed bound is safe for 2-D and 3-D lattices with the volumetric term (ν up to 0.45):
/// at 0.999 of it nothing grows (a bound above the true limit would blow up exponentially).
#[test]
fn the_bound_is_safe_for_lattices_with_poisson_effect() {
    for dim in [2usize, 3] {
        for nu in [0.0, 0.3, 0.45] {
            let cfg = if dim == 3 {
                box_config(vec![0.0; 3], vec![0.4, 0.3, 0.2], vec![4, 3, 2], E, nu, RHO)
            } else {
                box_config(vec![0.0; 2], vec![0.4, 0.3], vec![4, 3], E, nu, RHO)
            };
            let mut solid = build(&cfg, dim, 1);
            let mut noise = Noise(11);
            for p in 0..solid.n_particles() {
                let v: Vec<f64> = (0..dim).map(|_| 1e-3 * noise.next()).collect();
                let w: Vec<f64> = (0..if dim == 3 { 3 } else { 1 })
                    .map(|_| 1e-2 * noise.next())
                    .collect();
                solid.set_velocity(ParticleId(p as u32), &v);
                solid.set_angular_velocity(ParticleId(p as u32), &w);
            }
            let (bound, _) = solid.elastic_dt_limit();
            let e0 = solid.energies().total();
            let mut e_max: f64 = 0.0;
            for _ in 0..5000 {
                let report = solid.step_free(0.999 * bound);
                assert!(
                    report.diagnostics.is_empty(),
                    "{dim}-D nu {nu}: {:?}",
                    report.diagnostics
                );
                e_max = e_max.max(report.energies.total() / e0);
            }
            println!(
                "{dim}-D, nu = {nu}: bound {bound:.4e} s, max E/E0 at 0.999 bound = {e_max:.3}"
            );
            assert!(e_max < 100.0, "{dim}-D nu {nu}: energy grew {e_max}x");
        }
    }
}
