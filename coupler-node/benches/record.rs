//! Recording throughput: 64 KiB and 1 MiB frames through [`Recorder`] into a `Vec` (16 frames)
//! and into a file in `/tmp` (64 MiB a file), with `end_step` after every 4 frames (a step's
//! worth), for each `run.record_compression` (ids `none/file/65536` and so on), through a
//! `BufWriter` as a run does. Each sample writes a new file, as a run does; removing the
//! previous sample's file is not timed (truncating it in `File::create` was: with it the
//! uncompressed rate read 672–752 MiB/s, without it 1.5 GiB/s, on the same disk).
//!
//! `CARGO_TARGET_DIR=... cargo bench -p coupler-node --bench record`

use std::fs::File;
use std::io::{BufWriter, Cursor};
use std::time::{Duration, Instant};

use coupler_node::record::Recorder;
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use protocol::scene::{RecordCompression, RecordLevel};
use protocol::wire::NodeKind;

const FRAMES_PER_ITER: usize = 16;

/// A frame of f64 values as the bus carries them (seeded, not compressible to nothing).
fn frame(len: usize) -> Vec<u8> {
    let mut state = 0x2545_F491_4F6C_DD1Du64;
    (0..len / 8)
        .flat_map(|_| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            ((state >> 11) as f64 / (1u64 << 53) as f64).to_le_bytes()
        })
        .collect()
}

/// Bytes written per file: a run records one long file, so creating it must not dominate: with
/// 16 frames per file the uncompressed file rate was 296 MiB/s against 1.2–2.1 GB/s for `dd`
/// on the same disk.
const FILE_BYTES: usize = 64 << 20;

fn record<W: std::io::Write + std::io::Seek>(
    writer: W,
    compression: RecordCompression,
    frame: &[u8],
    frames: usize,
) -> W {
    let mut rec =
        Recorder::new(writer, RecordLevel::Exchange, compression, "bench", "").expect("recorder");
    for i in 0..frames {
        // Steps of 1 µs of simulated time.
        let t = (i / 4) as f64 * 1e-6;
        rec.record_frame(NodeKind::Fluid, NodeKind::Coupler, t, 0, frame)
            .expect("record");
        if i % 4 == 3 {
            rec.end_step().expect("end step");
        }
    }
    rec.finish().expect("finish")
}

fn bench_record(c: &mut Criterion) {
    let mut group = c.benchmark_group("record");
    group.sample_size(10);
    group.measurement_time(Duration::from_secs(4));
    let path = std::env::temp_dir().join(format!("cosim-record-bench-{}.mcap", std::process::id()));
    for compression in [
        RecordCompression::None,
        RecordCompression::Lz4,
        RecordCompression::Zstd,
    ] {
        let name = compression.name();
        for len in [64usize << 10, 1 << 20] {
            let data = frame(len);
            group.throughput(Throughput::Bytes((FRAMES_PER_ITER * len) as u64));
            group.bench_with_input(
                BenchmarkId::new(format!("{name}/vec"), len),
                &data,
                |b, data| {
                    b.iter(|| {
                        record(
                            Cursor::new(Vec::with_capacity(FRAMES_PER_ITER * len * 2)),
                            compression,
                            data,
                            FRAMES_PER_ITER,
                        )
                    })
                },
            );
            let frames = FILE_BYTES / len;
            group.throughput(Throughput::Bytes((frames * len) as u64));
            group.bench_with_input(
                BenchmarkId::new(format!("{name}/file"), len),
                &data,
                |b, data| {
                    b.iter_custom(|iters| {
                        let mut total = Duration::ZERO;
                        for _ in 0..iters {
                            let _ = std::fs::remove_file(&path);
                            let start = Instant::now();
                            let file = File::create(&path).expect("create bench file");
                            let mut out = record(BufWriter::new(file), compression, data, frames);
                            std::io::Write::flush(&mut out).expect("flush");
                            total += start.elapsed();
                        }
                        total
                    })
                },
            );
        }
    }
    group.finish();
    let _ = std::fs::remove_file(&path);
}

criterion_group!(benches, bench_record);
criterion_main!(benches);
