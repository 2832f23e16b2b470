//! [`Solid`]: the DEM state and its splittable step (`begin_step`, `trial`…, `commit`).
//!
//! Translation: velocity Verlet (003 eq. (4), (5), (8)); rotation: RATTLE (eq. (6), (7), (9))
//! through [`crate::dem::rattle`] in 3-D, the same kick–drift–kick on the angle in 2-D (rotation
//! about a fixed axis, where RATTLE is exactly Verlet). External loads are held fixed over the
//! step (003 eq. (14)–(17)): they enter both half kicks.

use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use protocol::scene::{FaceInertia, Motion, SolidConfig, SolidInit};

use crate::dem::contact::{Contact, ContactParams};
use crate::dem::lattice::build_lattice;
use crate::dem::link_force::LinkOut;
use crate::dem::model::{LinkId, Material, Model, ParticleId, ParticleMotion, build_model, to3};
use crate::dem::report::{Energies, Momentum};
use crate::dem::stability::elastic_limit;
use crate::dem::wet::{
    WetSurfaceData, WetTopology, build_elements, group_slots, write_connectivity, write_geometry,
};

/// Items per rayon task. NOTE: a fixed partition; every item is computed independently and
/// every reduction runs serially in index order, so results do not depend on the thread count.
pub(crate) const CHUNK: usize = 256;

/// [`par_fill`] runs serially below this many items: waking the pool, and its workers'
/// spinning after the job, cost tens of µs per call, more than a few chunks of link or particle
/// updates take (a 2-D beam of 728 particles and 1390 links spent most of its trial in futex
/// wake-ups). Items are independent, so the bits are the same either way.
pub(crate) const SERIAL_BELOW: usize = 8 * CHUNK;

/// Safety factor applied to the elastic bound in [`Solid::max_dt`].
pub const ELASTIC_SAFETY: f64 = 0.9;

/// Rotation allowed per step (003 §2.2) \[rad\].
pub const MAX_ROTATION: f64 = std::f64::consts::PI / 8.0;

/// Serializable dynamic state (the checkpoint).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct State {
    n_particles: u64,
    n_links: u64,
    step: u64,
    time: f64,
    x: Vec<[f64; 3]>,
    v: Vec<[f64; 3]>,
    /// 3-D: quaternion (w, x, y, z) of the principal frame; 2-D: `\[θ, 0, 0, 0\]`.
    rot: Vec<[f64; 4]>,
    /// 3-D: body angular momentum `I ω`; 2-D: `\[0, 0, ω\]`.
    ang: Vec<[f64; 3]>,
    broken: Vec<bool>,
    dissipated: f64,
    external_work: f64,
    /// Work the prescribed motions did on the solid so far \[J\]: what their constraints put in
    /// to hold the motion against the loads, internal and external, on the driven particles.
    driven_work: f64,
    /// Impulse of the external loads so far, `Σ F Δt` over all particles (fixed ones too).
    external_impulse: [f64; 3],
    wet_revision: u64,
    /// Dissipative contact loads `[force, torque]` per particle at n (empty without contact).
    contact_damping: Vec<[[f64; 3]; 2]>,
}

/// One particle's share of a trial.
#[derive(Clone, Copy, Debug, Default)]
struct ParticleTrial {
    x: [f64; 3],
    v_half: [f64; 3],
    rot: [f64; 4],
    /// 3-D: `m⁻ = Ωᵀ m½`; 2-D: `\[0, 0, ω½\]`.
    ang: [f64; 3],
    /// Mean angular velocity over the step, space frame.
    omega: [f64; 3],
    angle: f64,
    residual: f64,
}

/// Positions and velocities of a trial step (not yet committed).
#[derive(Clone, Debug, Default)]
pub struct Trial {
    /// Spatial dimension.
    pub dim: usize,
    /// Centres `X^{n+1}` \[m\], `dim` each.
    pub position: Vec<f64>,
    /// Orientation at n+1 relative to t = 0: 2-D the angle \[rad\], 3-D the unit quaternion
    /// `(w, x, y, z)` of `Q^{n+1}` (identity at t = 0).
    pub orientation: Vec<f64>,
    /// `V^{n+1/2}` \[m/s\], `dim` each.
    pub velocity_half: Vec<f64>,
    /// Mean angular velocity `Ω^{n+1/2}` over the step, space frame \[rad/s\] (2-D: 1 each).
    pub omega_half: Vec<f64>,
    /// Wet surface at n+1; element velocities are `V^{n+1/2} + Ω^{n+1/2} × (x − X^{n+1})`.
    pub wet: WetSurfaceData,
}

/// The discrete-element solid.
///
/// ```
/// use protocol::scene::Scene;
/// use solid_node::dem::Solid;
/// let scene = Scene::from_toml_str(r#"
///     name = "bar"
///     [solid]
///     density = 1000.0
///     young = 1e6
///     poisson = 0.0
///     [[solid.bodies]]
///     shape = { box = { center = [0.0, 0.0], size = [0.4, 0.1] } }
///     divisions = [4, 1]
/// "#, "doc").unwrap();
/// let mut solid = Solid::from_scene(scene.solid.as_ref().unwrap(), 2, 1).unwrap();
/// let dt = solid.max_dt(f64::INFINITY);
/// solid.begin_step(dt);
/// let n = solid.n_particles();
/// solid.trial(&vec![0.0; 2 * n], &vec![0.0; n]);
/// let report = solid.commit();
/// assert!(report.diagnostics.is_empty());
/// ```
pub struct Solid {
    model: Model,
    gravity: [f64; 3],
    elongation_at_break: Option<f64>,
    pool: Option<rayon::ThreadPool>,
    state: State,
    // Scratch and caches (not in the checkpoint; recomputed from the state).
    scratch: ForceScratch,
    force_int: Vec<[f64; 3]>,
    torque_int: Vec<[f64; 3]>,
    elastic: f64,
    forces_valid: bool,
    dt: f64,
    ext_force: Vec<[f64; 3]>,
    ext_torque: Vec<[f64; 3]>,
    particle_trial: Vec<ParticleTrial>,
    trial: Trial,
    trial_valid: bool,
    topo: WetTopology,
    wet: WetSurfaceData,
    sums: Vec<(Vector3<f64>, u32)>,
    /// Reused per-particle buffers for the wet-surface geometry (x, v, ω, orientation).
    kin: KinematicsScratch,
    limit: (f64, u32),
    /// Contact model (absent: `[solid.contact]` absent, nothing computed).
    contact: Option<Contact>,
    /// Stability bound of the contact springs (∞ without contact).
    contact_limit: (f64, u32),
    /// Per particle `[ΔX, Ω Δt]` of the step being committed.
    motion: Vec<[[f64; 3]; 2]>,
    /// Output of [`Solid::evaluate_contact`].
    bench_loads: (Vec<[f64; 3]>, Vec<[f64; 3]>),
    /// Centres and orientations at n of the step being committed (with fracture only: the
    /// energy a breaking link takes is evaluated there, [`Solid::break_dissipation`]).
    before_step: (Vec<[f64; 3]>, Vec<[f64; 4]>),
}

/// Per-particle buffers `(x, v, ω, orientation)` reused by the wet-surface geometry.
type KinematicsScratch = (Vec<[f64; 3]>, Vec<[f64; 3]>, Vec<[f64; 3]>, Vec<[f64; 4]>);

/// Fills `out\[k\] = f(k)` over a fixed partition (serially below [`SERIAL_BELOW`] items).
pub(crate) fn par_fill<T: Send>(
    pool: Option<&rayon::ThreadPool>,
    out: &mut [T],
    f: impl Fn(usize) -> T + Sync + Send,
) {
    match pool {
        Some(pool) if out.len() >= SERIAL_BELOW => pool.install(|| {
            out.par_chunks_mut(CHUNK)
                .enumerate()
                .for_each(|(c, chunk)| {
                    for (k, o) in chunk.iter_mut().enumerate() {
                        *o = f(c * CHUNK + k);
                    }
                })
        }),
        _ => {
            for (k, o) in out.iter_mut().enumerate() {
                *o = f(k);
            }
        }
    }
}

fn quat(r: &[f64; 4]) -> UnitQuaternion<f64> {
    UnitQuaternion::new_unchecked(nalgebra::Quaternion::new(r[0], r[1], r[2], r[3]))
}

fn quat_arr(q: &UnitQuaternion<f64>) -> [f64; 4] {
    [q.w, q.i, q.j, q.k]
}

mod forces;
mod step;

use forces::{ForceScratch, internal_forces};

impl Solid {
    /// Builds the solid of a scene: `dim` is the scene's dimension (2 or 3), `threads` the
    /// worker threads (1: no pool; results are bit-identical for any count).
    ///
    /// Bodies' `motion` and then `[[solid.constraints]]` set each particle's motion; then the
    /// `[[solid.init]]` entries, in order, give the free particles whose centre lies in their
    /// region their initial velocity and angular velocity ([`Solid::set_velocity`],
    /// [`Solid::set_angular_velocity`]). Fixed particles and particles with a prescribed
    /// velocity keep their prescribed motion: an init entry never overrides a constraint.
    pub fn from_scene(cfg: &SolidConfig, dim: usize, threads: usize) -> Result<Self, String> {
        let material = Material {
            density: cfg.density.ok_or("solid.density is required")?,
            young: cfg.young.ok_or("solid.young is required")?,
            poisson: cfg.poisson.ok_or("solid.poisson is required")?,
            face_inertia: cfg.face_inertia.unwrap_or_default(),
        };
        if material.face_inertia == FaceInertia::Unweighted && dim != 3 {
            return Err(
                "solid.face_inertia = \"unweighted\" is defined for 3-D scenes only".into(),
            );
        }
        if !(material.density > 0.0 && material.young > 0.0) {
            return Err(format!(
                "solid: expected density > 0 and young > 0, found {} and {}",
                material.density, material.young
            ));
        }
        if !(0.0..0.5).contains(&material.poisson) {
            return Err(format!(
                "solid.poisson: expected a number in [0, 0.5), found {}",
                material.poisson
            ));
        }
        let lattice = build_lattice(&cfg.bodies, dim)?;
        let mut model = build_model(&lattice, material)?;
        for c in &cfg.constraints {
            for p in model.particles.iter_mut() {
                let x0 = p.x0;
                if c.region.contains(&x0.as_slice()[..dim]) {
                    p.motion = match &c.motion {
                        Motion::Free => ParticleMotion::Free,
                        Motion::Fixed => ParticleMotion::Fixed,
                        Motion::Velocity(v) => ParticleMotion::Velocity(to3(v)),
                    };
                }
            }
        }
        let gravity = match &cfg.gravity {
            Some(g) if g.len() != dim => {
                return Err(format!(
                    "solid.gravity: expected {dim} components, found {g:?}"
                ));
            }
            Some(g) => to3(g),
            None => [0.0; 3],
        };
        let elongation_at_break = cfg.fracture.as_ref().map(|f| f.elongation_at_break);
        let pool = if threads > 1 {
            Some(
                rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .map_err(|e| format!("building the solid's thread pool: {e}"))?,
            )
        } else {
            None
        };
        for (k, init) in cfg.init.iter().enumerate() {
            let n_rot = if dim == 3 { 3 } else { 1 };
            if let Some(v) = init.velocity.as_ref().filter(|v| v.len() != dim) {
                return Err(format!(
                    "solid.init[{k}].velocity: expected {dim} components, found {v:?}"
                ));
            }
            if let Some(w) = init.angular_velocity.as_ref().filter(|w| w.len() != n_rot) {
                return Err(format!(
                    "solid.init[{k}].angular_velocity: expected {n_rot} components, found {w:?}"
                ));
            }
        }
        let contact = match &cfg.contact {
            Some(c) => Some(Contact::new(&model, ContactParams::from_config(c))?),
            None => None,
        };
        let mut solid = Self::from_model(model, gravity, elongation_at_break, pool, contact);
        solid.apply_init(&cfg.init);
        Ok(solid)
    }

    /// Applies `[[solid.init]]` entries in order (lengths checked by the caller) and brings the
    /// committed wet surface's element velocities up to date.
    fn apply_init(&mut self, inits: &[SolidInit]) {
        if inits.is_empty() {
            return;
        }
        let dim = self.model.dim;
        for init in inits {
            for p in 0..self.n_particles() {
                let x0 = self.model.particles[p].x0;
                if !init.region.contains(&x0.as_slice()[..dim]) {
                    continue;
                }
                let id = ParticleId(p as u32);
                if let Some(v) = &init.velocity {
                    self.set_velocity(id, v);
                }
                if let Some(w) = &init.angular_velocity {
                    self.set_angular_velocity(id, w);
                }
            }
        }
        self.update_wet();
    }

    fn from_model(
        model: Model,
        gravity: [f64; 3],
        elongation_at_break: Option<f64>,
        pool: Option<rayon::ThreadPool>,
        contact: Option<Contact>,
    ) -> Self {
        let n = model.particles.len();
        let n_links = model.links.len();
        let state = State {
            n_particles: n as u64,
            n_links: n_links as u64,
            step: 0,
            time: 0.0,
            x: model.particles.iter().map(|p| p.x0.into()).collect(),
            v: model
                .particles
                .iter()
                .map(|p| match p.motion {
                    ParticleMotion::Velocity(v) => v,
                    _ => [0.0; 3],
                })
                .collect(),
            rot: model
                .particles
                .iter()
                .map(|p| {
                    if model.dim == 3 {
                        quat_arr(&p.axes0)
                    } else {
                        [0.0; 4]
                    }
                })
                .collect(),
            ang: vec![[0.0; 3]; n],
            broken: vec![false; n_links],
            dissipated: 0.0,
            external_work: 0.0,
            driven_work: 0.0,
            external_impulse: [0.0; 3],
            wet_revision: 0,
            contact_damping: if contact.is_some() {
                vec![[[0.0; 3]; 2]; n]
            } else {
                Vec::new()
            },
        };
        let topo = build_elements(&model, elongation_at_break.is_some());
        let contact_limit = contact
            .as_ref()
            .map_or((f64::INFINITY, 0), |c| c.stability_limit(&model));
        let limit = min_limit(elastic_limit(&model, &state.broken), contact_limit);
        let mut solid = Solid {
            gravity,
            elongation_at_break,
            pool,
            state,
            scratch: ForceScratch {
                gaps: vec![0.0; n_links],
                eps: vec![0.0; n],
                link_out: vec![LinkOut::default(); n_links],
                rotation: vec![Matrix3::identity(); n],
                loads: vec![[[0.0; 3]; 2]; n],
            },
            force_int: vec![[0.0; 3]; n],
            torque_int: vec![[0.0; 3]; n],
            elastic: 0.0,
            forces_valid: false,
            dt: 0.0,
            ext_force: vec![[0.0; 3]; n],
            ext_torque: vec![[0.0; 3]; n],
            particle_trial: vec![ParticleTrial::default(); n],
            trial: Trial::default(),
            trial_valid: false,
            topo,
            wet: WetSurfaceData::default(),
            sums: Vec::new(),
            kin: (Vec::new(), Vec::new(), Vec::new(), Vec::new()),
            limit,
            contact,
            contact_limit,
            motion: vec![[[0.0; 3]; 2]; n],
            bench_loads: (Vec::new(), Vec::new()),
            before_step: (Vec::new(), Vec::new()),
            model,
        };
        solid.rebuild_wet_topology();
        solid.update_forces();
        solid.update_wet();
        solid
    }

    /// Number of particles.
    pub fn n_particles(&self) -> usize {
        self.model.particles.len()
    }

    /// Spatial dimension (2 or 3).
    pub fn dim(&self) -> usize {
        self.model.dim
    }

    /// The model (particles, links, faces).
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// Steps committed so far.
    pub fn step_count(&self) -> u64 {
        self.state.step
    }

    /// Simulated time \[s\].
    pub fn time(&self) -> f64 {
        self.state.time
    }

    /// Centre of particle `p` \[m\] (`dim` components used).
    pub fn position(&self, p: ParticleId) -> [f64; 3] {
        self.state.x[p.0 as usize]
    }

    /// Velocity of particle `p` \[m/s\].
    pub fn velocity(&self, p: ParticleId) -> [f64; 3] {
        self.state.v[p.0 as usize]
    }

    /// Orientation relative to t = 0: 2-D `\[θ, 0, 0, 0\]`, 3-D the quaternion `(w, x, y, z)`.
    pub fn orientation(&self, p: ParticleId) -> [f64; 4] {
        let i = p.0 as usize;
        if self.model.dim == 3 {
            quat_arr(&(quat(&self.state.rot[i]) * self.model.particles[i].axes0.inverse()))
        } else {
            self.state.rot[i]
        }
    }

    /// Rotation matrix `Q` of particle `p` relative to t = 0, row-major (2-D: about z).
    pub fn rotation_matrix(&self, p: ParticleId) -> [[f64; 3]; 3] {
        let i = p.0 as usize;
        let m = if self.model.dim == 3 {
            (quat(&self.state.rot[i]) * self.model.particles[i].axes0.inverse())
                .to_rotation_matrix()
                .into_inner()
        } else {
            nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), self.state.rot[i][0])
                .into_inner()
        };
        [
            [m[(0, 0)], m[(0, 1)], m[(0, 2)]],
            [m[(1, 0)], m[(1, 1)], m[(1, 2)]],
            [m[(2, 0)], m[(2, 1)], m[(2, 2)]],
        ]
    }

    /// Angular velocity of particle `p`, space frame \[rad/s\] (2-D: z only).
    pub fn angular_velocity(&self, p: ParticleId) -> [f64; 3] {
        let i = p.0 as usize;
        if self.model.dim == 3 {
            let inertia = self.model.particles[i].inertia;
            let m = self.state.ang[i];
            let w = Vector3::new(m[0] / inertia[0], m[1] / inertia[1], m[2] / inertia[2]);
            (quat(&self.state.rot[i]) * w).into()
        } else {
            self.state.ang[i]
        }
    }

    /// Sets the velocity of a free particle \[m/s\] (initial conditions).
    pub fn set_velocity(&mut self, p: ParticleId, v: &[f64]) {
        let i = p.0 as usize;
        if self.model.particles[i].motion == ParticleMotion::Free {
            self.state.v[i] = to3(v);
        }
        self.trial_valid = false;
    }

    /// Sets the angular velocity of a free particle, space frame \[rad/s\] (2-D: one value).
    pub fn set_angular_velocity(&mut self, p: ParticleId, omega: &[f64]) {
        let i = p.0 as usize;
        if self.model.particles[i].motion != ParticleMotion::Free {
            return;
        }
        if self.model.dim == 3 {
            let w_body =
                quat(&self.state.rot[i]).inverse_transform_vector(&Vector3::from(to3(omega)));
            let inertia = self.model.particles[i].inertia;
            self.state.ang[i] = [
                inertia[0] * w_body.x,
                inertia[1] * w_body.y,
                inertia[2] * w_body.z,
            ];
        } else {
            self.state.ang[i] = [0.0, 0.0, omega[0]];
        }
        self.trial_valid = false;
    }

    /// Whether link `l` is broken.
    pub fn is_broken(&self, l: LinkId) -> bool {
        self.state.broken[l.0 as usize]
    }

    /// Internal force on particle `p` at the current configuration \[N\].
    pub fn internal_force(&self, p: ParticleId) -> [f64; 3] {
        self.force_int[p.0 as usize]
    }

    /// Internal torque on particle `p` (space frame) \[N m\].
    pub fn internal_torque(&self, p: ParticleId) -> [f64; 3] {
        self.torque_int[p.0 as usize]
    }

    /// Test hook: mutable positions and orientations (internal representation), forces then
    /// recomputed by [`Solid::recompute_for_tests`].
    #[cfg(test)]
    pub(crate) fn pose_mut_for_tests(&mut self) -> (&mut Vec<[f64; 3]>, &mut Vec<[f64; 4]>) {
        (&mut self.state.x, &mut self.state.rot)
    }

    /// Test hook: recomputes forces and energy; returns the elastic energy.
    #[cfg(test)]
    pub(crate) fn recompute_for_tests(&mut self) -> f64 {
        self.recompute_internal_forces()
    }

    /// Evaluates every unbroken link (and, with `[solid.contact]`, every contact) at the
    /// committed configuration again (the step does this itself; exposed for benchmarks and
    /// diagnostics). Returns the elastic energy of the links \[J\].
    pub fn recompute_internal_forces(&mut self) -> f64 {
        self.update_forces();
        self.elastic
    }

    fn update_forces(&mut self) {
        self.elastic = internal_forces(
            &self.model,
            self.pool.as_ref(),
            &self.state.x,
            &self.state.rot,
            &self.state.broken,
            &mut self.scratch,
            &mut self.force_int,
            &mut self.torque_int,
        );
        if let Some(contact) = self.contact.as_mut() {
            let dim = self.model.dim;
            let rot = &self.state.rot;
            let rotate = |p: usize, v: &Vector3<f64>| rotate_body(dim, &rot[p], v);
            contact.add_forces(
                &self.model,
                self.pool.as_ref(),
                &self.state.x,
                &rotate,
                &self.state.broken,
                &mut self.force_int,
                &mut self.torque_int,
            );
        }
        self.forces_valid = true;
    }

    /// The stability bound now: links and contact.
    fn stability_limit(&self) -> (f64, u32) {
        min_limit(
            elastic_limit(&self.model, &self.state.broken),
            self.contact_limit,
        )
    }

    /// The contact model, if `[solid.contact]` is on.
    pub fn contact(&self) -> Option<&Contact> {
        self.contact.as_ref()
    }

    /// Evaluates the contact alone (broad phase, narrow phase, law) at the committed
    /// configuration into scratch buffers, leaving the solid unchanged (for benchmarks).
    /// Returns the pairs the narrow phase examined and those overlapping; `(0, 0)` without
    /// contact.
    pub fn evaluate_contact(&mut self) -> (usize, usize) {
        let Some(contact) = self.contact.as_mut() else {
            return (0, 0);
        };
        let n = self.model.particles.len();
        let (force, torque) = &mut self.bench_loads;
        force.clear();
        force.resize(n, [0.0; 3]);
        torque.clear();
        torque.resize(n, [0.0; 3]);
        let dim = self.model.dim;
        let rot = &self.state.rot;
        let rotate = |p: usize, v: &Vector3<f64>| rotate_body(dim, &rot[p], v);
        contact.add_forces(
            &self.model,
            self.pool.as_ref(),
            &self.state.x,
            &rotate,
            &self.state.broken,
            force,
            torque,
        );
        let pairs = contact.pairs();
        (pairs.len(), pairs.iter().filter(|p| p.energy > 0.0).count())
    }

    fn rebuild_wet_topology(&mut self) {
        group_slots(&self.model, &self.state.broken, &mut self.topo);
        write_connectivity(&self.model, &self.state.broken, &self.topo, &mut self.wet);
        self.wet.revision = self.state.wet_revision;
    }

    fn update_wet(&mut self) {
        let n = self.n_particles();
        let mut omega = std::mem::take(&mut self.kin.2);
        omega.clear();
        omega.extend((0..n).map(|p| self.angular_velocity(ParticleId(p as u32))));
        let dim = self.model.dim;
        let rot = &self.state.rot;
        let rotate = |p: usize, v: &Vector3<f64>| rotate_body(dim, &rot[p], v);
        write_geometry(
            &self.model,
            &self.topo,
            &self.state.x,
            &rotate,
            &self.state.v,
            &omega,
            &mut self.sums,
            &mut self.wet,
        );
        self.kin.2 = omega;
    }

    /// The largest step allowed now \[s\]: `ELASTIC_SAFETY ×` the stability bound (links and,
    /// with `[solid.contact]`, the contact springs: [`Solid::elastic_dt_limit`]), the step that
    /// moves a particle by its size h_s or by `displacement_cap` (the caller's limit, e.g. one
    /// fluid cell), and the step that turns a particle by π/8 (003 §2.2).
    pub fn max_dt(&self, displacement_cap: f64) -> f64 {
        let mut dt = ELASTIC_SAFETY * self.limit.0;
        for (i, p) in self.model.particles.iter().enumerate() {
            let speed = Vector3::from(self.state.v[i]).norm();
            if speed > 0.0 {
                dt = dt.min(p.size / speed).min(displacement_cap / speed);
            }
            let w = Vector3::from(self.angular_velocity(ParticleId(i as u32))).norm();
            if w > 0.0 {
                dt = dt.min(MAX_ROTATION / w);
            }
        }
        dt
    }

    /// Stability bound of the explicit scheme \[s\] and the particle that sets it: the links'
    /// (see [`crate::dem::stability`]) and, with contact, the contact springs'
    /// ([`Contact::stability_limit`]).
    pub fn elastic_dt_limit(&self) -> (f64, ParticleId) {
        (self.limit.0, ParticleId(self.limit.1))
    }

    /// The wet surface at the committed state (velocities at n).
    pub fn wet_surface(&self) -> &WetSurfaceData {
        &self.wet
    }

    /// Impulse the external loads gave the particles so far, `Σ_steps Σ_p F_p Δt` (fixed
    /// particles included: what they receive goes to their constraint).
    pub fn external_impulse(&self) -> [f64; 3] {
        self.state.external_impulse
    }

    /// Energies at the committed state.
    pub fn energies(&self) -> Energies {
        let mut e = Energies {
            elastic: self.elastic,
            contact: self.contact.as_ref().map_or(0.0, |c| c.energy()),
            dissipated: self.state.dissipated,
            external_work: self.state.external_work,
            driven_work: self.state.driven_work,
            ..Energies::default()
        };
        for (p, part) in self.model.particles.iter().enumerate() {
            let v = Vector3::from(self.state.v[p]);
            e.kinetic_translation += 0.5 * part.mass * v.norm_squared();
            let m = self.state.ang[p];
            if self.model.dim == 3 {
                for (mk, ik) in m.iter().zip(&part.inertia) {
                    e.kinetic_rotation += 0.5 * mk * mk / ik;
                }
            } else {
                e.kinetic_rotation += 0.5 * part.inertia[0] * m[2] * m[2];
            }
            if part.motion == ParticleMotion::Free {
                e.gravity -=
                    part.mass * Vector3::from(self.gravity).dot(&Vector3::from(self.state.x[p]));
            }
        }
        e
    }

    /// Linear and angular momentum (about the origin) at the committed state.
    pub fn momentum(&self) -> Momentum {
        let mut lin = Vector3::zeros();
        let mut ang = Vector3::zeros();
        for (p, part) in self.model.particles.iter().enumerate() {
            let mv = Vector3::from(self.state.v[p]) * part.mass;
            lin += mv;
            ang += Vector3::from(self.state.x[p]).cross(&mv);
            if self.model.dim == 3 {
                ang += quat(&self.state.rot[p]) * Vector3::from(self.state.ang[p]);
            } else {
                ang.z += part.inertia[0] * self.state.ang[p][2];
            }
        }
        Momentum {
            linear: lin.into(),
            angular: ang.into(),
        }
    }

    /// Normal stress of each particle \[Pa\]: the mean over its unbroken links of the normal
    /// traction `F_J→I · (X_J − X_I)/|X_J − X_I| / S_IJ` (positive in tension, 0 without links),
    /// the quantity plotted in 000 Fig. 16.
    pub fn normal_stress(&self) -> Vec<f64> {
        let mut out = vec![0.0; self.n_particles()];
        for (p, value) in out.iter_mut().enumerate() {
            let range =
                self.model.incidence_start[p] as usize..self.model.incidence_start[p + 1] as usize;
            let mut sum = 0.0;
            let mut count = 0;
            for &(l, is_i) in &self.model.incidence[range] {
                if self.state.broken[l as usize] {
                    continue;
                }
                let link = &self.model.links[l as usize];
                let other = if is_i { link.j } else { link.i } as usize;
                let dir = (Vector3::from(self.state.x[other]) - Vector3::from(self.state.x[p]))
                    .normalize();
                let f = self.scratch.link_out[l as usize].force_i * if is_i { 1.0 } else { -1.0 };
                sum += f.dot(&dir) / link.area;
                count += 1;
            }
            if count > 0 {
                *value = sum / count as f64;
            }
        }
        out
    }

    /// The full dynamic state as bytes (`protocol::codec::encode_blob`).
    pub fn to_checkpoint(&self) -> Vec<u8> {
        protocol::codec::encode_blob(&self.state)
    }

    /// Restores a state written by [`Solid::to_checkpoint`] of a solid built from the same scene.
    pub fn restore_checkpoint(&mut self, bytes: &[u8]) -> Result<(), String> {
        let state: State = protocol::codec::decode_blob(bytes)?;
        if state.n_particles as usize != self.n_particles()
            || state.n_links as usize != self.model.links.len()
        {
            return Err(format!(
                "checkpoint of {} particles and {} links, the solid has {} and {}",
                state.n_particles,
                state.n_links,
                self.n_particles(),
                self.model.links.len()
            ));
        }
        let n_damping = if self.contact.is_some() {
            self.n_particles()
        } else {
            0
        };
        if state.contact_damping.len() != n_damping {
            return Err(format!(
                "checkpoint has contact loads for {} particles, the solid needs {n_damping}",
                state.contact_damping.len()
            ));
        }
        self.state = state;
        self.limit = self.stability_limit();
        self.rebuild_wet_topology();
        self.update_forces();
        self.update_wet();
        self.trial_valid = false;
        Ok(())
    }
}

fn rotate_body(dim: usize, rot: &[f64; 4], v: &Vector3<f64>) -> Vector3<f64> {
    if dim == 3 {
        quat(rot) * v
    } else {
        let (s, c) = rot[0].sin_cos();
        Vector3::new(c * v.x - s * v.y, s * v.x + c * v.y, 0.0)
    }
}

fn min_limit(a: (f64, u32), b: (f64, u32)) -> (f64, u32) {
    if b.0 < a.0 { b } else { a }
}
