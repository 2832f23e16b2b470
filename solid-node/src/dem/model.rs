//! The mechanical model built once from a lattice: particles (mass, inertia, volumes), links
//! (contact surface, frames, stiffnesses of eq. (29)–(30) of paper 003), faces and the vertex
//! slots of the wet surface.
//!
//! Frames: in 3-D each particle's body frame is its principal frame; `axes0` is the rotation
//! from the body frame to space at t = 0 and every body-fixed vector below is stored in the body
//! frame. In 2-D the body frame is the space frame at t = 0 and the orientation is an angle.

use nalgebra::{UnitQuaternion, Vector2, Vector3};
use serde::{Deserialize, Serialize};

use protocol::scene::{FaceInertia, Motion};

use crate::dem::geometry::{
    FaceMoments, face_moments_with, inertia_from_second_moment, polygon_mass, polyhedron_mass,
};
use crate::dem::lattice::{Lattice, ParticleShape};

/// Typed index of a particle.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct ParticleId(pub u32);

/// Typed index of a link.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct LinkId(pub u32);

/// Elastic material of the solid.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Material {
    /// Density ρ \[kg/m³\].
    pub density: f64,
    /// Young's modulus E \[Pa\].
    pub young: f64,
    /// Poisson's ratio ν \[-\], in [0, 0.5).
    pub poisson: f64,
    /// How the link faces' second moments are integrated (3-D).
    pub face_inertia: FaceInertia,
}

impl Material {
    /// Lamé's first coefficient λ = Eν/((1+ν)(1−2ν)) \[Pa\].
    pub fn lambda(&self) -> f64 {
        self.young * self.poisson / ((1.0 + self.poisson) * (1.0 - 2.0 * self.poisson))
    }
}

/// How a particle moves.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum ParticleMotion {
    /// Under the forces.
    Free,
    /// Not at all.
    Fixed,
    /// Constant velocity \[m/s\] (no rotation).
    Velocity([f64; 3]),
}

/// A rigid particle.
#[derive(Clone, Debug)]
pub struct Particle {
    /// Body index in the scene.
    pub body: u32,
    /// Mass \[kg\] (2-D: per unit depth).
    pub mass: f64,
    /// Principal moments of inertia \[kg m²\] (2-D: `\[I_z, 0, 0\]`).
    pub inertia: [f64; 3],
    /// Body-to-space rotation at t = 0 (principal axes; identity in 2-D).
    pub axes0: UnitQuaternion<f64>,
    /// Volume \[m³\] (2-D: area).
    pub volume: f64,
    /// Free volume (pyramids on the free faces with the centre as summit, 003 App. A).
    pub free_volume: f64,
    /// Diameter h_s (largest vertex distance) \[m\].
    pub size: f64,
    /// Centre of mass at t = 0 \[m\].
    pub x0: Vector3<f64>,
    /// Prescribed motion.
    pub motion: ParticleMotion,
    /// `1 / (2 (V + 3ν/(1−2ν) V^f))`, the weight of a link in ε^v_I \[1/m³\].
    pub vol_weight: f64,
    /// `λ (V + 3ν/(1−2ν) V^f) / 2`: volumetric energy is `vol_energy_coef · (ε^v_I)²` \[J\].
    pub vol_energy_coef: f64,
}

/// The law of a link.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LinkLaw {
    /// The elastic link of paper 003 App. A (eq. (29)–(30)) from E and ν.
    Elastic,
    /// A linear spring between the particle centres, `½ k (|d| − D⁰)²`, plus a rotational
    /// spring `c (1 − cos θ_rel)` on the relative rotation (`[[solid.bodies]] links`).
    Spring {
        /// Axial stiffness k \[N/m\].
        k: f64,
        /// Rotational stiffness c \[N m/rad\].
        rotation: f64,
    },
}

/// A link between two particles sharing a face.
#[derive(Clone, Debug)]
pub struct Link {
    /// First particle.
    pub i: u32,
    /// Second particle.
    pub j: u32,
    /// Contact surface S_IJ \[m²\] (2-D: edge length × unit depth).
    pub area: f64,
    /// Rest distance D⁰_IJ \[m\].
    pub d0: f64,
    /// Contact centroid G⁰_IJ at t = 0 \[m\].
    pub centroid0: Vector3<f64>,
    /// Face normal n⁰_IJ at t = 0, out of `i` \[-\].
    pub normal0: Vector3<f64>,
    /// In-plane principal axes s, t at t = 0.
    pub s0: Vector3<f64>,
    /// See `s0`.
    pub t0: Vector3<f64>,
    /// Principal moments of the contact surface I^s, I^t \[m⁴\].
    pub i_st: [f64; 2],
    /// `S/D⁰ · E/(1+ν)` \[N/m\].
    pub k_shear: f64,
    /// `S λ / 2 = S · Eν/(2(1+ν)(1−2ν))` \[N\] (multiplies `ε^v_I + ε^v_J`).
    pub k_vol: f64,
    /// `S/D⁰ · (α_n, α_s, α_t)` \[N m\].
    pub flex: [f64; 3],
    /// `G⁰ − X⁰_i` in the body frame of `i`.
    pub r_i: Vector3<f64>,
    /// `G⁰ − X⁰_j` in the body frame of `j`.
    pub r_j: Vector3<f64>,
    /// `(n⁰, s, t)` in the body frame of `i`.
    pub axes_i: [Vector3<f64>; 3],
    /// `(n⁰, s, t)` in the body frame of `j`.
    pub axes_j: [Vector3<f64>; 3],
    /// Face of `i` and face of `j` on the contact surface.
    pub faces: [u32; 2],
    /// Its law; a spring link has `k_shear = k_vol = 0` and `flex = [c/2; 3]`.
    pub law: LinkLaw,
}

/// What the force kernels read of a link (hot data, copied from [`Link`] at build time so
/// that the evaluation streams 248 bytes per link instead of the whole record).
#[derive(Clone, Debug)]
pub struct LinkKernel {
    /// First particle.
    pub i: u32,
    /// Second particle.
    pub j: u32,
    /// Contact surface S_IJ \[m²\], the weight of the link in ε^v (0 for a spring link).
    pub area: f64,
    /// Axial stiffness k of a spring link \[N/m\] (0: an elastic link).
    pub spring: f64,
    /// See [`Link::d0`].
    pub d0: f64,
    /// See [`Link::k_shear`].
    pub k_shear: f64,
    /// See [`Link::k_vol`].
    pub k_vol: f64,
    /// See [`Link::flex`].
    pub flex: [f64; 3],
    /// See [`Link::r_i`].
    pub r_i: Vector3<f64>,
    /// See [`Link::r_j`].
    pub r_j: Vector3<f64>,
    /// See [`Link::axes_i`].
    pub axes_i: [Vector3<f64>; 3],
    /// See [`Link::axes_j`].
    pub axes_j: [Vector3<f64>; 3],
}

impl LinkKernel {
    /// The hot part of `link`.
    pub fn from_link(link: &Link) -> Self {
        let (area, spring) = match link.law {
            LinkLaw::Elastic => (link.area, 0.0),
            LinkLaw::Spring { k, .. } => (0.0, k),
        };
        LinkKernel {
            i: link.i,
            j: link.j,
            area,
            spring,
            d0: link.d0,
            k_shear: link.k_shear,
            k_vol: link.k_vol,
            flex: link.flex,
            r_i: link.r_i,
            r_j: link.r_j,
            axes_i: link.axes_i,
            axes_j: link.axes_j,
        }
    }
}

/// A particle face.
#[derive(Clone, Debug)]
pub struct Face {
    /// Owner.
    pub particle: u32,
    /// Vertex slots of the loop (3-D) or segment (2-D), outward / counter-clockwise.
    pub slots: Vec<u32>,
    /// Face centroid relative to the centre, body frame \[m\].
    pub centroid_body: Vector3<f64>,
    /// The link through this face, if any.
    pub link: Option<u32>,
}

/// One vertex of one particle (the wet surface averages the slots of a vertex, 000 eq. (10)).
#[derive(Clone, Debug)]
pub struct Slot {
    /// Lattice vertex.
    pub vertex: u32,
    /// Owner.
    pub particle: u32,
    /// `a⁰ − X⁰` in the body frame \[m\].
    pub body: Vector3<f64>,
}

/// Everything that does not change during a run (except link breaking, kept in the state).
#[derive(Clone, Debug)]
pub struct Model {
    /// 2 or 3.
    pub dim: usize,
    /// Material.
    pub material: Material,
    /// Particles.
    pub particles: Vec<Particle>,
    /// Links, `i < j`.
    pub links: Vec<Link>,
    /// Hot copies of `links` for the force kernels (same order).
    pub kernels: Vec<LinkKernel>,
    /// Faces of all particles.
    pub faces: Vec<Face>,
    /// Vertex slots of all particles.
    pub slots: Vec<Slot>,
    /// Per particle, start of its incident links in `incidence` (CSR, length n + 1).
    pub incidence_start: Vec<u32>,
    /// `(link, particle is the link's i)` sorted by link id within a particle.
    pub incidence: Vec<(u32, bool)>,
    /// Per lattice vertex, its slots (CSR).
    pub vertex_slot_start: Vec<u32>,
    /// See `vertex_slot_start`.
    pub vertex_slots: Vec<u32>,
    /// Lattice vertex positions at t = 0.
    pub vertices0: Vec<Vector3<f64>>,
}

/// Why a lattice gives no model.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ModelError {
    /// A 3-D particle's faces enclose no volume.
    #[error("particle {particle}: non-positive volume {volume} (faces not outward?)")]
    NonPositiveVolume {
        /// The particle's index.
        particle: usize,
        /// Its signed volume \[m³\].
        volume: f64,
    },
    /// A 2-D particle's polygon has no area.
    #[error("particle {particle}: non-positive area {area}")]
    NonPositiveArea {
        /// The particle's index.
        particle: usize,
        /// Its signed area \[m²\].
        area: f64,
    },
    /// More than two particles of a body share a face.
    #[error("a face is shared by {n_particles} particles")]
    FaceSharedByMany {
        /// The particles sharing it.
        n_particles: usize,
    },
}

/// Builds the model from a lattice.
pub fn build_model(lattice: &Lattice, material: Material) -> Result<Model, ModelError> {
    let dim = lattice.dim;
    let Shapes {
        mut particles,
        mut faces,
        slots,
        face_geo,
    } = build_particles(lattice, material)?;
    let mut face_offsets = Vec::with_capacity(lattice.particles.len() + 1);
    let mut acc = 0usize;
    for shape in &lattice.particles {
        face_offsets.push(acc);
        acc += shape.faces.len();
    }
    let links = build_links(
        lattice,
        material,
        &particles,
        &mut faces,
        &face_geo,
        &face_offsets,
    )?;
    set_free_volumes(material, &mut particles, &faces, &face_geo, &face_offsets);
    let (incidence_start, incidence) = incidence(particles.len(), &links);
    let (vertex_slot_start, vertex_slots) = vertex_slots(lattice.vertices.len(), &slots);
    Ok(Model {
        dim,
        material,
        particles,
        kernels: links.iter().map(LinkKernel::from_link).collect(),
        links,
        faces,
        slots,
        incidence_start,
        incidence,
        vertex_slot_start,
        vertex_slots,
        vertices0: lattice.vertices.clone(),
    })
}

/// The particles, faces and slots of a lattice, and per particle, per face, the face's moments
/// at t = 0 (space frame) with the volume of the pyramid it makes with the centre.
struct Shapes {
    particles: Vec<Particle>,
    faces: Vec<Face>,
    slots: Vec<Slot>,
    face_geo: Vec<Vec<(FaceMoments, f64)>>,
}

/// Mass properties of one particle: volume (2-D: area), centre, principal moments, principal
/// axes at t = 0.
type MassProperties = (f64, Vector3<f64>, [f64; 3], UnitQuaternion<f64>);

/// Every particle's mass properties, faces and vertex slots.
fn build_particles(lattice: &Lattice, material: Material) -> Result<Shapes, ModelError> {
    let dim = lattice.dim;
    let mut particles = Vec::with_capacity(lattice.particles.len());
    let mut faces: Vec<Face> = Vec::new();
    let mut slots: Vec<Slot> = Vec::new();
    // Per particle, per face: moments at t = 0 (space frame).
    let mut face_geo = Vec::new();
    for (p_idx, shape) in lattice.particles.iter().enumerate() {
        let mut ids: Vec<u32> = shape.faces.iter().flatten().copied().collect();
        ids.sort_unstable();
        ids.dedup();
        let pts: Vec<Vector3<f64>> = ids.iter().map(|&v| lattice.vertices[v as usize]).collect();
        let size = pts
            .iter()
            .flat_map(|a| pts.iter().map(move |b| (a - b).norm()))
            .fold(0.0, f64::max);
        let (volume, x0, inertia, axes0) =
            mass_properties(lattice, shape, &ids, &pts, material, p_idx)?;
        let to_body = |v: Vector3<f64>| axes0.inverse_transform_vector(&v);
        let slot_base = slots.len() as u32;
        for &v in &ids {
            slots.push(Slot {
                vertex: v,
                particle: p_idx as u32,
                body: to_body(lattice.vertices[v as usize] - x0),
            });
        }
        let mut geos = Vec::new();
        for f in &shape.faces {
            let loop_pts: Vec<Vector3<f64>> =
                f.iter().map(|&v| lattice.vertices[v as usize]).collect();
            let geo = if dim == 3 {
                face_moments_with(&loop_pts, material.face_inertia)
            } else {
                segment_moments(loop_pts[0], loop_pts[1])
            };
            let pyramid = geo.area * geo.normal.dot(&(geo.centroid - x0)) / dim as f64;
            faces.push(Face {
                particle: p_idx as u32,
                slots: f
                    .iter()
                    .map(|v| slot_base + ids.binary_search(v).unwrap() as u32)
                    .collect(),
                centroid_body: to_body(geo.centroid - x0),
                link: None,
            });
            geos.push((geo, pyramid));
        }
        face_geo.push(geos);
        particles.push(Particle {
            body: shape.body,
            mass: material.density * volume,
            inertia,
            axes0,
            volume,
            free_volume: 0.0,
            size,
            x0,
            motion: match &shape.motion {
                Motion::Free => ParticleMotion::Free,
                Motion::Fixed => ParticleMotion::Fixed,
                Motion::Velocity(v) => ParticleMotion::Velocity(to3(v)),
            },
            vol_weight: 0.0,
            vol_energy_coef: 0.0,
        });
    }
    Ok(Shapes {
        particles,
        faces,
        slots,
        face_geo,
    })
}

/// Volume, centre and principal inertia of particle `p_idx`, whose sorted vertex ids are `ids`
/// at `pts`.
fn mass_properties(
    lattice: &Lattice,
    shape: &ParticleShape,
    ids: &[u32],
    pts: &[Vector3<f64>],
    material: Material,
    p_idx: usize,
) -> Result<MassProperties, ModelError> {
    if lattice.dim == 3 {
        let local: Vec<Vec<u32>> = shape
            .faces
            .iter()
            .map(|f| {
                f.iter()
                    .map(|v| ids.binary_search(v).unwrap() as u32)
                    .collect()
            })
            .collect();
        let mp = polyhedron_mass(pts, &local);
        if mp.volume <= 0.0 {
            return Err(ModelError::NonPositiveVolume {
                particle: p_idx,
                volume: mp.volume,
            });
        }
        let tensor = inertia_from_second_moment(&mp.second_moment, material.density);
        let eig = tensor.symmetric_eigen();
        let mut axes = eig.eigenvectors;
        if axes.determinant() < 0.0 {
            axes.column_mut(2).neg_mut();
        }
        let rot = nalgebra::Rotation3::from_matrix_unchecked(axes);
        let q = UnitQuaternion::from_rotation_matrix(&rot);
        let ev = eig.eigenvalues;
        Ok((mp.volume, mp.centroid, [ev[0], ev[1], ev[2]], q))
    } else {
        // Polygon loop from the counter-clockwise edges.
        let loop2: Vec<Vector2<f64>> = shape
            .faces
            .iter()
            .map(|e| lattice.vertices[e[0] as usize].xy())
            .collect();
        let (area, c, polar) = polygon_mass(&loop2);
        if area <= 0.0 {
            return Err(ModelError::NonPositiveArea {
                particle: p_idx,
                area,
            });
        }
        Ok((
            area,
            Vector3::new(c.x, c.y, 0.0),
            [material.density * polar, 0.0, 0.0],
            UnitQuaternion::identity(),
        ))
    }
}

/// Links: faces with the same vertex set in the same body, sorted by `(i, j)`; each face
/// on a link gets the link's index.
fn build_links(
    lattice: &Lattice,
    material: Material,
    particles: &[Particle],
    faces: &mut [Face],
    face_geo: &[Vec<(FaceMoments, f64)>],
    face_offsets: &[usize],
) -> Result<Vec<Link>, ModelError> {
    let mut keyed: Vec<(u32, Vec<u32>, u32)> = Vec::new();
    let mut face_idx = 0u32;
    for shape in &lattice.particles {
        for f in &shape.faces {
            let mut key = f.clone();
            key.sort_unstable();
            keyed.push((shape.body, key, face_idx));
            face_idx += 1;
        }
    }
    keyed.sort();
    let mut links = Vec::new();
    let mut k = 0;
    while k < keyed.len() {
        let mut m = k + 1;
        while m < keyed.len() && keyed[m].0 == keyed[k].0 && keyed[m].1 == keyed[k].1 {
            m += 1;
        }
        if m - k > 2 {
            return Err(ModelError::FaceSharedByMany { n_particles: m - k });
        }
        if m - k == 2 {
            let (fa, fb) = (keyed[k].2, keyed[k + 1].2);
            let (pa, pb) = (faces[fa as usize].particle, faces[fb as usize].particle);
            let (fi, fj, i, j) = if pa < pb {
                (fa, fb, pa, pb)
            } else {
                (fb, fa, pb, pa)
            };
            let geo = face_geo[i as usize][fi as usize - face_offsets[i as usize]].0;
            let link_id = links.len() as u32;
            faces[fi as usize].link = Some(link_id);
            faces[fj as usize].link = Some(link_id);
            let law = match &lattice.particles[i as usize].links {
                None => LinkLaw::Elastic,
                Some(l) => LinkLaw::Spring {
                    k: l.spring,
                    rotation: l.rotation,
                },
            };
            links.push(link_through(
                material,
                (&particles[i as usize], &particles[j as usize]),
                &geo,
                law,
                [i, j],
                [fi, fj],
            ));
        }
        k = m;
    }
    links.sort_by_key(|l| (l.i, l.j));
    for (idx, l) in links.iter().enumerate() {
        faces[l.faces[0] as usize].link = Some(idx as u32);
        faces[l.faces[1] as usize].link = Some(idx as u32);
    }
    Ok(links)
}

/// The link between particles `ids = [i, j]` through the face `geo` (`faces = [of i, of j]`).
fn link_through(
    material: Material,
    (pi, pj): (&Particle, &Particle),
    geo: &FaceMoments,
    law: LinkLaw,
    [i, j]: [u32; 2],
    [fi, fj]: [u32; 2],
) -> Link {
    let e = material.young;
    let nu = material.poisson;
    let lambda = material.lambda();
    let d0 = (pj.x0 - pi.x0).norm();
    let s = geo.area;
    let (i_s, i_t) = (geo.i_s, geo.i_t);
    // 000 §2.2.1: α chosen to recover exact flexion and torsion of a beam. With
    // I^s = ∫(x·s)², flexion about t costs α_n + α_s = E I^s / S (checked in tests).
    let base = e / (4.0 * (1.0 + nu) * s);
    let alpha = [
        (1.0 + 2.0 * nu) * base * (i_s + i_t),
        base * ((3.0 + 2.0 * nu) * i_s - (1.0 + 2.0 * nu) * i_t),
        base * ((3.0 + 2.0 * nu) * i_t - (1.0 + 2.0 * nu) * i_s),
    ];
    let (k_shear, k_vol, flex) = match law {
        LinkLaw::Elastic => (
            s / d0 * e / (1.0 + nu),
            // NOTE: half the printed S λ, see `link_force.rs` (mean of ε^v_I and ε^v_J).
            0.5 * s * lambda,
            [alpha[0] * s / d0, alpha[1] * s / d0, alpha[2] * s / d0],
        ),
        // Σ_k c/2 (1 − Q_I a_k · Q_J a_k) = c (1 − cos φ) for a relative rotation φ.
        LinkLaw::Spring { rotation, .. } => (0.0, 0.0, [0.5 * rotation; 3]),
    };
    let bi = |v: Vector3<f64>| pi.axes0.inverse_transform_vector(&v);
    let bj = |v: Vector3<f64>| pj.axes0.inverse_transform_vector(&v);
    Link {
        i,
        j,
        area: s,
        d0,
        centroid0: geo.centroid,
        normal0: geo.normal,
        s0: geo.s,
        t0: geo.t,
        i_st: [i_s, i_t],
        k_shear,
        k_vol,
        flex,
        r_i: bi(geo.centroid - pi.x0),
        r_j: bj(geo.centroid - pj.x0),
        axes_i: [bi(geo.normal), bi(geo.s), bi(geo.t)],
        axes_j: [bj(geo.normal), bj(geo.s), bj(geo.t)],
        faces: [fi, fj],
        law,
    }
}

/// Free volumes (pyramids on the faces without a link) and volumetric weights.
fn set_free_volumes(
    material: Material,
    particles: &mut [Particle],
    faces: &[Face],
    face_geo: &[Vec<(FaceMoments, f64)>],
    face_offsets: &[usize],
) {
    let nu = material.poisson;
    let lambda = material.lambda();
    for (p_idx, p) in particles.iter_mut().enumerate() {
        let start = face_offsets[p_idx];
        let free: f64 = face_geo[p_idx]
            .iter()
            .enumerate()
            .filter(|(f, _)| faces[start + f].link.is_none())
            .map(|(_, g)| g.1)
            .sum();
        p.free_volume = free;
        let v_eff = p.volume + 3.0 * nu / (1.0 - 2.0 * nu) * free;
        p.vol_weight = 0.5 / v_eff;
        p.vol_energy_coef = 0.5 * lambda * v_eff;
    }
}

/// Incidence (CSR): per particle, its links sorted by id, as `(link, particle is the link's
/// i)`; returns the start of each particle's range (length n + 1) and the entries.
fn incidence(n: usize, links: &[Link]) -> (Vec<u32>, Vec<(u32, bool)>) {
    let mut counts = vec![0u32; n + 1];
    for l in links {
        counts[l.i as usize + 1] += 1;
        counts[l.j as usize + 1] += 1;
    }
    for p in 0..n {
        counts[p + 1] += counts[p];
    }
    let mut fill = counts.clone();
    let mut incidence = vec![(0u32, false); links.len() * 2];
    for (idx, l) in links.iter().enumerate() {
        incidence[fill[l.i as usize] as usize] = (idx as u32, true);
        fill[l.i as usize] += 1;
        incidence[fill[l.j as usize] as usize] = (idx as u32, false);
        fill[l.j as usize] += 1;
    }
    (counts, incidence)
}

/// Vertex → slots (CSR) over `n_vertices` lattice vertices: the start of each vertex's range
/// and the slots.
fn vertex_slots(n_vertices: usize, slots: &[Slot]) -> (Vec<u32>, Vec<u32>) {
    let nv = n_vertices;
    let mut vcount = vec![0u32; nv + 1];
    for s in slots {
        vcount[s.vertex as usize + 1] += 1;
    }
    for v in 0..nv {
        vcount[v + 1] += vcount[v];
    }
    let mut vfill = vcount.clone();
    let mut vertex_slots = vec![0u32; slots.len()];
    for (idx, s) in slots.iter().enumerate() {
        vertex_slots[vfill[s.vertex as usize] as usize] = idx as u32;
        vfill[s.vertex as usize] += 1;
    }
    (vcount, vertex_slots)
}

/// Moments of a 2-D edge seen as a unit-depth rectangle: S = ℓ, I^s = ℓ³/12 (in-plane),
/// I^t = ℓ/12 (depth); normal `(dy, −dx)/ℓ` is outward for a counter-clockwise polygon.
fn segment_moments(a: Vector3<f64>, b: Vector3<f64>) -> FaceMoments {
    let d = b - a;
    let len = d.norm();
    let s = d / len;
    let normal = Vector3::new(s.y, -s.x, 0.0);
    FaceMoments {
        area: len,
        centroid: (a + b) * 0.5,
        normal,
        s,
        t: Vector3::z(),
        i_s: len * len * len / 12.0,
        i_t: len / 12.0,
    }
}

/// A 1-, 2- or 3-component vector as `\[f64; 3\]` (missing components 0).
pub fn to3(v: &[f64]) -> [f64; 3] {
    let mut out = [0.0; 3];
    for (o, x) in out.iter_mut().zip(v) {
        *o = *x;
    }
    out
}
