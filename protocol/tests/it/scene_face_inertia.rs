//! `solid.face_inertia` (the authors' unweighted face moments, for reproducing papers 003 and
//! 000): absent means exact and leaves the resolved scene and its hash as they were, a 3-D scene
//! takes "unweighted", a 2-D one refuses it naming the key, and an unknown value is a parse error.

use protocol::scene::{FaceInertia, Scene, SceneError};

fn scene(dim: usize, extra: &str) -> Result<Scene, SceneError> {
    let (center, size, divisions) = if dim == 3 {
        ("[0.0, 0.0, 0.0]", "[0.1, 0.2, 0.1]", "[1, 2, 1]")
    } else {
        ("[0.0, 0.0]", "[0.1, 0.2]", "[1, 2]")
    };
    let text = format!(
        r#"
name = "column"
[solid]
density = 100.0
young = 7000.0
poisson = 0.0
{extra}
[[solid.bodies]]
shape = {{ box = {{ center = {center}, size = {size} }} }}
divisions = {divisions}
"#
    );
    Scene::from_toml_str(&text, "face_inertia.toml")
}

#[test]
fn absent_means_exact_and_unweighted_is_physics_that_round_trips() {
    let absent = scene(3, "").expect("valid scene");
    assert_eq!(absent.solid.as_ref().expect("solid").face_inertia, None);
    assert!(!absent.to_toml().contains("face_inertia"));
    let exact = scene(3, r#"face_inertia = "exact""#).expect("valid scene");
    assert_eq!(
        exact.solid.as_ref().expect("solid").face_inertia,
        Some(FaceInertia::Exact)
    );
    let legacy = scene(3, r#"face_inertia = "unweighted""#).expect("valid scene");
    assert_eq!(
        legacy.solid.as_ref().expect("solid").face_inertia,
        Some(FaceInertia::Unweighted)
    );
    assert_ne!(legacy.hash(), absent.hash(), "the face moments are physics");
    let again = Scene::from_toml_str(&legacy.to_toml(), "resolved").expect("resolved parses");
    assert_eq!(again, legacy);
}

#[test]
fn a_2d_scene_refuses_unweighted_and_a_typo_is_a_parse_error() {
    assert!(scene(2, r#"face_inertia = "exact""#).is_ok());
    match scene(2, r#"face_inertia = "unweighted""#) {
        Err(SceneError::Invalid { path, found, .. }) => {
            assert_eq!(path, "solid.face_inertia");
            assert_eq!(found, "\"unweighted\"");
        }
        other => panic!("expected an Invalid error, got {other:?}"),
    }
    match scene(3, r#"face_inertia = "unweighed""#) {
        Err(SceneError::Parse { path, message, .. }) => {
            assert!(path.contains("face_inertia"), "{path}: {message}");
        }
        other => panic!("expected a parse error, got {other:?}"),
    }
}
