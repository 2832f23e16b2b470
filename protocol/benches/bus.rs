//! One exchange round trip (send a frame, the peer echoes it back) for 1 KiB to 16 MiB frames,
//! over the iceoryx2 bus between two threads and over the in-memory transport for comparison.
//!
//! `CARGO_TARGET_DIR=... cargo bench -p protocol --bench bus`

use std::hint::black_box;
use std::thread;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use protocol::bus::{Bus, cleanup_run};
use protocol::transport::{MemoryTransport, Transport};
use protocol::wire::NodeKind;

const SIZES: [usize; 4] = [1 << 10, 64 << 10, 1 << 20, 16 << 20];
const LONG: Duration = Duration::from_secs(30);

/// Echoes every frame from the coupler until an empty one arrives.
fn echo(mut end: impl Transport) {
    loop {
        let (_, frame) = end.recv(Some(NodeKind::Coupler), LONG).expect("echo recv");
        end.send(NodeKind::Coupler, &frame).expect("echo send");
        if frame.is_empty() {
            return;
        }
    }
}

fn round_trips(c: &mut Criterion, name: &str, mut coupler: impl Transport) {
    let mut group = c.benchmark_group(name);
    group.sample_size(20);
    group.measurement_time(Duration::from_secs(3));
    for len in SIZES {
        // Seeded, non-trivial content.
        let frame: Vec<u8> = (0..len).map(|i| (i as u8).wrapping_mul(31)).collect();
        group.throughput(Throughput::Bytes(2 * len as u64));
        group.bench_with_input(BenchmarkId::from_parameter(len), &frame, |b, frame| {
            b.iter(|| {
                coupler.send(NodeKind::Fluid, frame).expect("send");
                let (_, back) = coupler.recv(Some(NodeKind::Fluid), LONG).expect("recv");
                black_box(back)
            })
        });
    }
    group.finish();
    coupler.send(NodeKind::Fluid, &[]).expect("stop");
    coupler
        .recv(Some(NodeKind::Fluid), LONG)
        .expect("stop echo");
}

fn bench_bus(c: &mut Criterion) {
    let run_id = format!("bench{}", std::process::id());
    let _ = cleanup_run(&run_id);
    let id = run_id.clone();
    let peer = thread::spawn(move || {
        echo(Bus::open(&id, NodeKind::Fluid, &[NodeKind::Coupler]).expect("open fluid"))
    });
    let coupler = Bus::open(&run_id, NodeKind::Coupler, &[NodeKind::Fluid]).expect("open coupler");
    round_trips(c, "bus_round_trip", coupler);
    peer.join().expect("echo thread");
    let _ = cleanup_run(&run_id);
}

fn bench_memory(c: &mut Criterion) {
    let (coupler, mut ends) = MemoryTransport::star(&[NodeKind::Fluid]);
    let fluid = ends.pop().expect("one end");
    let peer = thread::spawn(move || echo(fluid));
    round_trips(c, "memory_round_trip", coupler);
    peer.join().expect("echo thread");
}

criterion_group!(benches, bench_bus, bench_memory);
criterion_main!(benches);
