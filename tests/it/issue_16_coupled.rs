//! Issue 16 item 3 through the binaries and MPI: a coupled scene whose clamped beam crosses the
//! cuts between the fluid's ranks (2-D and 3-D, semi-implicit with IQN-ILS, so several trial
//! surfaces per step) gives the record frames (solid states, loads, totals, checkpoints) and
//! output files of one rank, bit for bit, on 2, 3, 4 and 8 ranks (oversubscribed on 2 cores),
//! cut into slabs or blocks (issue 40); so does a fragmenting 3-D scene (issue 40 item 3).
//!
//! Built only with `--features mpi`: `cargo test -p cosim-tests --features mpi --test it
//! issue_16`.

use std::path::{Path, PathBuf};

use crate::e2e::{frames_by_topic, out_dir, summary};
use crate::issue_16_mpi::{files, run};

/// A beam of `divisions` particles clamped at its foot on the wall y = 0, in a channel hit by
/// a pressure jump at x = 0.95 m (just before the beam's upstream face at 0.9–1.1 m).
fn beam_scene(dir: &Path, dim: usize) -> PathBuf {
    std::fs::create_dir_all(dir).expect("dir");
    let path = dir.join("beam.toml");
    // The lowest row of particles is centred on the wall y = 0 and fixed with the second
    // (clamp line at 1.5 rows), as in `scenes/clamped-beam-3d.toml`.
    let (fluid, body) = if dim == 3 {
        (
            r#"lower = [0.0, 0.0, 0.0]
upper = [2.0, 1.0, 1.0]
cells = [32, 16, 24]
boundary = { x = ["periodic", "periodic"], y = ["wall", "wall"], z = ["wall", "wall"] }
[[fluid.init]]
region = "all"
rho = 1.4
p = 12.0
[[fluid.init]]
region = { box = { lower = [0.0, 0.0, 0.0], upper = [0.95, 1.0, 1.0] } }
rho = 8.0
p = 116.5"#,
            r#"[[solid.bodies]]
shape = { box = { center = [1.0, 0.3, 0.5], size = [0.2, 0.75, 0.2] } }
divisions = [1, 5, 1]
[[solid.constraints]]
region = { box = { lower = [0.5, -1.0, 0.0], upper = [1.5, 0.225, 1.0] } }
motion = "fixed""#,
        )
    } else {
        (
            r#"lower = [0.0, 0.0]
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
p = 116.5"#,
            r#"[[solid.bodies]]
shape = { box = { center = [1.0, 0.3375], size = [0.2, 0.75] } }
divisions = [3, 10]
[[solid.constraints]]
region = { box = { lower = [0.5, -1.0], upper = [1.5, 0.1125] } }
motion = "fixed""#,
        )
    };
    let tip = if dim == 3 {
        "[1.0, 0.6, 0.5]"
    } else {
        "[1.0, 0.6]"
    };
    std::fs::write(
        &path,
        format!(
            r#"name = "mpibeam{dim}"
[run]
t_end = 1.0
max_steps = 4
scheme = "semi-implicit"
tolerance = 1e-12
relaxation = "iqn-ils"
predictor = "linear"
max_iterations = 50
record = "all"
checkpoint_every = 2
[fluid]
gamma = 1.4
cfl = 0.5
flux = {{ scheme = "osmp", order = 5 }}
{fluid}
[solid]
density = 100.0
young = 7000.0
poisson = 0.0
{body}
[output]
every = 0.004
formats = ["csv", "vtk"]
[[output.probes]]
name = "tip"
particle_at = {tip}
"#
        ),
    )
    .expect("scene");
    path
}

/// The beam scene of `dim` run on one rank and on each of `ranks`: every record frame and output
/// file is bit for bit that of one rank ([`assert_same_on_ranks`]).
fn assert_beam_same_on_ranks(dim: usize, ranks: &[(&str, Option<&str>)]) {
    let dir = out_dir(&format!("mpi-beam-{dim}d"));
    let scene = beam_scene(&dir, dim);
    assert_same_on_ranks(
        &format!("{dim}-D beam"),
        &dir,
        &scene,
        4,
        ranks,
        |one, outputs| {
            // Several trial surfaces per step.
            let s1 = summary(one);
            assert!(s1["coupling_iterations"]["max"].as_u64() > Some(1), "{s1}");
            let names: Vec<&str> = outputs.iter().map(|(n, _)| n.as_str()).collect();
            for expected in ["fluid_0.csv", "surface_0.csv", "loads_1.csv", "fluid_1.vti"] {
                assert!(names.contains(&expected), "{expected} in {names:?}");
            }
            let surface = |k: usize| {
                let name = format!("surface_{k}.csv");
                &outputs.iter().find(|(n, _)| *n == name).expect("surface").1
            };
            assert!(surface(0) != surface(1), "the beam moves");
        },
    );
    let _ = std::fs::remove_dir_all(dir);
}

/// `scene` (in `dir`) run on one rank, checked by `check_one` (its folder and output files),
/// and on each of `ranks` (`--fluid-ranks K`, the process grid `protocol::decomp::choose`
/// picks, or `(K, blocks)`: a copy of the scene with `fluid.ranks = K` and
/// `fluid.decomposition = blocks`): `steps` steps each, and every record frame and output file
/// bit for bit that of one rank.
fn assert_same_on_ranks(
    what: &str,
    dir: &Path,
    scene: &Path,
    steps: u64,
    ranks: &[(&str, Option<&str>)],
    check_one: impl Fn(&Path, &[(String, Vec<u8>)]),
) {
    let one = dir.join("one");
    run(scene, &one, &[]);
    let s1 = summary(&one);
    assert_eq!(s1["steps"], steps, "{s1}");
    let frames = frames_by_topic(&one.join("exchange.mcap"));
    let outputs = files(&one);
    check_one(&one, &outputs);
    for &(ranks, blocks) in ranks {
        let out = dir.join(format!("ranks{ranks}{}", blocks.map_or("", |_| "-blocks")));
        match blocks {
            None => {
                run(scene, &out, &["--fluid-ranks", ranks]);
            }
            Some(blocks) => {
                let text = std::fs::read_to_string(scene).expect("scene");
                let cut = format!("[fluid]\nranks = {ranks}\ndecomposition = {blocks}");
                let path = dir.join(format!("scene-{ranks}.toml"));
                std::fs::write(&path, text.replacen("[fluid]", &cut, 1)).expect("scene");
                run(&path, &out, &[]);
            }
        }
        let s = summary(&out);
        assert_eq!(s["status"], s1["status"], "{s}");
        assert_eq!(s["steps"], steps, "{s}");
        let many = frames_by_topic(&out.join("exchange.mcap"));
        assert_eq!(
            frames.iter().map(|(t, f)| (t, f.len())).collect::<Vec<_>>(),
            many.iter().map(|(t, f)| (t, f.len())).collect::<Vec<_>>(),
            "{what}: topics and frame counts of 1 and {ranks} ranks"
        );
        for ((topic, a), (_, b)) in frames.iter().zip(&many) {
            assert!(
                a == b,
                "{what}: {topic} frames of 1 and {ranks} ranks differ"
            );
        }
        let files_many = files(&out);
        assert_eq!(
            outputs.iter().map(|(n, _)| n).collect::<Vec<_>>(),
            files_many.iter().map(|(n, _)| n).collect::<Vec<_>>()
        );
        for ((name, a), (_, b)) in outputs.iter().zip(&files_many) {
            assert!(a == b, "{what}: {name} of 1 and {ranks} ranks differs");
        }
    }
}

/// On 2, 3, 4 and 8 ranks the 64 × 48 grid is cut 2 × 1, 3 × 1, 4 × 1 and 4 × 2 (cuts
/// along x through the beam; issue 40), and 1 × 4 as slabs.
#[test]
fn issue_16_clamped_beam_2d_across_the_cuts_is_bit_identical_on_1_2_3_4_and_8_ranks() {
    let ranks = [
        ("2", None),
        ("3", None),
        ("4", None),
        ("8", None),
        ("4", Some("[1, 4]")),
    ];
    assert_beam_same_on_ranks(2, &ranks);
}

/// On 2, 3, 4 and 8 ranks the 32 × 16 × 24 grid is cut into slabs of 2, 3 and 4 and into
/// blocks 1 × 2 × 4; 1 × 2 × 2 cuts y at the beam's middle as well (issue 40).
#[test]
fn issue_16_clamped_beam_3d_across_the_cuts_is_bit_identical_on_1_2_3_4_and_8_ranks() {
    let ranks = [
        ("2", None),
        ("3", None),
        ("4", None),
        ("8", None),
        ("4", Some("[1, 2, 2]")),
    ];
    assert_beam_same_on_ranks(3, &ranks);
}

/// `scenes/opening-fracture-3d.toml` on 24³ cells, 6 steps (issue 40 item 3, the fragmenting
/// scene): its link breaks at step 0 and the crack between the two halves opens into vacuum;
/// slabs of 2, 3 and 4, blocks 1 × 2 × 4 on 8 ranks and 1 × 2 × 2 from the key give the
/// frames and files of one rank.
#[test]
fn issue_16_opening_fracture_3d_fragmenting_is_bit_identical_on_1_2_3_4_and_8_ranks() {
    let dir = out_dir("mpi-fracture-3d");
    std::fs::create_dir_all(&dir).expect("dir");
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/opening-fracture-3d.toml"),
    )
    .expect("scene");
    let text = text
        .replace("cells = [100, 100, 100]", "cells = [24, 24, 24]")
        .replace("record = \"exchange\"", "record = \"all\"\nmax_steps = 6")
        .replace("checkpoint_every = 100", "checkpoint_every = 3")
        .replace("threads = 2", "threads = 1");
    assert!(text.contains("cells = [24, 24, 24]") && text.contains("max_steps = 6"));
    let scene = dir.join("fracture.toml");
    std::fs::write(&scene, text).expect("scene");
    let ranks = [
        ("2", None),
        ("3", None),
        ("4", None),
        ("8", None),
        ("4", Some("[1, 2, 2]")),
    ];
    assert_same_on_ranks("opening fracture", &dir, &scene, 6, &ranks, |one, _| {
        // The link broke: links_broken.csv has a header and at least one row.
        let broken = std::fs::read_to_string(one.join("links_broken.csv")).expect("links");
        assert!(broken.lines().count() >= 2, "{broken}");
    });
    let _ = std::fs::remove_dir_all(dir);
}
