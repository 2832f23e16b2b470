//! Sub-face swept volumes (paper 000 eq. 12 per sub-face at `t^{n+1}`), in 3-D and 2-D under seeded
//! translations, rigid motions and deformations (vertices moved independently), moving up to about
//! one cell. Pins three identities:
//!
//! - (a) in every cell, `Σ entries = (Λ^{n+1} − Λ^n) V` (conservation, as for `swept_volumes`);
//! - (b) for a translation by `d`, every sub-face sweeps `(d · n_s) area_s`;
//! - (c) for a translation, the sub-prisms of an element add up to its `swept_volumes` prism, per
//!   element and per (element, cell).
//!
//! Also: skipped sub-faces on non-finite input, and the piece counts against `swept_volumes`.

#![allow(clippy::needless_range_loop)]

use crate::cutcell_support;

use cutcell_support::*;
use fluid_node::cutcell::{
    CutGeometry, SubfaceSwept, Surface, SweptVolumes, compute, subface_swept_volumes, swept_volumes,
};
use fluid_node::grid::Grid;

/// Tolerance of identity (a), relative to the cell volume.
const CELL_TOL: f64 = 1e-12;
/// Tolerance of identities (b) and (c), relative to `area · |d|` (see [`Report::subface`]).
const TRANSLATION_TOL: f64 = 1e-12;

/// Worst values of the identities over one motion.
#[derive(Clone, Copy, Debug, Default)]
struct Report {
    /// (a): `max_cell |Σ entries − ΔΛ V| / V`.
    cell: f64,
    /// `max_cell |Σ entries − Σ swept_volumes entries| / V` (holds for any motion, even one that
    /// folds the surface, where Λ is clamped and (a) fails for both).
    versus_elements: f64,
    /// (b): `max_s |vol(K_s) − (d · n_s) area_s| / (|d| max(area_s, 10⁻² A))`, `A` the face area of a
    /// cell (so tiny sub-faces are held to an absolute round-off of `10⁻¹⁴ |d| A`).
    subface: f64,
    /// (c): `max_e |Σ_{s ⊂ e} vol(K_s) − swept_e| / (|d| max(area_e, 10⁻² A))`.
    element: f64,
    /// (c) per (element, cell) pair, same scale.
    element_cell: f64,
    n_subfaces: usize,
}

impl Report {
    fn worst(self, other: Report) -> Report {
        Report {
            cell: self.cell.max(other.cell),
            versus_elements: self.versus_elements.max(other.versus_elements),
            subface: self.subface.max(other.subface),
            element: self.element.max(other.element),
            element_cell: self.element_cell.max(other.element_cell),
            n_subfaces: self.n_subfaces.max(other.n_subfaces),
        }
    }
}

/// Evaluates the identities for `before -> after`; (b) and (c) only when `translation` is given.
fn check(grid: &Grid, before: &Mesh, after: &Mesh, translation: Option<[f64; 3]>) -> Report {
    let mut g0 = CutGeometry::new();
    let mut g1 = CutGeometry::new();
    compute(grid, &before.surface(), &mut g0);
    compute(grid, &after.surface(), &mut g1);
    let mut out = SubfaceSwept::new();
    subface_swept_volumes(grid, &before.surface(), &after.surface(), &g1, &mut out);
    assert_eq!(out.n_skipped_subfaces, 0);
    // Sorted by sub-face then cell, no zero volume, no duplicate.
    for w in out.entries.windows(2) {
        assert!((w[0].subface, w[0].cell) < (w[1].subface, w[1].cell));
    }
    assert!(out.entries.iter().all(|e| e.volume != 0.0));
    let v = grid.cell_volume();
    let mut report = Report {
        n_subfaces: g1.subfaces.len(),
        ..Report::default()
    };
    let mut swept = SweptVolumes::new();
    swept_volumes(grid, &before.surface(), &after.surface(), &mut swept);
    let mut acc = vec![0.0; grid.n_cells()];
    out.accumulate(&mut acc);
    let mut acc_elements = vec![0.0; grid.n_cells()];
    swept.accumulate(&mut acc_elements);
    for c in 0..grid.n_cells() {
        let r = (acc[c] - (g1.solid_fraction[c] - g0.solid_fraction[c]) * v).abs() / v;
        report.cell = report.cell.max(r);
        let r = (acc[c] - acc_elements[c]).abs() / v;
        report.versus_elements = report.versus_elements.max(r);
    }
    let Some(d) = translation else {
        return report;
    };
    let face_area = v / grid.dx[0];
    let d_len = dot(d, d).sqrt();
    let mut per_subface = vec![0.0; g1.subfaces.len()];
    for e in &out.entries {
        per_subface[e.subface as usize] += e.volume;
    }
    let n_elements = after.n_elements();
    let mut element_area = vec![0.0; n_elements];
    let mut per_element = vec![0.0; n_elements];
    let mut per_element_cell = std::collections::BTreeMap::new();
    for (s, sub) in g1.subfaces.iter().enumerate() {
        let exact = dot(d, sub.normal) * sub.area;
        let scale = d_len * sub.area.max(1e-2 * face_area);
        report.subface = report.subface.max((per_subface[s] - exact).abs() / scale);
        element_area[sub.element as usize] += sub.area;
        per_element[sub.element as usize] += per_subface[s];
    }
    for e in &out.entries {
        let element = g1.subfaces[e.subface as usize].element;
        *per_element_cell.entry((element, e.cell)).or_insert(0.0) += e.volume;
    }
    let mut swept_element = vec![0.0; n_elements];
    for e in &swept.entries {
        swept_element[e.element as usize] += e.volume;
        *per_element_cell.entry((e.element, e.cell)).or_insert(0.0) -= e.volume;
    }
    let scale = |e: usize| d_len * element_area[e].max(1e-2 * face_area);
    for e in 0..n_elements {
        let r = (per_element[e] - swept_element[e]).abs() / scale(e);
        report.element = report.element.max(r);
    }
    for (&(e, _), &diff) in &per_element_cell {
        report.element_cell = report.element_cell.max(diff.abs() / scale(e as usize));
    }
    report
}

impl std::fmt::Display for Report {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "(a) {:.2e}, vs elements {:.2e}, (b) {:.2e}, (c) {:.2e}, (c) per cell {:.2e}",
            self.cell, self.versus_elements, self.subface, self.element, self.element_cell
        )
    }
}

fn assert_report(r: &Report, what: &str) {
    assert!(r.cell <= CELL_TOL, "{what}: (a) {:.2e}", r.cell);
    assert!(
        r.versus_elements <= CELL_TOL,
        "{what}: vs elements {:.2e}",
        r.versus_elements
    );
    assert!(
        r.subface <= TRANSLATION_TOL,
        "{what}: (b) {:.2e}",
        r.subface
    );
    assert!(
        r.element <= TRANSLATION_TOL,
        "{what}: (c) {:.2e}",
        r.element
    );
    assert!(
        r.element_cell <= TRANSLATION_TOL,
        "{what}: (c) per cell {:.2e}",
        r.element_cell
    );
}

fn assert_conserves(r: &Report, what: &str) {
    assert!(r.cell <= CELL_TOL, "{what}: (a) {:.2e}", r.cell);
    assert!(
        r.versus_elements <= CELL_TOL,
        "{what}: vs elements {:.2e}",
        r.versus_elements
    );
}

/// Length of the shortest element edge.
fn shortest_edge(mesh: &Mesh) -> f64 {
    let v = |i: u32| {
        let i = i as usize * mesh.dim;
        let mut x = [0.0; 3];
        x[..mesh.dim].copy_from_slice(&mesh.vertices[i..i + mesh.dim]);
        x
    };
    let mut shortest = f64::INFINITY;
    for e in mesh.elements.chunks(mesh.dim) {
        for k in 0..mesh.dim {
            let d = sub(v(e[k]), v(e[(k + 1) % mesh.dim]));
            shortest = shortest.min(dot(d, d).sqrt());
        }
    }
    shortest
}

/// A random vector of length at most `max_len` (3-D; z zeroed in 2-D).
fn random_shift(rng: &mut Rng, max_len: f64, dim: usize) -> [f64; 3] {
    loop {
        let mut d = [
            rng.uniform(-1.0, 1.0),
            rng.uniform(-1.0, 1.0),
            rng.uniform(-1.0, 1.0),
        ];
        if dim == 2 {
            d[2] = 0.0;
        }
        let len = dot(d, d).sqrt();
        if len > 0.1 && len <= 1.0 {
            return d.map(|x| x * max_len);
        }
    }
}

/// `mesh` with every vertex moved by its own random vector of length at most `max_len`.
fn jitter(rng: &mut Rng, mesh: &Mesh, max_len: f64) -> Mesh {
    let mut out = mesh.clone();
    let dim = mesh.dim;
    for x in out.vertices.chunks_mut(dim) {
        let d = random_shift(rng, max_len, dim);
        for k in 0..dim {
            x[k] += d[k];
        }
    }
    out
}

fn bodies_3d() -> Vec<(&'static str, Mesh)> {
    vec![
        ("sphere", sphere_mesh([0.5, 0.48, 0.52], 0.3, 14, 28)),
        ("torus", torus_mesh([0.5, 0.5, 0.5], 0.28, 0.1, 32, 12)),
        ("box", box_mesh([0.21, 0.33, 0.25], [0.77, 0.61, 0.7])),
    ]
}

fn shapes_2d() -> Vec<(&'static str, Mesh)> {
    let mut two = disc_mesh([0.3, 0.3], 0.15, 17, 0.0);
    two.append(
        &loop_mesh(&[[0.55, 0.5], [0.9, 0.52], [0.85, 0.9], [0.6, 0.8]]),
        1,
    );
    vec![("disc", disc_mesh([0.5, 0.5], 0.3, 40, 0.1)), ("two", two)]
}

#[test]
fn translations_3d_sweep_normal_displacement_per_subface() {
    let grid = Grid::new(&[0.0; 3], &[1.0; 3], &[14, 12, 13]).unwrap();
    let dx = 1.0 / 12.0;
    let mut rng = Rng(7);
    let mut worst = Report::default();
    for (name, body) in bodies_3d() {
        for case in 0..6 {
            let d = random_shift(&mut rng, dx, 3);
            let after = body.map(|p| [p[0] + d[0], p[1] + d[1], p[2] + d[2]]);
            // NOTE: `before` is `after − d` as the map computes it; the identities use `d`, off by
            // round-off of the coordinates only.
            let r = check(&grid, &body, &after, Some(d));
            assert!(r.n_subfaces > 100);
            assert_report(&r, &format!("{name} case {case}"));
            worst = worst.worst(r);
        }
    }
    eprintln!("3-D translations: {worst}");
}

#[test]
fn box_on_grid_planes_translated_3d() {
    // At t^{n+1} every face lies in a grid plane and every vertex on a grid node.
    let grid = Grid::new(&[0.0; 3], &[1.0; 3], &[8; 3]).unwrap();
    let after = box_mesh([0.25, 0.375, 0.25], [0.625, 0.75, 0.5]);
    let mut worst = Report::default();
    for d in [[0.05, -0.03, 0.07], [-0.125, 0.0, 0.0], [0.1, 0.11, -0.09]] {
        let before = after.map(|p| [p[0] - d[0], p[1] - d[1], p[2] - d[2]]);
        let r = check(&grid, &before, &after, Some(d));
        assert_report(&r, &format!("box {d:?}"));
        worst = worst.worst(r);
    }
    eprintln!("box on grid planes: {worst}");
}

#[test]
fn rigid_motions_and_deformations_3d_conserve() {
    let grid = Grid::new(&[0.0; 3], &[1.0; 3], &[14, 12, 13]).unwrap();
    let dx = 1.0 / 12.0;
    let mut rng = Rng(2025);
    let mut worst = Report::default();
    for (name, body) in bodies_3d() {
        let edge = shortest_edge(&body);
        for case in 0..4 {
            let axis = random_shift(&mut rng, 1.0, 3);
            let r = rotation(axis, rng.uniform(-0.5, 0.5) * dx / 0.35);
            let shift = random_shift(&mut rng, 0.5 * dx, 3);
            let after = body.map(|p| rigid(p, &r, [0.5; 3], shift));
            let rep = check(&grid, &body, &after, None);
            assert_conserves(&rep, &format!("{name} rigid {case}"));
            worst = worst.worst(rep);
            // NOTE: the jitter stays below a quarter of the shortest edge so that the surface
            // stays embedded (a fold makes Λ, hence (a), meaningless for any swept volume).
            let shift = random_shift(&mut rng, 0.8 * dx, 3);
            let moved = body.map(|p| [p[0] + shift[0], p[1] + shift[1], p[2] + shift[2]]);
            let after = jitter(&mut rng, &moved, (0.25 * edge).min(0.6 * dx));
            let rep = check(&grid, &body, &after, None);
            assert_conserves(&rep, &format!("{name} deformation {case}"));
            worst = worst.worst(rep);
        }
        // A smooth deformation of up to 0.9 cell (that of tests/it/cutcell_swept.rs).
        let amp = 0.9 * dx;
        let after = body.map(|p| {
            [
                p[0] + amp * (2.0 * p[1] + 0.3).sin() * 0.7,
                p[1] + amp * (-p[2] + 3.0 * p[0]).cos() * 0.7,
                p[2] + amp * (0.5 * p[0] * p[1] + 4.0).sin() * 0.7,
            ]
        });
        let rep = check(&grid, &body, &after, None);
        assert_conserves(&rep, &format!("{name} smooth deformation"));
        worst = worst.worst(rep);
    }
    eprintln!("3-D rigid motions and deformations: {worst}");
}

#[test]
fn motions_2d_conserve_and_translations_sweep_normal_displacement() {
    let grid = Grid::new(&[0.0, 0.0], &[1.0, 1.0], &[23, 19]).unwrap();
    let dx = 1.0 / 19.0;
    let mut rng = Rng(11);
    let mut translations = Report::default();
    let mut others = Report::default();
    for (name, shape) in shapes_2d() {
        let edge = shortest_edge(&shape);
        for case in 0..6 {
            let d = random_shift(&mut rng, dx, 2);
            let after = shape.map(|p| [p[0] + d[0], p[1] + d[1], 0.0]);
            let r = check(&grid, &shape, &after, Some(d));
            assert_report(&r, &format!("{name} translation {case}"));
            translations = translations.worst(r);
            let rot = rotation([0.0, 0.0, 1.0], rng.uniform(-1.0, 1.0) * dx / 0.4);
            let shift = random_shift(&mut rng, 0.5 * dx, 2);
            let after = shape.map(|p| rigid(p, &rot, [0.5, 0.5, 0.0], shift));
            let r = check(&grid, &shape, &after, None);
            assert_conserves(&r, &format!("{name} rigid {case}"));
            others = others.worst(r);
            let shift = random_shift(&mut rng, 0.8 * dx, 2);
            let moved = shape.map(|p| [p[0] + shift[0], p[1] + shift[1], 0.0]);
            let after = jitter(&mut rng, &moved, (0.25 * edge).min(0.6 * dx));
            let r = check(&grid, &shape, &after, None);
            assert_conserves(&r, &format!("{name} deformation {case}"));
            others = others.worst(r);
        }
    }
    eprintln!("2-D translations: {translations}");
    eprintln!("2-D rigid motions and deformations: {others}");
}

#[test]
fn non_finite_input_skips_subfaces() {
    let grid = Grid::new(&[0.0; 3], &[1.0; 3], &[9; 3]).unwrap();
    let after = sphere_mesh([0.5, 0.5, 0.5], 0.3, 8, 16);
    let mut before = after.map(|p| [p[0] - 0.02, p[1], p[2] + 0.01]);
    before.vertices[0] = f64::NAN; // the north pole
    let with_pole: Vec<bool> = after.elements.chunks(3).map(|e| e.contains(&0)).collect();
    let mut g1 = CutGeometry::new();
    compute(&grid, &after.surface(), &mut g1);
    let mut out = SubfaceSwept::new();
    subface_swept_volumes(&grid, &before.surface(), &after.surface(), &g1, &mut out);
    let expected = g1
        .subfaces
        .iter()
        .filter(|s| with_pole[s.element as usize])
        .count();
    assert!(expected > 0);
    assert_eq!(out.n_skipped_subfaces, expected);
    assert!(out.entries.iter().all(|e| e.volume.is_finite()));
    // A geometry of another surface: its sub-faces do not match and are skipped, no panic.
    let other = after.map(|p| [p[0] + 0.013, p[1], p[2]]);
    let mut g_other = CutGeometry::new();
    compute(&grid, &other.surface(), &mut g_other);
    subface_swept_volumes(
        &grid,
        &after.surface(),
        &after.surface(),
        &g_other,
        &mut out,
    );
    assert_eq!(out.n_skipped_subfaces, g_other.subfaces.len());
    assert!(out.entries.is_empty());
}

#[test]
fn reversed_twin_cancels_in_every_cell() {
    let grid = Grid::new(&[0.0; 3], &[1.0; 3], &[7; 3]).unwrap();
    let vertices = [0.1, 0.2, 0.3, 0.8, 0.25, 0.4, 0.3, 0.85, 0.6];
    let moved: Vec<f64> = vertices
        .iter()
        .enumerate()
        .map(|(i, x)| x + [0.05, -0.03, 0.11][i % 3] * (1.0 + 0.3 * i as f64))
        .collect();
    let mut acc = vec![0.0; grid.n_cells()];
    let mut n_entries = 0;
    for elements in [[0, 1, 2], [0, 2, 1]] {
        let surface = |v| Surface {
            dim: 3,
            vertices: v,
            elements: &elements,
            element_particle: &[],
        };
        let mut g1 = CutGeometry::new();
        compute(&grid, &surface(&moved), &mut g1);
        let mut out = SubfaceSwept::new();
        subface_swept_volumes(&grid, &surface(&vertices), &surface(&moved), &g1, &mut out);
        out.accumulate(&mut acc);
        n_entries = out.entries.len();
    }
    assert!(n_entries > 4, "the sub-prisms cross several cells");
    let worst = acc.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    assert!(worst <= 1e-16, "twins cancel: {worst:.2e}");
}

#[test]
fn piece_counts_of_the_bench_sphere() {
    // The sphere of benches/cutcell.rs (mesh refined with the grid, moved by 0.16 cell).
    for n in [32, 64] {
        let grid = Grid::new(&[0.0; 3], &[1.0; 3], &[n; 3]).unwrap();
        let before = sphere_mesh([0.5013, 0.4987, 0.5021], 0.3, n / 2, n);
        let shift = [0.11, -0.07, 0.09].map(|d| d / n as f64);
        let after = before.map(|p| [p[0] + shift[0], p[1] + shift[1], p[2] + shift[2]]);
        let mut g1 = CutGeometry::new();
        compute(&grid, &after.surface(), &mut g1);
        let mut swept = SweptVolumes::new();
        swept_volumes(&grid, &before.surface(), &after.surface(), &mut swept);
        let mut sub = SubfaceSwept::new();
        subface_swept_volumes(&grid, &before.surface(), &after.surface(), &g1, &mut sub);
        let r = check(&grid, &before, &after, Some(shift));
        assert_report(&r, &format!("bench sphere n {n}"));
        eprintln!(
            "n {n}: {} triangles, {} sub-faces; pieces: compute {}, swept_volumes {} ({} entries), \
             subface_swept_volumes {} ({} entries), ratio {:.2}; {r}",
            after.n_elements(),
            g1.subfaces.len(),
            g1.diagnostics.n_pieces,
            swept.n_pieces,
            swept.entries.len(),
            sub.n_pieces,
            sub.entries.len(),
            sub.n_pieces as f64 / swept.n_pieces as f64
        );
        assert!(sub.n_pieces > swept.n_pieces);
    }
}

/// The prisms are clipped in parallel by runs of sub-faces (issue 36 item 4): on pools of 1, 2
/// and 5 threads, and again into buffers that held a larger surface, the entries (sub-face,
/// cell, volume bits) and counters are those of one thread, on the 64³ bench sphere (26 602
/// sub-faces, 208 runs) and a 2-D disc (520 sub-faces, 5 runs).
#[test]
fn the_entries_are_the_same_on_any_number_of_threads() {
    let entries = |sub: &SubfaceSwept| {
        sub.entries
            .iter()
            .map(|e| (e.subface, e.cell, e.volume.to_bits()))
            .collect::<Vec<_>>()
    };
    let n = 64;
    let grid3 = Grid::new(&[0.0; 3], &[1.0; 3], &[n; 3]).unwrap();
    let before3 = sphere_mesh([0.5013, 0.4987, 0.5021], 0.3, n / 2, n);
    let shift = [0.11, -0.07, 0.09].map(|d| d / n as f64);
    let after3 = before3.map(|p| [p[0] + shift[0], p[1] + shift[1], p[2] + shift[2]]);
    let grid2 = Grid::new(&[0.0; 2], &[1.0; 2], &[200; 2]).unwrap();
    let before2 = shapes_2d().remove(0).1;
    let after2 = before2.map(|p| [p[0] + 0.0013, p[1] - 0.0021, p[2]]);
    for (grid, before, after) in [(&grid3, &before3, &after3), (&grid2, &before2, &after2)] {
        let mut g1 = CutGeometry::new();
        compute(grid, &after.surface(), &mut g1);
        let run = |threads: usize, sub: &mut SubfaceSwept| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| {
                    subface_swept_volumes(grid, &before.surface(), &after.surface(), &g1, sub)
                });
        };
        let mut one = SubfaceSwept::new();
        run(1, &mut one);
        assert!(g1.subfaces.len() > 100 && !one.entries.is_empty());
        for threads in [2, 5] {
            let mut many = SubfaceSwept::new();
            run(threads, &mut many);
            assert_eq!(entries(&many), entries(&one), "{threads} threads");
            assert_eq!(
                (many.n_pieces, many.n_skipped_subfaces),
                (one.n_pieces, one.n_skipped_subfaces)
            );
        }
        // Buffers of the 3-D sphere reused for this surface (fewer runs than buffers).
        let mut reused = SubfaceSwept::new();
        run(2, &mut reused);
        let mut g_big = CutGeometry::new();
        compute(&grid3, &after3.surface(), &mut g_big);
        rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap()
            .install(|| {
                subface_swept_volumes(
                    &grid3,
                    &before3.surface(),
                    &after3.surface(),
                    &g_big,
                    &mut reused,
                )
            });
        run(2, &mut reused);
        assert_eq!(entries(&reused), entries(&one));
    }
}

/// The elements are clipped in parallel by runs, and the y and z sweeps run together (issue 36
/// item 4): on pools of 1, 2 and 5 threads, and again into buffers that held a larger surface,
/// `compute` gives the bits of one thread (Λ, λ, sub-faces, their vertices, cut cells,
/// diagnostics), on the 64³ bench sphere (3 968 triangles, 16 runs) and a 2-D disc of 700
/// segments (3 runs).
#[test]
fn the_geometry_is_the_same_on_any_number_of_threads() {
    let n = 64;
    let grid3 = Grid::new(&[0.0; 3], &[1.0; 3], &[n; 3]).unwrap();
    let sphere = sphere_mesh([0.5013, 0.4987, 0.5021], 0.3, n / 2, n);
    let grid2 = Grid::new(&[0.0; 2], &[1.0; 2], &[200; 2]).unwrap();
    let disc = disc_mesh([0.5, 0.5], 0.3, 700, 0.1);
    let bits = |g: &CutGeometry| {
        let f = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<u64>>();
        (
            f(&g.solid_fraction),
            g.face_fraction.iter().map(|v| f(v)).collect::<Vec<_>>(),
            format!("{:?} {:?}", g.subfaces, g.subface_vertices),
            g.cut_cells.clone(),
            format!("{:?}", g.diagnostics),
        )
    };
    let on = |threads: usize, grid: &Grid, mesh: &Mesh, geom: &mut CutGeometry| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| compute(grid, &mesh.surface(), geom));
    };
    for (grid, mesh) in [(&grid3, &sphere), (&grid2, &disc)] {
        let mut one = CutGeometry::new();
        on(1, grid, mesh, &mut one);
        assert!(mesh.surface().n_elements() > 300 && one.subfaces.len() > 300);
        for threads in [2, 5] {
            let mut many = CutGeometry::new();
            on(threads, grid, mesh, &mut many);
            assert!(bits(&many) == bits(&one), "{threads} threads");
        }
        // Buffers of the sphere reused for this surface (fewer runs than buffers).
        let mut reused = CutGeometry::new();
        on(2, &grid3, &sphere, &mut reused);
        on(2, grid, mesh, &mut reused);
        assert!(bits(&reused) == bits(&one), "reused buffers");
    }
}

/// Issue 35: an internal face of a 3-D tube lying on the grid plane `x = 0.5` up to round-off
/// (vertices at `0.5 ± 1 ulp`), its particle moving 6e-8 m within the plane (the element and
/// motion of the tube's step 6, bit for bit). Each sub-face's prism stays in the cells beside it
/// and sweeps no more than its area times the motion. Before the polygon split kept its signs
/// monotone, the prism of the sub-face in cell [16, 24, 9] put -1.9e-6 m^3 (6 % of a cell) into
/// every cell of its row from i = 16 to 31, and the run stopped ("the solid moved too far").
#[test]
fn a_prism_lying_in_a_grid_plane_stays_beside_its_subface() {
    let grid = Grid::new(&[0.0; 3], &[1.0; 3], &[32, 32, 32]).unwrap();
    let before: [f64; 9] = [
        0.5,
        0.7749998882522705,
        0.2750001869145612,
        0.4999999999999999,
        0.7499998588799534,
        0.35000011482675203,
        0.5000000000000002,
        0.7999998588799433,
        0.3500001032199721,
    ];
    let after: [f64; 9] = [
        0.5,
        0.7749998514827174,
        0.27500024031583264,
        0.49999999999999994,
        0.74999979720321,
        0.35000015801116524,
        0.5000000000000007,
        0.7999997972031749,
        0.35000013742789965,
    ];
    let surface = |vertices| Surface {
        dim: 3,
        vertices,
        elements: &[0, 1, 2],
        element_particle: &[0],
    };
    let motion = (0..9)
        .map(|k| (after[k] - before[k]).abs())
        .fold(0.0, f64::max);
    let mut g1 = CutGeometry::new();
    compute(&grid, &surface(&after), &mut g1);
    let mut out = SubfaceSwept::new();
    subface_swept_volumes(&grid, &surface(&before), &surface(&after), &g1, &mut out);
    assert_eq!(out.n_skipped_subfaces, 0);
    assert_eq!(g1.subfaces.len(), 12);
    let mut swept = vec![0.0; g1.subfaces.len()];
    for e in &out.entries {
        let s = &g1.subfaces[e.subface as usize];
        let (a, b) = (grid.ijk(s.cell as usize), grid.ijk(e.cell as usize));
        let reach = (0..3).map(|k| a[k].abs_diff(b[k])).max().unwrap();
        assert!(
            reach <= 1,
            "sub-face in {a:?} sweeps {:e} m^3 in {b:?}",
            e.volume
        );
        swept[e.subface as usize] += e.volume.abs();
    }
    for (s, v) in g1.subfaces.iter().zip(&swept) {
        // 3 |d| A: the motion is within the plane (the prism is ~1e-16 m thick), any bound of
        // the order of the motion would do.
        assert!(
            *v <= 3.0 * motion * s.area,
            "{v:e} m^3 for {:e} m^2",
            s.area
        );
    }
}
