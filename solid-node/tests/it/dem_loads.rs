//! External loads held over the step (003 eq. (14)–(17)): with a constant force F and torque τ
//! (space frame) on a free body, the momenta change by exactly F t and τ t, and the work of F
//! equals the change of translational kinetic energy (Verlet is exact for a constant force).

use crate::dem_support;

use dem_support::*;
use solid_node::dem::ParticleId;

#[test]
fn held_loads_change_momentum_by_their_impulse() {
    for dim in [2usize, 3] {
        let cfg = if dim == 3 {
            box_config(
                vec![0.0; 3],
                vec![0.1, 0.2, 0.3],
                vec![1, 1, 1],
                1e6,
                0.0,
                1000.0,
            )
        } else {
            box_config(vec![0.0; 2], vec![0.1, 0.2], vec![1, 1], 1e6, 0.0, 1000.0)
        };
        let mut solid = build(&cfg, dim, 1);
        let w0: Vec<f64> = if dim == 3 {
            vec![0.3, -1.0, 2.0]
        } else {
            vec![1.5]
        };
        solid.set_angular_velocity(ParticleId(0), &w0);
        let force: Vec<f64> = [3.0, -2.0, 1.0][..dim].to_vec();
        let torque: Vec<f64> = if dim == 3 {
            vec![0.2, 0.1, -0.3]
        } else {
            vec![0.25]
        };
        let p0 = solid.momentum();
        let e0 = solid.energies();
        let dt = 1e-3;
        let steps = 2000;
        for _ in 0..steps {
            let report = solid.step(dt, &force, &torque);
            assert!(report.diagnostics.is_empty(), "{:?}", report.diagnostics);
        }
        let t = dt * steps as f64;
        let p1 = solid.momentum();
        for (k, f_k) in force.iter().enumerate() {
            let expected = p0.linear[k] + f_k * t;
            assert!((p1.linear[k] - expected).abs() < 1e-12 * expected.abs().max(1.0));
        }
        let rot_axes: Vec<usize> = if dim == 3 { vec![0, 1, 2] } else { vec![2] };
        for (k, &axis) in rot_axes.iter().enumerate() {
            // L about the origin includes X × mV, whose change is the moment of F about the
            // origin; subtract it to compare the spin with τ t.
            let x = solid.position(ParticleId(0));
            let v = solid.velocity(ParticleId(0));
            let m = solid.model().particles[0].mass;
            let orbital = match axis {
                0 => m * (x[1] * v[2] - x[2] * v[1]),
                1 => m * (x[2] * v[0] - x[0] * v[2]),
                _ => m * (x[0] * v[1] - x[1] * v[0]),
            };
            let spin = p1.angular[axis] - orbital;
            let expected = p0.angular[axis] + torque[k] * t;
            assert!(
                (spin - expected).abs() < 1e-11 * expected.abs().max(1.0),
                "{dim}-D axis {axis}: {spin} vs {expected}"
            );
        }
        // Work of the held loads against the kinetic energy gained: exact for the translation
        // and for the 2-D rotation (kick–drift–kick with a constant load), second order for
        // the 3-D rotation (RATTLE with a space-fixed torque).
        let e1 = solid.energies();
        let d_kin = e1.kinetic_translation - e0.kinetic_translation;
        let d_total = d_kin + e1.kinetic_rotation - e0.kinetic_rotation;
        let tol = if dim == 2 { 1e-9 } else { 1e-4 };
        assert!(
            (e1.external_work - d_total).abs() <= tol * d_total.abs(),
            "{dim}-D: work {} vs kinetic energy gained {d_total}",
            e1.external_work
        );
        println!(
            "{dim}-D: dKE_trans = {d_kin:.6e} J, external work {:.6e} J",
            e1.external_work
        );
    }
}
