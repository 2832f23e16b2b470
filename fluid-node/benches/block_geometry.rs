//! The cut-cell geometry per rank (issue 40 item 1, step 1): `compute_block` of each rank's
//! block and halo against `compute` on the whole grid, with K = 1, 2, 4 ranks cut as
//! `protocol::decomp::choose` cuts the grid: the loads' trial geometry (`compute_block_cells`,
//! halo 1) and the whole geometry with the embedded part's halo (11); best time of repeats (one rank after the other
//! in this one process, so no rank waits for a core), heap bytes and elements clipped per rank.
//! Then the sweeps' hook inputs per rank (issue 40 item 1, step 2): `embedded::wall_hooks` of
//! each block (its geometry with a halo of `hook_halo(3)` = 15 cells, and the ghost fills, wall
//! runs and vacuum cells of its cells from it) against the whole grid's (`compute`, then the
//! same from the whole geometry: what every rank derived before, with the geometry at hand).
//!
//! ```text
//! cargo bench -p fluid-node --no-default-features --bench block_geometry
//! BLOCK_BENCH_N=96 BLOCK_BENCH_REPS=15 target/release/deps/block_geometry-HASH
//! ```
//!
//! Surfaces: the two particles of `scenes/opening-fracture-3d.toml` at t = 0 (the box
//! `[0.6, 1.4]³` of its 2 m domain, split at x = 1, 12 triangles each, the shared face carried on
//! both sides), and a polyhedral sphere of radius 0.3 in the unit cube refined with the grid
//! (`n/2 × n` bands and sectors, edges of about two cells, as the `cutcell` bench).

use std::time::Instant;

#[path = "../tests/it/cutcell_support/mod.rs"]
mod cutcell_support;

use fluid_node::cutcell::{
    BlockSweep, CellBox, CutGeometry, Surface, compute, compute_block, compute_block_cells,
    compute_blocks,
};
use fluid_node::embedded::{SolidFrame, hook_halo, wall_hooks};
use fluid_node::grid::Grid;

/// The halo of the embedded part at OSMP 5 (ng = 3): `NEAR_RADIUS` (2) + the ghost depth
/// `2 ng` (6) + `WIDEN_RINGS` (2) + one cell of motion (docs/mpi.md, the plan's step 1).
const HALO: usize = 11;

/// Best wall time of `reps` calls \[s\] (the machine's other load only adds time).
fn timed(reps: usize, mut f: impl FnMut()) -> f64 {
    (0..reps)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
}

fn run(name: &str, grid: &Grid, mesh: &cutcell_support::Mesh, reps: usize) {
    let surface = Surface {
        dim: 3,
        vertices: &mesh.vertices,
        elements: &mesh.elements,
        element_particle: &mesh.particle,
    };
    let mut whole = CutGeometry::new();
    compute(grid, &surface, &mut whole);
    let t_whole = timed(reps, || {
        let mut g = CutGeometry::new();
        compute(grid, &surface, &mut g);
        std::hint::black_box(&g);
    });
    println!(
        "{name}: {} elements, {} cut cells; compute on the whole grid {} pieces, {:.2} ms, {:.1} MB",
        surface.n_elements(),
        whole.cut_cells.len(),
        whole.diagnostics.n_pieces,
        1e3 * t_whole,
        whole.memory_bytes() as f64 / 1e6
    );
    println!(
        "| K | cut | rank | geometry, halo | elements clipped | rows swept whole | pieces | ms | MB |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    for k in [1, 2, 4] {
        let dims = protocol::decomp::choose(&grid.cells[..3], k, 6).expect("decomposition");
        for r in 0..k {
            let block = CellBox::of_rank(grid, dims, r);
            // The loads' trial geometry (cells only, halo 1), then the embedded part's.
            for (halo, cells) in [(1, true), (HALO, false)] {
                let geometry = |b| {
                    if cells {
                        compute_block_cells(grid, &surface, b, halo)
                    } else {
                        compute_block(grid, &surface, b, halo)
                    }
                };
                let b = geometry(block);
                let t = timed(reps, || {
                    std::hint::black_box(geometry(block));
                });
                let what = if cells { "cells, 1" } else { "all, 11" };
                println!(
                    "| {k} | {dims:?} | {r} | {what} | {} | {} | {} | {:.2} | {:.1} |",
                    b.clipped_elements,
                    b.whole_rows,
                    b.n_pieces,
                    1e3 * t,
                    b.memory_bytes() as f64 / 1e6
                );
            }
            // The embedded part's geometry of F^(n+1) (no halo): with rows swept whole, and the
            // local part of the chained one (`BlockSweep::new`, before the messages).
            let b = compute_block(grid, &surface, block, 0);
            let t = timed(reps, || {
                std::hint::black_box(compute_block(grid, &surface, block, 0));
            });
            let t_local = timed(reps, || {
                std::hint::black_box(BlockSweep::new(grid, &surface, block));
            });
            println!(
                "| {k} | {dims:?} | {r} | all, 0 / chained local | {} | {} | {} | {:.2} / {:.2} | {:.1} |",
                b.clipped_elements,
                b.whole_rows,
                b.n_pieces,
                1e3 * t,
                1e3 * t_local,
                b.memory_bytes() as f64 / 1e6
            );
        }
        // Every block chained in this one process (local parts, messages, finish), per rank.
        let t = timed(reps, || {
            std::hint::black_box(compute_blocks(grid, &surface, dims));
        });
        println!(
            "| {k} | {dims:?} | all | chained, 0, per rank | | | | {:.2} | |",
            1e3 * t / k as f64
        );
    }
}

/// The mesh as a frame at rest (one particle per mesh particle, every element wet).
fn frame_of(mesh: &cutcell_support::Mesh) -> SolidFrame {
    let np = mesh.particle.iter().max().map_or(1, |&p| p as usize + 1);
    SolidFrame {
        dim: 3,
        position: vec![0.0; 3 * np],
        velocity: vec![0.0; 3 * np],
        angular_velocity: vec![0.0; 3 * np],
        vertices: mesh.vertices.clone(),
        elements: mesh.elements.clone(),
        element_particle: mesh.particle.clone(),
        wet: vec![true; mesh.elements.len() / 3],
    }
}

/// The hook inputs per rank (`ng` = 3, OSMP 5) against the whole grid's.
fn run_hooks(name: &str, grid: &Grid, mesh: &cutcell_support::Mesh, reps: usize) {
    let ng = 3;
    let frame = frame_of(mesh);
    let t_compute = timed(reps, || {
        let mut g = CutGeometry::new();
        compute(grid, &frame.surface(), &mut g);
        std::hint::black_box(&g);
    });
    let whole = wall_hooks(grid, ng, &frame, None);
    let t_whole = timed(reps, || {
        std::hint::black_box(wall_hooks(grid, ng, &frame, None));
    });
    let count = |h: &fluid_node::embedded::WallHooks| {
        let fills: usize = h.ghosts.iter().map(Vec::len).sum();
        let runs: usize = h.walls.iter().map(Vec::len).sum();
        format!("{fills} / {runs} / {}", h.vacuum.len())
    };
    println!(
        "{name}, hooks (ng {ng}, halo {}): whole grid {} (fills / runs / vacuum), compute {:.2} ms, then the hooks {:.2} ms",
        hook_halo(ng),
        count(&whole),
        1e3 * t_compute,
        1e3 * (t_whole - t_compute)
    );
    println!("| K | cut | rank | fills / runs / vacuum | ms |");
    println!("| --- | --- | --- | --- | --- |");
    for k in [1, 2, 4] {
        let dims = protocol::decomp::choose(&grid.cells[..3], k, 6).expect("decomposition");
        for r in 0..k {
            let block = CellBox::of_rank(grid, dims, r);
            let h = wall_hooks(grid, ng, &frame, Some(block));
            let t = timed(reps, || {
                std::hint::black_box(wall_hooks(grid, ng, &frame, Some(block)));
            });
            println!("| {k} | {dims:?} | {r} | {} | {:.2} |", count(&h), 1e3 * t);
        }
    }
}

fn main() {
    let env = |key: &str, default: usize| {
        std::env::var(key)
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(default)
    };
    let n = env("BLOCK_BENCH_N", 96);
    let reps = env("BLOCK_BENCH_REPS", 15);
    // opening-fracture-3d: two boxes sharing the face x = 1 (particles 0 and 1).
    let grid = Grid::new(&[0.0; 3], &[2.0; 3], &[n; 3]).unwrap();
    let mut boxes = cutcell_support::box_mesh([0.6, 0.6, 0.6], [1.0, 1.4, 1.4]);
    let right = cutcell_support::box_mesh([1.0, 0.6, 0.6], [1.4, 1.4, 1.4]);
    let first = (boxes.vertices.len() / 3) as u32;
    boxes.particle = vec![0; boxes.elements.len() / 3];
    boxes.vertices.extend_from_slice(&right.vertices);
    boxes
        .elements
        .extend(right.elements.iter().map(|v| v + first));
    boxes
        .particle
        .extend(std::iter::repeat_n(1, right.elements.len() / 3));
    run(
        &format!("opening-fracture-3d boxes, {n}^3"),
        &grid,
        &boxes,
        reps,
    );
    run_hooks(
        &format!("opening-fracture-3d boxes, {n}^3"),
        &grid,
        &boxes,
        reps,
    );
    let grid = Grid::new(&[0.0; 3], &[1.0; 3], &[n; 3]).unwrap();
    let sphere = cutcell_support::sphere_mesh([0.5013, 0.4987, 0.5021], 0.3, n / 2, n);
    run(&format!("sphere r = 0.3, {n}^3"), &grid, &sphere, reps);
    run_hooks(&format!("sphere r = 0.3, {n}^3"), &grid, &sphere, reps);
}
