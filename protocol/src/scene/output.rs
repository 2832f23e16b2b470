//! `[output]`: output times, formats and probes, and their validation.

use serde::{Deserialize, Serialize};

use super::error::{Check, SceneError};

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
    /// File formats: `"csv"`, `"vtk"` (VTK XML: `.vti`, `.vtp` and a `.pvd` series per kind),
    /// `"vtk-legacy"` (legacy ASCII `.vtk`) (default csv and vtk: a run opens in ParaView).
    #[serde(default = "default_formats")]
    pub formats: Vec<OutputFormat>,
    /// Probes.
    #[serde(default)]
    pub probes: Vec<ProbeConfig>,
}

fn default_formats() -> Vec<OutputFormat> {
    vec![OutputFormat::Csv, OutputFormat::Vtk]
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
    /// VTK XML for ParaView: compressed binary `.vti` (fluid) and `.vtp` (particles, wet
    /// surface), and one `.pvd` time series per kind.
    Vtk,
    /// Legacy ASCII VTK (`.vtk`), as written before the XML files.
    VtkLegacy,
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

impl OutputConfig {
    /// The `[output]` rules; probes need the side they probe.
    pub(super) fn validate(
        &self,
        c: &Check<'_>,
        has_fluid: bool,
        has_solid: bool,
    ) -> Result<(), SceneError> {
        if let Some(every) = self.every {
            c.positive("output.every", every)?;
        }
        for (k, t) in self.times.iter().enumerate() {
            if !(t.is_finite() && *t >= 0.0) {
                return Err(c.invalid(&format!("output.times[{k}]"), "a time >= 0", t.to_string()));
            }
        }
        for (k, probe) in self.probes.iter().enumerate() {
            let base = format!("output.probes[{k}]");
            // Each probe writes `probe_<name>.csv`: a repeated name would overwrite another's.
            if let Some(first) = self.probes[..k].iter().position(|p| p.name == probe.name) {
                return Err(c.invalid(
                    &format!("{base}.name"),
                    &format!("a name no other probe has (output.probes[{first}] has it)"),
                    format!("{:?}", probe.name),
                ));
            }
            let n_targets = usize::from(probe.point.is_some())
                + usize::from(probe.particle_at.is_some())
                + usize::from(probe.particle.is_some());
            if n_targets != 1 {
                return Err(c.invalid(
                    &base,
                    "exactly one of point, particle_at, particle",
                    format!("{n_targets}"),
                ));
            }
            if let Some(p) = &probe.point {
                c.check_len(&format!("{base}.point"), p)?;
                if !has_fluid {
                    return Err(c.invalid(
                        &format!("{base}.point"),
                        "a [fluid] section to probe",
                        "none".into(),
                    ));
                }
            }
            if let Some(p) = &probe.particle_at {
                c.check_len(&format!("{base}.particle_at"), p)?;
            }
            if (probe.particle_at.is_some() || probe.particle.is_some()) && !has_solid {
                return Err(c.invalid(
                    &base,
                    "a [solid] section to probe a particle",
                    "none".into(),
                ));
            }
        }
        Ok(())
    }
}
