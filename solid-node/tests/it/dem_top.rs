//! Torque-free asymmetric top (one 3-D particle, RATTLE): energy and angular momentum kept to
//! round-off, rotation matrix orthogonal to 1e-14.

use crate::dem_support;

use dem_support::*;
use solid_node::dem::ParticleId;

#[test]
fn torque_free_asymmetric_top_keeps_energy_and_angular_momentum() {
    let cfg = box_config(
        vec![0.0, 0.0, 0.0],
        vec![0.1, 0.2, 0.3],
        vec![1, 1, 1],
        1e6,
        0.0,
        1000.0,
    );
    let mut solid = build(&cfg, 3, 1);
    // Close to the unstable middle axis, so that the motion is far from a steady rotation.
    solid.set_angular_velocity(ParticleId(0), &[0.05, 3.0, 0.1]);
    let e0 = solid.energies().kinetic_rotation;
    let l0 = solid.momentum().angular;
    let l_norm = (l0[0] * l0[0] + l0[1] * l0[1] + l0[2] * l0[2]).sqrt();
    let dt = 0.01;
    let steps = if slow() { 100_000 } else { 10_000 };
    let (mut de, mut dl, mut orth): (f64, f64, f64) = (0.0, 0.0, 0.0);
    let mut min_wy: f64 = f64::INFINITY;
    for _ in 0..steps {
        let report = solid.step_free(dt);
        assert!(report.diagnostics.is_empty(), "{:?}", report.diagnostics);
        de = de.max((report.energies.kinetic_rotation - e0).abs() / e0);
        let l = solid.momentum().angular;
        dl = dl.max((0..3).map(|k| (l[k] - l0[k]).abs()).fold(0.0, f64::max) / l_norm);
        let q = solid.rotation_matrix(ParticleId(0));
        for i in 0..3 {
            for j in 0..3 {
                let dot: f64 = (0..3).map(|k| q[i][k] * q[j][k]).sum();
                orth = orth.max((dot - if i == j { 1.0 } else { 0.0 }).abs());
            }
        }
        min_wy = min_wy.min(solid.angular_velocity(ParticleId(0))[1].abs());
    }
    println!(
        "top, {steps} steps of {dt} s: max |dE|/E = {de:e}, max |dL|/|L| = {dl:e}, max |QQt - 1| = {orth:e}"
    );
    assert!(de < 1e-12, "energy error {de:e}");
    assert!(dl < 1e-12, "angular momentum error {dl:e}");
    assert!(orth < 1e-14, "orthogonality {orth:e}");
}
