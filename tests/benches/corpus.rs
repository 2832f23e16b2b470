//! The long corpus of generated coupled scenes (issue 35): runs `CORPUS_N` cases (default 200)
//! from seed `CORPUS_FROM` (default 0), each in one process for about `corpus::STEPS` steps,
//! and prints the count of each outcome, by dimension and shape, then the failing seeds with
//! their reason. `CORPUS_OUT` (default a folder under the system's temporary folder) holds the
//! cases' outputs.
//!
//! `cargo bench -p cosim-tests --bench corpus` (env `CORPUS_N=2000` for the long corpus;
//! `CORPUS_PRINT=SEED` prints that case's scene instead). A failing case's folder keeps its
//! `scene.toml`.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Instant;

use cosim_tests::corpus::{self, Outcome};

fn env_u64(name: &str, default: u64) -> u64 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn main() {
    if let Ok(seed) = std::env::var("CORPUS_PRINT") {
        // One case's scene, to run it with `coupler-node run`.
        let seed = seed.parse().expect("CORPUS_PRINT=SEED");
        print!("{}", corpus::generate(seed).toml);
        return;
    }
    let n = env_u64("CORPUS_N", 200);
    let from = env_u64("CORPUS_FROM", 0);
    let out = std::env::var_os("CORPUS_OUT")
        .map(PathBuf::from)
        .unwrap_or_else(|| std::env::temp_dir().join("cosim-corpus"));
    let start = Instant::now();
    let mut counts: BTreeMap<&str, usize> = BTreeMap::new();
    let mut by_kind: BTreeMap<String, BTreeMap<&str, usize>> = BTreeMap::new();
    let mut failures: Vec<(u64, String, Outcome)> = Vec::new();
    for seed in from..from + n {
        let case = corpus::generate(seed);
        let dir = out.join(format!("{seed}"));
        let _ = std::fs::remove_dir_all(&dir);
        let outcome = corpus::check(&case, &dir);
        let category = outcome.category();
        *counts.entry(category).or_default() += 1;
        let kind = format!(
            "{}-D {:?} {:?}{}",
            case.dim,
            case.shape,
            case.placement,
            if case.fracture { " fracture" } else { "" }
        );
        *by_kind
            .entry(kind.clone())
            .or_default()
            .entry(category)
            .or_default() += 1;
        if !outcome.passed() {
            let _ = std::fs::write(dir.join("scene.toml"), &case.toml);
            failures.push((
                seed,
                format!("{kind} Mach {:.2} {:?}", case.mach, case.kept),
                outcome,
            ));
        } else {
            let _ = std::fs::remove_dir_all(&dir);
        }
    }
    println!(
        "{n} cases from seed {from} in {:.1} s",
        start.elapsed().as_secs_f64()
    );
    for (category, count) in &counts {
        println!("  {category:>13}: {count}");
    }
    println!("\nby case kind:");
    for (kind, c) in &by_kind {
        let row: Vec<String> = c.iter().map(|(k, v)| format!("{k} {v}")).collect();
        println!("  {kind:<40} {}", row.join(", "));
    }
    println!("\nfailing seeds:");
    for (seed, kind, outcome) in &failures {
        let mut text = format!("{outcome:?}");
        if text.len() > 300 {
            let mut end = 300;
            while !text.is_char_boundary(end) {
                end -= 1;
            }
            text.truncate(end);
        }
        println!("  {seed:>6} {kind}: {text}");
    }
}
