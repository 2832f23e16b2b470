//! Link evaluations per second (eq. (29)–(30) of paper 003, ν ≠ 0 so both passes run) on a
//! 3-D box lattice of 40×20×10 particles (22 k links), with 1 and 2 threads.
//!
//! Run: `cargo bench -p solid-node --no-default-features --bench dem_links`. Criterion prints
//! the throughput in links/s; per core = value / threads.

mod support;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use support::lattice;

fn links(c: &mut Criterion) {
    let mut group = c.benchmark_group("dem_links");
    group.sample_size(20);
    group.measurement_time(std::time::Duration::from_secs(4));
    for threads in [1usize, 2] {
        let mut solid = lattice(threads);
        group.throughput(Throughput::Elements(solid.model().links.len() as u64));
        group.bench_function(format!("links_{threads}_threads"), |b| {
            b.iter(|| std::hint::black_box(solid.recompute_internal_forces()))
        });
    }
    group.finish();
}

criterion_group!(benches, links);
criterion_main!(benches);
