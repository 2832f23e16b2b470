//! End-to-end test of `fluid-node cut-cells` through the library `run` function: a 3-D STL box
//! moved by a rigid motion and a 2-D CSV of two loops, checking the JSON line and the files (the
//! VTK XML ones decoded and compared with the CSV ones).

#![cfg(feature = "node")]

use std::path::PathBuf;

use fluid_node::cutcell_cmd::{CutCellsArgs, run, run_to_json};

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("cutcell_cmd_{name}_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The value of `key` in a flat JSON object line (numbers only).
fn field(json: &str, key: &str) -> f64 {
    let at = json
        .find(&format!("\"{key}\":"))
        .unwrap_or_else(|| panic!("{key} missing in {json}"));
    let rest = &json[at + key.len() + 3..];
    let end = rest.find([',', '}']).unwrap();
    rest[..end]
        .parse()
        .unwrap_or_else(|_| panic!("{key}: {:?}", &rest[..end]))
}

const SCENE_3D: &str = r#"
name = "cut"
[fluid]
lower = [0.0, 0.0, 0.0]
upper = [1.0, 1.0, 1.0]
cells = [10, 12, 9]
[[fluid.init]]
region = "all"
rho = 1.0
p = 1.0
"#;

/// ASCII STL of the box [lo, hi] rotated about z by `angle` around (0.5, 0.5) and shifted.
fn box_stl(lo: [f64; 3], hi: [f64; 3], angle: f64, shift: [f64; 3]) -> String {
    let corner = |k: usize| {
        let p = [
            if k & 1 == 0 { lo[0] } else { hi[0] },
            if k & 2 == 0 { lo[1] } else { hi[1] },
            if k & 4 == 0 { lo[2] } else { hi[2] },
        ];
        let (s, c) = angle.sin_cos();
        let d = [p[0] - 0.5, p[1] - 0.5];
        [
            0.5 + c * d[0] - s * d[1] + shift[0],
            0.5 + s * d[0] + c * d[1] + shift[1],
            p[2] + shift[2],
        ]
    };
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let mut text = String::from("solid box\n");
    for q in quads {
        for t in [[q[0], q[1], q[2]], [q[0], q[2], q[3]]] {
            text.push_str("facet normal 0 0 0\nouter loop\n");
            for v in t {
                let x = corner(v);
                text.push_str(&format!("vertex {:e} {:e} {:e}\n", x[0], x[1], x[2]));
            }
            text.push_str("endloop\nendfacet\n");
        }
    }
    text.push_str("endsolid box\n");
    text
}

/// Columns `cols` of a CSV file's rows, as numbers.
fn csv_rows(path: &std::path::Path, cols: &[usize]) -> Vec<Vec<f64>> {
    csv::Reader::from_path(path)
        .unwrap()
        .records()
        .map(|row| {
            let row = row.unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            cols.iter().map(|&c| row[c].parse().unwrap()).collect()
        })
        .collect()
}

/// `solid_fraction.vti` and `subfaces.vtp` hold what `cells.csv` and `subfaces.csv` hold (both
/// written as the shortest text that reads back to the same double, so equal bits).
fn check_xml_against_csv(out: &std::path::Path, dim: usize) {
    use protocol::vtk::read;
    let image = read::parse(&std::fs::read(out.join("solid_fraction.vti")).unwrap()).unwrap();
    let fraction = image.array("CellData", "solid_fraction").unwrap();
    let fraction = fraction.as_f64().unwrap();
    let cells = csv_rows(&out.join("cells.csv"), &[0, 4]);
    assert!(!cells.is_empty());
    for row in &cells {
        assert_eq!(
            fraction[row[0] as usize].to_bits(),
            row[1].to_bits(),
            "cell {}",
            row[0]
        );
    }
    let listed = cells.iter().filter(|r| r[1] != 0.0).count();
    assert_eq!(fraction.iter().filter(|f| **f != 0.0).count(), listed);

    let poly = read::parse(&std::fs::read(out.join("subfaces.vtp")).unwrap()).unwrap();
    let tag = if dim == 3 { "Polys" } else { "Lines" };
    let rows = csv_rows(&out.join("subfaces.csv"), &[0, 6, 7, 8, 9]);
    assert_eq!(
        poly.piece[&format!("NumberOf{tag}")],
        rows.len().to_string()
    );
    let area = poly.array("CellData", "area").unwrap().as_f64().unwrap();
    let cell = poly.array("CellData", "cell").unwrap().as_i64().unwrap();
    let normal = poly.array("CellData", "normal").unwrap().as_f64().unwrap();
    for (s, row) in rows.iter().enumerate() {
        assert_eq!(cell[s], row[0] as i64, "sub-face {s}");
        assert_eq!(area[s].to_bits(), row[1].to_bits(), "sub-face {s}");
        for d in 0..3 {
            assert_eq!(
                normal[3 * s + d].to_bits(),
                row[2 + d].to_bits(),
                "sub-face {s}"
            );
        }
    }
    let offsets = poly.array(tag, "offsets").unwrap().as_i64().unwrap();
    let points = poly.array("Points", "Points").unwrap().as_f64().unwrap();
    assert_eq!(offsets.len(), rows.len());
    assert_eq!(
        poly.array(tag, "connectivity").unwrap().values.len() as i64,
        *offsets.last().unwrap()
    );
    assert!(points.len() >= 3 * dim);
}

#[test]
fn three_dimensional_box_with_motion() {
    let dir = temp_dir("3d");
    std::fs::write(dir.join("scene.toml"), SCENE_3D).unwrap();
    let (lo, hi) = ([0.3, 0.25, 0.2], [0.7, 0.65, 0.75]);
    std::fs::write(dir.join("body.stl"), box_stl(lo, hi, 0.3, [0.0; 3])).unwrap();
    std::fs::write(
        dir.join("moved.stl"),
        box_stl(lo, hi, 0.34, [0.05, -0.03, 0.04]),
    )
    .unwrap();
    let args = CutCellsArgs {
        scene: dir.join("scene.toml"),
        surface: dir.join("body.stl"),
        to: Some(dir.join("moved.stl")),
        out: dir.join("out"),
    };
    let json = run_to_json(&args).unwrap();
    eprintln!("{json}");
    let volume = 0.4 * 0.4 * 0.55;
    assert!((field(&json, "solid_volume") - volume).abs() <= 1e-12 * volume);
    let area = 2.0 * (0.4 * 0.4 + 2.0 * 0.4 * 0.55);
    assert!((field(&json, "wet_area") - area).abs() <= 1e-12 * area);
    assert!(field(&json, "cut_cells") > 0.0);
    // The computation was timed: a finite, positive duration (not the 0 or null of a field
    // that was never set).
    let compute_s = field(&json, "compute_s");
    assert!(compute_s.is_finite() && compute_s > 0.0, "{compute_s}");
    assert!(field(&json, "swept_volume").abs() <= 1e-13);
    assert!(field(&json, "max_cell_residual") <= 1e-12);
    for name in [
        "solid_fraction.vtk",
        "face_fraction.vtk",
        "subfaces.vtk",
        "cells.csv",
        "faces.csv",
        "subfaces.csv",
        "swept.csv",
    ] {
        let text = std::fs::read_to_string(dir.join("out").join(name)).unwrap();
        assert!(text.lines().count() > 2, "{name} is empty");
    }
    let vtk = std::fs::read_to_string(dir.join("out/solid_fraction.vtk")).unwrap();
    assert!(vtk.contains("DIMENSIONS 11 13 10") && vtk.contains("CELL_DATA 1080"));
    check_xml_against_csv(&dir.join("out"), 3);
    // Printing variant.
    run(&args).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn two_dimensional_loops_and_errors() {
    let dir = temp_dir("2d");
    let scene = r#"
name = "cut2"
[fluid]
lower = [0.0, 0.0]
upper = [2.0, 1.0]
cells = [20, 10]
[[fluid.init]]
region = "all"
rho = 1.0
p = 1.0
"#;
    std::fs::write(dir.join("scene.toml"), scene).unwrap();
    // Two bodies; the second is clockwise in the file and gets reversed.
    let loops = "x,y\n0.2,0.2\n0.8,0.2\n0.8,0.6\n0.2,0.6\n\n1.2,0.3\n1.2,0.7\n1.7,0.7\n1.7,0.3\n";
    std::fs::write(dir.join("body.csv"), loops).unwrap();
    let moved = "x,y\n0.25,0.22\n0.85,0.22\n0.85,0.62\n0.25,0.62\n\n1.2,0.33\n1.2,0.73\n1.7,0.73\n1.7,0.33\n";
    std::fs::write(dir.join("moved.csv"), moved).unwrap();
    let mut args = CutCellsArgs {
        scene: dir.join("scene.toml"),
        surface: dir.join("body.csv"),
        to: Some(dir.join("moved.csv")),
        out: dir.join("out"),
    };
    let json = run_to_json(&args).unwrap();
    eprintln!("{json}");
    let area = 0.6 * 0.4 + 0.5 * 0.4;
    assert!((field(&json, "solid_volume") - area).abs() <= 1e-12 * area);
    assert!((field(&json, "wet_area") - (2.0 + 1.8)).abs() <= 1e-12);
    assert!(field(&json, "max_cell_residual") <= 1e-12);
    check_xml_against_csv(&dir.join("out"), 2);
    // Errors are reported, not panics.
    args.surface = dir.join("missing.csv");
    let err = run_to_json(&args).unwrap_err();
    assert!(format!("{err:#}").contains("missing.csv"), "{err:#}");
    args.surface = dir.join("body.csv");
    std::fs::write(dir.join("short.csv"), "0.2,0.2\n0.8,0.2\n0.8,0.6\n").unwrap();
    args.to = Some(dir.join("short.csv"));
    let err = run_to_json(&args).unwrap_err();
    assert!(format!("{err:#}").contains("same elements"), "{err:#}");
    // An output folder whose name holds a tab, a quote and a backslash: the line is still JSON
    // (a JSON parser reads it), and gives the path back unchanged.
    args.to = None;
    args.out = dir.join("out\tquote\"back\\slash");
    let json = run_to_json(&args).unwrap();
    let doc: serde_json::Value =
        serde_json::from_str(&json).unwrap_or_else(|e| panic!("{e}: {json}"));
    assert_eq!(doc["out"], args.out.display().to_string());
    let solid = doc["solid_volume"].as_f64().expect("a number");
    assert!((solid - area).abs() <= 1e-12 * area, "{solid}");
    assert!(
        doc.get("swept_volume").is_none(),
        "no --to, no swept volume: {json}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
