//! The real fluid and the real solid over iceoryx2: deterministic for any thread count, a
//! coupled step replayed, restarts from a checkpoint, doubles beside the real other node.

use super::*;

/// A small coupled scene: a shock on a free deformable block, the real fluid and the real solid.
const COUPLED: &str = r#"
name = "coupled-small"
[run]
t_end = 0.2
scheme = "semi-implicit"
record = "exchange"
checkpoint_every = 20
threads = THREADS
[fluid]
lower = [0.0, 0.0]
upper = [2.0, 1.0]
cells = [60, 30]
boundary = { x = ["wall", "wall"], y = ["wall", "wall"] }
[[fluid.init]]
region = "all"
rho = 1.4
p = 1.0
[[fluid.init]]
region = { box = { lower = [0.0, 0.0], upper = [0.5, 1.0] } }
rho = 5.6
p = 10.0
[solid]
density = 100.0
young = 7000.0
poisson = 0.0
[[solid.bodies]]
shape = { box = { center = [0.9, 0.45], size = [0.3, 0.3] } }
divisions = [4, 4]
[solid.prescribed]
box = { center = [0.9, 0.45], size = [0.3, 0.3] }
motion = { velocity = [0.5, 0.0] }
[fluid.pressure]
value = 1.0
gradient = [-1.0, 0.0]
[output]
every = 0.1
"#;

fn coupled_scene(dir: &Path, threads: u32) -> PathBuf {
    std::fs::create_dir_all(dir).expect("dir");
    let path = dir.join(format!("coupled-{threads}.toml"));
    std::fs::write(&path, COUPLED.replace("THREADS", &threads.to_string())).expect("scene");
    path
}

#[test]
fn the_real_fluid_and_solid_over_the_bus_are_deterministic_for_any_thread_count() {
    let dir = out_dir("coupled-det");
    let (a, b) = (dir.join("a"), dir.join("b"));
    run_scene(&coupled_scene(&dir, 1), &a, &[]);
    run_scene(&coupled_scene(&dir, 2), &b, &[]);
    let s = summary(&a);
    assert_eq!(s["status"], "completed", "{s}");
    assert_eq!(s["nodes"]["fluid"], "real");
    assert_eq!(s["nodes"]["solid"], "real");
    assert!(s["mass_rel_err"].as_f64().expect("mass") <= 1e-12, "{s}");
    assert!(
        s["coupling_iterations"]["max"].as_u64().expect("max") < 7,
        "{s}"
    );
    let (fa, fb) = (
        frames_by_topic(&a.join("exchange.mcap")),
        frames_by_topic(&b.join("exchange.mcap")),
    );
    assert!(fa.len() >= 6, "{} topics", fa.len());
    assert!(fa == fb, "1 and 2 threads recorded different payload bytes");
    // Log times (simulated time) and the diagnostics but their wall-clock part are the same.
    let (ta, da) = times_and_diagnostics(&a.join("exchange.mcap"));
    let (tb, db) = times_and_diagnostics(&b.join("exchange.mcap"));
    assert!(ta == tb, "1 and 2 threads recorded different log times");
    assert_eq!(da.len() as u64, s["steps"].as_u64().expect("steps"));
    assert!(da == db, "1 and 2 threads recorded different diagnostics");
    check_ledger_csv_and_record(&a);
    inspect_ends_quietly_on_a_closed_pipe(&a);
    // The bus carries exactly what the in-process run exchanges, on every channel.
    let text = std::fs::read_to_string(coupled_scene(&dir, 1)).expect("scene");
    let scene = protocol::scene::Scene::from_toml_str(&text, "coupled").expect("scene");
    let mem = cosim_tests::run_in_process(&scene);
    assert_eq!(mem.error, None);
    for (from, to, topic) in [
        (NodeKind::Solid, NodeKind::Coupler, "/solid-to-coupler"),
        (NodeKind::Fluid, NodeKind::Coupler, "/fluid-to-coupler"),
    ] {
        let mem_frames: Vec<&Vec<u8>> = mem
            .sink
            .frames
            .iter()
            .filter(|f| f.0 == from && f.1 == to)
            .map(|f| &f.2)
            .filter(|f| {
                codec::decode_header(f)
                    .is_ok_and(|h| h.kind != protocol::wire::MessageKind::Checkpoint)
            })
            .collect();
        let bus = &fa.iter().find(|(t, _)| t == topic).expect("topic").1;
        assert_eq!(mem_frames.len(), bus.len(), "{topic}");
        assert!(
            mem_frames.iter().zip(bus).all(|(m, b)| *m == b),
            "{topic}: bus and memory differ"
        );
    }
    // The coupled outputs: fluid cells with their fluid fraction, the wet surface, the loads.
    let fluid = std::fs::read_to_string(a.join("fluid_1.csv")).expect("fluid_1.csv");
    assert!(fluid.starts_with("x,y,rho,u,v,p,alpha\n"));
    let alphas = cosim_tests::csv_column(&a.join("fluid_1.csv"), "alpha");
    assert!(alphas.iter().all(|a| *a > 0.0 && *a <= 1.0));
    assert!(alphas.len() < 60 * 30, "covered cells are left out");
    assert!(alphas.iter().any(|a| *a < 1.0), "cut cells are listed");
    let surface = std::fs::read_to_string(a.join("surface_1.csv")).expect("surface_1.csv");
    assert!(surface.starts_with("element,particle,wet,x0,y0,x1,y1\n"));
    // The loads of the particles that own an element, by the solid's numbers (the fluid was
    // sent only those: issue 39 item 4), in order.
    let loads = std::fs::read_to_string(a.join("loads_1.csv")).expect("loads_1.csv");
    let mut owners = cosim_tests::csv_column(&a.join("surface_1.csv"), "particle");
    owners.sort_by(f64::total_cmp);
    owners.dedup();
    let loaded = cosim_tests::csv_column(&a.join("loads_1.csv"), "particle");
    assert_eq!(loaded, owners, "{loads}");
    assert!(
        loaded.len() < 16,
        "the inner particles own no element: {loads}"
    );
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn a_coupled_step_replays_identically() {
    let dir = out_dir("coupled-replay");
    let out = dir.join("run");
    run_scene(&coupled_scene(&dir, 1), &out, &[]);
    let file = out.join("exchange.mcap");
    for (step, node) in [
        ("30", "fluid"),
        ("30", "solid"),
        ("45", "fluid"),
        ("45", "coupler"),
    ] {
        assert_replays_identically(&file, step, node);
    }
    assert_restart_continues_identically(&out, 40, &dir.join("restart"));
    let _ = std::fs::remove_dir_all(dir);
}

/// `run --restart RUN/exchange.mcap --step STEP` of the run in `run` writes into `out` a record
/// whose frames from `step` on are the original's, byte for byte, on every channel (but the
/// checkpoints it sends the nodes to restore them), and ends with the same balance.
pub(super) fn assert_restart_continues_identically(run: &Path, step: u64, out: &Path) {
    let file = run.join("exchange.mcap");
    run_scene(
        &run.join("scene.toml"),
        out,
        &[
            "--restart",
            &file.to_string_lossy(),
            "--step",
            &step.to_string(),
        ],
    );
    let from = |path: &Path, skip_restores: bool| -> Vec<(String, Vec<u8>)> {
        let rec = record::read_recording(&std::fs::read(path).expect("record")).expect("read");
        rec.messages
            .into_iter()
            .filter(|m| m.step >= step && m.topic != "/diagnostics")
            .filter(|m| {
                !(skip_restores
                    && m.topic.starts_with("/coupler-to-")
                    && codec::decode_header(&m.data)
                        .is_ok_and(|h| h.kind == protocol::wire::MessageKind::Checkpoint))
            })
            .map(|m| (m.topic, m.data))
            .collect()
    };
    let by_topic = |frames: Vec<(String, Vec<u8>)>| {
        let mut t: std::collections::BTreeMap<String, Vec<Vec<u8>>> = Default::default();
        for (topic, data) in frames {
            t.entry(topic).or_default().push(data);
        }
        t
    };
    let original = by_topic(from(&file, false));
    let restarted = by_topic(from(&out.join("exchange.mcap"), true));
    assert!(original.len() >= 7, "{:?}", original.keys());
    for (topic, frames) in &original {
        let again = restarted.get(topic).map_or(0, Vec::len);
        assert_eq!(frames.len(), again, "{topic}: frames from step {step}");
        assert!(
            Some(frames) == restarted.get(topic),
            "{topic}: the restarted run's frames differ from the original's"
        );
    }
    let (a, b) = (summary(run), summary(out));
    for key in [
        "status",
        "steps",
        "t_end",
        "coupling_iterations",
        "mass_rel_err",
        "energy_rel_err",
        "energy_err_vs_exchange",
    ] {
        assert_eq!(a[key], b[key], "{key}");
    }
}

#[test]
fn a_restart_refuses_another_scene_and_a_step_without_checkpoints() {
    let dir = out_dir("restart-refusals");
    let run = dir.join("run");
    run_scene(&workspace().join("scenes/backbone-doubles.toml"), &run, &[]);
    let file = run.join("exchange.mcap").to_string_lossy().into_owned();
    let restart = |scene: &Path, step: &str| {
        let r = coupler()
            .arg("run")
            .arg(scene)
            .arg("--out")
            .arg(dir.join("restart"))
            .args(["--quiet", "--restart", &file, "--step", step])
            .output()
            .expect("coupler starts");
        assert!(!r.status.success());
        String::from_utf8_lossy(&r.stderr).into_owned()
    };
    // checkpoint_every = 20: steps 20, 40, ... have checkpoints, 30 has none.
    let err = restart(&run.join("scene.toml"), "30");
    assert!(
        err.contains("no /checkpoint/coupler at that step") && err.contains("[20, 40, 60"),
        "{err}"
    );
    let other = dir.join("other.toml");
    let text =
        std::fs::read_to_string(workspace().join("scenes/backbone-doubles.toml")).expect("scene");
    assert!(text.contains("tolerance = 1e-12"));
    std::fs::write(
        &other,
        text.replace("tolerance = 1e-12", "tolerance = 1e-10"),
    )
    .expect("write");
    let err = restart(&other, "40");
    assert!(
        err.contains("the scene differs from the recorded one"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn doubles_stand_in_for_either_node_beside_the_real_other() {
    let dir = out_dir("coupled-doubles");
    let scene = coupled_scene(&dir, 1);
    // A box moving at 0.5 m/s through the real gas (the prescribed solid).
    let moving = dir.join("moving");
    run_scene(&scene, &moving, &["--solid", "prescribed"]);
    let s = summary(&moving);
    assert_eq!(s["status"], "completed", "{s}");
    assert_eq!(s["nodes"]["solid"], "prescribed");
    assert!(s["mass_rel_err"].as_f64().expect("mass") <= 1e-12, "{s}");
    // The real solid in a given pressure field (the pressure double).
    let pressed = dir.join("pressed");
    run_scene(&scene, &pressed, &["--fluid", "pressure"]);
    let s = summary(&pressed);
    assert_eq!(s["status"], "completed", "{s}");
    assert_eq!(s["nodes"]["fluid"], "pressure");
    let _ = std::fs::remove_dir_all(dir);
}

/// `inspect` piped into a reader that stops after one line (`| head -1`) ends on SIGPIPE,
/// silently (it panicked in `print!`, and the streamed export reported a write error).
fn inspect_ends_quietly_on_a_closed_pipe(out: &Path) {
    // The whole table of this record is larger than a pipe's buffer (64 KiB).
    for args in [
        &["inspect", "--export", "csv"][..],
        &["inspect", "--export", "json", "--step", "1"][..],
    ] {
        let mut child = coupler()
            .args(args)
            .arg(out.join("exchange.mcap"))
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .expect("inspect starts");
        let mut first = String::new();
        std::io::BufRead::read_line(
            &mut std::io::BufReader::new(child.stdout.take().expect("stdout")),
            &mut first,
        )
        .expect("a first line");
        let r = child.wait_with_output().expect("inspect ends");
        let stderr = String::from_utf8_lossy(&r.stderr);
        assert!(!first.is_empty() && stderr.is_empty(), "{args:?}: {stderr}");
        use std::os::unix::process::ExitStatusExt;
        assert!(
            r.status.success() || r.status.signal() == Some(13),
            "{args:?}: {:?}",
            r.status
        );
        if args[2] == "csv" {
            assert_eq!(
                r.status.signal(),
                Some(13),
                "the whole table outgrows the pipe"
            );
        }
    }
}
