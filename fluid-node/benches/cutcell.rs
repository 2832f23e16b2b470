//! Cut-cell geometry of a polyhedral sphere as the grid is refined: the cost must follow the
//! number of cut cells (∝ N^(2/3) for N cells), not the grid.
//!
//! `cargo bench -p fluid-node --no-default-features --bench cutcell` runs the criterion groups
//! (`compute` and `swept`, throughput in pieces = (triangle, cell) pairs) and then prints a
//! summary table with the fitted exponent of time against N and the (triangle, cell) pairs per
//! second. `CUTCELL_BENCH_MAX=128` caps the finest grid (default 256).
//!
//! On a shared machine wall times are noisy; count instructions instead (STYLE §8): with
//! `CUTCELL_BENCH_ONLY=N` the binary skips criterion, warms the buffers up on an N³ grid and then
//! calls `measured_compute` and `measured_swept` once each:
//!
//! ```text
//! CUTCELL_BENCH_ONLY=64 valgrind --tool=callgrind --collect-atstart=no \
//!     --toggle-collect='*measured_compute*' target/release/deps/cutcell-HASH
//! ```

use std::hint::black_box;
use std::time::Instant;

// The test meshes (the bench uses the same sphere as the tests).
#[path = "../tests/it/cutcell_support/mod.rs"]
mod cutcell_support;

use criterion::{BenchmarkId, Criterion, Throughput};
use fluid_node::cutcell::{CutGeometry, Surface, SweptVolumes, compute, swept_volumes};
use fluid_node::grid::Grid;

fn resolutions() -> Vec<usize> {
    let max: usize = std::env::var("CUTCELL_BENCH_MAX")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(256);
    [32, 64, 128, 256]
        .into_iter()
        .filter(|&n| n <= max)
        .collect()
}

/// Best wall time of `reps` calls [s].
fn best_time(reps: usize, mut f: impl FnMut()) -> f64 {
    let mut best = f64::INFINITY;
    for _ in 0..reps {
        let t = Instant::now();
        f();
        best = best.min(t.elapsed().as_secs_f64());
    }
    best
}

#[inline(never)]
fn measured_compute(grid: &Grid, surface: &Surface, geometry: &mut CutGeometry) {
    compute(grid, black_box(surface), geometry);
}

#[inline(never)]
fn measured_swept(grid: &Grid, before: &Surface, after: &Surface, swept: &mut SweptVolumes) {
    swept_volumes(grid, black_box(before), after, swept);
}

/// The sphere (and the same sphere moved by a fraction of a cell) benchmarked on an `n³` grid.
///
/// NOTE: by default the mesh is refined with the grid (`n/2 × n` bands and sectors, edges of about
/// two cells), so the pieces, like the cut cells, grow as N^(2/3); `CUTCELL_BENCH_MESH=fixed` keeps
/// one 7080-triangle mesh, where the pieces approach that law only once cells are smaller than
/// triangles. The centre is off the grid planes.
fn sphere_for(n: usize) -> (Vec<f64>, Vec<f64>, Vec<u32>) {
    let fixed = std::env::var("CUTCELL_BENCH_MESH").is_ok_and(|m| m == "fixed");
    let (n_lat, n_lon) = if fixed { (60, 60) } else { (n / 2, n) };
    let cutcell_support::Mesh {
        vertices, elements, ..
    } = cutcell_support::sphere_mesh([0.5013, 0.4987, 0.5021], 0.3, n_lat, n_lon);
    let shift = [0.11, -0.07, 0.09].map(|d| d / n as f64);
    let moved = vertices
        .iter()
        .enumerate()
        .map(|(i, x)| x + shift[i % 3])
        .collect();
    (vertices, moved, elements)
}

fn surface<'a>(vertices: &'a [f64], elements: &'a [u32]) -> Surface<'a> {
    Surface {
        dim: 3,
        vertices,
        elements,
        element_particle: &[],
    }
}

fn main() {
    if let Some(n) = std::env::var("CUTCELL_BENCH_ONLY")
        .ok()
        .and_then(|s| s.parse::<usize>().ok())
    {
        let (vertices, moved, elements) = sphere_for(n);
        let (before, after) = (surface(&vertices, &elements), surface(&moved, &elements));
        let grid = Grid::new(&[0.0; 3], &[1.0; 3], &[n; 3]).unwrap();
        let mut geometry = CutGeometry::new();
        let mut swept = SweptVolumes::new();
        compute(&grid, &before, &mut geometry);
        swept_volumes(&grid, &before, &after, &mut swept);
        measured_compute(&grid, &before, &mut geometry);
        measured_swept(&grid, &before, &after, &mut swept);
        println!(
            "n {n}: {} triangles, {} cut cells, {} pieces, {} swept entries",
            before.n_elements(),
            geometry.cut_cells.len(),
            geometry.diagnostics.n_pieces,
            swept.entries.len()
        );
        return;
    }

    let mut criterion = Criterion::default()
        .sample_size(10)
        .warm_up_time(std::time::Duration::from_millis(300))
        .measurement_time(std::time::Duration::from_secs(2))
        .configure_from_args();
    let mut rows = Vec::new();
    for n in resolutions() {
        let (vertices, moved, elements) = sphere_for(n);
        let (surface, after) = (surface(&vertices, &elements), surface(&moved, &elements));
        let n_triangles = surface.n_elements();
        let grid = Grid::new(&[0.0; 3], &[1.0; 3], &[n; 3]).unwrap();
        let mut geometry = CutGeometry::new();
        compute(&grid, &surface, &mut geometry);
        let pieces = geometry.diagnostics.n_pieces as u64;
        let mut group = criterion.benchmark_group("cutcell_sphere");
        group.throughput(Throughput::Elements(pieces));
        group.bench_function(BenchmarkId::new("compute", n), |b| {
            b.iter(|| compute(&grid, black_box(&surface), &mut geometry))
        });
        let mut swept = SweptVolumes::new();
        group.bench_function(BenchmarkId::new("swept", n), |b| {
            b.iter(|| swept_volumes(&grid, black_box(&surface), &after, &mut swept))
        });
        group.finish();
        let t_compute = best_time(5, || compute(&grid, &surface, &mut geometry));
        let t_swept = best_time(3, || swept_volumes(&grid, &surface, &after, &mut swept));
        rows.push((
            n,
            n_triangles,
            geometry.cut_cells.len(),
            pieces,
            t_compute,
            t_swept,
        ));
    }
    criterion.final_summary();

    println!("\ncut-cell sphere (best of repeated calls, buffers reused)");
    println!(
        "    n        N  triangles  cut cells    pieces  compute [ms]  swept [ms]  pieces/s  triangles/s"
    );
    for &(n, n_triangles, cut, pieces, t, ts) in &rows {
        println!(
            "{n:5} {:8} {n_triangles:10} {cut:10} {pieces:9} {:13.3} {:11.3} {:9.3e} {:11.3e}",
            n * n * n,
            t * 1e3,
            ts * 1e3,
            pieces as f64 / t,
            n_triangles as f64 / t,
        );
    }
    if rows.len() >= 2 {
        // Least-squares slope of log t against log N.
        let pts: Vec<(f64, f64)> = rows
            .iter()
            .map(|&(n, _, _, _, t, _)| (((n * n * n) as f64).ln(), t.ln()))
            .collect();
        let m = pts.len() as f64;
        let (sx, sy) = pts.iter().fold((0.0, 0.0), |a, p| (a.0 + p.0, a.1 + p.1));
        let (mx, my) = (sx / m, sy / m);
        let num: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
        let den: f64 = pts.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
        println!(
            "fitted exponent of compute time vs N: {:.3} (cut cells: 2/3 = 0.667)",
            num / den
        );
    }
}
