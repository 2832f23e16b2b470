//! `fluid-node cut-cells`: computes the cut-cell geometry of a surface file on the grid of a
//! scene, writes Λ, λ and the sub-faces (VTK XML and legacy ASCII, and CSV) and prints one JSON
//! line.
//!
//! ```text
//! fluid-node cut-cells --scene SCENE.toml --surface BODY.stl [--to MOVED.stl] --out DIR
//! ```
//!
//! 3-D surfaces are STL (ASCII or binary); 2-D surfaces are CSV loops (`x,y` per line, one closed
//! loop per body, loops separated by a blank line). With `--to` (the same elements, moved) the
//! swept volumes are computed too, and identity (3) is checked in every cell.
//!
//! Files written in DIR: `solid_fraction.vtk` (cell data), `face_fraction.vtk` (face centres with
//! λ > 0), `subfaces.vtk` (clipped polygons or segments), `cells.csv`, `faces.csv`,
//! `subfaces.csv`, and with `--to` `swept.csv`; `solid_fraction.vti` and `subfaces.vtp` hold the
//! arrays of the first and the third as VTK XML (compressed binary).

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, bail};
use protocol::vtk::{DataArray, ImageData, PolyCells, PolyData, Values, image_data, poly_data};

use crate::cutcell::stl::{SurfaceMesh, parse_loops_csv, parse_stl};
use crate::cutcell::{CutGeometry, SweptVolumes, compute, face_index, n_faces, swept_volumes};
use crate::grid::Grid;

/// Arguments of `fluid-node cut-cells`.
#[derive(Clone, Debug, clap::Args)]
pub struct CutCellsArgs {
    /// Scene file; the grid is read from `[fluid]` (`lower`, `upper`, `cells`).
    #[arg(long, value_name = "SCENE.toml")]
    pub scene: PathBuf,
    /// Surface at t^n: STL (3-D) or CSV loops `x,y` (2-D), normals out of the solid.
    #[arg(long, value_name = "BODY.stl")]
    pub surface: PathBuf,
    /// The same surface moved (same elements in the same order): adds swept volumes.
    #[arg(long, value_name = "MOVED.stl")]
    pub to: Option<PathBuf>,
    /// Output directory (created if missing).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
}

/// Runs the command: reads, computes, writes, prints one JSON line to stdout.
pub fn run(args: &CutCellsArgs) -> anyhow::Result<()> {
    let line = run_to_json(args)?;
    let mut stdout = std::io::stdout().lock();
    writeln!(stdout, "{line}").context("writing to stdout")?;
    Ok(())
}

/// [`run`] without printing: returns the JSON line.
pub fn run_to_json(args: &CutCellsArgs) -> anyhow::Result<String> {
    let scene_text = std::fs::read_to_string(&args.scene)
        .with_context(|| format!("reading scene {}", args.scene.display()))?;
    let scene =
        protocol::scene::Scene::from_toml_str(&scene_text, &args.scene.display().to_string())
            .with_context(|| format!("parsing scene {}", args.scene.display()))?;
    let fluid = scene
        .fluid
        .as_ref()
        .with_context(|| format!("scene {} has no [fluid] section", args.scene.display()))?;
    let cells: Vec<usize> = fluid.cells.iter().map(|&n| n as usize).collect();
    let grid = Grid::new(&fluid.lower, &fluid.upper, &cells)
        .map_err(|err| anyhow::anyhow!("grid of scene {}: {err}", args.scene.display()))?;
    if grid.dim < 2 {
        bail!(
            "cut cells need a 2-D or 3-D grid, the scene has {} axis",
            grid.dim
        );
    }
    let before = read_surface(&args.surface, grid.dim)?;
    let after = match &args.to {
        Some(path) => {
            let after = read_surface(path, grid.dim)?;
            if after.elements != before.elements {
                bail!(
                    "{} and {} do not have the same elements ({} and {})",
                    args.surface.display(),
                    path.display(),
                    before.n_elements(),
                    after.n_elements()
                );
            }
            Some(after)
        }
        None => None,
    };
    if before.enclosed_volume() < 0.0 {
        tracing::warn!(
            "cut-cells: {} encloses a negative volume; its normals may point into the solid",
            args.surface.display()
        );
    }

    let start = Instant::now();
    let mut geometry = CutGeometry::new();
    compute(&grid, &before.surface(), &mut geometry);
    let moved = after.as_ref().map(|after| {
        let mut geometry_to = CutGeometry::new();
        compute(&grid, &after.surface(), &mut geometry_to);
        let mut swept = SweptVolumes::new();
        swept_volumes(&grid, &before.surface(), &after.surface(), &mut swept);
        (geometry_to, swept)
    });
    let compute_s = start.elapsed().as_secs_f64();

    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating output directory {}", args.out.display()))?;
    let mut per_cell_swept = Vec::new();
    let mut max_cell_residual = 0.0f64;
    if let Some((geometry_to, swept)) = &moved {
        per_cell_swept = vec![0.0; grid.n_cells()];
        swept.accumulate(&mut per_cell_swept);
        let volume = grid.cell_volume();
        let fractions = geometry_to
            .solid_fraction
            .iter()
            .zip(&geometry.solid_fraction);
        for (swept, (to, from)) in per_cell_swept.iter().zip(fractions) {
            let change = (to - from) * volume;
            max_cell_residual = max_cell_residual.max((swept - change).abs() / volume);
        }
    }
    write_outputs(
        &args.out,
        &grid,
        &before,
        &geometry,
        moved.as_ref(),
        &per_cell_swept,
    )?;

    let (solid_volume_to, swept_volume, max_cell_residual) = match &moved {
        Some((geometry_to, swept)) => (
            Some(geometry_to.solid_volume(&grid)),
            Some(swept.total()),
            Some(max_cell_residual),
        ),
        None => (None, None, None),
    };
    let line = CutCellsLine {
        dim: grid.dim,
        cells: grid.n_cells(),
        elements: before.n_elements(),
        solid_volume: geometry.solid_volume(&grid),
        wet_area: geometry.wet_area(),
        cut_cells: geometry.cut_cells.len(),
        compute_s,
        skipped_elements: geometry.diagnostics.n_skipped_elements,
        open_surface_defect: geometry.diagnostics.max_uncut_defect,
        solid_volume_to,
        swept_volume,
        max_cell_residual,
        out: args.out.display().to_string(),
    };
    // NOTE: serde_json escapes every string (a tab or quote in a path stays valid JSON) and
    // writes a non-finite number as null.
    serde_json::to_string(&line).context("serializing the JSON line")
}

/// The JSON line `cut-cells` prints (keys in this order; the `*_to`, swept and residual keys
/// only with `--to`).
#[derive(serde::Serialize)]
struct CutCellsLine {
    dim: usize,
    cells: usize,
    elements: usize,
    solid_volume: f64,
    wet_area: f64,
    cut_cells: usize,
    compute_s: f64,
    skipped_elements: usize,
    open_surface_defect: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    solid_volume_to: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    swept_volume: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    max_cell_residual: Option<f64>,
    out: String,
}

fn read_surface(path: &Path, dim: usize) -> anyhow::Result<SurfaceMesh> {
    let bytes =
        std::fs::read(path).with_context(|| format!("reading surface {}", path.display()))?;
    let mesh = if dim == 3 {
        parse_stl(&bytes)
    } else {
        let text = std::str::from_utf8(&bytes)
            .map_err(|_| anyhow::anyhow!("surface {} is not UTF-8 text", path.display()))?;
        parse_loops_csv(text)
    };
    mesh.with_context(|| format!("parsing surface {}", path.display()))
}

fn create(dir: &Path, name: &str) -> anyhow::Result<std::io::BufWriter<std::fs::File>> {
    let path = dir.join(name);
    let file =
        std::fs::File::create(&path).with_context(|| format!("creating {}", path.display()))?;
    Ok(std::io::BufWriter::new(file))
}

/// Writes every output of the command into `dir`: the cells, the faces with λ > 0 and the
/// sub-faces as legacy VTK and CSV, the same as VTK XML for ParaView, and (with `moved`) the
/// swept volumes.
fn write_outputs(
    dir: &Path,
    grid: &Grid,
    mesh: &SurfaceMesh,
    geometry: &CutGeometry,
    moved: Option<&(CutGeometry, SweptVolumes)>,
    per_cell_swept: &[f64],
) -> anyhow::Result<()> {
    let mut scalars = vec![("solid_fraction", &geometry.solid_fraction[..])];
    if let Some((geometry_to, _)) = moved {
        scalars.push(("solid_fraction_to", &geometry_to.solid_fraction[..]));
        scalars.push(("swept_volume", per_cell_swept));
    }
    write_cells(dir, grid, &scalars)?;
    write_faces(dir, grid, geometry)?;
    write_subfaces(dir, grid, geometry)?;
    write_xml(dir, grid, geometry, &scalars)?;
    if let Some((_, swept)) = moved {
        write_swept(dir, grid, mesh, swept)?;
    }
    Ok(())
}

/// The error of a failed write into `dir`.
fn io_error(dir: &Path) -> impl Fn(std::io::Error) -> anyhow::Error + Copy + '_ {
    move |err| anyhow::anyhow!("writing outputs in {}: {err}", dir.display())
}

/// Per-cell values by name (Λ, and with a motion Λ after it and the swept volume).
type Scalars<'a> = [(&'a str, &'a [f64])];

/// Cells: VTK structured points with cell data, and a CSV of the non-empty cells.
fn write_cells(dir: &Path, grid: &Grid, scalars: &Scalars<'_>) -> anyhow::Result<()> {
    let io = io_error(dir);
    let mut w = create(dir, "solid_fraction.vtk")?;
    let dims: Vec<usize> = (0..3)
        .map(|a| if a < grid.dim { grid.cells[a] + 1 } else { 1 })
        .collect();
    let spacing: Vec<f64> = (0..3)
        .map(|a| if a < grid.dim { grid.dx[a] } else { 0.0 })
        .collect();
    writeln!(
        w,
        "# vtk DataFile Version 3.0\ncut-cell solid fraction\nASCII\nDATASET STRUCTURED_POINTS"
    )
    .map_err(io)?;
    writeln!(w, "DIMENSIONS {} {} {}", dims[0], dims[1], dims[2]).map_err(io)?;
    writeln!(
        w,
        "ORIGIN {} {} {}",
        grid.lower[0],
        grid.lower[1],
        if grid.dim == 3 { grid.lower[2] } else { 0.0 }
    )
    .map_err(io)?;
    writeln!(w, "SPACING {} {} {}", spacing[0], spacing[1], spacing[2]).map_err(io)?;
    writeln!(w, "CELL_DATA {}", grid.n_cells()).map_err(io)?;
    for (name, values) in scalars {
        writeln!(w, "SCALARS {name} double 1\nLOOKUP_TABLE default").map_err(io)?;
        for v in values.iter() {
            writeln!(w, "{v}").map_err(io)?;
        }
    }
    w.flush().map_err(io)?;

    let mut w = create(dir, "cells.csv")?;
    let header = scalars
        .iter()
        .map(|(n, _)| *n)
        .collect::<Vec<_>>()
        .join(",");
    writeln!(w, "cell,i,j,k,{header}").map_err(io)?;
    for c in 0..grid.n_cells() {
        if scalars.iter().all(|(_, v)| v[c] == 0.0) {
            continue;
        }
        let [i, j, k] = grid.ijk(c);
        write!(w, "{c},{i},{j},{k}").map_err(io)?;
        for (_, v) in scalars {
            write!(w, ",{}", v[c]).map_err(io)?;
        }
        writeln!(w).map_err(io)?;
    }
    w.flush().map_err(io)?;
    Ok(())
}

/// Faces with λ > 0: CSV and VTK points at the face centres.
fn write_faces(dir: &Path, grid: &Grid, geometry: &CutGeometry) -> anyhow::Result<()> {
    let io = io_error(dir);
    let mut faces = Vec::new();
    for axis in 0..grid.dim {
        let mut n = grid.cells;
        n[axis] += 1;
        for f in 0..n_faces(grid, axis) {
            let lambda = geometry.face_fraction[axis][f];
            if lambda == 0.0 {
                continue;
            }
            let ijk = [f % n[0], (f / n[0]) % n[1], f / (n[0] * n[1])];
            debug_assert_eq!(face_index(grid, axis, ijk), f);
            let mut x = [0.0; 3];
            for a in 0..grid.dim {
                let offset = if a == axis { 0.0 } else { 0.5 };
                x[a] = grid.lower[a] + (ijk[a] as f64 + offset) * grid.dx[a];
            }
            faces.push((axis, ijk, x, lambda));
        }
    }
    let mut w = create(dir, "faces.csv")?;
    writeln!(w, "axis,i,j,k,x,y,z,face_fraction").map_err(io)?;
    for (axis, ijk, x, lambda) in &faces {
        writeln!(
            w,
            "{axis},{},{},{},{},{},{},{lambda}",
            ijk[0], ijk[1], ijk[2], x[0], x[1], x[2]
        )
        .map_err(io)?;
    }
    w.flush().map_err(io)?;
    let mut w = create(dir, "face_fraction.vtk")?;
    writeln!(w, "# vtk DataFile Version 3.0\ncut-cell face fractions (face centres)\nASCII\nDATASET POLYDATA")
        .map_err(io)?;
    writeln!(w, "POINTS {} double", faces.len()).map_err(io)?;
    for (_, _, x, _) in &faces {
        writeln!(w, "{} {} {}", x[0], x[1], x[2]).map_err(io)?;
    }
    writeln!(w, "VERTICES {} {}", faces.len(), 2 * faces.len()).map_err(io)?;
    for p in 0..faces.len() {
        writeln!(w, "1 {p}").map_err(io)?;
    }
    writeln!(
        w,
        "POINT_DATA {}\nSCALARS face_fraction double 1\nLOOKUP_TABLE default",
        faces.len()
    )
    .map_err(io)?;
    for (_, _, _, lambda) in &faces {
        writeln!(w, "{lambda}").map_err(io)?;
    }
    writeln!(w, "SCALARS axis int 1\nLOOKUP_TABLE default").map_err(io)?;
    for (axis, _, _, _) in &faces {
        writeln!(w, "{axis}").map_err(io)?;
    }
    w.flush().map_err(io)?;
    Ok(())
}

/// Sub-faces: CSV and VTK polygons (3-D) or lines (2-D).
fn write_subfaces(dir: &Path, grid: &Grid, geometry: &CutGeometry) -> anyhow::Result<()> {
    let io = io_error(dir);
    let mut w = create(dir, "subfaces.csv")?;
    writeln!(w, "cell,i,j,k,element,particle,area,nx,ny,nz,cx,cy,cz").map_err(io)?;
    for s in &geometry.subfaces {
        let [i, j, k] = grid.ijk(s.cell as usize);
        writeln!(
            w,
            "{},{i},{j},{k},{},{},{},{},{},{},{},{},{}",
            s.cell,
            s.element,
            s.particle,
            s.area,
            s.normal[0],
            s.normal[1],
            s.normal[2],
            s.centroid[0],
            s.centroid[1],
            s.centroid[2]
        )
        .map_err(io)?;
    }
    w.flush().map_err(io)?;
    let mut w = create(dir, "subfaces.vtk")?;
    writeln!(
        w,
        "# vtk DataFile Version 3.0\ncut-cell sub-faces\nASCII\nDATASET POLYDATA"
    )
    .map_err(io)?;
    writeln!(w, "POINTS {} double", geometry.subface_vertices.len()).map_err(io)?;
    for x in &geometry.subface_vertices {
        writeln!(w, "{} {} {}", x[0], x[1], x[2]).map_err(io)?;
    }
    let n = geometry.subfaces.len();
    let size: usize = geometry
        .subfaces
        .iter()
        .map(|s| s.n_vertices as usize + 1)
        .sum();
    writeln!(
        w,
        "{} {n} {size}",
        if grid.dim == 3 { "POLYGONS" } else { "LINES" }
    )
    .map_err(io)?;
    for s in &geometry.subfaces {
        write!(w, "{}", s.n_vertices).map_err(io)?;
        for v in s.first_vertex..s.first_vertex + s.n_vertices {
            write!(w, " {v}").map_err(io)?;
        }
        writeln!(w).map_err(io)?;
    }
    writeln!(
        w,
        "CELL_DATA {n}\nSCALARS area double 1\nLOOKUP_TABLE default"
    )
    .map_err(io)?;
    for s in &geometry.subfaces {
        writeln!(w, "{}", s.area).map_err(io)?;
    }
    writeln!(w, "SCALARS cell int 1\nLOOKUP_TABLE default").map_err(io)?;
    for s in &geometry.subfaces {
        writeln!(w, "{}", s.cell).map_err(io)?;
    }
    writeln!(w, "SCALARS particle int 1\nLOOKUP_TABLE default").map_err(io)?;
    for s in &geometry.subfaces {
        writeln!(w, "{}", s.particle).map_err(io)?;
    }
    writeln!(w, "NORMALS normal double").map_err(io)?;
    for s in &geometry.subfaces {
        writeln!(w, "{} {} {}", s.normal[0], s.normal[1], s.normal[2]).map_err(io)?;
    }
    w.flush().map_err(io)?;
    Ok(())
}

/// The same cell data and sub-faces as VTK XML (compressed binary) for ParaView.
fn write_xml(
    dir: &Path,
    grid: &Grid,
    geometry: &CutGeometry,
    scalars: &Scalars<'_>,
) -> anyhow::Result<()> {
    let io = io_error(dir);
    let image = ImageData {
        cells: grid.cells,
        origin: grid.lower,
        spacing: grid.dx,
        cell_data: scalars
            .iter()
            .map(|(name, values)| DataArray::scalar(name, Values::Float64(values.to_vec())))
            .collect(),
    };
    std::fs::write(
        dir.join("solid_fraction.vti"),
        image_data(&image, "cut-cell solid fraction"),
    )
    .map_err(io)?;
    let subfaces = &geometry.subfaces;
    let mut connectivity = Vec::new();
    let mut offsets = Vec::with_capacity(subfaces.len());
    for s in subfaces {
        connectivity.extend((s.first_vertex..s.first_vertex + s.n_vertices).map(i64::from));
        offsets.push(connectivity.len() as i64);
    }
    let poly = PolyData {
        points: geometry
            .subface_vertices
            .iter()
            .flatten()
            .copied()
            .collect(),
        kind: PolyCells::surface(grid.dim),
        connectivity,
        offsets,
        point_data: Vec::new(),
        cell_data: vec![
            DataArray::scalar(
                "area",
                Values::Float64(subfaces.iter().map(|s| s.area).collect()),
            ),
            DataArray::scalar(
                "cell",
                Values::Int64(subfaces.iter().map(|s| i64::from(s.cell)).collect()),
            ),
            DataArray::scalar(
                "particle",
                Values::Int64(subfaces.iter().map(|s| i64::from(s.particle)).collect()),
            ),
            DataArray::vector("normal", subfaces.iter().flat_map(|s| s.normal).collect()),
        ],
    };
    std::fs::write(
        dir.join("subfaces.vtp"),
        poly_data(&poly, "cut-cell sub-faces"),
    )
    .map_err(io)?;
    Ok(())
}

/// The swept volume of each element in each cell it crosses (CSV).
fn write_swept(
    dir: &Path,
    grid: &Grid,
    mesh: &SurfaceMesh,
    swept: &SweptVolumes,
) -> anyhow::Result<()> {
    let io = io_error(dir);
    let mut w = create(dir, "swept.csv")?;
    writeln!(w, "element,particle,cell,i,j,k,volume").map_err(io)?;
    for e in &swept.entries {
        let [i, j, k] = grid.ijk(e.cell as usize);
        let particle = mesh
            .element_particle
            .get(e.element as usize)
            .copied()
            .unwrap_or(0);
        writeln!(
            w,
            "{},{particle},{},{i},{j},{k},{}",
            e.element, e.cell, e.volume
        )
        .map_err(io)?;
    }
    w.flush().map_err(io)?;
    Ok(())
}
