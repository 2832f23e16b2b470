//! Issue 38, "done when": the hostile corpus of records (`tests/hostile/records/`, beside the
//! scenes of `tests/hostile/scenes/`). Every tool that reads a record (`inspect`, its streamed
//! CSV export, `replay`, and `check` of a scene that replays it) reads each file or refuses it
//! with exit 2 and a message naming the file and the damage; none panics.

use std::process::Command;

use crate::e2e::{coupler, workspace};

/// What each tool gives each file: 0 (read, a killed run's record warned as such) or 2 (refused).
const EXPECTED: [(&str, [i32; 4]); 7] = [
    // inspect, inspect --export csv, replay --step 1 --node solid, check --fluid replay:FILE
    ("empty.mcap", [2, 2, 2, 2]),
    ("not-mcap.mcap", [2, 2, 2, 2]),
    // A run killed right after it started: nothing to replay.
    ("magic-only.mcap", [0, 0, 2, 2]),
    // A run of `backbone-doubles` killed while it wrote: read up to its last whole record.
    ("cut-inside-a-record.mcap", [0, 0, 0, 0]),
    // One byte of a zstd chunk flipped: the chunk is named.
    ("flipped-byte.mcap", [2, 2, 2, 2]),
    // A record announcing 2^60 bytes: the whole reader calls it cut short (a killed run), the
    // streamed one refuses it past its record limit.
    ("huge-length.mcap", [0, 2, 2, 2]),
    // A record running past the end magic: damage, not a cut.
    ("past-the-end.mcap", [2, 2, 2, 2]),
];

#[test]
fn every_tool_reads_or_refuses_each_hostile_record_clearly() {
    let dir = workspace().join("tests/hostile/records");
    let mut files: Vec<String> = std::fs::read_dir(&dir)
        .expect("tests/hostile/records")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    files.sort();
    let mut listed: Vec<&str> = EXPECTED.iter().map(|(f, _)| *f).collect();
    listed.sort_unstable();
    assert_eq!(
        files, listed,
        "every file of the corpus has its expectations"
    );
    let scene = workspace().join("scenes/backbone-doubles.toml");
    for (name, expected) in EXPECTED {
        let file = dir.join(name);
        let path = file.to_str().expect("utf-8 path");
        let replay = format!("replay:{path}");
        let calls: [Vec<&str>; 4] = [
            vec!["inspect", path],
            vec!["inspect", path, "--export", "csv"],
            vec!["replay", path, "--step", "1", "--node", "solid"],
            vec!["check", scene.to_str().expect("utf-8"), "--fluid", &replay],
        ];
        for (args, want) in calls.iter().zip(expected) {
            let out: std::process::Output = {
                let mut cmd: Command = coupler();
                cmd.args(args).output().expect("coupler-node starts")
            };
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(want), "{args:?}: {stderr}");
            assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
            if want == 2 {
                assert!(stderr.contains(name), "{args:?} names the file: {stderr}");
            }
        }
    }
}
