//! Issue 11, items 2, 3, 4 and 8, end to end: a killed coupler's record reads with the standard
//! readers up to its last completed step; a damaged record is refused by `replay`, `inspect` and
//! a replay double (before any process starts) with the chunk and offset named, and `inspect
//! --recover` keeps what verifies; a replay step past the record's end is an error; a missing
//! replay record is refused before any process starts.

use std::process::Command;
use std::time::{Duration, Instant};

use coupler_node::record;
use protocol::mcap_read::End;

use crate::e2e::{
    coupler, long_doubles_scene, node_pids, out_dir, python, run_scene, start_long_run, workspace,
};

/// Runs `tests/py/check_mcap.py FILE FLAGS` and returns its stdout; fails unless it succeeds.
pub(crate) fn python_check(file: &std::path::Path, flags: &[&str]) -> String {
    let r = Command::new(python())
        .arg(workspace().join("tests/py/check_mcap.py"))
        .arg(file)
        .args(flags)
        .output()
        .unwrap_or_else(|e| panic!("running {}: {e}", python()));
    let stdout = String::from_utf8_lossy(&r.stdout).into_owned();
    assert!(
        r.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&r.stderr)
    );
    stdout
}

#[test]
fn issue_11_a_killed_coupler_leaves_a_record_standard_readers_read_to_its_last_step() {
    let dir = out_dir("issue11-sigkill");
    let scene = long_doubles_scene(&dir);
    let out = dir.join("out");
    let (mut child, run_id) = start_long_run(&scene, &out, 100_000, false, false);
    child.kill().expect("SIGKILL the coupler");
    child.wait().expect("reap the coupler");
    // Its nodes notice the coupler is gone; whatever is left after a while is ended here.
    let deadline = Instant::now() + Duration::from_secs(20);
    while !node_pids(&run_id).is_empty() && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(50));
    }
    for pid in node_pids(&run_id).split_whitespace() {
        let _ = Command::new("kill").args(["-9", pid]).status();
    }
    let file = out.join("exchange.mcap");
    let bytes = std::fs::read(&file).expect("record");
    let rec = record::read_recording(&bytes).expect("the killed run's record reads");
    let diagnostics: Vec<u64> = rec
        .topic(record::DIAGNOSTICS_TOPIC)
        .map(|m| m.step)
        .collect();
    let last = *diagnostics.last().expect("completed steps");
    assert!(
        last >= 5,
        "only {} steps before the kill",
        diagnostics.len()
    );
    assert_eq!(diagnostics, (0..=last).collect::<Vec<_>>());
    // Issue 15, item 6: ledger.csv keeps a row for every step the record completed (and at
    // most the steps the record's thread had not written yet, `record::MAX_LAG_STEPS` + 1 in
    // flight since issue 39 item 4, and the one whose row was written just before the kill).
    let steps = cosim_tests::csv_column(&out.join("ledger.csv"), "step");
    assert!(
        (diagnostics.len()..=diagnostics.len() + record::MAX_LAG_STEPS + 2).contains(&steps.len()),
        "{} ledger rows, {} completed steps in the record",
        steps.len(),
        diagnostics.len()
    );
    assert_eq!(
        steps,
        (0..steps.len()).map(|s| s as f64).collect::<Vec<_>>()
    );
    // Every completed step has its frames, both ways, for both nodes.
    for topic in [
        "/fluid-to-coupler",
        "/coupler-to-fluid",
        "/solid-to-coupler",
        "/coupler-to-solid",
    ] {
        for step in 0..=last {
            assert!(
                rec.topic(topic).any(|m| m.step == step),
                "{topic}: nothing at step {step} of 0..={last}"
            );
        }
    }
    match rec.end {
        End::Unfinished => {
            // The standard Python reader (`make_reader`) reads it as it is.
            let stdout = python_check(&file, &["--unfinished"]);
            assert_eq!(
                stdout.trim(),
                format!("ok {} messages, last step {last}", rec.messages.len())
            );
        }
        // Killed during the write that ends a step (a window of microseconds per step): only
        // that step's chunk is unfinished; the streaming reader reads everything before it.
        // (A file that ends exactly between two records, with nothing unfinished, was not ended
        // by the recorder: that is not this case.)
        End::CutShort {
            unreadable_bytes, ..
        } if unreadable_bytes > 0 => {
            let stdout = python_check(&file, &["--truncated"]);
            assert!(stdout.contains(&format!("last step {last}")), "{stdout}");
        }
        other => panic!("a killed coupler's record ends {other:?}"),
    }
    let r = coupler()
        .arg("inspect")
        .arg(&file)
        .output()
        .expect("inspect");
    let (stdout, stderr) = (
        String::from_utf8_lossy(&r.stdout),
        String::from_utf8_lossy(&r.stderr),
    );
    assert!(r.status.success(), "{stderr}");
    assert!(
        stderr.contains("a killed run") || stderr.contains("a run killed"),
        "{stderr}"
    );
    // The table counts the completed steps (those with diagnostics), lists the one in
    // progress when the run was killed only if it had started (a plan), and shows the last
    // completed step with its values.
    let completed = rec.topic(record::DIAGNOSTICS_TOPIC).count();
    assert!(
        stdout.contains(&format!("\n{completed} steps completed")),
        "{stdout}"
    );
    assert!(
        stdout.contains(&format!(", {} messages", rec.messages.len())),
        "{stdout}"
    );
    let row = stdout
        .lines()
        .find(|l| l.split_whitespace().next() == Some(last.to_string().as_str()))
        .expect("a row for the last completed step");
    assert!(!row.contains(" - "), "{row}");
    let _ = std::fs::remove_dir_all(dir);
}

/// Offsets and lengths of the chunk records of a file's data section (MCAP records are an
/// opcode byte, a u64 length and the body; chunks have opcode 0x06, the data end 0x0F).
fn chunks(bytes: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut at = 8;
    while at + 9 <= bytes.len() && bytes[at] != 0x0F {
        let len =
            9 + u64::from_le_bytes(bytes[at + 1..at + 9].try_into().expect("8 bytes")) as usize;
        if bytes[at] == 0x06 {
            out.push((at, len));
        }
        at += len;
    }
    out
}

#[test]
fn issue_11_damaged_records_are_refused_with_the_chunk_named_and_recover_keeps_the_rest() {
    let scene = workspace().join("scenes/backbone-doubles.toml");
    let dir = out_dir("issue11-damaged");
    let out = dir.join("first");
    run_scene(&scene, &out, &[]);
    let file = out.join("exchange.mcap");
    let bytes = std::fs::read(&file).expect("record");
    let complete = record::read_recording(&bytes).expect("readable");
    let last_step = complete
        .messages
        .iter()
        .map(|m| m.step)
        .max()
        .expect("steps");

    // Item 8: a step past the end of the record is an error, not "identical".
    let r = coupler()
        .args(["replay", "--step", "999999", "--node", "fluid"])
        .arg(&file)
        .output()
        .expect("replay starts");
    let (stdout, stderr) = (
        String::from_utf8_lossy(&r.stdout),
        String::from_utf8_lossy(&r.stderr),
    );
    assert_eq!(r.status.code(), Some(2), "{stdout}{stderr}");
    assert!(!stdout.contains("identical"), "{stdout}");
    assert!(
        stderr.contains(&format!("step 999999 is past the end of the record: its last step of the fluid node is {last_step}")),
        "{stderr}"
    );

    // One flipped byte in the middle of a chunk's data.
    let chunks = chunks(&bytes);
    let index = chunks.len() / 2;
    let (chunk_start_offset, chunk_length) = chunks[index];
    let mut bad = bytes.clone();
    bad[chunk_start_offset + chunk_length / 2] ^= 0x10;
    let damaged = dir.join("damaged.mcap");
    std::fs::write(&damaged, &bad).expect("write");
    let named = format!("chunk {index} at byte {chunk_start_offset}");

    // Item 2: a replay double on it is refused before any process starts.
    let second = dir.join("second");
    let r = coupler()
        .args(["run", "--quiet", "--solid"])
        .arg(format!("replay:{}", damaged.display()))
        .arg("--out")
        .arg(&second)
        .arg(&scene)
        .output()
        .expect("starts");
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("solid.node = \"replay:") && stderr.contains(&named),
        "{stderr}"
    );
    // Depending on where the flip lands, the decompressor refuses the chunk (zstd, the default
    // compression: "Data corruption detected"; lz4: "compression stream") or its CRC does.
    assert!(
        stderr.contains("CRC failed")
            || stderr.contains("compression stream")
            || stderr.contains("Data corruption detected"),
        "{stderr}"
    );
    assert_eq!(stderr.matches(&named).count(), 1, "{stderr}");
    assert!(
        !second.exists(),
        "the refused run created its output folder"
    );

    // `replay` and `inspect` refuse it too, naming the chunk.
    let r = coupler()
        .args(["replay", "--step", "5", "--node", "fluid"])
        .arg(&damaged)
        .output()
        .expect("replay starts");
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains(&named), "{stderr}");
    let r = coupler()
        .arg("inspect")
        .arg(&damaged)
        .output()
        .expect("inspect");
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains(&named) && stderr.contains("--recover"),
        "{stderr}"
    );
    assert!(!stderr.contains("killed"), "{stderr}");

    // Item 3: `inspect --recover` keeps every other chunk and says what it dropped.
    let r = coupler()
        .args(["inspect", "--recover"])
        .arg(&damaged)
        .output()
        .expect("inspect");
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert!(r.status.success(), "{stderr}");
    assert!(stderr.contains(&format!("dropped {named}")), "{stderr}");
    assert!(stderr.contains("1 damaged part dropped"), "{stderr}");
    let recovered = record::read_recording(
        &std::fs::read(dir.join("damaged.recovered.mcap")).expect("recovered"),
    )
    .expect("the recovered file reads");
    assert!(!recovered.truncated());
    assert!(recovered.messages.len() < complete.messages.len());
    assert!(
        recovered
            .messages
            .iter()
            .all(|m| complete.messages.contains(m))
    );
    // The python reader agrees on the recovered file.
    let stdout = python_check(&dir.join("damaged.recovered.mcap"), &["--allow-gaps"]);
    assert!(
        stdout.starts_with(&format!("ok {} messages", recovered.messages.len())),
        "{stdout}"
    );
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn issue_11_a_missing_or_unreadable_replay_record_is_refused_before_any_process_starts() {
    let scene = workspace().join("scenes/backbone-doubles.toml");
    let dir = out_dir("issue11-missing");
    std::fs::create_dir_all(&dir).expect("dir");
    let garbage = dir.join("garbage.mcap");
    std::fs::write(&garbage, b"not a record").expect("write");
    let missing = dir.join("missing.mcap");
    for (file, reason) in [
        (&missing, "No such file"),
        (&garbage, "not an mcap file: 12 bytes"),
    ] {
        let out = dir.join("out");
        let r = coupler()
            .args(["run", "--quiet", "--fluid"])
            .arg(format!("replay:{}", file.display()))
            .arg("--out")
            .arg(&out)
            .arg(&scene)
            .output()
            .expect("starts");
        let stderr = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{stderr}");
        assert!(
            stderr.contains(&format!("fluid.node = \"replay:{}\"", file.display()))
                && stderr.contains(reason),
            "{stderr}"
        );
        assert!(!out.exists(), "the refused run created its output folder");
    }
    let _ = std::fs::remove_dir_all(dir);
}
