//! Fluid output files: CSV of cell-centre primitive variables and legacy VTK image data for
//! ParaView. Writers take any `Write`; only binaries open files.

use std::io::Write;

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
    writeln!(w, "{}", header.join(","))?;
    for idx in 0..grid.n_cells() {
        let x = grid.cell_center(grid.ijk(idx));
        let (rho, vel, p) = state.primitive(idx, gamma);
        let mut line = String::with_capacity(128);
        for xa in &x[..dim] {
            line.push_str(&format!("{xa:.9e},"));
        }
        line.push_str(&format!("{rho:.12e},"));
        for v in &vel[..dim] {
            line.push_str(&format!("{v:.12e},"));
        }
        let a = alpha.and_then(|a| a.get(idx).copied()).unwrap_or(1.0);
        line.push_str(&format!("{p:.12e},{a}"));
        writeln!(w, "{line}")?;
    }
    Ok(())
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
