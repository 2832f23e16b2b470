//! The fixed-point keys of `[run]`: IQN-ILS, its reuse and filter, the first relaxation factor
//! and the predictor are read with their defaults, and out-of-range values are refused by key;
//! `record_compression` is read and a bad value refused naming the key and the choices.

use protocol::scene::{Predictor, RecordCompression, Relaxation, Scene, SceneError};

fn scene(run: &str) -> Result<Scene, SceneError> {
    let text = format!(
        r#"
name = "bar"
[run]
{run}
[solid]
density = 1000.0
young = 1e6
poisson = 0.0
[[solid.bodies]]
shape = {{ box = {{ center = [2.0, 0.5], size = [0.4, 1.0] }} }}
divisions = [4, 10]
"#
    );
    Scene::from_toml_str(&text, "run.toml")
}

#[test]
fn defaults_and_iqn_ils_keys_are_read() {
    let s = scene("").expect("defaults");
    assert_eq!(s.run.relaxation, Relaxation::None);
    assert_eq!(s.run.predictor, Predictor::None);
    assert_eq!((s.run.iqn_reuse, s.run.iqn_filter), (4, 1e-2));
    assert_eq!(s.run.relaxation_initial, 0.5);
    let s = scene(
        "relaxation = \"iqn-ils\"\niqn_reuse = 0\niqn_filter = 1e-3\nrelaxation_initial = 0.2\npredictor = \"linear\"",
    )
    .expect("iqn-ils");
    assert_eq!(s.run.relaxation, Relaxation::IqnIls);
    assert_eq!(s.run.predictor, Predictor::Linear);
    assert_eq!((s.run.iqn_reuse, s.run.iqn_filter), (0, 1e-3));
    assert_eq!(s.run.relaxation_initial, 0.2);
}

#[test]
fn out_of_range_fixed_point_keys_are_refused_by_key() {
    for (run, key) in [
        ("relaxation_initial = 0.0", "run.relaxation_initial"),
        ("relaxation_initial = 1.5", "run.relaxation_initial"),
        ("iqn_filter = 1.0", "run.iqn_filter"),
        ("iqn_filter = 0.0", "run.iqn_filter"),
        ("iqn_filter = 1e-7", "run.iqn_filter"),
        ("iqn_reuse = 65", "run.iqn_reuse"),
    ] {
        match scene(run) {
            Err(SceneError::Invalid { path, .. }) => assert_eq!(path, key, "{run}"),
            other => panic!("{run}: expected an Invalid error, got {other:?}"),
        }
    }
}

/// Issue 15, item 8: `run.record_compression` is zstd (issue 39: a compact record by default)
/// unless the scene says `"none"` or `"lz4"`; it survives the scene's round trip through TOML
/// (the record's metadata); any other value is refused naming the key and the three allowed
/// values.
#[test]
fn record_compression_is_read_and_a_bad_value_names_the_key_and_the_choices() {
    assert_eq!(
        scene("").expect("defaults").run.record_compression,
        RecordCompression::Zstd
    );
    for (value, want) in [
        ("none", RecordCompression::None),
        ("lz4", RecordCompression::Lz4),
        ("zstd", RecordCompression::Zstd),
    ] {
        let s = scene(&format!("record_compression = \"{value}\"")).expect(value);
        assert_eq!(s.run.record_compression, want);
        assert_eq!(want.name(), value);
        let again = Scene::from_toml_str(&s.to_toml(), "again.toml").expect("round trip");
        assert_eq!(again.run.record_compression, want);
    }
    for bad in [
        "record_compression = \"gzip\"",
        "record_compression = \"LZ4\"",
        "record_compression = 1",
    ] {
        match scene(bad) {
            Err(e @ SceneError::Parse { .. }) => {
                let SceneError::Parse { path, message, .. } = &e else {
                    unreachable!()
                };
                assert_eq!(path, "run.record_compression", "{bad}: {e}");
                let text = e.to_string();
                assert!(text.contains("run.record_compression"), "{bad}: {text}");
                if bad.contains('"') {
                    for allowed in ["`none`", "`lz4`", "`zstd`"] {
                        assert!(message.contains(allowed), "{bad}: {message}");
                    }
                }
            }
            other => panic!("{bad}: expected a Parse error, got {other:?}"),
        }
    }
}
