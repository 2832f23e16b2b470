//! `[[solid.init]]` in the scene schema: an entry is read with its region and velocities, a wrong
//! one is refused naming its key path, and a scene without it resolves and hashes as before.

use protocol::scene::{Region, Scene, SceneError, SolidInit};

/// A 2-D solid-only scene followed by `extra` (TOML appended at the end).
fn scene_2d(extra: &str) -> Result<Scene, SceneError> {
    let text = format!(
        r#"
name = "bar"
[solid]
density = 1000.0
young = 1e6
poisson = 0.0
[[solid.bodies]]
shape = {{ box = {{ center = [2.0, 0.5], size = [0.4, 1.0] }} }}
divisions = [4, 10]
{extra}"#
    );
    Scene::from_toml_str(&text, "init.toml")
}

/// The key path of an `Invalid` error, or the whole error.
fn invalid_path(res: Result<Scene, SceneError>) -> String {
    match res {
        Err(SceneError::Invalid { path, .. }) => path,
        other => panic!("expected an Invalid error, got {other:?}"),
    }
}

#[test]
fn solid_init_entries_are_read_in_order() {
    let scene = scene_2d(
        r#"
[[solid.init]]
region = { box = { lower = [1.8, 0.5], upper = [2.2, 1.0] } }
velocity = [0.25, 0.0]
[[solid.init]]
region = "all"
angular_velocity = [-1.5]
"#,
    )
    .expect("valid scene");
    let init = &scene.solid.as_ref().expect("solid").init;
    assert_eq!(
        init,
        &vec![
            SolidInit {
                region: Region::Box {
                    lower: vec![1.8, 0.5],
                    upper: vec![2.2, 1.0],
                },
                velocity: Some(vec![0.25, 0.0]),
                angular_velocity: None,
            },
            SolidInit {
                region: Region::All,
                velocity: None,
                angular_velocity: Some(vec![-1.5]),
            },
        ]
    );
    // The resolved scene reads back to the same scene (what the coupler hands the nodes).
    let again = Scene::from_toml_str(&scene.to_toml(), "resolved").expect("resolved parses");
    assert_eq!(again, scene);
    assert_eq!(again.hash(), scene.hash());
}

#[test]
fn absent_solid_init_changes_neither_the_resolved_scene_nor_the_hash() {
    let absent = scene_2d("").expect("valid scene");
    let text = absent
        .to_toml()
        .replace("[solid]\n", "[solid]\ninit = []\n");
    let explicit = Scene::from_toml_str(&text, "explicit").expect("init = [] parses");
    // (`run.relaxation_initial` also contains "init": look for the key itself.)
    let resolved = absent.to_toml();
    assert!(
        !resolved.contains("solid.init") && !resolved.contains("\ninit"),
        "{resolved}"
    );
    assert_eq!(explicit, absent);
    assert_eq!(explicit.hash(), absent.hash());
    let with_init =
        scene_2d("[[solid.init]]\nregion = \"all\"\nvelocity = [0.0, 0.0]\n").expect("valid scene");
    assert_ne!(with_init.hash(), absent.hash(), "an init entry is physics");
}

#[test]
fn solid_init_of_the_wrong_length_is_refused_naming_the_key() {
    let res = scene_2d("[[solid.init]]\nregion = \"all\"\nvelocity = [0.25]\n");
    match res {
        Err(SceneError::Invalid {
            file,
            path,
            expected,
            found,
        }) => {
            assert_eq!(file, "init.toml");
            assert_eq!(path, "solid.init[0].velocity");
            assert_eq!(expected, "2 finite numbers (the scene is 2-D)");
            assert_eq!(found, "[0.25]");
        }
        other => panic!("expected an Invalid error, got {other:?}"),
    }
    // The index counts entries; each vector is checked.
    let second = "[[solid.init]]\nregion = \"all\"\nvelocity = [0.0, 0.0]\n\
                  [[solid.init]]\nregion = \"all\"\nvelocity = [nan, 0.0]\n";
    assert_eq!(invalid_path(scene_2d(second)), "solid.init[1].velocity");
    let spin = "[[solid.init]]\nregion = \"all\"\nangular_velocity = [0.0, 0.0, 1.0]\n";
    assert_eq!(
        invalid_path(scene_2d(spin)),
        "solid.init[0].angular_velocity"
    );
    let spin_inf = "[[solid.init]]\nregion = \"all\"\nangular_velocity = [inf]\n";
    assert_eq!(
        invalid_path(scene_2d(spin_inf)),
        "solid.init[0].angular_velocity"
    );
    let region = "[[solid.init]]\nregion = { box = { lower = [0.0], upper = [1.0, 1.0] } }\n\
                  velocity = [0.0, 0.0]\n";
    assert_eq!(
        invalid_path(scene_2d(region)),
        "solid.init[0].region.box.lower"
    );
    let ball = "[[solid.init]]\nregion = { ball = { center = [0.0, 0.0, 0.0], radius = 1.0 } }\n\
                velocity = [0.0, 0.0]\n";
    assert_eq!(
        invalid_path(scene_2d(ball)),
        "solid.init[0].region.ball.center"
    );
}

#[test]
fn solid_init_without_any_velocity_is_refused() {
    let res = scene_2d("[[solid.init]]\nregion = \"all\"\n");
    match res {
        Err(SceneError::Invalid {
            path,
            expected,
            found,
            ..
        }) => {
            assert_eq!(path, "solid.init[0]");
            assert_eq!(expected, "velocity, angular_velocity or both");
            assert_eq!(found, "neither");
        }
        other => panic!("expected an Invalid error, got {other:?}"),
    }
}

#[test]
fn solid_init_with_an_unknown_key_is_refused() {
    let res = scene_2d("[[solid.init]]\nregion = \"all\"\nvelocity = [0.0, 0.0]\nspin = 1.0\n");
    match res {
        Err(SceneError::Parse {
            file,
            path,
            message,
        }) => {
            assert_eq!(file, "init.toml");
            assert_eq!(path, "solid.init[0].spin");
            assert!(message.contains("spin"), "message {message:?}");
        }
        other => panic!("expected a Parse error, got {other:?}"),
    }
}

#[test]
fn two_probes_of_one_name_are_refused() {
    let probes = |second: &str| {
        scene_2d(&format!(
            "[[output.probes]]\nname = \"tip\"\nparticle_at = [2.0, 1.0]\n[[output.probes]]\nname = \"{second}\"\nparticle_at = [2.0, 0.0]\n"
        ))
    };
    assert!(probes("base").is_ok());
    let err = probes("tip").expect_err("a repeated name");
    let text = err.to_string();
    assert_eq!(invalid_path(Err(err)), "output.probes[1].name");
    assert!(text.contains("output.probes[0] has it"), "{text}");
}

#[test]
fn the_characteristic_table_is_checked() {
    let scene = |boundary: &str, table: &str| {
        format!(
            r#"
            name = "far"
            [fluid]
            lower = [0.0, 0.0]
            upper = [1.0, 1.0]
            cells = [8, 8]
            boundary = {{ x = [{boundary}], y = ["wall", "wall"] }}
            characteristic = {table}
            [[fluid.init]]
            region = "all"
            rho = 1.0
            p = 1.0
        "#
        )
    };
    let err = |text: String| {
        protocol::scene::Scene::from_toml_str(&text, "far")
            .expect_err("refused")
            .to_string()
    };
    let ch = r#""characteristic", "outflow""#;
    assert!(protocol::scene::Scene::from_toml_str(&scene(ch, "{}"), "far").is_ok());
    let e = err(scene(r#""outflow", "outflow""#, "{ sigma = 0.1 }"));
    assert!(
        e.contains("fluid.characteristic") && e.contains("characteristic"),
        "{e}"
    );
    let e = err(scene(ch, "{ sigma = -0.1 }"));
    assert!(
        e.contains("fluid.characteristic.sigma") && e.contains("[0, 10]"),
        "{e}"
    );
    let e = err(scene(ch, "{ p_far = 0.0 }"));
    assert!(
        e.contains("fluid.characteristic.p_far") && e.contains("> 0"),
        "{e}"
    );
    let e = err(scene(ch, "{ p = 1.0 }"));
    assert!(e.contains("p"), "{e}");
}

/// A misspelt key or value gets the nearest valid name and the whole list of valid names (the
/// list used to be cut mid-way: "... (14 more bytes)").
#[test]
fn a_misspelt_key_or_value_gets_a_suggestion_and_the_whole_list() {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/sod.toml"))
        .expect("scenes/sod.toml");
    let parse = |from: &str, to: &str| {
        assert!(text.contains(from), "{from}");
        match Scene::from_toml_str(&text.replacen(from, to, 1), "sod.toml") {
            Err(SceneError::Parse { path, message, .. }) => (path, message),
            other => panic!("expected a Parse error, got {other:?}"),
        }
    };
    let (path, message) = parse("\ngamma = ", "\ngama = ");
    assert_eq!(path, "fluid.gama");
    assert!(
        message.contains(
            "unknown field `gama` (did you mean `gamma`?); valid here: `node`, `gamma`, `cfl`"
        ),
        "{message}"
    );
    assert!(message.trim_end().ends_with("`decomposition`"), "{message}");
    assert!(!message.contains("more bytes"), "{message}");
    let (path, message) = parse("scheme = \"osmp\"", "scheme = \"osnp\"");
    assert_eq!(path, "fluid.flux.scheme");
    assert!(
        message.contains("unknown variant `osnp` (did you mean `osmp`?)"),
        "{message}"
    );
    // Nothing near: no suggestion, the list still whole.
    let (_, message) = parse("\ngamma = ", "\nzzzzzzzz = ");
    assert!(!message.contains("did you mean"), "{message}");
    assert!(message.contains("valid here: `node`"), "{message}");
    // A misspelt node implementation.
    let fluid = text.replacen("[fluid]\n", "[fluid]\nnode = \"pressur\"\n", 1);
    match Scene::from_toml_str(&fluid, "sod.toml") {
        Err(SceneError::Invalid { path, expected, .. }) => {
            assert_eq!(path, "fluid.node");
            assert!(
                expected.ends_with("(did you mean `pressure`?)"),
                "{expected}"
            );
        }
        other => panic!("expected an Invalid error, got {other:?}"),
    }
}

/// Issue 40: `fluid.decomposition` is read, and a process grid that cuts x in 3-D, does not
/// multiply to `fluid.ranks`, has the wrong length or makes blocks thinner than the halo is
/// refused naming the key; without it, a rank count no grid fits is refused naming
/// `fluid.ranks`.
#[test]
fn a_decomposition_is_read_and_a_bad_one_is_refused_naming_the_key() {
    let scene = |ranks: u32, decomposition: &str| {
        let text = format!(
            "name = \"d\"\n[fluid]\nlower = [0.0, 0.0, 0.0]\nupper = [1.0, 1.0, 1.0]\n\
             cells = [16, 16, 24]\nranks = {ranks}\n{decomposition}\n[[fluid.init]]\n\
             region = \"all\"\nrho = 1.0\np = 1.0\nvelocity = [0.0, 0.0, 0.0]\n"
        );
        Scene::from_toml_str(&text, "d.toml")
    };
    let ok = scene(4, "decomposition = [1, 2, 2]").expect("valid");
    let fluid = ok.fluid.as_ref().expect("fluid");
    assert_eq!(fluid.decomposition, Some(vec![1, 2, 2]));
    assert_eq!(fluid.process_grid(), Some([1, 2, 2]));
    assert_eq!(
        scene(4, "")
            .expect("valid")
            .fluid
            .expect("fluid")
            .process_grid(),
        Some([1, 1, 4])
    );
    for bad in [
        "[2, 2, 1]",
        "[1, 2, 1]",
        "[1, 4]",
        "[1, 4, 1]",
        "[1, 2, 2, 1]",
    ] {
        let res = scene(4, &format!("decomposition = {bad}"));
        assert_eq!(invalid_path(res), "fluid.decomposition", "{bad}");
    }
    assert_eq!(invalid_path(scene(16, "")), "fluid.ranks");
    assert_eq!(
        invalid_path(scene(1, "decomposition = [1, 1, 2]")),
        "fluid.decomposition"
    );
}
