//! Fracture by relative elongation (000 §3.1): a bar pulled apart breaks at the set elongation;
//! breaking links keeps momentum to round-off, counts the link energy as dissipated, wets the
//! crack faces and bumps the wet-surface revision.

use crate::dem_support;

use dem_support::*;
use protocol::scene::Motion;
use solid_node::dem::{ParticleId, Solid, WetSurfaceData};

/// Every directed edge of the wet elements has exactly one reverse (3-D), or every vertex
/// starts and ends one wet segment (2-D).
fn assert_closed(wet: &WetSurfaceData) {
    let dim = wet.dim;
    let mut edges: Vec<(u32, u32)> = Vec::new();
    for e in 0..wet.n_elements() {
        if !wet.wet[e] {
            continue;
        }
        let el = &wet.elements[e * dim..(e + 1) * dim];
        for k in 0..dim {
            if dim == 2 && k == 1 {
                break;
            }
            edges.push((el[k], el[(k + 1) % dim]));
        }
    }
    let mut sorted = edges.clone();
    sorted.sort_unstable();
    for w in sorted.windows(2) {
        assert_ne!(w[0], w[1], "edge used twice in the same direction");
    }
    for &(a, b) in &edges {
        assert!(
            sorted.binary_search(&(b, a)).is_ok() || dim == 2,
            "edge ({a}, {b}) has no reverse"
        );
    }
    if dim == 2 {
        let mut starts: Vec<u32> = edges.iter().map(|e| e.0).collect();
        let mut ends: Vec<u32> = edges.iter().map(|e| e.1).collect();
        starts.sort_unstable();
        ends.sort_unstable();
        assert_eq!(starts, ends, "open polyline");
    }
}

fn bar(dim: usize, n: u32, elongation: f64) -> protocol::scene::SolidConfig {
    let mut cfg = if dim == 3 {
        box_config(
            vec![0.0; 3],
            vec![0.1 * n as f64, 0.1, 0.1],
            vec![n, 1, 1],
            1e7,
            0.0,
            1000.0,
        )
    } else {
        box_config(
            vec![0.0; 2],
            vec![0.1 * n as f64, 0.1],
            vec![n, 1],
            1e7,
            0.0,
            1000.0,
        )
    };
    with_fracture(&mut cfg, elongation);
    cfg
}

#[test]
fn bar_pulled_apart_breaks_at_the_set_elongation() {
    for dim in [2usize, 3] {
        let n = 6;
        let limit = 0.01;
        let mut cfg = bar(dim, n, limit);
        let half = 0.05 * n as f64;
        let (lo, hi) = (vec![-1.0; dim], vec![1.0; dim]);
        let mut left_hi = hi.clone();
        left_hi[0] = -half + 0.06;
        let mut right_lo = lo.clone();
        right_lo[0] = half - 0.06;
        constrain(&mut cfg, lo.clone(), left_hi, Motion::Fixed);
        let mut pull = vec![0.0; dim];
        pull[0] = 0.05; // m/s, slow against c = 100 m/s
        constrain(&mut cfg, right_lo, hi.clone(), Motion::Velocity(pull));
        let mut solid = build(&cfg, dim, 1);
        let dt = 0.5 * solid.max_dt(f64::INFINITY);
        let rev0 = solid.wet_surface().revision;
        let wet0 = solid.wet_surface().wet.iter().filter(|w| **w).count();
        let mut broke = None;
        for _ in 0..200_000 {
            let report = solid.step_free(dt);
            assert!(report.diagnostics.is_empty(), "{:?}", report.diagnostics);
            if let Some(b) = report.broken_links.first() {
                broke = Some((b.clone(), report.clone()));
                break;
            }
        }
        let (b, report) = broke.expect("the bar breaks");
        // The elongation grows by at most the pull speed × dt / D⁰ per step (plus waves).
        let step_growth = 0.05 * dt / 0.1;
        println!(
            "{dim}-D: link {:?} broke at elongation {:.6} (limit {limit}), t = {:.4} s, dissipated {:.3e} J",
            b.link, b.elongation, report.time, report.energies.dissipated
        );
        assert!(b.elongation > limit && b.elongation < limit + 10.0 * step_growth + 1e-4 * limit);
        // Normal stress (000 Fig. 16 quantity): E times the link strain, positive in tension.
        let sigma_max = solid.normal_stress().into_iter().fold(f64::MIN, f64::max);
        println!(
            "{dim}-D: max normal stress {sigma_max:.4e} Pa vs E x limit = {:.4e} Pa",
            1e7 * limit
        );
        assert!(
            (sigma_max / (1e7 * limit) - 1.0).abs() < 0.2,
            "sigma_n {sigma_max}"
        );
        assert!(solid.is_broken(b.link));
        assert!(report.energies.dissipated > 0.0);
        assert_eq!(solid.wet_surface().revision, rev0 + 1);
        let wet1 = solid.wet_surface().wet.iter().filter(|w| **w).count();
        assert!(wet1 > wet0, "crack faces become wet");
        assert_closed(solid.wet_surface());
    }
}

fn free_bar_flying_apart(dim: usize, threads: usize) -> Solid {
    let n = 8;
    let cfg = bar(dim, n, 0.002);
    let mut solid = build(&cfg, dim, threads);
    let mut noise = Noise(99);
    for p in 0..solid.n_particles() {
        let x = solid.model().particles[p].x0.x;
        let mut v: Vec<f64> = (0..dim).map(|_| 0.2 * noise.next()).collect();
        v[0] += if x > 0.0 { 2.0 } else { -2.0 };
        solid.set_velocity(ParticleId(p as u32), &v);
        let w: Vec<f64> = (0..if dim == 3 { 3 } else { 1 })
            .map(|_| 2.0 * noise.next())
            .collect();
        solid.set_angular_velocity(ParticleId(p as u32), &w);
    }
    solid
}

#[test]
fn momentum_is_conserved_to_round_off_when_links_break() {
    for dim in [2usize, 3] {
        let mut solid = free_bar_flying_apart(dim, 1);
        let m0 = solid.momentum();
        let e0 = solid.energies().total();
        let scale: f64 = (0..solid.n_particles())
            .map(|p| {
                let v = solid.velocity(ParticleId(p as u32));
                solid.model().particles[p].mass * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
            })
            .sum();
        let dt = 0.2 * solid.max_dt(f64::INFINITY);
        let mut n_broken = 0;
        let (mut dp, mut dl): (f64, f64) = (0.0, 0.0);
        let mut de: f64 = 0.0;
        for _ in 0..4000 {
            let report = solid.step_free(dt);
            assert!(report.diagnostics.is_empty(), "{:?}", report.diagnostics);
            n_broken += report.broken_links.len();
            let m = solid.momentum();
            for k in 0..3 {
                dp = dp.max((m.linear[k] - m0.linear[k]).abs());
                dl = dl.max((m.angular[k] - m0.angular[k]).abs());
            }
            de = de.max((report.energies.total() - e0).abs() / e0);
        }
        println!(
            "{dim}-D: {n_broken} links broken, max |dP| = {dp:.2e} (scale {scale:.2e}), max |dL| = {dl:.2e}, max |dE|/E = {de:.2e}"
        );
        assert!(n_broken >= 1, "links must break");
        assert!(dp < 1e-13 * scale, "linear momentum drift {dp}");
        assert!(dl < 1e-12 * scale, "angular momentum drift {dl}");
        // Measured 2.6e-5 (2-D), 3.7e-5 (3-D): Verlet's own fluctuation. Counting the broken
        // links' energy at n+1 instead (the kinetic energy never paid for it) gave 5.0e-3.
        assert!(de < 2e-4, "energy with dissipation accounted {de}");
        assert_closed(solid.wet_surface());
    }
}

/// The 2-D scenario of 000 §4 in miniature: a steel ring (50 particles, ν = 0, elongation at
/// break 1%) under an outward radial load breaks into fragments; every fragment's wet polyline
/// stays closed and the revision counts the fracture events.
#[test]
fn ring_under_internal_load_fragments_with_closed_wet_surface() {
    use protocol::scene::{BodyConfig, Shape};
    let mut cfg = box_config(
        vec![0.0, 0.0],
        vec![1.0, 1.0],
        vec![1, 1],
        210e9,
        0.0,
        7860.0,
    );
    cfg.bodies = vec![BodyConfig {
        shape: Shape::Ring {
            center: vec![0.0, 0.0],
            inner_radius: 0.9,
            outer_radius: 1.0,
        },
        divisions: vec![50],
        motion: Motion::Free,
        links: None,
    }];
    with_fracture(&mut cfg, 0.01);
    let mut solid = build(&cfg, 2, 1);
    let n = solid.n_particles();
    let mut force = vec![0.0; 2 * n];
    let mut noise = Noise(3);
    for p in 0..n {
        let x = solid.position(ParticleId(p as u32));
        let r = (x[0] * x[0] + x[1] * x[1]).sqrt();
        // 300 MPa on the inner face (per unit depth; static hoop strain 1.3%), 10% scatter.
        let f = 3e8 * 0.9 * 2.0 * std::f64::consts::PI / n as f64 * (1.0 + 0.1 * noise.next());
        force[2 * p] = f * x[0] / r;
        force[2 * p + 1] = f * x[1] / r;
    }
    let torque = vec![0.0; n];
    let dt = 0.5 * solid.max_dt(0.01);
    let mut revisions = 0;
    let mut broken = 0;
    for _ in 0..2000 {
        let report = solid.step(dt, &force, &torque);
        assert!(report.diagnostics.is_empty(), "{:?}", report.diagnostics);
        if !report.broken_links.is_empty() {
            revisions += 1;
            broken += report.broken_links.len();
        }
    }
    println!(
        "ring: {broken} links broken in {revisions} events, revision {}",
        solid.wet_surface().revision
    );
    assert!(broken >= 2, "the ring fragments");
    assert_eq!(solid.wet_surface().revision, revisions as u64);
    assert_closed(solid.wet_surface());
    let e = solid.energies();
    assert!(e.dissipated > 0.0);
}
