//! `links = { spring = K, rotation = C }` of a body (paper 003 §5.3): absent means the elastic
//! links of App. A, a bad value is refused naming its key path, and the table round-trips
//! through the resolved scene.

use protocol::scene::{LinksConfig, Scene, SceneError};

fn scene_2d(links: &str) -> Result<Scene, SceneError> {
    let text = format!(
        r#"
name = "chain"
[solid]
density = 1000.0
young = 1e6
poisson = 0.0
[[solid.bodies]]
shape = {{ box = {{ center = [0.0, 0.0], size = [0.1, 0.1] }} }}
divisions = [1, 2]
{links}"#
    );
    Scene::from_toml_str(&text, "links.toml")
}

#[test]
fn absent_links_mean_elastic_links_and_a_spring_round_trips() {
    let absent = scene_2d("").expect("valid scene");
    assert_eq!(absent.solid.as_ref().expect("solid").bodies[0].links, None);
    assert!(!absent.to_toml().contains("links"));
    let spring = scene_2d("links = { spring = 2000.0 }").expect("valid scene");
    assert_eq!(
        spring.solid.as_ref().expect("solid").bodies[0].links,
        Some(LinksConfig {
            spring: 2000.0,
            rotation: 0.0,
        })
    );
    assert_ne!(spring.hash(), absent.hash(), "the link law is physics");
    let again = Scene::from_toml_str(&spring.to_toml(), "resolved").expect("resolved parses");
    assert_eq!(again, spring);
    let both = scene_2d("links = { spring = 5.0, rotation = 1e-3 }").expect("valid scene");
    let l = both.solid.expect("solid").bodies[0]
        .links
        .clone()
        .expect("links");
    assert_eq!((l.spring, l.rotation), (5.0, 1e-3));
}

#[test]
fn bad_link_values_are_refused_naming_the_key() {
    for (text, key, found) in [
        ("spring = 0.0", "solid.bodies[0].links.spring", "0"),
        ("spring = -2.0", "solid.bodies[0].links.spring", "-2"),
        ("spring = inf", "solid.bodies[0].links.spring", "inf"),
        (
            "spring = 1.0, rotation = -1.0",
            "solid.bodies[0].links.rotation",
            "-1",
        ),
        (
            "spring = 1.0, rotation = nan",
            "solid.bodies[0].links.rotation",
            "NaN",
        ),
    ] {
        match scene_2d(&format!("links = {{ {text} }}")) {
            Err(SceneError::Invalid {
                path, found: got, ..
            }) => {
                assert_eq!(path, key, "{text}");
                assert_eq!(got, found, "{text}");
            }
            other => panic!("{text}: expected an Invalid error, got {other:?}"),
        }
    }
    for text in ["links = { stiffness = 1.0 }", "links = { rotation = 1.0 }"] {
        match scene_2d(text) {
            Err(SceneError::Parse { path, message, .. }) => {
                assert!(path.contains("links"), "{text}: {path}: {message}");
            }
            other => panic!("{text}: expected a parse error, got {other:?}"),
        }
    }
}
