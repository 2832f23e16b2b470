//! Link evaluations per CPU-second, 1 and 2 threads, measured with the process CPU time from
//! `/proc/self/stat` (utime + stime) as well as wall time. On a loaded shared machine wall time
//! says little; CPU time per link still gives the cost per core, and the ratio of CPU times
//! gives the parallel overhead.
//!
//! Run: `cargo bench -p solid-node --no-default-features --bench dem_links_cpu`.

mod support;

use std::time::Instant;

use support::lattice;

/// Process CPU time [s] (all threads), from `/proc/self/stat` fields 14 and 15 (clock ticks).
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let after = stat.rsplit_once(')').map_or("", |(_, rest)| rest);
    let fields: Vec<&str> = after.split_whitespace().collect();
    let ticks = |k: usize| {
        fields
            .get(k)
            .and_then(|v| v.parse::<f64>().ok())
            .unwrap_or(0.0)
    };
    // Fields after the command name start at field 3 (state): utime is 14, stime 15.
    (ticks(14 - 3) + ticks(15 - 3)) / 100.0
}

fn main() {
    let mut cpu_1 = 0.0;
    for threads in [1usize, 2] {
        let mut solid = lattice(threads);
        let n_links = solid.model().links.len() as f64;
        let (wall0, cpu0) = (Instant::now(), cpu_seconds());
        let mut evaluations = 0u64;
        while wall0.elapsed().as_secs_f64() < 5.0 {
            std::hint::black_box(solid.recompute_internal_forces());
            evaluations += 1;
        }
        let wall = wall0.elapsed().as_secs_f64();
        let cpu = cpu_seconds() - cpu0;
        let links = evaluations as f64 * n_links;
        if threads == 1 {
            cpu_1 = cpu / links;
        }
        println!(
            "{threads} thread(s): {n_links} links, {evaluations} evaluations; wall {:.3e} links/s; CPU {:.3e} links per CPU-second; CPU per link {:.1} ns; CPU(1)/CPU({threads}) = {:.3}",
            links / wall,
            links / cpu,
            1e9 * cpu / links,
            cpu_1 / (cpu / links)
        );
    }
}
