//! Building a [`Solid`] from its scene: material and options validated, lattice, model,
//! constraints, contact, initial velocities.

use nalgebra::Matrix3;

use protocol::scene::{BoundaryConfig, FaceInertia, Motion, SolidConfig, SolidInit};

use crate::dem::contact::{Contact, ContactError, ContactParams};
use crate::dem::lattice::{LatticeError, build_lattice};
use crate::dem::link_force::LinkOut;
use crate::dem::model::{
    Material, Model, ModelError, ParticleId, ParticleMotion, build_model, to3,
};
use crate::dem::solid::forces::ForceScratch;
use crate::dem::solid::limits::min_limit;
use crate::dem::solid::orientation::quat_arr;
use crate::dem::solid::state::{ParticleTrial, Solid, State, Substeps, Trial};
use crate::dem::stability::elastic_limit;
use crate::dem::walls::Walls;
use crate::dem::wet::{WetSurfaceData, build_elements};

/// Why a [`Solid`] could not be built from its scene (the text names the scene key).
#[derive(Debug, thiserror::Error)]
pub enum SetupError {
    /// A material constant is missing.
    #[error("{key} is required")]
    Missing {
        /// The scene key (`solid.density`, `solid.young`, `solid.poisson`).
        key: &'static str,
    },
    /// `solid.face_inertia = "unweighted"` in a 2-D scene.
    #[error("solid.face_inertia = \"unweighted\" is defined for 3-D scenes only")]
    UnweightedFaceInertiaIn2d,
    /// Density or Young's modulus not positive.
    #[error("solid: expected density > 0 and young > 0, found {density} and {young}")]
    NonPositiveMaterial {
        /// Density given \[kg/m³\].
        density: f64,
        /// Young's modulus given \[Pa\].
        young: f64,
    },
    /// Poisson's ratio outside [0, 0.5).
    #[error("solid.poisson: expected a number in [0, 0.5), found {poisson}")]
    PoissonOutOfRange {
        /// Poisson's ratio given \[-\].
        poisson: f64,
    },
    /// `solid.gravity` has the wrong number of components.
    #[error("solid.gravity: expected {dim} components, found {found:?}")]
    GravityComponents {
        /// The scene's dimension.
        dim: usize,
        /// The vector given.
        found: Vec<f64>,
    },
    /// `solid.init[index].velocity` has the wrong number of components.
    #[error("solid.init[{index}].velocity: expected {dim} components, found {found:?}")]
    InitVelocityComponents {
        /// Index of the init entry.
        index: usize,
        /// The scene's dimension.
        dim: usize,
        /// The vector given.
        found: Vec<f64>,
    },
    /// `solid.init[index].angular_velocity` has the wrong number of components.
    #[error("solid.init[{index}].angular_velocity: expected {n_rot} components, found {found:?}")]
    InitAngularVelocityComponents {
        /// Index of the init entry.
        index: usize,
        /// Components expected (1 in 2-D, 3 in 3-D).
        n_rot: usize,
        /// The vector given.
        found: Vec<f64>,
    },
    /// The worker threads could not be started.
    #[error("building the solid's thread pool: {0}")]
    ThreadPool(#[from] rayon::ThreadPoolBuildError),
    /// The bodies' shapes are invalid.
    #[error(transparent)]
    Lattice(#[from] LatticeError),
    /// The particles' mechanics could not be built.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// The contact cannot handle the particles.
    #[error(transparent)]
    Contact(#[from] ContactError),
}

/// The material of `[solid]`, validated.
fn material(cfg: &SolidConfig, dim: usize) -> Result<Material, SetupError> {
    let required = |value: Option<f64>, key: &'static str| value.ok_or(SetupError::Missing { key });
    let material = Material {
        density: required(cfg.density, "solid.density")?,
        young: required(cfg.young, "solid.young")?,
        poisson: required(cfg.poisson, "solid.poisson")?,
        face_inertia: cfg.face_inertia.unwrap_or_default(),
    };
    if material.face_inertia == FaceInertia::Unweighted && dim != 3 {
        return Err(SetupError::UnweightedFaceInertiaIn2d);
    }
    if !(material.density > 0.0 && material.young > 0.0) {
        return Err(SetupError::NonPositiveMaterial {
            density: material.density,
            young: material.young,
        });
    }
    if !(0.0..0.5).contains(&material.poisson) {
        return Err(SetupError::PoissonOutOfRange {
            poisson: material.poisson,
        });
    }
    Ok(material)
}

/// Each `[[solid.init]]` vector has `dim` (velocity) or 1 / 3 (angular velocity) components.
fn check_init_lengths(inits: &[SolidInit], dim: usize) -> Result<(), SetupError> {
    for (index, init) in inits.iter().enumerate() {
        let n_rot = if dim == 3 { 3 } else { 1 };
        if let Some(v) = init.velocity.as_ref().filter(|v| v.len() != dim) {
            return Err(SetupError::InitVelocityComponents {
                index,
                dim,
                found: v.clone(),
            });
        }
        if let Some(w) = init.angular_velocity.as_ref().filter(|w| w.len() != n_rot) {
            return Err(SetupError::InitAngularVelocityComponents {
                index,
                n_rot,
                found: w.clone(),
            });
        }
    }
    Ok(())
}

impl Solid {
    /// Builds the solid of a scene: `dim` is the scene's dimension (2 or 3), `threads` the
    /// worker threads (1: no pool; results are bit-identical for any count).
    ///
    /// Bodies' `motion` and then `[[solid.constraints]]` set each particle's motion; then the
    /// `[[solid.init]]` entries, in order, give the free particles whose centre lies in their
    /// region their initial velocity and angular velocity ([`Solid::set_velocity`],
    /// [`Solid::set_angular_velocity`]). Fixed particles and particles with a prescribed
    /// velocity keep their prescribed motion: an init entry never overrides a constraint.
    pub fn from_scene(cfg: &SolidConfig, dim: usize, threads: usize) -> Result<Self, SetupError> {
        let material = material(cfg, dim)?;
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
                return Err(SetupError::GravityComponents {
                    dim,
                    found: g.clone(),
                });
            }
            Some(g) => to3(g),
            None => [0.0; 3],
        };
        let elongation_at_break = cfg.fracture.as_ref().map(|f| f.elongation_at_break);
        let pool = if threads > 1 {
            Some(
                rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()?,
            )
        } else {
            None
        };
        check_init_lengths(&cfg.init, dim)?;
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
            substeps: Substeps::default(),
            walls: Walls::default(),
            model,
        };
        solid.rebuild_wet_topology();
        solid.update_forces();
        solid.update_wet();
        solid
    }

    /// Makes the `wall` sides of the box `[lower, upper]` (the fluid's domain) hold the solid
    /// (`solid.walls = "hold"`, [`Walls`]). Without it the solid passes through them.
    pub fn set_walls(&mut self, lower: &[f64], upper: &[f64], boundary: &BoundaryConfig) {
        self.walls = Walls::new(&self.model, lower, upper, boundary);
    }
}
