//! `coupler-node report`: the papers' figures drawn from a run's outputs.
//!
//! - `report figures RUN [--out DIR] [--polar]`: everything the run's files allow: the energy
//!   error against time (paper 003 Fig. 7, 10) from the record's diagnostics; for each particle
//!   probe its x against time, its xy trajectory and its normal stress (Fig. 8, 9, 13), with all
//!   particle probes on one chart when there are several (Fig. 13, 14); for each fluid probe its
//!   pressure; for each output of a 2-D run the density and pressure fields with the wet surface
//!   on top as PNG images (Fig. 6, 12, 18); with `--polar`, the normal stress against the
//!   azimuthal angle about the solid's centroid (Fig. 15). The ledger's mass and energy errors
//!   against time. Each field is also framed as an SVG (axes in metres, colour bar with the
//!   unit, the field and the time in the title), and `index.html` gathers the summary and every
//!   figure on one page.
//! - `report energy RUN... [--scale S,...] --out FILE.svg`: the energy error of several runs on
//!   one chart, each times its scale (Fig. 7: dt, dt/2, dt/4 rescaled by 1, 4, 16).
//! - `report pressure RUN... --reference P --out FILE.svg`: the largest |p − P| over the fluid
//!   cells of each output against its time, one curve per run (Fig. 5: explicit against
//!   semi-implicit on the rod).
//! - `report work-precision RUN... --reference REF --probe NAME --out FILE.svg`: for each run its
//!   wall time, its largest energy error and its largest deviation of the probed particle's x
//!   from the reference run's (interpolated in time), as a table and as error against wall time
//!   (log10 both), one curve per grid and scheme.
//!
//! Every chart also writes its numbers as CSV beside it.

pub mod data;
pub mod error;
pub mod field;
pub mod page;
pub mod plot;

use std::path::{Path, PathBuf};

use anyhow::Context;
use protocol::scene::Scene;

use crate::record;
use data::{Table, energy_history, relative_energy_error, stress_by_angle};
use plot::{Field, Series, field_png, line_chart};

/// A run's folder name, for legends and tables.
fn run_name(run: &Path) -> String {
    run.file_name().map_or_else(
        || run.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

/// Creates the folder `out` goes into.
fn create_parent(out: &Path) -> anyhow::Result<()> {
    match out.parent().filter(|d| !d.as_os_str().is_empty()) {
        Some(dir) => {
            std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))
        }
        None => Ok(()),
    }
}

fn read_table(path: &Path) -> anyhow::Result<Table> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    Table::parse(&text, &path.display().to_string()).map_err(|e| anyhow::anyhow!(e))
}

/// Writes `path`: a header row, then `records` (each as long as the header). A label holding a
/// comma or a quote is quoted.
fn write_table<R: IntoIterator<Item = String>>(
    path: &Path,
    header: &[&str],
    records: impl IntoIterator<Item = R>,
) -> anyhow::Result<()> {
    let mut table = csv::Writer::from_path(path)?;
    table.write_record(header)?;
    for record in records {
        table.write_record(record)?;
    }
    table.flush()?;
    Ok(())
}

/// Writes the points of `series` as `series,<x>,<y>` rows (`axes` names the two columns).
fn write_csv(path: &Path, axes: [&str; 2], series: &[Series]) -> anyhow::Result<()> {
    let rows = series.iter().flat_map(|s| {
        s.points
            .iter()
            .map(|(x, y)| [s.label.clone(), format!("{x:e}"), format!("{y:e}")])
    });
    write_table(path, &["series", axes[0], axes[1]], rows)
        .with_context(|| format!("writing {}", path.display()))
}

/// Writes a chart and its CSV; returns the SVG's path.
fn chart(
    out: &Path,
    stem: &str,
    title: &str,
    axes: (&str, &str),
    series: &[Series],
    written: &mut Vec<PathBuf>,
) -> anyhow::Result<()> {
    let svg = out.join(format!("{stem}.svg"));
    line_chart(&svg, title, axes.0, axes.1, series).map_err(|e| anyhow::anyhow!(e))?;
    write_csv(&out.join(format!("{stem}.csv")), ["x", "y"], series)?;
    written.push(svg);
    Ok(())
}

/// The relative energy error of the run in `run` (its `exchange.mcap`).
fn run_energy(run: &Path) -> anyhow::Result<Vec<data::EnergyPoint>> {
    let file = run.join("exchange.mcap");
    let bytes = std::fs::read(&file).with_context(|| format!("reading {}", file.display()))?;
    let rec =
        record::read_recording(&bytes).with_context(|| format!("reading {}", file.display()))?;
    let json: Vec<&[u8]> = rec
        .topic(record::DIAGNOSTICS_TOPIC)
        .map(|m| m.data.as_slice())
        .collect();
    anyhow::ensure!(
        !json.is_empty(),
        "{}: no diagnostics (record = \"none\"?)",
        file.display()
    );
    energy_history(json).map_err(|e| anyhow::anyhow!("{}: {e}", file.display()))
}

/// Files of `dir` named `<prefix><k><suffix>`, by k.
fn numbered(dir: &Path, prefix: &str, suffix: &str) -> Vec<(String, PathBuf)> {
    let mut found: Vec<(String, PathBuf)> = std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .filter_map(|e| e.ok())
        .filter_map(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            let key = name.strip_prefix(prefix)?.strip_suffix(suffix)?.to_string();
            Some((key, e.path()))
        })
        .collect();
    found.sort_by(|a, b| {
        let num = |s: &str| s.parse::<u64>().ok();
        num(&a.0).cmp(&num(&b.0)).then_with(|| a.0.cmp(&b.0))
    });
    found
}

/// `report figures`: every figure the outputs in `run` allow, into `out`.
pub fn figures(run: &Path, out: &Path, polar: bool) -> anyhow::Result<Vec<PathBuf>> {
    let scene_path = run.join("scene.toml");
    let text = std::fs::read_to_string(&scene_path).with_context(|| {
        format!(
            "reading {} (is {} the output folder of a run?)",
            scene_path.display(),
            run.display()
        )
    })?;
    let scene = Scene::from_toml_str(&text, &scene_path.display().to_string())
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let mut written = Vec::new();
    if run.join("exchange.mcap").exists() && scene.fluid.is_some() && scene.solid.is_some() {
        let energy = run_energy(run)?;
        chart(
            out,
            "energy_error",
            &format!("{}: energy error / largest exchange", scene.name),
            ("t [s]", "|E - E0| / max |W|"),
            &[Series {
                label: scene.name.clone(),
                points: relative_energy_error(&energy, 1.0),
            }],
            &mut written,
        )?;
    }
    ledger_figures(run, out, &scene.name, &mut written)?;
    let particles = probe_figures(run, out, &mut written)?;
    if particles.len() > 1 {
        probes_together(&particles, out, &mut written)?;
    }
    let outputs = output_times(run)?;
    if let Some(fluid) = scene.fluid.as_ref().filter(|_| scene.dim() == 2) {
        field_figures(run, out, (&scene.name, fluid), &outputs, &mut written)?;
    }
    if polar {
        polar_figures(run, out, &mut written)?;
    }
    let summary = std::fs::read_to_string(run.join("summary.json")).ok();
    let page = page::write_page(out, &scene.name, summary.as_deref(), &written, &outputs)
        .with_context(|| format!("writing {}", out.join("index.html").display()))?;
    written.push(page);
    Ok(written)
}

/// The run's output times `(k, t)` from `outputs.csv` (none without the file).
fn output_times(run: &Path) -> anyhow::Result<page::Outputs> {
    let path = run.join("outputs.csv");
    if !path.exists() {
        return Ok(Vec::new());
    }
    let t = read_table(&path)?;
    Ok(t.pairs("k", "t")
        .unwrap_or_default()
        .into_iter()
        .map(|(k, t)| (format!("{k}"), t))
        .collect())
}

/// The ledger's relative mass and energy errors against time, when the run has `ledger.csv`.
fn ledger_figures(
    run: &Path,
    out: &Path,
    name: &str,
    written: &mut Vec<PathBuf>,
) -> anyhow::Result<()> {
    let path = run.join("ledger.csv");
    if !path.exists() {
        return Ok(());
    }
    let t = read_table(&path)?;
    for (column, stem, title) in [
        ("mass_rel_err", "ledger_mass", "relative mass error"),
        ("energy_rel_err", "ledger_energy", "relative energy error"),
    ] {
        if let Some(points) = t.pairs("t", column) {
            chart(
                out,
                stem,
                &format!("{name}: {title} (ledger.csv)"),
                ("t [s]", column),
                &[Series {
                    label: name.to_string(),
                    points,
                }],
                written,
            )?;
        }
    }
    Ok(())
}

/// One chart per probe file of `run` (position, trajectory and stress of a particle, or the
/// pressure of a fluid probe); returns the particle probes, by name.
fn probe_figures(
    run: &Path,
    out: &Path,
    written: &mut Vec<PathBuf>,
) -> anyhow::Result<Vec<(String, Table)>> {
    let mut particles: Vec<(String, Table)> = Vec::new();
    for (name, path) in numbered(run, "probe_", ".csv") {
        let t = read_table(&path)?;
        if let (Some(x), Some(xy)) = (t.pairs("t", "x"), t.pairs("x", "y")) {
            let one = |points| {
                [Series {
                    label: name.clone(),
                    points,
                }]
            };
            chart(
                out,
                &format!("probe_{name}_x"),
                &format!("{name}: x of the particle"),
                ("t [s]", "x [m]"),
                &one(x),
                written,
            )?;
            chart(
                out,
                &format!("probe_{name}_xy"),
                &format!("{name}: trajectory"),
                ("x [m]", "y [m]"),
                &one(xy),
                written,
            )?;
            if let Some(s) = t.pairs("t", "sigma_n") {
                chart(
                    out,
                    &format!("probe_{name}_sigma"),
                    &format!("{name}: normal stress"),
                    ("t [s]", "sigma_n [Pa]"),
                    &one(s),
                    written,
                )?;
            }
            particles.push((name, t));
        } else if let Some(p) = t.pairs("t", "p") {
            chart(
                out,
                &format!("probe_{name}_p"),
                &format!("{name}: pressure"),
                ("t [s]", "p [Pa]"),
                &[Series {
                    label: name.clone(),
                    points: p,
                }],
                written,
            )?;
        }
    }
    Ok(particles)
}

/// The particle probes on one chart each for displacement and stress.
fn probes_together(
    particles: &[(String, Table)],
    out: &Path,
    written: &mut Vec<PathBuf>,
) -> anyhow::Result<()> {
    let displacement: Vec<Series> = particles
        .iter()
        .filter_map(|(name, t)| {
            let x = t.pairs("t", "x")?;
            let x0 = x.first()?.1;
            Some(Series {
                label: name.clone(),
                points: x.iter().map(|(t, x)| (*t, x - x0)).collect(),
            })
        })
        .collect();
    chart(
        out,
        "probes_displacement",
        "x displacement of the probed particles",
        ("t [s]", "x - x(0) [m]"),
        &displacement,
        written,
    )?;
    let stress: Vec<Series> = particles
        .iter()
        .filter_map(|(name, t)| {
            Some(Series {
                label: name.clone(),
                points: t.pairs("t", "sigma_n")?,
            })
        })
        .collect();
    if !stress.is_empty() {
        chart(
            out,
            "probes_sigma",
            "normal stress of the probed particles",
            ("t [s]", "sigma_n [Pa]"),
            &stress,
            written,
        )?;
    }
    Ok(())
}

/// The density and pressure fields of a 2-D fluid's outputs as pictures, with the solid's
/// surface of the same output drawn over them.
fn field_figures(
    run: &Path,
    out: &Path,
    (name, fluid): (&str, &protocol::scene::FluidConfig),
    outputs: &page::Outputs,
    written: &mut Vec<PathBuf>,
) -> anyhow::Result<()> {
    let grid = |cells: Vec<(f64, f64, f64)>| Field {
        cells,
        lower: [fluid.lower[0], fluid.lower[1]],
        upper: [fluid.upper[0], fluid.upper[1]],
        n: [fluid.cells[0] as usize, fluid.cells[1] as usize],
    };
    for (k, path) in numbered(run, "fluid_", ".csv") {
        let t = read_table(&path)?;
        let surface = run.join(format!("surface_{k}.csv"));
        let segments: Vec<[f64; 4]> = if surface.exists() {
            let s = read_table(&surface)?;
            match ["x0", "y0", "x1", "y1"].map(|c| s.column(c)) {
                [Some(a), Some(b), Some(c), Some(d)] => {
                    s.rows.iter().map(|r| [r[a], r[b], r[c], r[d]]).collect()
                }
                _ => Vec::new(),
            }
        } else {
            Vec::new()
        };
        let time = outputs.iter().find(|(key, _)| *key == k).map(|o| o.1);
        for (var, what, quantity) in [("rho", "density", "ρ [kg/m³]"), ("p", "pressure", "p [Pa]")]
        {
            let (Some(x), Some(y), Some(v)) = (t.column("x"), t.column("y"), t.column(var)) else {
                continue;
            };
            let png = out.join(format!("field_{k}_{var}.png"));
            let cells = t.rows.iter().map(|r| (r[x], r[y], r[v])).collect();
            let colours =
                field_png(&png, &grid(cells), &segments, 1000).map_err(|e| anyhow::anyhow!(e))?;
            written.push(png.clone());
            let title = match time {
                Some(t) => format!("{name}: {what} at t = {t:e} s (output {k})"),
                None => format!("{name}: {what} (output {k})"),
            };
            let svg = out.join(format!("field_{k}_{var}.svg"));
            let frame = field::Frame {
                title: &title,
                quantity,
                lower: [fluid.lower[0], fluid.lower[1]],
                upper: [fluid.upper[0], fluid.upper[1]],
                colours,
            };
            field::field_svg(&svg, &png, &frame).map_err(|e| anyhow::anyhow!(e))?;
            written.push(svg);
        }
    }
    Ok(())
}

/// The normal stress of each solid output against the azimuthal angle (`--polar`).
fn polar_figures(run: &Path, out: &Path, written: &mut Vec<PathBuf>) -> anyhow::Result<()> {
    for (k, path) in numbered(run, "solid_", ".csv") {
        let t = read_table(&path)?;
        if let Some(points) = stress_by_angle(&t) {
            chart(
                out,
                &format!("solid_{k}_sigma_theta"),
                &format!("output {k}: normal stress against the azimuthal angle"),
                ("theta [deg]", "sigma_n [Pa]"),
                &[Series {
                    label: format!("output {k}"),
                    points,
                }],
                written,
            )?;
        }
    }
    Ok(())
}

/// `report energy`: the energy errors of `runs`, each times its scale, on one chart `out`.
pub fn energy(runs: &[PathBuf], scales: &[f64], out: &Path) -> anyhow::Result<()> {
    anyhow::ensure!(
        scales.is_empty() || scales.len() == runs.len(),
        "{} scales for {} runs",
        scales.len(),
        runs.len()
    );
    let mut series = Vec::new();
    for (i, run) in runs.iter().enumerate() {
        let scale = scales.get(i).copied().unwrap_or(1.0);
        let name = run_name(run);
        series.push(Series {
            label: if scale == 1.0 {
                name
            } else {
                format!("{name} x {scale}")
            },
            points: relative_energy_error(&run_energy(run)?, scale),
        });
    }
    create_parent(out)?;
    line_chart(
        out,
        "energy error / largest exchange",
        "t [s]",
        "|E - E0| / max |W|",
        &series,
    )
    .map_err(|e| anyhow::anyhow!(e))?;
    write_csv(&out.with_extension("csv"), ["t", "error"], &series)
}

/// Largest |p − `reference`| over the cells of each fluid output of `run`, against the
/// output's time (from `outputs.csv`).
pub fn pressure_error(run: &Path, reference: f64) -> anyhow::Result<Vec<(f64, f64)>> {
    let outputs = read_table(&run.join("outputs.csv"))?;
    let (k, t) = outputs
        .column("k")
        .zip(outputs.column("t"))
        .with_context(|| format!("{}: outputs.csv has no k,t columns", run.display()))?;
    let mut points = Vec::new();
    for row in &outputs.rows {
        let path = run.join(format!("fluid_{}.csv", row[k]));
        let fluid = read_table(&path)?;
        let p = fluid
            .column("p")
            .with_context(|| format!("{}: no p column", path.display()))?;
        let worst = fluid
            .rows
            .iter()
            .map(|r| (r[p] - reference).abs())
            .fold(0.0, f64::max);
        points.push((row[t], worst));
    }
    Ok(points)
}

/// `report pressure`: [`pressure_error`] of `runs` on one chart `out`.
pub fn pressure(runs: &[PathBuf], reference: f64, out: &Path) -> anyhow::Result<()> {
    let mut series = Vec::new();
    for run in runs {
        series.push(Series {
            label: run_name(run),
            points: pressure_error(run, reference)?,
        });
    }
    create_parent(out)?;
    line_chart(
        out,
        &format!("largest |p - {reference}| over the fluid cells"),
        "t [s]",
        "max |p - p0| [Pa]",
        &series,
    )
    .map_err(|e| anyhow::anyhow!(e))?;
    write_csv(&out.with_extension("csv"), ["t", "error"], &series)
}

/// The probed particle's x of `reference` at time `t`, linear between its samples (`None`
/// outside them).
fn interpolate(reference: &[(f64, f64)], t: f64) -> Option<f64> {
    let i = reference.partition_point(|p| p.0 < t);
    match (i.checked_sub(1).map(|j| reference[j]), reference.get(i)) {
        (_, Some(b)) if b.0 == t => Some(b.1),
        (Some(a), Some(b)) => Some(a.1 + (b.1 - a.1) * (t - a.0) / (b.0 - a.0)),
        _ => None,
    }
}

/// One run of a work–precision study.
#[derive(Clone, Debug, PartialEq)]
pub struct WorkPoint {
    /// The run's folder name.
    pub run: String,
    /// Grid and scheme, e.g. `400x200 semi-implicit`.
    pub group: String,
    /// Wall time of the run \[s\].
    pub wall_s: f64,
    /// Steps.
    pub steps: u64,
    /// Largest |E − E0| / largest |W| over the run.
    pub energy_error: f64,
    /// Largest |x − x_ref| of the probed particle over the run's samples within the
    /// reference's time span \[m\].
    pub displacement_error: f64,
}

/// [`WorkPoint`] of `run` against `reference` for probe `probe`.
pub fn work_point(run: &Path, reference: &[(f64, f64)], probe: &str) -> anyhow::Result<WorkPoint> {
    let summary_path = run.join("summary.json");
    let summary: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(&summary_path)
            .with_context(|| format!("reading {}", summary_path.display()))?,
    )
    .with_context(|| format!("parsing {}", summary_path.display()))?;
    let number = |key: &str| {
        summary[key]
            .as_f64()
            .with_context(|| format!("{}: no number {key}", summary_path.display()))
    };
    let scene_path = run.join("scene.toml");
    let text = std::fs::read_to_string(&scene_path)
        .with_context(|| format!("reading {}", scene_path.display()))?;
    let scene = Scene::from_toml_str(&text, &scene_path.display().to_string())
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    let cells = scene.fluid.as_ref().map_or_else(String::new, |f| {
        f.cells
            .iter()
            .map(u32::to_string)
            .collect::<Vec<_>>()
            .join("x")
    });
    let scheme = match scene.run.scheme {
        protocol::scene::SchemeName::Explicit => "explicit",
        protocol::scene::SchemeName::SemiImplicit => "semi-implicit",
    };
    let x = read_table(&run.join(format!("probe_{probe}.csv")))?
        .pairs("t", "x")
        .with_context(|| format!("{}: probe {probe} has no t, x", run.display()))?;
    let displacement_error = x
        .iter()
        .filter_map(|(t, x)| Some((x - interpolate(reference, *t)?).abs()))
        .fold(0.0, f64::max);
    let energy_error = relative_energy_error(&run_energy(run)?, 1.0)
        .iter()
        .map(|p| p.1.abs())
        .fold(0.0, f64::max);
    Ok(WorkPoint {
        run: run_name(run),
        group: format!("{cells} {scheme}"),
        wall_s: number("wall_s")?,
        steps: number("steps")? as u64,
        energy_error,
        displacement_error,
    })
}

/// `report work-precision`: [`work_point`] of each run, as `out` (two charts: `out` for the
/// displacement error, `*_energy.svg` for the energy error) and a CSV table beside it.
pub fn work_precision(
    runs: &[PathBuf],
    reference: &Path,
    probe: &str,
    out: &Path,
) -> anyhow::Result<Vec<WorkPoint>> {
    let reference = read_table(&reference.join(format!("probe_{probe}.csv")))?
        .pairs("t", "x")
        .with_context(|| format!("{}: probe {probe} has no t, x", reference.display()))?;
    let points: Vec<WorkPoint> = runs
        .iter()
        .map(|r| work_point(r, &reference, probe))
        .collect::<anyhow::Result<_>>()?;
    create_parent(out)?;
    let csv = out.with_extension("csv");
    let header = [
        "run",
        "group",
        "wall_s",
        "steps",
        "energy_error",
        "displacement_error",
    ];
    let rows = points.iter().map(|p| {
        [
            p.run.clone(),
            p.group.clone(),
            format!("{:e}", p.wall_s),
            p.steps.to_string(),
            format!("{:e}", p.energy_error),
            format!("{:e}", p.displacement_error),
        ]
    });
    write_table(&csv, &header, rows).with_context(|| format!("writing {}", csv.display()))?;
    let curves = |error: fn(&WorkPoint) -> f64| -> Vec<Series> {
        let mut groups: Vec<String> = points.iter().map(|p| p.group.clone()).collect();
        groups.dedup();
        groups.sort();
        groups.dedup();
        groups
            .into_iter()
            .map(|g| {
                let mut pts: Vec<(f64, f64)> = points
                    .iter()
                    .filter(|p| p.group == g && error(p) > 0.0)
                    .map(|p| (p.wall_s.log10(), error(p).log10()))
                    .collect();
                pts.sort_by(|a, b| a.0.total_cmp(&b.0));
                Series {
                    label: g,
                    points: pts,
                }
            })
            .collect()
    };
    line_chart(
        out,
        &format!("probe {probe}: largest |x - x_ref| against wall time"),
        "log10 wall time [s]",
        "log10 |x - x_ref| [m]",
        &curves(|p| p.displacement_error),
    )
    .map_err(|e| anyhow::anyhow!(e))?;
    let stem = out
        .file_stem()
        .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
    line_chart(
        &out.with_file_name(format!("{stem}_energy.svg")),
        "largest energy error / largest exchange against wall time",
        "log10 wall time [s]",
        "log10 |E - E0| / max |W|",
        &curves(|p| p.energy_error),
    )
    .map_err(|e| anyhow::anyhow!(e))?;
    Ok(points)
}

#[cfg(test)]
mod tests {
    use super::{Series, interpolate, write_csv};

    #[test]
    fn a_chart_csv_quotes_a_label_with_a_comma_and_reads_back() {
        let dir = std::env::temp_dir().join(format!("cosim-report-csv-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        let path = dir.join("chart.csv");
        let series = [
            Series {
                label: "run 1, dt/2".into(),
                points: vec![(0.5, 1e-7)],
            },
            Series {
                label: "plain".into(),
                points: vec![(1.0, -2.0)],
            },
        ];
        write_csv(&path, ["t", "error"], &series).expect("writes");
        let text = std::fs::read_to_string(&path).expect("reads");
        assert_eq!(
            text,
            "series,t,error\n\"run 1, dt/2\",5e-1,1e-7\nplain,1e0,-2e0\n"
        );
        let rows: Vec<(String, f64, f64)> = csv::Reader::from_path(&path)
            .expect("opens")
            .deserialize()
            .collect::<Result<_, _>>()
            .expect("reads back");
        assert_eq!(rows[0], ("run 1, dt/2".to_string(), 0.5, 1e-7));
        let _ = std::fs::remove_dir_all(dir);
    }

    #[test]
    fn the_reference_is_interpolated_linearly_inside_its_samples_only() {
        let r = [(0.0, 1.0), (1.0, 3.0), (3.0, 3.0)];
        assert_eq!(interpolate(&r, 0.0), Some(1.0));
        assert_eq!(interpolate(&r, 0.25), Some(1.5));
        assert_eq!(interpolate(&r, 1.0), Some(3.0));
        assert_eq!(interpolate(&r, 2.0), Some(3.0));
        assert_eq!(interpolate(&r, -0.1), None);
        assert_eq!(interpolate(&r, 3.5), None);
    }
}
