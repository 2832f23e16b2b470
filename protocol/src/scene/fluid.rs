//! `[fluid]`: the grid, the gas, its boundaries and initial state, the pressure double's
//! field, and their validation.

use serde::{Deserialize, Serialize};

use super::error::{Check, SceneError, check_node_impl, quote_list};
use super::region::{Region, check_region};

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
    /// Vacuum thresholds (default: [`FluidConfig::vacuum`]).
    #[serde(default, rename = "vacuum", skip_serializing_if = "Option::is_none")]
    pub vacuum_thresholds: Option<VacuumConfig>,
    /// Settings of the `"characteristic"` sides (defaults: σ = 0.25, far-field pressure = the
    /// mean initial pressure along each side); only with such a side.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub characteristic: Option<CharacteristicConfig>,
    /// Initial state, applied in order (a later entry overrides an earlier one).
    #[serde(default)]
    pub init: Vec<InitEntry>,
    /// Settings of the pressure double (`fluid-node --double pressure`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pressure: Option<PressureField>,
    /// A smooth analytic initial state (verification cases); replaces `init` when present.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub profile: Option<Profile>,
    /// MPI ranks of the fluid (default 1): the grid is cut into this many blocks along its
    /// last two axes ([`crate::decomp::choose`]), each at least [`FluidConfig::halo_planes`]
    /// cells along every cut axis; results do not depend on it. `coupler-node run
    /// --fluid-ranks` overrides it.
    #[serde(default = "default_ranks", skip_serializing_if = "is_one")]
    pub ranks: u32,
    /// Blocks per axis (`[kx, ky]` or `[kx, ky, kz]`, product `ranks`): overrides the choice
    /// of [`crate::decomp::choose`] ([`crate::decomp::check`] says which are allowed).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub decomposition: Option<Vec<u32>>,
}

fn default_ranks() -> u32 {
    1
}

fn is_one(n: &u32) -> bool {
    *n == 1
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

pub(super) fn default_node_impl() -> String {
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
    /// Non-reflecting characteristic outflow (Thompson 1987 / Poinsot & Lele 1992, in ghost-cell
    /// form): the outgoing characteristics are extrapolated, the incoming one is held with a
    /// weak relaxation (`σ = 0.25`) toward the far-field pressure, which is the mean initial
    /// pressure of the cells along that side.
    Characteristic,
}

/// Poinsot–Lele relaxation coefficient σ of a characteristic side unless the scene sets one
/// (Poinsot & Lele 1992 use σ ≈ 0.25; Rudy & Strikwerda 1980 found 0.27 best).
pub const DEFAULT_CHARACTERISTIC_SIGMA: f64 = 0.25;

/// `fluid.characteristic`: how the non-reflecting sides hold the far field.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CharacteristicConfig {
    /// Relaxation coefficient σ \[-\] (default 0.25; 0 is the zero-gradient outflow, larger holds
    /// the far-field pressure more firmly and reflects more).
    #[serde(default = "default_characteristic_sigma")]
    pub sigma: f64,
    /// Far-field pressure \[Pa\] of every characteristic side (default: each side's mean
    /// initial pressure).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub p_far: Option<f64>,
}

fn default_characteristic_sigma() -> f64 {
    DEFAULT_CHARACTERISTIC_SIGMA
}

/// `fluid.vacuum`: below either threshold a cell is a vacuum cell.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VacuumConfig {
    /// Density threshold [kg/m³].
    pub rho: f64,
    /// Pressure threshold \[Pa\].
    pub p: f64,
}

impl VacuumConfig {
    /// The default thresholds' fraction of the largest initial density and pressure.
    pub const RELATIVE: f64 = 1e-10;
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

impl FluidConfig {
    /// The vacuum thresholds: `fluid.vacuum`, or by default [`VacuumConfig::RELATIVE`] of the
    /// largest density and pressure of `[[fluid.init]]` (of 1 for a scene without it).
    ///
    /// NOTE: the thresholds must lie above the round-off of the scene's own magnitudes. With
    /// the former absolute default of 1e-10, a burst at 1e11 Pa stopped at step 1097 on a crack
    /// cell holding `ρ = 0` and the energy `−2⁻²⁰` (one unit in the last place of the fluxes
    /// beside it, `p = −3.8e-7 < −1e-10`).
    pub fn vacuum(&self) -> VacuumConfig {
        if let Some(v) = &self.vacuum_thresholds {
            return v.clone();
        }
        let largest = |f: fn(&InitEntry) -> f64| {
            self.init
                .iter()
                .map(f)
                .filter(|x| x.is_finite())
                .fold(None, |m: Option<f64>, x| Some(m.map_or(x, |m| m.max(x))))
                .filter(|&x| x > 0.0)
                .unwrap_or(1.0)
        };
        VacuumConfig {
            rho: VacuumConfig::RELATIVE * largest(|e| e.rho),
            p: VacuumConfig::RELATIVE * largest(|e| e.p),
        }
    }

    /// Cells along each cut axis a rank needs when the grid is decomposed: the flux's ghost
    /// cells (3 for OSMP 3 and 5, 4 for OSMP 7) and the 3 rounds of the positivity fix.
    pub fn halo_planes(&self) -> u32 {
        let ghost = if self.flux.order >= 7 { 4 } else { 3 };
        ghost + 3
    }

    /// The process grid of `ranks` ranks on this grid: `decomposition` when given, else the
    /// choice of [`crate::decomp::choose`]. `None` on one rank or when it does not fit (the
    /// scene's validation refuses that).
    pub fn process_grid(&self) -> Option<[usize; 3]> {
        let cells: Vec<usize> = self.cells.iter().map(|&n| n as usize).collect();
        let (ranks, depth) = (self.ranks as usize, self.halo_planes() as usize);
        match &self.decomposition {
            Some(d) => {
                let dims = std::array::from_fn(|a| d.get(a).map_or(1, |&k| k as usize));
                let extra = d.iter().skip(3).any(|&k| k != 1);
                (!extra && crate::decomp::check(&cells, ranks, dims, depth).is_ok()).then_some(dims)
            }
            None => crate::decomp::choose(&cells, ranks, depth).ok(),
        }
    }

    /// The `[fluid]` rules, in the order their errors are reported.
    pub(super) fn validate(&self, c: &Check<'_>) -> Result<(), SceneError> {
        self.validate_grid(c)?;
        self.validate_numerics(c)?;
        self.validate_ranks(c)?;
        self.validate_characteristic(c)?;
        self.validate_profile(c)?;
        self.validate_init(c)?;
        self.validate_pressure(c)?;
        Ok(())
    }

    /// The node, the box, the cells and the boundary kinds.
    fn validate_grid(&self, c: &Check<'_>) -> Result<(), SceneError> {
        let fluid = self;
        let dim = c.dim;
        check_node_impl(
            "fluid.node",
            &fluid.node,
            &super::error::FLUID_NODES,
            c.file,
        )?;
        c.check_len("fluid.upper", &fluid.upper)?;
        c.check_len("fluid.lower", &fluid.lower)?;
        if fluid.cells.len() != dim || fluid.cells.contains(&0) {
            return Err(c.invalid(
                "fluid.cells",
                &format!("{dim} positive cell counts"),
                quote_list(&fluid.cells),
            ));
        }
        for axis in 0..dim {
            if fluid.upper[axis] <= fluid.lower[axis] {
                return Err(c.invalid(
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
                return Err(c.invalid(
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
                return Err(c.invalid(
                    &format!("fluid.boundary.{name}"),
                    &format!("no such axis in a {dim}-D scene"),
                    "a boundary".into(),
                ));
            }
        }
        Ok(())
    }

    /// The gas, the Courant number, the flux order and the vacuum thresholds.
    fn validate_numerics(&self, c: &Check<'_>) -> Result<(), SceneError> {
        let fluid = self;
        c.positive("fluid.gamma", fluid.gamma - 1.0)
            .map_err(|_| c.invalid("fluid.gamma", "a number > 1", fluid.gamma.to_string()))?;
        if !(fluid.cfl > 0.0 && fluid.cfl <= 1.0) {
            return Err(c.invalid("fluid.cfl", "a number in (0, 1]", fluid.cfl.to_string()));
        }
        if ![3, 5, 7].contains(&fluid.flux.order) {
            return Err(c.invalid(
                "fluid.flux.order",
                "3, 5 or 7",
                fluid.flux.order.to_string(),
            ));
        }
        if let Some(vacuum) = &fluid.vacuum_thresholds {
            c.positive("fluid.vacuum.rho", vacuum.rho)?;
            c.positive("fluid.vacuum.p", vacuum.p)?;
        }
        Ok(())
    }

    /// The MPI ranks: a real fluid, and a process grid of them that fits its grid.
    fn validate_ranks(&self, c: &Check<'_>) -> Result<(), SceneError> {
        let fluid = self;
        let dim = c.dim;
        if !(1..=4096).contains(&fluid.ranks) {
            return Err(c.invalid("fluid.ranks", "1 to 4096", fluid.ranks.to_string()));
        }
        if fluid.ranks > 1 {
            if fluid.node != "real" {
                return Err(c.invalid(
                    "fluid.ranks",
                    "1 unless fluid.node is \"real\" (only the solver runs on MPI ranks)",
                    format!("{} with node {:?}", fluid.ranks, fluid.node),
                ));
            }
            let cells: Vec<usize> = fluid.cells.iter().map(|&n| n as usize).collect();
            let (ranks, depth) = (fluid.ranks as usize, fluid.halo_planes() as usize);
            match &fluid.decomposition {
                Some(d) => {
                    let dims = std::array::from_fn(|a| d.get(a).map_or(1, |&k| k as usize));
                    let long = d.len() != dim && d.len() != 3;
                    let checked = crate::decomp::check(&cells, ranks, dims, depth);
                    if long || checked.is_err() {
                        let why = checked.err().map_or_else(
                            || format!("one count per axis ({dim} or 3 with the extra ones 1)"),
                            |e| e.to_string(),
                        );
                        return Err(c.invalid(
                            "fluid.decomposition",
                            &format!(
                                "blocks per axis whose product is fluid.ranks = {ranks}, cutting \
                                 only the last two axes: {why}"
                            ),
                            format!("{d:?}"),
                        ));
                    }
                }
                None => {
                    if let Err(e) = crate::decomp::choose(&cells, ranks, depth) {
                        return Err(c.invalid(
                            "fluid.ranks",
                            &format!("a count the grid can be cut into: {e}"),
                            fluid.ranks.to_string(),
                        ));
                    }
                }
            }
        } else if fluid
            .decomposition
            .as_ref()
            .is_some_and(|d| d.iter().any(|&k| k != 1))
        {
            return Err(c.invalid(
                "fluid.decomposition",
                "blocks per axis whose product is fluid.ranks = 1",
                format!("{:?}", fluid.decomposition),
            ));
        }
        Ok(())
    }

    /// The `[fluid.characteristic]` table, with a characteristic side to apply to.
    fn validate_characteristic(&self, c: &Check<'_>) -> Result<(), SceneError> {
        let fluid = self;
        if let Some(ch) = &fluid.characteristic {
            let dim = fluid.lower.len().min(3);
            let any = (0..dim).any(|a| fluid.boundary.axis(a).contains(&Boundary::Characteristic));
            if !any {
                return Err(c.invalid(
                    "fluid.characteristic",
                    "a side of kind \"characteristic\" in fluid.boundary",
                    "none: remove the table or make a side characteristic".to_string(),
                ));
            }
            if !(ch.sigma.is_finite() && (0.0..=10.0).contains(&ch.sigma)) {
                return Err(c.invalid(
                    "fluid.characteristic.sigma",
                    "a number in [0, 10]",
                    ch.sigma.to_string(),
                ));
            }
            if let Some(p) = ch.p_far
                && !(p.is_finite() && p > 0.0)
            {
                return Err(c.invalid(
                    "fluid.characteristic.p_far",
                    "a finite pressure > 0",
                    p.to_string(),
                ));
            }
        }
        Ok(())
    }

    /// The analytic initial profile.
    fn validate_profile(&self, c: &Check<'_>) -> Result<(), SceneError> {
        let fluid = self;
        let dim = c.dim;
        match &fluid.profile {
            Some(Profile::DensityWave {
                amplitude,
                wave,
                velocity,
                p,
            }) => {
                if !(amplitude.abs() < 1.0 && *p > 0.0) {
                    return Err(c.invalid(
                        "fluid.profile.density_wave",
                        "|amplitude| < 1 and p > 0",
                        format!("amplitude {amplitude}, p {p}"),
                    ));
                }
                c.check_len("fluid.profile.density_wave.wave", wave)?;
                c.check_len("fluid.profile.density_wave.velocity", velocity)?;
            }
            Some(Profile::IsentropicVortex {
                beta,
                center,
                velocity,
            }) => {
                if dim != 2 || !beta.is_finite() {
                    return Err(c.invalid(
                        "fluid.profile.isentropic_vortex",
                        "a 2-D scene and a finite beta",
                        format!("{dim}-D, beta {beta}"),
                    ));
                }
                c.check_len("fluid.profile.isentropic_vortex.center", center)?;
                c.check_len("fluid.profile.isentropic_vortex.velocity", velocity)?;
            }
            None => {}
        }
        Ok(())
    }

    /// The `[[fluid.init]]` entries: each valid and in the domain, and every cell covered.
    fn validate_init(&self, c: &Check<'_>) -> Result<(), SceneError> {
        let fluid = self;
        if fluid.node == "real" && fluid.init.is_empty() && fluid.profile.is_none() {
            return Err(c.invalid(
                "fluid.init",
                "at least one [[fluid.init]] entry",
                "none".into(),
            ));
        }
        for (k, init) in fluid.init.iter().enumerate() {
            let base = format!("fluid.init[{k}]");
            c.positive(&format!("{base}.rho"), init.rho)?;
            c.positive(&format!("{base}.p"), init.p)?;
            if !init.velocity.is_empty() {
                c.check_len(&format!("{base}.velocity"), &init.velocity)?;
            }
            for (name, v) in init.region.vectors() {
                c.check_len(&format!("{base}.region.{name}"), v)?;
            }
            check_region(&format!("{base}.region"), &init.region)
                .map_err(|(path, expected, found)| c.invalid(&path, &expected, found))?;
            if !init.region.meets_box(&fluid.lower, &fluid.upper) {
                return Err(c.invalid(
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
            return Err(c.invalid(
                "fluid.init",
                "[[fluid.init]] entries that cover every cell (or one with region = \"all\")",
                format!(
                    "cell {} (centre {}) in none of them",
                    quote_list(&cell),
                    quote_list(&centre)
                ),
            ));
        }
        Ok(())
    }

    /// The `[fluid.pressure]` table of the pressure double.
    fn validate_pressure(&self, c: &Check<'_>) -> Result<(), SceneError> {
        let fluid = self;
        if let Some(pressure) = &fluid.pressure {
            if !pressure.value.is_finite() {
                return Err(c.invalid(
                    "fluid.pressure.value",
                    "a finite number",
                    pressure.value.to_string(),
                ));
            }
            if !pressure.gradient.is_empty() {
                c.check_len("fluid.pressure.gradient", &pressure.gradient)?;
            }
        } else if fluid.node == "pressure" {
            return Err(c.invalid(
                "fluid.pressure",
                "a [fluid.pressure] table for the pressure double",
                "none".into(),
            ));
        }
        Ok(())
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
