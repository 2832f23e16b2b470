//! Shared helpers of the cut-cell tests: seeded RNG, closed test meshes with exact polyhedral
//! volumes, rigid motions, and the identity checks (2) and (3) evaluated over every cell.

#![allow(dead_code, unreachable_pub, clippy::needless_range_loop)]

use fluid_node::cutcell::{CutGeometry, Surface, SweptVolumes, compute, face_index, swept_volumes};
use fluid_node::grid::Grid;

/// SplitMix64: a tiny seeded generator (no dependency).
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [lo, hi).
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * ((self.next_u64() >> 11) as f64 / (1u64 << 53) as f64)
    }
}

/// A triangle (3-D) or segment (2-D) mesh that owns its arrays.
#[derive(Clone, Debug)]
pub struct Mesh {
    pub dim: usize,
    pub vertices: Vec<f64>,
    pub elements: Vec<u32>,
    pub particle: Vec<u32>,
}

impl Mesh {
    pub fn surface(&self) -> Surface<'_> {
        Surface {
            dim: self.dim,
            vertices: &self.vertices,
            elements: &self.elements,
            element_particle: &self.particle,
        }
    }
    pub fn n_elements(&self) -> usize {
        self.elements.len() / self.dim
    }
    /// Appends another mesh (its elements get particle ids shifted by `particle_offset`).
    pub fn append(&mut self, other: &Mesh, particle_offset: u32) {
        let base = (self.vertices.len() / self.dim) as u32;
        self.vertices.extend_from_slice(&other.vertices);
        self.elements
            .extend(other.elements.iter().map(|v| v + base));
        self.particle
            .extend(other.particle.iter().map(|p| p + particle_offset));
    }
    /// Exact (f64) enclosed volume / area of the closed oriented mesh.
    pub fn enclosed_volume(&self) -> f64 {
        let v = |i: u32| {
            let i = i as usize * self.dim;
            let mut x = [0.0; 3];
            x[..self.dim].copy_from_slice(&self.vertices[i..i + self.dim]);
            x
        };
        // About a reference point to keep precision.
        let o = v(0);
        let mut acc = 0.0;
        for e in self.elements.chunks(self.dim) {
            if self.dim == 3 {
                let (a, b, c) = (sub(v(e[0]), o), sub(v(e[1]), o), sub(v(e[2]), o));
                acc += dot(a, cross(b, c)) / 6.0;
            } else {
                let (a, b) = (sub(v(e[0]), o), sub(v(e[1]), o));
                acc += 0.5 * (a[0] * b[1] - a[1] * b[0]);
            }
        }
        acc
    }
    /// Total element area (length in 2-D).
    pub fn area(&self) -> f64 {
        let v = |i: u32| {
            let i = i as usize * self.dim;
            let mut x = [0.0; 3];
            x[..self.dim].copy_from_slice(&self.vertices[i..i + self.dim]);
            x
        };
        let mut acc = 0.0;
        for e in self.elements.chunks(self.dim) {
            if self.dim == 3 {
                let c = cross(sub(v(e[1]), v(e[0])), sub(v(e[2]), v(e[0])));
                acc += 0.5 * dot(c, c).sqrt();
            } else {
                let d = sub(v(e[1]), v(e[0]));
                acc += dot(d, d).sqrt();
            }
        }
        acc
    }
    /// Applies `f` to every vertex.
    pub fn map(&self, f: impl Fn([f64; 3]) -> [f64; 3]) -> Mesh {
        let mut out = self.clone();
        for x in out.vertices.chunks_mut(self.dim) {
            let mut p = [0.0; 3];
            p[..self.dim].copy_from_slice(x);
            let q = f(p);
            x.copy_from_slice(&q[..self.dim]);
        }
        out
    }
    /// Reverses every element (normals flipped).
    pub fn reversed(&self) -> Mesh {
        let mut out = self.clone();
        for e in out.elements.chunks_mut(self.dim) {
            e.swap(0, 1);
        }
        out
    }
}

pub fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
pub fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
pub fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Axis-aligned box `[lo, hi]` as 12 outward triangles.
pub fn box_mesh(lo: [f64; 3], hi: [f64; 3]) -> Mesh {
    let mut vertices = Vec::new();
    for k in 0..8 {
        vertices.push(if k & 1 == 0 { lo[0] } else { hi[0] });
        vertices.push(if k & 2 == 0 { lo[1] } else { hi[1] });
        vertices.push(if k & 4 == 0 { lo[2] } else { hi[2] });
    }
    // Quads (outward, counter-clockwise seen from outside).
    let quads = [
        [0, 2, 3, 1], // z = lo
        [4, 5, 7, 6], // z = hi
        [0, 1, 5, 4], // y = lo
        [2, 6, 7, 3], // y = hi
        [0, 4, 6, 2], // x = lo
        [1, 3, 7, 5], // x = hi
    ];
    let mut elements = Vec::new();
    for q in quads {
        elements.extend_from_slice(&[q[0], q[1], q[2], q[0], q[2], q[3]]);
    }
    let mesh = Mesh {
        dim: 3,
        vertices,
        elements,
        particle: vec![0; 12],
    };
    assert!(mesh.enclosed_volume() > 0.0);
    mesh
}

/// UV sphere of radius `r` about `c` with `n_lat` bands and `n_lon` sectors (outward).
pub fn sphere_mesh(c: [f64; 3], r: f64, n_lat: usize, n_lon: usize) -> Mesh {
    let mut vertices = vec![c[0], c[1], c[2] + r];
    for i in 1..n_lat {
        let theta = std::f64::consts::PI * i as f64 / n_lat as f64;
        for j in 0..n_lon {
            let phi = 2.0 * std::f64::consts::PI * j as f64 / n_lon as f64;
            vertices.extend_from_slice(&[
                c[0] + r * theta.sin() * phi.cos(),
                c[1] + r * theta.sin() * phi.sin(),
                c[2] + r * theta.cos(),
            ]);
        }
    }
    vertices.extend_from_slice(&[c[0], c[1], c[2] - r]);
    let south = (vertices.len() / 3 - 1) as u32;
    let ring = |i: usize, j: usize| (1 + (i - 1) * n_lon + j % n_lon) as u32;
    let mut elements = Vec::new();
    for j in 0..n_lon {
        elements.extend_from_slice(&[0, ring(1, j), ring(1, j + 1)]);
        for i in 1..n_lat - 1 {
            let (a, b, cc, d) = (
                ring(i, j),
                ring(i + 1, j),
                ring(i + 1, j + 1),
                ring(i, j + 1),
            );
            elements.extend_from_slice(&[a, b, cc, a, cc, d]);
        }
        elements.extend_from_slice(&[ring(n_lat - 1, j), south, ring(n_lat - 1, j + 1)]);
    }
    let n = elements.len() / 3;
    let mesh = Mesh {
        dim: 3,
        vertices,
        elements,
        particle: vec![0; n],
    };
    assert!(mesh.enclosed_volume() > 0.0, "sphere must be outward");
    mesh
}

/// Torus about the z axis through `c`, radii `big` and `small`, `n_u` × `n_v` quads (outward).
pub fn torus_mesh(c: [f64; 3], big: f64, small: f64, n_u: usize, n_v: usize) -> Mesh {
    let mut vertices = Vec::new();
    for i in 0..n_u {
        let u = 2.0 * std::f64::consts::PI * i as f64 / n_u as f64;
        for j in 0..n_v {
            let v = 2.0 * std::f64::consts::PI * j as f64 / n_v as f64;
            let rho = big + small * v.cos();
            vertices.extend_from_slice(&[
                c[0] + rho * u.cos(),
                c[1] + rho * u.sin(),
                c[2] + small * v.sin(),
            ]);
        }
    }
    let id = |i: usize, j: usize| ((i % n_u) * n_v + j % n_v) as u32;
    let mut elements = Vec::new();
    for i in 0..n_u {
        for j in 0..n_v {
            let (a, b, cc, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            elements.extend_from_slice(&[a, b, cc, a, cc, d]);
        }
    }
    let n = elements.len() / 3;
    let mut mesh = Mesh {
        dim: 3,
        vertices,
        elements,
        particle: vec![0; n],
    };
    if mesh.enclosed_volume() < 0.0 {
        mesh = mesh.reversed();
    }
    mesh
}

/// Closed counter-clockwise polygon loop (2-D) through `points`.
pub fn loop_mesh(points: &[[f64; 2]]) -> Mesh {
    let mut vertices = Vec::new();
    for p in points {
        vertices.extend_from_slice(p);
    }
    let n = points.len() as u32;
    let mut elements = Vec::new();
    for i in 0..n {
        elements.extend_from_slice(&[i, (i + 1) % n]);
    }
    let mesh = Mesh {
        dim: 2,
        vertices,
        elements,
        particle: vec![0; n as usize],
    };
    assert!(
        mesh.enclosed_volume() > 0.0,
        "loop must be counter-clockwise"
    );
    mesh
}

/// Regular polygon (2-D disc) of radius `r` about `c` with `n` sides, rotated by `phase`.
pub fn disc_mesh(c: [f64; 2], r: f64, n: usize, phase: f64) -> Mesh {
    let points: Vec<[f64; 2]> = (0..n)
        .map(|i| {
            let t = phase + 2.0 * std::f64::consts::PI * i as f64 / n as f64;
            [c[0] + r * t.cos(), c[1] + r * t.sin()]
        })
        .collect();
    loop_mesh(&points)
}

/// Rotation matrix about unit axis `axis` by `angle` (Rodrigues).
pub fn rotation(axis: [f64; 3], angle: f64) -> [[f64; 3]; 3] {
    let len = dot(axis, axis).sqrt();
    let [x, y, z] = [axis[0] / len, axis[1] / len, axis[2] / len];
    let (s, c) = angle.sin_cos();
    let t = 1.0 - c;
    [
        [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
        [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
        [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
    ]
}

/// `R (p − centre) + centre + shift`.
pub fn rigid(p: [f64; 3], r: &[[f64; 3]; 3], centre: [f64; 3], shift: [f64; 3]) -> [f64; 3] {
    let d = sub(p, centre);
    let mut out = [0.0; 3];
    for i in 0..3 {
        out[i] = centre[i] + shift[i] + r[i][0] * d[0] + r[i][1] * d[1] + r[i][2] * d[2];
    }
    out
}

/// Largest violation of identity (2) over every cell and active axis, relative to the face area:
/// `|A_a (λ_+ − λ_−) + Σ area n_a|`; for uncut cells also `|λ − Λ|` on each face.
pub fn identity_residual(grid: &Grid, geo: &CutGeometry) -> f64 {
    let mut projected = vec![[0.0; 3]; grid.n_cells()];
    for s in &geo.subfaces {
        for a in 0..3 {
            projected[s.cell as usize][a] += s.area * s.normal[a];
        }
    }
    let mut worst: f64 = 0.0;
    for cell in 0..grid.n_cells() {
        let ijk = grid.ijk(cell);
        for a in 0..grid.dim {
            let area: f64 = (0..grid.dim)
                .filter(|&b| b != a)
                .map(|b| grid.dx[b])
                .product();
            let mut up = ijk;
            up[a] += 1;
            let lower = geo.face_fraction[a][face_index(grid, a, ijk)];
            let upper = geo.face_fraction[a][face_index(grid, a, up)];
            let r = (area * (upper - lower) + projected[cell][a]).abs() / area;
            worst = worst.max(r);
            // An uncut cell is covered or empty: its faces carry its fraction.
            if geo.cut_cells.binary_search(&(cell as u32)).is_err() {
                let l = geo.solid_fraction[cell];
                worst = worst.max((lower - l).abs()).max((upper - l).abs());
            }
        }
    }
    worst
}

/// Largest violation of identity (3) over every cell, relative to the cell volume:
/// `|Σ swept − (Λ^{n+1} − Λ^n) V| / V`. Also returns the total swept volume.
pub fn swept_residual(grid: &Grid, before: &Mesh, after: &Mesh) -> (f64, f64) {
    let mut g0 = CutGeometry::new();
    let mut g1 = CutGeometry::new();
    compute(grid, &before.surface(), &mut g0);
    compute(grid, &after.surface(), &mut g1);
    let mut swept = SweptVolumes::new();
    swept_volumes(grid, &before.surface(), &after.surface(), &mut swept);
    let mut acc = vec![0.0; grid.n_cells()];
    swept.accumulate(&mut acc);
    let v = grid.cell_volume();
    let mut worst: f64 = 0.0;
    for c in 0..grid.n_cells() {
        let r = (acc[c] - (g1.solid_fraction[c] - g0.solid_fraction[c]) * v).abs() / v;
        worst = worst.max(r);
    }
    (worst, swept.total())
}

/// Σ Λ V over the whole array (independent of the library's own sum).
pub fn volume_of(grid: &Grid, geo: &CutGeometry) -> f64 {
    geo.solid_fraction.iter().sum::<f64>() * grid.cell_volume()
}
