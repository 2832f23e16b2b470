//! Unit tests of the DEM kernels: geometry, link-force gradients, RATTLE, wet surface.

use nalgebra::Vector3;

use crate::dem::geometry::{face_moments, face_moments_with, polyhedron_mass};

#[test]
fn unit_cube_mass_properties() {
    let v: Vec<Vector3<f64>> = (0..8)
        .map(|c| Vector3::new((c & 1) as f64, ((c >> 1) & 1) as f64, (c >> 2) as f64))
        .collect();
    let faces = vec![
        vec![0, 4, 6, 2],
        vec![1, 3, 7, 5],
        vec![0, 1, 5, 4],
        vec![2, 6, 7, 3],
        vec![0, 2, 3, 1],
        vec![4, 5, 7, 6],
    ];
    let m = polyhedron_mass(&v, &faces);
    assert!((m.volume - 1.0).abs() < 1e-14);
    assert!((m.centroid - Vector3::new(0.5, 0.5, 0.5)).norm() < 1e-14);
    assert!((m.second_moment[(0, 0)] - 1.0 / 12.0).abs() < 1e-14);
    assert!(m.second_moment[(0, 1)].abs() < 1e-14);
    let f = face_moments(&faces[1].iter().map(|&i| v[i as usize]).collect::<Vec<_>>());
    assert!((f.area - 1.0).abs() < 1e-14);
    assert!((f.normal - Vector3::x()).norm() < 1e-14);
    assert!((f.i_s - 1.0 / 12.0).abs() < 1e-14 && (f.i_t - 1.0 / 12.0).abs() < 1e-14);
}

/// The unweighted reading of a square of side a: each fan triangle (G, a, b) adds
/// (a_s² + a_s b_s + b_s²)/12, so I^s = 2·(3a²/4)/12 + 2·(a²/4)/12 = a²/6 against the exact
/// a⁴/12: a ratio 2/a² [m⁻²]. Area, centroid and normal are the exact ones.
#[test]
fn unweighted_face_moments_of_a_square_and_a_triangle() {
    let a = 0.2857;
    let square = [
        Vector3::new(0.0, 0.0, 0.0),
        Vector3::new(a, 0.0, 0.0),
        Vector3::new(a, 0.0, a),
        Vector3::new(0.0, 0.0, a),
    ];
    let exact = face_moments(&square);
    let legacy = face_moments_with(&square, FaceInertia::Unweighted);
    assert!((exact.i_s - a.powi(4) / 12.0).abs() < 1e-15);
    assert!((legacy.i_s - a * a / 6.0).abs() < 1e-15 && (legacy.i_t - a * a / 6.0).abs() < 1e-15);
    assert!((legacy.i_s / exact.i_s - 2.0 / (a * a)).abs() < 1e-12);
    assert_eq!(legacy.area, exact.area);
    assert_eq!(legacy.centroid, exact.centroid);
    assert_eq!(legacy.normal, exact.normal);
    // A right isosceles triangle: about each principal axis u, the sum over its three fan
    // triangles of (p² + pq + q²)/12, p and q the edge ends' coordinates along u from G.
    let l = 0.5;
    let tri = [
        Vector3::new(0.0, 0.0, 0.0),
        Vector3::new(l, 0.0, 0.0),
        Vector3::new(0.0, l, 0.0),
    ];
    let g = (tri[0] + tri[1] + tri[2]) / 3.0;
    let along = |axis: &Vector3<f64>| {
        (0..3)
            .map(|k| {
                let (p, q) = ((tri[k] - g).dot(axis), (tri[(k + 1) % 3] - g).dot(axis));
                (p * p + p * q + q * q) / 12.0
            })
            .sum::<f64>()
    };
    let legacy = face_moments_with(&tri, FaceInertia::Unweighted);
    assert!((legacy.i_s - along(&legacy.s)).abs() < 1e-15);
    assert!((legacy.i_t - along(&legacy.t)).abs() < 1e-15);
    // Its principal axes are those of the exact moments (the triangle's symmetry axes).
    let exact = face_moments(&tri);
    assert!(legacy.s.cross(&exact.s).norm() < 1e-12 || legacy.s.cross(&exact.t).norm() < 1e-12);
}

/// A column of two cubes of side a: the unweighted face inertia multiplies the flexion and
/// torsion stiffness of their link by exactly 2/a², and leaves the traction one alone.
#[test]
fn unweighted_face_inertia_scales_only_the_link_torques() {
    let a = 0.2857;
    let column = |inertia: Option<FaceInertia>| {
        let mut cfg = box_config(3, vec![1, 2, 1], 0.0);
        cfg.bodies[0].shape = Shape::Box {
            center: vec![0.0, 0.0, 0.0],
            size: vec![a, 2.0 * a, a],
        };
        cfg.face_inertia = inertia;
        let solid = Solid::from_scene(&cfg, 3, 1).unwrap();
        solid.model().links[0].clone()
    };
    let (exact, legacy) = (column(None), column(Some(FaceInertia::Unweighted)));
    assert_eq!(legacy.k_shear, exact.k_shear);
    for k in 0..3 {
        let ratio = legacy.flex[k] / exact.flex[k];
        assert!(
            (ratio - 2.0 / (a * a)).abs() < 1e-10,
            "flex[{k}] ratio {ratio}"
        );
    }
    let mut cfg = box_config(2, vec![2, 1], 0.0);
    cfg.face_inertia = Some(FaceInertia::Unweighted);
    let err = Solid::from_scene(&cfg, 2, 1).err().unwrap();
    assert!(
        matches!(err, SetupError::UnweightedFaceInertiaIn2d),
        "{err:?}"
    );
    assert!(err.to_string().contains("solid.face_inertia"), "{err}");
}

use protocol::scene::{BodyConfig, FaceInertia, Motion, Shape, SolidConfig};

use crate::dem::rattle::dmv_drift;
use crate::dem::{ParticleId, SetupError, Solid};

fn box_config(dim: usize, divisions: Vec<u32>, poisson: f64) -> SolidConfig {
    let (center, size) = if dim == 3 {
        (vec![0.0, 0.0, 0.0], vec![0.3, 0.2, 0.1])
    } else {
        (vec![0.0, 0.0], vec![0.3, 0.2])
    };
    SolidConfig {
        node: "real".into(),
        density: Some(1000.0),
        young: Some(1e6),
        poisson: Some(poisson),
        face_inertia: None,
        fracture: None,
        gravity: None,
        bodies: vec![BodyConfig {
            shape: Shape::Box { center, size },
            divisions,
            motion: Motion::Free,
            links: None,
        }],
        constraints: vec![],
        init: vec![],
        prescribed: None,
        contact: None,
        walls: None,
    }
}

/// Deterministic pseudo-random numbers in [-1, 1) (xorshift, seeded).
fn rng(seed: &mut u64) -> f64 {
    *seed ^= *seed << 13;
    *seed ^= *seed >> 7;
    *seed ^= *seed << 17;
    (*seed >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

fn rotate_particle(solid: &mut Solid, dim: usize, p: usize, axis: usize, angle: f64) {
    let (_, rot) = solid.pose_mut_for_tests();
    if dim == 2 {
        rot[p][0] += angle;
    } else {
        let r = rot[p];
        let q = nalgebra::UnitQuaternion::new_unchecked(nalgebra::Quaternion::new(
            r[0], r[1], r[2], r[3],
        ));
        let mut ax = Vector3::zeros();
        ax[axis] = 1.0;
        let dq = nalgebra::UnitQuaternion::from_scaled_axis(ax * angle);
        let qn = dq * q;
        rot[p] = [qn.w, qn.i, qn.j, qn.k];
    }
}

/// Forces and torques are the exact negative gradient of the elastic energy (eq. (29)–(30)
/// read as in `link_force.rs`), ν ≠ 0 included, away from the rest state.
fn check_gradient(dim: usize, divisions: Vec<u32>) {
    check_gradient_of(&box_config(dim, divisions, 0.3), dim);
}

fn check_gradient_of(cfg: &SolidConfig, dim: usize) {
    let mut solid = Solid::from_scene(cfg, dim, 1).unwrap();
    let mut seed = 0x9E37_79B9_7F4A_7C15u64;
    let n = solid.n_particles();
    for p in 0..n {
        for a in 0..dim {
            let d = 0.004 * rng(&mut seed);
            solid.pose_mut_for_tests().0[p][a] += d;
        }
        for a in 0..(if dim == 3 { 3 } else { 1 }) {
            let ang = 0.05 * rng(&mut seed);
            rotate_particle(&mut solid, dim, p, if dim == 3 { a } else { 2 }, ang);
        }
    }
    let e0 = solid.recompute_for_tests();
    assert!(e0 > 0.0);
    // NOTE: the FD error is round-off, ε E / h ≈ 1e-16 · e0 / 1e-6.
    let h = 1e-6;
    let mut worst: f64 = 0.0;
    let mut scale: f64 = 0.0;
    for p in 0..n {
        // Forces at the unperturbed configuration.
        solid.recompute_for_tests();
        let f = solid.internal_force(ParticleId(p as u32));
        let t = solid.internal_torque(ParticleId(p as u32));
        for (a, f_a) in f.iter().enumerate().take(dim) {
            solid.pose_mut_for_tests().0[p][a] += h;
            let ep = solid.recompute_for_tests();
            solid.pose_mut_for_tests().0[p][a] -= 2.0 * h;
            let em = solid.recompute_for_tests();
            solid.pose_mut_for_tests().0[p][a] += h;
            let fd = -(ep - em) / (2.0 * h);
            worst = worst.max((fd - f_a).abs());
            scale = scale.max(f_a.abs());
        }
        let axes: Vec<usize> = if dim == 3 { vec![0, 1, 2] } else { vec![2] };
        for a in axes {
            rotate_particle(&mut solid, dim, p, a, h);
            let ep = solid.recompute_for_tests();
            rotate_particle(&mut solid, dim, p, a, -2.0 * h);
            let em = solid.recompute_for_tests();
            rotate_particle(&mut solid, dim, p, a, h);
            let fd = -(ep - em) / (2.0 * h);
            worst = worst.max((fd - t[a]).abs() / 0.1);
            scale = scale.max(t[a].abs() / 0.1);
        }
    }
    solid.recompute_for_tests();
    assert!(
        worst < 1e-6 * scale,
        "gradient mismatch {worst:e} vs scale {scale:e}"
    );
}

#[test]
fn link_forces_are_the_energy_gradient_3d() {
    check_gradient(3, vec![3, 2, 2]);
}

#[test]
fn link_forces_are_the_energy_gradient_2d() {
    check_gradient(2, vec![3, 2]);
}

/// Spring links (`links = { spring, rotation }`): forces and torques are the gradient of
/// `½ k (|d| − D⁰)² + c (1 − cos φ)`, with ν ≠ 0 (no volumetric part may leak in).
#[test]
fn spring_link_forces_are_the_energy_gradient() {
    for (dim, divisions) in [(2, vec![3, 2]), (3, vec![3, 2, 2])] {
        let mut cfg = box_config(dim, divisions, 0.3);
        cfg.bodies[0].links = Some(protocol::scene::LinksConfig {
            spring: 3e4,
            rotation: 20.0,
        });
        check_gradient_of(&cfg, dim);
    }
}

#[test]
fn dmv_increment_is_orthogonal_and_solves_the_map() {
    let inertia = [0.345, 0.653, 1.0];
    let m = Vector3::new(1.1f64.cos(), 0.2, 1.1f64.sin());
    let h = 0.1;
    let drift = dmv_drift(&m, &inertia, h);
    let om = drift.increment.to_rotation_matrix().into_inner();
    let orth = (om.transpose() * om - nalgebra::Matrix3::identity())
        .abs()
        .max();
    assert!(orth < 1e-15, "orthogonality {orth:e}");
    let d = nalgebra::Matrix3::from_diagonal(&Vector3::new(
        0.5 * (inertia[1] + inertia[2] - inertia[0]),
        0.5 * (inertia[2] + inertia[0] - inertia[1]),
        0.5 * (inertia[0] + inertia[1] - inertia[2]),
    ));
    let lhs = om * d - d * om.transpose();
    let rhs = m.cross_matrix() * h;
    assert!((lhs - rhs).abs().max() < 1e-15);
}

#[test]
fn forces_and_energy_vanish_at_rest() {
    for dim in [2usize, 3] {
        let divisions = if dim == 3 { vec![3, 2, 2] } else { vec![3, 2] };
        let mut solid = Solid::from_scene(&box_config(dim, divisions, 0.3), dim, 1).unwrap();
        let e = solid.recompute_for_tests();
        assert!(e.abs() < 1e-20, "rest energy {e}");
        for p in 0..solid.n_particles() {
            let f = solid.internal_force(ParticleId(p as u32));
            let t = solid.internal_torque(ParticleId(p as u32));
            assert!(
                f.iter().chain(t.iter()).all(|c| c.abs() < 1e-9),
                "{f:?} {t:?}"
            );
        }
    }
}

mod properties {
    //! Property tests: mass properties of rotated boxes through the convex hull are those of
    //! the box, whatever the rotation.

    use nalgebra::{Rotation3, Vector3};
    use proptest::prelude::*;

    use crate::dem::geometry::{convex_hull_faces, inertia_from_second_moment, polyhedron_mass};

    proptest! {
        #![proptest_config(ProptestConfig {
            cases: 64,
            rng_seed: proptest::test_runner::RngSeed::Fixed(0),
            failure_persistence: None,
            ..ProptestConfig::default()
        })]
        #[test]
        fn rotated_box_mass_properties(
            a in 0.1f64..2.0, b in 0.1f64..2.0, c in 0.1f64..2.0,
            roll in -3.0f64..3.0, pitch in -1.5f64..1.5, yaw in -3.0f64..3.0,
            tx in -5.0f64..5.0, ty in -5.0f64..5.0, tz in -5.0f64..5.0,
        ) {
            let rot = Rotation3::from_euler_angles(roll, pitch, yaw);
            let shift = Vector3::new(tx, ty, tz);
            let pts: Vec<Vector3<f64>> = (0..8)
                .map(|k| {
                    let local = Vector3::new(
                        a * ((k & 1) as f64 - 0.5),
                        b * (((k >> 1) & 1) as f64 - 0.5),
                        c * ((k >> 2) as f64 - 0.5),
                    );
                    rot * local + shift
                })
                .collect();
            let faces = convex_hull_faces(&pts).unwrap();
            prop_assert_eq!(faces.len(), 6);
            let m = polyhedron_mass(&pts, &faces);
            let scale = a.max(b).max(c);
            prop_assert!((m.volume - a * b * c).abs() < 1e-12 * scale.powi(3));
            prop_assert!((m.centroid - shift).norm() < 1e-12 * (scale + shift.norm()));
            let inertia = inertia_from_second_moment(&m.second_moment, 1.0);
            let mut got: Vec<f64> = inertia.symmetric_eigen().eigenvalues.iter().copied().collect();
            got.sort_by(f64::total_cmp);
            let mass = a * b * c;
            let mut want = vec![
                mass * (b * b + c * c) / 12.0,
                mass * (a * a + c * c) / 12.0,
                mass * (a * a + b * b) / 12.0,
            ];
            want.sort_by(f64::total_cmp);
            for (g, w) in got.iter().zip(&want) {
                prop_assert!((g - w).abs() < 1e-10 * mass * scale * scale);
            }
        }
    }
}

/// A quadrilateral particle's area, centroid and polar moment do not depend on the vertex its
/// loop starts at, and its mirror image (y negated, loop reversed to stay counter-clockwise)
/// has the mirrored centroid and the same area and moment, to the bit; the values match the
/// exact ones of the trapezoid to round-off.
#[test]
fn polygon_mass_is_independent_of_the_start_and_mirror_exact() {
    use crate::dem::geometry::polygon_mass;
    use nalgebra::Vector2;
    // A ring sector like those of `cylinder-explosion` (radii 5 and 5.1 about (20, 0)).
    let (t0, t1) = (0.3f64, 0.3 + std::f64::consts::TAU / 50.0);
    let at = |r: f64, t: f64| Vector2::new(20.0 + r * t.cos(), r * t.sin());
    let quad = [at(5.0, t0), at(5.1, t0), at(5.1, t1), at(5.0, t1)];
    let reference = polygon_mass(&quad);
    for start in 1..4 {
        let rotated: Vec<_> = (0..4).map(|k| quad[(k + start) % 4]).collect();
        let m = polygon_mass(&rotated);
        assert_eq!(m.0.to_bits(), reference.0.to_bits(), "area, start {start}");
        assert_eq!(m.1, reference.1, "centroid, start {start}");
        assert_eq!(
            m.2.to_bits(),
            reference.2.to_bits(),
            "polar moment, start {start}"
        );
    }
    for start in 0..4 {
        let mirrored: Vec<_> = (0..4)
            .map(|k| {
                let p = quad[(start + 4 - k) % 4];
                Vector2::new(p.x, -p.y)
            })
            .collect();
        let m = polygon_mass(&mirrored);
        assert_eq!(m.0.to_bits(), reference.0.to_bits(), "mirrored area");
        assert_eq!(
            m.1.x.to_bits(),
            reference.1.x.to_bits(),
            "mirrored centroid x"
        );
        assert_eq!(
            m.1.y.to_bits(),
            (-reference.1.y).to_bits(),
            "mirrored centroid y"
        );
        assert_eq!(
            m.2.to_bits(),
            reference.2.to_bits(),
            "mirrored polar moment"
        );
    }
    // Exact: two isosceles triangles about the centre, area ½ sin(Δt) (R² − r²).
    let exact = 0.5 * (t1 - t0).sin() * (5.1f64 * 5.1 - 25.0);
    assert!(
        (reference.0 - exact).abs() <= 1e-12 * exact,
        "{} vs {exact}",
        reference.0
    );
}

/// The steel ring of `fragmenting-cylinder` (paper 000 §4.2: 50 particles, radii 5 and 5.2,
/// E = 210 GPa, ρs = 7860) under a uniform pressure p on its inner faces, applied as a step
/// at t = 0. Each particle takes p times its inner chord, radially; the links' tension that
/// balances it is T = p R_i, so the static hoop strain of every link (centre distance) is
/// ε = p R_i/(E t). Undamped and symmetric, the ring breathes: ε(t) = ε (1 − cos ωt), with
/// ω² = 2 E t sin(π/N)/(R_c m) (R_c the centres' radius, m a particle's mass per unit
/// depth), so the strain peaks at 2ε at t = π/ω. At 1 % elongation at break this is the
/// pressure that would break every link at once: p = 0.01 E t/(2 R_i) = 42 MPa.
#[test]
fn a_ring_under_a_step_internal_pressure_breathes_at_twice_the_static_hoop_strain() {
    let (n, r_in, r_out, young, rho) = (50usize, 5.0, 5.2, 2.1e11, 7860.0);
    let thickness = r_out - r_in;
    let mut cfg = box_config(2, vec![n as u32], 0.0);
    cfg.density = Some(rho);
    cfg.young = Some(young);
    cfg.bodies[0].shape = Shape::Ring {
        center: vec![0.0, 0.0],
        inner_radius: r_in,
        outer_radius: r_out,
    };
    let mut solid = Solid::from_scene(&cfg, 2, 1).unwrap();
    assert_eq!(solid.n_particles(), n);
    let p = 1e7;
    let half = std::f64::consts::PI / n as f64;
    let chord = 2.0 * r_in * half.sin();
    let x0: Vec<Vector3<f64>> = (0..n)
        .map(|k| Vector3::from(solid.position(ParticleId(k as u32))))
        .collect();
    let mut force = vec![0.0; 2 * n];
    for (k, x) in x0.iter().enumerate() {
        let radial = x.normalize();
        force[2 * k] = p * chord * radial.x;
        force[2 * k + 1] = p * chord * radial.y;
    }
    let torque = vec![0.0; n];
    let d0: Vec<f64> = (0..n).map(|k| (x0[k] - x0[(k + 1) % n]).norm()).collect();
    let strain = |solid: &Solid| {
        (0..n)
            .map(|k| {
                let (a, b) = (k as u32, ((k + 1) % n) as u32);
                let d = (Vector3::from(solid.position(ParticleId(a)))
                    - Vector3::from(solid.position(ParticleId(b))))
                .norm();
                (d - d0[k]) / d0[k]
            })
            .collect::<Vec<f64>>()
    };
    let static_strain = p * r_in / (young * thickness);
    let r_c = x0[0].norm();
    let mass = solid.model().particles[0].mass;
    let omega = (2.0 * young * thickness * half.sin() / (r_c * mass)).sqrt();
    let dt = 1e-6;
    assert!(dt < 0.1 * solid.elastic_dt_limit().0);
    let (mut peak, mut t_peak, mut spread) = (0.0f64, 0.0, 0.0f64);
    let steps = (1.2 * std::f64::consts::PI / omega / dt) as usize;
    for s in 1..=steps {
        solid.step(dt, &force, &torque);
        let e = strain(&solid);
        let (lo, hi) = e
            .iter()
            .fold((f64::MAX, f64::MIN), |(lo, hi), &v| (lo.min(v), hi.max(v)));
        spread = spread.max(hi - lo);
        if hi > peak {
            peak = hi;
            t_peak = s as f64 * dt;
        }
    }
    // Breathing scales the ring about its centre, so links and loads keep their directions
    // and the response is linear; what is left is Verlet's O((ω dt)²) = 1e-6 (measured 1e-8).
    assert!(
        (peak / (2.0 * static_strain) - 1.0).abs() < 1e-6,
        "peak strain {peak:e} vs 2 p R_i/(E t) = {:e}",
        2.0 * static_strain
    );
    assert!(
        (t_peak * omega / std::f64::consts::PI - 1.0).abs() < 1e-3,
        "peak at {t_peak:e} s vs π/ω = {:e} s",
        std::f64::consts::PI / omega
    );
    // Every link alike: the breathing is the only mode a symmetric step load excites.
    assert!(spread < 1e-9 * peak, "links differ by {spread:e}");
}
