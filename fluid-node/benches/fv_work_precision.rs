//! Sod work–precision study in release: OSMP3/5/7 and the MUSCL–Hancock reference at
//! N = 100 … 1600, one thread; writes `work_precision_sod.{csv,svg}` into `$OUT_DIR` (default
//! `target/work-precision`) and prints the table.
//!
//! `cargo bench -p fluid-node --no-default-features --bench fv_work_precision`

fn main() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let text = std::fs::read_to_string(root.join("scenes/sod.toml")).expect("scenes/sod.toml");
    let scene = protocol::scene::Scene::from_toml_str(&text, "sod.toml").expect("valid scene");
    let out = std::env::var("OUT_DIR")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|_| root.join("target/work-precision"));
    let rows =
        fluid_node::report::work_precision(&scene, &[100, 200, 400, 800, 1600], &[3, 5, 7], &out)
            .expect("study runs");
    print!("{}", fluid_node::report::to_csv(&rows));
    println!("written to {}", out.display());
}
