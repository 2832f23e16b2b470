//! `scenes/cantilever.toml` parses with the scene schema and builds the expected solid.

use protocol::scene::Scene;
use solid_node::dem::{ParticleId, ParticleMotion, Solid};

#[test]
fn cantilever_scene_parses_and_builds() {
    let text = include_str!("../../../scenes/cantilever.toml");
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

/// `scenes/clamped-beam-3d-tets.toml` (paper 003 §5.1.2's "24 tetrahedral particles"): four
/// cuboids of 0.2857 x 1/7 x 0.2857 m, each cut into the 6 tetrahedra of Kuhn's split, link
/// into one body: 6 links inside each cuboid and 2 across each of the 3 squares between them.
/// The lowest layer is the clamp.
#[test]
fn the_tetrahedral_beam_builds_with_its_links() {
    let text = include_str!("../../../scenes/clamped-beam-3d-tets.toml");
    let scene = Scene::from_toml_str(text, "scenes/clamped-beam-3d-tets.toml").expect("parses");
    let cfg = scene.solid.as_ref().expect("a solid section");
    let solid = Solid::from_scene(cfg, scene.dim(), 1).expect("builds");
    let model = solid.model();
    assert_eq!(solid.n_particles(), 24);
    assert_eq!(model.links.len(), 4 * 6 + 3 * 2);
    let cuboid = 0.2857 * 0.2857 / 7.0;
    for (p, particle) in model.particles.iter().enumerate() {
        let rel = (particle.volume - cuboid / 6.0).abs() / (cuboid / 6.0);
        assert!(rel < 1e-12, "particle {p}: volume {:e}", particle.volume);
        let fixed = particle.motion == ParticleMotion::Fixed;
        assert_eq!(
            fixed,
            particle.x0.y < 1.0 / 14.0,
            "particle {p} at y = {}",
            particle.x0.y
        );
    }
    let n_fixed = model
        .particles
        .iter()
        .filter(|p| p.motion == ParticleMotion::Fixed)
        .count();
    assert_eq!(n_fixed, 6);
}
