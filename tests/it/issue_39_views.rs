//! Issue 39 item 2: Foxglove out of the box. The record of a coupled 2-D run holds, at each
//! output time, a `foxglove.Grid` on `/foxglove/fluid` and a `foxglove.SceneUpdate` on
//! `/foxglove/solid` (JSON, schema encoding `jsonschema`). Each message has the fields
//! Foxglove's schemas require (the lists below are Foxglove's, docs.foxglove.dev/docs/sdk/schemas);
//! the grid's data hold exactly `column_count x rows x cell_stride` bytes, and its values are
//! the fluid's output field (`fluid_k.vti`, read with the project's VTK reader) to single
//! precision, NaN where the solid covers the cell; the scene's points are the solid's face
//! points (`solid_k.vtp`), coloured by the sign of `sigma_n`. Two runs of the scene record the
//! same bytes on both channels; `inspect`, `replay` and Python's `mcap` read the record.

use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;

use protocol::mcap_read::{Mode, scan};
use protocol::vtk::Values;
use protocol::vtk::read::{VtkFile, parse};
use serde_json::Value;

use crate::e2e::{coupler, out_dir, python, run_scene, summary, workspace};

/// Foxglove's `required` lists (foxglove.Grid, SceneUpdate, SceneEntity, LinePrimitive,
/// PackedElementField, Pose, time).
const GRID: &[&str] = &[
    "timestamp",
    "frame_id",
    "pose",
    "column_count",
    "cell_size",
    "row_stride",
    "cell_stride",
    "fields",
    "data",
];
const SCENE_UPDATE: &[&str] = &["deletions", "entities"];
const SCENE_ENTITY: &[&str] = &[
    "timestamp",
    "frame_id",
    "id",
    "lifetime",
    "frame_locked",
    "metadata",
    "arrows",
    "cubes",
    "spheres",
    "cylinders",
    "lines",
    "triangles",
    "texts",
    "models",
];
const LINE: &[&str] = &[
    "type",
    "pose",
    "thickness",
    "scale_invariant",
    "points",
    "color",
    "colors",
    "indices",
];
const FIELD: &[&str] = &["name", "offset", "type"];
const POSE: &[&str] = &["position", "orientation"];
const TIME: &[&str] = &["sec", "nsec"];

/// The beam of issue_39's VTK test (which names it "vtkbeam"): 4 steps, 2 outputs, nothing
/// breaks.
pub(crate) const SCENE: &str = r#"name = "viewbeam"
[run]
t_end = 1.0
max_steps = 4
[fluid]
lower = [0.0, 0.0]
upper = [2.0, 1.0]
cells = [64, 48]
boundary = { x = ["periodic", "periodic"], y = ["wall", "wall"] }
[[fluid.init]]
region = "all"
rho = 1.4
p = 12.0
[[fluid.init]]
region = { box = { lower = [0.0, 0.0], upper = [0.95, 1.0] } }
rho = 8.0
p = 116.5
[solid]
density = 100.0
young = 7000.0
poisson = 0.0
[[solid.bodies]]
shape = { box = { center = [1.0, 0.3375], size = [0.2, 0.75] } }
divisions = [3, 10]
[[solid.constraints]]
region = { box = { lower = [0.5, -1.0], upper = [1.5, 0.1125] } }
motion = "fixed"
[output]
every = 0.004
"#;

fn has(value: &Value, keys: &[&str], what: &str) {
    for key in keys {
        assert!(value.get(key).is_some(), "{what} lacks {key}: {value:.200}");
    }
}

fn base64_decode(text: &str) -> Vec<u8> {
    let digit = |c: u8| match c {
        b'A'..=b'Z' => c - b'A',
        b'a'..=b'z' => c - b'a' + 26,
        b'0'..=b'9' => c - b'0' + 52,
        b'+' => 62,
        b'/' => 63,
        _ => panic!("not base64: {c}"),
    };
    let bytes = text.as_bytes();
    assert_eq!(bytes.len() % 4, 0, "base64 comes in groups of 4");
    let mut out = Vec::with_capacity(bytes.len() / 4 * 3);
    for group in bytes.chunks(4) {
        let pad = group.iter().filter(|&&c| c == b'=').count();
        let n = group[..4 - pad]
            .iter()
            .enumerate()
            .fold(0u32, |n, (i, &c)| n | u32::from(digit(c)) << (18 - 6 * i));
        out.extend_from_slice(&n.to_be_bytes()[1..4 - pad]);
    }
    out
}

/// The record's messages on the Foxglove topics: topic → (log time, publish time, JSON bytes).
fn views(record: &Path) -> BTreeMap<String, Vec<(u64, u64, Vec<u8>)>> {
    let scan = scan(&std::fs::read(record).expect("record"), Mode::Strict).expect("reads");
    let mut out: BTreeMap<String, Vec<(u64, u64, Vec<u8>)>> = BTreeMap::new();
    for (topic, schema) in [
        ("/foxglove/fluid", "foxglove.Grid"),
        ("/foxglove/solid", "foxglove.SceneUpdate"),
    ] {
        let (id, channel) = scan
            .channels
            .iter()
            .find(|(_, c)| c.topic == topic)
            .unwrap_or_else(|| panic!("no channel {topic}"));
        assert_eq!(channel.message_encoding, "json");
        let s = channel.schema.as_ref().expect("a schema");
        assert_eq!(
            (s.name.as_str(), s.encoding.as_str()),
            (schema, "jsonschema")
        );
        let doc: Value = serde_json::from_slice(&s.data).expect("the schema is JSON");
        assert_eq!(doc["title"], schema);
        let messages = scan.messages.iter().filter(|m| m.channel_id == *id);
        out.insert(
            topic.to_string(),
            messages
                .map(|m| (m.log_time, m.publish_time, m.data.clone()))
                .collect(),
        );
    }
    out
}

fn vtk(path: &Path) -> VtkFile {
    parse(&std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())))
        .expect("parses")
}

/// The grid of output `k` is the fluid's `fluid_k.vti` (rho, p) in single precision.
fn check_grid(grid: &Value, fluid: &VtkFile) {
    has(grid, GRID, "Grid");
    has(&grid["pose"], POSE, "Grid.pose");
    has(&grid["timestamp"], TIME, "Grid.timestamp");
    for f in grid["fields"].as_array().expect("fields") {
        has(f, FIELD, "PackedElementField");
    }
    let ext: Vec<usize> = fluid.dataset["WholeExtent"]
        .split_whitespace()
        .map(|v| v.parse().expect("an integer"))
        .collect();
    // A flat axis has extent 0 0 (one layer); a 3-D grid's slice is its middle layer.
    let (nx, ny, nz) = (ext[1], ext[3], ext[5].max(1));
    let kz = nz / 2;
    let origin: Vec<f64> = fluid.dataset["Origin"]
        .split_whitespace()
        .map(|v| v.parse().expect("a number"))
        .collect();
    let spacing: Vec<f64> = fluid.dataset["Spacing"]
        .split_whitespace()
        .map(|v| v.parse().expect("a number"))
        .collect();
    let z = if ext[5] == 0 {
        0.0
    } else {
        origin[2] + (kz as f64 + 0.5) * spacing[2]
    };
    assert_eq!(
        grid["pose"]["position"]["z"].as_f64(),
        Some(z),
        "the slice's plane"
    );
    assert_eq!(grid["cell_size"]["x"].as_f64(), Some(spacing[0]));
    let stride = grid["cell_stride"].as_u64().expect("cell_stride") as usize;
    assert_eq!(grid["column_count"], nx);
    assert_eq!(grid["row_stride"].as_u64(), Some((nx * stride) as u64));
    let data = base64_decode(grid["data"].as_str().expect("data"));
    assert_eq!(data.len(), nx * ny * stride, "width x height x cell_stride");
    let hidden = match &fluid
        .array("CellData", "vtkGhostType")
        .expect("ghosts")
        .values
    {
        Values::UInt8(g) => g.clone(),
        other => panic!("vtkGhostType {other:?}"),
    };
    let mut covered = 0;
    for f in grid["fields"].as_array().expect("fields") {
        assert_eq!(f["type"], 7, "FLOAT32");
        let name = f["name"].as_str().expect("a name");
        let offset = f["offset"].as_u64().expect("offset") as usize;
        let field = fluid
            .array("CellData", name)
            .expect("the field")
            .as_f64()
            .expect("f64");
        let slice = &field[nx * ny * kz..nx * ny * (kz + 1)];
        for (cell, &want) in slice.iter().enumerate() {
            let (idx, at) = (cell + nx * ny * kz, cell * stride + offset);
            let got = f32::from_le_bytes(data[at..at + 4].try_into().expect("4 bytes"));
            if hidden[idx] & 32 != 0 {
                assert!(got.is_nan(), "{name} of covered cell {idx}: {got}");
                covered += 1;
            } else {
                assert_eq!(
                    got.to_bits(),
                    (want as f32).to_bits(),
                    "{name} of cell {idx}"
                );
            }
        }
    }
    assert!(covered > 0, "the solid covers cells of the slice");
}

/// The scene of output `k` draws the solid's faces (`solid_k.vtp`), coloured by `sigma_n`.
fn check_scene(scene: &Value, faces: &VtkFile) {
    has(scene, SCENE_UPDATE, "SceneUpdate");
    let entities = scene["entities"].as_array().expect("entities");
    assert_eq!(entities.len(), 1);
    let entity = &entities[0];
    has(entity, SCENE_ENTITY, "SceneEntity");
    let lines = entity["lines"].as_array().expect("lines");
    assert_eq!(lines.len(), 1, "the faces (no link broke)");
    let line = &lines[0];
    has(line, LINE, "LinePrimitive");
    has(&line["pose"], POSE, "LinePrimitive.pose");
    assert_eq!(line["type"], 2, "LINE_LIST");
    let points = faces
        .array("Points", "Points")
        .expect("points")
        .as_f64()
        .expect("f64");
    let got = line["points"].as_array().expect("points");
    assert_eq!(got.len(), points.len() / 3);
    for (p, want) in got.iter().zip(points.chunks(3)) {
        for (axis, w) in ["x", "y", "z"].iter().zip(want) {
            assert_eq!(p[axis].as_f64().expect("a number") as f32, *w as f32);
        }
    }
    let conn = faces
        .array("Lines", "connectivity")
        .expect("lines")
        .as_i64()
        .expect("i64");
    let offsets = faces
        .array("Lines", "offsets")
        .expect("offsets")
        .as_i64()
        .expect("i64");
    let indices: Vec<i64> = line["indices"]
        .as_array()
        .expect("indices")
        .iter()
        .map(|i| i.as_i64().expect("an index"))
        .collect();
    assert_eq!(indices, conn, "one segment per 2-D face");
    let sigma = faces
        .array("CellData", "sigma_n")
        .expect("sigma_n")
        .as_f64()
        .expect("f64");
    let max = sigma.iter().fold(0.0_f64, |m, s| m.max(s.abs()));
    assert!(max > 0.0, "the loaded beam is stressed");
    let meta = &entity["metadata"].as_array().expect("metadata")[0];
    assert_eq!(meta["key"], "sigma_n_max_Pa");
    assert_eq!(
        meta["value"].as_str().expect("text").parse::<f64>(),
        Ok(max)
    );
    let colors = line["colors"].as_array().expect("colors");
    let mut start = 0;
    for (face, &end) in offsets.iter().enumerate() {
        for &s in &conn[start as usize..end as usize] {
            let c = &colors[s as usize];
            let (r, b) = (c["r"].as_f64().expect("r"), c["b"].as_f64().expect("b"));
            // Tension red (r = 1), compression blue (b = 1); the fade is 1 - |sigma| / max.
            let fade = 1.0 - sigma[face].abs() / max;
            let (full, faded) = if sigma[face] >= 0.0 { (r, b) } else { (b, r) };
            assert_eq!(full, 1.0, "face {face} sigma {}", sigma[face]);
            assert!(
                (faded - fade).abs() <= 5e-4 + 1e-6,
                "face {face}: {faded} vs {fade}"
            );
        }
        start = end;
    }
}

#[test]
fn the_record_shows_the_run_in_foxglove() {
    let dir = out_dir("issue-39-foxglove");
    std::fs::create_dir_all(&dir).expect("dir");
    let scene = dir.join("beam.toml");
    std::fs::write(&scene, SCENE).expect("scene");
    let (a, b) = (dir.join("a"), dir.join("b"));
    run_scene(&scene, &a, &[]);
    run_scene(&scene, &b, &[]);
    assert_eq!(summary(&a)["steps"], 4);
    let record = a.join("exchange.mcap");
    let got = views(&record);
    assert_eq!(
        got,
        views(&b.join("exchange.mcap")),
        "the same bytes in two runs"
    );
    let outputs = cosim_tests::read_table(&a.join("outputs.csv"));
    let times: Vec<(u32, f64)> = (outputs.pairs("k", "t").expect("k,t").into_iter())
        .map(|(k, t)| (k as u32, t))
        .collect();
    assert_eq!(times.len(), 2, "{outputs:?}");
    for topic in ["/foxglove/fluid", "/foxglove/solid"] {
        assert_eq!(
            got[topic].len(),
            times.len(),
            "{topic}: one message per output"
        );
    }
    for (i, &(k, t)) in times.iter().enumerate() {
        let ns = protocol::topics::log_time(t);
        let (log, publish, grid) = &got["/foxglove/fluid"][i];
        assert_eq!((*log, *publish), (ns, ns), "output {k}: simulated time");
        let grid: Value = serde_json::from_slice(grid).expect("JSON");
        let stamp = &grid["timestamp"];
        assert_eq!(
            stamp["sec"].as_u64().expect("sec") * 1_000_000_000
                + stamp["nsec"].as_u64().expect("ns"),
            ns
        );
        check_grid(&grid, &vtk(&a.join(format!("fluid_{k}.vti"))));
        let scene: Value = serde_json::from_slice(&got["/foxglove/solid"][i].2).expect("JSON");
        check_scene(&scene, &vtk(&a.join(format!("solid_{k}.vtp"))));
    }
    // The tools read the record as before; Python's `mcap` checks the Foxglove channels too.
    let inspect = coupler()
        .arg("inspect")
        .arg(&record)
        .output()
        .expect("inspect");
    assert!(
        inspect.status.success(),
        "{}",
        String::from_utf8_lossy(&inspect.stderr)
    );
    let replay = coupler()
        .args(["replay", "--step", "2", "--node", "fluid"])
        .arg(&record)
        .output()
        .expect("replay");
    assert!(
        String::from_utf8_lossy(&replay.stdout).contains("identical"),
        "{}{}",
        String::from_utf8_lossy(&replay.stdout),
        String::from_utf8_lossy(&replay.stderr)
    );
    let check = Command::new(python())
        .arg(workspace().join("tests/py/check_mcap.py"))
        .arg(&record)
        .output()
        .expect("python runs");
    assert!(
        check.status.success(),
        "{}",
        String::from_utf8_lossy(&check.stdout)
    );
    assert!(
        String::from_utf8_lossy(&check.stderr).contains("foxglove views: 4"),
        "{}",
        String::from_utf8_lossy(&check.stderr)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Two cubes linked by one link, one pulled away at 1 m/s (scenes/opening-fracture-3d.toml on
/// a 16³ grid): the link breaks in the first steps.
const SCENE_3D: &str = r#"name = "viewcrack"
[run]
t_end = 0.06
scheme = "semi-implicit"
tolerance = 1e-12
[fluid]
lower = [0.0, 0.0, 0.0]
upper = [2.0, 2.0, 2.0]
cells = [16, 16, 16]
boundary = { x = ["wall", "wall"], y = ["wall", "wall"], z = ["wall", "wall"] }
[[fluid.init]]
region = "all"
rho = 1.4
p = 1.0
[solid]
density = 7000.0
young = 2.1e11
poisson = 0.3
fracture = { elongation_at_break = 1e-3 }
[[solid.bodies]]
shape = { box = { center = [1.0, 1.0, 1.0], size = [0.8, 0.8, 0.8] } }
divisions = [2, 1, 1]
[[solid.constraints]]
region = { box = { lower = [0.7, 0.9, 0.9], upper = [0.9, 1.1, 1.1] } }
motion = "fixed"
[[solid.constraints]]
region = { box = { lower = [1.1, 0.9, 0.9], upper = [1.3, 1.1, 1.1] } }
motion = { velocity = [1.0, 0.0, 0.0] }
[output]
times = [0.0, 0.05]
"#;

/// 3-D: the grid is the fluid's mid-plane slice, the particles' faces are triangle fans, and
/// the broken link is a red segment between the two particles' centres.
#[test]
fn a_3d_run_shows_its_slice_faces_and_broken_links() {
    let dir = out_dir("issue-39-foxglove-3d");
    std::fs::create_dir_all(&dir).expect("dir");
    let scene = dir.join("crack.toml");
    std::fs::write(&scene, SCENE_3D).expect("scene");
    let out = dir.join("out");
    run_scene(&scene, &out, &[]);
    let broken = cosim_tests::read_table(&out.join("links_broken.csv"));
    let pairs: Vec<[usize; 2]> = (broken.pairs("a", "b").expect("a,b").into_iter())
        .map(|(a, b)| [a as usize, b as usize])
        .collect();
    assert_eq!(pairs, [[0, 1]], "{broken:?}");
    let got = views(&out.join("exchange.mcap"));
    // Outputs 0 (t = 0, before the break), 1 (t = 0.05) and 2 (t_end), after it.
    assert_eq!(got["/foxglove/fluid"].len(), 3);
    assert_eq!(got["/foxglove/solid"].len(), 3);
    let outputs = got["/foxglove/fluid"].iter().zip(&got["/foxglove/solid"]);
    for (k, ((_, _, grid), (_, _, scene))) in outputs.enumerate() {
        let grid: Value = serde_json::from_slice(grid).expect("JSON");
        check_grid(&grid, &vtk(&out.join(format!("fluid_{k}.vti"))));
        let scene: Value = serde_json::from_slice(scene).expect("JSON");
        let entity = &scene["entities"][0];
        has(entity, SCENE_ENTITY, "SceneEntity");
        let faces = vtk(&out.join(format!("solid_{k}.vtp")));
        let offsets = faces
            .array("Polys", "offsets")
            .and_then(|a| a.as_i64())
            .expect("polys");
        // A fan of n - 2 triangles per polygon of n points.
        let mut start = 0;
        let triangles: i64 = offsets
            .iter()
            .map(|&end| {
                let n = end - start;
                start = end;
                n - 2
            })
            .sum();
        let tri = &entity["triangles"][0];
        assert_eq!(
            tri["indices"].as_array().expect("indices").len() as i64,
            3 * triangles
        );
        let lines = entity["lines"].as_array().expect("lines");
        if k == 0 {
            assert!(lines.is_empty(), "nothing broken at t = 0");
            continue;
        }
        assert_eq!(lines.len(), 1, "the broken links");
        let centres = vtk(&out.join(format!("particles_{k}.vtp")));
        let x = centres
            .array("Points", "Points")
            .and_then(|a| a.as_f64())
            .expect("points");
        let points = lines[0]["points"].as_array().expect("points");
        assert_eq!(points.len(), 2);
        for (p, id) in points.iter().zip(pairs[0]) {
            for (axis, c) in ["x", "y", "z"].iter().zip(&x[3 * id..3 * id + 3]) {
                assert_eq!(p[axis].as_f64().expect("a number") as f32, *c as f32);
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
