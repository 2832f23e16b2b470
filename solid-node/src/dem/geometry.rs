//! Mass properties of polygons and polyhedra, planar-face moments, and a small convex hull.
//!
//! All integrals are exact for straight-sided shapes: a polyhedron is cut into tetrahedra
//! (reference point, face centroid, edge), a polygon into triangles (centroid, edge). Faces must
//! be planar and star-shaped with respect to their centroid, particles star-shaped with respect
//! to their vertex mean (paper 003 §2.2 makes the same assumption).

use nalgebra::{Matrix2, Matrix3, Vector2, Vector3};
use protocol::scene::FaceInertia;
use protocol::sum::odd_sum;

/// Volume integrals of a polyhedron with unit density.
#[derive(Clone, Copy, Debug)]
pub struct PolyhedronMass {
    /// Volume \[m³\].
    pub volume: f64,
    /// Centroid \[m\].
    pub centroid: Vector3<f64>,
    /// Second moment `∫ (x − c)(x − c)ᵀ dV` about the centroid \[m⁵\].
    pub second_moment: Matrix3<f64>,
}

/// Integrals of a planar polygonal face.
#[derive(Clone, Copy, Debug)]
pub struct FaceMoments {
    /// Area \[m²\].
    pub area: f64,
    /// Centroid \[m\].
    pub centroid: Vector3<f64>,
    /// Unit normal from the right-hand rule on the vertex order.
    pub normal: Vector3<f64>,
    /// In-plane principal direction `s`.
    pub s: Vector3<f64>,
    /// In-plane principal direction `t = n × s`.
    pub t: Vector3<f64>,
    /// `∫ ((x − G)·s)² dA` \[m⁴\] (see [`FaceInertia`] for the other reading).
    pub i_s: f64,
    /// `∫ ((x − G)·t)² dA` \[m⁴\].
    pub i_t: f64,
}

/// Area-weighted centroid and vector area of a planar polygon (vertex loop).
fn polygon_area_centroid(points: &[Vector3<f64>]) -> (Vector3<f64>, f64, Vector3<f64>) {
    let mean = points.iter().sum::<Vector3<f64>>() / points.len() as f64;
    let mut vector_area = Vector3::zeros();
    let mut weighted = Vector3::zeros();
    for k in 0..points.len() {
        let a = points[k];
        let b = points[(k + 1) % points.len()];
        let tri = (a - mean).cross(&(b - mean)) * 0.5;
        vector_area += tri;
        let c = (mean + a + b) / 3.0;
        weighted += c * tri.norm();
    }
    let area = vector_area.norm();
    let centroid = if area > 0.0 { weighted / area } else { mean };
    (centroid, area, vector_area)
}

/// Moments of a planar face given by its vertex loop.
pub fn face_moments(points: &[Vector3<f64>]) -> FaceMoments {
    face_moments_with(points, FaceInertia::Exact)
}

/// Moments of a planar face, its second moments integrated as `inertia` says. Area, centroid
/// and normal are exact either way.
pub fn face_moments_with(points: &[Vector3<f64>], inertia: FaceInertia) -> FaceMoments {
    // NOTE: triangles fanned from the centroid; exact for planar faces star-shaped with
    // respect to that point (the papers assume star-shaped faces).
    let (centroid, area, vector_area) = polygon_area_centroid(points);
    let normal = vector_area.normalize();
    let mut second = Matrix3::zeros();
    for k in 0..points.len() {
        let p1 = points[k] - centroid;
        let p2 = points[(k + 1) % points.len()] - centroid;
        let tri_area = p1.cross(&p2).dot(&normal) * 0.5;
        // ∫_T x xᵀ dA = A/12 (Σ pᵢpᵢᵀ + (Σ pᵢ)(Σ pᵢ)ᵀ), here with p0 = 0; its ss entry is
        // A/6 (a² + ab + b²). The unweighted sum keeps (a² + ab + b²)/12, i.e. A = 1/2.
        let weight = match inertia {
            FaceInertia::Exact => tri_area / 12.0,
            FaceInertia::Unweighted => 1.0 / 24.0,
        };
        let sum = p1 + p2;
        second += (p1 * p1.transpose() + p2 * p2.transpose() + sum * sum.transpose()) * weight;
    }
    // In-plane basis, then the 2×2 principal directions.
    let seed = if normal.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let e1 = (seed - normal * normal.dot(&seed)).normalize();
    let e2 = normal.cross(&e1);
    let m = Matrix2::new(
        e1.dot(&(second * e1)),
        e1.dot(&(second * e2)),
        e2.dot(&(second * e1)),
        e2.dot(&(second * e2)),
    );
    let eig = m.symmetric_eigen();
    let v = eig.eigenvectors.column(0);
    let s = (e1 * v[0] + e2 * v[1]).normalize();
    let t = normal.cross(&s);
    FaceMoments {
        area,
        centroid,
        normal,
        s,
        t,
        i_s: s.dot(&(second * s)),
        i_t: t.dot(&(second * t)),
    }
}

/// Volume, centroid and second moment of a closed polyhedron whose faces are outward loops.
pub fn polyhedron_mass(vertices: &[Vector3<f64>], faces: &[Vec<u32>]) -> PolyhedronMass {
    let reference = vertices.iter().sum::<Vector3<f64>>() / vertices.len() as f64;
    let mut volume = 0.0;
    let mut first = Vector3::zeros();
    let mut second = Matrix3::zeros();
    let mut loop_points: Vec<Vector3<f64>> = Vec::new();
    for face in faces {
        loop_points.clear();
        loop_points.extend(face.iter().map(|&v| vertices[v as usize] - reference));
        let (fc, _, _) = polygon_area_centroid(&loop_points);
        for k in 0..loop_points.len() {
            let a = loop_points[k];
            let b = loop_points[(k + 1) % loop_points.len()];
            // Tetrahedron (0, fc, a, b), positive when the loop is outward.
            let vol = fc.dot(&a.cross(&b)) / 6.0;
            volume += vol;
            let sum = fc + a + b;
            first += sum * (vol / 4.0);
            // ∫ x xᵀ dV = V/20 (Σ pᵢpᵢᵀ + (Σ pᵢ)(Σ pᵢ)ᵀ) with p0 = 0.
            second += (fc * fc.transpose()
                + a * a.transpose()
                + b * b.transpose()
                + sum * sum.transpose())
                * (vol / 20.0);
        }
    }
    let c_rel = first / volume;
    let second_c = second - c_rel * c_rel.transpose() * volume;
    PolyhedronMass {
        volume,
        centroid: reference + c_rel,
        second_moment: second_c,
    }
}

/// Area, centroid and polar moment `∫ |x − c|² dA` of a counter-clockwise polygon.
///
/// NOTE: every sum is independent of the order of its terms ([`odd_sum`]), so the result does
/// not depend on the vertex the loop starts at, and the mirror image of a polygon (its loop
/// reversed to stay counter-clockwise) gets the mirrored centroid and the same area and moment
/// to the bit: a symmetric body is built symmetric.
pub fn polygon_mass(points: &[Vector2<f64>]) -> (f64, Vector2<f64>, f64) {
    let n = points.len();
    let mut xs: Vec<f64> = points.iter().map(|p| p.x).collect();
    let mut ys: Vec<f64> = points.iter().map(|p| p.y).collect();
    let reference = Vector2::new(odd_sum(&mut xs), odd_sum(&mut ys)) / n as f64;
    let mut area = Vec::with_capacity(n);
    let mut first_x = Vec::with_capacity(n);
    let mut first_y = Vec::with_capacity(n);
    let mut polar = Vec::with_capacity(n);
    for k in 0..n {
        let a = points[k] - reference;
        let b = points[(k + 1) % n] - reference;
        let tri = 0.5 * (a.x * b.y - a.y * b.x);
        area.push(tri);
        first_x.push((a.x + b.x) * (tri / 3.0));
        first_y.push((a.y + b.y) * (tri / 3.0));
        // ∫_T |x|² dA = A/6 (|a|² + a·b + |b|²) with the third vertex at 0.
        let mut sq = [
            a.x * a.x,
            a.y * a.y,
            a.x * b.x,
            a.y * b.y,
            b.x * b.x,
            b.y * b.y,
        ];
        polar.push(tri / 6.0 * odd_sum(&mut sq));
    }
    let area = odd_sum(&mut area);
    let c_rel = Vector2::new(odd_sum(&mut first_x), odd_sum(&mut first_y)) / area;
    let polar = odd_sum(&mut polar);
    (area, reference + c_rel, polar - area * c_rel.norm_squared())
}

/// Inertia tensor `ρ (tr(J) 1 − J)` from a second moment `J`.
pub fn inertia_from_second_moment(second: &Matrix3<f64>, density: f64) -> Matrix3<f64> {
    (Matrix3::identity() * second.trace() - second) * density
}

/// Why the points of an explicit 3-D particle have no convex hull.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum HullError {
    /// Fewer than 4 points.
    #[error("a 3-D particle needs at least 4 vertices, got {n_vertices}")]
    TooFewVertices {
        /// The number of points given.
        n_vertices: usize,
    },
    /// All points lie in one plane.
    #[error("the particle's vertices are coplanar")]
    Coplanar,
}

/// Faces of the convex hull of `points` as outward vertex loops (indices into `points`).
///
/// O(n⁴) brute force, meant for the few vertices of one explicit particle. Coplanar hull points
/// are merged into one polygonal face.
pub fn convex_hull_faces(points: &[Vector3<f64>]) -> Result<Vec<Vec<u32>>, HullError> {
    let n = points.len();
    if n < 4 {
        return Err(HullError::TooFewVertices { n_vertices: n });
    }
    let scale = points
        .iter()
        .map(|p| (p - points[0]).norm())
        .fold(0.0, f64::max);
    let tol = 1e-9 * scale.max(f64::MIN_POSITIVE);
    let mut planes: Vec<(Vector3<f64>, f64)> = Vec::new();
    let mut faces = Vec::new();
    for i in 0..n {
        for j in (i + 1)..n {
            for k in (j + 1)..n {
                let nrm = (points[j] - points[i]).cross(&(points[k] - points[i]));
                if nrm.norm() <= tol * scale {
                    continue;
                }
                let nrm = nrm.normalize();
                let off = nrm.dot(&points[i]);
                let above = points.iter().filter(|p| nrm.dot(p) - off > tol).count();
                let below = points.iter().filter(|p| nrm.dot(p) - off < -tol).count();
                let (nrm, off) = match (above, below) {
                    (0, _) => (nrm, off),
                    (_, 0) => (-nrm, -off),
                    _ => continue,
                };
                if planes
                    .iter()
                    .any(|(m, o)| (m - nrm).norm() < 1e-9 && (o - off).abs() < tol)
                {
                    continue;
                }
                planes.push((nrm, off));
                let on: Vec<u32> = (0..n as u32)
                    .filter(|&p| (nrm.dot(&points[p as usize]) - off).abs() <= tol)
                    .collect();
                let c =
                    on.iter().map(|&p| points[p as usize]).sum::<Vector3<f64>>() / on.len() as f64;
                let e1 = (points[on[0] as usize] - c).normalize();
                let e2 = nrm.cross(&e1);
                let mut sorted: Vec<(f64, u32)> = on
                    .iter()
                    .map(|&p| {
                        let d = points[p as usize] - c;
                        (d.dot(&e2).atan2(d.dot(&e1)), p)
                    })
                    .collect();
                sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
                faces.push(sorted.into_iter().map(|(_, p)| p).collect());
            }
        }
    }
    if faces.len() < 4 {
        return Err(HullError::Coplanar);
    }
    Ok(faces)
}
