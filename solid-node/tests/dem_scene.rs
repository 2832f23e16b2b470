//! `scenes/cantilever.toml` parses with the scene schema and builds the expected solid.

use protocol::scene::Scene;
use solid_node::dem::{ParticleId, ParticleMotion, Solid};

#[test]
fn cantilever_scene_parses_and_builds() {
    let text = include_str!("../../scenes/cantilever.toml");
    let scene = Scene::from_toml_str(text, "scenes/cantilever.toml").expect("scene parses");
    assert_eq!(scene.dim(), 3);
    let cfg = scene.solid.as_ref().expect("a solid section");
    let solid = Solid::from_scene(cfg, scene.dim(), scene.run.threads as usize).expect("builds");
    assert_eq!(solid.n_particles(), 21);
    assert_eq!(solid.model().links.len(), 20);
    let fixed: Vec<usize> = (0..21)
        .filter(|&p| solid.model().particles[p].motion == ParticleMotion::Fixed)
        .collect();
    assert_eq!(fixed, vec![0]);
    assert!(
        solid.position(ParticleId(0))[0].abs() < 1e-12,
        "clamp particle centred at x = 0"
    );
    let h = 2.0 / 20.5;
    let last = solid.model().particles[20].x0.x;
    assert!((last + 0.5 * h - 2.0).abs() < 1e-12, "free end at x = 2 m");
}
