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
    /// Optional cap on the number of steps, at least 1 (the run stops with status
    /// "max_steps").
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_steps: Option<u64>,
    /// Smallest coupling step a node may impose \[s\]: a step a node limits to less stops the
    /// run with a report naming the node and what limits it (cell or particle). Default: the
    /// larger of [`DT_MIN_RELATIVE`] times the smallest step the nodes proposed for the first
    /// step and [`DT_MIN_OF_T_END`] times `t_end`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dt_min: Option<f64>,
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
            dt_min: None,
            threads: 1,
            mass_tolerance: 1e-9,
            energy_tolerance: None,
        }
    }
}

/// Default `run.dt_min` relative to the first step the nodes propose: a step that has collapsed
/// a millionfold is a run without progress.
///
/// NOTE: a shock reflecting from a wall or a body speeding up changes the step by factors of a
/// few; a millionfold collapse takes hours of steps for nothing.
pub const DT_MIN_RELATIVE: f64 = 1e-6;

/// Default `run.dt_min` relative to `run.t_end`: a step that would need more than a billion
/// steps to reach the end is a run without progress, even from the first step.
///
/// NOTE: Sod with ρ = 1e-300 on one side proposes 3e-153 s for its first step (the sound speed
/// of the near-vacuum cells), then 1e-8 s for hours; [`DT_MIN_RELATIVE`] alone, relative to
/// that first proposal, would never stop it.
pub const DT_MIN_OF_T_END: f64 = 1e-9;

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
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "low_high"
    )]
    pub x: Option<[Boundary; 2]>,
    /// y axis.
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "low_high"
    )]
    pub y: Option<[Boundary; 2]>,
    /// z axis.
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "low_high"
    )]
    pub z: Option<[Boundary; 2]>,
}

/// Reads `[low, high]`, refusing a list of another length (a fixed-size array would drop the
/// entries after the second without a word).
fn low_high<'de, D: serde::Deserializer<'de>>(de: D) -> Result<Option<[Boundary; 2]>, D::Error> {
    let list: Vec<Boundary> = Vec::deserialize(de)?;
    match list.as_slice() {
        [low, high] => Ok(Some([*low, *high])),
        other => Err(serde::de::Error::custom(format!(
            "expected 2 entries [low, high], found {} ({})",
            other.len(),
            quote_list(other)
        ))),
    }
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
            message: shorten_lines(err.to_string().trim()),
        })?;
        let scene: Scene = serde_path_to_error::deserialize(de).map_err(|err| {
            let path = err.path().to_string();
            SceneError::Parse {
                file: file.to_string(),
                path: if path == "." { String::new() } else { path },
                message: shorten_lines(err.into_inner().to_string().trim()),
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

    /// Whether `output.times` holds 0: the initial state is then written as output 0, before
    /// the first step (as Clawpack does), and the outputs of [`Scene::output_times`] follow
    /// from 1.
    pub fn initial_output(&self) -> bool {
        self.output.times.contains(&0.0)
    }

    /// Times at which a step ends on an output, in increasing order, the end time always last
    /// (an output at t = 0 is not among them: see [`Scene::initial_output`]).
    pub fn output_times(&self) -> Vec<f64> {
        let t_end = self.run.t_end;
        let mut times: Vec<f64> = self
            .output
            .times
            .iter()
            .copied()
            .filter(|t| *t > 0.0 && *t < t_end)
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
                shorten_lines(&format!("{:?}", self.name)),
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
        if run.max_steps == Some(0) {
            return Err(invalid("run.max_steps", "at least 1 step", "0".into()));
        }
        if let Some(dt_min) = run.dt_min {
            positive("run.dt_min", dt_min)?;
            if let Some(dt_max) = run.dt_max
                && dt_min >= dt_max
            {
                return Err(invalid(
                    "run.dt_min",
                    &format!("a step below run.dt_max = {dt_max:e}"),
                    format!("{dt_min:e}"),
                ));
            }
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
                    quote_list(v),
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
                    quote_list(&fluid.cells),
                ));
            }
            for axis in 0..dim {
                if fluid.upper[axis] <= fluid.lower[axis] {
                    return Err(invalid(
                        "fluid.upper",
                        "upper > lower on every axis",
                        format!(
                            "{} vs lower {}",
                            quote_list(&fluid.upper),
                            quote_list(&fluid.lower)
                        ),
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
                check_region(&format!("{base}.region"), &init.region)
                    .map_err(|(path, expected, found)| invalid(&path, &expected, found))?;
                if !init.region.meets_box(&fluid.lower, &fluid.upper) {
                    return Err(invalid(
                        &format!("{base}.region"),
                        "a region that meets the domain",
                        format!(
                            "a region outside the domain {} to {}",
                            quote_list(&fluid.lower),
                            quote_list(&fluid.upper)
                        ),
                    ));
                }
            }
            if fluid.node == "real"
                && fluid.profile.is_none()
                && let Some((cell, centre)) = uncovered_cell(fluid)
            {
                return Err(invalid(
                    "fluid.init",
                    "[[fluid.init]] entries that cover every cell (or one with region = \"all\")",
                    format!(
                        "cell {} (centre {}) in none of them",
                        quote_list(&cell),
                        quote_list(&centre)
                    ),
                ));
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
                                quote_list(&body.divisions),
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
                check_region(&format!("solid.constraints[{k}].region"), &c.region)
                    .map_err(|(path, expected, found)| invalid(&path, &expected, found))?;
                if let Motion::Velocity(v) = &c.motion {
                    check_len(&format!("solid.constraints[{k}].motion.velocity"), v)?;
                }
            }
            for (k, init) in solid.init.iter().enumerate() {
                let base = format!("solid.init[{k}]");
                for (name, v) in init.region.vectors() {
                    check_len(&format!("{base}.region.{name}"), v)?;
                }
                check_region(&format!("{base}.region"), &init.region)
                    .map_err(|(path, expected, found)| invalid(&path, &expected, found))?;
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
                            quote_list(w),
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

/// A region's own consistency: a ball's radius > 0, a box's lower <= upper, a half space's
/// normal not zero. Returns `(key path, expected, found)`.
fn check_region(base: &str, region: &Region) -> Result<(), (String, String, String)> {
    match region {
        Region::All => Ok(()),
        Region::Ball { radius, .. } if !(radius.is_finite() && *radius > 0.0) => Err((
            format!("{base}.ball.radius"),
            "a finite radius > 0".into(),
            radius.to_string(),
        )),
        Region::Box { lower, upper } if lower.iter().zip(upper).any(|(lo, hi)| lo > hi) => Err((
            format!("{base}.box"),
            "lower <= upper on every axis".into(),
            format!(
                "lower {} and upper {}",
                quote_list(lower),
                quote_list(upper)
            ),
        )),
        Region::HalfSpace { normal, .. } if normal.iter().all(|n| *n == 0.0) => Err((
            format!("{base}.half_space.normal"),
            "a normal that is not zero".into(),
            quote_list(normal),
        )),
        _ => Ok(()),
    }
}

impl Region {
    /// Whether the region meets the box `[lower, upper]` (touching counts).
    fn meets_box(&self, lower: &[f64], upper: &[f64]) -> bool {
        let corners = lower.iter().zip(upper);
        match self {
            Region::All => true,
            Region::Box {
                lower: lo,
                upper: hi,
            } => corners
                .zip(lo.iter().zip(hi))
                .all(|((d_lo, d_hi), (lo, hi))| lo <= d_hi && hi >= d_lo),
            Region::Ball { center, radius } => {
                let d2: f64 = corners
                    .zip(center)
                    .map(|((d_lo, d_hi), c)| {
                        let gap = (d_lo - c).max(c - d_hi).max(0.0);
                        gap * gap
                    })
                    .sum();
                d2 <= radius * radius
            }
            // The box corner deepest on the inner side (normal points out of the half space).
            Region::HalfSpace { point, normal } => {
                let s: f64 = corners
                    .zip(point.iter().zip(normal))
                    .map(|((d_lo, d_hi), (p, n))| (if *n > 0.0 { d_lo } else { d_hi } - p) * n)
                    .sum();
                s <= 0.0
            }
        }
    }
}

/// Largest grid whose coverage by `[[fluid.init]]` is checked cell by cell (cells).
///
/// NOTE: about a second of validation; a larger grid without a `region = "all"` entry is left to
/// the fluid node (and is refused by the memory estimate first when it is too large to run).
const COVERAGE_CHECK_MAX_CELLS: u64 = 20_000_000;

/// The first cell (index per axis and centre) whose centre no `[[fluid.init]]` region holds;
/// `None` when every cell is covered, or when an entry covers all of them by itself.
fn uncovered_cell(fluid: &FluidConfig) -> Option<(Vec<u64>, Vec<f64>)> {
    if fluid.init.iter().any(|e| e.region == Region::All) {
        return None;
    }
    let n_cells: u64 = fluid.cells.iter().map(|&n| u64::from(n)).product();
    if n_cells > COVERAGE_CHECK_MAX_CELLS {
        return None;
    }
    let dim = fluid.cells.len();
    let mut idx = vec![0u64; dim];
    let mut centre = vec![0.0; dim];
    for _ in 0..n_cells {
        for a in 0..dim {
            let dx = (fluid.upper[a] - fluid.lower[a]) / f64::from(fluid.cells[a]);
            centre[a] = fluid.lower[a] + (idx[a] as f64 + 0.5) * dx;
        }
        if !fluid.init.iter().any(|e| e.region.contains(&centre)) {
            return Some((idx, centre));
        }
        for (i, n) in idx.iter_mut().zip(&fluid.cells) {
            *i += 1;
            if *i < u64::from(*n) {
                break;
            }
            *i = 0;
        }
    }
    None
}

/// Longest quoted value or message line in an error, in bytes.
const QUOTE_MAX: usize = 160;

/// A list quoted for an error: its entries, or for a long list the first ones and the count (a
/// 50 MB array must not come back whole on stderr).
fn quote_list<T: std::fmt::Debug>(list: &[T]) -> String {
    let whole = format!("{list:?}");
    if whole.len() <= QUOTE_MAX {
        return whole;
    }
    let mut head = String::from("[");
    for (k, v) in list.iter().enumerate() {
        let next = format!("{}{v:?}", if k == 0 { "" } else { ", " });
        if head.len() + next.len() > QUOTE_MAX {
            break;
        }
        head.push_str(&next);
    }
    format!("{head}, ...] ({} entries)", list.len())
}

/// A message with every line longer than [`QUOTE_MAX`] cut (the TOML parser quotes the line of
/// the error, which can be megabytes long).
fn shorten_lines(message: &str) -> String {
    message
        .lines()
        .map(|line| {
            if line.len() <= QUOTE_MAX {
                return line.to_string();
            }
            let cut = (0..=QUOTE_MAX)
                .rev()
                .find(|&i| line.is_char_boundary(i))
                .unwrap_or(0);
            format!("{}... ({} more bytes)", &line[..cut], line.len() - cut)
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// Memory a scene's processes need, part by part, before anything runs ([`Scene::memory_estimate`]).
#[derive(Clone, Debug, PartialEq)]
pub struct MemoryEstimate {
    /// `(key, bytes, how)`: the scene key that sets the part, its estimate, and how it was
    /// counted (for the error).
    pub parts: Vec<(String, u64, String)>,
}

impl MemoryEstimate {
    /// The whole estimate, in bytes (saturating).
    pub fn total_bytes(&self) -> u64 {
        self.parts
            .iter()
            .fold(0u64, |acc, (_, b, _)| acc.saturating_add(*b))
    }

    /// The largest part: its key and bytes (`("", 0)` for none).
    pub fn largest(&self) -> (&str, u64) {
        self.parts
            .iter()
            .max_by_key(|(_, b, _)| *b)
            .map_or(("", 0), |(k, b, _)| (k.as_str(), *b))
    }
}

/// A scene that needs more memory than the machine has ([`Scene::check_memory`]).
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
#[error(
    "the scene needs an estimated {} of memory, more than the {} available; the largest part is `{key}`: {} ({how})",
    gib(*estimate), gib(*limit), gib(*part)
)]
pub struct MemoryError {
    /// Key of the largest part.
    pub key: String,
    /// Its bytes.
    pub part: u64,
    /// How it was counted.
    pub how: String,
    /// The whole estimate \[bytes\].
    pub estimate: u64,
    /// What the machine has \[bytes\].
    pub limit: u64,
}

fn gib(bytes: u64) -> String {
    format!("{:.1} GiB", bytes as f64 / f64::from(1u32 << 30))
}

/// Bytes per fluid cell and conserved variable: the state and the split step's copy of it.
///
/// NOTE: measured, fluid-only 3-D 128³: 161 MiB for 2.1 M cells of 5 variables (2 copies of 8
/// bytes, README "Coupled step cost").
const FLUID_BYTES_PER_VARIABLE: u64 = 16;

/// Bytes per fluid cell of a coupled run: the dense Λ and λ of two geometries and the
/// near-surface data (README: 342 MiB against 161 MiB at 128³).
const FLUID_COUPLED_BYTES_PER_CELL: u64 = 96;

/// Bytes per solid particle: particle, links, wet surface, and the shared-memory slots of the
/// frames carrying them.
///
/// NOTE: an upper estimate from the data structures (a 3-D cuboid: 8 vertices, 12 wet
/// triangles, up to 26 links; every frame about it is held in 10 bus slots per direction).
const SOLID_BYTES_PER_PARTICLE: [u64; 3] = [1 << 10, 4 << 10, 16 << 10];

/// Slots of a publisher's data segment, each the size of its largest frame
/// (`bus::SAMPLES_PER_SEGMENT`): what one checkpoint frame costs in shared memory.
const BUS_SLOTS: u64 = 10;

impl Scene {
    /// Estimates the memory the scene's processes need: fluid cells × variables × copies (more
    /// with a solid), the shared-memory slots of checkpoint frames, solid particles. A lower
    /// bound of what a run takes, meant to refuse scenes that cannot start (issue 11).
    pub fn memory_estimate(&self) -> MemoryEstimate {
        let dim = self.dim().clamp(1, 3);
        let mut parts = Vec::new();
        let checkpoints = self.run.checkpoint_every > 0 || self.run.record == RecordLevel::All;
        if let Some(fluid) = &self.fluid
            && fluid.node == "real"
        {
            let n_cells = fluid
                .cells
                .iter()
                .fold(1u64, |acc, &n| acc.saturating_mul(u64::from(n)));
            let nvar = dim as u64 + 2;
            let mut per_cell = FLUID_BYTES_PER_VARIABLE * nvar;
            if self.solid.is_some() {
                per_cell += FLUID_COUPLED_BYTES_PER_CELL;
            }
            parts.push((
                "fluid.cells".to_string(),
                n_cells.saturating_mul(per_cell),
                format!("{n_cells} cells x {per_cell} B"),
            ));
            if checkpoints {
                let frame = n_cells.saturating_mul(nvar * 8);
                parts.push((
                    "run.checkpoint_every".to_string(),
                    frame.saturating_mul(BUS_SLOTS),
                    format!("{BUS_SLOTS} shared-memory slots of a {frame} B fluid checkpoint"),
                ));
            }
        }
        if let Some(solid) = &self.solid
            && solid.node == "real"
        {
            for (k, body) in solid.bodies.iter().enumerate() {
                let n_particles = match &body.shape {
                    Shape::Particles(list) => list.len() as u64,
                    _ => body
                        .divisions
                        .iter()
                        .fold(1u64, |acc, &n| acc.saturating_mul(u64::from(n))),
                };
                let per_particle = SOLID_BYTES_PER_PARTICLE[dim - 1];
                parts.push((
                    format!("solid.bodies[{k}].divisions"),
                    n_particles.saturating_mul(per_particle),
                    format!("{n_particles} particles x {per_particle} B"),
                ));
            }
        }
        MemoryEstimate { parts }
    }

    /// Refuses a scene whose [`Scene::memory_estimate`] exceeds `limit` bytes (what the machine
    /// has available), naming the largest part's key, the estimate and the limit.
    pub fn check_memory(&self, limit: u64) -> Result<(), MemoryError> {
        let est = self.memory_estimate();
        let total = est.total_bytes();
        if total <= limit {
            return Ok(());
        }
        let (key, part) = est.largest();
        let how = est
            .parts
            .iter()
            .find(|(k, _, _)| k == key)
            .map_or(String::new(), |(_, _, h)| h.clone());
        Err(MemoryError {
            key: key.to_string(),
            part,
            how,
            estimate: total,
            limit,
        })
    }
}
