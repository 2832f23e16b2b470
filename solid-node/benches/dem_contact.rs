//! Contact (issue 10): narrow-phase pairs evaluated per second on a fragmenting 3-D lattice
//! (1 and 2 threads), broad-phase cost against the particle count (10³ … 10⁵ spheres in a
//! heap), and the share of the step taken by contact in the fragmenting ring of paper 000
//! §4.2 (50 particles, steel, 1 % elongation at break), with and without `[solid.contact]`.
//!
//! Run: `cargo bench -p solid-node --no-default-features --bench dem_contact`. Throughputs are
//! pairs/s (`contact_eval`) and particles/s (`broad_phase`); per core = value / threads. The
//! contact share of a ring step is `1 − t(ring_step_no_contact) / t(ring_step_contact)`.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use protocol::scene::{BodyConfig, ContactConfig, FractureConfig, Motion, Shape, SolidConfig};
use solid_node::dem::contact::broad::{Grid, candidate_pairs};
use solid_node::dem::{ParticleId, Solid};

fn noise(seed: &mut u64) -> f64 {
    *seed ^= *seed << 13;
    *seed ^= *seed >> 7;
    *seed ^= *seed << 17;
    (*seed >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

fn config(shape: Shape, divisions: Vec<u32>, steel: bool, contact: bool) -> SolidConfig {
    SolidConfig {
        node: "real".into(),
        density: Some(if steel { 7860.0 } else { 1000.0 }),
        young: Some(if steel { 2.1e11 } else { 1e6 }),
        poisson: Some(if steel { 0.0 } else { 0.25 }),
        face_inertia: None,
        fracture: Some(FractureConfig {
            elongation_at_break: if steel { 0.01 } else { 0.002 },
        }),
        gravity: None,
        bodies: vec![BodyConfig {
            shape,
            divisions,
            motion: Motion::Free,
            links: None,
        }],
        constraints: vec![],
        init: vec![],
        prescribed: None,
        contact: contact.then(ContactConfig::default),
        walls: None,
    }
}

/// The fragmenting 12×6×4 lattice of the integration test `dem_contact`, 40 steps in.
fn lattice(threads: usize) -> Solid {
    let shape = Shape::Box {
        center: vec![0.0; 3],
        size: vec![1.2, 0.6, 0.4],
    };
    let mut solid =
        Solid::from_scene(&config(shape, vec![12, 6, 4], false, true), 3, threads).expect("builds");
    let mut seed = 777u64;
    for p in 0..solid.n_particles() {
        let v = [noise(&mut seed), noise(&mut seed), noise(&mut seed)];
        solid.set_velocity(ParticleId(p as u32), &v);
    }
    let dt = 0.5 * solid.max_dt(f64::INFINITY);
    for _ in 0..40 {
        solid.step_free(dt);
    }
    solid
}

fn contact_eval(c: &mut Criterion) {
    let mut group = c.benchmark_group("contact_eval");
    group.sample_size(10);
    group.measurement_time(std::time::Duration::from_secs(3));
    for threads in [1usize, 2] {
        let mut solid = lattice(threads);
        let (pairs, overlapping) = solid.evaluate_contact();
        eprintln!("lattice: {pairs} pairs examined, {overlapping} overlapping");
        group.throughput(Throughput::Elements(pairs as u64));
        group.bench_function(format!("pairs_{threads}_threads"), |b| {
            b.iter(|| std::hint::black_box(solid.evaluate_contact()))
        });
    }
    group.finish();
}

fn broad_phase(c: &mut Criterion) {
    let mut group = c.benchmark_group("broad_phase");
    group.sample_size(10);
    group.measurement_time(std::time::Duration::from_secs(3));
    for n in [1_000usize, 10_000, 100_000] {
        // A heap: spheres of radius 0.05–0.1, about 4 overlapping neighbours each.
        let side = (n as f64).cbrt() * 0.075;
        let mut seed = 42u64;
        let centers: Vec<[f64; 3]> = (0..n)
            .map(|_| {
                [
                    side * noise(&mut seed),
                    side * noise(&mut seed),
                    side * noise(&mut seed),
                ]
            })
            .collect();
        let radii: Vec<f64> = (0..n).map(|_| 0.075 + 0.025 * noise(&mut seed)).collect();
        let mut grid = Grid::default();
        let mut pairs = Vec::new();
        candidate_pairs(3, &centers, &radii, &mut grid, &mut pairs);
        eprintln!("heap of {n}: {} candidate pairs", pairs.len());
        group.throughput(Throughput::Elements(n as u64));
        group.bench_function(format!("heap_{n}"), |b| {
            b.iter(|| {
                candidate_pairs(3, &centers, &radii, &mut grid, &mut pairs);
                std::hint::black_box(pairs.len())
            })
        });
    }
    group.finish();
}

/// The ring of paper 000 §4.2, kicked outward with seeded noise and run until 10 of its 50
/// links broke.
fn ring(contact: bool) -> (Solid, f64) {
    let shape = Shape::Ring {
        center: vec![15.0, 7.5],
        inner_radius: 5.0,
        outer_radius: 5.2,
    };
    let mut solid =
        Solid::from_scene(&config(shape, vec![50], true, contact), 2, 1).expect("builds");
    let mut seed = 2026u64;
    for p in 0..solid.n_particles() {
        let x = solid.position(ParticleId(p as u32));
        let (dx, dy) = (x[0] - 15.0, x[1] - 7.5);
        let r = (dx * dx + dy * dy).sqrt();
        // Radial 100 ± 60 m/s (hoop strain up to ≈ v/c = 3 %), tangential ± 30 m/s.
        let speed = 100.0 + 60.0 * noise(&mut seed);
        let swirl = 30.0 * noise(&mut seed);
        let (ex, ey) = (dx / r, dy / r);
        solid.set_velocity(
            ParticleId(p as u32),
            &[speed * ex - swirl * ey, speed * ey + swirl * ex],
        );
    }
    let dt = 0.5 * solid.max_dt(f64::INFINITY);
    // Until a fifth of the links broke, while the fragments still touch.
    let (mut broken, mut steps) = (0, 0);
    while broken < 10 && steps < 100_000 {
        broken += solid.step_free(dt).broken_links.len();
        steps += 1;
    }
    eprintln!(
        "ring (contact {contact}): {broken} links broken after {steps} steps of {dt:.3e} s, \
         (examined, overlapping) pairs {:?}",
        solid.evaluate_contact()
    );
    (solid, dt)
}

fn ring_share(c: &mut Criterion) {
    let mut group = c.benchmark_group("ring");
    group.sample_size(10);
    group.measurement_time(std::time::Duration::from_secs(3));
    for contact in [false, true] {
        let (solid, dt) = ring(contact);
        let name = if contact {
            "ring_step_contact"
        } else {
            "ring_step_no_contact"
        };
        // Each iteration runs 100 steps from the same fragmented state (restore not timed).
        let bytes = solid.to_checkpoint();
        let mut solid = solid;
        group.throughput(Throughput::Elements(100));
        group.bench_function(name, |b| {
            b.iter_custom(|iters| {
                let mut total = std::time::Duration::ZERO;
                for _ in 0..iters {
                    solid.restore_checkpoint(&bytes).expect("restores");
                    let start = std::time::Instant::now();
                    for _ in 0..100 {
                        std::hint::black_box(solid.step_free(dt));
                    }
                    total += start.elapsed();
                }
                total
            })
        });
    }
    group.finish();
}

criterion_group!(benches, contact_eval, broad_phase, ring_share);
criterion_main!(benches);
