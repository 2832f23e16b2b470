//! Long-time energy behaviour without fracture (003 §2.2: explicit symplectic scheme): over
//! 10⁵ steps the total-energy error stays bounded, does not drift, and its amplitude falls about
//! 4× when dt halves (second order). ν ≠ 0, so the volumetric terms are exercised too.

use crate::dem_support;

use dem_support::*;
use solid_node::dem::{ParticleId, Solid};

fn lattice(dim: usize) -> Solid {
    let cfg = if dim == 3 {
        box_config(
            vec![0.0; 3],
            vec![0.3, 0.2, 0.2],
            vec![3, 2, 2],
            1e6,
            0.25,
            1000.0,
        )
    } else {
        box_config(vec![0.0; 2], vec![0.3, 0.2], vec![3, 2], 1e6, 0.25, 1000.0)
    };
    let mut solid = build(&cfg, dim, 1);
    let mut noise = Noise(0x2545_F491_4F6C_DD1D);
    for p in 0..solid.n_particles() {
        let v: Vec<f64> = (0..dim).map(|_| 0.05 * noise.next()).collect();
        let w: Vec<f64> = (0..if dim == 3 { 3 } else { 1 })
            .map(|_| 0.5 * noise.next())
            .collect();
        solid.set_velocity(ParticleId(p as u32), &v);
        solid.set_angular_velocity(ParticleId(p as u32), &w);
    }
    solid
}

/// (amplitude max|E − E0|/E0, drift = (mean of last 10% − mean of first 10%)/E0).
fn run(dim: usize, dt: f64, t_end: f64) -> (f64, f64) {
    let mut solid = lattice(dim);
    let e0 = solid.energies().total();
    let steps = (t_end / dt).round() as usize;
    let window = steps / 10;
    let (mut amp, mut first, mut last): (f64, f64, f64) = (0.0, 0.0, 0.0);
    for k in 0..steps {
        let report = solid.step_free(dt);
        assert!(report.diagnostics.is_empty(), "{:?}", report.diagnostics);
        let err = (report.energies.total() - e0) / e0;
        amp = amp.max(err.abs());
        if k < window {
            first += err / window as f64;
        }
        if k >= steps - window {
            last += err / window as f64;
        }
    }
    (amp, last - first)
}

fn check(dim: usize) {
    let solid = lattice(dim);
    let dt = 0.25 * solid.elastic_dt_limit().0;
    let steps = if slow() { 1_000_000.0 } else { 100_000.0 };
    let t_end = steps * dt;
    let (amp1, drift1) = run(dim, dt, t_end);
    let (amp2, drift2) = run(dim, 0.5 * dt, t_end);
    let ratio = amp1 / amp2;
    println!(
        "{dim}-D, {steps} steps: amplitude {amp1:.3e} (dt) {amp2:.3e} (dt/2), ratio {ratio:.3}; drift {drift1:.2e}, {drift2:.2e}"
    );
    assert!(amp1 < 0.05, "energy error amplitude {amp1}");
    assert!((3.3..4.7).contains(&ratio), "amplitude ratio {ratio}");
    assert!(
        drift1.abs() < 0.2 * amp1,
        "drift {drift1} vs amplitude {amp1}"
    );
    assert!(
        drift2.abs() < 0.2 * amp2,
        "drift {drift2} vs amplitude {amp2}"
    );
}

#[test]
fn energy_error_is_bounded_second_order_without_drift_3d() {
    check(3);
}

#[test]
fn energy_error_is_bounded_second_order_without_drift_2d() {
    check(2);
}
