//! Fluid output files: CSV of cell-centre primitive variables, and VTK image data for ParaView
//! (XML `.vti`, or legacy ASCII). Writers take any `Write` or return bytes; only binaries open
//! files.

use std::io::Write;

use protocol::vtk::{DataArray, ImageData, Values, image_data};

use crate::embedded::{COVERED_TOLERANCE, Loads, SolidFrame};
use crate::fv::FluidState;
use crate::grid::Grid;

/// Writes one CSV row per cell (x fastest) with the columns `x[,y[,z]],rho,u[,v[,w]],p,alpha`
/// (only the active axes; positions of cell centres \[m\], ρ [kg/m³], velocity [m/s], p \[Pa\],
/// `alpha` the fluid volume fraction [-], 1 when `alpha` is `None`).
pub fn write_fluid_csv(
    w: &mut impl Write,
    grid: &Grid,
    state: &FluidState,
    gamma: f64,
    alpha: Option<&[f64]>,
) -> std::io::Result<()> {
    let dim = grid.dim;
    let axes = ["x", "y", "z"];
    let vels = ["u", "v", "w"];
    let mut header: Vec<&str> = axes[..dim].to_vec();
    header.push("rho");
    header.extend_from_slice(&vels[..dim]);
    header.push("p");
    header.push("alpha");
    let mut table = csv::Writer::from_writer(w);
    table.write_record(&header)?;
    for idx in 0..grid.n_cells() {
        if alpha.is_some_and(|a| a[idx] <= 0.0) {
            // Covered by the solid: no fluid (the state there is a ghost).
            continue;
        }
        let x = grid.cell_center(grid.ijk(idx));
        let (rho, vel, p) = state.primitive(idx, gamma);
        for xa in &x[..dim] {
            table.write_field(format!("{xa:.9e}"))?;
        }
        table.write_field(format!("{rho:.12e}"))?;
        for v in &vel[..dim] {
            table.write_field(format!("{v:.12e}"))?;
        }
        let a = alpha.and_then(|a| a.get(idx).copied()).unwrap_or(1.0);
        table.write_record([format!("{p:.12e}"), a.to_string()])?;
    }
    table.flush()
}

/// The fluid as VTK XML image data (`.vti` bytes, compressed binary): cell data `rho`
/// [kg/m³], `p` \[Pa\], `alpha` (fluid fraction [-], 1 when `alpha` is `None`) and the vector
/// `velocity` [m/s] (3 components, inactive axes 0), the arrays of [`write_fluid_vtk`]; and,
/// with `alpha`, VTK's `vtkGhostType` marking the cells the solid covers hidden (32), so that
/// ParaView shows the solid through them without a filter. Inactive axes are flat: a 2-D fluid
/// is an image in the plane z = 0, the 2-D solid's plane.
pub fn fluid_vti(
    grid: &Grid,
    state: &FluidState,
    gamma: f64,
    alpha: Option<&[f64]>,
    title: &str,
) -> Vec<u8> {
    let n = grid.n_cells();
    let mut rho = Vec::with_capacity(n);
    let mut p = Vec::with_capacity(n);
    let mut velocity = Vec::with_capacity(3 * n);
    for idx in 0..n {
        let (r, v, pressure) = state.primitive(idx, gamma);
        rho.push(r);
        p.push(pressure);
        velocity.extend_from_slice(&v);
    }
    // vtkDataSetAttributes::HIDDENCELL: not drawn, not picked, left out by filters.
    const HIDDEN_CELL: u8 = 32;
    let ghost = alpha.map(|a| {
        a.iter()
            .map(|&f| {
                if f <= COVERED_TOLERANCE {
                    HIDDEN_CELL
                } else {
                    0
                }
            })
            .collect()
    });
    let alpha = match alpha {
        Some(a) => a.to_vec(),
        None => vec![1.0; n],
    };
    let flat = |a: usize| a >= grid.dim;
    let mut image = ImageData {
        cells: grid.cells,
        origin: std::array::from_fn(|a| if flat(a) { 0.0 } else { grid.lower[a] }),
        spacing: std::array::from_fn(|a| if flat(a) { 0.0 } else { grid.dx[a] }),
        cell_data: vec![
            DataArray::scalar("rho", Values::Float64(rho)),
            DataArray::scalar("p", Values::Float64(p)),
            DataArray::scalar("alpha", Values::Float64(alpha)),
            DataArray::vector("velocity", velocity),
        ],
    };
    if let Some(ghost) = ghost {
        image
            .cell_data
            .push(DataArray::scalar("vtkGhostType", Values::UInt8(ghost)));
    }
    image_data(&image, title)
}

/// Writes a legacy VTK `STRUCTURED_POINTS` file (ASCII) with cell data `rho`, `p`, `alpha`
/// and the vector `velocity` (3 components, inactive axes 0); inactive axes are one cell thick.
pub fn write_fluid_vtk(
    w: &mut impl Write,
    grid: &Grid,
    state: &FluidState,
    gamma: f64,
    alpha: Option<&[f64]>,
    title: &str,
) -> std::io::Result<()> {
    let n = grid.n_cells();
    let title: String = title.chars().filter(|c| *c != '\n').take(250).collect();
    writeln!(w, "# vtk DataFile Version 3.0")?;
    writeln!(w, "{title}")?;
    writeln!(w, "ASCII")?;
    writeln!(w, "DATASET STRUCTURED_POINTS")?;
    writeln!(
        w,
        "DIMENSIONS {} {} {}",
        grid.cells[0] + 1,
        grid.cells[1] + 1,
        grid.cells[2] + 1
    )?;
    writeln!(
        w,
        "ORIGIN {} {} {}",
        grid.lower[0], grid.lower[1], grid.lower[2]
    )?;
    writeln!(w, "SPACING {} {} {}", grid.dx[0], grid.dx[1], grid.dx[2])?;
    writeln!(w, "CELL_DATA {n}")?;
    let prims: Vec<(f64, [f64; 3], f64)> = (0..n).map(|i| state.primitive(i, gamma)).collect();
    for (name, pick) in [("rho", 0usize), ("p", 2)] {
        writeln!(w, "SCALARS {name} double 1")?;
        writeln!(w, "LOOKUP_TABLE default")?;
        for (rho, _, p) in &prims {
            writeln!(w, "{:.12e}", if pick == 0 { *rho } else { *p })?;
        }
    }
    writeln!(w, "SCALARS alpha double 1")?;
    writeln!(w, "LOOKUP_TABLE default")?;
    for idx in 0..n {
        writeln!(
            w,
            "{}",
            alpha.and_then(|a| a.get(idx).copied()).unwrap_or(1.0)
        )?;
    }
    writeln!(w, "VECTORS velocity double")?;
    for (_, v, _) in &prims {
        writeln!(w, "{:.12e} {:.12e} {:.12e}", v[0], v[1], v[2])?;
    }
    Ok(())
}

/// Writes the wet surface as the fluid used it, one row per element: `element,particle,wet`
/// then the coordinates of its vertices (`x0,y0,x1,y1` in 2-D, three vertices in 3-D) \[m\].
pub fn write_surface_csv(w: &mut impl Write, surface: &SolidFrame) -> std::io::Result<()> {
    let d = surface.dim;
    let axes = ["x", "y", "z"];
    let mut header = vec!["element".to_string(), "particle".into(), "wet".into()];
    for v in 0..d {
        for a in &axes[..d] {
            header.push(format!("{a}{v}"));
        }
    }
    let mut table = csv::Writer::from_writer(w);
    table.write_record(&header)?;
    for (e, nodes) in surface.elements.chunks_exact(d).enumerate() {
        table.write_field(e.to_string())?;
        table.write_field(surface.element_particle[e].to_string())?;
        table.write_field(u8::from(surface.wet[e]).to_string())?;
        for &v in nodes {
            for x in &surface.vertices[v as usize * d..(v as usize + 1) * d] {
                table.write_field(format!("{x:.12e}"))?;
            }
        }
        table.write_record(None::<&[u8]>)?;
    }
    table.flush()
}

/// Writes the fluid loads of the last step per particle: `particle,fx,fy[,fz],m` (2-D, torque
/// about z) or `...,mx,my,mz` (3-D) [N, N m; 2-D per unit depth].
pub fn write_loads_csv(w: &mut impl Write, dim: usize, loads: &Loads) -> std::io::Result<()> {
    let header = if dim == 2 {
        &["particle", "fx", "fy", "m"][..]
    } else {
        &["particle", "fx", "fy", "fz", "mx", "my", "mz"]
    };
    let mut table = csv::Writer::from_writer(w);
    table.write_record(header)?;
    let nr = if dim == 2 { 1 } else { 3 };
    for (p, f) in loads.force.chunks_exact(dim).enumerate() {
        table.write_field(p.to_string())?;
        let moments = &loads.torque[p * nr..(p + 1) * nr];
        table.write_record(f.iter().chain(moments).map(|x| format!("{x:.12e}")))?;
    }
    table.flush()
}

/// Replaces `path` with `bytes` through a temporary file beside it and a rename, so that a
/// reader (or a run killed while writing) sees the old file or the new one, never a part.
pub fn replace_file(path: &std::path::Path, bytes: &[u8]) -> std::io::Result<()> {
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    std::fs::write(&tmp, bytes)?;
    std::fs::rename(&tmp, path)
}

/// Writes `bytes` to `path`: appended when `append`, else into a new (or emptied) file. An error
/// names the file.
pub fn append_or_create(path: &std::path::Path, append: bool, bytes: &[u8]) -> std::io::Result<()> {
    use std::io::Write as _;
    let named =
        |e: std::io::Error| std::io::Error::new(e.kind(), format!("{}: {e}", path.display()));
    let mut file = std::fs::OpenOptions::new()
        .create(true)
        .write(true)
        .append(append)
        .truncate(!append)
        .open(path)
        .map_err(named)?;
    file.write_all(bytes).map_err(named)
}
