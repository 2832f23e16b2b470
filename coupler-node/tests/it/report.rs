//! `coupler-node report figures` on a small hand-written run folder: the files it writes and
//! the numbers in them.

use std::path::PathBuf;

use coupler_node::report;

const SCENE: &str = r#"
name = "tiny"
[run]
t_end = 0.1
[fluid]
lower = [0.0, 0.0]
upper = [2.0, 1.0]
cells = [4, 2]
[[fluid.init]]
region = "all"
rho = 1.0
p = 1.0
"#;

fn run_dir(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("cosim-report-{test}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("dir");
    dir
}

#[test]
fn figures_plot_the_probes_and_draw_each_field() {
    let run = run_dir("figures");
    std::fs::write(run.join("scene.toml"), SCENE).expect("scene");
    std::fs::write(
        run.join("probe_tip.csv"),
        "t,x,y,vx,vy,theta,omega,sigma_n\n0,2,1,0,0,0,0,-1\n0.05,2.01,1,0,0,0,0,3\n",
    )
    .expect("probe");
    std::fs::write(
        run.join("probe_far.csv"),
        "t,x,y,sigma_n\n0,3,1,0\n0.05,3.5,1,1\n",
    )
    .expect("probe");
    std::fs::write(
        run.join("probe_gas.csv"),
        "t,rho,u,v,p\n0,1,0,0,1\n0.1,1,0,0,2\n",
    )
    .expect("probe");
    // Six of the eight cells hold fluid.
    let mut fluid = String::from("x,y,rho,u,v,p,alpha\n");
    for (i, j) in [(0, 0), (1, 0), (2, 0), (3, 0), (0, 1), (3, 1)] {
        let (x, y) = (0.25 + 0.5 * i as f64, 0.25 + 0.5 * j as f64);
        fluid.push_str(&format!("{x},{y},{},0,0,{},1\n", 1.0 + x, 2.0 * y));
    }
    std::fs::write(run.join("fluid_0.csv"), fluid).expect("fluid");
    std::fs::write(
        run.join("surface_0.csv"),
        "element,particle,wet,x0,y0,x1,y1\n0,0,1,0.5,0.5,1.5,0.5\n",
    )
    .expect("surface");

    let out = run.join("figures");
    let written = report::figures(&run, &out, false).expect("figures");
    let names: Vec<String> = written
        .iter()
        .map(|p| p.file_name().expect("name").to_string_lossy().into_owned())
        .collect();
    assert_eq!(
        names,
        [
            "probe_far_x.svg",
            "probe_far_xy.svg",
            "probe_far_sigma.svg",
            "probe_gas_p.svg",
            "probe_tip_x.svg",
            "probe_tip_xy.svg",
            "probe_tip_sigma.svg",
            "probes_displacement.svg",
            "probes_sigma.svg",
            "field_0_rho.png",
            "field_0_p.png",
        ]
    );
    // The numbers behind a chart are the probe's, exactly.
    let csv = std::fs::read_to_string(out.join("probes_displacement.csv")).expect("csv");
    let rows: Vec<(String, f64, f64)> = csv
        .lines()
        .skip(1)
        .map(|l| {
            let v: Vec<&str> = l.split(',').collect();
            (
                v[0].to_string(),
                v[1].parse().unwrap(),
                v[2].parse().unwrap(),
            )
        })
        .collect();
    assert_eq!(rows.len(), 4);
    assert_eq!(rows[1].0, "far");
    assert_eq!((rows[1].1, rows[1].2), (0.05, 0.5));
    assert_eq!(rows[3].0, "tip");
    assert!((rows[3].2 - 0.01).abs() < 1e-15, "{rows:?}");
    let svg = std::fs::read_to_string(out.join("probe_tip_x.svg")).expect("svg");
    assert!(svg.starts_with("<svg") && svg.contains("tip: x of the particle"));
    // 1000 px over 4 cells: 250 px a cell.
    let png = std::fs::read(out.join("field_0_p.png")).expect("png");
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    let width = u32::from_be_bytes(png[16..20].try_into().unwrap());
    let height = u32::from_be_bytes(png[20..24].try_into().unwrap());
    assert_eq!((width, height), (1000, 500));
    let _ = std::fs::remove_dir_all(run);
}

#[test]
fn figures_of_a_folder_that_is_not_a_run_say_so() {
    let run = run_dir("not-a-run");
    let err = report::figures(&run, &run.join("figures"), false).expect_err("no scene");
    assert!(
        format!("{err:#}").contains("the output folder of a run"),
        "{err:#}"
    );
    std::fs::write(run.join("scene.toml"), SCENE).expect("scene");
    std::fs::write(run.join("probe_tip.csv"), "t,x,y\n0,1\n").expect("probe");
    let err = report::figures(&run, &run.join("figures"), false).expect_err("ragged");
    assert!(
        format!("{err:#}").contains("line 2 has 2 values"),
        "{err:#}"
    );
    let err = report::energy(std::slice::from_ref(&run), &[1.0, 4.0], &run.join("e.svg"))
        .expect_err("scales");
    assert!(err.to_string().contains("2 scales for 1 runs"), "{err}");
    let _ = std::fs::remove_dir_all(run);
}

#[test]
fn pressure_error_is_the_largest_deviation_of_each_output() {
    let run = run_dir("pressure");
    std::fs::write(run.join("outputs.csv"), "k,t\n0,0.1\n1,0.2\n").expect("outputs");
    std::fs::write(
        run.join("fluid_0.csv"),
        "x,y,rho,u,v,p,alpha\n0,0,1,0,0,1,1\n1,0,1,0,0,1,1\n",
    )
    .expect("fluid");
    std::fs::write(
        run.join("fluid_1.csv"),
        "x,y,rho,u,v,p,alpha\n0,0,1,0,0,1.25,1\n1,0,1,0,0,0.5,1\n",
    )
    .expect("fluid");
    let e = report::pressure_error(&run, 1.0).expect("pressure");
    assert_eq!(e, [(0.1, 0.0), (0.2, 0.5)]);
    let out = run.join("p.svg");
    report::pressure(std::slice::from_ref(&run), 1.0, &out).expect("chart");
    let csv = std::fs::read_to_string(out.with_extension("csv")).expect("csv");
    assert!(csv.ends_with(",2e-1,5e-1\n"), "{csv}");
    std::fs::remove_file(run.join("fluid_1.csv")).expect("remove");
    let err = report::pressure_error(&run, 1.0).expect_err("a missing output");
    assert!(format!("{err:#}").contains("fluid_1.csv"), "{err:#}");
    let _ = std::fs::remove_dir_all(run);
}
