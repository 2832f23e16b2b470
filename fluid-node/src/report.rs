//! Work–precision study (not part of the pure core: it reads the clock and writes files): runs
//! a 1-D Riemann scene at several resolutions with OSMP of several orders and the second-order
//! TVD reference (MUSCL–Hancock + HLLC), measures wall time, and writes a CSV table and a
//! hand-written SVG plot of the L1 density error against wall time.

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use protocol::scene::Scene;

use crate::fv::study::{RiemannReference, StudyError, solver_for};
use crate::fv::{FluxKind, SolverError, StepError};

/// Why the work–precision study stopped.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// The scene has no `[fluid]` table.
    #[error("scene {scene} has no [fluid] table")]
    NoFluid {
        /// The scene's name.
        scene: String,
    },
    /// The scene is no 1-D Riemann problem.
    #[error(transparent)]
    Study(#[from] StudyError),
    /// An OSMP order other than 3, 5 or 7.
    #[error("osmp order must be 3, 5 or 7, got {order}")]
    FluxOrder {
        /// The order given.
        order: u32,
    },
    /// A solver could not be built.
    #[error(transparent)]
    Solver(#[from] SolverError),
    /// A run met numerical trouble.
    #[error("{scheme} at {cells} cells: numerical trouble: {source}")]
    Trouble {
        /// The scheme (`osmp5`, ...).
        scheme: String,
        /// Its cells.
        cells: u32,
        /// The failed step.
        source: StepError,
    },
    /// The output folder or a file could not be written.
    #[error("{action} {}: {source}", path.display())]
    Io {
        /// `"creating"` (the folder) or `"writing"` (a file).
        action: &'static str,
        /// The path.
        path: std::path::PathBuf,
        /// The reason.
        source: std::io::Error,
    },
}

/// One run of the study.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// `"osmp3"`, `"osmp5"`, `"osmp7"` or `"muscl-hancock"`.
    pub scheme: String,
    /// Formal order (2 for MUSCL–Hancock).
    pub order: u32,
    /// Cells.
    pub cells: u32,
    /// Time steps taken.
    pub steps: u64,
    /// Wall time of the run \[s\] (setup and error evaluation excluded).
    pub wall_s: f64,
    /// L1 error of the density at `run.t_end` [kg/m²].
    pub l1_rho: f64,
}

/// Runs per (scheme, resolution); the table keeps the shortest wall time.
pub const TIMING_RUNS: usize = 3;

/// Runs the study (one thread) and writes `work_precision_<scene>.csv` and `.svg` into
/// `out_dir` (created if missing). The scene must be 1-D with two constant states.
pub fn work_precision(
    scene: &Scene,
    resolutions: &[u32],
    orders: &[u32],
    out_dir: &Path,
) -> Result<Vec<Row>, ReportError> {
    let cfg = scene.fluid.as_ref().ok_or_else(|| ReportError::NoFluid {
        scene: scene.name.clone(),
    })?;
    let reference = RiemannReference::from_config(cfg)?;
    let t_end = scene.run.t_end;
    let mut schemes: Vec<(String, u32, FluxKind)> = Vec::new();
    for &order in orders {
        if ![3, 5, 7].contains(&order) {
            return Err(ReportError::FluxOrder { order });
        }
        schemes.push((format!("osmp{order}"), order, FluxKind::Osmp(order)));
    }
    schemes.push(("muscl-hancock".into(), 2, FluxKind::MusclHancock));
    let mut rows = Vec::new();
    for (name, order, flux) in &schemes {
        for &cells in resolutions {
            // Best of `TIMING_RUNS` identical runs: the runs are deterministic, so the spread
            // is the machine's, and the minimum is the closest to the scheme's own cost.
            let mut wall_s = f64::INFINITY;
            let mut run = None;
            for _ in 0..TIMING_RUNS {
                let mut solver = solver_for(cfg, *flux, cells, 1)?;
                let start = Instant::now();
                let (steps, last) = solver.run_until(t_end, u64::MAX);
                wall_s = wall_s.min(start.elapsed().as_secs_f64());
                last.check(last.step)
                    .map_err(|source| ReportError::Trouble {
                        scheme: name.clone(),
                        cells,
                        source,
                    })?;
                run = Some((solver, steps));
            }
            let (solver, steps) = run.expect("TIMING_RUNS > 0");
            rows.push(Row {
                scheme: name.clone(),
                order: *order,
                cells,
                steps,
                wall_s,
                l1_rho: reference.l1_density(&solver),
            });
        }
    }
    let io = |action, path: &Path| {
        let path = path.to_path_buf();
        move |source| ReportError::Io {
            action,
            path,
            source,
        }
    };
    std::fs::create_dir_all(out_dir).map_err(io("creating", out_dir))?;
    let base = out_dir.join(format!("work_precision_{}", scene.name));
    let csv_path = base.with_extension("csv");
    std::fs::write(&csv_path, to_csv(&rows)).map_err(io("writing", &csv_path))?;
    let svg_path = base.with_extension("svg");
    std::fs::write(&svg_path, to_svg(&rows, &scene.name)).map_err(io("writing", &svg_path))?;
    Ok(rows)
}

/// The CSV table: `scheme,order,cells,steps,wall_s,l1_rho`.
pub fn to_csv(rows: &[Row]) -> String {
    let mut s = String::from("scheme,order,cells,steps,wall_s,l1_rho\n");
    for r in rows {
        let _ = writeln!(
            s,
            "{},{},{},{},{:.6e},{:.6e}",
            r.scheme, r.order, r.cells, r.steps, r.wall_s, r.l1_rho
        );
    }
    s
}

/// A log–log SVG plot of L1 error against wall time, one polyline per scheme.
pub fn to_svg(rows: &[Row], title: &str) -> String {
    let (w, h, margin) = (640.0, 440.0, 70.0);
    let finite = |v: f64| v.is_finite() && v > 0.0;
    let xs: Vec<f64> = rows
        .iter()
        .map(|r| r.wall_s.max(1e-6))
        .filter(|v| finite(*v))
        .collect();
    let ys: Vec<f64> = rows
        .iter()
        .map(|r| r.l1_rho)
        .filter(|v| finite(*v))
        .collect();
    let range = |v: &[f64]| {
        let lo = v.iter().cloned().fold(f64::INFINITY, f64::min);
        let hi = v.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        if lo.is_finite() && hi.is_finite() {
            (
                lo.log10().floor(),
                hi.log10().ceil().max(lo.log10().floor() + 1.0),
            )
        } else {
            (0.0, 1.0)
        }
    };
    let (x0, x1) = range(&xs);
    let (y0, y1) = range(&ys);
    let px = |v: f64| margin + (v.max(1e-6).log10() - x0) / (x1 - x0) * (w - 2.0 * margin);
    let py = |v: f64| h - margin - (v.log10() - y0) / (y1 - y0) * (h - 2.0 * margin);
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let _ = writeln!(
        s,
        r#"<text x="{}" y="20" text-anchor="middle" font-size="14">work-precision: {}</text>"#,
        w / 2.0,
        title.replace(['<', '>', '&'], "")
    );
    // Axes with decade ticks.
    let _ = writeln!(
        s,
        r#"<rect x="{margin}" y="{margin}" width="{}" height="{}" fill="none" stroke="black"/>"#,
        w - 2.0 * margin,
        h - 2.0 * margin
    );
    for d in (x0 as i32)..=(x1 as i32) {
        let x = px(10f64.powi(d));
        let _ = writeln!(
            s,
            r##"<line x1="{x}" y1="{margin}" x2="{x}" y2="{}" stroke="#ddd"/><text x="{x}" y="{}" text-anchor="middle">1e{d}</text>"##,
            h - margin,
            h - margin + 16.0
        );
    }
    for d in (y0 as i32)..=(y1 as i32) {
        let y = py(10f64.powi(d));
        let _ = writeln!(
            s,
            r##"<line x1="{margin}" y1="{y}" x2="{}" y2="{y}" stroke="#ddd"/><text x="{}" y="{}" text-anchor="end">1e{d}</text>"##,
            w - margin,
            margin - 6.0,
            y + 4.0
        );
    }
    let _ = writeln!(
        s,
        r#"<text x="{}" y="{}" text-anchor="middle">wall time [s]</text>"#,
        w / 2.0,
        h - 20.0
    );
    let _ = writeln!(
        s,
        r#"<text x="18" y="{}" text-anchor="middle" transform="rotate(-90 18 {})">L1 error of density</text>"#,
        h / 2.0,
        h / 2.0
    );
    let colors = [
        "#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b",
    ];
    let mut names: Vec<&str> = Vec::new();
    for r in rows {
        if !names.contains(&r.scheme.as_str()) {
            names.push(&r.scheme);
        }
    }
    for (k, name) in names.iter().enumerate() {
        let color = colors[k % colors.len()];
        let pts: Vec<(f64, f64)> = rows
            .iter()
            .filter(|r| r.scheme == *name && finite(r.l1_rho))
            .map(|r| (px(r.wall_s), py(r.l1_rho)))
            .collect();
        let path: Vec<String> = pts.iter().map(|(x, y)| format!("{x:.1},{y:.1}")).collect();
        let _ = writeln!(
            s,
            r#"<polyline points="{}" fill="none" stroke="{color}" stroke-width="2"/>"#,
            path.join(" ")
        );
        for (x, y) in &pts {
            let _ = writeln!(
                s,
                r#"<circle cx="{x:.1}" cy="{y:.1}" r="3.5" fill="{color}"/>"#
            );
        }
        let ly = margin + 16.0 + 18.0 * k as f64;
        let lx = w - margin - 130.0;
        let _ = writeln!(
            s,
            r#"<line x1="{lx}" y1="{ly}" x2="{}" y2="{ly}" stroke="{color}" stroke-width="2"/><text x="{}" y="{}">{name}</text>"#,
            lx + 20.0,
            lx + 26.0,
            ly + 4.0
        );
    }
    s.push_str("</svg>\n");
    s
}
