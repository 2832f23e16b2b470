//! The lattice both link benchmarks measure: a 3-D box of 40×20×10 particles (22 k links),
//! ν ≠ 0, a few free steps from seeded velocities so that every link is stretched.

use protocol::scene::{BodyConfig, Motion, Shape, SolidConfig};
use solid_node::dem::{ParticleId, Solid};

/// The lattice, built for `threads` threads.
pub(crate) fn lattice(threads: usize) -> Solid {
    let cfg = SolidConfig {
        node: "real".into(),
        density: Some(1000.0),
        young: Some(1e8),
        poisson: Some(0.3),
        face_inertia: None,
        fracture: None,
        gravity: None,
        bodies: vec![BodyConfig {
            shape: Shape::Box {
                center: vec![0.0, 0.0, 0.0],
                size: vec![4.0, 2.0, 1.0],
            },
            divisions: vec![40, 20, 10],
            motion: Motion::Free,
            links: None,
        }],
        constraints: vec![],
        init: vec![],
        prescribed: None,
        contact: None,
        walls: None,
    };
    let mut solid = Solid::from_scene(&cfg, 3, threads).expect("bench scene builds");
    // Seeded deformation: a few steps from seeded velocities.
    let mut seed = 0x1234_5678_9abc_def0u64;
    let mut next = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    };
    for p in 0..solid.n_particles() {
        let v = [0.1 * next(), 0.1 * next(), 0.1 * next()];
        solid.set_velocity(ParticleId(p as u32), &v);
    }
    let dt = 0.5 * solid.max_dt(f64::INFINITY);
    for _ in 0..3 {
        solid.step_free(dt);
    }
    solid
}
