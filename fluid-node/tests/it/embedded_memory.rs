//! The memory accessors count the dense buffers exactly: the state and sweep buffer of the
//! solver, Λ and λ of both geometries and the per-cell slots of the embedded solid.

use crate::embedded_support;

use embedded_support::*;
use fluid_node::embedded::Embedded;

#[test]
fn memory_accessors_count_the_dense_buffers_2d() {
    let mut solver = solver(
        r#"
        name = "memory"
        [fluid]
        lower = [0.0, 0.0]
        upper = [1.0, 1.0]
        cells = [40, 30]
        boundary = { x = ["wall", "wall"], y = ["wall", "wall"] }
        [[fluid.init]]
        region = "all"
        rho = 1.4
        p = 1.0
        "#,
    );
    let n_cells = 40 * 30;
    let state = 4 * 8 * n_cells;
    let fluid = solver.memory_bytes();
    // State and sweep buffer, plus one report per pencil (at most 40) and the per-thread scratch.
    assert!(
        fluid >= 2 * state && fluid < 2 * state + 40 * 256,
        "{fluid} bytes for a {state}-byte state"
    );
    let body = polygon_2d(
        &[[0.4, 0.35], [0.65, 0.45], [0.55, 0.7], [0.3, 0.6]],
        [0.1, 0.0],
        0.0,
    );
    let mut embedded = Embedded::new(&solver, body).unwrap();
    let dense_one = 8 * (n_cells + 41 * 30 + 40 * 31);
    let m = embedded.memory();
    assert_eq!(m.dense_geometry, dense_one, "the accepted geometry only");
    assert_eq!(m.slot_of, 4 * n_cells);
    let dt = solver.max_dt().min(embedded.one_cell_dt());
    let next = translated(embedded.surface(), dt);
    step(&mut solver, &mut embedded, dt, next, 0);
    let m = embedded.memory();
    assert_eq!(
        m.dense_geometry,
        2 * dense_one,
        "accepted and trial geometries"
    );
    assert!(m.near_surface > 0 && m.sparse_geometry > 0, "{m:?}");
    assert_eq!(m.block_buffers, 0, "no block geometry on one rank");
    assert_eq!(
        m.total(),
        m.dense_geometry + m.slot_of + m.near_surface + m.sparse_geometry + m.block_buffers
    );
    assert_eq!(
        solver.memory_bytes(),
        fluid,
        "the coupled step allocates no dense buffer"
    );
    assert!(!embedded.near_cells().is_empty());
}
