//! The scene file (DESIGN §6): one TOML file describes a whole run; each node reads its part.
//!
//! Parsing is pure: [`Scene::from_toml_str`] takes the text and a name for error messages; only
//! binaries read files. A wrong scene is refused with the file, the key path, what was expected
//! and what was found ([`SceneError`]). Keys of DESIGN §6 are a contract: extend, never rename.

use serde::{Deserialize, Serialize};

/// A whole scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Name used in output names.
    pub name: String,
    /// The time loop and the coupling.
    #[serde(default)]
    pub run: RunConfig,
    /// The fluid side; absent: no fluid process.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fluid: Option<FluidConfig>,
    /// The solid side; absent: no solid process.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub solid: Option<SolidConfig>,
    /// What the run writes.
    #[serde(default)]
    pub output: OutputConfig,
}

/// `[run]`: the time loop and the coupling.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RunConfig {
    /// End time \[s\] (default 1.0).
    pub t_end: f64,
    /// Coupling scheme (default semi-implicit; ignored when one side is absent).
    pub scheme: SchemeName,
    /// Fixed-point criterion of eq. (22) of paper 003 (default 1e-12).
    pub tolerance: f64,
    /// Fixed-point iterations allowed per step; exceeding it stops the run (default 50).
    pub max_iterations: u32,
    /// Relaxation of the solid positions in the fixed point (default none).
    pub relaxation: Relaxation,
    /// Constant relaxation factor of the first iteration of Aitken and IQN-ILS, when no
    /// earlier information is available (default 0.5).
    pub relaxation_initial: f64,
    /// IQN-ILS: steps whose secant columns are kept besides the current step's; 0 = only this
    /// step's (default 4).
    pub iqn_reuse: u32,
    /// IQN-ILS: QR2 filter limit; a column whose part orthogonal to the newer columns is
    /// shorter than this fraction of its own length is dropped (default 1e-2).
    pub iqn_filter: f64,
    /// Predictor of a semi-implicit step's first inputs (default none).
    pub predictor: Predictor,
    /// Recording level (default exchange).
    pub record: RecordLevel,
    /// Steps between node checkpoints in the record; 0 = none (default 0; `record = "all"`
    /// checkpoints every step).
    pub checkpoint_every: u64,
    /// Optional cap on the coupling step \[s\].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dt_max: Option<f64>,
    /// Optional cap on the number of steps (the run stops with status "max_steps").
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_steps: Option<u64>,
    /// Worker threads per node for the solver cores (default 1; results do not depend on it).
    pub threads: u32,
    /// Largest relative mass error the ledger accepts before it stops the run (default 1e-9;
    /// checked only when the initial mass is not zero).
    pub mass_tolerance: f64,
    /// Largest relative energy error the ledger accepts (default: recorded, not checked).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub energy_tolerance: Option<f64>,
}

impl Default for RunConfig {
    fn default() -> Self {
        RunConfig {
            t_end: 1.0,
            scheme: SchemeName::SemiImplicit,
            tolerance: 1e-12,
            max_iterations: 50,
            relaxation: Relaxation::None,
            relaxation_initial: 0.5,
            iqn_reuse: 4,
            iqn_filter: 1e-2,
            predictor: Predictor::None,
            record: RecordLevel::Exchange,
            checkpoint_every: 0,
            dt_max: None,
            max_steps: None,
            threads: 1,
            mass_tolerance: 1e-9,
            energy_tolerance: None,
        }
    }
}

/// `run.scheme`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SchemeName {
    /// One pass per step.
    Explicit,
    /// Fixed point on the wet-surface position.
    SemiImplicit,
}

/// `run.relaxation`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Relaxation {
    /// Plain fixed point.
    None,
    /// Aitken's dynamic relaxation of the solid positions.
    Aitken,
    /// Interface quasi-Newton with an inverse Jacobian from a least-squares model (Degroote et
    /// al. 2009), on the positions and orientations of the particles.
    IqnIls,
}

/// `run.predictor`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Predictor {
    /// Iteration 0 runs on the accepted surface `F^n`, iteration 1 on the relaxation of its
    /// trial.
    None,
    /// Iteration 0 runs on the linear extrapolation of the last two accepted states (sent to
    /// the fluid right after the step plan) instead of on `F^n`.
    Linear,
    /// Iteration 1 starts from iteration 0's trial plus the last step's correction (its
    /// accepted state minus its first trial).
    Correction,
}

/// `run.record`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum RecordLevel {
    /// Every exchanged message, the diagnostics, and a checkpoint of each node at every step
    /// (so that a replay of any step starts at that step).
    All,
    /// Every exchanged message and the diagnostics (hello and welcome included).
    Exchange,
    /// The diagnostics channel only.
    Diagnostics,
    /// No MCAP file.
    None,
}

/// `[fluid]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FluidConfig {
    /// Which implementation runs the fluid by default: `"real"` (default), `"pressure"`, or
    /// `"replay:FILE.mcap"`; `coupler-node run --fluid` overrides it.
    #[serde(default = "default_node_impl")]
    pub node: String,
    /// Ratio of specific heats γ [-] (default 1.4).
    #[serde(default = "default_gamma")]
    pub gamma: f64,
    /// CFL number (default 0.5).
    #[serde(default = "default_cfl")]
    pub cfl: f64,
    /// Numerical flux (default OSMP order 5).
    #[serde(default)]
    pub flux: FluxConfig,
    /// Lower corner of the grid \[m\]; its length (1, 2 or 3) is the dimension.
    pub lower: Vec<f64>,
    /// Upper corner of the grid \[m\].
    pub upper: Vec<f64>,
    /// Cells along each axis.
    pub cells: Vec<u32>,
    /// Boundary conditions per axis (default outflow everywhere).
    #[serde(default)]
    pub boundary: BoundaryConfig,
    /// Vacuum thresholds (default ρ = p = 1e-10).
    #[serde(default)]
    pub vacuum: VacuumConfig,
    /// Initial state, applied in order (a later entry overrides an earlier one).
    #[serde(default)]
    pub init: Vec<InitEntry>,
    /// Settings of the pressure double (`fluid-node --double pressure`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pressure: Option<PressureField>,
    /// A smooth analytic initial state (verification cases); replaces `init` when present.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub profile: Option<Profile>,
}

/// `fluid.profile`: smooth initial states with exact solutions (exact cell averages).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum Profile {
    /// `ρ = 1 + amplitude sin(2π Σ_a wave_a (x_a − lower_a)/L_a)` at uniform velocity and
    /// pressure: advected unchanged on a periodic grid.
    DensityWave {
        /// Amplitude (< 1) [kg/m³].
        amplitude: f64,
        /// Integer wave numbers per axis.
        wave: Vec<f64>,
        /// Uniform velocity [m/s].
        velocity: Vec<f64>,
        /// Uniform pressure \[Pa\].
        p: f64,
    },
    /// Isentropic vortex of Shu (1998), ρ∞ = p∞ = 1, strength `beta`, 2-D only.
    IsentropicVortex {
        /// Strength.
        beta: f64,
        /// Centre at t = 0 \[m\].
        center: Vec<f64>,
        /// Free-stream velocity [m/s].
        velocity: Vec<f64>,
    },
}

fn default_node_impl() -> String {
    "real".to_string()
}
fn default_gamma() -> f64 {
    1.4
}
fn default_cfl() -> f64 {
    0.5
}

/// `fluid.flux`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FluxConfig {
    /// Flux scheme (only `"osmp"`).
    pub scheme: FluxScheme,
    /// Order of the OSMP flux: 3, 5 or 7 (default 5).
    #[serde(default = "default_order")]
    pub order: u32,
}

fn default_order() -> u32 {
    5
}

impl Default for FluxConfig {
    fn default() -> Self {
        FluxConfig {
            scheme: FluxScheme::Osmp,
            order: 5,
        }
    }
}

/// `fluid.flux.scheme`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FluxScheme {
    /// One-step monotonicity-preserving scheme of Daru & Tenaud (2004).
    Osmp,
}

/// `fluid.boundary`: per axis `[low, high]`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoundaryConfig {
    /// x axis (default outflow, outflow).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub x: Option<[Boundary; 2]>,
    /// y axis.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub y: Option<[Boundary; 2]>,
    /// z axis.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub z: Option<[Boundary; 2]>,
}

impl BoundaryConfig {
    /// Boundary conditions of `axis` (0, 1, 2), outflow where not given.
    pub fn axis(&self, axis: usize) -> [Boundary; 2] {
        let given = match axis {
            0 => self.x,
            1 => self.y,
            _ => self.z,
        };
        given.unwrap_or([Boundary::Outflow, Boundary::Outflow])
    }
}

/// One side of the domain.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Boundary {
    /// Reflecting slip wall.
    Wall,
    /// Periodic (both sides of the axis must say so).
    Periodic,
    /// Zero-gradient outflow.
    Outflow,
}

/// `fluid.vacuum`: below either threshold a cell is a vacuum cell.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VacuumConfig {
    /// Density threshold [kg/m³] (default 1e-10).
    pub rho: f64,
    /// Pressure threshold \[Pa\] (default 1e-10).
    pub p: f64,
}

impl Default for VacuumConfig {
    fn default() -> Self {
        VacuumConfig {
            rho: 1e-10,
            p: 1e-10,
        }
    }
}

/// One `[[fluid.init]]` entry.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InitEntry {
    /// Where it applies (cells whose centre lies in the region).
    pub region: Region,
    /// Density [kg/m³].
    pub rho: f64,
    /// Pressure \[Pa\].
    pub p: f64,
    /// Velocity [m/s], one entry per axis (default zero).
    #[serde(default)]
    pub velocity: Vec<f64>,
}

/// A region of space.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum Region {
    /// The whole domain (`region = "all"`).
    All,
    /// Axis-aligned box.
    Box {
        /// Lower corner.
        lower: Vec<f64>,
        /// Upper corner.
        upper: Vec<f64>,
    },
    /// Ball (disc in 2-D, interval in 1-D).
    Ball {
        /// Centre.
        center: Vec<f64>,
        /// Radius \[m\].
        radius: f64,
    },
    /// Half space: the side opposite to `normal` (the normal points out of it).
    HalfSpace {
        /// A point on the plane.
        point: Vec<f64>,
        /// Outward normal (need not be unit).
        normal: Vec<f64>,
    },
}

impl Region {
    /// Whether `x` lies in the region (boundaries included).
    pub fn contains(&self, x: &[f64]) -> bool {
        match self {
            Region::All => true,
            Region::Box { lower, upper } => x
                .iter()
                .zip(lower.iter().zip(upper))
                .all(|(xi, (lo, hi))| *lo <= *xi && *xi <= *hi),
            Region::Ball { center, radius } => {
                let d2: f64 = x.iter().zip(center).map(|(a, b)| (a - b) * (a - b)).sum();
                d2 <= radius * radius
            }
            Region::HalfSpace { point, normal } => {
                let s: f64 = x
                    .iter()
                    .zip(point.iter().zip(normal))
                    .map(|(xi, (pi, ni))| (xi - pi) * ni)
                    .sum();
                s <= 0.0
            }
        }
    }

    fn vectors(&self) -> Vec<(&'static str, &Vec<f64>)> {
        match self {
            Region::All => vec![],
            Region::Box { lower, upper } => vec![("box.lower", lower), ("box.upper", upper)],
            Region::Ball { center, .. } => vec![("ball.center", center)],
            Region::HalfSpace { point, normal } => {
                vec![("half_space.point", point), ("half_space.normal", normal)]
            }
        }
    }
}

/// `fluid.pressure`: the field of the pressure double,
/// `p(x, v) = value + gradient · x + impedance (v · n)`.
///
/// The impedance term (default 0) is the acoustic reaction of a gas to a wall moving at normal
/// velocity `v · n` into it (`Z = ρ c`); it makes the loads depend on the trial motion, so the
/// semi-implicit fixed point has something to converge.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PressureField {
    /// Pressure at the origin \[Pa\].
    pub value: f64,
    /// Pressure gradient [Pa/m] (default zero).
    #[serde(default)]
    pub gradient: Vec<f64>,
    /// Acoustic impedance `Z` [Pa s/m] (default 0).
    #[serde(default)]
    pub impedance: f64,
}

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

/// `[output]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputConfig {
    /// Output times \[s\]; the end time is always written.
    #[serde(default)]
    pub times: Vec<f64>,
    /// Output period \[s\] (instead of or with `times`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub every: Option<f64>,
    /// File formats: `"csv"`, `"vtk"` (default csv).
    #[serde(default = "default_formats")]
    pub formats: Vec<OutputFormat>,
    /// Probes.
    #[serde(default)]
    pub probes: Vec<ProbeConfig>,
}

fn default_formats() -> Vec<OutputFormat> {
    vec![OutputFormat::Csv]
}

impl Default for OutputConfig {
    fn default() -> Self {
        OutputConfig {
            times: Vec::new(),
            every: None,
            formats: default_formats(),
            probes: Vec::new(),
        }
    }
}

/// An output file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum OutputFormat {
    /// Comma-separated values.
    Csv,
    /// Legacy VTK for ParaView.
    Vtk,
}

/// One `[[output.probes]]` entry.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProbeConfig {
    /// Name, used in `probe_<name>.csv`.
    pub name: String,
    /// Fluid probe: the cell holding this point.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub point: Option<Vec<f64>>,
    /// Particle probe: the particle whose centre is nearest this point.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub particle_at: Option<Vec<f64>>,
    /// Particle probe by id.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub particle: Option<u32>,
}

/// A scene that could not be read or is inconsistent.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum SceneError {
    /// TOML syntax or type error.
    #[error("{file}: key `{path}`: {message}")]
    Parse {
        /// The scene file.
        file: String,
        /// Key path (`fluid.cfl`), empty at top level.
        path: String,
        /// The parser's message (says what was expected and found, with line and column).
        message: String,
    },
    /// A value that parses but is not acceptable.
    #[error("{file}: key `{path}`: expected {expected}, found {found}")]
    Invalid {
        /// The scene file.
        file: String,
        /// Key path.
        path: String,
        /// What is acceptable.
        expected: String,
        /// What was there.
        found: String,
    },
}

impl Scene {
    /// Parses and validates a scene; `file` names it in errors.
    pub fn from_toml_str(text: &str, file: &str) -> Result<Scene, SceneError> {
        let de = toml::Deserializer::parse(text).map_err(|err| SceneError::Parse {
            file: file.to_string(),
            path: String::new(),
            message: err.to_string().trim().to_string(),
        })?;
        let scene: Scene = serde_path_to_error::deserialize(de).map_err(|err| {
            let path = err.path().to_string();
            SceneError::Parse {
                file: file.to_string(),
                path: if path == "." { String::new() } else { path },
                message: err.into_inner().to_string().trim().to_string(),
            }
        })?;
        scene.validate(file)?;
        Ok(scene)
    }

    /// Spatial dimension of the run: the fluid grid's, else the first body's.
    pub fn dim(&self) -> usize {
        if let Some(fluid) = &self.fluid {
            return fluid.lower.len();
        }
        let solid = self.solid.as_ref();
        let from_body = solid
            .and_then(|s| s.bodies.first())
            .map(|b| match &b.shape {
                Shape::Box { center, .. }
                | Shape::Ring { center, .. }
                | Shape::Tube { center, .. } => center.len(),
                Shape::Particles(p) => p
                    .first()
                    .and_then(|p| p.vertices.first())
                    .map_or(0, |v| v.len()),
            });
        let from_double = solid
            .and_then(|s| s.prescribed.as_ref())
            .map(|p| p.r#box.center.len());
        from_body.or(from_double).unwrap_or(0)
    }

    /// A stable 64-bit hash (FNV-1a) of the resolved scene, sent in hello messages. Which
    /// implementation runs a side (`fluid.node`, `solid.node`) is not part of it: a double or a
    /// replay stands in for a node of the same scene. Nor is `run.threads`: results do not depend
    /// on it.
    pub fn hash(&self) -> u64 {
        let mut physics = self.clone();
        // NOTE: results do not depend on the thread count, so neither does the hash.
        physics.run.threads = RunConfig::default().threads;
        if let Some(f) = physics.fluid.as_mut() {
            f.node = default_node_impl();
        }
        if let Some(s) = physics.solid.as_mut() {
            s.node = default_node_impl();
        }
        let text = physics.to_toml();
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        for b in text.bytes() {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
        h
    }

    /// The resolved scene (defaults filled in) as TOML.
    pub fn to_toml(&self) -> String {
        toml::to_string(self).expect("a scene always serializes")
    }

    /// Output times in increasing order, the end time always last.
    pub fn output_times(&self) -> Vec<f64> {
        let t_end = self.run.t_end;
        let mut times: Vec<f64> = self
            .output
            .times
            .iter()
            .copied()
            .filter(|t| *t < t_end)
            .collect();
        if let Some(every) = self.output.every {
            let n = (t_end / every).floor() as u64;
            for k in 1..=n {
                let t = k as f64 * every;
                if t < t_end * (1.0 - 1e-12) {
                    times.push(t);
                }
            }
        }
        times.push(t_end);
        times.sort_by(f64::total_cmp);
        times.dedup_by(|a, b| (*a - *b).abs() <= 1e-12 * t_end.abs().max(1.0));
        times
    }

    fn validate(&self, file: &str) -> Result<(), SceneError> {
        let invalid = |path: &str, expected: &str, found: String| SceneError::Invalid {
            file: file.to_string(),
            path: path.to_string(),
            expected: expected.to_string(),
            found,
        };
        let positive = |path: &str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(invalid(path, "a finite number > 0", format!("{v}")))
            }
        };
        if self.name.is_empty()
            || !self
                .name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
        {
            return Err(invalid(
                "name",
                "a non-empty name of letters, digits, '-' and '_'",
                format!("{:?}", self.name),
            ));
        }
        let run = &self.run;
        positive("run.t_end", run.t_end)?;
        positive("run.tolerance", run.tolerance)?;
        positive("run.mass_tolerance", run.mass_tolerance)?;
        if let Some(e) = run.energy_tolerance {
            positive("run.energy_tolerance", e)?;
        }
        if run.max_iterations == 0 {
            return Err(invalid("run.max_iterations", "at least 1", "0".into()));
        }
        if !(run.relaxation_initial > 0.0 && run.relaxation_initial <= 1.0) {
            return Err(invalid(
                "run.relaxation_initial",
                "a number in (0, 1]",
                format!("{}", run.relaxation_initial),
            ));
        }
        if !(run.iqn_filter > 0.0 && run.iqn_filter < 1.0) {
            return Err(invalid(
                "run.iqn_filter",
                "a number in (0, 1)",
                format!("{}", run.iqn_filter),
            ));
        }
        if run.iqn_reuse > 64 {
            return Err(invalid(
                "run.iqn_reuse",
                "0 to 64",
                run.iqn_reuse.to_string(),
            ));
        }
        if let Some(dt) = run.dt_max {
            positive("run.dt_max", dt)?;
        }
        if run.threads == 0 || run.threads > 256 {
            return Err(invalid("run.threads", "1 to 256", run.threads.to_string()));
        }
        if self.fluid.is_none() && self.solid.is_none() {
            return Err(invalid(
                "fluid",
                "a [fluid] or a [solid] section (or both)",
                "neither".into(),
            ));
        }
        let dim = self.dim();
        if !(1..=3).contains(&dim) {
            return Err(invalid(
                if self.fluid.is_some() {
                    "fluid.lower"
                } else {
                    "solid.bodies"
                },
                "1, 2 or 3 coordinates",
                dim.to_string(),
            ));
        }
        let check_len = |path: &str, v: &[f64]| {
            if v.len() == dim && v.iter().all(|x| x.is_finite()) {
                Ok(())
            } else {
                Err(invalid(
                    path,
                    &format!("{dim} finite numbers (the scene is {dim}-D)"),
                    format!("{v:?}"),
                ))
            }
        };
        if let Some(fluid) = &self.fluid {
            check_node_impl("fluid.node", &fluid.node, &["real", "pressure"], file)?;
            check_len("fluid.upper", &fluid.upper)?;
            check_len("fluid.lower", &fluid.lower)?;
            if fluid.cells.len() != dim || fluid.cells.contains(&0) {
                return Err(invalid(
                    "fluid.cells",
                    &format!("{dim} positive cell counts"),
                    format!("{:?}", fluid.cells),
                ));
            }
            for axis in 0..dim {
                if fluid.upper[axis] <= fluid.lower[axis] {
                    return Err(invalid(
                        "fluid.upper",
                        "upper > lower on every axis",
                        format!("{:?} vs lower {:?}", fluid.upper, fluid.lower),
                    ));
                }
                let [lo, hi] = fluid.boundary.axis(axis);
                if (lo == Boundary::Periodic) != (hi == Boundary::Periodic) {
                    let name = ["x", "y", "z"][axis];
                    return Err(invalid(
                        &format!("fluid.boundary.{name}"),
                        "periodic on both sides or on neither",
                        format!("[{lo:?}, {hi:?}]"),
                    ));
                }
            }
            for (axis, name) in ["y", "z"].iter().enumerate() {
                let given = if axis == 0 {
                    fluid.boundary.y
                } else {
                    fluid.boundary.z
                };
                if given.is_some() && axis + 1 >= dim {
                    return Err(invalid(
                        &format!("fluid.boundary.{name}"),
                        &format!("no such axis in a {dim}-D scene"),
                        "a boundary".into(),
                    ));
                }
            }
            positive("fluid.gamma", fluid.gamma - 1.0)
                .map_err(|_| invalid("fluid.gamma", "a number > 1", fluid.gamma.to_string()))?;
            if !(fluid.cfl > 0.0 && fluid.cfl <= 1.0) {
                return Err(invalid(
                    "fluid.cfl",
                    "a number in (0, 1]",
                    fluid.cfl.to_string(),
                ));
            }
            if ![3, 5, 7].contains(&fluid.flux.order) {
                return Err(invalid(
                    "fluid.flux.order",
                    "3, 5 or 7",
                    fluid.flux.order.to_string(),
                ));
            }
            positive("fluid.vacuum.rho", fluid.vacuum.rho)?;
            positive("fluid.vacuum.p", fluid.vacuum.p)?;
            match &fluid.profile {
                Some(Profile::DensityWave {
                    amplitude,
                    wave,
                    velocity,
                    p,
                }) => {
                    if !(amplitude.abs() < 1.0 && *p > 0.0) {
                        return Err(invalid(
                            "fluid.profile.density_wave",
                            "|amplitude| < 1 and p > 0",
                            format!("amplitude {amplitude}, p {p}"),
                        ));
                    }
                    check_len("fluid.profile.density_wave.wave", wave)?;
                    check_len("fluid.profile.density_wave.velocity", velocity)?;
                }
                Some(Profile::IsentropicVortex {
                    beta,
                    center,
                    velocity,
                }) => {
                    if dim != 2 || !beta.is_finite() {
                        return Err(invalid(
                            "fluid.profile.isentropic_vortex",
                            "a 2-D scene and a finite beta",
                            format!("{dim}-D, beta {beta}"),
                        ));
                    }
                    check_len("fluid.profile.isentropic_vortex.center", center)?;
                    check_len("fluid.profile.isentropic_vortex.velocity", velocity)?;
                }
                None => {}
            }
            if fluid.node == "real" && fluid.init.is_empty() && fluid.profile.is_none() {
                return Err(invalid(
                    "fluid.init",
                    "at least one [[fluid.init]] entry",
                    "none".into(),
                ));
            }
            for (k, init) in fluid.init.iter().enumerate() {
                let base = format!("fluid.init[{k}]");
                positive(&format!("{base}.rho"), init.rho)?;
                positive(&format!("{base}.p"), init.p)?;
                if !init.velocity.is_empty() {
                    check_len(&format!("{base}.velocity"), &init.velocity)?;
                }
                for (name, v) in init.region.vectors() {
                    check_len(&format!("{base}.region.{name}"), v)?;
                }
            }
            if let Some(pressure) = &fluid.pressure {
                if !pressure.value.is_finite() {
                    return Err(invalid(
                        "fluid.pressure.value",
                        "a finite number",
                        pressure.value.to_string(),
                    ));
                }
                if !pressure.gradient.is_empty() {
                    check_len("fluid.pressure.gradient", &pressure.gradient)?;
                }
            } else if fluid.node == "pressure" {
                return Err(invalid(
                    "fluid.pressure",
                    "a [fluid.pressure] table for the pressure double",
                    "none".into(),
                ));
            }
        }
        if let Some(solid) = &self.solid {
            check_node_impl("solid.node", &solid.node, &["real", "prescribed"], file)?;
            if solid.node == "real" {
                for (path, v) in [
                    ("solid.density", solid.density),
                    ("solid.young", solid.young),
                ] {
                    match v {
                        Some(v) => positive(path, v)?,
                        None => {
                            return Err(invalid(
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
                        return Err(invalid(
                            "solid.poisson",
                            "a number in [0, 0.5)",
                            format!("{other:?}"),
                        ));
                    }
                }
                if solid.bodies.is_empty() {
                    return Err(invalid(
                        "solid.bodies",
                        "at least one [[solid.bodies]]",
                        "none".into(),
                    ));
                }
            }
            if let Some(f) = &solid.fracture {
                positive("solid.fracture.elongation_at_break", f.elongation_at_break)?;
            }
            if let Some(c) = &solid.contact {
                c.check()
                    .map_err(|(path, expected, v)| invalid(path, expected, v.to_string()))?;
            }
            if let Some(g) = &solid.gravity {
                check_len("solid.gravity", g)?;
            }
            for (k, body) in solid.bodies.iter().enumerate() {
                let base = format!("solid.bodies[{k}]");
                match &body.shape {
                    Shape::Box { center, size } => {
                        check_len(&format!("{base}.shape.box.center"), center)?;
                        check_len(&format!("{base}.shape.box.size"), size)?;
                        if body.divisions.len() != dim || body.divisions.contains(&0) {
                            return Err(invalid(
                                &format!("{base}.divisions"),
                                &format!("{dim} positive counts"),
                                format!("{:?}", body.divisions),
                            ));
                        }
                    }
                    Shape::Ring {
                        center,
                        inner_radius,
                        outer_radius,
                    } => {
                        check_len(&format!("{base}.shape.ring.center"), center)?;
                        if dim != 2 || !(0.0 < *inner_radius && inner_radius < outer_radius) {
                            return Err(invalid(
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
                        check_len(&format!("{base}.shape.tube.center"), center)?;
                        if dim != 3
                            || *axis > 2
                            || !(0.0 < *inner_radius && inner_radius < outer_radius)
                            || *length <= 0.0
                        {
                            return Err(invalid(
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
                                return Err(invalid(
                                    &format!("{base}.shape.particles[{i}].vertices"),
                                    &format!("at least {} vertices", dim + 1),
                                    p.vertices.len().to_string(),
                                ));
                            }
                            for (j, v) in p.vertices.iter().enumerate() {
                                check_len(
                                    &format!("{base}.shape.particles[{i}].vertices[{j}]"),
                                    v,
                                )?;
                            }
                        }
                    }
                }
                if let Motion::Velocity(v) = &body.motion {
                    check_len(&format!("{base}.motion.velocity"), v)?;
                }
            }
            for (k, c) in solid.constraints.iter().enumerate() {
                for (name, v) in c.region.vectors() {
                    check_len(&format!("solid.constraints[{k}].region.{name}"), v)?;
                }
                if let Motion::Velocity(v) = &c.motion {
                    check_len(&format!("solid.constraints[{k}].motion.velocity"), v)?;
                }
            }
            for (k, init) in solid.init.iter().enumerate() {
                let base = format!("solid.init[{k}]");
                for (name, v) in init.region.vectors() {
                    check_len(&format!("{base}.region.{name}"), v)?;
                }
                if init.velocity.is_none() && init.angular_velocity.is_none() {
                    return Err(invalid(
                        &base,
                        "velocity, angular_velocity or both",
                        "neither".into(),
                    ));
                }
                if let Some(v) = &init.velocity {
                    check_len(&format!("{base}.velocity"), v)?;
                }
                if let Some(w) = &init.angular_velocity {
                    let n_rot = crate::wire::n_rot(dim as u32);
                    if n_rot == 0 || w.len() != n_rot || !w.iter().all(|x| x.is_finite()) {
                        return Err(invalid(
                            &format!("{base}.angular_velocity"),
                            &format!(
                                "1 finite number in a 2-D scene, 3 in a 3-D scene (the scene is {dim}-D)"
                            ),
                            format!("{w:?}"),
                        ));
                    }
                }
            }
            if let Some(p) = &solid.prescribed {
                check_len("solid.prescribed.box.center", &p.r#box.center)?;
                check_len("solid.prescribed.box.size", &p.r#box.size)?;
                if dim == 1 {
                    return Err(invalid(
                        "solid.prescribed",
                        "a 2-D or 3-D scene",
                        "1-D".into(),
                    ));
                }
                match &p.motion {
                    PrescribedMotion::Fixed => {}
                    PrescribedMotion::Velocity(v) => {
                        check_len("solid.prescribed.motion.velocity", v)?
                    }
                    PrescribedMotion::Sinusoid {
                        amplitude,
                        frequency,
                    } => {
                        check_len("solid.prescribed.motion.sinusoid.amplitude", amplitude)?;
                        positive("solid.prescribed.motion.sinusoid.frequency", *frequency)?;
                    }
                    PrescribedMotion::Spring { mass, stiffness } => {
                        positive("solid.prescribed.motion.spring.mass", *mass)?;
                        positive("solid.prescribed.motion.spring.stiffness", *stiffness)?;
                    }
                }
            } else if solid.node == "prescribed" {
                return Err(invalid(
                    "solid.prescribed",
                    "a [solid.prescribed] table for the prescribed double",
                    "none".into(),
                ));
            }
        }
        if let Some(every) = self.output.every {
            positive("output.every", every)?;
        }
        for (k, t) in self.output.times.iter().enumerate() {
            if !(t.is_finite() && *t >= 0.0) {
                return Err(invalid(
                    &format!("output.times[{k}]"),
                    "a time >= 0",
                    t.to_string(),
                ));
            }
        }
        for (k, probe) in self.output.probes.iter().enumerate() {
            let base = format!("output.probes[{k}]");
            let n_targets = usize::from(probe.point.is_some())
                + usize::from(probe.particle_at.is_some())
                + usize::from(probe.particle.is_some());
            if n_targets != 1 {
                return Err(invalid(
                    &base,
                    "exactly one of point, particle_at, particle",
                    format!("{n_targets}"),
                ));
            }
            if let Some(p) = &probe.point {
                check_len(&format!("{base}.point"), p)?;
                if self.fluid.is_none() {
                    return Err(invalid(
                        &format!("{base}.point"),
                        "a [fluid] section to probe",
                        "none".into(),
                    ));
                }
            }
            if let Some(p) = &probe.particle_at {
                check_len(&format!("{base}.particle_at"), p)?;
            }
            if (probe.particle_at.is_some() || probe.particle.is_some()) && self.solid.is_none() {
                return Err(invalid(
                    &base,
                    "a [solid] section to probe a particle",
                    "none".into(),
                ));
            }
        }
        Ok(())
    }
}

fn check_node_impl(path: &str, value: &str, known: &[&str], file: &str) -> Result<(), SceneError> {
    if known.contains(&value) || value.strip_prefix("replay:").is_some_and(|f| !f.is_empty()) {
        Ok(())
    } else {
        Err(SceneError::Invalid {
            file: file.to_string(),
            path: path.to_string(),
            expected: format!("one of {known:?} or \"replay:FILE.mcap\""),
            found: format!("{value:?}"),
        })
    }
}
