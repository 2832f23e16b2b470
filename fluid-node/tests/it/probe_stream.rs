//! Issue 38 item 8: probe rows go to their files as the run goes, so a node's memory does not
//! grow with the steps: nothing is written while fewer than `PROBE_ROWS_HELD` rows are held,
//! then every held row is appended, and the end writes the rest; the file is the one a single
//! write at the end gave (header and one row per step, in order).

use fluid_node::exchange::RealFluid;
use protocol::scene::Scene;
use protocol::session::{NodeModel, PROBE_ROWS_HELD};

#[test]
fn probe_rows_are_written_as_they_come_and_the_file_is_whole() {
    let scene = Scene::from_toml_str(
        r#"name = "probes"
[fluid]
lower = [0.0]
upper = [1.0]
cells = [8]
boundary = { x = ["wall", "wall"] }
[[fluid.init]]
region = "all"
rho = 1.0
p = 1.0
[[output.probes]]
name = "mid"
point = [0.5]
"#,
        "probes.toml",
    )
    .expect("scene");
    let mut fluid = RealFluid::from_scene(&scene).expect("fluid");
    let out = std::env::temp_dir().join(format!("cosim-probe-stream-{}", std::process::id()));
    std::fs::create_dir_all(&out).expect("out");
    let file = out.join("probe_mid.csv");
    let lines = || std::fs::read_to_string(&file).map(|t| t.lines().count());
    let n = 2 * PROBE_ROWS_HELD + 7;
    for step in 0..n {
        fluid.record_probes(step as f64 * 1e-3);
        fluid.write_probes(&out, false).expect("written");
        let rows = step + 1;
        // Written once PROBE_ROWS_HELD rows are held, then every PROBE_ROWS_HELD more.
        let expected =
            (rows >= PROBE_ROWS_HELD).then(|| 1 + rows / PROBE_ROWS_HELD * PROBE_ROWS_HELD);
        assert_eq!(lines().ok(), expected, "after {rows} rows");
    }
    fluid.write_probes(&out, true).expect("written");
    let text = std::fs::read_to_string(&file).expect("file");
    let mut it = text.lines();
    assert_eq!(it.next(), Some("t,rho,u,p"));
    for (step, line) in it.enumerate() {
        let t: f64 = line.split(',').next().unwrap().parse().unwrap();
        assert_eq!(t, step as f64 * 1e-3, "row {step}: {line}");
        assert_eq!(
            &line[line.find(',').unwrap()..],
            ",1e0,0e0,1e0",
            "row {step}"
        );
    }
    assert_eq!(text.lines().count(), 1 + n);
    let _ = std::fs::remove_dir_all(&out);
}
