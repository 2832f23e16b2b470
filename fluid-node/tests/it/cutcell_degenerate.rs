//! Degenerate inputs of the 3-D cut-cell geometry (brief item 4): vertices exactly on grid planes,
//! triangles lying in grid planes, sliver and zero-area triangles, internal faces carried on both
//! sides (a body split into two particles), bodies touching the domain boundary, non-finite
//! input. Each case checks the exact volume, identity (2), no NaN, no lost or doubled area.

#![allow(clippy::needless_range_loop)]

use crate::cutcell_support;

use cutcell_support::*;
use fluid_node::cutcell::{CutGeometry, compute};
use fluid_node::grid::Grid;

const TOL: f64 = 1e-12;

/// How far Λ and λ of one body may leave [0, 1] by round-off.
const ROUND_OFF: f64 = 1e-14;

fn check(grid: &Grid, mesh: &Mesh, exact_volume: f64, exact_area: Option<f64>) -> CutGeometry {
    let mut geo = CutGeometry::new();
    compute(grid, &mesh.surface(), &mut geo);
    // Λ and λ are not clamped (overlapping bodies count twice): one body leaves [0, 1] by
    // round-off only.
    let in_range = |x: &f64| x.is_finite() && (-ROUND_OFF..=1.0 + ROUND_OFF).contains(x);
    assert!(geo.solid_fraction.iter().all(in_range));
    for axis in 0..3 {
        assert!(geo.face_fraction[axis].iter().all(in_range));
    }
    assert!(
        geo.subfaces
            .iter()
            .all(|s| s.area.is_finite() && s.centroid.iter().all(|c| c.is_finite()))
    );
    let err = (volume_of(grid, &geo) - exact_volume).abs() / exact_volume;
    assert!(err <= TOL, "volume error {err}");
    if let Some(area) = exact_area {
        let err = (geo.wet_area() - area).abs() / area;
        assert!(err <= TOL, "area error {err}");
    }
    let identity = identity_residual(grid, &geo);
    assert!(identity <= TOL, "identity residual {identity}");
    assert_eq!(geo.diagnostics.max_uncut_defect, 0.0, "uncut defect");
    geo
}

fn unit_grid(n: usize) -> Grid {
    Grid::new(&[0.0; 3], &[1.0; 3], &[n; 3]).unwrap()
}

/// Octahedron with vertices at grid nodes: every vertex on three grid planes, edges along planes.
#[test]
fn octahedron_with_vertices_on_grid_nodes() {
    let grid = unit_grid(8);
    let (c, r) = (0.5, 0.375);
    let vertices = vec![
        c + r,
        c,
        c,
        c - r,
        c,
        c,
        c,
        c + r,
        c,
        c,
        c - r,
        c,
        c,
        c,
        c + r,
        c,
        c,
        c - r,
    ];
    // Faces (outward): (+x, +y, +z) etc.
    let elements = vec![
        0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5,
    ];
    let mesh = Mesh {
        dim: 3,
        vertices,
        elements,
        particle: vec![0; 8],
    };
    let exact = 4.0 / 3.0 * r * r * r;
    assert!((mesh.enclosed_volume() - exact).abs() < 1e-15);
    check(&grid, &mesh, exact, Some(mesh.area()));
}

#[test]
fn tetrahedron_with_a_face_in_a_grid_plane() {
    let grid = unit_grid(8);
    // Base in z = 0.25 (a grid plane), apex above; base vertices on grid lines.
    let vertices = vec![
        0.25, 0.25, 0.25, 0.8, 0.3, 0.25, 0.4, 0.75, 0.25, 0.45, 0.45, 0.7,
    ];
    let mut mesh = Mesh {
        dim: 3,
        vertices,
        elements: vec![0, 2, 1, 0, 1, 3, 1, 2, 3, 2, 0, 3],
        particle: vec![0; 4],
    };
    if mesh.enclosed_volume() < 0.0 {
        mesh = mesh.reversed();
    }
    let geo = check(&grid, &mesh, mesh.enclosed_volume(), Some(mesh.area()));
    // The base (normal −z) lies in the plane z = 0.25 and goes to the cells above it (k = 2).
    for s in &geo.subfaces {
        if s.normal[2] < -0.999 {
            assert_eq!(grid.ijk(s.cell as usize)[2], 2);
        }
    }
    // Flipped upside down: base in the plane z = 0.75 (normal +z), apex below.
    let flipped = mesh.map(|p| [p[0], p[1], 1.0 - p[2]]).reversed();
    check(
        &grid,
        &flipped,
        flipped.enclosed_volume(),
        Some(flipped.area()),
    );
}

#[test]
fn sphere_with_vertices_snapped_to_grid_planes() {
    let grid = unit_grid(10);
    // Snap every vertex coordinate within 0.02 of a grid plane onto the plane.
    let snapped = sphere_mesh([0.5; 3], 0.33, 18, 36).map(|p| {
        let mut q = p;
        for a in 0..3 {
            let s = (p[a] * 10.0).round() / 10.0;
            if (p[a] - s).abs() < 0.02 {
                q[a] = s;
            }
        }
        q
    });
    check(
        &grid,
        &snapped,
        snapped.enclosed_volume(),
        Some(snapped.area()),
    );
}

#[test]
fn sliver_and_zero_area_triangles() {
    let grid = unit_grid(9);
    // A box whose top face is fanned from a vertex 1e-13 above the face (slivers), plus a
    // zero-area triangle (repeated vertex) and a needle.
    let (lo, hi) = ([0.21, 0.18, 0.3], [0.73, 0.66, 0.71]);
    let mut mesh = box_mesh(lo, hi);
    // Drop the two top triangles (indices 2 and 3 of 12: quad z = hi).
    let top: Vec<u32> = mesh.elements.drain(6..12).collect();
    mesh.particle.truncate(10);
    let apex = (mesh.vertices.len() / 3) as u32;
    mesh.vertices.extend_from_slice(&[0.5, 0.4, hi[2] + 1e-13]);
    // The top quad's outer loop (4, 5, 7, 6) fanned from the apex.
    let ring = [top[0], top[1], top[2], top[5]];
    for i in 0..4 {
        mesh.elements
            .extend_from_slice(&[ring[i], ring[(i + 1) % 4], apex]);
        mesh.particle.push(0);
    }
    // Zero-area triangles (repeated vertex, collinear) add nothing.
    mesh.elements.extend_from_slice(&[0, 0, 1, 0, 1, 1]);
    mesh.particle.extend_from_slice(&[0, 0]);
    let exact = mesh.enclosed_volume();
    assert!((exact - 0.52 * 0.48 * 0.41).abs() < 1e-12);
    check(&grid, &mesh, exact, Some(mesh.area()));
}

#[test]
fn internal_faces_carried_on_both_sides_cancel() {
    // A box split into two particles along x = 0.47 and a tilted cut; each half is closed, so the
    // internal faces appear twice with opposite orientations.
    let grid = unit_grid(11);
    let mut pair = box_mesh([0.2, 0.25, 0.3], [0.47, 0.75, 0.8]);
    pair.append(&box_mesh([0.47, 0.25, 0.3], [0.81, 0.75, 0.8]), 1);
    let geo = check(&grid, &pair, 0.61 * 0.5 * 0.5, None);
    let mut whole = CutGeometry::new();
    compute(
        &grid,
        &box_mesh([0.2, 0.25, 0.3], [0.81, 0.75, 0.8]).surface(),
        &mut whole,
    );
    for (a, b) in geo.solid_fraction.iter().zip(&whole.solid_fraction) {
        assert!((a - b).abs() <= 1e-14);
    }
    for axis in 0..3 {
        for (a, b) in geo.face_fraction[axis]
            .iter()
            .zip(&whole.face_fraction[axis])
        {
            assert!((a - b).abs() <= 1e-14);
        }
    }
    // The same, rotated (the shared face is oblique to the grid).
    let r = rotation([0.3, 0.4, 1.0], 0.5);
    let turned = pair.map(|p| rigid(p, &r, [0.5; 3], [0.0; 3]));
    check(&grid, &turned, 0.61 * 0.5 * 0.5, None);
}

#[test]
fn bodies_touching_the_domain_boundary() {
    let grid = unit_grid(6);
    // Faces lying exactly in the domain's boundary planes.
    for (lo, hi) in [
        ([0.0, 0.0, 0.0], [0.5, 0.4, 0.3]),
        ([0.5, 0.6, 0.7], [1.0, 1.0, 1.0]),
        ([0.0, 0.0, 0.0], [1.0, 1.0, 1.0]),
    ] {
        let mesh = box_mesh(lo, hi);
        check(&grid, &mesh, mesh.enclosed_volume(), None);
    }
}

#[test]
fn non_finite_and_out_of_range_input_is_skipped() {
    let grid = unit_grid(5);
    let mut mesh = box_mesh([0.2; 3], [0.7; 3]);
    let bad = (mesh.vertices.len() / 3) as u32;
    mesh.vertices.extend_from_slice(&[f64::NAN, 0.5, 0.5]);
    mesh.elements.extend_from_slice(&[0, 1, bad, 0, 1, 999]);
    mesh.particle.extend_from_slice(&[0, 0]);
    let mut geo = CutGeometry::new();
    compute(&grid, &mesh.surface(), &mut geo);
    assert_eq!(geo.diagnostics.n_skipped_elements, 2);
    assert!((volume_of(&grid, &geo) - 0.125).abs() <= 1e-14);
    // An empty surface gives an empty geometry.
    let empty = Mesh {
        dim: 3,
        vertices: vec![],
        elements: vec![],
        particle: vec![],
    };
    compute(&grid, &empty.surface(), &mut geo);
    assert!(geo.solid_fraction.iter().all(|&x| x == 0.0));
    assert!(geo.subfaces.is_empty());
}

#[test]
fn open_surface_is_reported() {
    // A box with its top removed: not closed, the defect is of order one.
    let grid = unit_grid(6);
    let mut mesh = box_mesh([0.2; 3], [0.7; 3]);
    mesh.elements.drain(6..12);
    mesh.particle.truncate(10);
    let mut geo = CutGeometry::new();
    compute(&grid, &mesh.surface(), &mut geo);
    assert!(geo.diagnostics.max_uncut_defect > 0.5);
}
