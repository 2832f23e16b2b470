//! The bounds a scene must keep before any process starts (issue 38): every size a scene
//! controls (output times, probes, names that become file names, checkpoint frames), every
//! number finite and physically bounded, particles that are polygons or solids, and bodies that
//! meet the fluid's domain. Each refusal names the key, the figure and the limit.

use super::error::{Check, SceneError, quote_list};
use super::{Scene, Shape};

/// Most outputs a run may plan (`output.times` and `output.every` up to `run.t_end`): the
/// coupler holds them in memory and every output writes files.
pub const MAX_OUTPUTS: u64 = 100_000;

/// Most `[[output.probes]]` (each keeps a row per step in its node and writes a file).
pub const MAX_PROBES: usize = 256;

/// Longest name that becomes part of a file name (the scene's `name`, a probe's `name`), in
/// bytes.
pub const MAX_NAME_LEN: usize = 64;

/// Largest magnitude of any number in a scene.
///
/// NOTE: products of a few scene numbers (ρ u², ρ E V, the stiffness of a link times a
/// displacement, t_end over a step) must stay finite in f64 (1.8e308): with every factor
/// below 1e30, products of up to ten of them do.
pub const MAX_MAGNITUDE: f64 = 1e30;

/// Largest frame the bus carries, in bytes (`bus::MAX_FRAME_LEN`, checked equal by a test): a
/// checkpoint larger than this cannot be sent.
pub const MAX_FRAME_BYTES: u64 = 128 << 20;

impl Scene {
    /// The bounds of this module, after each section's own rules.
    pub(super) fn check_bounds(&self, c: &Check<'_>) -> Result<(), SceneError> {
        check_name(c, "name", &self.name)?;
        check_numbers(c, self)?;
        self.check_outputs(c)?;
        self.check_checkpoint_frames(c)?;
        self.check_particles(c)?;
        self.check_bodies_meet_domain(c)
    }

    /// How many outputs the scene plans up to `run.t_end` (saturating; `output.every` counted
    /// without building the list).
    pub fn planned_outputs(&self) -> u64 {
        let t_end = self.run.t_end;
        let listed = self.output.times.len() as u64;
        let periodic = self
            .output
            .every
            .map_or(0.0, |every| (t_end / every).floor());
        // NOTE: `as` saturates a float too large for u64.
        listed.saturating_add(periodic as u64)
    }

    fn check_outputs(&self, c: &Check<'_>) -> Result<(), SceneError> {
        let n = self.planned_outputs();
        if n > MAX_OUTPUTS {
            let (key, how) = match self.output.every {
                Some(every) => (
                    "output.every",
                    format!(
                        "an output every {every:e} s up to run.t_end = {:e} s: {n} outputs",
                        self.run.t_end
                    ),
                ),
                None => ("output.times", format!("{n} output times")),
            };
            return Err(c.invalid(key, &format!("at most {MAX_OUTPUTS} outputs in a run"), how));
        }
        let probes = &self.output.probes;
        if probes.len() > MAX_PROBES {
            return Err(c.invalid(
                "output.probes",
                &format!("at most {MAX_PROBES} probes"),
                probes.len().to_string(),
            ));
        }
        for (k, probe) in probes.iter().enumerate() {
            check_name(c, &format!("output.probes[{k}].name"), &probe.name)?;
        }
        Ok(())
    }

    /// A fluid checkpoint (the recorded `run.checkpoint_every` or `run.record = "all"`) must
    /// fit in one bus frame.
    fn check_checkpoint_frames(&self, c: &Check<'_>) -> Result<(), SceneError> {
        let checkpoints =
            self.run.checkpoint_every > 0 || self.run.record == super::RecordLevel::All;
        let Some(fluid) = self.fluid.as_ref().filter(|f| f.node == "real") else {
            return Ok(());
        };
        if !checkpoints {
            return Ok(());
        }
        let n_cells = fluid
            .cells
            .iter()
            .fold(1u64, |acc, &n| acc.saturating_mul(u64::from(n)));
        let bytes = n_cells.saturating_mul((fluid.cells.len() as u64 + 2) * 8);
        if bytes > MAX_FRAME_BYTES {
            let key = if self.run.checkpoint_every > 0 {
                "run.checkpoint_every"
            } else {
                "run.record"
            };
            return Err(c.invalid(
                key,
                &format!(
                    "fluid checkpoints that fit in one bus frame of {MAX_FRAME_BYTES} bytes (no checkpoints with this grid)"
                ),
                format!("a checkpoint of {n_cells} cells: {bytes} bytes"),
            ));
        }
        Ok(())
    }

    /// Explicit particles: 2-D polygons convex and counter-clockwise with no three consecutive
    /// vertices on a line; 3-D point sets that span a volume.
    fn check_particles(&self, c: &Check<'_>) -> Result<(), SceneError> {
        let Some(solid) = &self.solid else {
            return Ok(());
        };
        for (k, body) in solid.bodies.iter().enumerate() {
            let Shape::Particles(list) = &body.shape else {
                continue;
            };
            for (i, p) in list.iter().enumerate() {
                let path = format!("solid.bodies[{k}].shape.particles[{i}].vertices");
                let why = match c.dim {
                    2 => polygon_fault(&p.vertices),
                    3 => solid_fault(&p.vertices),
                    _ => None,
                };
                if let Some(why) = why {
                    let expected = if c.dim == 2 {
                        "a convex polygon with its vertices counter-clockwise, no three consecutive ones on a line"
                    } else {
                        "points that span a volume (their convex hull is the particle)"
                    };
                    return Err(c.invalid(&path, expected, why));
                }
            }
        }
        Ok(())
    }

    /// Every real body must meet the fluid's domain (a body may touch or cross a side, not lie
    /// wholly outside it).
    fn check_bodies_meet_domain(&self, c: &Check<'_>) -> Result<(), SceneError> {
        let (Some(fluid), Some(solid)) = (&self.fluid, &self.solid) else {
            return Ok(());
        };
        if solid.node != "real" {
            return Ok(());
        }
        for (k, body) in solid.bodies.iter().enumerate() {
            let Some((lo, hi)) = body_bounds(&body.shape, c.dim) else {
                continue;
            };
            let outside = (0..c.dim).any(|a| hi[a] < fluid.lower[a] || lo[a] > fluid.upper[a]);
            if outside {
                return Err(c.invalid(
                    &format!("solid.bodies[{k}]"),
                    &format!(
                        "a body that meets the fluid domain {} to {} (it may touch or cross a side)",
                        quote_list(&fluid.lower),
                        quote_list(&fluid.upper)
                    ),
                    format!(
                        "a body from {} to {}, wholly outside",
                        quote_list(&lo),
                        quote_list(&hi)
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// A name that becomes part of a file name: letters, digits, `-` and `_`, 1 to
/// [`MAX_NAME_LEN`] bytes (no path separator, no `..`, nothing a shell or a file system reads
/// specially).
fn check_name(c: &Check<'_>, path: &str, name: &str) -> Result<(), SceneError> {
    let safe = name
        .chars()
        .all(|ch| ch.is_ascii_alphanumeric() || ch == '-' || ch == '_');
    if safe && !name.is_empty() && name.len() <= MAX_NAME_LEN {
        return Ok(());
    }
    let shown: String = name.chars().take(40).collect();
    let found = if name.chars().count() > 40 {
        format!("{shown:?}... ({} bytes)", name.len())
    } else {
        format!("{shown:?}")
    };
    Err(c.invalid(
        path,
        &format!("a name of 1 to {MAX_NAME_LEN} letters, digits, '-' and '_' (it names files)"),
        found,
    ))
}

/// Every number of the scene finite and at most [`MAX_MAGNITUDE`] in magnitude, named by its
/// key path.
fn check_numbers(c: &Check<'_>, scene: &Scene) -> Result<(), SceneError> {
    let Ok(value) = toml::Value::try_from(scene) else {
        // A scene always serializes (`Scene::to_toml`); nothing to walk otherwise.
        return Ok(());
    };
    let mut bad = None;
    walk(&value, &mut String::new(), &mut bad);
    match bad {
        Some((path, v)) => Err(c.invalid(
            &path,
            &format!("a finite number of magnitude at most {MAX_MAGNITUDE:e}"),
            format!("{v:e}"),
        )),
        None => Ok(()),
    }
}

fn walk(value: &toml::Value, path: &mut String, bad: &mut Option<(String, f64)>) {
    if bad.is_some() {
        return;
    }
    let len = path.len();
    match value {
        toml::Value::Float(v) if !(v.is_finite() && v.abs() <= MAX_MAGNITUDE) => {
            *bad = Some((path.clone(), *v));
        }
        toml::Value::Table(table) => {
            for (key, v) in table {
                if !path.is_empty() {
                    path.push('.');
                }
                path.push_str(key);
                walk(v, path, bad);
                path.truncate(len);
            }
        }
        toml::Value::Array(list) => {
            for (i, v) in list.iter().enumerate() {
                path.push_str(&format!("[{i}]"));
                walk(v, path, bad);
                path.truncate(len);
            }
        }
        _ => {}
    }
}

/// Why a 2-D particle's vertices are not a convex counter-clockwise polygon (`None`: they are).
fn polygon_fault(v: &[Vec<f64>]) -> Option<String> {
    let n = v.len();
    let scale = v
        .iter()
        .flat_map(|p| p.iter())
        .fold(0.0f64, |m, x| m.max(x.abs()))
        .max(f64::MIN_POSITIVE);
    let mut area = 0.0;
    for i in 0..n {
        let (a, b) = (&v[i], &v[(i + 1) % n]);
        area += a[0] * b[1] - b[0] * a[1];
    }
    if area <= 0.0 {
        return Some(format!(
            "vertices in clockwise order or enclosing no area (signed area {:e})",
            area / 2.0
        ));
    }
    for i in 0..n {
        let (a, b, d) = (&v[i], &v[(i + 1) % n], &v[(i + 2) % n]);
        let cross = (b[0] - a[0]) * (d[1] - b[1]) - (b[1] - a[1]) * (d[0] - b[0]);
        // NOTE: relative to the coordinates' size, so a turn lost in round-off counts as none.
        if cross <= 1e-12 * scale * scale {
            let what = if cross.abs() <= 1e-12 * scale * scale {
                "on a line"
            } else {
                "turning clockwise (not convex)"
            };
            return Some(format!(
                "vertices {i}, {}, {} {what}",
                (i + 1) % n,
                (i + 2) % n
            ));
        }
    }
    None
}

/// Why a 3-D particle's points span no volume (`None`: they do).
fn solid_fault(v: &[Vec<f64>]) -> Option<String> {
    let sub = |a: &[f64], b: &[f64]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let o = &v[0];
    let far = v
        .iter()
        .map(|p| sub(p, o))
        .max_by(|a, b| dot(*a, *a).total_cmp(&dot(*b, *b)))?;
    let normal = v
        .iter()
        .map(|p| cross(far, sub(p, o)))
        .max_by(|a, b| dot(*a, *a).total_cmp(&dot(*b, *b)))?;
    let volume = v
        .iter()
        .map(|p| dot(normal, sub(p, o)).abs())
        .fold(0.0, f64::max);
    let size = dot(far, far).sqrt();
    // NOTE: the largest |((far × e) · d)| over the points is (twice the triangle) × height; a
    // volume below 1e-12 of the cube of the particle's size is a flat particle.
    (volume <= 1e-12 * size * size * size || size == 0.0)
        .then(|| "points on a line or in a plane (no volume)".to_string())
}

/// A body's bounding box (`None` when its shape does not say, which validation refuses
/// elsewhere).
fn body_bounds(shape: &Shape, dim: usize) -> Option<(Vec<f64>, Vec<f64>)> {
    let around = |center: &[f64], half: &[f64]| {
        let lo = center.iter().zip(half).map(|(c, h)| c - h).collect();
        let hi = center.iter().zip(half).map(|(c, h)| c + h).collect();
        (lo, hi)
    };
    match shape {
        Shape::Box { center, size } => {
            let half: Vec<f64> = size.iter().map(|s| s / 2.0).collect();
            Some(around(center, &half))
        }
        Shape::Ring {
            center,
            outer_radius,
            ..
        } => Some(around(center, &vec![*outer_radius; dim])),
        Shape::Tube {
            center,
            axis,
            outer_radius,
            length,
            ..
        } => {
            let mut half = vec![*outer_radius; dim];
            *half.get_mut(*axis as usize)? = length / 2.0;
            Some(around(center, &half))
        }
        Shape::Particles(list) => {
            let mut lo = vec![f64::INFINITY; dim];
            let mut hi = vec![f64::NEG_INFINITY; dim];
            for v in list.iter().flat_map(|p| p.vertices.iter()) {
                for a in 0..dim.min(v.len()) {
                    lo[a] = lo[a].min(v[a]);
                    hi[a] = hi[a].max(v[a]);
                }
            }
            lo.iter().all(|x| x.is_finite()).then_some((lo, hi))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene(extra: &str) -> Result<Scene, SceneError> {
        let text = format!(
            "name = \"s\"\n[fluid]\nlower = [0.0]\nupper = [1.0]\ncells = [10]\n[[fluid.init]]\nregion = \"all\"\nrho = 1.0\np = 1.0\n{extra}"
        );
        Scene::from_toml_str(&text, "s.toml")
    }

    #[test]
    fn output_times_beyond_the_limit_are_refused_and_never_listed() {
        let times: Vec<String> = (1..=MAX_OUTPUTS + 1)
            .map(|k| format!("{}", k as f64 * 1e-7))
            .collect();
        let err = scene(&format!("[output]\ntimes = [{}]\n", times.join(", ")))
            .expect_err("too many times");
        assert!(
            err.to_string()
                .contains("key `output.times`: expected at most 100000 outputs in a run, found 100001 output times"),
            "{err}"
        );
        let ok = scene("[output]\nevery = 1e-5\n").expect("100000 outputs");
        // 1 / 1e-5 rounds to 99999.99999999999.
        assert_eq!(ok.planned_outputs(), MAX_OUTPUTS - 1);
        // Up to t_end, which is always last.
        let times = ok.output_times();
        assert!(times.len() as u64 <= MAX_OUTPUTS + 1, "{}", times.len());
        assert_eq!(times.last(), Some(&1.0));
        let mut bad = ok.clone();
        bad.output.every = Some(1e-300);
        // Unvalidated (built in code), the list is still bounded.
        assert!(bad.output_times().len() as u64 <= MAX_OUTPUTS + 1);
    }

    #[test]
    fn the_frame_limit_is_the_bus_limit() {
        #[cfg(feature = "bus")]
        assert_eq!(MAX_FRAME_BYTES, crate::bus::MAX_FRAME_LEN as u64);
        assert_eq!(MAX_FRAME_BYTES, 128 << 20);
    }

    #[test]
    fn polygons_and_solids() {
        let square = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]].map(|v| v.to_vec());
        assert_eq!(polygon_fault(&square), None);
        let mut clockwise = square.clone();
        clockwise.reverse();
        assert!(
            polygon_fault(&clockwise)
                .expect("clockwise")
                .contains("clockwise")
        );
        let tet = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ]
        .map(|v| v.to_vec());
        assert_eq!(solid_fault(&tet), None);
        let flat = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 1.0, 0.0],
        ]
        .map(|v| v.to_vec());
        assert!(solid_fault(&flat).is_some());
    }
}
