//! Cell updates per second of full split steps: 1-D (4096 cells, one pencil: no thread parallelism), 2-D 512², 3-D 128³, at
//! OSMP orders 3, 5, 7, with 1 and 2 threads; and 3-D OSMP5 on one thread on each instruction set
//! the CPU has (`isa_3d`), and on 32³, 64³ and 128³ (`size_3d`). A "cell update" is one cell advanced by one
//! whole step (all sweeps). Initial state: a blast with a swirl (all waves active).
//!
//! `cargo bench -p fluid-node --no-default-features --bench fv_throughput -- --warm-up-time 1 --measurement-time 3`

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use fluid_node::fv::{BoundaryKind, FluidParams, FluidSolver, FluidState, FluxKind, Isa};
use fluid_node::grid::Grid;

fn blast(dim: usize, n: usize, order: u32, threads: usize) -> FluidSolver {
    let grid = Grid::new(&vec![0.0; dim], &vec![1.0; dim], &vec![n; dim]).expect("grid");
    let mut state = FluidState::zeros(dim, grid.n_cells());
    for idx in 0..grid.n_cells() {
        let x = grid.cell_center(grid.ijk(idx));
        let r2: f64 = (0..dim).map(|a| (x[a] - 0.45).powi(2)).sum();
        let (rho, p) = if r2 < 0.04 { (8.0, 116.5) } else { (1.4, 1.0) };
        let mut vel = [0.0; 3];
        for a in 0..dim {
            vel[a] = 0.3 * (2.0 * std::f64::consts::PI * x[(a + 1) % dim]).sin();
        }
        state.set_primitive(idx, rho, vel, p, 1.4);
    }
    let params = FluidParams {
        gamma: 1.4,
        cfl: 0.5,
        flux: FluxKind::Osmp(order),
        boundary: [[BoundaryKind::Wall; 2]; 3],
        vacuum_rho: 1e-10,
        vacuum_p: 1e-10,
    };
    FluidSolver::new(grid, params, state, threads).expect("solver")
}

fn throughput(c: &mut Criterion) {
    for (dim, n) in [(1usize, 4096usize), (2, 512), (3, 128)] {
        let mut group = c.benchmark_group(format!("step_{dim}d"));
        group.sample_size(10);
        let cells = n.pow(dim as u32) as u64;
        group.throughput(Throughput::Elements(cells));
        for order in [3u32, 5, 7] {
            for threads in [1usize, 2] {
                let mut solver = blast(dim, n, order, threads);
                group.bench_function(
                    BenchmarkId::new(format!("osmp{order}"), format!("{threads}t")),
                    |b| {
                        b.iter(|| {
                            let dt = solver.max_dt();
                            let rep = solver.advance(dt);
                            assert!(rep.ok());
                            rep.hlle_faces
                        })
                    },
                );
            }
        }
        group.finish();
    }
    // 3-D OSMP5 on one thread as the grid grows past the caches (32³: 1.3 MB of state, in L2;
    // 64³: 10 MB; 128³: 84 MB): what the state's traffic costs a cell update.
    let mut group = c.benchmark_group("size_3d");
    group.sample_size(10);
    for n in [32usize, 64, 128] {
        group.throughput(Throughput::Elements(n.pow(3) as u64));
        let mut solver = blast(3, n, 5, 1);
        group.bench_function(BenchmarkId::new("osmp5", n), |b| {
            b.iter(|| {
                let dt = solver.max_dt();
                let rep = solver.advance(dt);
                assert!(rep.ok());
                rep.hlle_faces
            })
        });
    }
    group.finish();
    // The same step on each instruction set this CPU has (the rows above run on the best).
    let mut group = c.benchmark_group("isa_3d");
    group.sample_size(10);
    group.throughput(Throughput::Elements(128u64.pow(3)));
    for isa in Isa::available() {
        let mut solver = blast(3, 128, 5, 1);
        solver.set_isa(isa);
        group.bench_function(BenchmarkId::new("osmp5", format!("{isa:?}")), |b| {
            b.iter(|| {
                let dt = solver.max_dt();
                let rep = solver.advance(dt);
                assert!(rep.ok());
                rep.hlle_faces
            })
        });
    }
    group.finish();
}

criterion_group!(benches, throughput);
criterion_main!(benches);
