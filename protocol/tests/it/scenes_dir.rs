//! Every scene shipped in `scenes/` reads and validates (a typo in one fails here, not in a
//! user's first run).

use protocol::scene::Scene;

#[test]
fn every_shipped_scene_validates() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    let mut names = Vec::new();
    for entry in std::fs::read_dir(&dir).expect("scenes/") {
        let path = entry.expect("entry").path();
        if path.extension().is_some_and(|e| e == "toml") {
            let text = std::fs::read_to_string(&path).expect("read");
            let scene = Scene::from_toml_str(&text, &path.display().to_string())
                .unwrap_or_else(|e| panic!("{e}"));
            let stem = path
                .file_stem()
                .expect("stem")
                .to_string_lossy()
                .into_owned();
            assert_eq!(
                scene.name,
                stem,
                "{}: name differs from the file",
                path.display()
            );
            names.push(stem);
        }
    }
    names.sort();
    for required in [
        "clamped-beam-2d",
        "clamped-beam-3d",
        "rod-tangential-2d",
        "rod-tangential-3d",
    ] {
        assert!(
            names.iter().any(|n| n == required),
            "{required} missing: {names:?}"
        );
    }
}
