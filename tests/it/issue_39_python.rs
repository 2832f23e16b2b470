//! Issue 39 item 6: the Python reader. `tests/py/check_reader.py` opens a fresh run with
//! `fsi_cosim.open_run` (python/ on PYTHONPATH, as `pip install ./python` installs it) and
//! prints what it reads; each number equals what the run wrote, read here in Rust: the ledger's
//! rows and largest mass error against `summary.json`, the diagnostics against the record, the
//! fluid's and the particles' fields against their VTK files, one step's exchanged arrays
//! against the record's frames.

use std::process::Command;

use coupler_node::record::{self, DIAGNOSTICS_TOPIC, Diagnostics};
use protocol::codec;
use protocol::vtk::Values;
use protocol::vtk::read::parse;
use protocol::wire::Message;
use serde_json::Value;

use crate::e2e::{out_dir, python, run_scene, summary, workspace};
use crate::issue_39_views::SCENE;

#[test]
fn the_python_reader_reads_what_the_run_wrote() {
    let dir = out_dir("issue-39-python");
    std::fs::create_dir_all(&dir).expect("dir");
    let scene = dir.join("beam.toml");
    std::fs::write(&scene, SCENE).expect("scene");
    let out = dir.join("out");
    run_scene(&scene, &out, &[]);
    let step = 2;
    let run = Command::new(python())
        .arg(workspace().join("tests/py/check_reader.py"))
        .arg(&out)
        .arg(step.to_string())
        .env("PYTHONPATH", workspace().join("python"))
        .env("COSIM_COUPLER", env!("CARGO_BIN_EXE_it-coupler-node"))
        .output()
        .expect("python runs");
    assert!(
        run.status.success(),
        "{}{}",
        String::from_utf8_lossy(&run.stdout),
        String::from_utf8_lossy(&run.stderr)
    );
    let py: Value = serde_json::from_slice(&run.stdout).expect("one JSON object");
    // Floats come as text (check_reader.py's `x`): `parse` rounds correctly.
    let f = |key: &str| -> f64 {
        py[key]
            .as_str()
            .and_then(|t| t.parse().ok())
            .unwrap_or_else(|| panic!("{key}: {py}"))
    };
    let u = |key: &str| py[key].as_u64().unwrap_or_else(|| panic!("{key}: {py}"));

    // summary.json and ledger.csv.
    let s = summary(&out);
    let steps = s["steps"].as_u64().expect("steps");
    assert_eq!(u("steps"), steps);
    assert_eq!(u("ledger_rows"), steps);
    assert_eq!(py["ledger_steps"], serde_json::json!([0, steps - 1]));
    assert_eq!(
        f("max_mass_rel_err"),
        s["mass_rel_err"].as_f64().expect("mass error")
    );

    // The record's diagnostics.
    let rec = record::read_recording(&std::fs::read(out.join("exchange.mcap")).expect("record"))
        .expect("reads");
    let diagnostics: Vec<Diagnostics> = rec
        .topic(DIAGNOSTICS_TOPIC)
        .map(|m| serde_json::from_slice(&m.data).expect("diagnostics"))
        .collect();
    assert_eq!(u("diagnostics"), diagnostics.len() as u64);
    let last = diagnostics
        .last()
        .and_then(|d| d.ledger.as_ref())
        .expect("a ledger");
    assert_eq!(f("diagnostics_last_energy_rel_err"), last.energy_rel_err);
    assert_eq!(f("last_energy_rel_err"), last.energy_rel_err);

    // The last output's fluid and particles.
    let outputs = cosim_tests::read_table(&out.join("outputs.csv"));
    let rows = outputs.pairs("k", "t").expect("k,t");
    assert_eq!(u("outputs"), rows.len() as u64);
    let (k, t) = rows.last().copied().expect("an output");
    let k = k as u64;
    assert_eq!(u("output_k"), k);
    assert_eq!(f("output_t"), t);
    let fluid =
        parse(&std::fs::read(out.join(format!("fluid_{k}.vti"))).expect("vti")).expect("vti");
    let p = fluid
        .array("CellData", "p")
        .and_then(|a| a.as_f64())
        .expect("p");
    let (nx, ny) = (64, 48);
    assert_eq!(py["fluid_shape"], serde_json::json!([ny, nx]));
    let picks: Vec<f64> = [0, p.len() / 2, p.len() - 1]
        .iter()
        .map(|&i| p[i])
        .collect();
    let got: Vec<f64> = py["fluid_p"]
        .as_array()
        .expect("fluid_p")
        .iter()
        .map(|v| v.as_str().and_then(|t| t.parse().ok()).expect("a float"))
        .collect();
    assert_eq!(got, picks);
    assert_eq!(f("fluid_p_grid_row1_col2"), p[nx + 2], "row-major (y, x)");
    let Values::UInt8(ghost) = &fluid
        .array("CellData", "vtkGhostType")
        .expect("ghosts")
        .values
    else {
        panic!("vtkGhostType is UInt8")
    };
    let hidden = ghost.iter().filter(|&&g| g & 32 != 0).count() as u64;
    assert!(hidden > 0);
    assert_eq!(u("fluid_hidden"), hidden);
    let particles =
        parse(&std::fs::read(out.join(format!("particles_{k}.vtp"))).expect("vtp")).expect("vtp");
    let x = particles
        .array("Points", "Points")
        .and_then(|a| a.as_f64())
        .expect("points");
    let sigma = particles
        .array("PointData", "sigma_n")
        .and_then(|a| a.as_f64())
        .expect("sigma_n");
    assert_eq!(u("particles"), (x.len() / 3) as u64);
    assert_eq!(f("particle_last_x"), x[x.len() - 3]);
    assert_eq!(f("particle_last_sigma_n"), sigma[sigma.len() - 1]);

    exchange_matches(&rec, step, &py);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Step `step`'s exchanged messages as the reader gives them (`py`, through `coupler-node inspect
/// --step`) against the record `rec`: as recorded, and the solid's trials put back whole.
fn exchange_matches(rec: &record::Recording, step: u64, py: &Value) {
    // One step's exchanged messages (through `coupler-node inspect --step`).
    // (`inspect` lists the step's diagnostics with its frames.)
    let at_step: Vec<_> = rec.messages.iter().filter(|m| m.step == step).collect();
    assert_eq!(py["exchange_messages"].as_u64(), Some(at_step.len() as u64));
    // Each SolidState: (topic, sequence, positions, first position), sorted.
    let mut states: Vec<(String, u64, usize, f64)> = at_step
        .iter()
        .filter(|m| m.topic != DIAGNOSTICS_TOPIC)
        .filter_map(|m| match codec::decode(&m.data).expect("a frame").1 {
            Message::SolidState(s) => Some((
                m.topic.clone(),
                u64::from(m.sequence),
                s.position.len(),
                s.position[0],
            )),
            _ => None,
        })
        .collect();
    states.sort_by(|a, b| (&a.0, a.1).cmp(&(&b.0, b.1)));
    assert!(!states.is_empty());
    let got: Vec<(String, u64, usize, f64)> = py["exchange_states"]
        .as_array()
        .expect("exchange_states")
        .iter()
        .map(|v| {
            (
                v[0].as_str().expect("topic").to_string(),
                v[1].as_u64().expect("sequence"),
                v[2].as_u64().expect("length") as usize,
                v[3].as_str().and_then(|t| t.parse().ok()).expect("a float"),
            )
        })
        .collect();
    assert_eq!(got, states);
    // Put back whole (`Run.exchange`'s default): every trial of the solid as long as the step's
    // first, none left as changes. (The solid sends its later trials as their changes.)
    let first_len = at_step
        .iter()
        .filter(|m| m.topic == "/solid-to-coupler")
        .find_map(|m| match codec::decode(&m.data).expect("a frame").1 {
            Message::SolidState(s) if !s.changed_only => Some(s.position.len() as u64),
            _ => None,
        })
        .expect("the step's first trial");
    let changes = at_step
        .iter()
        .filter(|m| m.topic == "/solid-to-coupler")
        .filter(|m| {
            matches!(codec::decode(&m.data).expect("a frame").1,
                Message::SolidState(s) if s.changed_only)
        })
        .count();
    assert!(changes > 0, "no trial of step {step} sent as its changes");
    assert_eq!(py["whole_state_lengths"], serde_json::json!([first_len]));
    assert_eq!(py["whole_states_changed_only"], serde_json::json!(0));
}
