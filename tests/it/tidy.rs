//! House rules checked on the source tree (rust-analyzer's tidy test): every `.rs` file opens
//! with a `//!` doc, no `dbg!`, and `protocol` does no IO outside its bus and replay modules;
//! no file or function too long ([`lengths`]) and no import circle between a crate's files
//! ([`circles`]).

use std::path::{Path, PathBuf};

mod circles;
mod lengths;

fn rust_files(dir: &Path, acc: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("readable dir") {
        let path = entry.expect("entry").path();
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
        if path.is_dir() {
            if !name.starts_with('.') && name != "target" {
                rust_files(&path, acc);
            }
        } else if name.ends_with(".rs") {
            acc.push(path);
        }
    }
}

/// The workspace's folder.
fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn crate_files() -> Vec<PathBuf> {
    let root = workspace_root();
    let mut files = Vec::new();
    for krate in [
        "protocol",
        "fluid-node",
        "solid-node",
        "coupler-node",
        "tests",
    ] {
        rust_files(&root.join(krate), &mut files);
    }
    files
}

#[test]
fn every_file_starts_with_a_module_doc() {
    let files = crate_files();
    assert!(files.len() > 50, "{} files", files.len());
    let missing: Vec<String> = files
        .iter()
        .filter(|p| {
            let text = std::fs::read_to_string(p).expect("readable");
            !text.trim_start().starts_with("//!")
        })
        .map(|p| p.display().to_string())
        .collect();
    assert!(
        missing.is_empty(),
        "files without a //! header: {missing:?}"
    );
}

#[test]
fn no_dbg_macro() {
    let needle = concat!("dbg", "!(");
    let offenders: Vec<String> = crate_files()
        .iter()
        .filter(|p| {
            std::fs::read_to_string(p)
                .expect("readable")
                .contains(needle)
        })
        .map(|p| p.display().to_string())
        .collect();
    assert!(offenders.is_empty(), "{offenders:?}");
}

#[test]
fn protocol_core_does_no_io() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../protocol/src");
    let mut names: Vec<String> = [
        "lib.rs",
        "wire.rs",
        "codec.rs",
        "transport.rs",
        "session.rs",
        "mcap_read.rs",
    ]
    .map(String::from)
    .to_vec();
    // The scene schema, one file per section.
    for entry in std::fs::read_dir(src.join("scene")).expect("protocol/src/scene") {
        let name = entry
            .expect("entry")
            .file_name()
            .to_string_lossy()
            .into_owned();
        names.push(format!("scene/{name}"));
    }
    assert!(names.len() > 6, "{names:?}");
    for name in &names {
        let text = std::fs::read_to_string(src.join(name)).expect("readable");
        for banned in [
            "std::fs",
            "std::net",
            "std::env",
            "std::thread",
            "std::process",
        ] {
            assert!(!text.contains(banned), "protocol/src/{name} uses {banned}");
        }
    }
}

#[test]
fn solver_cores_do_no_io() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut files = Vec::new();
    for core in [
        "fluid-node/src/fv",
        "fluid-node/src/cutcell",
        "fluid-node/src/embedded",
        "solid-node/src/dem",
    ] {
        rust_files(&root.join(core), &mut files);
    }
    assert!(files.len() > 10);
    for path in files {
        let text = std::fs::read_to_string(&path).expect("readable");
        for banned in [
            "std::fs",
            "std::net",
            "std::env",
            "Instant::now",
            "SystemTime",
            "iceoryx2",
            "mcap",
        ] {
            assert!(!text.contains(banned), "{} uses {banned}", path.display());
        }
    }
}
