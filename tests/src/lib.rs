//! Helpers of the end-to-end tests: the whole co-simulation in one process over the in-memory
//! transport (the baseline against which the bus is measured), paths of the node binaries, and
//! the runs' CSV files read back.

use std::time::Duration;

pub mod corpus;

use coupler_node::driver::{self, Abort, DriverConfig, RecordSink, SinkError, Summary};
use coupler_node::report::data::Table;
use coupler_node::scheme::{Coupler, CouplerConfig};
use protocol::scene::Scene;
use protocol::transport::{Link, MemoryTransport};
use protocol::wire::NodeKind;

/// A numeric CSV file of a run, read as `coupler-node report` reads it (the `csv` crate): a
/// ragged row or a value that is no number panics naming the file, the line and the column.
pub fn read_table(path: &std::path::Path) -> Table {
    let text =
        std::fs::read_to_string(path).unwrap_or_else(|e| panic!("reading {}: {e}", path.display()));
    Table::parse(&text, &path.display().to_string()).unwrap_or_else(|e| panic!("{e}"))
}

/// Column `name` of the CSV file `path` ([`read_table`]); panics without that column.
pub fn csv_column(path: &std::path::Path, name: &str) -> Vec<f64> {
    let table = read_table(path);
    let col = table
        .column(name)
        .unwrap_or_else(|| panic!("{}: no column {name}", path.display()));
    table.rows.iter().map(|row| row[col]).collect()
}

/// Every frame the coupler saw, in order: `(from, to, bytes)`.
#[derive(Default)]
pub struct MemorySink {
    /// Exchanged frames.
    pub frames: Vec<(NodeKind, NodeKind, Vec<u8>)>,
    /// Diagnostics JSON, one per step.
    pub diagnostics: Vec<Vec<u8>>,
    /// The rows `links_broken.csv` would hold, without its header.
    pub links_broken: String,
}

impl RecordSink for MemorySink {
    fn frame(
        &mut self,
        from: NodeKind,
        to: NodeKind,
        _: f64,
        _: u64,
        f: &[u8],
    ) -> Result<(), SinkError> {
        self.frames.push((from, to, f.to_vec()));
        Ok(())
    }
    fn checkpoint(&mut self, node: NodeKind, _: f64, _: u64, f: &[u8]) -> Result<(), SinkError> {
        self.frames.push((node, NodeKind::Coupler, f.to_vec()));
        Ok(())
    }
    fn diagnostics(&mut self, _: f64, _: u64, json: &[u8]) -> Result<(), SinkError> {
        self.diagnostics.push(json.to_vec());
        Ok(())
    }
    fn links_broken(&mut self, step: u64, links: &[(f64, [u32; 2])]) -> Result<(), SinkError> {
        for row in coupler_node::sink::links_broken_records(step, links) {
            self.links_broken.push_str(&(row.join(",") + "\n"));
        }
        Ok(())
    }
    fn end_step(&mut self) -> Result<(), SinkError> {
        Ok(())
    }
}

/// Result of an in-process run.
pub struct InProcess {
    /// The coupler's summary.
    pub summary: Summary,
    /// The coupler's error, if the run stopped early.
    pub error: Option<String>,
    /// What the nodes' loops returned.
    pub node_errors: Vec<String>,
    /// What was exchanged.
    pub sink: MemorySink,
}

/// Runs a scene with its configured implementations, each node on its own thread, over the
/// in-memory transport.
pub fn run_in_process(scene: &Scene) -> InProcess {
    run_in_process_to(scene, None)
}

/// [`run_in_process`], with the nodes writing their outputs (fields, probes) into `out`.
pub fn run_in_process_to(scene: &Scene, out: Option<&std::path::Path>) -> InProcess {
    let mut nodes = Vec::new();
    if scene.fluid.is_some() {
        nodes.push(NodeKind::Fluid);
    }
    if scene.solid.is_some() {
        nodes.push(NodeKind::Solid);
    }
    let (mut coupler_end, ends) = MemoryTransport::star(&nodes);
    let timeout = Duration::from_secs(60);
    let mut handles = Vec::new();
    for mut end in ends {
        let scene = scene.clone();
        let out = out.map(std::path::Path::to_path_buf);
        handles.push(std::thread::spawn(move || -> Result<(), String> {
            let mut link = Link::new(&mut end, timeout);
            match link.me() {
                NodeKind::Fluid => {
                    let fluid = scene.fluid.as_ref().expect("fluid section");
                    let mut model = fluid_node::cli::model_from_scene(&scene, &fluid.node)
                        .map_err(|e| e.to_string())?;
                    let cfg = fluid_node::node::LoopConfig {
                        scene_hash: scene.hash(),
                        coupled: scene.solid.is_some(),
                        out: out.clone(),
                        initial_output: scene.initial_output(),
                    };
                    fluid_node::node::run(model.as_mut(), &mut link, &cfg)
                        .map_err(|e| e.to_string())
                }
                _ => {
                    let solid = scene.solid.as_ref().expect("solid section");
                    let mut model = solid_node::cli::model_from_scene(&scene, &solid.node)
                        .map_err(|e| e.to_string())?;
                    let cfg = solid_node::node::LoopConfig {
                        scene_hash: scene.hash(),
                        coupled: scene.fluid.is_some(),
                        out,
                        initial_output: scene.initial_output(),
                    };
                    solid_node::node::run(model.as_mut(), &mut link, &cfg)
                        .map_err(|e| e.to_string())
                }
            }
        }));
    }
    let mut coupler = Coupler::new(CouplerConfig::from_scene(scene));
    let mut sink = MemorySink::default();
    let cfg = DriverConfig {
        timeout,
        progress: false,
        name: scene.name.clone(),
        t_end: scene.run.t_end,
        dt_min: scene.run.dt_min,
    };
    let (summary, error) = driver::drive(
        &mut coupler_end,
        &mut coupler,
        &mut sink,
        &cfg,
        &Abort::default(),
    );
    drop(coupler_end);
    let node_errors = handles
        .into_iter()
        .filter_map(|h| match h.join() {
            Ok(Ok(())) => None,
            Ok(Err(e)) => Some(e),
            Err(_) => Some("node thread panicked".into()),
        })
        .collect();
    InProcess {
        summary,
        error: error.map(|e| e.to_string()),
        node_errors,
        sink,
    }
}

/// Reads a scene from the workspace's `scenes/` folder.
pub fn scene(name: &str) -> Scene {
    scene_with(name, "")
}

/// [`scene`] with `extra` TOML (tables such as `[[output.probes]]`) appended to its text.
pub fn scene_with(name: &str, extra: &str) -> Scene {
    let path = format!("{}/../scenes/{name}", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("reading {path}: {e}"));
    Scene::from_toml_str(&(text + extra), &path).unwrap_or_else(|e| panic!("{e}"))
}
