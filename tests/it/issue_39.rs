//! Issue 39 item 1: a run opens in ParaView out of the box. A coupled 2-D scene that names no
//! `output.formats` writes the VTK XML series of the fluid, the particles, the solid and the wet
//! surface, and VTK's own readers (`vtkXMLImageDataReader`, `vtkXMLPolyDataReader`, Python
//! `vtk`) load every file without an error; the fluid lies in the plane z = 0 and hides
//! exactly the cells the solid covers (`vtkGhostType`).

use std::process::Command;

use crate::e2e::{out_dir, python, run_scene, summary, workspace};

#[test]
fn a_coupled_run_writes_vtk_series_that_vtks_readers_load() {
    let dir = out_dir("issue-39-vtk");
    std::fs::create_dir_all(&dir).expect("dir");
    let scene = dir.join("beam.toml");
    // The beam of issue_39_views (which reads the same run's Foxglove channels), named apart.
    std::fs::write(
        &scene,
        crate::issue_39_views::SCENE.replace("\"viewbeam\"", "\"vtkbeam\""),
    )
    .expect("scene");
    let out = dir.join("out");
    run_scene(&scene, &out, &[]);
    assert_eq!(summary(&out)["steps"], 4);
    for series in ["fluid.pvd", "particles.pvd", "solid.pvd", "wet.pvd"] {
        assert!(out.join(series).is_file(), "{series} written by default");
    }
    let check = Command::new(python())
        .arg(workspace().join("tests/py/check_vtk.py"))
        .arg(&out)
        .output()
        .expect("python runs");
    let text = String::from_utf8_lossy(&check.stdout);
    assert!(
        check.status.success(),
        "{text}{}",
        String::from_utf8_lossy(&check.stderr)
    );
    // The cells wholly inside the beam are hidden in every fluid file: x in [0.9, 1.1] holds 6
    // columns of 1/32 m, y in [0, 0.7125] 34 rows of 1/48 m, 204 cells (4 steps barely move
    // it); the grid's 64 x 48 cells lie in the plane z = 0 (checked by the script).
    let fluid: Vec<&str> = text
        .lines()
        .filter(|l| l.starts_with("fluid.pvd"))
        .collect();
    assert_eq!(fluid.len(), 2, "{text}");
    for line in &fluid {
        assert!(
            line.contains("3072 cells, 204 hidden, dimensions (65, 49, 1)"),
            "{line}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
