//! Broad phase: a uniform grid of bounding spheres, rebuilt at every evaluation, cost linear in
//! the number of particles.
//!
//! Cells have the size of the largest bounding diameter, so two overlapping spheres lie in the
//! same or in neighbouring cells. Cells are hashed into `2^k ≥ 2n` buckets filled by a counting
//! sort in particle order; each particle scans the 3^dim cells around its own. Pairs come out
//! sorted by first particle, then by neighbour cell, then by second particle: the order depends
//! only on the positions, never on a thread count or a hash-map iteration.

/// Reusable grid buffers (no allocation once warm).
#[derive(Clone, Debug, Default)]
pub struct Grid {
    cell_of: Vec<[i64; 3]>,
    bucket_start: Vec<u32>,
    bucket_items: Vec<u32>,
}

/// Appends to `out` every pair `(i, j)`, `i < j`, whose bounding spheres (centre `centers[i]`,
/// radius `radii[i]`) overlap strictly. `dim` is 2 or 3 (2-D: z ignored).
pub fn candidate_pairs(
    dim: usize,
    centers: &[[f64; 3]],
    radii: &[f64],
    grid: &mut Grid,
    out: &mut Vec<(u32, u32)>,
) {
    out.clear();
    let n = centers.len();
    debug_assert_eq!(radii.len(), n);
    let r_max = radii.iter().copied().fold(0.0, f64::max);
    if n < 2 || r_max <= 0.0 {
        return;
    }
    let cell = 2.0 * r_max;
    let n_buckets = (2 * n).next_power_of_two();
    let mask = (n_buckets - 1) as u64;
    let Grid {
        cell_of,
        bucket_start,
        bucket_items,
    } = grid;
    cell_of.clear();
    cell_of.extend(centers.iter().map(|x| {
        let mut c = [0i64; 3];
        for a in 0..dim {
            // NOTE: `as` saturates (NaN → 0), so a non-finite centre cannot misbehave here;
            // the step's chokepoint reports it.
            c[a] = (x[a] / cell).floor() as i64;
        }
        c
    }));
    bucket_start.clear();
    bucket_start.resize(n_buckets + 1, 0);
    for c in cell_of.iter() {
        bucket_start[bucket(c, mask) + 1] += 1;
    }
    for b in 0..n_buckets {
        bucket_start[b + 1] += bucket_start[b];
    }
    bucket_items.clear();
    bucket_items.resize(n, 0);
    // Fill in particle order: items of a bucket are sorted by particle.
    for (i, c) in cell_of.iter().enumerate() {
        let b = bucket(c, mask);
        // `bucket_start[b]` is used as the fill cursor, then restored below.
        bucket_items[bucket_start[b] as usize] = i as u32;
        bucket_start[b] += 1;
    }
    for b in (1..=n_buckets).rev() {
        bucket_start[b] = bucket_start[b - 1];
    }
    bucket_start[0] = 0;
    let span: i64 = 1;
    let z_span = if dim == 3 { span } else { 0 };
    for i in 0..n {
        let ci = cell_of[i];
        let xi = centers[i];
        for dz in -z_span..=z_span {
            for dy in -span..=span {
                for dx in -span..=span {
                    let key = [ci[0] + dx, ci[1] + dy, ci[2] + dz];
                    let b = bucket(&key, mask);
                    let items =
                        &bucket_items[bucket_start[b] as usize..bucket_start[b + 1] as usize];
                    for &j in items {
                        let ju = j as usize;
                        if ju <= i || cell_of[ju] != key {
                            continue;
                        }
                        let xj = centers[ju];
                        let mut d2 = 0.0;
                        for a in 0..dim {
                            let d = xj[a] - xi[a];
                            d2 += d * d;
                        }
                        let reach = radii[i] + radii[ju];
                        if d2 < reach * reach {
                            out.push((i as u32, j));
                        }
                    }
                }
            }
        }
    }
}

fn bucket(c: &[i64; 3], mask: u64) -> usize {
    let h = (c[0] as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (c[1] as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
        ^ (c[2] as u64).wrapping_mul(0x1656_67B1_9E37_79F9);
    ((h ^ (h >> 29)) & mask) as usize
}
