//! Replays through the real binaries: a replayed node is identical or names the altered value,
//! an IQN-ILS run replays for every node, a recorded node stands in as a double.

use super::coupled::assert_restart_continues_identically;
use super::*;

#[test]
fn replay_is_identical_and_names_an_altered_value() {
    let scene = workspace().join("scenes/backbone-doubles.toml");
    let out = out_dir("replay");
    run_scene(&scene, &out, &[]);
    let file = out.join("exchange.mcap");
    for node in ["solid", "fluid"] {
        assert_replays_identically(&file, "126", node);
    }
    // Change one recorded number: the solid's trial position at step 125, iteration 0.
    let rec = record::read_recording(&std::fs::read(&file).expect("record")).expect("readable");
    let altered_path = out.join("altered.mcap");
    let mut recorder = Recorder::new(
        std::io::BufWriter::new(std::fs::File::create(&altered_path).expect("create")),
        RecordLevel::Exchange,
        RecordCompression::Lz4,
        "backbone-doubles",
        &rec.metadata["scene"]["toml"],
    )
    .expect("recorder");
    let mut changed = None;
    for m in &rec.messages {
        let mut data = m.data.clone();
        if m.topic == "/solid-to-coupler"
            && changed.is_none()
            && m.step == 125
            && let Ok((_, Message::SolidState(mut s))) = codec::decode(&data)
        {
            let old = s.position[0];
            s.position[0] = old + 1e-9;
            changed = Some((old, s.position[0]));
            data = codec::encode(NodeKind::Solid, &Message::SolidState(s));
        }
        let topic = m.topic.as_str();
        // The log time back in seconds (exact: whole ns below 2^53).
        let t = m.log_time as f64 * 1e-9;
        let result = match topic {
            "/diagnostics" => recorder.record_diagnostics(t, m.publish_time, &data),
            "/checkpoint/fluid" => {
                recorder.record_checkpoint(NodeKind::Fluid, t, m.publish_time, &data)
            }
            "/checkpoint/solid" => {
                recorder.record_checkpoint(NodeKind::Solid, t, m.publish_time, &data)
            }
            "/checkpoint/coupler" => {
                recorder.record_checkpoint(NodeKind::Coupler, t, m.publish_time, &data)
            }
            _ => {
                let (from, to) = topic[1..].split_once("-to-").expect("a frame topic");
                let kind = |n: &str| match n {
                    "fluid" => NodeKind::Fluid,
                    "solid" => NodeKind::Solid,
                    _ => NodeKind::Coupler,
                };
                recorder.record_frame(kind(from), kind(to), t, m.publish_time, &data)
            }
        };
        result.expect("re-record");
    }
    recorder.finish().expect("finish");
    let (old, new) = changed.expect("a solid state at step 125");
    let r = coupler()
        .args(["replay", "--step", "126", "--node", "solid"])
        .arg(&altered_path)
        .output()
        .expect("replay starts");
    let text = String::from_utf8_lossy(&r.stdout);
    assert_eq!(r.status.code(), Some(1), "{text}");
    assert!(
        text.contains("solid-to-coupler step 125 iteration 0"),
        "{text}"
    );
    assert!(text.contains("position[0]"), "{text}");
    assert!(
        text.contains(&format!("recorded {new}")) && text.contains(&format!("replayed {old}")),
        "{text}"
    );
    let _ = std::fs::remove_dir_all(out);
}

#[test]
fn replay_of_an_iqn_ils_run_is_identical_for_both_nodes_and_the_coupler() {
    // The accelerated input is what the coupler sends, so the recorded coupler-to-node messages
    // hold everything the columns and the predictor decided (the linear predictor's iteration-0
    // state travels after each plan): a node replayed against them iterates exactly as in the
    // run.
    let out = out_dir("replay-iqn");
    std::fs::create_dir_all(&out).expect("dir");
    let text = std::fs::read_to_string(workspace().join("scenes/backbone-doubles.toml"))
        .expect("scene")
        .replace(
            "relaxation = \"none\"",
            "relaxation = \"iqn-ils\"\npredictor = \"linear\"",
        );
    assert!(text.contains("iqn-ils"));
    let scene = out.join("iqn.toml");
    std::fs::write(&scene, text).expect("write scene");
    run_scene(&scene, &out.join("run"), &[]);
    let s = summary(&out.join("run"));
    assert!(s["steps"].as_u64().expect("steps") > 126, "{s}");
    let mean = s["coupling_iterations"]["mean"].as_f64().expect("mean");
    assert!(mean <= 3.0, "{s}");
    let file = out.join("run/exchange.mcap");
    for node in ["solid", "fluid"] {
        assert_replays_identically(&file, "126", node);
    }
    // The coupler itself, resumed from its checkpoint of step 120 (columns, accepted states),
    // sends the very frames of the run; without the columns it iterates otherwise.
    assert_replays_identically(&file, "126", "coupler");
    // A restart from step 60 goes on as the run did: the columns and the predictor's states
    // travel in the coupler's checkpoint.
    assert_restart_continues_identically(&out.join("run"), 60, &out.join("restart"));
    let mut rec = record::read_recording(&std::fs::read(&file).expect("record")).expect("read");
    let scene_toml = rec.metadata["scene"]["toml"].clone();
    let scene = protocol::scene::Scene::from_toml_str(&scene_toml, "recorded").expect("scene");
    let outcome = coupler_node::coupler_replay::replay(&rec, &scene, 126).expect("replay");
    assert!(
        matches!(
            outcome,
            coupler_node::replay::Outcome::Identical { from_step: 120, .. }
        ),
        "{outcome:?}"
    );
    let own = rec
        .messages
        .iter_mut()
        .rfind(|m| m.topic == "/checkpoint/coupler" && m.step == 120)
        .expect("a coupler checkpoint at step 120");
    let Ok((_, Message::Checkpoint(mut c))) = codec::decode(&own.data) else {
        panic!("the coupler checkpoint is a Checkpoint frame");
    };
    let mut state: coupler_node::scheme::CouplerCheckpoint =
        codec::decode_blob(&c.bytes).expect("coupler state");
    let columns = state.acceleration.iqn.as_mut().expect("IQN-ILS columns");
    assert!(!columns.old.is_empty() || !columns.now.is_empty());
    columns.old.clear();
    columns.now.clear();
    c.bytes = codec::encode_blob(&state);
    own.data = codec::encode(NodeKind::Coupler, &Message::Checkpoint(c));
    match coupler_node::coupler_replay::replay(&rec, &scene, 126).expect("replay") {
        coupler_node::replay::Outcome::Differs(diff) => {
            assert!(diff.contains("coupler-to-"), "{diff}");
        }
        other => panic!("a coupler without its columns iterated identically: {other:?}"),
    }
    let _ = std::fs::remove_dir_all(out);
}

#[test]
fn a_recorded_node_replays_as_a_double_the_coupler_cannot_tell() {
    let scene = workspace().join("scenes/backbone-doubles.toml");
    let first = out_dir("replay-double-a");
    run_scene(&scene, &first, &[]);
    let record = first.join("exchange.mcap");
    let second = out_dir("replay-double-b");
    let solid = format!("replay:{}", record.display());
    run_scene(&scene, &second, &["--solid", &solid]);
    let s = summary(&second);
    assert_eq!(s["status"], "completed");
    assert_eq!(s["nodes"]["solid"], solid.as_str());
    // The real pressure double, fed the recorded solid, sends exactly what it sent before.
    let (a, b) = (
        frames_by_topic(&record),
        frames_by_topic(&second.join("exchange.mcap")),
    );
    let pick = |v: &Vec<(String, Vec<Vec<u8>>)>, t: &str| {
        v.iter().find(|(n, _)| n == t).map(|(_, f)| f.clone())
    };
    for topic in [
        "/fluid-to-coupler",
        "/solid-to-coupler",
        "/coupler-to-solid",
        "/coupler-to-fluid",
    ] {
        assert!(pick(&a, topic) == pick(&b, topic), "{topic} differs");
    }
    // Asked for more than the record holds (a record cut short, as a killed run leaves it),
    // the double fails clearly.
    let bytes = std::fs::read(&record).expect("record");
    let cut = first.join("cut.mcap");
    std::fs::write(&cut, &bytes[..bytes.len() * 6 / 10]).expect("write");
    let third = out_dir("replay-double-c");
    let start = shared_start();
    let r = coupler()
        .args([
            "run",
            "--quiet",
            "--solid",
            &format!("replay:{}", cut.display()),
            "--out",
        ])
        .arg(&third)
        .arg(&scene)
        .output()
        .expect("starts");
    drop(start);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert!(!r.status.success());
    assert!(
        stderr.contains("after the end of the record (the record was cut short)"),
        "{stderr}"
    );
    for dir in [first, second, third] {
        let _ = std::fs::remove_dir_all(dir);
    }
}
