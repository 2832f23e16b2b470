//! Shared helpers of the `fv_*` integration tests: Riemann test cases, solver construction on
//! 1-D, planar 2-D/3-D and diagonal 2-D grids, L1 errors against the exact solution.

#![allow(dead_code, unreachable_pub)]

use fluid_node::fv::exact_riemann::{ExactRiemann, Prim1};
use fluid_node::fv::{BoundaryKind, FluidParams, FluidSolver, FluidState, FluxKind, init};
use fluid_node::grid::Grid;

/// A Riemann problem on [0, 1] (numerics.md §4.2).
#[derive(Clone, Copy, Debug)]
pub struct Case {
    pub name: &'static str,
    pub left: (f64, f64, f64),
    pub right: (f64, f64, f64),
    pub x0: f64,
    pub t_end: f64,
}

pub const SOD: Case = Case {
    name: "sod",
    left: (1.0, 0.0, 1.0),
    right: (0.125, 0.0, 0.1),
    x0: 0.5,
    t_end: 0.2,
};
pub const LAX: Case = Case {
    name: "lax",
    left: (0.445, 0.698, 3.528),
    right: (0.5, 0.0, 0.571),
    x0: 0.5,
    t_end: 0.13,
};
pub const TORO_123: Case = Case {
    name: "toro-123",
    left: (1.0, -2.0, 0.4),
    right: (1.0, 2.0, 0.4),
    x0: 0.5,
    t_end: 0.15,
};
pub const TORO_3: Case = Case {
    name: "toro-3",
    left: (1.0, 0.0, 1000.0),
    right: (1.0, 0.0, 0.01),
    x0: 0.5,
    t_end: 0.012,
};
pub const CASES: [Case; 4] = [SOD, LAX, TORO_123, TORO_3];

impl Case {
    pub fn exact(&self) -> ExactRiemann {
        let p = |s: (f64, f64, f64)| Prim1 {
            rho: s.0,
            u: s.1,
            p: s.2,
        };
        ExactRiemann::new(p(self.left), p(self.right), 1.4).expect("test data are physical")
    }
}

/// How the 1-D problem is laid on the grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Layout {
    /// 1-D grid of N cells.
    OneD,
    /// `dim`-D grid, N cells along `axis`, 4 periodic cells of the same width across.
    Axis { dim: usize, axis: usize },
    /// 2-D 2N×2N grid of [0,2]², normal (1,1)/√2 through the centre, outflow everywhere; the
    /// L1 error is taken over the central square [0.5,1.5]² (out of reach of the boundary
    /// disturbances by the end time) per unit length of front (÷ √2).
    Diagonal,
}

pub fn params(dim: usize, flux: FluxKind, bc: [[BoundaryKind; 2]; 3]) -> FluidParams {
    let _ = dim;
    FluidParams {
        gamma: 1.4,
        cfl: 0.5,
        flux,
        boundary: bc,
        vacuum_rho: 1e-10,
        vacuum_p: 1e-10,
    }
}

pub struct Setup {
    pub grid: Grid,
    pub normal: [f64; 3],
    pub xi0: f64,
    /// Measure across the normal (L1 per unit transverse measure).
    pub transverse: f64,
}

pub fn setup(case: &Case, n: usize, layout: Layout) -> (Setup, [[BoundaryKind; 2]; 3]) {
    use BoundaryKind::*;
    let dx = 1.0 / n as f64;
    match layout {
        Layout::OneD => (
            Setup {
                grid: Grid::new(&[0.0], &[1.0], &[n]).expect("grid"),
                normal: [1.0, 0.0, 0.0],
                xi0: case.x0,
                transverse: 1.0,
            },
            [[Outflow; 2]; 3],
        ),
        Layout::Axis { dim, axis } => {
            let mut lower = vec![0.0; dim];
            let mut upper = vec![4.0 * dx; dim];
            let mut cells = vec![4; dim];
            upper[axis] = 1.0;
            lower[axis] = 0.0;
            cells[axis] = n;
            let mut bc = [[Periodic; 2]; 3];
            bc[axis] = [Outflow; 2];
            let mut normal = [0.0; 3];
            normal[axis] = 1.0;
            (
                Setup {
                    grid: Grid::new(&lower, &upper, &cells).expect("grid"),
                    normal,
                    xi0: case.x0,
                    transverse: (4.0 * dx).powi(dim as i32 - 1),
                },
                bc,
            )
        }
        Layout::Diagonal => {
            let s = std::f64::consts::FRAC_1_SQRT_2;
            (
                Setup {
                    grid: Grid::new(&[0.0, 0.0], &[2.0, 2.0], &[2 * n, 2 * n]).expect("grid"),
                    normal: [s, s, 0.0],
                    xi0: 2.0 * s,
                    transverse: std::f64::consts::SQRT_2,
                },
                [[Outflow; 2]; 3],
            )
        }
    }
}

pub struct RunResult {
    pub l1: f64,
    pub min_rho: f64,
    pub min_p: f64,
    pub steps: u64,
    pub solver: FluidSolver,
    pub ok: bool,
}

/// Runs `case` to its end time and returns the L1 density error against the exact cell
/// averages (per unit transverse measure).
pub fn run_case(
    case: &Case,
    n: usize,
    flux: FluxKind,
    layout: Layout,
    threads: usize,
) -> RunResult {
    let ex = case.exact();
    let (s, bc) = setup(case, n, layout);
    let grid = s.grid.clone();
    let mut state = FluidState::zeros(grid.dim, grid.n_cells());
    init::riemann_planar(&mut state, &grid, &ex, s.normal, s.xi0, 0.0);
    let mut solver =
        FluidSolver::new(grid.clone(), params(grid.dim, flux, bc), state, threads).expect("solver");
    let mut min_rho = f64::INFINITY;
    let mut min_p = f64::INFINITY;
    let mut steps = 0;
    let mut ok = true;
    while solver.time() < case.t_end * (1.0 - 1e-14) {
        let dt = solver.max_dt().min(case.t_end - solver.time());
        let rep = solver.advance(dt);
        steps += 1;
        if !rep.ok() {
            ok = false;
            break;
        }
        for idx in 0..grid.n_cells() {
            let (rho, _, p) = solver.primitive(idx);
            min_rho = min_rho.min(rho);
            min_p = min_p.min(p);
        }
    }
    let mut exact = FluidState::zeros(grid.dim, grid.n_cells());
    init::riemann_planar(&mut exact, &grid, &ex, s.normal, s.xi0, case.t_end);
    let l1 = if layout == Layout::Diagonal {
        let mut acc = 0.0;
        for idx in 0..grid.n_cells() {
            let x = grid.cell_center(grid.ijk(idx));
            if (0.5..=1.5).contains(&x[0]) && (0.5..=1.5).contains(&x[1]) {
                acc += (solver.state().u[idx * 4] - exact.u[idx * 4]).abs();
            }
        }
        acc * grid.cell_volume() / s.transverse
    } else {
        init::l1_density(&grid, solver.state(), &exact) / s.transverse
    };
    RunResult {
        l1,
        min_rho,
        min_p,
        steps,
        solver,
        ok,
    }
}

pub fn slow_tests() -> bool {
    std::env::var("COSIM_SLOW_TESTS").is_ok_and(|v| v == "1")
}

/// A blast with a swirl on the unit box of `cells`: ρ = 8, p = 116.5 in the ball of radius 0.2
/// about `(c, c, c)`, ρ = 1.4, p = 1 outside; velocity `0.3 sin(2π x_{a+1})` along each axis a.
pub fn blast_state(cells: &[usize], c: f64) -> (Grid, FluidState) {
    let dim = cells.len();
    let grid = Grid::new(&vec![0.0; dim], &vec![1.0; dim], cells).expect("grid");
    let mut state = FluidState::zeros(dim, grid.n_cells());
    for idx in 0..grid.n_cells() {
        let x = grid.cell_center(grid.ijk(idx));
        let r2: f64 = (0..dim).map(|a| (x[a] - c).powi(2)).sum();
        let (rho, p) = if r2 < 0.2 * 0.2 {
            (8.0, 116.5)
        } else {
            (1.4, 1.0)
        };
        let mut vel = [0.0; 3];
        for a in 0..dim {
            vel[a] = 0.3 * (2.0 * std::f64::consts::PI * x[(a + 1) % dim]).sin();
        }
        state.set_primitive(idx, rho, vel, p, 1.4);
    }
    (grid, state)
}
