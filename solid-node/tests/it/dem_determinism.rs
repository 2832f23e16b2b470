//! Same bits for 1 and 2 threads (fixed partition, serial reductions), and checkpoint → restore
//! → continue gives the same bits as running straight through.

use crate::dem_support;

use dem_support::*;
use solid_node::dem::{CheckpointError, ParticleId, Solid};

/// Big enough that links and particles span several rayon chunks (256 items) and reach the
/// pool at all (2048 items: fewer run serially).
fn scene() -> protocol::scene::SolidConfig {
    let mut cfg = box_config(
        vec![0.0; 3],
        vec![1.6, 1.6, 0.8],
        vec![16, 16, 8],
        1e6,
        0.25,
        1000.0,
    );
    cfg.gravity = Some(vec![0.0, 0.0, -9.81]);
    with_fracture(&mut cfg, 0.002);
    cfg
}

fn kicked(threads: usize) -> Solid {
    let mut solid = build(&scene(), 3, threads);
    let mut noise = Noise(12345);
    for p in 0..solid.n_particles() {
        let v = [0.5 * noise.next(), 0.5 * noise.next(), 0.5 * noise.next()];
        solid.set_velocity(ParticleId(p as u32), &v);
        let w = [5.0 * noise.next(), 5.0 * noise.next(), 5.0 * noise.next()];
        solid.set_angular_velocity(ParticleId(p as u32), &w);
    }
    solid
}

fn bits(solid: &Solid) -> Vec<u64> {
    let mut out = Vec::new();
    for p in 0..solid.n_particles() {
        let id = ParticleId(p as u32);
        out.extend(solid.position(id).iter().map(|v| v.to_bits()));
        out.extend(solid.velocity(id).iter().map(|v| v.to_bits()));
        out.extend(solid.orientation(id).iter().map(|v| v.to_bits()));
        out.extend(solid.angular_velocity(id).iter().map(|v| v.to_bits()));
    }
    let e = solid.energies();
    out.extend(
        [e.elastic, e.dissipated, e.kinetic_rotation]
            .iter()
            .map(|v| v.to_bits()),
    );
    out.extend(solid.wet_surface().vertices.iter().map(|v| v.to_bits()));
    out
}

fn advance(solid: &mut Solid, steps: usize, dt: f64) -> usize {
    let n = solid.n_particles();
    let force: Vec<f64> = (0..3 * n).map(|k| ((k % 7) as f64 - 3.0) * 0.1).collect();
    let torque: Vec<f64> = (0..3 * n).map(|k| ((k % 5) as f64 - 2.0) * 0.01).collect();
    let mut broken = 0;
    for _ in 0..steps {
        solid.begin_step(dt);
        // Two fixed-point iterations with different loads, then the final one.
        solid.trial(&vec![0.0; 3 * n], &vec![0.0; 3 * n]);
        solid.trial(&force, &torque);
        let report = solid.commit();
        broken += report.broken_links.len();
    }
    broken
}

#[test]
fn one_and_two_threads_give_the_same_bits() {
    let mut one = kicked(1);
    let mut two = kicked(2);
    assert!(one.model().links.len() > 512);
    let dt = 0.5 * one.max_dt(f64::INFINITY);
    let b1 = advance(&mut one, 30, dt);
    let b2 = advance(&mut two, 30, dt);
    assert!(b1 > 0, "fracture exercised");
    assert_eq!(b1, b2);
    assert_eq!(bits(&one), bits(&two));
}

#[test]
fn checkpoint_restore_continues_bit_identically() {
    let mut straight = kicked(1);
    let dt = 0.5 * straight.max_dt(f64::INFINITY);
    advance(&mut straight, 10, dt);
    let bytes = straight.to_checkpoint();
    advance(&mut straight, 10, dt);

    let mut restored = build(&scene(), 3, 2);
    restored.restore_checkpoint(&bytes).expect("restores");
    advance(&mut restored, 10, dt);
    assert_eq!(bits(&straight), bits(&restored));
    assert_eq!(straight.step_count(), restored.step_count());

    let other = box_config(
        vec![0.0; 3],
        vec![0.2, 0.1, 0.1],
        vec![2, 1, 1],
        1e6,
        0.0,
        1000.0,
    );
    let mut wrong = build(&other, 3, 1);
    let err = wrong.restore_checkpoint(&bytes).unwrap_err();
    assert!(matches!(err, CheckpointError::Size { .. }), "{err:?}");
    assert!(err.to_string().contains("particles"), "{err}");
    assert!(matches!(
        wrong.restore_checkpoint(&[1, 2, 3]),
        Err(CheckpointError::Decode(_))
    ));
}

#[test]
fn trials_do_not_commit_anything() {
    let mut a = kicked(1);
    let mut b = kicked(1);
    let n = a.n_particles();
    let dt = 0.5 * a.max_dt(f64::INFINITY);
    let force: Vec<f64> = (0..3 * n).map(|k| (k % 3) as f64).collect();
    let torque = vec![0.01; 3 * n];
    a.begin_step(dt);
    a.trial(&vec![5.0; 3 * n], &vec![-1.0; 3 * n]);
    a.trial(&vec![f64::NAN; 3 * n], &vec![f64::NAN; 3 * n]);
    a.trial(&force, &torque);
    a.commit();
    b.begin_step(dt);
    b.trial(&force, &torque);
    b.commit();
    assert_eq!(bits(&a), bits(&b));
}
