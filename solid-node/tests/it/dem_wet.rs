//! Wet surface (003 §3.2 eq. (18)): closed, consistently oriented (normals out of the solid: the
//! divergence theorem gives back the solid's volume), carried internal faces flagged dry, rigid
//! velocities at element centroids; for boxes, rings and tubes.

use crate::dem_support;

use dem_support::*;
use protocol::scene::{BodyConfig, Motion, Shape, SolidConfig};
use solid_node::dem::{ParticleId, Solid, WetSurfaceData};

fn assert_closed(wet: &WetSurfaceData) {
    let dim = wet.dim;
    let mut edges: Vec<(u32, u32)> = Vec::new();
    for e in 0..wet.n_elements() {
        if !wet.wet[e] {
            continue;
        }
        let el = &wet.elements[e * dim..(e + 1) * dim];
        if dim == 2 {
            edges.push((el[0], el[1]));
        } else {
            for k in 0..3 {
                edges.push((el[k], el[(k + 1) % 3]));
            }
        }
    }
    let mut sorted = edges.clone();
    sorted.sort_unstable();
    for w in sorted.windows(2) {
        assert_ne!(w[0], w[1], "edge used twice in the same direction");
    }
    if dim == 3 {
        for &(a, b) in &edges {
            assert!(
                sorted.binary_search(&(b, a)).is_ok(),
                "edge ({a}, {b}) has no reverse"
            );
        }
    } else {
        let mut starts: Vec<u32> = edges.iter().map(|e| e.0).collect();
        let mut ends: Vec<u32> = edges.iter().map(|e| e.1).collect();
        starts.sort_unstable();
        ends.sort_unstable();
        assert_eq!(starts, ends, "open polyline");
    }
}

/// `(1/dim) Σ (c·n) A` over the wet elements: the enclosed volume (area in 2-D).
fn enclosed(wet: &WetSurfaceData) -> f64 {
    let dim = wet.dim;
    (0..wet.n_elements())
        .filter(|&e| wet.wet[e])
        .map(|e| {
            let c = &wet.centroid[e * dim..(e + 1) * dim];
            let n = &wet.normal[e * dim..(e + 1) * dim];
            c.iter().zip(n).map(|(a, b)| a * b).sum::<f64>() * wet.area[e] / dim as f64
        })
        .sum()
}

fn total_volume(solid: &Solid) -> f64 {
    solid.model().particles.iter().map(|p| p.volume).sum()
}

fn shape_config(shape: Shape, divisions: Vec<u32>, fracture: bool) -> SolidConfig {
    let mut cfg = box_config(vec![0.0, 0.0], vec![1.0, 1.0], vec![1, 1], 1e6, 0.2, 1000.0);
    cfg.bodies = vec![BodyConfig {
        shape,
        divisions,
        motion: Motion::Free,
        links: None,
    }];
    if fracture {
        with_fracture(&mut cfg, 0.1);
    }
    cfg
}

fn check(cfg: &SolidConfig, dim: usize, expected_volume: f64) {
    let solid = build(cfg, dim, 1);
    let wet = solid.wet_surface();
    assert_closed(wet);
    let v = enclosed(wet);
    let v_particles = total_volume(&solid);
    assert!(
        (v_particles - expected_volume).abs() < 1e-12 * expected_volume.max(1.0)
            || expected_volume < 0.0
    );
    assert!(
        (v - v_particles).abs() < 1e-12 * v_particles,
        "enclosed {v} vs {v_particles}"
    );
    assert_eq!(wet.vertices.len() % dim, 0);
    assert_eq!(wet.elements.len(), dim * wet.n_elements());
    let carried_dry = wet.wet.iter().filter(|w| !**w).count();
    if cfg.fracture.is_some() {
        assert!(carried_dry > 0, "internal faces carried, dry");
    } else {
        assert_eq!(carried_dry, 0);
    }
}

#[test]
fn box_surfaces_are_closed_and_outward() {
    for fracture in [false, true] {
        let cfg3 = shape_config(
            Shape::Box {
                center: vec![0.1, 0.2, 0.3],
                size: vec![0.3, 0.2, 0.1],
            },
            vec![3, 2, 2],
            fracture,
        );
        check(&cfg3, 3, 0.006);
        let cfg2 = shape_config(
            Shape::Box {
                center: vec![0.1, 0.2],
                size: vec![0.3, 0.2],
            },
            vec![3, 2],
            fracture,
        );
        check(&cfg2, 2, 0.06);
    }
}

#[test]
fn ring_and_tube_surfaces_are_closed_and_outward() {
    for fracture in [false, true] {
        let ring = shape_config(
            Shape::Ring {
                center: vec![1.0, 2.0],
                inner_radius: 0.9,
                outer_radius: 1.0,
            },
            vec![24],
            fracture,
        );
        check(&ring, 2, -1.0);
        let tube = shape_config(
            Shape::Tube {
                center: vec![0.0, 0.0, 0.0],
                axis: 2,
                inner_radius: 0.9,
                outer_radius: 1.0,
                length: 0.5,
            },
            vec![16, 2],
            fracture,
        );
        check(&tube, 3, -1.0);
    }
}

#[test]
fn explicit_particles_link_through_shared_faces() {
    let spec = |v: Vec<Vec<f64>>| protocol::scene::ParticleSpec { vertices: v };
    let cfg = shape_config(
        Shape::Particles(vec![
            spec(vec![
                vec![0.0, 0.0],
                vec![1.0, 0.0],
                vec![1.0, 1.0],
                vec![0.0, 1.0],
            ]),
            spec(vec![vec![1.0, 0.0], vec![2.0, 0.5], vec![1.0, 1.0]]),
        ]),
        vec![],
        false,
    );
    let solid = build(&cfg, 2, 1);
    assert_eq!(solid.model().links.len(), 1);
    check(&cfg, 2, 1.5);
    let cube: Vec<Vec<f64>> = (0..8)
        .map(|c| vec![(c & 1) as f64, ((c >> 1) & 1) as f64, (c >> 2) as f64])
        .collect();
    let tip = vec![
        vec![1.0, 0.0, 0.0],
        vec![1.0, 1.0, 0.0],
        vec![1.0, 0.0, 1.0],
        vec![1.0, 1.0, 1.0],
        vec![2.0, 0.5, 0.5],
    ];
    let cfg3 = shape_config(Shape::Particles(vec![spec(cube), spec(tip)]), vec![], false);
    let solid3 = build(&cfg3, 3, 1);
    assert_eq!(solid3.model().links.len(), 1);
    check(&cfg3, 3, 1.0 + 1.0 / 3.0);
}

#[test]
fn element_velocity_is_the_rigid_velocity_and_trial_surface_moves() {
    let cfg = shape_config(
        Shape::Box {
            center: vec![0.0, 0.0, 0.0],
            size: vec![0.2, 0.1, 0.1],
        },
        vec![2, 1, 1],
        false,
    );
    let mut solid = build(&cfg, 3, 1);
    for p in 0..2 {
        solid.set_velocity(ParticleId(p), &[1.0, -2.0, 0.5]);
    }
    let x0 = solid.position(ParticleId(0))[0];
    solid.begin_step(1e-4);
    let trial = solid.trial(&[0.0; 6], &[0.0; 6]);
    let wet = &trial.wet;
    for e in 0..wet.n_elements() {
        let v = &wet.velocity[3 * e..3 * e + 3];
        assert!(
            (v[0] - 1.0).abs() < 1e-12 && (v[1] + 2.0).abs() < 1e-12 && (v[2] - 0.5).abs() < 1e-12
        );
    }
    let moved = trial.position[0] - x0;
    assert!((moved - 1e-4).abs() < 1e-12);
    assert_closed(wet);
}

/// `(1/3) Σ (c·n) A` over the carried dry elements (the internal faces of unbroken links).
fn enclosed_by_dry(wet: &WetSurfaceData) -> f64 {
    (0..wet.n_elements())
        .filter(|&e| !wet.wet[e])
        .map(|e| {
            let c = &wet.centroid[e * 3..(e + 1) * 3];
            let n = &wet.normal[e * 3..(e + 1) * 3];
            c.iter().zip(n).map(|(a, b)| a * b).sum::<f64>() * wet.area[e] / 3.0
        })
        .sum()
}

/// The two faces of a stretched unbroken link coincide (3-D): their loops are mean vertices and
/// their centroids the mean of both, so together they enclose nothing (the fluid's `Λ` counts
/// dry elements too; two rigid centroids left a lens of "fluid" inside the intact solid). Once
/// the link breaks, each face takes its own particle's rigid centroid.
#[test]
fn stretched_link_faces_coincide_until_the_link_breaks() {
    let mut cfg = box_config(
        vec![0.0; 3],
        vec![0.8, 0.4, 0.4],
        vec![2, 1, 1],
        2.1e11,
        0.3,
        7000.0,
    );
    with_fracture(&mut cfg, 1e-3);
    constrain(&mut cfg, vec![-1.0; 3], vec![0.0, 1.0, 1.0], Motion::Fixed);
    constrain(
        &mut cfg,
        vec![0.0, -1.0, -1.0],
        vec![1.0; 3],
        Motion::Velocity(vec![1.0, 0.0, 0.0]),
    );
    let mut solid = build(&cfg, 3, 1);
    // A step of 1e-4 s stretches the link by 1e-4 m: 2.5e-4 of its length, below the limit.
    let r = solid.step_free(1e-4);
    assert!(r.broken_links.is_empty());
    let wet = solid.wet_surface();
    let lens = enclosed_by_dry(wet);
    let dry = wet.wet.iter().filter(|w| !**w).count();
    println!("stretched by 1e-4 m: {dry} dry elements enclose {lens:e} m^3");
    assert_eq!(dry, 8, "the two internal faces, 4 triangles each");
    // A rigid centroid on each side would leave two pyramids of height 5e-5 m over the
    // 0.16 m² face: 2 × (1/3) × 0.16 × 5e-5 = 5.3e-6 m³.
    assert!(lens.abs() < 1e-18, "lens {lens:e}");
    // Past the limit the link breaks and the crack faces separate (wet, rigid centroids).
    let mut broke = false;
    for _ in 0..10 {
        let r = solid.step_free(1e-3);
        broke |= !r.broken_links.is_empty();
    }
    assert!(broke, "the link breaks");
    let wet = solid.wet_surface();
    assert_eq!(wet.wet.iter().filter(|w| !**w).count(), 0);
    assert_closed(wet);
    let v = enclosed(wet);
    assert!(
        (v - total_volume(&solid)).abs() < 1e-12 * v,
        "each fragment closed: {v} vs {}",
        total_volume(&solid)
    );
}

/// Issue 37 (docs/subcycling.md, the thin shell's rotation): the vertices shared by linked
/// particles are the means of their rigid corners, so particles of a column that all turn by θ
/// keep their long wet faces parallel to the column, shifted along it by `(t/2) sin θ`. A
/// uniform pressure p on the two long faces of the middle particle then gives it the torque
/// `p h t sin θ`, in the sense of θ: a negative stiffness `p h t` (the faces of a lone rigid
/// rectangle turn with it and take none).
#[test]
fn particles_turning_together_keep_their_long_faces_parallel_a_negative_stiffness() {
    let (t, h) = (3.125e-3, 5e-3);
    let cfg = shape_config(
        Shape::Box {
            center: vec![0.5, 0.1],
            size: vec![t, 3.0 * h],
        },
        vec![1, 3],
        false,
    );
    let mut solid = build(&cfg, 2, 1);
    for p in 0..3 {
        solid.set_angular_velocity(ParticleId(p), &[100.0]);
    }
    solid.begin_step(1e-4);
    let trial = solid.trial(&[0.0; 6], &[0.0; 3]);
    let theta = trial.orientation[1];
    assert!((theta - 1e-2).abs() <= 1e-12, "theta {theta}");
    let x = [trial.position[2], trial.position[3]];
    let wet = &trial.wet;
    let (mut torque, mut faces) = (0.0, 0);
    for e in 0..wet.n_elements() {
        if !wet.wet[e] || wet.element_particle[e] != 1 {
            continue;
        }
        let (n, c, a) = (
            &wet.normal[2 * e..2 * e + 2],
            &wet.centroid[2 * e..2 * e + 2],
            wet.area[e],
        );
        assert!(n[1].abs() <= 1e-12, "a long face turned: normal {n:?}");
        assert!((a - h).abs() <= 1e-12 * h, "area {a}");
        // Pressure p = 1 Pa: force −p n A at the face's centroid, moment about the centre.
        let f = [-n[0] * a, -n[1] * a];
        torque += (c[0] - x[0]) * f[1] - (c[1] - x[1]) * f[0];
        faces += 1;
    }
    assert_eq!(faces, 2, "the middle particle's two long faces are wet");
    let expected = h * t * theta.sin();
    println!("torque {torque:e} N m, p h t sin(theta) {expected:e}");
    assert!(
        (torque - expected).abs() <= 1e-9 * expected,
        "torque {torque:e}, expected {expected:e}"
    );
}

/// The coordinates of element `e`'s vertices, as bits.
fn element_points(wet: &WetSurfaceData, e: usize) -> Vec<u64> {
    let dim = wet.dim;
    (wet.elements[e * dim..(e + 1) * dim].iter())
        .flat_map(|&v| &wet.vertices[v as usize * dim..(v as usize + 1) * dim])
        .map(|x| x.to_bits())
        .collect()
}

/// Without fracture only the vertices the elements use are carried (issue 39 item 4), and the
/// elements are where the whole numbering puts them: with fracture on (every slot carried, the
/// internal faces too) the wet elements, in order, have the same particles and the same vertex
/// coordinates, to the bit; with it, the vertex count is the slots' (3-D: and the faces').
#[test]
fn without_fracture_only_the_vertices_the_elements_use_are_carried() {
    let shapes = [
        (
            Shape::Box {
                center: vec![0.1, 0.2],
                size: vec![0.3, 0.2],
            },
            vec![3, 2],
            2,
        ),
        (
            Shape::Box {
                center: vec![0.1, 0.2, 0.3],
                size: vec![0.3, 0.2, 0.1],
            },
            vec![3, 2, 2],
            3,
        ),
        (
            Shape::Ring {
                center: vec![1.0, 2.0],
                inner_radius: 0.9,
                outer_radius: 1.0,
            },
            vec![24],
            2,
        ),
    ];
    for (shape, divisions, dim) in shapes {
        let compact = build(
            &shape_config(shape.clone(), divisions.clone(), false),
            dim,
            1,
        );
        let whole = build(&shape_config(shape, divisions, true), dim, 1);
        let (c, w) = (compact.wet_surface(), whole.wet_surface());
        let model = whole.model();
        let n_whole = model.slots.len() + if dim == 3 { model.faces.len() } else { 0 };
        assert_eq!(
            w.vertices.len(),
            n_whole * dim,
            "{dim}-D: fracture on carries all"
        );
        let mut used: Vec<u32> = c.elements.clone();
        used.sort_unstable();
        used.dedup();
        let n_compact = c.vertices.len() / dim;
        assert_eq!(
            used.len(),
            n_compact,
            "{dim}-D: a carried vertex no element uses"
        );
        assert!(n_compact < n_whole, "{dim}-D: {n_compact} of {n_whole}");
        let wet: Vec<usize> = (0..w.n_elements()).filter(|&e| w.wet[e]).collect();
        assert_eq!(wet.len(), c.n_elements());
        for (k, &e) in wet.iter().enumerate() {
            assert_eq!(c.element_particle[k], w.element_particle[e]);
            assert_eq!(
                element_points(c, k),
                element_points(w, e),
                "{dim}-D element {k}"
            );
        }
    }
}
