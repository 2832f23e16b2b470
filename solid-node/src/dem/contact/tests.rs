//! Kernel tests of the narrow and broad phases: known overlaps, gradients against finite
//! differences, closure (Newton's third law for moments), and the broad phase against brute
//! force.

use nalgebra::{Rotation3, Vector2, Vector3};

use super::broad::{Grid, candidate_pairs};
use super::overlap::{
    ClipScratch, Overlap, PolyhedronView, contact_polygon_polygon, contact_polyhedron_polyhedron,
};

fn square(center: Vector2<f64>, half: f64, angle: f64) -> Vec<Vector2<f64>> {
    let (s, c) = angle.sin_cos();
    [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
        .iter()
        .map(|&(x, y)| {
            let (x, y) = (x * half, y * half * 0.7);
            center + Vector2::new(c * x - s * y, s * x + c * y)
        })
        .collect()
}

fn overlap_2d(ca: Vector2<f64>, ta: f64, cb: Vector2<f64>, tb: f64) -> Overlap {
    let mut scratch = ClipScratch::default();
    contact_polygon_polygon(
        &square(ca, 0.5, ta),
        ca,
        &square(cb, 0.5, tb),
        cb,
        1e-12,
        &mut scratch,
    )
}

/// A box of half sizes (0.5, 0.35, 0.3) rotated by `rot` about its centre.
struct Block {
    vertices: Vec<Vector3<f64>>,
    ranges: Vec<(u32, u32)>,
    loops: Vec<u32>,
    planes: Vec<(Vector3<f64>, f64)>,
    center: Vector3<f64>,
}

fn block(center: Vector3<f64>, rot: Rotation3<f64>) -> Block {
    let h = Vector3::new(0.5, 0.35, 0.3);
    let mut vertices = Vec::new();
    for k in 0..2 {
        for j in 0..2 {
            for i in 0..2 {
                let local = Vector3::new(
                    if i == 0 { -h.x } else { h.x },
                    if j == 0 { -h.y } else { h.y },
                    if k == 0 { -h.z } else { h.z },
                );
                vertices.push(center + rot * local);
            }
        }
    }
    let p = |i: u32, j: u32, k: u32| i + 2 * j + 4 * k;
    let faces = [
        [p(0, 0, 0), p(0, 0, 1), p(0, 1, 1), p(0, 1, 0)],
        [p(1, 0, 0), p(1, 1, 0), p(1, 1, 1), p(1, 0, 1)],
        [p(0, 0, 0), p(1, 0, 0), p(1, 0, 1), p(0, 0, 1)],
        [p(0, 1, 0), p(0, 1, 1), p(1, 1, 1), p(1, 1, 0)],
        [p(0, 0, 0), p(0, 1, 0), p(1, 1, 0), p(1, 0, 0)],
        [p(0, 0, 1), p(1, 0, 1), p(1, 1, 1), p(0, 1, 1)],
    ];
    let mut loops = Vec::new();
    let mut ranges = Vec::new();
    let mut planes = Vec::new();
    for f in faces {
        ranges.push((loops.len() as u32, 4));
        loops.extend_from_slice(&f);
        let v: Vec<Vector3<f64>> = f.iter().map(|&i| vertices[i as usize]).collect();
        let n = (v[1] - v[0]).cross(&(v[2] - v[0])).normalize();
        planes.push((n, n.dot(&v[0])));
    }
    Block {
        vertices,
        ranges,
        loops,
        planes,
        center,
    }
}

fn overlap_3d(a: &Block, b: &Block) -> Overlap {
    contact_polyhedron_polyhedron(&view(a), &view(b), 1e-12, &mut ClipScratch::default())
}

fn view(k: &Block) -> PolyhedronView<'_> {
    PolyhedronView {
        vertices: &k.vertices,
        face_ranges: &k.ranges,
        face_vertices: &k.loops,
        planes: &k.planes,
        center: k.center,
    }
}

fn rot(v: [f64; 3]) -> Rotation3<f64> {
    Rotation3::new(Vector3::from(v))
}

#[test]
fn aligned_squares_and_boxes_overlap_by_the_slab() {
    let o = overlap_2d(Vector2::zeros(), 0.0, Vector2::new(0.9, 0.0), 0.0);
    assert!((o.volume - 0.1 * 0.7).abs() < 1e-15, "{o:?}");
    assert!((o.grad_b - Vector3::new(-0.7, 0.0, 0.0)).norm() < 1e-15);
    assert!((o.centroid - Vector3::new(0.45, 0.0, 0.0)).norm() < 1e-15);
    let apart = overlap_2d(Vector2::zeros(), 0.0, Vector2::new(1.01, 0.0), 0.0);
    assert_eq!(apart.volume, 0.0);
    let a = block(Vector3::zeros(), rot([0.0; 3]));
    let b = block(Vector3::new(0.0, 0.0, 0.55), rot([0.0; 3]));
    let o = overlap_3d(&a, &b);
    assert!((o.volume - 1.0 * 0.7 * 0.05).abs() < 1e-15, "{o:?}");
    assert!((o.grad_b - Vector3::new(0.0, 0.0, -0.7)).norm() < 1e-14);
    assert_eq!(
        overlap_3d(&a, &block(Vector3::new(0.0, 0.0, 0.61), rot([0.0; 3]))).volume,
        0.0
    );
}

#[test]
fn gradients_match_finite_differences_2d() {
    let (ca, ta) = (Vector2::new(0.1, -0.05), 0.3);
    let (cb, tb) = (Vector2::new(0.75, 0.3), -0.4);
    let o = overlap_2d(ca, ta, cb, tb);
    assert!(o.volume > 0.01);
    let h = 1e-6;
    let fd = |f: &dyn Fn(f64) -> f64| (f(h) - f(-h)) / (2.0 * h);
    let gx = fd(&|e| overlap_2d(ca, ta, cb + Vector2::new(e, 0.0), tb).volume);
    let gy = fd(&|e| overlap_2d(ca, ta, cb + Vector2::new(0.0, e), tb).volume);
    let gta = fd(&|e| overlap_2d(ca, ta + e, cb, tb).volume);
    let gtb = fd(&|e| overlap_2d(ca, ta, cb, tb + e).volume);
    let gax = fd(&|e| overlap_2d(ca + Vector2::new(e, 0.0), ta, cb, tb).volume);
    assert!((o.grad_b.x - gx).abs() < 1e-8, "{} {gx}", o.grad_b.x);
    assert!((o.grad_b.y - gy).abs() < 1e-8, "{} {gy}", o.grad_b.y);
    assert!((-o.grad_b.x - gax).abs() < 1e-8);
    assert!(
        (o.grad_rot_a.z - gta).abs() < 1e-8,
        "{} {gta}",
        o.grad_rot_a.z
    );
    assert!(
        (o.grad_rot_b.z - gtb).abs() < 1e-8,
        "{} {gtb}",
        o.grad_rot_b.z
    );
    // Moments about the origin cancel: ∫ x × n over the closed boundary is zero.
    let (ca3, cb3) = (Vector3::new(ca.x, ca.y, 0.0), Vector3::new(cb.x, cb.y, 0.0));
    let total = o.grad_rot_a + o.grad_rot_b + ca3.cross(&-o.grad_b) + cb3.cross(&o.grad_b);
    assert!(total.norm() < 1e-15, "{total}");
}

#[test]
fn gradients_match_finite_differences_3d() {
    let ra = rot([0.3, -0.2, 0.5]);
    let rb = rot([-0.4, 0.25, 0.1]);
    let ca = Vector3::new(0.02, -0.03, 0.01);
    let cb = Vector3::new(0.6, 0.3, 0.25);
    let vol = |ca: Vector3<f64>, ra: Rotation3<f64>, cb: Vector3<f64>, rb: Rotation3<f64>| {
        overlap_3d(&block(ca, ra), &block(cb, rb)).volume
    };
    let o = overlap_3d(&block(ca, ra), &block(cb, rb));
    assert!(o.volume > 0.01, "{o:?}");
    let h = 1e-6;
    for axis in 0..3 {
        let mut e = Vector3::zeros();
        e[axis] = h;
        let g = (vol(ca, ra, cb + e, rb) - vol(ca, ra, cb - e, rb)) / (2.0 * h);
        assert!(
            (o.grad_b[axis] - g).abs() < 1e-8,
            "{axis}: {} {g}",
            o.grad_b[axis]
        );
        let ga = (vol(ca + e, ra, cb, rb) - vol(ca - e, ra, cb, rb)) / (2.0 * h);
        assert!((-o.grad_b[axis] - ga).abs() < 1e-8);
        // Rotation about the centre: space-frame increment.
        let mut w = [0.0; 3];
        w[axis] = h;
        let mut wm = [0.0; 3];
        wm[axis] = -h;
        let gb = (vol(ca, ra, cb, rot(w) * rb) - vol(ca, ra, cb, rot(wm) * rb)) / (2.0 * h);
        assert!(
            (o.grad_rot_b[axis] - gb).abs() < 1e-8,
            "{axis}: {} {gb}",
            o.grad_rot_b[axis]
        );
        let gra = (vol(ca, rot(w) * ra, cb, rb) - vol(ca, rot(wm) * ra, cb, rb)) / (2.0 * h);
        assert!((o.grad_rot_a[axis] - gra).abs() < 1e-8);
    }
    let total = o.grad_rot_a + o.grad_rot_b + ca.cross(&-o.grad_b) + cb.cross(&o.grad_b);
    assert!(total.norm() < 1e-14, "{total}");
}

#[test]
fn broad_phase_finds_exactly_the_brute_force_pairs() {
    let mut seed = 7u64;
    let mut next = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    for dim in [2usize, 3] {
        let n = 2000;
        let centers: Vec<[f64; 3]> = (0..n)
            .map(|_| {
                let mut c = [next() * 4.0 - 2.0, next() * 4.0 - 2.0, next() * 4.0 - 2.0];
                if dim == 2 {
                    c[2] = 0.0;
                }
                c
            })
            .collect();
        let radii: Vec<f64> = (0..n).map(|_| 0.02 + 0.06 * next()).collect();
        let mut pairs = Vec::new();
        candidate_pairs(dim, &centers, &radii, &mut Grid::default(), &mut pairs);
        let mut brute = Vec::new();
        for i in 0..n {
            for j in i + 1..n {
                let d2: f64 = (0..dim)
                    .map(|a| (centers[i][a] - centers[j][a]).powi(2))
                    .sum();
                if d2 < (radii[i] + radii[j]).powi(2) {
                    brute.push((i as u32, j as u32));
                }
            }
        }
        let mut sorted = pairs.clone();
        sorted.sort_unstable();
        assert!(brute.len() > 100, "{dim}-D: {} pairs", brute.len());
        assert_eq!(sorted, brute, "{dim}-D");
    }
}

#[test]
fn aligned_neighbours_get_no_lateral_force_from_round_off() {
    // Two equal rotated boxes side by side along their own x axis: their y and z faces are
    // coplanar, where V has a kink; the gradient must be the symmetric one, along x only.
    let r = rot([0.3, -0.7, 1.1]);
    let a = block(Vector3::new(0.1, 0.2, 0.3), r);
    let b = block(
        Vector3::new(0.1, 0.2, 0.3) + r * Vector3::new(0.97, 0.0, 0.0),
        r,
    );
    let o = overlap_3d(&a, &b);
    let along = r * Vector3::new(-0.7 * 0.6, 0.0, 0.0);
    assert!((o.volume - 0.03 * 0.42).abs() < 1e-15, "{o:?}");
    assert!((o.grad_b - along).norm() < 1e-14, "{} vs {along}", o.grad_b);
    let (s, c) = 0.9f64.sin_cos();
    let ca = Vector2::new(0.3, -0.2);
    let cb = ca + Vector2::new(c, s) * 0.97;
    let o = overlap_2d(ca, 0.9, cb, 0.9);
    let along = Vector3::new(-c * 0.7, -s * 0.7, 0.0);
    assert!((o.grad_b - along).norm() < 1e-14, "{} vs {along}", o.grad_b);
}

#[test]
fn touching_and_slab_overlapping_boxes_perturbed_near_the_tolerance() {
    // Aligned equal boxes (sizes 1 × 0.7 × 0.6) offset along each axis by 0 (full overlap),
    // ±(size − 0.05) (a slab) or ±size (touching: face, edge or corner neighbours, overlap 0),
    // then moved and turned by `eps` (round-off, and around the clipping's `tol` = 1e-12 where
    // points within `tol` outside a plane count as on it). The overlap is the aligned one to
    // within the perturbation: every boundary point moves by at most ~2 eps, over a boundary of
    // area at most 3.44, so |ΔV| < 7 eps (2-D: at most 2 eps over a length at most 3.4). (A cut point once extrapolated from a vertex within
    // `tol` outside a plane threw the overlap of touching boxes up to a third of a box.)
    let mut seed = 11u64;
    let mut next = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let size: [f64; 3] = [1.0, 0.7, 0.6];
    let offsets = |axis: usize| {
        let h = size[axis];
        [-h, -(h - 0.05), 0.0, h - 0.05, h]
    };
    let mut checked = 0;
    for ox in offsets(0) {
        for oy in offsets(1) {
            for oz in offsets(2) {
                let exact: f64 = [ox, oy, oz]
                    .iter()
                    .zip(size)
                    .map(|(o, h)| (h - o.abs()).max(0.0))
                    .product();
                for eps in [0.0, 1e-16, 1e-13, 1e-11] {
                    for _ in 0..20 {
                        let mut jitter = || Vector3::new(next(), next(), next()) * eps;
                        let ca = Vector3::new(0.3, 0.2, 0.1) + jitter();
                        let cb = Vector3::new(0.3 + ox, 0.2 + oy, 0.1 + oz) + jitter();
                        let (ra, rb) = (Rotation3::new(jitter()), Rotation3::new(jitter()));
                        let (a, b) = (block(ca, ra), block(cb, rb));
                        for v in [overlap_3d(&a, &b).volume, overlap_3d(&b, &a).volume] {
                            assert!(
                                (v - exact).abs() <= 7.0 * eps + 1e-15,
                                "offset ({ox}, {oy}, {oz}), eps {eps}: {v} vs {exact}"
                            );
                        }
                        checked += 1;
                    }
                }
            }
        }
    }
    assert_eq!(checked, 125 * 4 * 20);
    // The same in 2-D (rectangles 1 × 0.7), through the polygon clipping.
    for ox in offsets(0) {
        for oy in offsets(1) {
            let exact = (1.0 - ox.abs()).max(0.0) * (0.7 - oy.abs()).max(0.0);
            for eps in [0.0, 1e-16, 1e-13, 1e-11] {
                for _ in 0..20 {
                    let ca = Vector2::new(0.3 + next() * eps, 0.2 + next() * eps);
                    let cb = Vector2::new(0.3 + ox + next() * eps, 0.2 + oy + next() * eps);
                    let (ta, tb) = (next() * eps, next() * eps);
                    for v in [
                        overlap_2d(ca, ta, cb, tb).volume,
                        overlap_2d(cb, tb, ca, ta).volume,
                    ] {
                        assert!(
                            (v - exact).abs() <= 7.0 * eps + 1e-15,
                            "2-D offset ({ox}, {oy}), eps {eps}: {v} vs {exact}"
                        );
                    }
                }
            }
        }
    }
}
