//! Cut-cell geometry in 2-D: Σ Λ A against exact polygon areas (square, rotated rectangle,
//! regular polygon, several bodies, bodies crossing the domain boundary), face fractions against
//! exact chord lengths, identity (19)–(20) in every cell, and the degenerate cases (vertices on
//! grid lines, segments along grid lines, slivers, internal segments carried on both sides).

#![allow(clippy::needless_range_loop)]

use crate::cutcell_support;

use cutcell_support::*;
use fluid_node::cutcell::{CutGeometry, compute, face_index};
use fluid_node::grid::Grid;

const TOL: f64 = 1e-12;

fn check(grid: &Grid, mesh: &Mesh, exact: f64) -> CutGeometry {
    let mut geo = CutGeometry::new();
    compute(grid, &mesh.surface(), &mut geo);
    let err = (volume_of(grid, &geo) - exact).abs() / exact;
    let identity = identity_residual(grid, &geo);
    eprintln!("area err {err:.2e}, identity {identity:.2e}");
    assert!(err <= TOL, "area error {err}");
    assert!(identity <= TOL, "identity residual {identity}");
    assert_eq!(geo.diagnostics.max_uncut_defect, 0.0);
    assert!(
        geo.solid_fraction
            .iter()
            .all(|x| x.is_finite() && (0.0..=1.0).contains(x))
    );
    geo
}

fn grid(n: [usize; 2]) -> Grid {
    Grid::new(&[0.0, 0.0], &[1.0, 1.0], &n).unwrap()
}

#[test]
fn rectangle_fractions_are_exact() {
    let g = grid([10, 8]);
    let mesh = loop_mesh(&[[0.23, 0.31], [0.77, 0.31], [0.77, 0.58], [0.23, 0.58]]);
    let geo = check(&g, &mesh, 0.54 * 0.27);
    // Cell (2, 2): x 0.2..0.3, y 0.25..0.375 → (0.07 × 0.065) / (0.1 × 0.125).
    let expected = 0.07 * 0.065 / (0.1 * 0.125);
    assert!((geo.solid_fraction[g.index(2, 2, 0)] - expected).abs() < 1e-14);
    assert_eq!(geo.solid_fraction[g.index(4, 3, 0)], 1.0);
    // x-face x = 0.3 of row j = 2: solid part y 0.31..0.375 of 0.125.
    let f = geo.face_fraction[0][face_index(&g, 0, [3, 2, 0])];
    assert!((f - 0.065 / 0.125).abs() < 1e-14);
    assert!(geo.face_fraction[2].is_empty());
    // Perimeter.
    assert!((geo.wet_area() - 2.0 * (0.54 + 0.27)).abs() < 1e-14);
}

#[test]
fn rotated_polygons_and_discs_match_exact_areas() {
    let g = grid([17, 13]);
    let mut rng = Rng(11);
    for _ in 0..20 {
        let r = rotation([0.0, 0.0, 1.0], rng.uniform(0.0, 6.3));
        let shift = [rng.uniform(-0.1, 0.1), rng.uniform(-0.1, 0.1), 0.0];
        let rect = loop_mesh(&[[0.25, 0.3], [0.75, 0.3], [0.75, 0.62], [0.25, 0.62]])
            .map(|p| rigid(p, &r, [0.5, 0.5, 0.0], shift));
        check(&g, &rect, 0.5 * 0.32);
        let disc = disc_mesh(
            [0.5 + shift[0], 0.5 + shift[1]],
            0.33,
            64,
            rng.uniform(0.0, 1.0),
        );
        check(&g, &disc, disc.enclosed_volume());
    }
}

#[test]
fn several_bodies_and_boundary_crossing() {
    let g = grid([20, 20]);
    let mut mesh = disc_mesh([0.25, 0.25], 0.15, 30, 0.0);
    mesh.append(&disc_mesh([0.7, 0.7], 0.2, 30, 0.3), 1);
    check(&g, &mesh, mesh.enclosed_volume());
    // A square sticking out of the left and bottom sides.
    let out = loop_mesh(&[[-0.3, -0.2], [0.41, -0.2], [0.41, 0.53], [-0.3, 0.53]]);
    check(&g, &out, 0.41 * 0.53);
    // A body containing the whole domain.
    let all = loop_mesh(&[[-1.0, -1.0], [2.0, -1.0], [2.0, 2.0], [-1.0, 2.0]]);
    let geo = check(&g, &all, 1.0);
    assert!(geo.solid_fraction.iter().all(|&x| x == 1.0));
    assert!(geo.cut_cells.is_empty());
}

#[test]
fn vertices_and_segments_on_grid_lines() {
    // Diamond with its vertices on grid nodes and a square with edges on grid lines.
    let g = grid([8, 8]);
    let diamond = loop_mesh(&[[0.5, 0.125], [0.875, 0.5], [0.5, 0.875], [0.125, 0.5]]);
    check(&g, &diamond, 2.0 * 0.375 * 0.375);
    let square = loop_mesh(&[[0.25, 0.25], [0.625, 0.25], [0.625, 0.75], [0.25, 0.75]]);
    let geo = check(&g, &square, 0.375 * 0.5);
    assert!(geo.solid_fraction.iter().all(|&x| x == 0.0 || x == 1.0));
    // Polygon with many vertices exactly on grid lines and a horizontal edge along y = 0.5.
    let poly = loop_mesh(&[
        [0.125, 0.5],
        [0.375, 0.25],
        [0.625, 0.5],
        [0.875, 0.5],
        [0.5, 0.875],
    ]);
    check(&g, &poly, poly.enclosed_volume());
}

#[test]
fn slivers_and_internal_segments() {
    let g = grid([9, 7]);
    // A square whose bottom edge is split at a point 1e-14 off the line (two sliver pieces).
    let sliver = loop_mesh(&[
        [0.2, 0.3],
        [0.5, 0.3 - 1e-14],
        [0.5 + 1e-15, 0.3],
        [0.8, 0.3],
        [0.8, 0.7],
        [0.2, 0.7],
    ]);
    check(&g, &sliver, sliver.enclosed_volume());
    // Two rectangles sharing the internal segment x = 0.47 (carried on both sides).
    let mut pair = loop_mesh(&[[0.2, 0.3], [0.47, 0.3], [0.47, 0.7], [0.2, 0.7]]);
    pair.append(
        &loop_mesh(&[[0.47, 0.3], [0.8, 0.3], [0.8, 0.7], [0.47, 0.7]]),
        1,
    );
    let geo = check(&g, &pair, 0.6 * 0.4);
    let mut single = CutGeometry::new();
    let whole = loop_mesh(&[[0.2, 0.3], [0.8, 0.3], [0.8, 0.7], [0.2, 0.7]]);
    compute(&g, &whole.surface(), &mut single);
    for (a, b) in geo.solid_fraction.iter().zip(&single.solid_fraction) {
        assert!((a - b).abs() <= 1e-14);
    }
    for axis in 0..2 {
        for (a, b) in geo.face_fraction[axis]
            .iter()
            .zip(&single.face_fraction[axis])
        {
            assert!((a - b).abs() <= 1e-14);
        }
    }
    // Degenerate (zero-length) segments and a non-finite vertex are harmless.
    let mut bad = whole.clone();
    bad.vertices.extend_from_slice(&[0.5, 0.5, f64::NAN, 0.1]);
    bad.elements.extend_from_slice(&[0, 0, 4, 5]);
    bad.particle.extend_from_slice(&[0, 0]);
    let mut geo = CutGeometry::new();
    compute(&g, &bad.surface(), &mut geo);
    assert_eq!(geo.diagnostics.n_skipped_elements, 1);
    assert!((volume_of(&g, &geo) - 0.24).abs() < 1e-14);
}

#[test]
fn face_fractions_are_exact_chords() {
    let g = grid([16, 16]);
    let disc = disc_mesh([0.49, 0.52], 0.35, 50, 0.2);
    let geo = check(&g, &disc, disc.enclosed_volume());
    // Chord of the polygon along each vertical grid line, against Σ λ dy.
    let pts: Vec<[f64; 2]> = disc.vertices.chunks(2).map(|p| [p[0], p[1]]).collect();
    for i in 0..=16 {
        let x0 = i as f64 / 16.0;
        let mut ys = Vec::new();
        for e in 0..pts.len() {
            let (p, q) = (pts[e], pts[(e + 1) % pts.len()]);
            if (p[0] - x0) * (q[0] - x0) < 0.0 {
                ys.push(p[1] + (x0 - p[0]) / (q[0] - p[0]) * (q[1] - p[1]));
            }
        }
        let chord = if ys.len() == 2 {
            (ys[0] - ys[1]).abs()
        } else {
            0.0
        };
        let sum: f64 = (0..16)
            .map(|j| geo.face_fraction[0][face_index(&g, 0, [i, j, 0])] / 16.0)
            .sum();
        assert!((sum - chord).abs() <= 1e-14, "x = {x0}: {sum} vs {chord}");
    }
}

/// A ring (outer loop counter-clockwise, inner loop clockwise) symmetric about y = 0 on a grid
/// centred there: Λ, λ and the sub-faces of mirrored cells are mirror images to the bit (the
/// grid's coordinates from the nearer corner, canonical cut points, order-independent sums and
/// the running face fractions taken from the end on each face's side of the middle). In the
/// coordinates `lower + i dx` of before, Λ of 72 cut cells of this ring differed by up to 1e-13.
#[test]
fn a_ring_symmetric_about_the_middle_is_cut_mirror_exactly() {
    let (nx, ny) = (800, 400);
    let g = Grid::new(&[0.0, -7.5], &[30.0, 7.5], &[nx, ny]).unwrap();
    let n = 50;
    // One loop of `n` vertices at radius `r` about (20, 0), built mirror-exact: vertex n − k is
    // vertex k with y negated.
    let ring_loop = |r: f64| -> Vec<[f64; 2]> {
        let half: Vec<[f64; 2]> = (0..=n / 2)
            .map(|k| {
                let t = 2.0 * std::f64::consts::PI * (k as f64 + 0.5) / n as f64;
                [20.0 + r * t.cos(), r * t.sin()]
            })
            .collect();
        (0..n)
            .map(|k| {
                if k < n / 2 {
                    half[k]
                } else {
                    let m = half[n - 1 - k];
                    [m[0], -m[1]]
                }
            })
            .collect()
    };
    let mut mesh = loop_mesh(&ring_loop(5.1));
    let mut inner = ring_loop(5.0);
    inner.reverse();
    let offset = mesh.vertices.len() as u32 / 2;
    for p in &inner {
        mesh.vertices.extend_from_slice(p);
    }
    for i in 0..n as u32 {
        mesh.elements
            .extend_from_slice(&[offset + i, offset + (i + 1) % n as u32]);
        mesh.particle.push(0);
    }
    let mut geo = CutGeometry::new();
    compute(&g, &mesh.surface(), &mut geo);
    let exact = std::f64::consts::PI * (5.1f64.powi(2) - 5.0f64.powi(2));
    assert!((volume_of(&g, &geo) - exact).abs() <= 0.01 * exact);
    let mut cut = 0;
    for j in 0..ny {
        for i in 0..nx {
            let (a, b) = (g.index(i, j, 0), g.index(i, ny - 1 - j, 0));
            let (la, lb) = (geo.solid_fraction[a], geo.solid_fraction[b]);
            assert!(
                la == lb,
                "Λ of cells [{i}, {j}] and its mirror: {la:e} {lb:e}"
            );
            cut += usize::from(la > 0.0 && la < 1.0);
            let (fa, fb) = (
                geo.face_fraction[0][face_index(&g, 0, [i, j, 0])],
                geo.face_fraction[0][face_index(&g, 0, [i, ny - 1 - j, 0])],
            );
            assert!(fa == fb, "λ_x of face [{i}, {j}]: {fa:e} {fb:e}");
        }
    }
    for j in 0..=ny {
        for i in 0..nx {
            let (fa, fb) = (
                geo.face_fraction[1][face_index(&g, 1, [i, j, 0])],
                geo.face_fraction[1][face_index(&g, 1, [i, ny - j, 0])],
            );
            assert!(fa == fb, "λ_y of face [{i}, {j}]: {fa:e} {fb:e}");
        }
    }
    assert!(cut > 500, "{cut} cut cells");
    // The sub-faces, as (cell, area, normal, centroid) with y mirrored for the lower half.
    let key = |s: &fluid_node::cutcell::SubFace, flip: bool| {
        let [i, j, _] = g.ijk(s.cell as usize);
        let sign = if flip { -1.0 } else { 1.0 };
        let j = if flip { ny - 1 - j } else { j };
        (
            i,
            j,
            // NOTE: `+ 0.0` makes −0 and +0 one key (they compare equal).
            (s.area + 0.0).to_bits(),
            (s.normal[0] + 0.0).to_bits(),
            (sign * s.normal[1] + 0.0).to_bits(),
            (s.centroid[0] + 0.0).to_bits(),
            (sign * s.centroid[1] + 0.0).to_bits(),
        )
    };
    let mut upper: Vec<_> = geo
        .subfaces
        .iter()
        .filter(|s| g.ijk(s.cell as usize)[1] >= ny / 2)
        .map(|s| key(s, false))
        .collect();
    let mut lower: Vec<_> = geo
        .subfaces
        .iter()
        .filter(|s| g.ijk(s.cell as usize)[1] < ny / 2)
        .map(|s| key(s, true))
        .collect();
    upper.sort_unstable();
    lower.sort_unstable();
    assert_eq!(upper.len(), lower.len());
    if let Some(k) = (0..upper.len()).find(|&k| upper[k] != lower[k]) {
        panic!(
            "sub-faces of the two halves differ: {:?} against {:?}",
            upper[k], lower[k]
        );
    }
}

/// Two bodies pressed into each other (a penalty contact, walls flush and pushed together):
/// Λ and λ are integrals of the winding number, so the overlap counts twice: Λ and λ exceed 1
/// where it lies, Σ Λ A is the sum of the two areas, identity (19)–(20) holds in every cell,
/// and so does identity (3) when the overlap deepens or opens.
#[test]
fn overlapping_bodies_count_the_overlap_twice_and_keep_the_identities() {
    let g = grid([10, 10]);
    let a = loop_mesh(&[[0.2, 0.2], [0.53, 0.2], [0.53, 0.8], [0.2, 0.8]]);
    let b_at = |x0: f64| loop_mesh(&[[x0, 0.3], [0.8, 0.3], [0.8, 0.6], [x0, 0.6]]);
    let mut mesh = a.clone();
    mesh.append(&b_at(0.48), 1);
    let mut geo = CutGeometry::new();
    compute(&g, &mesh.surface(), &mut geo);
    let exact = 0.33 * 0.6 + 0.32 * 0.3;
    let err = (volume_of(&g, &geo) - exact).abs() / exact;
    let identity = identity_residual(&g, &geo);
    eprintln!("area err {err:.2e}, identity {identity:.2e}");
    assert!(err <= TOL, "area error {err}");
    assert!(identity <= TOL, "identity residual {identity}");
    assert_eq!(geo.diagnostics.max_uncut_defect, 0.0);
    // Cell (4, 3), x 0.4..0.5, y 0.3..0.4: A covers it, B its part x > 0.48.
    let l = geo.solid_fraction[g.index(4, 3, 0)];
    assert!((l - 1.2).abs() < 1e-14, "{l}");
    // Cell (5, 4), x 0.5..0.6: B covers it, A its part x < 0.53.
    let l = geo.solid_fraction[g.index(5, 4, 0)];
    assert!((l - 1.3).abs() < 1e-14, "{l}");
    // The face x = 0.5 of row 3 lies inside both.
    let f = geo.face_fraction[0][face_index(&g, 0, [5, 3, 0])];
    assert!((f - 2.0).abs() < 1e-14, "{f}");
    // Outside the overlap the fractions are those of one body.
    assert_eq!(geo.solid_fraction[g.index(3, 3, 0)], 1.0);
    assert_eq!(geo.solid_fraction[g.index(6, 3, 0)], 1.0);
    // Identity (3): B pushed deeper into A, then pulled out of it past a grid line.
    for (from, to) in [(0.48, 0.47), (0.48, 0.535)] {
        let (mut before, mut after) = (a.clone(), a.clone());
        before.append(&b_at(from), 1);
        after.append(&b_at(to), 1);
        let (residual, total) = swept_residual(&g, &before, &after);
        let expected = (from - to) * 0.3;
        assert!(residual <= 1e-12, "{from} -> {to}: residual {residual}");
        assert!(
            (total - expected).abs() <= 1e-14,
            "{from} -> {to}: {total} vs {expected}"
        );
    }
}
