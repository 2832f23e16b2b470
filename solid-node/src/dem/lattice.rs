//! Particle lattices built from the scene shapes: boxes cut into cuboids, a 2-D ring and a 3-D
//! tube one particle thick, and explicit particle lists.
//!
//! A lattice is pure geometry: shared vertices (deduplicated per body, so two bodies never
//! share a vertex and are never linked), and per particle its faces as outward vertex loops
//! (3-D) or its polygon's edges in counter-clockwise order (2-D).

use std::collections::BTreeMap;

use nalgebra::Vector3;
use protocol::scene::{BodyConfig, LinksConfig, Motion, ParticleSpec, Shape};

use crate::dem::geometry::{HullError, convex_hull_faces};

/// Why the bodies of a scene give no lattice.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum LatticeError {
    /// The scene is neither 2-D nor 3-D.
    #[error("the solid needs a 2-D or 3-D scene, found {dim}-D")]
    Dimension {
        /// The scene's dimension.
        dim: usize,
    },
    /// One body's shape is invalid.
    #[error("solid.bodies[{body}]: {error}")]
    Body {
        /// Index of the body in `solid.bodies`.
        body: usize,
        /// What is wrong with it.
        error: BodyError,
    },
    /// No body gave a particle.
    #[error("the solid has no particles")]
    NoParticles,
}

/// What is wrong with one body's shape (the text names the shape or the particle).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum BodyError {
    /// A box with the wrong number of coordinates or a size that is not positive.
    #[error("box: expected {dim} coordinates and positive sizes")]
    Box {
        /// The scene's dimension.
        dim: usize,
    },
    /// `divisions` with the wrong length or a zero.
    #[error("{shape}: expected {expected} positive divisions, found {found:?}")]
    Divisions {
        /// The shape (`box`, `ring`, `tube`).
        shape: &'static str,
        /// The number of divisions it takes.
        expected: usize,
        /// The divisions given.
        found: Vec<u32>,
    },
    /// A ring outside a 2-D scene or with radii out of order.
    #[error("ring: a 2-D centre and 0 < inner_radius < outer_radius")]
    Ring,
    /// A tube outside a 3-D scene, or with an invalid axis, radii or length.
    #[error("tube: a 3-D centre, axis 0..=2, 0 < inner < outer, length > 0")]
    Tube,
    /// A ring or tube of fewer than 3 particles around.
    #[error("{shape}: at least 3 particles around, found {found}")]
    TooFewAround {
        /// The shape (`ring`, `tube`).
        shape: &'static str,
        /// The particles around given.
        found: usize,
    },
    /// An explicit particle's vertex with the wrong number of coordinates.
    #[error("particle {particle}: vertices need {dim} coordinates")]
    VertexCoordinates {
        /// Index of the particle in the body's list.
        particle: usize,
        /// The scene's dimension.
        dim: usize,
    },
    /// An explicit 2-D particle of fewer than 3 vertices.
    #[error("particle {particle}: a polygon needs 3 vertices")]
    TooFewPolygonVertices {
        /// Index of the particle in the body's list.
        particle: usize,
    },
    /// An explicit 2-D particle whose vertices run clockwise.
    #[error("particle {particle}: vertices must run counter-clockwise (signed area {signed_area})")]
    Clockwise {
        /// Index of the particle in the body's list.
        particle: usize,
        /// Its signed area \[m²\] (not positive).
        signed_area: f64,
    },
    /// An explicit 3-D particle whose vertices have no convex hull.
    #[error("particle {particle}: {error}")]
    Hull {
        /// Index of the particle in the body's list.
        particle: usize,
        /// Why.
        error: HullError,
    },
}

/// The particles of all bodies before any mechanics.
#[derive(Clone, Debug, Default)]
pub struct Lattice {
    /// Spatial dimension, 2 or 3.
    pub dim: usize,
    /// Vertex positions \[m\] (2-D: z = 0).
    pub vertices: Vec<Vector3<f64>>,
    /// The particles.
    pub particles: Vec<ParticleShape>,
}

/// One particle's shape.
#[derive(Clone, Debug)]
pub struct ParticleShape {
    /// Index of its body in the scene.
    pub body: u32,
    /// 3-D: outward faces as vertex loops; 2-D: edges `\[a, b\]` running counter-clockwise.
    pub faces: Vec<Vec<u32>>,
    /// Motion of its body.
    pub motion: Motion,
    /// Link law of its body (`None`: the elastic links of paper 003 App. A).
    pub links: Option<LinksConfig>,
}

/// Deduplicates vertices of one body by their exact quantised coordinates.
struct VertexPool<'a> {
    lattice: &'a mut Lattice,
    index: BTreeMap<[i64; 3], u32>,
    quantum: f64,
}

impl VertexPool<'_> {
    fn id(&mut self, p: Vector3<f64>) -> u32 {
        let key = [
            (p.x / self.quantum).round() as i64,
            (p.y / self.quantum).round() as i64,
            (p.z / self.quantum).round() as i64,
        ];
        let next = self.lattice.vertices.len() as u32;
        *self.index.entry(key).or_insert_with(|| {
            self.lattice.vertices.push(p);
            next
        })
    }
}

/// Outward loops of a hexahedron from its corners `c\[i + 2j + 4k\]` in a right-handed (i, j, k)
/// order (same as an axis-aligned cube with corner `(x_i, y_j, z_k)`).
fn hexahedron_faces(c: [u32; 8]) -> Vec<Vec<u32>> {
    let p = |i: usize, j: usize, k: usize| c[i + 2 * j + 4 * k];
    vec![
        vec![p(0, 0, 0), p(0, 0, 1), p(0, 1, 1), p(0, 1, 0)],
        vec![p(1, 0, 0), p(1, 1, 0), p(1, 1, 1), p(1, 0, 1)],
        vec![p(0, 0, 0), p(1, 0, 0), p(1, 0, 1), p(0, 0, 1)],
        vec![p(0, 1, 0), p(0, 1, 1), p(1, 1, 1), p(1, 1, 0)],
        vec![p(0, 0, 0), p(0, 1, 0), p(1, 1, 0), p(1, 0, 0)],
        vec![p(0, 0, 1), p(1, 0, 1), p(1, 1, 1), p(0, 1, 1)],
    ]
}

fn polygon_edges(ids: &[u32]) -> Vec<Vec<u32>> {
    (0..ids.len())
        .map(|k| vec![ids[k], ids[(k + 1) % ids.len()]])
        .collect()
}

/// The body's `divisions` for a shape of `n` directions (1 each when absent).
fn divisions(body: &BodyConfig, n: usize, shape: &'static str) -> Result<Vec<usize>, BodyError> {
    if body.divisions.is_empty() {
        return Ok(vec![1; n]);
    }
    if body.divisions.len() != n || body.divisions.contains(&0) {
        return Err(BodyError::Divisions {
            shape,
            expected: n,
            found: body.divisions.clone(),
        });
    }
    Ok(body.divisions.iter().map(|&d| d as usize).collect())
}

/// Builds the lattice of all bodies of a `dim`-dimensional scene.
pub fn build_lattice(bodies: &[BodyConfig], dim: usize) -> Result<Lattice, LatticeError> {
    if dim != 2 && dim != 3 {
        return Err(LatticeError::Dimension { dim });
    }
    let mut lattice = Lattice {
        dim,
        ..Lattice::default()
    };
    for (body_idx, body) in bodies.iter().enumerate() {
        let scale = body_scale(&body.shape);
        let mut shapes = Vec::new();
        {
            let mut pool = VertexPool {
                lattice: &mut lattice,
                index: BTreeMap::new(),
                quantum: 1e-9 * scale.max(1e-300),
            };
            add_body(&mut pool, body, dim, &mut shapes).map_err(|error| LatticeError::Body {
                body: body_idx,
                error,
            })?;
        }
        for faces in shapes {
            lattice.particles.push(ParticleShape {
                body: body_idx as u32,
                faces,
                motion: body.motion.clone(),
                links: body.links.clone(),
            });
        }
    }
    if lattice.particles.is_empty() {
        return Err(LatticeError::NoParticles);
    }
    Ok(lattice)
}

fn body_scale(shape: &Shape) -> f64 {
    match shape {
        Shape::Box { size, .. } => size.iter().fold(0.0, |a: f64, b| a.max(b.abs())),
        Shape::Ring { outer_radius, .. } => *outer_radius,
        Shape::Tube {
            outer_radius,
            length,
            ..
        } => outer_radius.max(*length),
        Shape::Particles(list) => list
            .iter()
            .flat_map(|p| p.vertices.iter())
            .flat_map(|v| v.iter())
            .fold(0.0, |a: f64, b| a.max(b.abs()))
            .max(1.0),
    }
}

fn point(coords: &[f64]) -> Vector3<f64> {
    Vector3::new(
        coords[0],
        coords[1],
        if coords.len() > 2 { coords[2] } else { 0.0 },
    )
}

/// The particles of one body, as faces of pooled vertices, appended to `out`.
fn add_body(
    pool: &mut VertexPool<'_>,
    body: &BodyConfig,
    dim: usize,
    out: &mut Vec<Vec<Vec<u32>>>,
) -> Result<(), BodyError> {
    match &body.shape {
        Shape::Box { center, size } => add_box(pool, body, dim, center, size, out),
        Shape::Ring {
            center,
            inner_radius,
            outer_radius,
        } => add_ring(pool, body, dim, center, *inner_radius, *outer_radius, out),
        Shape::Tube {
            center,
            axis,
            inner_radius,
            outer_radius,
            length,
        } => {
            let tube = TubeSpec {
                center,
                axis: *axis,
                inner_radius: *inner_radius,
                outer_radius: *outer_radius,
                length: *length,
            };
            add_tube(pool, body, dim, &tube, out)
        }
        Shape::Particles(list) => add_particles(pool, dim, list, out),
    }
}

/// A box cut into `divisions` rectangles (2-D) or cuboids (3-D).
fn add_box(
    pool: &mut VertexPool<'_>,
    body: &BodyConfig,
    dim: usize,
    center: &[f64],
    size: &[f64],
    out: &mut Vec<Vec<Vec<u32>>>,
) -> Result<(), BodyError> {
    if center.len() != dim || size.len() != dim || size.iter().any(|s| *s <= 0.0) {
        return Err(BodyError::Box { dim });
    }
    let n = divisions(body, dim, "box")?;
    let lower: Vec<f64> = (0..dim).map(|a| center[a] - 0.5 * size[a]).collect();
    let at = |a: usize, i: usize| lower[a] + size[a] * i as f64 / n[a] as f64;
    if dim == 2 {
        for j in 0..n[1] {
            for i in 0..n[0] {
                let ids = [
                    pool.id(Vector3::new(at(0, i), at(1, j), 0.0)),
                    pool.id(Vector3::new(at(0, i + 1), at(1, j), 0.0)),
                    pool.id(Vector3::new(at(0, i + 1), at(1, j + 1), 0.0)),
                    pool.id(Vector3::new(at(0, i), at(1, j + 1), 0.0)),
                ];
                out.push(polygon_edges(&ids));
            }
        }
    } else {
        for k in 0..n[2] {
            for j in 0..n[1] {
                for i in 0..n[0] {
                    let mut c = [0u32; 8];
                    for (corner, slot) in c.iter_mut().enumerate() {
                        let (di, dj, dk) = (corner & 1, (corner >> 1) & 1, corner >> 2);
                        *slot = pool.id(Vector3::new(at(0, i + di), at(1, j + dj), at(2, k + dk)));
                    }
                    out.push(hexahedron_faces(c));
                }
            }
        }
    }
    Ok(())
}

/// A 2-D ring of `divisions` quadrilaterals one particle thick.
fn add_ring(
    pool: &mut VertexPool<'_>,
    body: &BodyConfig,
    dim: usize,
    center: &[f64],
    inner_radius: f64,
    outer_radius: f64,
    out: &mut Vec<Vec<Vec<u32>>>,
) -> Result<(), BodyError> {
    if dim != 2 || center.len() != 2 || !(0.0 < inner_radius && inner_radius < outer_radius) {
        return Err(BodyError::Ring);
    }
    let n = divisions(body, 1, "ring")?[0];
    if n < 3 {
        return Err(BodyError::TooFewAround {
            shape: "ring",
            found: n,
        });
    }
    let c = point(center);
    // NOTE: vertex n − k is the mirror image of vertex k about the x-axis to the last bit
    // (sin(2π − φ) is not −sin φ in floating point, nor sin π zero), so a ring symmetric
    // about the line through its centre along x is built symmetric.
    let on = |r: f64, k: usize| {
        let k = k % n;
        let m = k.min(n - k);
        let (sin, cos) = if 2 * m == n {
            (0.0, -1.0)
        } else {
            (2.0 * std::f64::consts::PI * m as f64 / n as f64).sin_cos()
        };
        let sin = if m == k { sin } else { -sin };
        c + Vector3::new(r * cos, r * sin, 0.0)
    };
    for k in 0..n {
        // Counter-clockwise: inner k, outer k, outer k+1, inner k+1.
        let ids = [
            pool.id(on(inner_radius, k)),
            pool.id(on(outer_radius, k)),
            pool.id(on(outer_radius, k + 1)),
            pool.id(on(inner_radius, k + 1)),
        ];
        out.push(polygon_edges(&ids));
    }
    Ok(())
}

/// The parameters of a `tube` shape.
struct TubeSpec<'a> {
    center: &'a [f64],
    axis: u32,
    inner_radius: f64,
    outer_radius: f64,
    length: f64,
}

/// A 3-D tube of `divisions = [around, along]` hexahedra one particle thick.
fn add_tube(
    pool: &mut VertexPool<'_>,
    body: &BodyConfig,
    dim: usize,
    tube: &TubeSpec<'_>,
    out: &mut Vec<Vec<Vec<u32>>>,
) -> Result<(), BodyError> {
    let TubeSpec {
        center,
        axis,
        inner_radius,
        outer_radius,
        length,
    } = *tube;
    if dim != 3
        || center.len() != 3
        || axis > 2
        || inner_radius <= 0.0
        || inner_radius >= outer_radius
        || length <= 0.0
    {
        return Err(BodyError::Tube);
    }
    let nd = divisions(body, 2, "tube")?;
    let (n_around, n_along) = (nd[0], nd[1]);
    if n_around < 3 {
        return Err(BodyError::TooFewAround {
            shape: "tube",
            found: n_around,
        });
    }
    let a = axis as usize;
    // (u, w, e) right-handed: e = u × w.
    let e = Vector3::from_fn(|r, _| if r == a { 1.0 } else { 0.0 });
    let u = Vector3::from_fn(|r, _| if r == (a + 1) % 3 { 1.0 } else { 0.0 });
    let w = e.cross(&u);
    let c = point(center);
    let at = |r: f64, k: usize, l: usize| {
        let phi = 2.0 * std::f64::consts::PI * (k % n_around) as f64 / n_around as f64;
        let z = -0.5 * length + length * l as f64 / n_along as f64;
        c + u * (r * phi.cos()) + w * (r * phi.sin()) + e * z
    };
    for l in 0..n_along {
        for k in 0..n_around {
            let mut corners = [0u32; 8];
            for (corner, slot) in corners.iter_mut().enumerate() {
                let (di, dj, dk) = (corner & 1, (corner >> 1) & 1, corner >> 2);
                let r = if di == 0 { inner_radius } else { outer_radius };
                *slot = pool.id(at(r, k + dj, l + dk));
            }
            out.push(hexahedron_faces(corners));
        }
    }
    Ok(())
}

/// Explicit particles: 2-D counter-clockwise polygons, 3-D convex hulls of their vertices.
fn add_particles(
    pool: &mut VertexPool<'_>,
    dim: usize,
    list: &[ParticleSpec],
    out: &mut Vec<Vec<Vec<u32>>>,
) -> Result<(), BodyError> {
    for (p_idx, spec) in list.iter().enumerate() {
        if spec.vertices.iter().any(|v| v.len() != dim) {
            return Err(BodyError::VertexCoordinates {
                particle: p_idx,
                dim,
            });
        }
        let pts: Vec<Vector3<f64>> = spec.vertices.iter().map(|v| point(v)).collect();
        if dim == 2 {
            if pts.len() < 3 {
                return Err(BodyError::TooFewPolygonVertices { particle: p_idx });
            }
            let mut signed = 0.0;
            for k in 0..pts.len() {
                let (a, b) = (pts[k], pts[(k + 1) % pts.len()]);
                signed += a.x * b.y - a.y * b.x;
            }
            if signed <= 0.0 {
                return Err(BodyError::Clockwise {
                    particle: p_idx,
                    signed_area: 0.5 * signed,
                });
            }
            let ids: Vec<u32> = pts.iter().map(|p| pool.id(*p)).collect();
            out.push(polygon_edges(&ids));
        } else {
            let faces = convex_hull_faces(&pts).map_err(|error| BodyError::Hull {
                particle: p_idx,
                error,
            })?;
            let ids: Vec<u32> = pts.iter().map(|p| pool.id(*p)).collect();
            out.push(
                faces
                    .into_iter()
                    .map(|f| f.into_iter().map(|v| ids[v as usize]).collect())
                    .collect(),
            );
        }
    }
    Ok(())
}

#[cfg(test)]
mod ring_tests {
    use super::*;

    /// A ring is built mirror-symmetric about the line through its centre along x: vertex n − k
    /// has vertex k's x to the last bit and its y reflected (to the rounding of the centre plus
    /// the offset, one ulp where the two lie in different binades), and the vertices at angles 0
    /// and π lie on that line (the blast of `scenes/cylinder-explosion.toml` is symmetric about
    /// it).
    #[test]
    fn a_ring_is_symmetric_about_its_x_line() {
        let text = r#"
name = "ring"
[solid]
density = 7860.0
young = 2.1e11
poisson = 0.0
[[solid.bodies]]
shape = { ring = { center = [20.0, 7.5], inner_radius = 5.0, outer_radius = 5.1 } }
divisions = [50]
"#;
        let scene = protocol::scene::Scene::from_toml_str(text, "test").expect("scene");
        let solid = scene.solid.expect("a [solid]");
        let lattice = build_lattice(&solid.bodies, 2).expect("lattice");
        let on_line = lattice.vertices.iter().filter(|v| v.y == 7.5).count();
        assert_eq!(on_line, 4, "inner and outer vertices at angles 0 and π");
        for v in &lattice.vertices {
            assert!(
                lattice
                    .vertices
                    .iter()
                    .any(|w| w.x == v.x && (w.y + v.y - 15.0).abs() <= 2e-15),
                "vertex {v:?} has no mirror image"
            );
        }
    }
}
