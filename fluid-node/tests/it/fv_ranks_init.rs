//! Issue 40: a rank of a decomposed grid builds the initial state of its own block only from
//! the `[[fluid.init]]` regions (`FluidSolver::from_scene_on`), with the bits of one rank's
//! whole state there, and the error of one rank for a cell no region covers.

use fluid_node::fv::slab::take_block;
use fluid_node::fv::{FluidSolver, from_scene};
use protocol::scene::{FluidConfig, Region, Scene};

use crate::fv_ranks::on_thread_ranks;

/// A 3-D box (or 2-D, `cells` of 2 entries) of gas with three overlapping init regions (a later
/// one wins), cut into the blocks `decomposition` (`None`: as chosen), the first region
/// covering every cell (`all`) or not.
fn fluid(cells: &[u32], decomposition: Option<[u32; 3]>, all: bool) -> FluidConfig {
    let dim = cells.len();
    let axes = |v: [f64; 3]| format!("{:?}", &v[..dim]);
    let text = format!(
        r#"
name = "init-by-block"

[run]
t_end = 0.1

[fluid]
gamma = 1.4
lower = {lower}
upper = {upper}
cells = {cells:?}

[[fluid.init]]
region = "all"
rho = 1.0
p = 1.0

[[fluid.init]]
region = {{ box = {{ lower = {lo}, upper = {hi} }} }}
rho = 2.5
p = 3.0
velocity = {velocity}

[[fluid.init]]
region = {{ ball = {{ center = {center}, radius = 0.3 }} }}
rho = 0.125
p = 0.1
"#,
        lower = axes([0.0; 3]),
        upper = axes([1.0; 3]),
        lo = axes([0.1, 0.2, 0.3]),
        hi = axes([0.7, 0.9, 0.6]),
        velocity = axes([0.5, -0.25, 0.125]),
        center = axes([0.6, 0.5, 0.4]),
    );
    let scene = Scene::from_toml_str(&text, "init-by-block").expect("valid scene");
    let mut cfg = scene.fluid.expect("fluid");
    if !all {
        // (After the scene's checks, which refuse a cell no entry covers.)
        let upper = [1.0, 1.0, 0.9][..dim].to_vec();
        cfg.init[0].region = Region::Box {
            lower: vec![0.0; dim],
            upper,
        };
    }
    cfg.decomposition = decomposition.map(|d| d[..cells.len()].to_vec());
    cfg
}

/// A grid's cells, its blocks per axis (`None`: as chosen) and its ranks.
type Case = (&'static [u32], Option<[u32; 3]>, usize);

#[test]
fn each_rank_builds_its_blocks_initial_state_with_the_bits_of_one_rank() {
    let cases: [Case; 6] = [
        (&[12, 12, 16], None, 2),
        (&[12, 12, 16], Some([1, 2, 2]), 4),
        (&[12, 12, 16], Some([1, 2, 1]), 2),
        (&[24, 20], None, 2),
        (&[24, 20], Some([2, 2, 1]), 4),
        (&[24, 20], Some([3, 1, 1]), 3),
    ];
    for (cells, decomposition, ranks) in cases {
        let cfg = fluid(cells, decomposition, true);
        let (grid, _, whole) = from_scene(&cfg).expect("one rank");
        let states = on_thread_ranks(ranks, |comm| {
            let s = FluidSolver::from_scene_on(&cfg, 1, Box::new(comm)).expect("rank");
            let slab = s.slab();
            let expected = take_block(&grid, slab.block_of_rank(slab.rank), whole.nvar, &whole.u);
            (s.state().u.clone(), expected)
        });
        for (rank, (got, expected)) in states.into_iter().enumerate() {
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(
                bits(&got),
                bits(&expected),
                "{cells:?} {decomposition:?} rank {rank}"
            );
        }
    }
}

#[test]
fn a_cell_no_region_covers_is_every_ranks_error_as_on_one_rank() {
    // The first region leaves the two top planes uncovered (z > 0.9; the others do not reach
    // them): the first uncovered cell in the grid's order lies in the upper blocks only.
    for (decomposition, ranks) in [(None, 2), (Some([1, 2, 2]), 4), (Some([1, 1, 2]), 2)] {
        let cfg = fluid(&[12, 12, 16], decomposition, false);
        let one = from_scene(&cfg).expect_err("uncovered").to_string();
        assert!(one.contains("covered by no"), "{one}");
        let errors = on_thread_ranks(ranks, |comm| {
            FluidSolver::from_scene_on(&cfg, 1, Box::new(comm))
                .err()
                .map(|e| e.to_string())
        });
        for (rank, e) in errors.into_iter().enumerate() {
            assert_eq!(
                e.as_deref(),
                Some(one.as_str()),
                "{decomposition:?} rank {rank}"
            );
        }
    }
}
