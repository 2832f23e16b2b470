//! Fluid output files: CSV of cell-centre primitive variables, and VTK image data for ParaView
//! (XML `.vti`, or legacy ASCII). Writers take any `Write` or return bytes; only binaries open
//! files.

mod sci;

use std::io::Write;

use rayon::prelude::*;

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
    let mut table = csv::Writer::from_writer(&mut *w);
    table.write_record(&header)?;
    table.flush()?;
    drop(table);
    write_fluid_csv_rows(w, grid, state, gamma, alpha, RUN_CELLS, CSV_BATCH_RUNS)
}

/// The rows of [`write_fluid_csv`], formatted in runs of `run_rows` cells, `batch_runs` runs at
/// a time.
fn write_fluid_csv_rows(
    w: &mut impl Write,
    grid: &Grid,
    state: &FluidState,
    gamma: f64,
    alpha: Option<&[f64]>,
    run_rows: usize,
    batch_runs: usize,
) -> std::io::Result<()> {
    // NOTE: the rows are formatted in runs of `RUN_CELLS` cells, in parallel on the rayon pool
    // the caller runs this on (the node: the fluid's own), a batch of runs at a time, and written
    // in cell order: the same bytes as one writer over every row. Formatting is most of a large output's time (a 64³ blast's final output took a quarter
    // of its whole run on one thread).
    let n = grid.n_cells();
    let batch = run_rows * batch_runs;
    let coords = CoordinateTexts::new(grid);
    for start in (0..n).step_by(batch) {
        let runs: Vec<usize> = (start..n.min(start + batch)).step_by(run_rows).collect();
        let rows = |&lo: &usize| {
            fluid_csv_rows(grid, state, gamma, alpha, &coords, lo..n.min(lo + run_rows))
        };
        let parts: Vec<Vec<u8>> = runs.par_iter().map(rows).collect();
        for part in parts {
            w.write_all(&part)?;
        }
    }
    w.flush()
}

/// Cells a parallel task of the writers takes: a run of CSV rows ([`write_fluid_csv`]) or of
/// primitives ([`fluid_vti`]).
const RUN_CELLS: usize = 4096;

/// Runs formatted before they are written (bounds the memory: about 130 bytes a 3-D row).
const CSV_BATCH_RUNS: usize = 32;

/// The text of the cell centres' coordinates along each axis (`{:.9e}`), formatted once a file:
/// a centre's coordinate along an axis depends on its index along that axis alone.
struct CoordinateTexts {
    /// For each active axis, the text of every index's coordinate, one after another.
    text: Vec<Vec<u8>>,
    /// For each active axis, where each index's text starts in `text` (and the end, last).
    starts: Vec<Vec<usize>>,
}

impl CoordinateTexts {
    fn new(grid: &Grid) -> Self {
        let (mut text, mut starts) = (Vec::new(), Vec::new());
        for axis in 0..grid.dim {
            let (mut t, mut s) = (Vec::new(), vec![0]);
            for i in 0..grid.cells[axis] {
                let mut ijk = [0; 3];
                ijk[axis] = i;
                let x = grid.cell_center(ijk)[axis];
                write!(t, "{x:.9e}").expect("writing to a Vec does not fail");
                s.push(t.len());
            }
            text.push(t);
            starts.push(s);
        }
        CoordinateTexts { text, starts }
    }

    /// The text of index `i`'s coordinate along `axis`.
    fn get(&self, axis: usize, i: usize) -> &[u8] {
        &self.text[axis][self.starts[axis][i]..self.starts[axis][i + 1]]
    }
}

/// The last value written in one column and its text, reused while the column repeats it
/// (a uniform region: most of the cells of a scene's first output).
struct LastField {
    bits: u64,
    text: [u8; 32],
    len: usize,
}

impl LastField {
    fn new() -> Self {
        LastField {
            bits: u64::MAX,
            text: [0; 32],
            len: 0,
        }
    }

    /// Appends `v`'s text with `format` (the bytes of `format!("{v:.12e}")` or of `{v}`) to
    /// `out`, from the last text when `v` has the last value's bits.
    fn push(&mut self, out: &mut Vec<u8>, v: f64, format: impl Fn(&mut Vec<u8>, f64)) {
        if self.len > 0 && v.to_bits() == self.bits {
            out.extend_from_slice(&self.text[..self.len]);
            return;
        }
        let start = out.len();
        format(out, v);
        let text = &out[start..];
        if text.len() <= self.text.len() {
            self.text[..text.len()].copy_from_slice(text);
            (self.bits, self.len) = (v.to_bits(), text.len());
        }
    }
}

/// The CSV rows of the cells `cells` ([`write_fluid_csv`]'s columns, no header).
///
/// NOTE: written as bytes, not through a `csv` writer: every field is a number's text (digits,
/// `.`, `e`, `-`, `inf`, `NaN`), which a `csv` writer never quotes, with its `,` and `\n`; so
/// the bytes are the writer's (test `rows_formatted_in_runs_on_any_pool_are_the_bytes_of_one_writer`
/// against a `csv` writer of `format!` fields).
fn fluid_csv_rows(
    grid: &Grid,
    state: &FluidState,
    gamma: f64,
    alpha: Option<&[f64]>,
    coords: &CoordinateTexts,
    cells: std::ops::Range<usize>,
) -> Vec<u8> {
    let dim = grid.dim;
    let mut out = Vec::with_capacity(cells.len() * 20 * (2 * dim + 3));
    let sci = |out: &mut Vec<u8>, v: f64| sci::push_sci(out, v, 12);
    let display = |out: &mut Vec<u8>, v: f64| {
        write!(out, "{v}").expect("writing to a Vec does not fail");
    };
    // The columns ρ, the velocity's, p and α.
    let mut last: [LastField; 6] = std::array::from_fn(|_| LastField::new());
    for idx in cells {
        if alpha.is_some_and(|a| a[idx] <= 0.0) {
            // Covered by the solid: no fluid (the state there is a ghost).
            continue;
        }
        let ijk = grid.ijk(idx);
        for (axis, &i) in ijk[..dim].iter().enumerate() {
            out.extend_from_slice(coords.get(axis, i));
            out.push(b',');
        }
        let (rho, vel, p) = state.primitive(idx, gamma);
        last[0].push(&mut out, rho, sci);
        out.push(b',');
        for (a, &v) in vel[..dim].iter().enumerate() {
            last[1 + a].push(&mut out, v, sci);
            out.push(b',');
        }
        last[4].push(&mut out, p, sci);
        out.push(b',');
        let a = alpha.and_then(|a| a.get(idx).copied()).unwrap_or(1.0);
        last[5].push(&mut out, a, display);
        out.push(b'\n');
    }
    out
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
    let (mut rho, mut p, mut velocity) = (vec![0.0; n], vec![0.0; n], vec![0.0; 3 * n]);
    // In runs of cells, on the caller's rayon pool as the CSV rows (each cell's values are its own).
    let run = |k: usize, rho: &mut [f64], p: &mut [f64], velocity: &mut [f64]| {
        let first = k * RUN_CELLS;
        for (i, (r, pressure)) in rho.iter_mut().zip(p.iter_mut()).enumerate() {
            let (ri, v, pi) = state.primitive(first + i, gamma);
            (*r, *pressure) = (ri, pi);
            velocity[3 * i..3 * i + 3].copy_from_slice(&v);
        }
    };
    (rho.par_chunks_mut(RUN_CELLS))
        .zip(p.par_chunks_mut(RUN_CELLS))
        .zip(velocity.par_chunks_mut(3 * RUN_CELLS))
        .enumerate()
        .for_each(|(k, ((rho, p), velocity))| run(k, rho, p, velocity));
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
/// `particle` is the solid's number: `ids[p]` for the frame's particle `p` (`ids` empty: `p`).
pub fn write_surface_csv(
    w: &mut impl Write,
    surface: &SolidFrame,
    ids: &[u32],
) -> std::io::Result<()> {
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
        table.write_field(particle_id(ids, surface.element_particle[e] as usize).to_string())?;
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

/// The solid's number of the frame's particle `p` (see [`write_surface_csv`]).
fn particle_id(ids: &[u32], p: usize) -> u32 {
    ids.get(p).copied().unwrap_or(p as u32)
}

/// Writes the fluid loads of the last step per particle: `particle,fx,fy[,fz],m` (2-D, torque
/// about z) or `...,mx,my,mz` (3-D) [N, N m; 2-D per unit depth], for the particles the fluid
/// was sent (those the surface's elements belong to), by the solid's numbers (`ids` as in
/// [`write_surface_csv`]).
pub fn write_loads_csv(
    w: &mut impl Write,
    dim: usize,
    loads: &Loads,
    ids: &[u32],
) -> std::io::Result<()> {
    let header = if dim == 2 {
        &["particle", "fx", "fy", "m"][..]
    } else {
        &["particle", "fx", "fy", "fz", "mx", "my", "mz"]
    };
    let mut table = csv::Writer::from_writer(w);
    table.write_record(header)?;
    let nr = if dim == 2 { 1 } else { 3 };
    for (p, f) in loads.force.chunks_exact(dim).enumerate() {
        table.write_field(particle_id(ids, p).to_string())?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fv::FluidSolver;
    use protocol::scene::Scene;

    /// A box of `cells` (0.1 m cells) with a ball of dense gas moving (every column differs from
    /// cell to cell near the ball), and a fluid fraction with covered cells (left out) and
    /// partial ones.
    fn ball(cells: [usize; 3]) -> (FluidSolver, Vec<f64>) {
        let upper = cells.map(|n| n as f64 * 0.1);
        let text = format!(
            r#"
            name = "rows"
            [run]
            t_end = 1.0
            [fluid]
            lower = [0.0, 0.0, 0.0]
            upper = {upper:?}
            cells = {cells:?}
            boundary = {{ x = ["wall", "wall"], y = ["wall", "wall"], z = ["wall", "wall"] }}
            [[fluid.init]]
            region = "all"
            rho = 1.4
            p = 1.0
            [[fluid.init]]
            region = {{ ball = {{ center = [0.6, 0.5, 0.3], radius = 0.3 }} }}
            rho = 8.0
            p = 116.5
            velocity = [1.5, -0.25, 1e-7]
        "#
        );
        let scene = Scene::from_toml_str(&text, "test").expect("valid scene");
        let s = FluidSolver::from_scene(scene.fluid.as_ref().expect("fluid"), 1).expect("solver");
        let n = s.grid().n_cells();
        let alpha = (0..n)
            .map(|i| match i % 4 {
                0 => 0.0,
                1 => 1.0,
                _ => (i as f64 + 0.5) / n as f64,
            })
            .collect();
        (s, alpha)
    }

    /// The rows as one `csv` writer wrote them before the runs: a `format!` a field, in cell
    /// order.
    fn one_writer(s: &FluidSolver, alpha: Option<&[f64]>) -> Vec<u8> {
        let (grid, dim) = (s.grid(), s.grid().dim);
        let mut table = csv::WriterBuilder::new()
            .has_headers(false)
            .from_writer(Vec::new());
        for idx in 0..grid.n_cells() {
            if alpha.is_some_and(|a| a[idx] <= 0.0) {
                continue;
            }
            let x = grid.cell_center(grid.ijk(idx));
            let (rho, vel, p) = s.state().primitive(idx, 1.4);
            for xa in &x[..dim] {
                table.write_field(format!("{xa:.9e}")).expect("field");
            }
            table.write_field(format!("{rho:.12e}")).expect("field");
            for v in &vel[..dim] {
                table.write_field(format!("{v:.12e}")).expect("field");
            }
            let a = alpha.map_or(1.0, |a| a[idx]);
            (table.write_record([format!("{p:.12e}"), a.to_string()])).expect("record");
        }
        table.into_inner().expect("in memory")
    }

    #[test]
    fn rows_formatted_in_runs_on_any_pool_are_the_bytes_of_one_writer() {
        let (s, alpha) = ball([13, 11, 7]);
        for alpha in [None, Some(&alpha[..])] {
            let expected = one_writer(&s, alpha);
            assert!(expected.len() > 40_000, "{} bytes", expected.len());
            let (grid, state) = (s.grid(), s.state());
            let rows = |run: usize, batch: usize| {
                let mut out = Vec::new();
                write_fluid_csv_rows(&mut out, grid, state, 1.4, alpha, run, batch)
                    .expect("in memory");
                out
            };
            // Runs of 7 cells, 3 to a batch (1001 cells: 48 batches, the last one run of 0 and
            // a partial one), one run of everything, and the node's sizes.
            for (run, batch) in [(7, 3), (1001, 1), (RUN_CELLS, CSV_BATCH_RUNS)] {
                assert!(
                    rows(run, batch) == expected,
                    "on the global pool, runs of {run}"
                );
                for threads in [1, 2, 5] {
                    let pool = rayon::ThreadPoolBuilder::new()
                        .num_threads(threads)
                        .build()
                        .expect("pool");
                    let on_pool = pool.install(|| rows(run, batch));
                    assert!(on_pool == expected, "{threads} threads, runs of {run}");
                }
            }
        }
    }

    #[test]
    fn vti_bytes_on_any_pool_are_those_of_one_thread() {
        // 24 000 cells: six runs of primitives, six zlib blocks of ρ, eighteen of the velocity.
        let (s, alpha) = ball([40, 30, 20]);
        let (grid, state) = (s.grid(), s.state());
        let alone = fluid_vti(grid, state, 1.4, Some(&alpha), "rows");
        for threads in [1, 2, 5] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("pool");
            let on_pool = pool.install(|| fluid_vti(grid, state, 1.4, Some(&alpha), "rows"));
            assert!(on_pool == alone, "{threads} threads");
        }
    }
}
