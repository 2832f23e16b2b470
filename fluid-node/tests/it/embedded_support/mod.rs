//! Shared pieces of the embedded-solid tests: scenes, rigid bodies as wet surfaces, and one
//! coupled step of a solid whose motion is prescribed.

#![allow(dead_code, unreachable_pub, clippy::needless_range_loop)]

use fluid_node::embedded::{Embedded, SolidFrame};
use fluid_node::fv::FluidSolver;
use protocol::scene::Scene;

/// A fluid solver from the `[fluid]` table of a scene text.
pub fn solver(toml: &str) -> FluidSolver {
    let scene = Scene::from_toml_str(toml, "test.toml").expect("scene");
    FluidSolver::from_scene(scene.fluid.as_ref().expect("[fluid]"), 1).expect("solver")
}

/// The scene text of gas at rest (ρ = 1, p = 1, γ = 1.4) in the unit square or cube with walls
/// on every side, `cells` cells (2 or 3 of them), OSMP of order 3, CFL 0.5.
pub fn at_rest_in_unit_box(name: &str, cells: &[usize]) -> String {
    let dim = cells.len();
    let list = |v: &str| vec![v; dim].join(", ");
    let cells: Vec<String> = cells.iter().map(usize::to_string).collect();
    let walls: Vec<String> = ["x", "y", "z"][..dim]
        .iter()
        .map(|a| format!(r#"{a} = ["wall", "wall"]"#))
        .collect();
    format!(
        r#"
name = "{name}"
[fluid]
gamma = 1.4
cfl = 0.5
flux = {{ scheme = "osmp", order = 3 }}
lower = [{}]
upper = [{}]
cells = [{}]
boundary = {{ {} }}
[[fluid.init]]
region = "all"
rho = 1.0
p = 1.0
"#,
        list("0.0"),
        list("1.0"),
        cells.join(", "),
        walls.join(", ")
    )
}

/// The scene text of gas at rest (ρ = p = 1) in a 2-D channel with slip walls, `length` along
/// `axis` on `n` cells and `width` across on `n_across` cells.
pub fn channel(axis: usize, length: f64, width: f64, n: usize, n_across: usize) -> String {
    let across = 1 - axis;
    let (mut upper, mut cells) = ([0.0; 2], [0; 2]);
    upper[axis] = length;
    upper[across] = width;
    cells[axis] = n;
    cells[across] = n_across;
    format!(
        r#"
        name = "channel"
        [fluid]
        lower = [0.0, 0.0]
        upper = [{}, {}]
        cells = [{}, {}]
        boundary = {{ x = ["wall", "wall"], y = ["wall", "wall"] }}
        [[fluid.init]]
        region = "all"
        rho = 1.0
        p = 1.0
        "#,
        upper[0], upper[1], cells[0], cells[1]
    )
}

/// A rigid 2-D polygon (counter-clockwise vertices) as one particle with its wet loop.
pub fn polygon_2d(vertices: &[[f64; 2]], velocity: [f64; 2], omega: f64) -> SolidFrame {
    let n = vertices.len();
    let area2: f64 = (0..n)
        .map(|i| {
            let (a, b) = (vertices[i], vertices[(i + 1) % n]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum();
    let (mut cx, mut cy) = (0.0, 0.0);
    for i in 0..n {
        let (a, b) = (vertices[i], vertices[(i + 1) % n]);
        let w = a[0] * b[1] - b[0] * a[1];
        cx += (a[0] + b[0]) * w;
        cy += (a[1] + b[1]) * w;
    }
    cx /= 3.0 * area2;
    cy /= 3.0 * area2;
    SolidFrame {
        dim: 2,
        position: vec![cx, cy],
        velocity: velocity.to_vec(),
        angular_velocity: vec![omega],
        vertices: vertices.iter().flatten().copied().collect(),
        elements: (0..n as u32)
            .flat_map(|i| [i, (i + 1) % n as u32])
            .collect(),
        element_particle: vec![0; n],
        wet: vec![true; n],
    }
}

/// A rigid 3-D box (centre, half sizes) rotated by `rotation` (rows), as one particle.
pub fn box_3d(
    center: [f64; 3],
    half: [f64; 3],
    rotation: [[f64; 3]; 3],
    velocity: [f64; 3],
) -> SolidFrame {
    let mut vertices = Vec::new();
    for k in 0..8 {
        let s = [
            if k & 1 == 0 { -1.0 } else { 1.0 },
            if k & 2 == 0 { -1.0 } else { 1.0 },
            if k & 4 == 0 { -1.0 } else { 1.0 },
        ];
        let local = [s[0] * half[0], s[1] * half[1], s[2] * half[2]];
        for r in &rotation {
            vertices.push(0.0);
            let last = vertices.len() - 1;
            vertices[last] = r[0] * local[0] + r[1] * local[1] + r[2] * local[2];
        }
        let base = vertices.len() - 3;
        for a in 0..3 {
            vertices[base + a] += center[a];
        }
    }
    // Faces as quads (outward, counter-clockwise seen from outside), split into triangles.
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let mut elements = Vec::new();
    for q in quads {
        elements.extend_from_slice(&[q[0], q[1], q[2], q[0], q[2], q[3]]);
    }
    let ne = elements.len() / 3;
    SolidFrame {
        dim: 3,
        position: center.to_vec(),
        velocity: velocity.to_vec(),
        angular_velocity: vec![0.0; 3],
        vertices,
        elements,
        element_particle: vec![0; ne],
        wet: vec![true; ne],
    }
}

/// A rotation by `angle` about the unit axis `axis` (rows of the matrix).
pub fn rotation(axis: [f64; 3], angle: f64) -> [[f64; 3]; 3] {
    let (s, c) = angle.sin_cos();
    let [x, y, z] = axis;
    [
        [
            c + x * x * (1.0 - c),
            x * y * (1.0 - c) - z * s,
            x * z * (1.0 - c) + y * s,
        ],
        [
            y * x * (1.0 - c) + z * s,
            c + y * y * (1.0 - c),
            y * z * (1.0 - c) - x * s,
        ],
        [
            z * x * (1.0 - c) - y * s,
            z * y * (1.0 - c) + x * s,
            c + z * z * (1.0 - c),
        ],
    ]
}

/// The frame translated by `velocity · dt` (the same velocity kept as the mid-step velocity).
pub fn translated(frame: &SolidFrame, dt: f64) -> SolidFrame {
    let d = frame.dim;
    let mut next = frame.clone();
    for (k, x) in next.position.iter_mut().enumerate() {
        *x += dt * frame.velocity[k % d];
    }
    for (k, x) in next.vertices.iter_mut().enumerate() {
        *x += dt * frame.velocity[k % d];
    }
    next
}

/// One coupled step with a prescribed next frame: predict, loads on `F^n`, correct.
pub fn step(
    solver: &mut FluidSolver,
    embedded: &mut Embedded,
    dt: f64,
    next: SolidFrame,
    step: u64,
) -> fluid_node::embedded::Loads {
    let report = embedded.predict(solver, dt);
    assert!(report.ok(), "predict: {:?}", report.troubles);
    let current = embedded.surface().clone();
    let loads = embedded.loads(solver, &current).expect("loads");
    embedded
        .correct(solver, dt, next, step, false)
        .unwrap_or_else(|e| panic!("correct: {e}"));
    loads
}

/// Largest |velocity component| and largest |p − p0| over the cells holding fluid.
pub fn deviation(solver: &FluidSolver, embedded: &Embedded, p0: f64, u0: [f64; 3]) -> (f64, f64) {
    let lambda = embedded.solid_fraction();
    let (mut du, mut dp) = (0.0f64, 0.0f64);
    for c in 0..solver.grid().n_cells() {
        if lambda[c] >= 1.0 {
            continue;
        }
        let (_, u, p) = solver.primitive(c);
        for a in 0..solver.grid().dim {
            du = du.max((u[a] - u0[a]).abs());
        }
        dp = dp.max((p - p0).abs());
    }
    (du, dp)
}
