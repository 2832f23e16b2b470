//! `[solid.contact]` in the scene schema: absent means no contact, an empty table turns it on
//! with every default, a bad value is refused naming its key path, and the table round-trips
//! through the resolved scene.

use protocol::scene::{ContactConfig, Scene, SceneError};

fn scene_2d(extra: &str) -> Result<Scene, SceneError> {
    let text = format!(
        r#"
name = "blocks"
[solid]
density = 1000.0
young = 1e6
poisson = 0.0
[[solid.bodies]]
shape = {{ box = {{ center = [0.0, 0.0], size = [0.1, 0.1] }} }}
divisions = [1, 1]
{extra}"#
    );
    Scene::from_toml_str(&text, "contact.toml")
}

#[test]
fn absent_table_means_no_contact_and_an_empty_one_every_default() {
    let absent = scene_2d("").expect("valid scene");
    assert_eq!(absent.solid.as_ref().expect("solid").contact, None);
    assert!(!absent.to_toml().contains("contact"));
    let empty = scene_2d("[solid.contact]\n").expect("valid scene");
    let c = empty.solid.as_ref().expect("solid").contact.clone();
    assert_eq!(
        c,
        Some(ContactConfig {
            stiffness: 1.0,
            restitution: 0.5,
            friction: 0.3,
        })
    );
    assert_eq!(c, Some(ContactConfig::default()));
    assert_ne!(empty.hash(), absent.hash(), "contact is physics");
    let again = Scene::from_toml_str(&empty.to_toml(), "resolved").expect("resolved parses");
    assert_eq!(again, empty);
    let set = scene_2d("[solid.contact]\nstiffness = 2.0\nrestitution = 1.0\nfriction = 0.0\n")
        .expect("valid scene");
    let c = set.solid.expect("solid").contact.expect("contact");
    assert_eq!((c.stiffness, c.restitution, c.friction), (2.0, 1.0, 0.0));
}

#[test]
fn bad_contact_values_are_refused_naming_the_key() {
    for (text, key, found) in [
        ("stiffness = 0.0", "solid.contact.stiffness", "0"),
        ("restitution = 1.5", "solid.contact.restitution", "1.5"),
        ("restitution = -0.1", "solid.contact.restitution", "-0.1"),
        ("friction = -1.0", "solid.contact.friction", "-1"),
    ] {
        match scene_2d(&format!("[solid.contact]\n{text}\n")) {
            Err(SceneError::Invalid {
                path, found: got, ..
            }) => {
                assert_eq!(path, key, "{text}");
                assert_eq!(got, found, "{text}");
            }
            other => panic!("{text}: expected an Invalid error, got {other:?}"),
        }
    }
    match scene_2d("[solid.contact]\ndamping = 0.1\n") {
        Err(SceneError::Parse { path, message, .. }) => {
            assert!(
                path.contains("contact") || message.contains("damping"),
                "{path}: {message}"
            );
        }
        other => panic!("expected a parse error, got {other:?}"),
    }
}
