//! The fluid's VTK XML image data (`.vti`), read back with `protocol::vtk::read`: a 2-D vortex
//! and a 3-D two-state box give back every cell's ρ, p, α and velocity bit for bit, and VTK's
//! cell order (x fastest from `Origin` in steps of `Spacing`) puts each value at its cell's
//! centre.

use fluid_node::fv::FluidSolver;
use fluid_node::output::fluid_vti;
use protocol::scene::Scene;
use protocol::vtk::read;

const GAMMA: f64 = 1.4;

fn solver(text: &str) -> FluidSolver {
    let scene = Scene::from_toml_str(text, "test").expect("valid scene");
    FluidSolver::from_scene(scene.fluid.as_ref().expect("fluid"), 1).expect("solver")
}

fn words(text: &str) -> Vec<f64> {
    text.split(' ')
        .map(|w| w.parse().expect("a number"))
        .collect()
}

/// Writes the solver's state with a fluid fraction that differs in every cell, reads it back
/// and compares; returns the number of cells.
fn check(s: &FluidSolver) -> usize {
    let grid = s.grid();
    let n = grid.n_cells();
    // Every third cell covered (fluid fraction 0): hidden by `vtkGhostType`.
    let alpha: Vec<f64> = (0..n)
        .map(|i| {
            if i % 3 == 0 {
                0.0
            } else {
                (i as f64 + 0.5) / n as f64
            }
        })
        .collect();
    let file =
        read::parse(&fluid_vti(grid, s.state(), GAMMA, Some(&alpha), "test")).expect("decodes");
    assert_eq!(file.kind, "ImageData");
    let extent: Vec<usize> = file.dataset["WholeExtent"]
        .split(' ')
        .map(|w| w.parse().expect("extent"))
        .collect();
    // Inactive axes are flat: one layer of points (extent 0 0), one cell.
    let cells = [extent[1].max(1), extent[3].max(1), extent[5].max(1)];
    assert_eq!(cells, grid.cells);
    for a in grid.dim..3 {
        assert_eq!(extent[2 * a + 1], 0, "axis {a} is flat");
    }
    assert_eq!(cells.iter().product::<usize>(), n);
    let (origin, spacing) = (
        words(&file.dataset["Origin"]),
        words(&file.dataset["Spacing"]),
    );
    let get = |name: &str, components: usize| {
        let a = file.array("CellData", name).expect(name);
        assert_eq!(a.components, components, "{name}");
        a.as_f64().expect("Float64").to_vec()
    };
    let (rho, p, alpha_read, velocity) = (
        get("rho", 1),
        get("p", 1),
        get("alpha", 1),
        get("velocity", 3),
    );
    let ghost = match &file
        .array("CellData", "vtkGhostType")
        .expect("ghost")
        .values
    {
        protocol::vtk::Values::UInt8(g) => g.clone(),
        other => panic!("vtkGhostType is {}", other.type_name()),
    };
    for idx in 0..n {
        // vtkDataSetAttributes::HIDDENCELL where the solid covers the cell, else a plain cell.
        assert_eq!(
            ghost[idx],
            if idx % 3 == 0 { 32 } else { 0 },
            "ghost of cell {idx}"
        );
        let (r, v, pressure) = s.state().primitive(idx, GAMMA);
        assert_eq!(rho[idx].to_bits(), r.to_bits(), "rho of cell {idx}");
        assert_eq!(p[idx].to_bits(), pressure.to_bits(), "p of cell {idx}");
        assert_eq!(
            alpha_read[idx].to_bits(),
            alpha[idx].to_bits(),
            "alpha of cell {idx}"
        );
        for d in 0..3 {
            assert_eq!(
                velocity[3 * idx + d].to_bits(),
                v[d].to_bits(),
                "velocity of cell {idx}"
            );
        }
        // VTK's cell idx is (i, j, k) with i fastest; its centre is origin + (i + 1/2) spacing.
        let ijk = [
            idx % cells[0],
            (idx / cells[0]) % cells[1],
            idx / (cells[0] * cells[1]),
        ];
        let centre = grid.cell_center(grid.ijk(idx));
        for d in 0..grid.dim {
            let vtk_centre = origin[d] + (ijk[d] as f64 + 0.5) * spacing[d];
            assert!(
                (vtk_centre - centre[d]).abs() <= 1e-12 * (1.0 + centre[d].abs()),
                "cell {idx} axis {d}: VTK puts it at {vtk_centre}, the grid at {}",
                centre[d]
            );
        }
    }
    n
}

#[test]
fn a_2d_vortex_round_trips_bit_for_bit() {
    let s = solver(
        r#"name = "vortex"
[fluid]
lower = [0.0, -1.0]
upper = [10.0, 8.0]
cells = [12, 9]
boundary = { x = ["periodic", "periodic"], y = ["periodic", "periodic"] }
[fluid.profile]
isentropic_vortex = { beta = 5.0, center = [5.0, 3.5], velocity = [1.0, 0.5] }
"#,
    );
    // The vortex makes every cell differ; a writer that swapped axes or arrays would show.
    let (r0, _, _) = s.state().primitive(0, GAMMA);
    assert!((1..108).any(|i| s.state().primitive(i, GAMMA).0 != r0));
    assert_eq!(check(&s), 108);
}

#[test]
fn a_3d_two_state_box_round_trips_bit_for_bit() {
    let s = solver(
        r#"name = "box"
[fluid]
lower = [0.0, 0.0, -0.5]
upper = [2.0, 2.5, 1.5]
cells = [7, 5, 4]
boundary = { x = ["wall", "wall"], y = ["wall", "wall"], z = ["wall", "wall"] }
[[fluid.init]]
region = "all"
rho = 1.4
p = 1.0
velocity = [0.1, 0.2, 0.3]
[[fluid.init]]
region = { box = { lower = [0.0, 0.0, -0.5], upper = [1.0, 1.2, 0.5] } }
rho = 8.0
p = 116.5
velocity = [-1.0, 2.0, 3.0]
"#,
    );
    let n_dense = (0..140)
        .filter(|&i| s.state().primitive(i, GAMMA).0 == 8.0)
        .count();
    assert!(n_dense > 0 && n_dense < 140, "{n_dense}");
    assert_eq!(check(&s), 140);
}
