//! `run.solid_substeps`: parsing, validation and the K a step takes (docs/subcycling.md).

use protocol::scene::{AUTO_SUBSTEP_FRACTION, MAX_SOLID_SUBSTEPS, Scene, SolidSubsteps};

fn run_with(value: &str) -> Result<Scene, String> {
    let line = if value.is_empty() {
        String::new()
    } else {
        format!("solid_substeps = {value}")
    };
    let text = format!(
        "name = \"k\"\n[run]\n{line}\n[solid]\ndensity = 1.0\nyoung = 1.0\npoisson = 0.0\n[[solid.bodies]]\nshape = {{ box = {{ center = [0.0, 0.0], size = [1.0, 1.0] }} }}\ndivisions = [1, 1]\n"
    );
    Scene::from_toml_str(&text, "k.toml").map_err(|e| e.to_string())
}

#[test]
fn the_key_takes_an_integer_from_1_to_256_or_auto() {
    let k = |v: &str| run_with(v).map(|s| s.run.solid_substeps);
    assert_eq!(k("1"), Ok(Some(SolidSubsteps::Fixed(1))));
    assert_eq!(k("256"), Ok(Some(SolidSubsteps::Fixed(256))));
    assert_eq!(k("\"auto\""), Ok(Some(SolidSubsteps::AUTO)));
    for bad in ["0", "257", "\"fast\"", "-1", "2.5"] {
        let err = k(bad).expect_err(bad);
        assert!(err.contains("solid_substeps"), "{bad}: {err}");
    }
    // Absent: not in the resolved scene, so the scene hash is the one it had before the key.
    let without = run_with("").expect("scene");
    assert_eq!(without.run.solid_substeps, None);
    assert!(!without.to_toml().contains("solid_substeps"));
}

#[test]
fn auto_takes_the_smallest_k_whose_sub_step_is_within_half_the_bound() {
    assert_eq!(AUTO_SUBSTEP_FRACTION, 0.5);
    let auto = SolidSubsteps::AUTO;
    assert_eq!(auto.for_step(1.0, 4.0), Ok(1));
    assert_eq!(auto.for_step(1.0, 2.0), Ok(1));
    assert_eq!(auto.for_step(1.0, 1.0), Ok(2));
    assert_eq!(auto.for_step(1.0, 0.5), Ok(4));
    assert_eq!(auto.for_step(1.0, 0.4999), Ok(5));
    assert_eq!(auto.for_step(1.0, f64::INFINITY), Ok(1));
    // Thin-shell's numbers: the fluid's 1.68e-4 s over the solid's 1.5e-5 s.
    let (dt, bound) = (1.6849455e-4, 1.5038e-5);
    let k = auto.for_step(dt, bound).expect("within 256");
    let half = bound * AUTO_SUBSTEP_FRACTION;
    assert!(
        dt / f64::from(k) <= half && dt / f64::from(k - 1) > half,
        "{k}"
    );
    for (dt, bound) in [
        (1.0, 1.0 / 3.0),
        (0.7, 0.1),
        (1e-3, 1e-3 / 7.0),
        (3.3e-5, 1.1e-6),
    ] {
        let half = bound * AUTO_SUBSTEP_FRACTION;
        let k = auto.for_step(dt, bound).expect("within 256");
        assert!(dt / f64::from(k) <= half, "{dt} {bound} {k}");
        assert!(k == 1 || dt / f64::from(k - 1) > half, "{dt} {bound} {k}");
    }
    assert_eq!(auto.for_step(1.0, 1.0 / 128.0), Ok(MAX_SOLID_SUBSTEPS));
    assert_eq!(auto.for_step(1.0, 1.0 / 1000.0), Err(2000));
    assert_eq!(auto.for_step(1.0, 0.0), Err(u64::MAX));
    assert_eq!(SolidSubsteps::Fixed(5).for_step(1.0, 1e-9), Ok(5));
}
