//! `coupler-node report figures` on a small hand-written run folder: the files it writes and
//! the numbers in them.

use std::path::PathBuf;

use coupler_node::report;
use coupler_node::report::plot::{AXIS_LABELS, Ticks};
use proptest::prelude::*;

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

/// One output at t = 0.1 and a ledger of two steps.
fn write_outputs_and_ledger(run: &std::path::Path) {
    std::fs::write(run.join("outputs.csv"), "k,t\n0,0.1\n").expect("outputs");
    std::fs::write(
        run.join("ledger.csv"),
        "t,step,mass_rel_err,energy_rel_err\n0.05,0,1e-16,2e-7\n0.1,1,3e-16,1e-7\n",
    )
    .expect("ledger");
}

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
    write_outputs_and_ledger(&run);
    std::fs::write(
        run.join("summary.json"),
        r#"{"scene":"tiny","status":"completed","steps":2,"coupling_iterations":{"mean":1.5,"max":2}}"#,
    )
    .expect("summary");

    let out = run.join("figures");
    let written = report::figures(&run, &out, false).expect("figures");
    let names: Vec<String> = written
        .iter()
        .map(|p| p.file_name().expect("name").to_string_lossy().into_owned())
        .collect();
    assert_eq!(
        names,
        [
            "ledger_mass.svg",
            "ledger_energy.svg",
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
            "field_0_rho.svg",
            "field_0_p.png",
            "field_0_p.svg",
            "index.html",
        ]
    );
    // The ledger's chart carries its numbers.
    let ledger = std::fs::read_to_string(out.join("ledger_energy.csv")).expect("csv");
    assert_eq!(ledger, "series,x,y\ntiny,5e-2,2e-7\ntiny,1e-1,1e-7\n");
    // The framed field: title with the field and the output's time, axes in metres, the colour
    // bar with the unit, and the PNG inside it, whole (base64 of 4 characters per 3 bytes).
    let framed = std::fs::read_to_string(out.join("field_0_p.svg")).expect("svg");
    assert!(
        framed.contains("tiny: pressure at t = 1e-1 s (output 0)"),
        "{framed}"
    );
    assert!(framed.contains("x [m]") && framed.contains("y [m]") && framed.contains("p [Pa]"));
    let png = std::fs::read(out.join("field_0_p.png")).expect("png");
    let data = framed
        .split("base64,")
        .nth(1)
        .and_then(|rest| rest.split('"').next())
        .expect("an embedded image");
    assert_eq!(data.len(), png.len().div_ceil(3) * 4);
    assert!(data.starts_with("iVBORw0KGgo"), "a PNG's signature");
    // x from 0 to 2 m and y from 0 to 1 m, in one decimal: 0.0 on both axes, 2.0 on x alone.
    assert_eq!(framed.matches(">0.0<").count(), 2, "{framed}");
    assert_eq!(framed.matches(">2.0<").count(), 1, "{framed}");
    // The page: the summary and every SVG, in that order.
    let page = std::fs::read_to_string(out.join("index.html")).expect("page");
    assert!(
        page.contains("<th>coupling_iterations.max</th><td>2</td>"),
        "{page}"
    );
    let mut at = page.find("<h2>Summary</h2>").expect("summary");
    for name in names.iter().filter(|n| n.ends_with(".svg")) {
        let here = page[at..]
            .find(&format!("<img src=\"{name}\""))
            .unwrap_or_else(|| panic!("{name} not on the page after byte {at}"));
        at += here;
    }
    assert!(page.contains("<h3>Output 0 (t = 1e-1 s)</h3>"), "{page}");
    // The numbers behind a chart are the probe's, exactly.
    let rows: Vec<(String, f64, f64)> = csv::Reader::from_path(out.join("probes_displacement.csv"))
        .expect("csv")
        .deserialize()
        .collect::<Result<_, _>>()
        .expect("rows of a label and two numbers");
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

proptest! {
    #![proptest_config(ProptestConfig { cases: 500, ..ProptestConfig::default() })]

    /// Tick labels tell every tick of an axis apart, read back as their values (to half a unit
    /// of their last decimal), and stay short, whatever the axis's range.
    #[test]
    fn tick_labels_are_distinct_and_read_back(
        centre in -1e3f64..1e3,
        scale in -12i32..13,
        span_digits in -6i32..3,
    ) {
        let size = 10f64.powi(scale);
        let (c, span) = (centre * size, 10f64.powi(span_digits) * size);
        let range = (c - span / 2.0)..(c + span / 2.0);
        prop_assume!(range.end > range.start);
        let ticks = Ticks::new(&range, AXIS_LABELS);
        prop_assert!(ticks.values.len() >= 2, "{ticks:?}");
        let labels: Vec<String> = ticks.values.iter().map(|&v| ticks.label(v)).collect();
        for (i, a) in labels.iter().enumerate() {
            prop_assert!(!labels[i + 1..].contains(a), "{a} repeated in {labels:?}");
            prop_assert!(a.len() <= 12, "{a} too long ({ticks:?})");
        }
        let unit = 10f64.powi(ticks.exponent);
        for (v, l) in ticks.values.iter().zip(&labels) {
            let back = l.parse::<f64>().expect("a number") * unit + ticks.offset;
            let half = 0.5 * 10f64.powi(-(ticks.decimals as i32)) * unit;
            prop_assert!((back - v).abs() <= half * (1.0 + 1e-9) + 1e-12 * v.abs(), "{l} for {v}");
        }
    }
}

/// The page `report figures` writes opens in a real browser with every image loaded: headless
/// Chromium (`$COSIM_CHROMIUM`, else `chromium` on the PATH; `.ci/run` installs Debian's)
/// dumps the DOM after the page's load event, which marks each image with its natural width.
#[test]
fn the_report_page_loads_every_image_in_a_browser() {
    let run = run_dir("browser");
    std::fs::write(run.join("scene.toml"), SCENE).expect("scene");
    let mut fluid = String::from("x,y,rho,u,v,p,alpha\n");
    for (i, j) in [
        (0, 0),
        (1, 0),
        (2, 0),
        (3, 0),
        (0, 1),
        (1, 1),
        (2, 1),
        (3, 1),
    ] {
        let (x, y) = (0.25 + 0.5 * i as f64, 0.25 + 0.5 * j as f64);
        fluid.push_str(&format!("{x},{y},{},0,0,{},1\n", 1.0 + x, 1e5 * (1.0 + y)));
    }
    std::fs::write(run.join("fluid_0.csv"), fluid).expect("fluid");
    write_outputs_and_ledger(&run);
    std::fs::write(
        run.join("probe_tip.csv"),
        "t,x,y,sigma_n\n0,1.02,1,0\n0.05,1.02001,1.00002,1e6\n0.1,1.02003,1.00001,3e6\n",
    )
    .expect("probe");
    let out = run.join("report");
    let written = report::figures(&run, &out, false).expect("figures");
    let images = written
        .iter()
        .filter(|p| p.extension().is_some_and(|e| e == "svg"))
        .count();
    assert_eq!(images, 7, "{written:?}");
    let browser = std::env::var("COSIM_CHROMIUM").unwrap_or_else(|_| "chromium".into());
    let profile = run.join("profile");
    let dump = std::process::Command::new(&browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--allow-file-access-from-files",
            "--virtual-time-budget=10000",
            &format!("--user-data-dir={}", profile.display()),
            "--dump-dom",
        ])
        .arg(format!("file://{}", out.join("index.html").display()))
        .output()
        .unwrap_or_else(|e| {
            panic!("running {browser} ({e}): install Chromium (Debian: apt-get install chromium) or set COSIM_CHROMIUM")
        });
    let dom = String::from_utf8_lossy(&dump.stdout);
    assert!(
        dom.contains("data-loaded=\"yes\""),
        "the load event did not run: {dom}"
    );
    let widths: Vec<u64> = dom
        .split("data-natural-width=\"")
        .skip(1)
        .map(|rest| rest.split('"').next().unwrap().parse().unwrap())
        .collect();
    assert_eq!(dom.matches("<img ").count(), images, "{dom}");
    assert_eq!(widths.len(), images, "{dom}");
    assert!(
        widths.iter().all(|&w| w > 0),
        "an image did not load: {widths:?}"
    );
    let _ = std::fs::remove_dir_all(run);
}
