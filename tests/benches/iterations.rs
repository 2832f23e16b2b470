//! Fixed-point iterations per step of the semi-implicit scheme for each relaxation and
//! predictor, on the doubles scene in one process (`cargo bench -p cosim-tests --bench
//! iterations`; `SCENE=name.toml` picks another scene of `scenes/`).

use cosim_tests::{run_in_process, scene};
use protocol::scene::{Predictor, Relaxation};

fn main() {
    let name = std::env::var("SCENE").unwrap_or_else(|_| "backbone-doubles.toml".into());
    let mut scene = scene(&name);
    scene.run.record = protocol::scene::RecordLevel::None;
    println!("{name}: mean (max) iterations per step");
    println!("relaxation \\ predictor | none | linear | correction");
    for relaxation in [Relaxation::None, Relaxation::Aitken, Relaxation::IqnIls] {
        let mut row = format!("{relaxation:?}");
        for predictor in [Predictor::None, Predictor::Linear, Predictor::Correction] {
            scene.run.relaxation = relaxation;
            scene.run.predictor = predictor;
            let run = run_in_process(&scene);
            let it = &run.summary.coupling_iterations;
            match run.error {
                None => row.push_str(&format!(" | {:.2} ({})", it.mean, it.max)),
                Some(e) => row.push_str(&format!(" | failed: {e}")),
            }
        }
        println!("{row}");
    }
}
