//! `[solid]`: material, bodies, constraints, initial velocities, the prescribed double, and
//! their validation.

use serde::{Deserialize, Serialize};

use super::error::{Check, SceneError, check_node_impl, quote_list};
use super::fluid::default_node_impl;
use super::region::{Region, check_region};

/// `[solid]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolidConfig {
    /// Which implementation runs the solid by default: `"real"` (default), `"prescribed"`, or
    /// `"replay:FILE.mcap"`; `coupler-node run --solid` overrides it.
    #[serde(default = "default_node_impl")]
    pub node: String,
    /// Density [kg/m³] (required by the real node).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub density: Option<f64>,
    /// Young's modulus \[Pa\] (required by the real node).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub young: Option<f64>,
    /// Poisson's ratio [-] (required by the real node).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub poisson: Option<f64>,
    /// Second moments of the link faces in the flexion and torsion torques (default `"exact"`).
    /// `"unweighted"` sums each fan triangle's term without its area, as the authors' code did
    /// when papers 003 and 000 were computed (fixed upstream in 2017): a dimensionally wrong,
    /// mesh-dependent stiffening kept only to reproduce their figures. 3-D scenes only. Left out
    /// of the resolved scene when absent, so a scene without it hashes as before.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub face_inertia: Option<FaceInertia>,
    /// Fracture criterion; absent: no fracture, no internal faces carried.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fracture: Option<FractureConfig>,
    /// Body acceleration [m/s²], one entry per axis.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gravity: Option<Vec<f64>>,
    /// Bodies, each divided into particles.
    #[serde(default)]
    pub bodies: Vec<BodyConfig>,
    /// Constraints on the particles whose centre lies in a region.
    #[serde(default)]
    pub constraints: Vec<ConstraintConfig>,
    /// Initial velocities of the particles whose centre lies in a region, applied in order (a
    /// later entry overrides an earlier one; default none: every free particle starts at rest).
    /// Left out of the resolved scene when empty, so a scene without it hashes as before.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub init: Vec<SolidInit>,
    /// Settings of the prescribed double (`solid-node --double prescribed`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub prescribed: Option<PrescribedConfig>,
    /// Contact between particles that are not linked; absent: none is computed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub contact: Option<ContactConfig>,
    /// What the fluid domain's `wall` sides do to the solid (default `"hold"`). Left out of the
    /// resolved scene when absent, so a scene without it hashes as before.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub walls: Option<SolidWalls>,
}

/// `solid.walls`: what the fluid domain's `wall` sides do to the solid.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SolidWalls {
    /// A wall holds the solid: rigid, frictionless and perfectly inelastic. A particle's vertex
    /// on or beyond a wall plane cannot move further into it; the kinetic energy that takes out
    /// is counted as dissipated. A body resting flush against a wall stays at rest.
    #[default]
    Hold,
    /// The solid passes through walls (the fluid's walls bound the gas only): fragments leave
    /// the domain, and what lies beyond a side is ignored by the fluid.
    Pass,
}

/// `[solid.contact]`: contact between particles that are not linked (never linked, or whose
/// link broke) and with fixed particles. Every key has a default, so an empty table turns
/// contact on.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactConfig {
    /// Penalty stiffness as a multiple of the material's [-] (default 1): a face-to-face contact
    /// over a particle's cross-section is as stiff as a link of Young's modulus `stiffness × E`.
    #[serde(default = "default_contact_stiffness")]
    pub stiffness: f64,
    /// Normal restitution coefficient in \[0, 1\] (default 0.5; 1: elastic, no damping).
    #[serde(default = "default_contact_restitution")]
    pub restitution: f64,
    /// Coulomb friction coefficient μ ≥ 0 (default 0.3; 0: frictionless).
    #[serde(default = "default_contact_friction")]
    pub friction: f64,
}

fn default_contact_stiffness() -> f64 {
    1.0
}
fn default_contact_restitution() -> f64 {
    0.5
}
fn default_contact_friction() -> f64 {
    0.3
}

impl Default for ContactConfig {
    fn default() -> Self {
        ContactConfig {
            stiffness: default_contact_stiffness(),
            restitution: default_contact_restitution(),
            friction: default_contact_friction(),
        }
    }
}

impl ContactConfig {
    /// The first bad key as `(path, expected, found)`.
    fn check(&self) -> Result<(), (&'static str, &'static str, f64)> {
        if !(self.stiffness.is_finite() && self.stiffness > 0.0) {
            return Err((
                "solid.contact.stiffness",
                "a finite number > 0",
                self.stiffness,
            ));
        }
        if !(0.0..=1.0).contains(&self.restitution) {
            return Err((
                "solid.contact.restitution",
                "a number in [0, 1]",
                self.restitution,
            ));
        }
        if !(self.friction.is_finite() && self.friction >= 0.0) {
            return Err((
                "solid.contact.friction",
                "a finite number >= 0",
                self.friction,
            ));
        }
        Ok(())
    }
}

/// `solid.face_inertia`: how the second moments `I^s, I^t` of a link's face are integrated.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FaceInertia {
    /// `∫ ((x − G)·s)² dA`, exact for a planar face (paper 003 App. A).
    #[default]
    Exact,
    /// `Σ_T (a² + ab + b²)/12` over the triangles `(G, a, b)` fanned from the centroid, without
    /// the factor `2|T|` of the exact integral: the formula of the authors' code before its
    /// 2017 fix ("surface area missing"). In m², not m⁴: it stiffens flexion and torsion by
    /// about `1/(2|T|)` per face.
    Unweighted,
}

/// `solid.fracture`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FractureConfig {
    /// Relative elongation at which a link breaks [-] (paper 000 §3.1).
    pub elongation_at_break: f64,
}

/// One `[[solid.bodies]]` entry.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodyConfig {
    /// Geometry.
    pub shape: Shape,
    /// Particles along each axis of the shape (box: per axis; ring: `[n_around]`; tube:
    /// `[n_around, n_along]`).
    #[serde(default)]
    pub divisions: Vec<u32>,
    /// Motion of the whole body (default free).
    #[serde(default)]
    pub motion: Motion,
    /// Law of the links between the body's particles; absent: the elastic links of paper 003
    /// App. A derived from `solid.young` and `solid.poisson`. Left out of the resolved scene
    /// when absent, so a scene without it hashes as before.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub links: Option<LinksConfig>,
}

/// `links = { spring = K }` of a body: every link of the body is a linear spring between the
/// two particle centres, energy `½ k (|d| − d⁰)²` (paper 003 §5.3, the thin shell), instead of
/// the elastic link of App. A. The spring exerts no torque and the link has no shear or
/// volumetric part, so a chain of such links is a discrete string: the particles' rotations are
/// held only by `rotation`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinksConfig {
    /// Axial stiffness k > 0 [N/m] (2-D: per unit depth, N/m per m).
    pub spring: f64,
    /// Stiffness c ≥ 0 of a rotational spring on the relative rotation of the two particles
    /// \[N m/rad\] (default 0), energy `c (1 − cos(θ_J − θ_I))` in 2-D (in 3-D the same for a
    /// rotation about any axis). It does not couple to the centre line (no beam bending); it keeps
    /// the particles from spinning freely under fluid torques (fixed particles do not rotate).
    #[serde(default)]
    pub rotation: f64,
}

impl LinksConfig {
    /// The first bad key as `(key, expected, found)`.
    fn check(&self) -> Result<(), (&'static str, &'static str, f64)> {
        if !(self.spring.is_finite() && self.spring > 0.0) {
            return Err(("spring", "a finite number > 0 [N/m]", self.spring));
        }
        if !(self.rotation.is_finite() && self.rotation >= 0.0) {
            return Err(("rotation", "a finite number >= 0 [N m/rad]", self.rotation));
        }
        Ok(())
    }
}

/// A body's geometry.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum Shape {
    /// Axis-aligned box.
    Box {
        /// Centre \[m\].
        center: Vec<f64>,
        /// Edge lengths \[m\].
        size: Vec<f64>,
    },
    /// 2-D ring, one particle thick.
    Ring {
        /// Centre \[m\].
        center: Vec<f64>,
        /// Inner radius \[m\].
        inner_radius: f64,
        /// Outer radius \[m\].
        outer_radius: f64,
    },
    /// 3-D tube along `axis`, one particle thick.
    Tube {
        /// Centre \[m\].
        center: Vec<f64>,
        /// Axis direction: 0 = x, 1 = y, 2 = z.
        axis: u32,
        /// Inner radius \[m\].
        inner_radius: f64,
        /// Outer radius \[m\].
        outer_radius: f64,
        /// Length along the axis \[m\].
        length: f64,
    },
    /// Explicit convex particles, each given by its vertices (2-D: counter-clockwise polygon;
    /// 3-D: the convex hull of the points).
    Particles(Vec<ParticleSpec>),
}

/// One explicit particle.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParticleSpec {
    /// Vertices \[m\].
    pub vertices: Vec<Vec<f64>>,
}

/// Motion of a body or of constrained particles.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum Motion {
    /// Moves under the forces.
    #[default]
    Free,
    /// Does not move.
    Fixed,
    /// Constant prescribed velocity [m/s].
    Velocity(Vec<f64>),
}

/// One `[[solid.constraints]]` entry.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConstraintConfig {
    /// Particles whose centre lies in this region.
    pub region: Region,
    /// Their motion.
    pub motion: Motion,
}

/// One `[[solid.init]]` entry: the initial velocity of the particles whose centre (at t = 0)
/// lies in `region`.
///
/// Entries apply in order; for a particle in several regions the later entry's given fields
/// override the earlier ones (an entry with only `velocity` leaves an earlier `angular_velocity`
/// in place). Only free particles take them: fixed particles and particles with a prescribed
/// `motion = { velocity = [...] }` (of their body or of a `[[solid.constraints]]` entry) keep
/// that motion, whatever the entries say. At least one of the two velocities must be given.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolidInit {
    /// The particles whose centre lies in this region (same [`Region`] as `[[fluid.init]]`).
    pub region: Region,
    /// Velocity of the centre of mass [m/s], `dim` entries (absent: unchanged, at rest unless an
    /// earlier entry set it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub velocity: Option<Vec<f64>>,
    /// Angular velocity of each particle about its own centre of mass, space frame \[rad/s\]: one
    /// entry in 2-D (about z), three in 3-D (absent: unchanged, zero unless an earlier entry set
    /// it). It is a spin of every particle, not a rigid rotation of the region.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub angular_velocity: Option<Vec<f64>>,
}

/// `solid.prescribed`: the prescribed-motion double.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PrescribedConfig {
    /// The rigid box whose surface is the double's wet surface (one particle).
    pub r#box: BoxSpec,
    /// How the box moves.
    pub motion: PrescribedMotion,
}

/// An axis-aligned box.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoxSpec {
    /// Centre \[m\].
    pub center: Vec<f64>,
    /// Edge lengths \[m\].
    pub size: Vec<f64>,
}

/// Motion law of the prescribed double.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum PrescribedMotion {
    /// Never moves.
    Fixed,
    /// Constant velocity [m/s].
    Velocity(Vec<f64>),
    /// `x(t) = x0 + amplitude sin(2π frequency t)`.
    Sinusoid {
        /// Amplitude \[m\] per axis.
        amplitude: Vec<f64>,
        /// Frequency \[Hz\].
        frequency: f64,
    },
    /// A mass on a linear spring driven by the received loads: `m x'' = -k (x - x0) + F`.
    Spring {
        /// Mass \[kg\].
        mass: f64,
        /// Stiffness [N/m].
        stiffness: f64,
    },
}

impl SolidConfig {
    /// The `[solid]` rules.
    pub(super) fn validate(&self, c: &Check<'_>) -> Result<(), SceneError> {
        self.validate_material(c)?;
        self.validate_options(c)?;
        self.validate_bodies(c)?;
        self.validate_constraints(c)?;
        self.validate_init(c)?;
        self.validate_prescribed(c)?;
        Ok(())
    }

    /// The node and, for the real solid, its material and at least one body.
    fn validate_material(&self, c: &Check<'_>) -> Result<(), SceneError> {
        let solid = self;
        check_node_impl(
            "solid.node",
            &solid.node,
            &super::error::SOLID_NODES,
            c.file,
        )?;
        if solid.node == "real" {
            for (path, v) in [
                ("solid.density", solid.density),
                ("solid.young", solid.young),
            ] {
                match v {
                    Some(v) => c.positive(path, v)?,
                    None => {
                        return Err(c.invalid(
                            path,
                            "a number > 0 (the real solid needs it)",
                            "nothing".into(),
                        ));
                    }
                }
            }
            match solid.poisson {
                Some(nu) if (0.0..0.5).contains(&nu) => {}
                other => {
                    return Err(c.invalid(
                        "solid.poisson",
                        "a number in [0, 0.5)",
                        format!("{other:?}"),
                    ));
                }
            }
            if solid.bodies.is_empty() {
                return Err(c.invalid(
                    "solid.bodies",
                    "at least one [[solid.bodies]]",
                    "none".into(),
                ));
            }
        }
        Ok(())
    }

    /// Face inertia, fracture, contact and gravity.
    fn validate_options(&self, c: &Check<'_>) -> Result<(), SceneError> {
        let solid = self;
        let dim = c.dim;
        if solid.face_inertia == Some(FaceInertia::Unweighted) && dim != 3 {
            return Err(c.invalid(
                "solid.face_inertia",
                "\"exact\" in a 2-D scene (\"unweighted\" is defined for 3-D faces only)",
                "\"unweighted\"".into(),
            ));
        }
        if let Some(f) = &solid.fracture {
            c.positive("solid.fracture.elongation_at_break", f.elongation_at_break)?;
        }
        if let Some(contact) = &solid.contact {
            contact
                .check()
                .map_err(|(path, expected, v)| c.invalid(path, expected, v.to_string()))?;
        }
        if let Some(g) = &solid.gravity {
            c.check_len("solid.gravity", g)?;
        }
        Ok(())
    }

    /// Each `[[solid.bodies]]` entry: its shape, divisions and links.
    fn validate_bodies(&self, c: &Check<'_>) -> Result<(), SceneError> {
        let solid = self;
        let dim = c.dim;
        for (k, body) in solid.bodies.iter().enumerate() {
            let base = format!("solid.bodies[{k}]");
            match &body.shape {
                Shape::Box { center, size } => {
                    c.check_len(&format!("{base}.shape.box.center"), center)?;
                    c.check_len(&format!("{base}.shape.box.size"), size)?;
                    if body.divisions.len() != dim || body.divisions.contains(&0) {
                        return Err(c.invalid(
                            &format!("{base}.divisions"),
                            &format!("{dim} positive counts"),
                            quote_list(&body.divisions),
                        ));
                    }
                }
                Shape::Ring {
                    center,
                    inner_radius,
                    outer_radius,
                } => {
                    c.check_len(&format!("{base}.shape.ring.center"), center)?;
                    if dim != 2 || !(0.0 < *inner_radius && inner_radius < outer_radius) {
                        return Err(c.invalid(
                            &format!("{base}.shape.ring"),
                            "a 2-D ring with 0 < inner_radius < outer_radius",
                            format!("{dim}-D, radii {inner_radius}, {outer_radius}"),
                        ));
                    }
                }
                Shape::Tube {
                    center,
                    axis,
                    inner_radius,
                    outer_radius,
                    length,
                } => {
                    c.check_len(&format!("{base}.shape.tube.center"), center)?;
                    if dim != 3
                        || *axis > 2
                        || !(0.0 < *inner_radius && inner_radius < outer_radius)
                        || *length <= 0.0
                    {
                        return Err(c.invalid(
                            &format!("{base}.shape.tube"),
                            "a 3-D tube with axis 0..2, 0 < inner_radius < outer_radius and length > 0",
                            format!(
                                "{dim}-D, axis {axis}, radii {inner_radius}, {outer_radius}, length {length}"
                            ),
                        ));
                    }
                }
                Shape::Particles(list) => {
                    for (i, p) in list.iter().enumerate() {
                        if p.vertices.len() < dim + 1 {
                            return Err(c.invalid(
                                &format!("{base}.shape.particles[{i}].vertices"),
                                &format!("at least {} vertices", dim + 1),
                                p.vertices.len().to_string(),
                            ));
                        }
                        for (j, v) in p.vertices.iter().enumerate() {
                            c.check_len(&format!("{base}.shape.particles[{i}].vertices[{j}]"), v)?;
                        }
                    }
                }
            }
            if let Motion::Velocity(v) = &body.motion {
                c.check_len(&format!("{base}.motion.velocity"), v)?;
            }
            if let Some(links) = &body.links {
                links.check().map_err(|(key, expected, v)| {
                    c.invalid(&format!("{base}.links.{key}"), expected, v.to_string())
                })?;
            }
        }
        Ok(())
    }

    /// Each `[[solid.constraints]]` entry: its region and motion.
    fn validate_constraints(&self, c: &Check<'_>) -> Result<(), SceneError> {
        let solid = self;
        for (k, constraint) in solid.constraints.iter().enumerate() {
            for (name, v) in constraint.region.vectors() {
                c.check_len(&format!("solid.constraints[{k}].region.{name}"), v)?;
            }
            check_region(
                &format!("solid.constraints[{k}].region"),
                &constraint.region,
            )
            .map_err(|(path, expected, found)| c.invalid(&path, &expected, found))?;
            if let Motion::Velocity(v) = &constraint.motion {
                c.check_len(&format!("solid.constraints[{k}].motion.velocity"), v)?;
            }
        }
        Ok(())
    }

    /// Each `[[solid.init]]` entry: its region and velocities.
    fn validate_init(&self, c: &Check<'_>) -> Result<(), SceneError> {
        let solid = self;
        let dim = c.dim;
        for (k, init) in solid.init.iter().enumerate() {
            let base = format!("solid.init[{k}]");
            for (name, v) in init.region.vectors() {
                c.check_len(&format!("{base}.region.{name}"), v)?;
            }
            check_region(&format!("{base}.region"), &init.region)
                .map_err(|(path, expected, found)| c.invalid(&path, &expected, found))?;
            if init.velocity.is_none() && init.angular_velocity.is_none() {
                return Err(c.invalid(
                    &base,
                    "velocity, angular_velocity or both",
                    "neither".into(),
                ));
            }
            if let Some(v) = &init.velocity {
                c.check_len(&format!("{base}.velocity"), v)?;
            }
            if let Some(w) = &init.angular_velocity {
                let n_rot = crate::wire::n_rot(dim as u32);
                if n_rot == 0 || w.len() != n_rot || !w.iter().all(|x| x.is_finite()) {
                    return Err(c.invalid(
                        &format!("{base}.angular_velocity"),
                        &format!(
                            "1 finite number in a 2-D scene, 3 in a 3-D scene (the scene is {dim}-D)"
                        ),
                        quote_list(w),
                    ));
                }
            }
        }
        Ok(())
    }

    /// The `[solid.prescribed]` table of the prescribed double.
    fn validate_prescribed(&self, c: &Check<'_>) -> Result<(), SceneError> {
        let solid = self;
        let dim = c.dim;
        if let Some(p) = &solid.prescribed {
            c.check_len("solid.prescribed.box.center", &p.r#box.center)?;
            c.check_len("solid.prescribed.box.size", &p.r#box.size)?;
            if dim == 1 {
                return Err(c.invalid("solid.prescribed", "a 2-D or 3-D scene", "1-D".into()));
            }
            match &p.motion {
                PrescribedMotion::Fixed => {}
                PrescribedMotion::Velocity(v) => {
                    c.check_len("solid.prescribed.motion.velocity", v)?
                }
                PrescribedMotion::Sinusoid {
                    amplitude,
                    frequency,
                } => {
                    c.check_len("solid.prescribed.motion.sinusoid.amplitude", amplitude)?;
                    c.positive("solid.prescribed.motion.sinusoid.frequency", *frequency)?;
                }
                PrescribedMotion::Spring { mass, stiffness } => {
                    c.positive("solid.prescribed.motion.spring.mass", *mass)?;
                    c.positive("solid.prescribed.motion.spring.stiffness", *stiffness)?;
                }
            }
        } else if solid.node == "prescribed" {
            return Err(c.invalid(
                "solid.prescribed",
                "a [solid.prescribed] table for the prescribed double",
                "none".into(),
            ));
        }
        Ok(())
    }
}
