//! The wet surface (003 §3.2 eq. (18), 000 eq. (10)): mean vertices, face centroids, and the
//! triangles (3-D) or segments (2-D) the fluid sees.
//!
//! Vertices: one per (lattice vertex, particle) slot, placed at the mean of the rigid positions
//! of the slots of the same vertex that are still connected through unbroken links (so a crack
//! splits a vertex, and each fragment's surface stays closed). In 3-D the face centroids, moving
//! rigidly with their particle, follow the slots. The vertex and element counts never change
//! during a run; fracture changes connectivity and wet flags only, and bumps `revision`.
//!
//! Which vertices are carried: with fracture on, all of them (so that a crack, which moves
//! elements onto other slots, changes no message shape). Without fracture the connectivity is
//! that of the start for the whole run, and only the vertices the elements use are carried,
//! renumbered in their order ([`WetTopology::kept`]): in `clamped-beam-2d` 132 of the 2 912
//! slots, the rest being the corners of the particles inside the beam, which no element
//! references and which were half of every `SolidState` the record holds (issue 39 item 4).
//!
//! Elements: 3-D: for a face with loop `a_0 … a_k`, the triangles `(centroid, a_i, a_{i+1})`,
//! normal outward by the right-hand rule. 2-D: each polygon edge `(a, b)` in counter-clockwise
//! order, outward normal `(dy, −dx)`.

use nalgebra::Vector3;

use crate::dem::model::Model;

/// The wet surface at one configuration, flat arrays ready for `protocol::wire::WetSurface`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct WetSurfaceData {
    /// Spatial dimension: 2 (segments) or 3 (triangles).
    pub dim: usize,
    /// Incremented when the connectivity or wet flags change.
    pub revision: u64,
    /// Vertex coordinates \[m\], `dim` each.
    pub vertices: Vec<f64>,
    /// `dim` vertex indices per element, oriented with normals out of the solid.
    pub elements: Vec<u32>,
    /// Owner particle of each element.
    pub element_particle: Vec<u32>,
    /// Whether each element touches the fluid (`false`: internal face of an unbroken link).
    pub wet: Vec<bool>,
    /// Element area \[m²\] (2-D: length, per unit depth).
    pub area: Vec<f64>,
    /// Unit outward normal, `dim` each.
    pub normal: Vec<f64>,
    /// Element centroid \[m\], `dim` each.
    pub centroid: Vec<f64>,
    /// Velocity of the owner particle's rigid motion at the element centroid \[m/s\], `dim` each.
    pub velocity: Vec<f64>,
}

impl WetSurfaceData {
    /// Number of elements.
    pub fn n_elements(&self) -> usize {
        self.element_particle.len()
    }
}

/// Connectivity of the wet surface: which faces are carried and how slots are merged.
#[derive(Clone, Debug, Default)]
pub struct WetTopology {
    /// Per element: 3-D `[n_slots + face, slot_a, slot_b]`; 2-D `[slot_a, slot_b, 0]`.
    pub element_slots: Vec<[u32; 3]>,
    /// Face of each element.
    pub element_face: Vec<u32>,
    /// Per slot, the representative slot of its group (smallest slot index).
    pub slot_rep: Vec<u32>,
    /// 3-D, per face: the face across an unbroken link whose centroid this face's centroid
    /// vertex shares ([`NO_PARTNER`]: a boundary face or a broken link).
    pub centroid_partner: Vec<u32>,
    /// Whether the internal faces are carried (fracture on); then every vertex is carried.
    pub carry_internal: bool,
    /// The vertices carried, as indices of the whole numbering (slots, then the 3-D face
    /// centroids), ascending; empty with fracture on (see the module docs).
    pub kept: Vec<u32>,
    /// Index of each vertex of the whole numbering among the carried ones ([`NOT_CARRIED`]
    /// for the others); empty with fracture on: all vertices carried, as they are numbered.
    pub renumber: Vec<u32>,
}

/// [`WetTopology::renumber`] of a vertex no element uses.
pub const NOT_CARRIED: u32 = u32::MAX;

/// [`WetTopology::centroid_partner`] of a face that shares its centroid with none.
pub const NO_PARTNER: u32 = u32::MAX;

/// Elements of every carried face: boundary faces always, internal faces when fracture is on.
pub fn build_elements(model: &Model, carry_internal: bool) -> WetTopology {
    let mut topo = WetTopology::default();
    let n_slots = model.slots.len() as u32;
    for (f_idx, face) in model.faces.iter().enumerate() {
        if face.link.is_some() && !carry_internal {
            continue;
        }
        if model.dim == 3 {
            let k = face.slots.len();
            for e in 0..k {
                topo.element_slots.push([
                    n_slots + f_idx as u32,
                    face.slots[e],
                    face.slots[(e + 1) % k],
                ]);
                topo.element_face.push(f_idx as u32);
            }
        } else {
            topo.element_slots.push([face.slots[0], face.slots[1], 0]);
            topo.element_face.push(f_idx as u32);
        }
    }
    topo.slot_rep = (0..n_slots).collect();
    topo.centroid_partner = vec![NO_PARTNER; model.faces.len()];
    topo.carry_internal = carry_internal;
    carried_vertices(model, &mut topo);
    topo
}

/// [`WetTopology::kept`] and [`WetTopology::renumber`] after the slots' grouping: without
/// fracture, the representative slots and (3-D) face centroids the elements use.
fn carried_vertices(model: &Model, topo: &mut WetTopology) {
    topo.kept.clear();
    topo.renumber.clear();
    if topo.carry_internal {
        return;
    }
    let n_slots = model.slots.len();
    let n_vertices = if model.dim == 3 {
        n_slots + model.faces.len()
    } else {
        n_slots
    };
    let mut used = vec![false; n_vertices];
    for slots in &topo.element_slots {
        for &s in &slots[..model.dim] {
            let v = if (s as usize) < n_slots {
                topo.slot_rep[s as usize]
            } else {
                s
            };
            used[v as usize] = true;
        }
    }
    topo.renumber = vec![NOT_CARRIED; n_vertices];
    for (v, _) in used.iter().enumerate().filter(|(_, u)| **u) {
        topo.renumber[v] = topo.kept.len() as u32;
        topo.kept.push(v as u32);
    }
}

fn find(parent: &mut [u32], mut a: u32) -> u32 {
    while parent[a as usize] != a {
        let up = parent[parent[a as usize] as usize];
        parent[a as usize] = up;
        a = up;
    }
    a
}

/// Groups the slots of each vertex whose particles are joined by an unbroken link, and (3-D)
/// pairs the centroids of the two faces of each unbroken link.
///
/// NOTE: why the centroids. A 3-D face is the fan of triangles from its centroid to its loop.
/// The loop's vertices are means over the linked particles, but a centroid moving rigidly with
/// its own particle leaves the two faces of a stretched link as two pyramids over one loop: a
/// lens between them that the fluid's `Λ` (which counts every element, wet or not) takes for
/// fluid inside the intact solid (seen in `opening-fracture-3d`: a stretched link opened a
/// quarter of a cell of "fluid" that the sweeps then fed momentum without mass). With the mean
/// of the two centroids the faces coincide and cancel, as their loops do in 2-D; when the link
/// breaks each face takes its own rigid centroid again.
pub fn group_slots(model: &Model, broken: &[bool], topo: &mut WetTopology) {
    let mut parent: Vec<u32> = (0..model.slots.len() as u32).collect();
    for v in 0..model.vertex_slot_start.len() - 1 {
        let range = model.vertex_slot_start[v] as usize..model.vertex_slot_start[v + 1] as usize;
        let slots = &model.vertex_slots[range];
        for (a_pos, &a) in slots.iter().enumerate() {
            let pa = model.slots[a as usize].particle as usize;
            for &b in &slots[a_pos + 1..] {
                let pb = model.slots[b as usize].particle;
                let inc =
                    model.incidence_start[pa] as usize..model.incidence_start[pa + 1] as usize;
                let joined = model.incidence[inc].iter().any(|&(l, _)| {
                    let link = &model.links[l as usize];
                    !broken[l as usize] && (link.i == pb || link.j == pb)
                });
                if joined {
                    let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
                    let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
                    parent[hi as usize] = lo;
                }
            }
        }
    }
    for s in 0..parent.len() as u32 {
        let r = find(&mut parent, s);
        topo.slot_rep[s as usize] = r;
    }
    carried_vertices(model, topo);
    topo.centroid_partner.clear();
    topo.centroid_partner.resize(model.faces.len(), NO_PARTNER);
    if model.dim == 3 {
        let mut first = vec![NO_PARTNER; model.links.len()];
        for (f, face) in model.faces.iter().enumerate() {
            let Some(l) = face.link.filter(|&l| !broken[l as usize]) else {
                continue;
            };
            match first[l as usize] {
                NO_PARTNER => first[l as usize] = f as u32,
                g => {
                    topo.centroid_partner[f] = g;
                    topo.centroid_partner[g as usize] = f as u32;
                }
            }
        }
    }
}

/// Writes connectivity and wet flags into `out` (after [`group_slots`]).
pub fn write_connectivity(
    model: &Model,
    broken: &[bool],
    topo: &WetTopology,
    out: &mut WetSurfaceData,
) {
    let dim = model.dim;
    let n_slots = model.slots.len() as u32;
    out.dim = dim;
    out.elements.clear();
    out.element_particle.clear();
    out.wet.clear();
    for (e, slots) in topo.element_slots.iter().enumerate() {
        let face = &model.faces[topo.element_face[e] as usize];
        let map = |s: u32| {
            let v = if s < n_slots {
                topo.slot_rep[s as usize]
            } else {
                s
            };
            topo.renumber.get(v as usize).copied().unwrap_or(v)
        };
        out.elements.extend(slots[..dim].iter().map(|&s| map(s)));
        out.element_particle.push(face.particle);
        out.wet.push(face.link.is_none_or(|l| broken[l as usize]));
    }
}

/// Positions, areas, normals, centroids and velocities for the configuration given per particle
/// by `x`, `rotate` (body → space) and the rigid velocity `(v, ω)`.
#[allow(clippy::too_many_arguments)]
pub fn write_geometry(
    model: &Model,
    topo: &WetTopology,
    x: &[[f64; 3]],
    rotate: &dyn Fn(usize, &Vector3<f64>) -> Vector3<f64>,
    v: &[[f64; 3]],
    omega: &[[f64; 3]],
    sums: &mut Vec<(Vector3<f64>, u32)>,
    out: &mut WetSurfaceData,
) {
    let dim = model.dim;
    let n_slots = model.slots.len();
    sums.clear();
    sums.resize(n_slots, (Vector3::zeros(), 0));
    for (s, slot) in model.slots.iter().enumerate() {
        let p = slot.particle as usize;
        let pos = Vector3::from(x[p]) + rotate(p, &slot.body);
        let r = topo.slot_rep[s] as usize;
        sums[r].0 += pos;
        sums[r].1 += 1;
    }
    let n_vertices = if dim == 3 {
        n_slots + model.faces.len()
    } else {
        n_slots
    };
    out.vertices.clear();
    out.vertices.resize(n_vertices * dim, 0.0);
    for s in 0..n_slots {
        let (sum, count) = sums[topo.slot_rep[s] as usize];
        let mean = sum / count as f64;
        out.vertices[s * dim..(s + 1) * dim].copy_from_slice(&mean.as_slice()[..dim]);
    }
    if dim == 3 {
        let rigid = |f: usize| {
            let face = &model.faces[f];
            let p = face.particle as usize;
            Vector3::from(x[p]) + rotate(p, &face.centroid_body)
        };
        for f in 0..model.faces.len() {
            // Both faces of an unbroken link get the same bits: the sum in face order.
            let c = match topo.centroid_partner.get(f).copied().unwrap_or(NO_PARTNER) {
                NO_PARTNER => rigid(f),
                g => {
                    let (lo, hi) = (f.min(g as usize), f.max(g as usize));
                    (rigid(lo) + rigid(hi)) * 0.5
                }
            };
            out.vertices[(n_slots + f) * 3..(n_slots + f + 1) * 3].copy_from_slice(c.as_slice());
        }
    }
    if !topo.renumber.is_empty() {
        // Ascending, so each carried vertex moves down or stays: in place, front to back.
        for (i, &v) in topo.kept.iter().enumerate() {
            let v = v as usize;
            out.vertices.copy_within(v * dim..(v + 1) * dim, i * dim);
        }
        out.vertices.truncate(topo.kept.len() * dim);
    }
    let n_el = out.element_particle.len();
    let vert = |i: u32| {
        let i = i as usize * dim;
        if dim == 3 {
            Vector3::new(out.vertices[i], out.vertices[i + 1], out.vertices[i + 2])
        } else {
            Vector3::new(out.vertices[i], out.vertices[i + 1], 0.0)
        }
    };
    // Reuse the buffers (no allocation after the first call).
    let mut area = std::mem::take(&mut out.area);
    let mut normal = std::mem::take(&mut out.normal);
    let mut centroid = std::mem::take(&mut out.centroid);
    let mut velocity = std::mem::take(&mut out.velocity);
    area.clear();
    normal.clear();
    centroid.clear();
    velocity.clear();
    for e in 0..n_el {
        let p = out.element_particle[e] as usize;
        let (a_e, n_e, c_e) = if dim == 3 {
            let (a, b, c) = (
                vert(out.elements[3 * e]),
                vert(out.elements[3 * e + 1]),
                vert(out.elements[3 * e + 2]),
            );
            let cr = (b - a).cross(&(c - a));
            let len = cr.norm();
            (0.5 * len, cr / len, (a + b + c) / 3.0)
        } else {
            let (a, b) = (vert(out.elements[2 * e]), vert(out.elements[2 * e + 1]));
            let d = b - a;
            let len = d.norm();
            (len, Vector3::new(d.y, -d.x, 0.0) / len, (a + b) * 0.5)
        };
        let arm = c_e - Vector3::from(x[p]);
        let vel = Vector3::from(v[p]) + Vector3::from(omega[p]).cross(&arm);
        area.push(a_e);
        normal.extend_from_slice(&n_e.as_slice()[..dim]);
        centroid.extend_from_slice(&c_e.as_slice()[..dim]);
        velocity.extend_from_slice(&vel.as_slice()[..dim]);
    }
    out.area = area;
    out.normal = normal;
    out.centroid = centroid;
    out.velocity = velocity;
}
