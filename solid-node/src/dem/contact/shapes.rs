//! The particles' shapes as the contact sees them, built once from the model: vertices and
//! (3-D) faces in the body frame, bounding radii, and the convex pieces each particle is cut
//! into for the law (see the parent module's doc).

use nalgebra::Vector3;

use crate::dem::model::Model;

/// Vertices of a 2-D particle at most (stack copies in the plane).
pub(super) const MAX_VERTICES: usize = 64;

/// Why the contact cannot be built for a model.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ContactError {
    /// A 2-D particle has more vertices than the kernels' stack buffers hold.
    #[error(
        "solid.contact: particle {particle} has {vertices} vertices, contact handles at most \
         {max} in 2-D",
        max = MAX_VERTICES
    )]
    TooManyVertices {
        /// The particle's index.
        particle: usize,
        /// Its number of vertices.
        vertices: usize,
    },
}

/// Per-particle shape data for the contact (body frame), built once.
#[derive(Clone, Debug, Default)]
pub(super) struct Shapes {
    /// Per particle, range into `vertices` (CSR).
    pub(super) vertex_start: Vec<u32>,
    /// Vertices relative to the centre, body frame (2-D: counter-clockwise).
    pub(super) vertices: Vec<Vector3<f64>>,
    /// Owner of each vertex.
    pub(super) vertex_owner: Vec<u32>,
    /// 3-D: per particle, range into `faces` (CSR).
    pub(super) face_start: Vec<u32>,
    /// 3-D: per face, its loop as a range into `face_vertices` (indices local to the particle).
    pub(super) face_ranges: Vec<(u32, u32)>,
    pub(super) face_vertices: Vec<u32>,
    /// 3-D: outward normal of each face, body frame.
    pub(super) face_normals: Vec<Vector3<f64>>,
    pub(super) face_owner: Vec<u32>,
    /// Bounding radius about the centre \[m\].
    pub(super) radius: Vec<f64>,
    /// Per particle, range into `pieces` (CSR).
    pub(super) piece_start: Vec<u32>,
    /// The pieces each particle is cut into for the law (see the `contact` module doc), body frame.
    pub(super) pieces: Vec<Piece>,
}

/// One convex piece of a particle: 2-D the triangle (centre, vertex, edge midpoint) in
/// counter-clockwise order; 3-D the tetrahedron (centre, face centroid, edge) as four planes
/// `(outward normal, point)`. Body frame, relative to the centre.
#[derive(Clone, Copy, Debug)]
pub(super) struct Piece {
    pub(super) corners: [Vector3<f64>; 3],
    pub(super) planes: [(Vector3<f64>, Vector3<f64>); 4],
    /// Number of pieces its face is cut into (`κ_p = multiplier × κ`).
    pub(super) multiplier: f64,
}

/// The shapes of every particle of `model`; refuses a 2-D particle of more than
/// [`MAX_VERTICES`] vertices (the kernels' stack buffers).
pub(super) fn build_shapes(model: &Model) -> Result<Shapes, ContactError> {
    let mut shapes = Shapes::default();
    let mut face_cursor = 0usize;
    for (p, part) in model.particles.iter().enumerate() {
        shapes.vertex_start.push(shapes.vertices.len() as u32);
        shapes.face_start.push(shapes.face_ranges.len() as u32);
        // Faces of particle p are contiguous in `model.faces`.
        let first_face = face_cursor;
        while face_cursor < model.faces.len() && model.faces[face_cursor].particle == p as u32 {
            face_cursor += 1;
        }
        let faces = &model.faces[first_face..face_cursor];
        // Local vertex numbering by slot.
        let mut local: Vec<u32> = Vec::new();
        let mut index_of = |slot: u32, verts: &mut Vec<Vector3<f64>>| -> u32 {
            if let Some(k) = local.iter().position(|&s| s == slot) {
                return k as u32;
            }
            local.push(slot);
            verts.push(model.slots[slot as usize].body);
            (local.len() - 1) as u32
        };
        let mut verts = Vec::new();
        if model.dim == 2 {
            for f in faces {
                index_of(f.slots[0], &mut verts);
            }
        } else {
            for f in faces {
                let begin = shapes.face_vertices.len() as u32;
                for &s in &f.slots {
                    let k = index_of(s, &mut verts);
                    shapes.face_vertices.push(k);
                }
                shapes
                    .face_ranges
                    .push((begin, shapes.face_vertices.len() as u32 - begin));
                let loop_pts: Vec<Vector3<f64>> = f
                    .slots
                    .iter()
                    .map(|&s| model.slots[s as usize].body)
                    .collect();
                let mut area = Vector3::zeros();
                for k in 1..loop_pts.len() - 1 {
                    area += (loop_pts[k] - loop_pts[0]).cross(&(loop_pts[k + 1] - loop_pts[0]));
                }
                shapes.face_normals.push(area.normalize());
                shapes.face_owner.push(p as u32);
            }
        }
        shapes.piece_start.push(shapes.pieces.len() as u32);
        if model.dim == 2 {
            let m = verts.len();
            for k in 0..m {
                let (v0, v1) = (verts[k], verts[(k + 1) % m]);
                let mid = (v0 + v1) * 0.5;
                for (p, q) in [(v0, mid), (mid, v1)] {
                    shapes.pieces.push(Piece {
                        corners: [Vector3::zeros(), p, q],
                        planes: [(Vector3::zeros(), Vector3::zeros()); 4],
                        multiplier: 2.0,
                    });
                }
            }
        } else {
            for f in faces {
                let loop_pts: Vec<Vector3<f64>> = f
                    .slots
                    .iter()
                    .map(|&s| model.slots[s as usize].body)
                    .collect();
                let g = f.centroid_body;
                let m = loop_pts.len();
                for k in 0..m {
                    let tet = [Vector3::zeros(), g, loop_pts[k], loop_pts[(k + 1) % m]];
                    let mut planes = [(Vector3::zeros(), Vector3::zeros()); 4];
                    for (skip, plane) in planes.iter_mut().enumerate() {
                        let others: Vec<Vector3<f64>> =
                            (0..4).filter(|&i| i != skip).map(|i| tet[i]).collect();
                        let mut n = (others[1] - others[0]).cross(&(others[2] - others[0]));
                        if n.dot(&(tet[skip] - others[0])) > 0.0 {
                            n = -n;
                        }
                        *plane = (n.normalize(), others[0]);
                    }
                    shapes.pieces.push(Piece {
                        corners: [tet[1], tet[2], tet[3]],
                        planes,
                        multiplier: m as f64,
                    });
                }
            }
        }
        if model.dim == 2 && verts.len() > MAX_VERTICES {
            return Err(ContactError::TooManyVertices {
                particle: p,
                vertices: verts.len(),
            });
        }
        let radius = verts.iter().map(|v| v.norm()).fold(0.0, f64::max);
        shapes.radius.push(radius.max(0.5 * part.size));
        shapes
            .vertex_owner
            .extend(std::iter::repeat_n(p as u32, verts.len()));
        shapes.vertices.extend(verts);
    }
    shapes.vertex_start.push(shapes.vertices.len() as u32);
    shapes.face_start.push(shapes.face_ranges.len() as u32);
    shapes.piece_start.push(shapes.pieces.len() as u32);
    Ok(shapes)
}
