//! Issue 11, items 6 and 9: scene values that parsed but ran wrong (a truncated boundary list,
//! negative radii, inverted boxes, zero normals, init regions outside the domain, cells no
//! `[[fluid.init]]` covers, `max_steps = 0`, `run.dt_min`) are refused with their key path and the
//! reason; an output time of 0 is accepted (the initial state is output 0); an oversized value is
//! quoted shortened in the error; the memory a scene needs is estimated before anything starts.

use protocol::scene::{Scene, SceneError};

/// A 2-D fluid-only scene on [0, 1]² with 10 × 10 cells, then `extra` (appended at the end), with
/// `init` as its `[[fluid.init]]` entries.
fn fluid_2d(init: &str, extra: &str) -> Result<Scene, SceneError> {
    let text = format!(
        r#"
name = "box"
[run]
t_end = 0.1
[fluid]
lower = [0.0, 0.0]
upper = [1.0, 1.0]
cells = [10, 10]
{init}
{extra}"#
    );
    Scene::from_toml_str(&text, "scene.toml")
}

const ALL: &str = r#"
[[fluid.init]]
region = "all"
rho = 1.0
p = 1.0
"#;

/// The key path and the message of a refused scene.
fn refused(res: Result<Scene, SceneError>) -> (String, String) {
    match res {
        Err(err @ SceneError::Invalid { .. }) => {
            let SceneError::Invalid { path, .. } = &err else {
                unreachable!()
            };
            (path.clone(), err.to_string())
        }
        Err(err @ SceneError::Parse { .. }) => {
            let SceneError::Parse { path, .. } = &err else {
                unreachable!()
            };
            (path.clone(), err.to_string())
        }
        Ok(_) => panic!("the scene was accepted"),
    }
}

fn init_entry(region: &str) -> String {
    format!("{ALL}\n[[fluid.init]]\nregion = {region}\nrho = 2.0\np = 2.0\n")
}

#[test]
fn a_boundary_with_three_entries_is_refused() {
    let (path, msg) = refused(fluid_2d(
        ALL,
        r#"[fluid.boundary]
x = ["wall", "wall", "outflow"]"#,
    ));
    assert_eq!(path, "fluid.boundary.x", "{msg}");
    assert!(msg.contains("2 entries"), "{msg}");
}

#[test]
fn a_negative_ball_radius_is_refused() {
    let (path, msg) = refused(fluid_2d(
        &init_entry("{ ball = { center = [0.5, 0.5], radius = -0.1 } }"),
        "",
    ));
    assert_eq!(path, "fluid.init[1].region.ball.radius", "{msg}");
    let (path, _) = refused(fluid_2d(
        ALL,
        r#"[solid]
node = "prescribed"
[solid.prescribed]
box = { center = [0.5, 0.5], size = [0.1, 0.1] }
motion = "fixed"
[[solid.constraints]]
region = { ball = { center = [0.5, 0.5], radius = -1.0 } }
motion = "fixed""#,
    ));
    assert_eq!(path, "solid.constraints[0].region.ball.radius");
}

#[test]
fn a_box_with_lower_above_upper_is_refused() {
    let (path, msg) = refused(fluid_2d(
        &init_entry("{ box = { lower = [0.6, 0.0], upper = [0.4, 1.0] } }"),
        "",
    ));
    assert_eq!(path, "fluid.init[1].region.box", "{msg}");
    assert!(msg.contains("lower <= upper"), "{msg}");
}

#[test]
fn a_zero_normal_of_a_half_space_is_refused() {
    let (path, msg) = refused(fluid_2d(
        &init_entry("{ half_space = { point = [0.5, 0.5], normal = [0.0, 0.0] } }"),
        "",
    ));
    assert_eq!(path, "fluid.init[1].region.half_space.normal", "{msg}");
}

#[test]
fn an_init_region_outside_the_domain_is_refused() {
    for region in [
        "{ box = { lower = [2.0, 2.0], upper = [3.0, 3.0] } }",
        "{ ball = { center = [5.0, 5.0], radius = 1.0 } }",
        "{ half_space = { point = [-1.0, 0.0], normal = [1.0, 0.0] } }",
    ] {
        let (path, msg) = refused(fluid_2d(&init_entry(region), ""));
        assert_eq!(path, "fluid.init[1].region", "{region}: {msg}");
        assert!(msg.contains("outside the domain"), "{msg}");
    }
    // Touching the domain is enough.
    fluid_2d(
        &init_entry("{ ball = { center = [1.5, 0.5], radius = 0.6 } }"),
        "",
    )
    .expect("a ball overlapping the domain is fine");
}

#[test]
fn cells_no_init_entry_covers_are_refused() {
    let half = r#"
[[fluid.init]]
region = { box = { lower = [0.0, 0.0], upper = [0.5, 1.0] } }
rho = 1.0
p = 1.0
"#;
    let (path, msg) = refused(fluid_2d(half, ""));
    assert_eq!(path, "fluid.init", "{msg}");
    assert!(msg.contains("cell"), "{msg}");
    let both = format!(
        "{half}\n[[fluid.init]]\nregion = {{ half_space = {{ point = [0.5, 0.0], normal = [-1.0, 0.0] }} }}\nrho = 2.0\np = 2.0\n"
    );
    fluid_2d(&both, "").expect("two halves cover the grid");
}

#[test]
fn max_steps_zero_is_refused() {
    let (path, _) = refused(fluid_2d(ALL, "").and_then(|s| {
        let text = s.to_toml().replace("[run]\n", "[run]\nmax_steps = 0\n");
        Scene::from_toml_str(&text, "scene.toml")
    }));
    assert_eq!(path, "run.max_steps");
}

#[test]
fn an_output_time_of_zero_is_the_initial_state() {
    let scene = fluid_2d(ALL, "[output]\ntimes = [0.0, 0.05]").expect("output time 0 is accepted");
    assert!(scene.initial_output());
    // The steps end at the other output times; output 0 is written before the first step.
    assert_eq!(scene.output_times(), vec![0.05, 0.1]);
    let later = fluid_2d(ALL, "[output]\ntimes = [0.05]").expect("valid");
    assert!(!later.initial_output());
}

#[test]
fn dt_min_must_be_positive_and_below_dt_max() {
    let with = |run: &str| {
        fluid_2d(ALL, "").and_then(|s| {
            let text = s.to_toml().replace("[run]\n", &format!("[run]\n{run}\n"));
            Scene::from_toml_str(&text, "scene.toml")
        })
    };
    let scene = with("dt_min = 1e-9").expect("valid dt_min");
    assert_eq!(scene.run.dt_min, Some(1e-9));
    assert_eq!(refused(with("dt_min = -1.0")).0, "run.dt_min");
    assert_eq!(
        refused(with("dt_min = 0.01\ndt_max = 0.001")).0,
        "run.dt_min"
    );
}

#[test]
fn an_oversized_value_is_quoted_shortened() {
    let cells: Vec<String> = (0..200_000).map(|i| i.to_string()).collect();
    let err = fluid_2d(ALL, "")
        .and_then(|s| {
            let text = s.to_toml().replace(
                "cells = [10, 10]",
                &format!("cells = [{}]", cells.join(", ")),
            );
            Scene::from_toml_str(&text, "scene.toml")
        })
        .expect_err("200000 cell counts in 2-D");
    let msg = err.to_string();
    assert!(
        msg.contains("fluid.cells"),
        "{}",
        &msg[..msg.len().min(400)]
    );
    assert!(msg.len() < 1000, "{} bytes: {}", msg.len(), &msg[..400]);
    assert!(msg.contains("200000 entries"), "{msg}");
}

#[test]
fn a_scene_too_large_to_parse_in_memory_is_not_echoed_whole() {
    // A TOML error on a long line quotes that line: it must come back shortened.
    let long = format!(
        "name = \"x\"\n[run]\nt_end = [{}]\n",
        "1.0, ".repeat(100_000)
    );
    let msg = Scene::from_toml_str(&long, "big.toml")
        .expect_err("t_end is a number")
        .to_string();
    assert!(msg.len() < 2000, "{} bytes", msg.len());
}

#[test]
fn the_memory_estimate_names_the_largest_part() {
    let small = fluid_2d(ALL, "").expect("valid");
    let est = small.memory_estimate();
    assert!(
        est.total_bytes() > 0 && est.total_bytes() < 64 << 20,
        "{est:?}"
    );
    let text = small
        .to_toml()
        .replace("lower = [0.0, 0.0]", "lower = [0.0, 0.0, 0.0]")
        .replace("upper = [1.0, 1.0]", "upper = [1.0, 1.0, 1.0]")
        .replace("cells = [10, 10]", "cells = [2000, 2000, 2000]");
    let huge = Scene::from_toml_str(&text, "scene.toml").expect("valid apart from its size");
    let est = huge.memory_estimate();
    // 8e9 cells of 5 conserved variables in at least two copies: well over 500 GB.
    assert!(est.total_bytes() > 500 << 30, "{est:?}");
    assert_eq!(est.largest().0, "fluid.cells");
    let err = huge
        .check_memory(64 << 30)
        .expect_err("8e9 cells do not fit in 64 GiB");
    let msg = err.to_string();
    assert!(
        msg.contains("fluid.cells") && msg.contains("GiB") && msg.contains("64.0 GiB"),
        "{msg}"
    );
    small.check_memory(64 << 30).expect("a small scene fits");
}

#[test]
fn the_memory_estimate_counts_solid_particles() {
    let solid = |divisions: &str| {
        Scene::from_toml_str(
            &format!(
                r#"name = "bar"
[solid]
density = 1000.0
young = 1e6
poisson = 0.0
[[solid.bodies]]
shape = {{ box = {{ center = [0.0, 0.0, 0.0], size = [1.0, 1.0, 1.0] }} }}
divisions = {divisions}
"#
            ),
            "solid.toml",
        )
        .expect("valid")
    };
    let est = solid("[100000, 100000, 100000]").memory_estimate();
    assert_eq!(est.largest().0, "solid.bodies[0].divisions");
    let msg = solid("[100000, 100000, 100000]")
        .check_memory(64 << 30)
        .expect_err("1e15 particles")
        .to_string();
    assert!(msg.contains("solid.bodies[0].divisions"), "{msg}");
    solid("[10, 10, 10]")
        .check_memory(64 << 30)
        .expect("1000 particles fit");
}
