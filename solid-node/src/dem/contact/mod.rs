//! Contact between particles that are not linked (never linked, or whose link broke), fixed
//! particles included: broad phase ([`broad`]), exact overlap ([`overlap`]), and the contact law.
//!
//! # Law
//!
//! Elastic part: the potential `U = Σ_p ½ κ_p V_p²`, `V_p` the overlap of A with the piece `p`
//! of B (B the particle of larger index), B being cut into convex pieces attached to it: 2-D
//! the triangles (centre, vertex, edge midpoint), 3-D the tetrahedra (centre, face centroid,
//! face edge). `κ_p = m κ`, `m` the number of pieces of the piece's face (2 per edge in 2-D,
//! the face's edge count in 3-D), `κ = s E / h^dim` (`s` = `[solid.contact] stiffness`, `h`
//! the smaller particle size). Forces and torques are the exact negative gradient of `U`
//! ([`overlap`], per piece), so the Verlet/RATTLE step conserves energy as it does for the
//! links, momentum and angular momentum to round-off, and the force grows continuously from
//! zero at first touch. A face-to-face contact of area `S` and depth `δ` has stiffness
//! `κ S²` (each of its `m` pieces takes `S/m`); over a cross-section `S = h^(dim−1)` that is
//! `s E h^(dim−2)`, the stiffness of a link of modulus `s E` (2-D: per unit depth).
//!
//! NOTE: why pieces. Two flat faces in full contact keep the whole overlap `V` unchanged to
//! first order when one turns against the other, so `½ κ V²` alone has no moment resistance,
//! and under load the faces turn at constant `V` while the centres approach (measured with it:
//! a block resting on a fixed floor rocked, in 3-D without ever settling, 3.7·10⁻⁴ m of drift
//! over 10⁴ steps). Turning moves volume from some pieces to others and `Σ V_p²` grows, which
//! resists like a Winkler foundation sampled at `m` points per face. Putting the force of
//! `½ κ V²` at the overlap centroid instead (as common polyhedral DEM does) also resists, but
//! is not a gradient: it lost 6 % of the energy in an oblique elastic impact at every dt tried.
//!
//! Dissipative part, at the centroid `G` of the whole overlap with the normal `n` of the
//! elastic force on B (from A to B) and the relative velocity `w` of B's material point at `G`
//! w.r.t. A's: a normal dashpot `−c_n (w·n) n`, `c_n = 2ζ √(k m*)`, `k = Σ κ_p |∇V_p|²` (the
//! tangent normal stiffness), `m*` the reduced mass and `ζ = −ln e / √(π² + ln² e)` for the
//! restitution `e` (the linear spring–dashpot value), limited so that the total normal force
//! never pulls (which leaves a head-on flat impact at e = 0.5 with 0.53–0.55); and a
//! regularised Coulomb friction `−min(μ N, c_t |w_t|) w_t/|w_t|`, `c_t = 2√(k m*)`, with `N` the
//! total normal force. These loads are evaluated at commit from the positions at n+1 and the
//! mid-step velocities `V^{n+1/2}`, `Ω^{n+1/2}`, and held like a force at n+1 (second half kick,
//! and first half kick of the next step): they are part of the checkpoint. Their work, the
//! trapezoidal `½ (D^n + D^{n+1})·(ΔX, Ω Δt)` summed over particles, goes to `dissipated`.
//!
//! NOTE: the friction is regularised (stateless), so a body under a sustained tangential load
//! `F_t` below the Coulomb limit creeps at `F_t / c_t` instead of sticking (measured on a
//! slope of 0.2 with μ = 0.3: 2–4 mm/s for the 0.1 m test block); above it, a body slides at
//! the Coulomb rate. A tangential spring (Cundall–Strack, per-pair history in the checkpoint)
//! held the block, but with friction at one point and no torsional friction the pushed half of
//! the 3-D bar test then twisted about the contact normal and kept spinning (a square face
//! turned on a square overlaps less, which is softer, which a dead load favours).
//! The law treats A and B alike except that B (the larger index) is the one cut into pieces.
//!
//! Past [`hold::HOLD_OVERLAP`] of the smaller particle's volume a pair also holds: at each half
//! kick its approach is stopped by a perfectly inelastic impulse ([`hold`]), so that impacts
//! faster than the law can stop (overlap `≈ w / (c √s)` of a particle for a relative speed `w`,
//! `c = √(E/ρ)`) stop at that depth instead of reaching the deep contact the step reports
//! ([`DEEP_OVERLAP`]).

pub mod broad;
pub mod hold;
pub mod overlap;
mod shapes;

#[cfg(test)]
mod tests;

use nalgebra::{Vector2, Vector3};

use protocol::scene::ContactConfig;

use crate::dem::model::{Model, ParticleMotion};
use crate::dem::parallel::{par_each, par_fill};
use broad::{Grid, candidate_pairs};
use overlap::{
    ClipScratch, Overlap, PolyhedronView, contact_polygon_polygon, contact_polyhedron_polyhedron,
};
pub use shapes::ContactError;
use shapes::{MAX_VERTICES, Piece, Shapes, build_shapes};

/// Overlap volume, as a fraction of the smaller particle's volume, that the step reports as
/// deep contact ([`crate::dem::Diagnostic::DeepContact`]): since pairs hold past
/// [`hold::HOLD_OVERLAP`], only a step that carries a pair from below that depth past this one
/// reaches it (a step too long for the pair's approach).
pub const DEEP_OVERLAP: f64 = 0.25;

/// Distance to a face plane, as a fraction of the smaller particle size, within which a point
/// counts as on the plane ([`overlap`]): far above round-off, far below any physical gap.
const COPLANAR: f64 = 1e-10;

/// Contact parameters (validated `[solid.contact]`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactParams {
    /// Stiffness factor `s` on Young's modulus \[-\].
    pub stiffness: f64,
    /// Damping ratio ζ of the normal dashpot \[-\] (from the restitution).
    pub zeta: f64,
    /// Coulomb coefficient μ \[-\].
    pub friction: f64,
}

impl ContactParams {
    /// From the scene table (validated by the scene parser).
    pub fn from_config(cfg: &ContactConfig) -> Self {
        let e = cfg.restitution;
        let zeta = if e <= 0.0 {
            1.0
        } else {
            let l = e.ln();
            -l / (std::f64::consts::PI * std::f64::consts::PI + l * l).sqrt()
        };
        ContactParams {
            stiffness: cfg.stiffness,
            zeta,
            friction: cfg.friction,
        }
    }

    /// Whether the law has a dissipative part.
    pub fn dissipative(&self) -> bool {
        self.zeta > 0.0 || self.friction > 0.0
    }
}

/// One candidate pair and its overlap at the last evaluation.
#[derive(Clone, Copy, Debug, Default)]
pub struct ContactPair {
    /// Particle A (the smaller index).
    pub a: u32,
    /// Particle B.
    pub b: u32,
    /// `κ` of the pair \[J/m^(2·dim)\].
    pub kappa: f64,
    /// The whole overlap (zero volume: apart).
    pub overlap: Overlap,
    /// Elastic force on B \[N\] (on A: the opposite).
    pub force_b: Vector3<f64>,
    /// Elastic torque on A about its centre \[N m\].
    pub torque_a: Vector3<f64>,
    /// Elastic torque on B about its centre \[N m\].
    pub torque_b: Vector3<f64>,
    /// Contact potential \[J\].
    pub energy: f64,
    /// Tangent normal stiffness `Σ κ_p |∇V_p|²` \[N/m\].
    pub stiffness: f64,
}

/// The contact model and its buffers.
#[derive(Clone, Debug)]
pub struct Contact {
    /// Parameters.
    pub params: ContactParams,
    shapes: Shapes,
    grid: Grid,
    candidates: Vec<(u32, u32)>,
    pairs: Vec<ContactPair>,
    /// World vertices of all particles (per evaluation).
    world: Vec<Vector3<f64>>,
    /// 3-D: world planes `(n, d)` of all faces.
    planes: Vec<(Vector3<f64>, f64)>,
    /// Per pair: force on B, torque on A, torque on B (dissipative part).
    damping: Vec<[Vector3<f64>; 3]>,
    /// Contact potential at the last evaluation \[J\].
    energy: f64,
}

thread_local! {
    static SCRATCH: std::cell::RefCell<ClipScratch> = std::cell::RefCell::new(ClipScratch::default());
}

impl Contact {
    /// Builds the shapes of every particle from the model; refuses a 2-D particle of more
    /// than 64 vertices (the kernels' stack buffers).
    pub fn new(model: &Model, params: ContactParams) -> Result<Self, ContactError> {
        let shapes = build_shapes(model)?;
        Ok(Contact {
            params,
            world: vec![Vector3::zeros(); shapes.vertices.len()],
            planes: vec![(Vector3::zeros(), 0.0); shapes.face_ranges.len()],
            shapes,
            grid: Grid::default(),
            candidates: Vec::new(),
            pairs: Vec::new(),
            damping: Vec::new(),
            energy: 0.0,
        })
    }

    /// Contact potential `Σ ½ κ V²` at the last evaluation \[J\].
    pub fn energy(&self) -> f64 {
        self.energy
    }

    /// Pairs examined by the narrow phase at the last evaluation (overlapping or not).
    pub fn pairs(&self) -> &[ContactPair] {
        &self.pairs
    }

    /// Conservative contact forces and torques at a configuration, added to `force` and
    /// `torque`; returns the contact potential. `rotate(p, v)` turns a body vector of `p`
    /// into space.
    #[allow(clippy::too_many_arguments)]
    pub fn add_forces(
        &mut self,
        model: &Model,
        pool: Option<&rayon::ThreadPool>,
        x: &[[f64; 3]],
        rotate: &Rotate<'_>,
        broken: &[bool],
        force: &mut [[f64; 3]],
        torque: &mut [[f64; 3]],
    ) -> f64 {
        let dim = model.dim;
        self.place_shapes(dim, pool, x, rotate);
        candidate_pairs(
            dim,
            x,
            &self.shapes.radius,
            &mut self.grid,
            &mut self.candidates,
        );
        self.keep_law_pairs(model, broken);
        let frame = Frame {
            shapes: &self.shapes,
            world: &self.world,
            planes: &self.planes,
            x,
            rotate,
        };
        par_each(pool, &mut self.pairs, |pair| pair_law(model, &frame, pair));
        self.gather(force, torque)
    }

    /// World vertices of every particle and (3-D) world planes of every face.
    fn place_shapes(
        &mut self,
        dim: usize,
        pool: Option<&rayon::ThreadPool>,
        x: &[[f64; 3]],
        rotate: &Rotate<'_>,
    ) {
        let shapes = &self.shapes;
        par_fill(pool, &mut self.world, |k| {
            let p = shapes.vertex_owner[k] as usize;
            Vector3::from(x[p]) + rotate(p, &shapes.vertices[k])
        });
        if dim == 3 {
            let world: &[Vector3<f64>] = &self.world;
            par_fill(pool, &mut self.planes, |f| {
                let p = shapes.face_owner[f] as usize;
                let n = rotate(p, &shapes.face_normals[f]);
                let (start, _) = shapes.face_ranges[f];
                let v0 = shapes.vertex_start[p] + shapes.face_vertices[start as usize];
                (n, n.dot(&world[v0 as usize]))
            });
        }
    }

    /// Keeps the candidate pairs the law applies to: not linked by an unbroken link, one at
    /// least free.
    fn keep_law_pairs(&mut self, model: &Model, broken: &[bool]) {
        let dim = model.dim;
        self.pairs.clear();
        for &(a, b) in &self.candidates {
            let (pa, pb) = (&model.particles[a as usize], &model.particles[b as usize]);
            if pa.motion != ParticleMotion::Free && pb.motion != ParticleMotion::Free {
                continue;
            }
            if linked(model, broken, a, b) {
                continue;
            }
            let h = pa.size.min(pb.size);
            self.pairs.push(ContactPair {
                a,
                b,
                kappa: self.params.stiffness * model.material.young / h.powi(dim as i32),
                ..ContactPair::default()
            });
        }
    }

    /// Serial gather of the pairs' loads in pair order (bit-reproducible); returns the contact
    /// potential.
    fn gather(&mut self, force: &mut [[f64; 3]], torque: &mut [[f64; 3]]) -> f64 {
        let mut energy = 0.0;
        for pair in &self.pairs {
            if pair.energy <= 0.0 {
                continue;
            }
            energy += pair.energy;
            let (a, b) = (pair.a as usize, pair.b as usize);
            for k in 0..3 {
                force[b][k] += pair.force_b[k];
                force[a][k] -= pair.force_b[k];
                torque[a][k] += pair.torque_a[k];
                torque[b][k] += pair.torque_b[k];
            }
        }
        self.energy = energy;
        energy
    }

    /// Dissipative loads (force, torque per particle) for the overlaps of the last
    /// [`Contact::add_forces`] and the velocities `v` (centres) and `omega` (space frame);
    /// `out` is overwritten.
    pub fn damping_loads(
        &mut self,
        model: &Model,
        pool: Option<&rayon::ThreadPool>,
        x: &[[f64; 3]],
        v: &[[f64; 3]],
        omega: &[[f64; 3]],
        out: &mut [[[f64; 3]; 2]],
    ) {
        for o in out.iter_mut() {
            *o = [[0.0; 3]; 2];
        }
        if !self.params.dissipative() {
            return;
        }
        let params = self.params;
        let pairs: &[ContactPair] = &self.pairs;
        self.damping.clear();
        self.damping.resize(pairs.len(), [Vector3::zeros(); 3]);
        par_fill(pool, &mut self.damping, |k| {
            pair_damping(model, &params, &pairs[k], x, v, omega)
        });
        for (pair, d) in pairs.iter().zip(&self.damping) {
            let (a, b) = (pair.a as usize, pair.b as usize);
            for k in 0..3 {
                out[b][0][k] += d[0][k];
                out[a][0][k] -= d[0][k];
                out[a][1][k] += d[1][k];
                out[b][1][k] += d[2][k];
            }
        }
    }

    /// Stability bound of the contact springs \[s\] and the particle that sets it: for each
    /// free particle, `2/ω` with `ω² = 2 n_f k (1/m + r²/I_min)`, `k = s E h^(dim−2)` the
    /// largest tangent stiffness of one contact, `r` the bounding radius and `n_f` its number
    /// of faces (the contacts it can have at once).
    ///
    /// NOTE: the bound takes `Σ_p κ_p |∇V_p|² ≤ κ h^(2(dim−1))` (a flat face gives `κ S²`; a
    /// box piece has `m S_p² ≤ h^(2(dim−1))/4`) and leaves out `κ_p V_p ∇²V_p`, small for
    /// shallow overlaps; deep overlaps are reported by the step.
    pub fn stability_limit(&self, model: &Model) -> (f64, u32) {
        let mut best = (f64::INFINITY, 0u32);
        for (p, part) in model.particles.iter().enumerate() {
            if part.motion != ParticleMotion::Free {
                continue;
            }
            let k =
                self.params.stiffness * model.material.young * part.size.powi(model.dim as i32 - 2);
            let i_min = if model.dim == 3 {
                part.inertia.iter().copied().fold(f64::INFINITY, f64::min)
            } else {
                part.inertia[0]
            };
            let r = self.shapes.radius[p];
            let n_faces = if model.dim == 3 {
                self.shapes.face_start[p + 1] - self.shapes.face_start[p]
            } else {
                self.shapes.vertex_start[p + 1] - self.shapes.vertex_start[p]
            };
            let w2 = 2.0 * n_faces as f64 * k * (1.0 / part.mass + r * r / i_min);
            let dt = 2.0 / w2.sqrt();
            if dt < best.0 {
                best = (dt, p as u32);
            }
        }
        best
    }
}

/// `rotate(p, v)`: a body vector `v` of particle `p` turned into space.
pub type Rotate<'a> = dyn Fn(usize, &Vector3<f64>) -> Vector3<f64> + Sync + 'a;

/// The particles' shapes placed at a configuration, as the narrow phase and the law read them.
struct Frame<'a> {
    shapes: &'a Shapes,
    /// World vertices of all particles.
    world: &'a [Vector3<f64>],
    /// 3-D: world planes `(n, d)` of all faces.
    planes: &'a [(Vector3<f64>, f64)],
    /// Centres.
    x: &'a [[f64; 3]],
    rotate: &'a Rotate<'a>,
}

/// The overlap of one pair and, when they overlap, the law piece by piece of B: elastic force,
/// torques, potential and tangent stiffness (zero when apart).
fn pair_law(model: &Model, frame: &Frame<'_>, pair: &mut ContactPair) {
    let dim = model.dim;
    let Frame {
        shapes,
        world,
        planes,
        x,
        rotate,
    } = *frame;
    let (a, b) = (pair.a as usize, pair.b as usize);
    let tol = COPLANAR * model.particles[a].size.min(model.particles[b].size);
    pair.overlap = SCRATCH.with(|s| {
        let scratch = &mut s.borrow_mut();
        if dim == 2 {
            overlap_2d(shapes, world, x, a, b, tol, scratch)
        } else {
            let view = |p: usize| polyhedron_view(frame, p);
            contact_polyhedron_polyhedron(&view(a), &view(b), tol, scratch)
        }
    });
    pair.force_b = Vector3::zeros();
    pair.torque_a = Vector3::zeros();
    pair.torque_b = Vector3::zeros();
    pair.energy = 0.0;
    pair.stiffness = 0.0;
    if pair.overlap.volume <= 0.0 {
        return;
    }
    // The law, piece by piece of B.
    let xb = Vector3::from(x[b]);
    let range = shapes.piece_start[b] as usize..shapes.piece_start[b + 1] as usize;
    let (va0, va1) = (
        shapes.vertex_start[a] as usize,
        shapes.vertex_start[a + 1] as usize,
    );
    let (fa0, fa1) = (
        shapes.face_start[a] as usize,
        shapes.face_start[a + 1] as usize,
    );
    for piece in &shapes.pieces[range] {
        // Cheap rejection: all corners outside one face plane of A.
        let corners = [
            xb,
            xb + rotate(b, &piece.corners[0]),
            xb + rotate(b, &piece.corners[1]),
            xb + rotate(b, &piece.corners[2]),
        ];
        // (2-D: the centre is `corners[0]` and `corners[1]`.)
        let outside = |n: &Vector3<f64>, d: f64| corners.iter().all(|c| n.dot(c) > d);
        let separated = if dim == 2 {
            let poly = &world[va0..va1];
            (0..poly.len()).any(|k| {
                let e = poly[(k + 1) % poly.len()] - poly[k];
                let n = Vector3::new(e.y, -e.x, 0.0);
                outside(&n, n.dot(&poly[k]))
            })
        } else {
            planes[fa0..fa1].iter().any(|(n, d)| outside(n, *d))
        };
        if separated {
            continue;
        }
        let o = piece_overlap(dim, frame, a, b, piece, tol);
        if o.volume <= 0.0 {
            continue;
        }
        let kappa = pair.kappa * piece.multiplier;
        let scale = kappa * o.volume;
        pair.energy += 0.5 * scale * o.volume;
        pair.force_b -= o.grad_b * scale;
        pair.torque_a -= o.grad_rot_a * scale;
        pair.torque_b -= o.grad_rot_b * scale;
        pair.stiffness += kappa * o.grad_b.norm_squared();
    }
}

/// Particle `p` as a polyhedron in space (3-D).
fn polyhedron_view<'a>(frame: &Frame<'a>, p: usize) -> PolyhedronView<'a> {
    let shapes = frame.shapes;
    let (f0, f1) = (
        shapes.face_start[p] as usize,
        shapes.face_start[p + 1] as usize,
    );
    let (v0, v1) = (
        shapes.vertex_start[p] as usize,
        shapes.vertex_start[p + 1] as usize,
    );
    PolyhedronView {
        vertices: &frame.world[v0..v1],
        face_ranges: &shapes.face_ranges[f0..f1],
        face_vertices: &shapes.face_vertices,
        planes: &frame.planes[f0..f1],
        center: Vector3::from(frame.x[p]),
    }
}

/// The overlap of particle A with one piece of B, placed in space.
fn piece_overlap(
    dim: usize,
    frame: &Frame<'_>,
    a: usize,
    b: usize,
    piece: &Piece,
    tol: f64,
) -> Overlap {
    let (world, x, rotate) = (frame.world, frame.x, frame.rotate);
    let xb = Vector3::from(x[b]);
    SCRATCH.with(|s| {
        let scratch = &mut s.borrow_mut();
        if dim == 2 {
            let (v0, v1) = (
                frame.shapes.vertex_start[a] as usize,
                frame.shapes.vertex_start[a + 1] as usize,
            );
            let mut pa = [Vector2::zeros(); MAX_VERTICES];
            for (k, w) in world[v0..v1].iter().enumerate() {
                pa[k] = w.xy();
            }
            let tri = piece.corners.map(|c| (xb + rotate(b, &c)).xy());
            contact_polygon_polygon(
                &pa[..v1 - v0],
                Vector2::new(x[a][0], x[a][1]),
                &tri,
                xb.xy(),
                tol,
                scratch,
            )
        } else {
            let planes = piece.planes.map(|(n, p)| {
                let n = rotate(b, &n);
                (n, n.dot(&(xb + rotate(b, &p))))
            });
            let view_a = polyhedron_view(frame, a);
            let view_b = PolyhedronView {
                vertices: &[],
                face_ranges: &[],
                face_vertices: &[],
                planes: &planes,
                center: xb,
            };
            contact_polyhedron_polyhedron(&view_a, &view_b, tol, scratch)
        }
    })
}

/// Whether `a` and `b` are joined by an unbroken link.
fn linked(model: &Model, broken: &[bool], a: u32, b: u32) -> bool {
    let range =
        model.incidence_start[a as usize] as usize..model.incidence_start[a as usize + 1] as usize;
    model.incidence[range].iter().any(|&(l, _)| {
        let link = &model.links[l as usize];
        (link.i == b || link.j == b) && !broken[l as usize]
    })
}

fn overlap_2d(
    shapes: &Shapes,
    world: &[Vector3<f64>],
    x: &[[f64; 3]],
    a: usize,
    b: usize,
    tol: f64,
    scratch: &mut ClipScratch,
) -> Overlap {
    const MAX: usize = MAX_VERTICES;
    let flat = |p: usize, buf: &mut [Vector2<f64>; MAX]| -> usize {
        let (v0, v1) = (
            shapes.vertex_start[p] as usize,
            shapes.vertex_start[p + 1] as usize,
        );
        debug_assert!(v1 - v0 <= MAX, "checked by Contact::new");
        for (k, w) in world[v0..v1].iter().enumerate() {
            buf[k] = w.xy();
        }
        v1 - v0
    };
    let mut pa = [Vector2::zeros(); MAX];
    let mut pb = [Vector2::zeros(); MAX];
    let na = flat(a, &mut pa);
    let nb = flat(b, &mut pb);
    contact_polygon_polygon(
        &pa[..na],
        Vector2::new(x[a][0], x[a][1]),
        &pb[..nb],
        Vector2::new(x[b][0], x[b][1]),
        tol,
        scratch,
    )
}

/// Dissipative loads of one pair: force on B, torque on A, torque on B.
fn pair_damping(
    model: &Model,
    params: &ContactParams,
    pair: &ContactPair,
    x: &[[f64; 3]],
    v: &[[f64; 3]],
    omega: &[[f64; 3]],
) -> [Vector3<f64>; 3] {
    let o = &pair.overlap;
    let elastic = pair.force_b.norm();
    if pair.energy <= 0.0 || elastic <= 0.0 {
        return [Vector3::zeros(); 3];
    }
    let (a, b) = (pair.a as usize, pair.b as usize);
    let n = pair.force_b / elastic;
    let (ra, rb) = (
        o.centroid - Vector3::from(x[a]),
        o.centroid - Vector3::from(x[b]),
    );
    let (wa, wb) = (Vector3::from(omega[a]), Vector3::from(omega[b]));
    let rel = (Vector3::from(v[b]) + wb.cross(&rb)) - (Vector3::from(v[a]) + wa.cross(&ra));
    let (pa, pb) = (&model.particles[a], &model.particles[b]);
    let m_red = match (pa.motion, pb.motion) {
        (ParticleMotion::Free, ParticleMotion::Free) => pa.mass * pb.mass / (pa.mass + pb.mass),
        (ParticleMotion::Free, _) => pa.mass,
        _ => pb.mass,
    };
    let root = (pair.stiffness * m_red).sqrt();
    let w_n = rel.dot(&n);
    // The dashpot never makes the normal force pull.
    let damp = (-2.0 * params.zeta * root * w_n).max(-elastic);
    let mut f = n * damp;
    if params.friction > 0.0 {
        let w_t = rel - n * w_n;
        let speed = w_t.norm();
        if speed > 0.0 {
            let magnitude = (params.friction * (elastic + damp)).min(2.0 * root * speed);
            f -= w_t * (magnitude / speed);
        }
    }
    [f, ra.cross(&(-f)), rb.cross(&f)]
}
