//! Cut-cell geometry in 3-D: Σ Λ V against exact polyhedral volumes (box, tilted box, sphere,
//! torus, several bodies, bodies crossing the domain boundary), face fractions against exact
//! areas, wet area conservation, and identity (19)–(21) of paper 003 in every cell.

#![allow(clippy::needless_range_loop)]

use crate::cutcell_support;

use cutcell_support::*;
use fluid_node::cutcell::{CutGeometry, compute, face_index};
use fluid_node::grid::Grid;

/// Relative tolerance of volumes and areas (the brief asks for 1e-12).
const VOLUME_TOL: f64 = 1e-12;
/// Tolerance of identity (2), relative to the face area.
const IDENTITY_TOL: f64 = 1e-12;

struct Summary {
    volume_error: f64,
    area_error: f64,
    identity: f64,
    defect: f64,
}

/// Computes the geometry of `mesh` and compares it with its exact volume (and, when the mesh is
/// entirely inside the domain, its area).
fn check(grid: &Grid, mesh: &Mesh, inside: bool) -> (Summary, CutGeometry) {
    let mut geo = CutGeometry::new();
    compute(grid, &mesh.surface(), &mut geo);
    let exact = mesh.enclosed_volume();
    let summary = Summary {
        volume_error: (volume_of(grid, &geo) - exact).abs() / exact,
        area_error: if inside {
            (geo.wet_area() - mesh.area()).abs() / mesh.area()
        } else {
            0.0
        },
        identity: identity_residual(grid, &geo),
        defect: geo.diagnostics.max_uncut_defect,
    };
    assert!(geo.solid_fraction.iter().all(|x| x.is_finite()));
    assert!(
        (volume_of(grid, &geo) - geo.solid_volume(grid)).abs() <= 1e-13 * exact,
        "library solid_volume disagrees with the sum over the array"
    );
    (summary, geo)
}

fn assert_ok(name: &str, s: &Summary) {
    eprintln!(
        "{name}: volume err {:.2e}, area err {:.2e}, identity {:.2e}, defect {:.2e}",
        s.volume_error, s.area_error, s.identity, s.defect
    );
    assert!(
        s.volume_error <= VOLUME_TOL,
        "{name}: volume error {}",
        s.volume_error
    );
    assert!(
        s.area_error <= VOLUME_TOL,
        "{name}: area error {}",
        s.area_error
    );
    assert!(
        s.identity <= IDENTITY_TOL,
        "{name}: identity residual {}",
        s.identity
    );
    assert_eq!(s.defect, 0.0, "{name}: uncut defect");
}

fn unit_grid(n: usize) -> Grid {
    Grid::new(&[0.0; 3], &[1.0; 3], &[n; 3]).unwrap()
}

#[test]
fn axis_aligned_box_fractions_are_exact() {
    let grid = unit_grid(10);
    let mesh = box_mesh([0.23, 0.31, 0.405], [0.67, 0.7, 0.8]);
    let (s, geo) = check(&grid, &mesh, true);
    assert_ok("box", &s);
    // Cell (3, 4, 5) lies inside; cell (2, 3, 4) holds the corner (0.23..0.3, 0.31..0.4, 0.405..0.5).
    assert_eq!(geo.solid_fraction[grid.index(3, 4, 5)], 1.0);
    let corner = 0.7 * 0.9 * 0.95;
    assert!((geo.solid_fraction[grid.index(2, 3, 4)] - corner).abs() < 1e-14);
    // x-face at x = 0.3 of row (j, k) = (3, 4): solid part (0.31..0.4) × (0.405..0.5).
    let f = geo.face_fraction[0][face_index(&grid, 0, [3, 3, 4])];
    assert!((f - 0.9 * 0.95).abs() < 1e-14, "face fraction {f}");
    // Face x = 0.7 lies outside the box (x_hi = 0.67).
    assert_eq!(geo.face_fraction[0][face_index(&grid, 0, [7, 5, 5])], 0.0);
}

#[test]
fn box_on_grid_planes_follows_the_tie_rule() {
    // Every face of the box lies in a grid plane.
    let grid = unit_grid(8);
    let mesh = box_mesh([0.25, 0.25, 0.25], [0.75, 0.625, 0.5]);
    let (s, geo) = check(&grid, &mesh, true);
    assert_ok("box on planes", &s);
    for (c, &l) in geo.solid_fraction.iter().enumerate() {
        let [i, j, k] = grid.ijk(c);
        let inside = (2..6).contains(&i) && (2..5).contains(&j) && (2..4).contains(&k);
        assert_eq!(l, if inside { 1.0 } else { 0.0 }, "cell {i} {j} {k}");
    }
    // Sub-faces in a grid plane go to the cell above the plane.
    for sf in &geo.subfaces {
        let [i, j, k] = grid.ijk(sf.cell as usize);
        if sf.normal[2] < -0.5 {
            assert_eq!(k, 2, "bottom face in the cell above z = 0.25 ({i} {j})");
        }
        if sf.normal[2] > 0.5 {
            assert_eq!(k, 4, "top face in the cell above z = 0.5");
        }
    }
}

#[test]
fn tilted_boxes_match_exact_volume() {
    let grid = Grid::new(&[-1.0, -1.0, -1.0], &[1.0, 1.2, 1.0], &[13, 17, 11]).unwrap();
    let mut rng = Rng(7);
    for case in 0..20 {
        let axis = [
            rng.uniform(-1.0, 1.0),
            rng.uniform(-1.0, 1.0),
            rng.uniform(-1.0, 1.0),
        ];
        let r = rotation(axis, rng.uniform(0.0, 6.3));
        let centre = [
            rng.uniform(-0.2, 0.2),
            rng.uniform(-0.2, 0.2),
            rng.uniform(-0.2, 0.2),
        ];
        let mesh =
            box_mesh([-0.4, -0.3, -0.25], [0.4, 0.35, 0.2]).map(|p| rigid(p, &r, [0.0; 3], centre));
        let (s, _) = check(&grid, &mesh, true);
        assert_ok(&format!("tilted box {case}"), &s);
    }
}

#[test]
fn polyhedral_sphere_matches_exact_volume_and_area() {
    for (n, lat, lon) in [(8, 10, 20), (21, 24, 48), (40, 40, 80)] {
        let grid = unit_grid(n);
        let mesh = sphere_mesh([0.503, 0.49, 0.511], 0.37, lat, lon);
        let (s, _) = check(&grid, &mesh, true);
        assert_ok(&format!("sphere n={n}"), &s);
    }
}

#[test]
fn polyhedral_torus_matches_exact_volume_and_area() {
    let grid = Grid::new(&[-1.0; 3], &[1.0; 3], &[24, 24, 12]).unwrap();
    let r = rotation([0.3, 1.0, 0.2], 0.7);
    let mesh = torus_mesh([0.0; 3], 0.6, 0.22, 48, 24)
        .map(|p| rigid(p, &r, [0.0; 3], [0.01, -0.02, 0.03]));
    let (s, _) = check(&grid, &mesh, true);
    assert_ok("torus", &s);
}

#[test]
fn several_bodies_add_up() {
    let grid = unit_grid(16);
    let mut mesh = sphere_mesh([0.3, 0.3, 0.3], 0.2, 12, 24);
    mesh.append(&box_mesh([0.55, 0.55, 0.2], [0.9, 0.8, 0.7]), 1);
    mesh.append(&torus_mesh([0.3, 0.7, 0.7], 0.17, 0.06, 24, 12), 2);
    let (s, geo) = check(&grid, &mesh, true);
    assert_ok("three bodies", &s);
    let particles: std::collections::BTreeSet<u32> =
        geo.subfaces.iter().map(|s| s.particle).collect();
    assert_eq!(particles.into_iter().collect::<Vec<_>>(), vec![0, 1, 2]);
}

#[test]
fn body_crossing_the_domain_boundary_gives_the_clipped_volume() {
    // A box sticking out of every side of the domain [0,1]³ on some axes: the solid volume in the
    // domain is the volume of the box ∩ domain.
    let grid = unit_grid(9);
    let cases = [
        ([-0.5, 0.2, 0.3], [0.45, 0.7, 0.6]),
        ([0.2, -0.3, -0.4], [0.6, 1.3, 0.55]),
        ([-1.0, -1.0, 0.5], [2.0, 2.0, 2.0]),
        ([-1.0, -1.0, -1.0], [2.0, 2.0, 2.0]),
    ];
    for (lo, hi) in cases {
        let mesh = box_mesh(lo, hi);
        let mut geo = CutGeometry::new();
        compute(&grid, &mesh.surface(), &mut geo);
        let mut exact = 1.0;
        for a in 0..3 {
            exact *= hi[a].min(1.0) - lo[a].max(0.0);
        }
        let err = (volume_of(&grid, &geo) - exact).abs() / exact;
        assert!(err <= VOLUME_TOL, "box {lo:?} {hi:?}: error {err}");
        assert!(identity_residual(&grid, &geo) <= IDENTITY_TOL);
        assert_eq!(geo.diagnostics.max_uncut_defect, 0.0);
    }
    // A tilted box and a sphere crossing the boundary: compare with the exact volume of the part
    // inside, measured by a grid that covers the whole body and summing over the subdomain.
    let r = rotation([1.0, 2.0, 0.5], 0.9);
    let sphere = sphere_mesh([0.95, 0.1, 0.5], 0.3, 16, 32)
        .map(|p| rigid(p, &r, [0.95, 0.1, 0.5], [0.0; 3]));
    let small = unit_grid(10);
    let big = Grid::new(&[-1.0; 3], &[2.0; 3], &[30; 3]).unwrap();
    let (mut g_small, mut g_big) = (CutGeometry::new(), CutGeometry::new());
    compute(&small, &sphere.surface(), &mut g_small);
    compute(&big, &sphere.surface(), &mut g_big);
    let mut inside = 0.0;
    for (c, l) in g_big.solid_fraction.iter().enumerate() {
        let [i, j, k] = big.ijk(c);
        if (10..20).contains(&i) && (10..20).contains(&j) && (10..20).contains(&k) {
            inside += l;
        }
    }
    inside *= big.cell_volume();
    let err = (volume_of(&small, &g_small) - inside).abs() / inside;
    assert!(err <= VOLUME_TOL, "sphere across the boundary: error {err}");
    assert!(
        (volume_of(&big, &g_big) - sphere.enclosed_volume()).abs()
            <= VOLUME_TOL * sphere.enclosed_volume()
    );
}

#[test]
fn face_fractions_match_exact_section_areas() {
    // A box rotated about z: its sections by z-planes are rotated rectangles (area known) and by
    // x-planes rectangles whose width is the chord of the rotated rectangle.
    let grid = unit_grid(12);
    let mut geo = CutGeometry::new();
    let r_z = rotation([0.0, 0.0, 1.0], 0.37);
    let upright =
        box_mesh([0.3, 0.25, 0.31], [0.7, 0.7, 0.66]).map(|p| rigid(p, &r_z, [0.5; 3], [0.0; 3]));
    compute(&grid, &upright.surface(), &mut geo);
    let face_area = grid.dx[0] * grid.dx[1];
    for k in 0..=12 {
        let z = k as f64 / 12.0;
        let exact = if (0.31..0.66).contains(&z) {
            0.4 * 0.45
        } else {
            0.0
        };
        let mut sum = 0.0;
        for j in 0..12 {
            for i in 0..12 {
                sum += geo.face_fraction[2][face_index(&grid, 2, [i, j, k])] * face_area;
            }
        }
        assert!(
            (sum - exact).abs() <= 1e-13,
            "plane z = {z}: {sum} vs {exact}"
        );
    }
    // x-planes of the upright box are cut along rotated rectangles: width of the section of the
    // rotated rectangle by the line x = x0 times the box height.
    let (c, s) = (0.37f64.cos(), 0.37f64.sin());
    let corners: Vec<[f64; 2]> = [[0.3, 0.25], [0.7, 0.25], [0.7, 0.7], [0.3, 0.7]]
        .iter()
        .map(|p| {
            let d = [p[0] - 0.5, p[1] - 0.5];
            [0.5 + c * d[0] - s * d[1], 0.5 + s * d[0] + c * d[1]]
        })
        .collect();
    let face_area_x = grid.dx[1] * grid.dx[2];
    for i in 0..=12 {
        let x0 = i as f64 / 12.0;
        // Chord of the convex quad at x = x0.
        let mut ys = Vec::new();
        for e in 0..4 {
            let (p, q) = (corners[e], corners[(e + 1) % 4]);
            if (p[0] - x0) * (q[0] - x0) < 0.0 {
                ys.push(p[1] + (x0 - p[0]) / (q[0] - p[0]) * (q[1] - p[1]));
            }
        }
        let chord = if ys.len() == 2 {
            (ys[0] - ys[1]).abs()
        } else {
            0.0
        };
        let exact = chord * (0.66 - 0.31);
        let mut sum = 0.0;
        for k in 0..12 {
            for j in 0..12 {
                sum += geo.face_fraction[0][face_index(&grid, 0, [i, j, k])] * face_area_x;
            }
        }
        assert!(
            (sum - exact).abs() <= 1e-13,
            "plane x = {x0}: {sum} vs {exact}"
        );
    }
}

#[test]
fn buffers_are_reused_and_reset() {
    let grid = unit_grid(12);
    let a = sphere_mesh([0.3, 0.3, 0.3], 0.2, 12, 24);
    let b = box_mesh([0.5, 0.5, 0.5], [0.9, 0.8, 0.95]);
    let mut geo = CutGeometry::new();
    compute(&grid, &a.surface(), &mut geo);
    compute(&grid, &b.surface(), &mut geo);
    let mut fresh = CutGeometry::new();
    compute(&grid, &b.surface(), &mut fresh);
    assert_eq!(geo.solid_fraction, fresh.solid_fraction);
    assert_eq!(geo.face_fraction, fresh.face_fraction);
    assert_eq!(geo.subfaces, fresh.subfaces);
    assert_eq!(geo.cut_cells, fresh.cut_cells);
}

#[test]
fn sub_faces_carry_area_normal_and_centroid() {
    let grid = unit_grid(7);
    let r = rotation([1.0, 1.0, 0.3], 0.4);
    let mesh = sphere_mesh([0.5; 3], 0.3, 10, 20).map(|p| rigid(p, &r, [0.5; 3], [0.0; 3]));
    let mut geo = CutGeometry::new();
    compute(&grid, &mesh.surface(), &mut geo);
    // Sorted by cell, then element.
    assert!(
        geo.subfaces
            .windows(2)
            .all(|w| (w[0].cell, w[0].element) <= (w[1].cell, w[1].element))
    );
    // Per element, the sub-face areas add up to the element area and the first moments add up to
    // area × centroid of the element.
    let n_el = mesh.n_elements();
    let mut area = vec![0.0; n_el];
    let mut moment = vec![[0.0; 3]; n_el];
    for s in &geo.subfaces {
        area[s.element as usize] += s.area;
        for a in 0..3 {
            moment[s.element as usize][a] += s.area * s.centroid[a];
        }
        assert!((dot(s.normal, s.normal) - 1.0).abs() < 1e-14);
        // The centroid lies in its cell (closed box).
        let [i, j, k] = grid.ijk(s.cell as usize);
        for (a, idx) in [i, j, k].into_iter().enumerate() {
            let lo = idx as f64 * grid.dx[a];
            assert!(s.centroid[a] >= lo - 1e-12 && s.centroid[a] <= lo + grid.dx[a] + 1e-12);
        }
    }
    let surf = mesh.surface();
    for e in 0..n_el {
        let t = surf.element(e).unwrap();
        let c = cross(sub(t[1], t[0]), sub(t[2], t[0]));
        let exact = 0.5 * dot(c, c).sqrt();
        assert!((area[e] - exact).abs() <= 1e-14, "element {e} area");
        for a in 0..3 {
            let centroid = (t[0][a] + t[1][a] + t[2][a]) / 3.0;
            assert!(
                (moment[e][a] / area[e] - centroid).abs() <= 1e-13,
                "element {e} centroid"
            );
        }
    }
}

#[test]
fn results_are_repeatable_and_independent_of_element_order() {
    let grid = unit_grid(13);
    let r = rotation([0.7, -0.2, 0.4], 1.1);
    let mesh = torus_mesh([0.5; 3], 0.3, 0.1, 24, 12).map(|p| rigid(p, &r, [0.5; 3], [0.0; 3]));
    let (mut a, mut b) = (CutGeometry::new(), CutGeometry::new());
    compute(&grid, &mesh.surface(), &mut a);
    compute(&grid, &mesh.surface(), &mut b);
    let bits = |g: &CutGeometry| {
        g.solid_fraction
            .iter()
            .map(|x| x.to_bits())
            .collect::<Vec<_>>()
    };
    assert_eq!(bits(&a), bits(&b), "same input, same bits");
    // Elements in reverse order (vertex order inside each element kept).
    let mut shuffled = mesh.clone();
    let elements: Vec<[u32; 3]> = mesh
        .elements
        .chunks(3)
        .rev()
        .map(|e| [e[0], e[1], e[2]])
        .collect();
    shuffled.elements = elements.concat();
    compute(&grid, &shuffled.surface(), &mut b);
    assert_eq!(a.cut_cells, b.cut_cells);
    for (x, y) in a.solid_fraction.iter().zip(&b.solid_fraction) {
        assert!((x - y).abs() <= 1e-14);
    }
}
