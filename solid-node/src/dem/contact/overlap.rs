//! Narrow phase: the exact overlap of two convex particles and its gradient.
//!
//! The overlap `I = A ∩ B` of two convex polygons (2-D) or polyhedra (3-D) is built by clipping
//! `A` with every supporting half-space of `B` (Sutherland–Hodgman; in 3-D each clip also closes
//! the polytope with a cap on the clipping plane). Every boundary piece of `I` is tagged with the
//! particle whose boundary it lies on. Then, with `V = |I|`:
//!
//! - `∇_{X_B} V = ∫_{∂I ∩ ∂B} n dS` (moving `B` by `δ` sweeps its boundary inside `A` by `n·δ`),
//!   and `∇_{X_A} V = −∇_{X_B} V` (the boundary of `I` is closed);
//! - `∇_{θ_K} V = ∫_{∂I ∩ ∂K} (x − X_K) × n dS` for a rotation of `K` about its centre.
//!
//! These are exact for straight-sided convex shapes (the overlap volume of convex bodies is
//! C¹ in their poses), so a potential `U(V)` gives forces and torques that are its exact
//! negative gradient, which conserve linear and angular momentum (`∫_{∂I} x × n dS = 0`).
//!
//! NOTE: clipping rather than GJK/EPA: the contact law ([`super`]) derives from the overlap
//! volume, which a depth-and-point query (parry's `contact`) does not give; clipping convex
//! polytopes is exact, has no iteration and no tolerance. Points on a clipping plane count as
//! inside; an edge crossing a plane is cut from its inside end, so the two faces sharing the
//! edge produce the same bits and the cap's duplicate points are removed exactly.
//!
//! NOTE: where a face of `A` lies on a face plane of `B` (aligned blocks side by side), `V` has
//! a kink: its one-sided derivatives are 0 and the full face. Such a face, within `tol` of the
//! plane, counts half for each particle (the mean of the two), which keeps the lateral force of
//! aligned neighbours zero instead of a side chosen by round-off. Points within `tol` of a
//! plane count as on it.

use nalgebra::{Vector2, Vector3};

/// What the contact law needs of one overlap.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Overlap {
    /// Overlap volume V \[m³\] (2-D: area per unit depth \[m²\]); 0 when apart.
    pub volume: f64,
    /// Centroid of the overlap \[m\] (meaningful when `volume > 0`).
    pub centroid: Vector3<f64>,
    /// `∇_{X_B} V` \[m²\] (2-D: \[m\], z = 0); `∇_{X_A} V` is its opposite.
    pub grad_b: Vector3<f64>,
    /// `∇_{θ_A} V` about `A`'s centre \[m³\] (2-D: z only).
    pub grad_rot_a: Vector3<f64>,
    /// `∇_{θ_B} V` about `B`'s centre \[m³\] (2-D: z only).
    pub grad_rot_b: Vector3<f64>,
}

/// Which particle a boundary piece of the overlap lies on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Side {
    A,
    B,
    /// On both boundaries (a face of `A` on a supporting plane of `B`, same outward side).
    Both,
}

/// Reusable buffers of the clipping (one set per thread; no allocation once warm).
#[derive(Clone, Debug, Default)]
pub struct ClipScratch {
    pts: Vec<Vector3<f64>>,
    tags: Vec<Side>,
    next_pts: Vec<Vector3<f64>>,
    next_tags: Vec<Side>,
    /// 3-D: faces as `(start, len, side)` into `pts`.
    faces: Vec<(u32, u32, Side)>,
    next_faces: Vec<(u32, u32, Side)>,
    cap: Vec<(f64, Vector3<f64>)>,
}

/// Overlap of two convex counter-clockwise polygons `a` and `b` (world coordinates, z ignored)
/// with centres `center_a`, `center_b`.
pub fn contact_polygon_polygon(
    a: &[Vector2<f64>],
    center_a: Vector2<f64>,
    b: &[Vector2<f64>],
    center_b: Vector2<f64>,
    tol: f64,
    scratch: &mut ClipScratch,
) -> Overlap {
    let ClipScratch {
        pts,
        tags,
        next_pts,
        next_tags,
        ..
    } = scratch;
    pts.clear();
    tags.clear();
    for p in a {
        pts.push(Vector3::new(p.x, p.y, 0.0));
        tags.push(Side::A);
    }
    let n_b = b.len();
    for k in 0..n_b {
        let (p, q) = (b[k], b[(k + 1) % n_b]);
        let e = q - p;
        // Outward normal of a counter-clockwise edge; inside: n·x ≤ n·p.
        let normal = Vector3::new(e.y, -e.x, 0.0);
        let offset = normal.x * p.x + normal.y * p.y;
        let tol_k = tol * normal.norm();
        next_pts.clear();
        next_tags.clear();
        let m = pts.len();
        for i in 0..m {
            let (p0, p1) = (pts[i], pts[(i + 1) % m]);
            let (d0, d1) = (normal.dot(&p0) - offset, normal.dot(&p1) - offset);
            let (in0, in1) = (d0 <= tol_k, d1 <= tol_k);
            if in0 {
                next_pts.push(p0);
                let on_plane = in1 && d0.abs() <= tol_k && d1.abs() <= tol_k;
                next_tags.push(if on_plane && tags[i] == Side::A {
                    Side::Both
                } else {
                    tags[i]
                });
                if !in1 {
                    next_pts.push(cut(p0, d0, p1, d1));
                    next_tags.push(Side::B);
                }
            } else if in1 {
                next_pts.push(cut(p1, d1, p0, d0));
                next_tags.push(tags[i]);
            }
        }
        std::mem::swap(pts, next_pts);
        std::mem::swap(tags, next_tags);
        if pts.len() < 3 {
            return Overlap::default();
        }
    }
    // Area and centroid by a fan from the first vertex; boundary integrals per tagged edge.
    let o = pts[0];
    let mut area2 = 0.0;
    let mut first = Vector3::zeros();
    let m = pts.len();
    let ca = Vector3::new(center_a.x, center_a.y, 0.0);
    let cb = Vector3::new(center_b.x, center_b.y, 0.0);
    let mut res = Overlap::default();
    for i in 0..m {
        let (p, q) = (pts[i], pts[(i + 1) % m]);
        let (u, w) = (p - o, q - o);
        let tri2 = u.x * w.y - u.y * w.x;
        area2 += tri2;
        first += (o + p + q) * tri2;
        let e = q - p;
        let n_len = Vector3::new(e.y, -e.x, 0.0);
        let mid = (p + q) * 0.5;
        let (wa, wb) = weights(tags[i]);
        res.grad_b += n_len * wb;
        res.grad_rot_b.z += wb * cross_z(&(mid - cb), &n_len);
        res.grad_rot_a.z += wa * cross_z(&(mid - ca), &n_len);
    }
    if area2 <= 0.0 {
        return Overlap::default();
    }
    res.volume = 0.5 * area2;
    res.centroid = first / (3.0 * area2);
    res
}

/// A convex polyhedron seen by the clipping: its faces as outward vertex loops and its
/// supporting planes `(n, d)` with `n·x ≤ d` inside (world coordinates).
#[derive(Clone, Copy, Debug)]
pub struct PolyhedronView<'a> {
    /// Vertex positions.
    pub vertices: &'a [Vector3<f64>],
    /// Per face, the range of its loop in `face_vertices`.
    pub face_ranges: &'a [(u32, u32)],
    /// Vertex indices of all loops.
    pub face_vertices: &'a [u32],
    /// Per face, outward unit normal and offset.
    pub planes: &'a [(Vector3<f64>, f64)],
    /// Centre of mass.
    pub center: Vector3<f64>,
}

/// Overlap of two convex polyhedra.
pub fn contact_polyhedron_polyhedron(
    a: &PolyhedronView<'_>,
    b: &PolyhedronView<'_>,
    tol: f64,
    scratch: &mut ClipScratch,
) -> Overlap {
    let ClipScratch {
        pts,
        next_pts,
        faces,
        next_faces,
        cap,
        ..
    } = scratch;
    pts.clear();
    faces.clear();
    for &(start, len) in a.face_ranges {
        let begin = pts.len() as u32;
        for &v in &a.face_vertices[start as usize..(start + len) as usize] {
            pts.push(a.vertices[v as usize]);
        }
        faces.push((begin, len, Side::A));
    }
    for &(normal, offset) in b.planes {
        next_pts.clear();
        next_faces.clear();
        cap.clear();
        for &(start, len, side) in faces.iter() {
            let begin = next_pts.len() as u32;
            let face = &pts[start as usize..(start + len) as usize];
            let m = face.len();
            let mut on_plane = true;
            for i in 0..m {
                let (p0, p1) = (face[i], face[(i + 1) % m]);
                let (d0, d1) = (normal.dot(&p0) - offset, normal.dot(&p1) - offset);
                on_plane &= d0.abs() <= tol;
                let (in0, in1) = (d0 <= tol, d1 <= tol);
                if in0 {
                    next_pts.push(p0);
                    if !in1 {
                        let c = cut(p0, d0, p1, d1);
                        next_pts.push(c);
                        cap.push((0.0, c));
                    }
                } else if in1 {
                    let c = cut(p1, d1, p0, d0);
                    next_pts.push(c);
                    cap.push((0.0, c));
                }
            }
            let n_new = next_pts.len() as u32 - begin;
            if n_new >= 3 {
                let side = if on_plane && side == Side::A {
                    Side::Both
                } else {
                    side
                };
                next_faces.push((begin, n_new, side));
            } else {
                next_pts.truncate(begin as usize);
            }
        }
        if cap.len() >= 3 {
            // Order the cap counter-clockwise about the plane's normal (outward of the overlap).
            let mut mean = Vector3::zeros();
            for (_, p) in cap.iter() {
                mean += p;
            }
            mean /= cap.len() as f64;
            let u = any_perpendicular(&normal);
            let w = normal.cross(&u);
            for (angle, p) in cap.iter_mut() {
                let r = *p - mean;
                *angle = r.dot(&w).atan2(r.dot(&u));
            }
            cap.sort_by(|x, y| {
                x.0.total_cmp(&y.0).then_with(|| {
                    (x.1.x, x.1.y, x.1.z)
                        .partial_cmp(&(y.1.x, y.1.y, y.1.z))
                        .unwrap_or(std::cmp::Ordering::Equal)
                })
            });
            cap.dedup_by(|x, y| x.1 == y.1);
            if cap.len() >= 3 {
                let begin = next_pts.len() as u32;
                next_pts.extend(cap.iter().map(|(_, p)| *p));
                next_faces.push((begin, cap.len() as u32, Side::B));
            }
        }
        if next_faces.len() < 4 {
            return Overlap::default();
        }
        std::mem::swap(pts, next_pts);
        std::mem::swap(faces, next_faces);
    }
    let o = pts[faces[0].0 as usize];
    let mut vol6 = 0.0;
    let mut first = Vector3::zeros();
    let mut res = Overlap::default();
    for &(start, len, side) in faces.iter() {
        let face = &pts[start as usize..(start + len) as usize];
        let p0 = face[0];
        for k in 1..face.len() - 1 {
            let (p1, p2) = (face[k], face[k + 1]);
            let t6 = (p0 - o).dot(&(p1 - o).cross(&(p2 - o)));
            vol6 += t6;
            first += (o + p0 + p1 + p2) * t6;
            let area = (p1 - p0).cross(&(p2 - p0)) * 0.5;
            let g = (p0 + p1 + p2) / 3.0;
            let (wa, wb) = weights(side);
            res.grad_b += area * wb;
            res.grad_rot_b += (g - b.center).cross(&area) * wb;
            res.grad_rot_a += (g - a.center).cross(&area) * wa;
        }
    }
    if vol6 <= 0.0 {
        return Overlap::default();
    }
    res.volume = vol6 / 6.0;
    res.centroid = first / (4.0 * vol6);
    res
}

/// Weights of a boundary piece in `A`'s and `B`'s gradients.
fn weights(side: Side) -> (f64, f64) {
    match side {
        Side::A => (1.0, 0.0),
        Side::B => (0.0, 1.0),
        Side::Both => (0.5, 0.5),
    }
}

/// The point where the segment from `inside` (signed distance `d_in ≤ tol`) to `outside`
/// (`d_out > tol`) crosses the plane, computed from the inside end (same bits from either face).
/// An inside end within `tol` outside the plane counts as on it and is the cut point itself:
/// the segment does not cross the plane between its ends, and `t = d_in / (d_in − d_out)` would
/// be negative, of size `d_in / (d_out − d_in)` ≫ 1 when the segment is nearly parallel to the
/// plane (a face tilted by more than `tol` across it), throwing the point far behind the inside
/// end: the 3-D cap then no longer closes the polytope and its volume is anything.
fn cut(inside: Vector3<f64>, d_in: f64, outside: Vector3<f64>, d_out: f64) -> Vector3<f64> {
    let t = d_in.min(0.0) / (d_in - d_out);
    inside + (outside - inside) * t
}

fn cross_z(a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    a.x * b.y - a.y * b.x
}

/// A unit vector perpendicular to the unit vector `n`.
fn any_perpendicular(n: &Vector3<f64>) -> Vector3<f64> {
    let helper = if n.x.abs() < 0.6 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    (helper - n * n.dot(&helper)).normalize()
}
