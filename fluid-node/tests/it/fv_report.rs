//! The work–precision study and the output writers: the study runs the Sod scene at two
//! resolutions with OSMP5 and the MUSCL–Hancock reference and writes its CSV and SVG; the CSV
//! and VTK writers give the documented columns and sizes.

use fluid_node::fv::FluidSolver;
use fluid_node::output::{write_fluid_csv, write_fluid_vtk};
use fluid_node::report::work_precision;

fn scene(name: &str) -> protocol::scene::Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../scenes")
        .join(format!("{name}.toml"));
    let text = std::fs::read_to_string(&path).expect("scene file");
    protocol::scene::Scene::from_toml_str(&text, name).expect("valid scene")
}

#[test]
fn work_precision_writes_table_and_plot() {
    let sod = scene("sod");
    let dir = std::env::temp_dir().join(format!("fv_report_{}", std::process::id()));
    let rows = work_precision(&sod, &[100, 200], &[5], &dir).expect("study runs");
    assert_eq!(rows.len(), 4);
    for scheme in ["osmp5", "muscl-hancock"] {
        let r: Vec<_> = rows.iter().filter(|r| r.scheme == scheme).collect();
        assert_eq!(r.len(), 2);
        assert!(r[1].l1_rho < 0.75 * r[0].l1_rho, "{scheme}: {r:?}");
        // The timing was taken (it starts at infinity and keeps the best of the repeats).
        for row in &r {
            assert!(row.wall_s.is_finite() && row.wall_s > 0.0, "{row:?}");
            assert!(row.steps > 0, "{row:?}");
        }
    }
    // OSMP5 at N = 200 matches the tests' exact-average setup (1.2607e-3 within 10 %).
    let osmp = rows
        .iter()
        .find(|r| r.scheme == "osmp5" && r.cells == 200)
        .expect("row");
    assert!(osmp.l1_rho < 1.1 * 1.2607e-3, "{osmp:?}");
    let csv = std::fs::read_to_string(dir.join("work_precision_sod.csv")).expect("csv written");
    assert_eq!(csv.lines().count(), 5);
    assert!(csv.starts_with("scheme,order,cells,steps,wall_s,l1_rho"));
    // The table holds the measured times, row for row.
    for (line, row) in csv.lines().skip(1).zip(&rows) {
        let wall: f64 = line
            .split(',')
            .nth(4)
            .expect("wall_s")
            .parse()
            .expect("number");
        // (written with 7 significant digits)
        assert!(
            (wall - row.wall_s).abs() <= 1e-6 * row.wall_s,
            "{line} vs {row:?}"
        );
    }
    let svg = std::fs::read_to_string(dir.join("work_precision_sod.svg")).expect("svg written");
    assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
    assert_eq!(svg.matches("<polyline").count(), 2);
    let _ = std::fs::remove_dir_all(&dir);
    // A 2-D scene is refused with a message.
    let err = work_precision(&scene("isentropic-vortex"), &[10], &[5], &dir).expect_err("2-D");
    assert!(err.to_string().contains("1-D"), "{err}");
}

#[test]
fn csv_and_vtk_writers() {
    let vortex = scene("isentropic-vortex");
    let mut fluid = vortex.fluid.clone().expect("fluid");
    fluid.cells = vec![4, 3];
    // The free stream alone (the scene's vortex profile replaced by a uniform state).
    fluid.profile = None;
    fluid.init = vec![protocol::scene::InitEntry {
        region: protocol::scene::Region::All,
        rho: 1.0,
        p: 1.0,
        velocity: vec![1.0, 1.0],
    }];
    let s = FluidSolver::from_scene(&fluid, 1).expect("solver");
    let mut out = Vec::new();
    write_fluid_csv(&mut out, s.grid(), s.state(), 1.4, None).expect("in memory");
    let text = String::from_utf8(out).expect("utf8");
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("x,y,rho,u,v,p,alpha"));
    let first: Vec<f64> = lines
        .next()
        .expect("a row")
        .split(',')
        .map(|v| v.parse().expect("number"))
        .collect();
    assert_eq!(first.len(), 7);
    assert!((first[0] - 1.25).abs() < 1e-12 && (first[1] - 10.0 / 6.0).abs() < 1e-9);
    assert!((first[2] - 1.0).abs() < 1e-12 && (first[5] - 1.0).abs() < 1e-12 && first[6] == 1.0);
    assert_eq!(text.lines().count(), 13);
    let alpha = vec![0.5; 12];
    let mut out = Vec::new();
    write_fluid_vtk(&mut out, s.grid(), s.state(), 1.4, Some(&alpha), "vortex").expect("vtk");
    let vtk = String::from_utf8(out).expect("utf8");
    assert!(vtk.contains("DIMENSIONS 5 4 2") && vtk.contains("CELL_DATA 12"));
    assert_eq!(vtk.lines().filter(|l| *l == "0.5").count(), 12);
    // 1-D Sod: only x, u.
    let sod = scene("sod");
    let s = FluidSolver::from_scene(sod.fluid.as_ref().expect("fluid"), 1).expect("solver");
    let mut out = Vec::new();
    write_fluid_csv(&mut out, s.grid(), s.state(), 1.4, None).expect("in memory");
    let text = String::from_utf8(out).expect("utf8");
    assert!(text.starts_with("x,rho,u,p,alpha\n"));
    assert_eq!(text.lines().count(), 401);
}
