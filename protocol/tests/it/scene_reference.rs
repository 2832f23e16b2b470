//! `docs/scenes.md` against the scene schema, both ways.
//!
//! Covers: every key path of the resolved scene (`Scene::to_toml`) of a few scenes built field by
//! field, which together set every optional table and every enum variant that takes a table
//! (regions, shapes, motions, prescribed motions, profiles), must be documented on a
//! "- `path` (...)" line of `docs/scenes.md`, and every path documented there must occur in one
//! of them. Arrays of tables are written `a[].k`. The scenes are struct literals, so a new field
//! does not compile until it is set here (and so shows up in the key set), and the `match`es
//! below without a wildcard do not compile when a variant is added.
//!
//! Cannot cover: the string values of enum keys (`run.scheme`, `fluid.boundary.x`, ...) and the
//! string forms of `region = "all"` and `motion = "free"` (they are values, not keys), defaults
//! and types as written in the doc, nor whether a meaning is right.

use std::collections::BTreeSet;

use protocol::scene::*;

fn walk(prefix: &str, value: &toml::Value, out: &mut BTreeSet<String>) {
    let join = |k: &str| {
        if prefix.is_empty() {
            k.to_string()
        } else {
            format!("{prefix}.{k}")
        }
    };
    if let toml::Value::Table(t) = value {
        for (k, v) in t {
            let path = join(k);
            out.insert(path.clone());
            match v {
                toml::Value::Table(_) => walk(&path, v, out),
                toml::Value::Array(items) => {
                    for item in items.iter().filter(|i| i.is_table()) {
                        walk(&format!("{path}[]"), item, out);
                    }
                }
                _ => {}
            }
        }
    }
}

// No wildcard: a new variant breaks the build until the scenes below use it.
fn _regions(r: &Region) {
    match r {
        Region::All | Region::Box { .. } | Region::Ball { .. } | Region::HalfSpace { .. } => {}
    }
}
fn _shapes(s: &Shape) {
    match s {
        Shape::Box { .. } | Shape::Ring { .. } | Shape::Tube { .. } | Shape::Particles(_) => {}
    }
}
fn _motions(m: &Motion, p: &PrescribedMotion, f: &Profile) {
    match m {
        Motion::Free | Motion::Fixed | Motion::Velocity(_) => {}
    }
    match p {
        PrescribedMotion::Fixed
        | PrescribedMotion::Velocity(_)
        | PrescribedMotion::Sinusoid { .. }
        | PrescribedMotion::Spring { .. } => {}
    }
    match f {
        Profile::DensityWave { .. } | Profile::IsentropicVortex { .. } => {}
    }
}

fn regions() -> Vec<Region> {
    vec![
        Region::All,
        Region::Box {
            lower: vec![0.0, 0.0],
            upper: vec![1.0, 1.0],
        },
        Region::Ball {
            center: vec![0.5, 0.5],
            radius: 0.1,
        },
        Region::HalfSpace {
            point: vec![0.5, 0.5],
            normal: vec![1.0, 0.0],
        },
    ]
}

/// A fluid section with every key set, `profile` its initial profile.
fn fluid(profile: Profile) -> FluidConfig {
    FluidConfig {
        node: "real".into(),
        gamma: 1.4,
        cfl: 0.5,
        flux: FluxConfig::default(),
        lower: vec![0.0, 0.0],
        upper: vec![1.0, 1.0],
        cells: vec![4, 4],
        boundary: BoundaryConfig {
            x: Some([Boundary::Wall, Boundary::Characteristic]),
            y: Some([Boundary::Periodic, Boundary::Periodic]),
            z: Some([Boundary::Outflow, Boundary::Outflow]),
        },
        vacuum_thresholds: Some(VacuumConfig {
            rho: 1e-10,
            p: 1e-10,
        }),
        characteristic: Some(CharacteristicConfig {
            sigma: DEFAULT_CHARACTERISTIC_SIGMA,
            p_far: Some(1.0),
        }),
        init: regions()
            .into_iter()
            .map(|region| InitEntry {
                region,
                rho: 1.0,
                p: 1.0,
                velocity: vec![0.0, 0.0],
            })
            .collect(),
        pressure: Some(PressureField {
            value: 1.0,
            gradient: vec![0.0, 0.0],
            impedance: 1.0,
        }),
        profile: Some(profile),
        ranks: 2,
        decomposition: Some(vec![1, 2]),
    }
}

/// A solid section with every key set, `motion` its prescribed motion.
fn solid(motion: PrescribedMotion) -> SolidConfig {
    let body = |shape: Shape, motion: Motion| BodyConfig {
        shape,
        divisions: vec![2, 2],
        motion,
        links: Some(LinksConfig {
            spring: 1.0,
            rotation: 1.0,
        }),
    };
    SolidConfig {
        node: "real".into(),
        density: Some(1.0),
        young: Some(1.0),
        poisson: Some(0.3),
        face_inertia: Some(FaceInertia::Exact),
        fracture: Some(FractureConfig {
            elongation_at_break: 0.1,
        }),
        gravity: Some(vec![0.0, -9.8]),
        bodies: vec![
            body(
                Shape::Box {
                    center: vec![0.5, 0.5],
                    size: vec![0.1, 0.1],
                },
                Motion::Free,
            ),
            body(
                Shape::Ring {
                    center: vec![0.5, 0.5],
                    inner_radius: 0.1,
                    outer_radius: 0.2,
                },
                Motion::Fixed,
            ),
            body(
                Shape::Tube {
                    center: vec![0.5, 0.5, 0.5],
                    axis: 2,
                    inner_radius: 0.1,
                    outer_radius: 0.2,
                    length: 1.0,
                },
                Motion::Velocity(vec![1.0, 0.0]),
            ),
            body(
                Shape::Particles(vec![ParticleSpec {
                    vertices: vec![vec![0.0, 0.0], vec![1.0, 0.0], vec![0.0, 1.0]],
                }]),
                Motion::Free,
            ),
        ],
        constraints: regions()
            .into_iter()
            .map(|region| ConstraintConfig {
                region,
                motion: Motion::Velocity(vec![0.0, 0.0]),
            })
            .collect(),
        init: regions()
            .into_iter()
            .map(|region| SolidInit {
                region,
                velocity: Some(vec![0.0, 0.0]),
                angular_velocity: Some(vec![0.0]),
            })
            .collect(),
        prescribed: Some(PrescribedConfig {
            r#box: BoxSpec {
                center: vec![0.5, 0.5],
                size: vec![0.1, 0.1],
            },
            motion,
        }),
        contact: Some(ContactConfig::default()),
        walls: Some(SolidWalls::Hold),
    }
}

fn scenes() -> Vec<Scene> {
    let run = RunConfig {
        dt_max: Some(1.0),
        max_steps: Some(10),
        dt_min: Some(1e-9),
        energy_tolerance: Some(1e-6),
        record_max_bytes: Some(1 << 30),
        solid_substeps: Some(protocol::scene::SolidSubsteps::AUTO),
        ..RunConfig::default()
    };
    let output = OutputConfig {
        times: vec![0.5],
        every: Some(0.1),
        formats: vec![
            OutputFormat::Csv,
            OutputFormat::Vtk,
            OutputFormat::VtkLegacy,
        ],
        probes: vec![ProbeConfig {
            name: "a".into(),
            point: Some(vec![0.5, 0.5]),
            particle_at: Some(vec![0.5, 0.5]),
            particle: Some(0),
        }],
    };
    let scene = |profile, motion| Scene {
        name: "reference".into(),
        run: run.clone(),
        fluid: Some(fluid(profile)),
        solid: Some(solid(motion)),
        output: output.clone(),
    };
    vec![
        scene(
            Profile::DensityWave {
                amplitude: 0.1,
                wave: vec![1.0, 0.0],
                velocity: vec![1.0, 0.0],
                p: 1.0,
            },
            PrescribedMotion::Velocity(vec![1.0, 0.0]),
        ),
        scene(
            Profile::IsentropicVortex {
                beta: 5.0,
                center: vec![0.5, 0.5],
                velocity: vec![1.0, 1.0],
            },
            PrescribedMotion::Sinusoid {
                amplitude: vec![0.1, 0.0],
                frequency: 1.0,
            },
        ),
        scene(
            Profile::DensityWave {
                amplitude: 0.1,
                wave: vec![1.0, 0.0],
                velocity: vec![1.0, 0.0],
                p: 1.0,
            },
            PrescribedMotion::Spring {
                mass: 1.0,
                stiffness: 1.0,
            },
        ),
    ]
}

/// The paths documented on "- `path` (" lines.
fn documented() -> BTreeSet<String> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../docs/scenes.md");
    let text = std::fs::read_to_string(path).expect("docs/scenes.md");
    text.lines()
        .filter_map(|l| l.strip_prefix("- `"))
        .filter_map(|rest| rest.split_once("` ("))
        .map(|(key, _)| key.to_string())
        .collect()
}

#[test]
fn scene_reference_documents_every_schema_key_and_no_other() {
    let mut schema = BTreeSet::new();
    for scene in scenes() {
        let value: toml::Value = toml::from_str(&scene.to_toml()).expect("resolved scene");
        walk("", &value, &mut schema);
    }
    let doc = documented();
    let undocumented: Vec<_> = schema.difference(&doc).collect();
    let unknown: Vec<_> = doc.difference(&schema).collect();
    assert!(
        undocumented.is_empty() && unknown.is_empty(),
        "docs/scenes.md out of step with the scene schema:\n  keys missing from the doc: \
         {undocumented:?}\n  documented keys the schema lacks: {unknown:?}"
    );
    assert!(doc.len() > 100, "only {} keys documented", doc.len());
}

/// Every key that `scenes/*.toml` uses is documented (the example scenes, as written).
#[test]
fn scene_reference_documents_the_example_scenes_keys() {
    let doc = documented();
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes");
    let mut missing = BTreeSet::new();
    for entry in std::fs::read_dir(dir).expect("scenes/") {
        let path = entry.expect("entry").path();
        if path.extension().is_none_or(|e| e != "toml") {
            continue;
        }
        let text = std::fs::read_to_string(&path).expect("scene");
        let value: toml::Value = toml::from_str(&text).expect("toml");
        let mut keys = BTreeSet::new();
        walk("", &value, &mut keys);
        for k in keys.difference(&doc) {
            missing.insert(format!("{}: {k}", path.display()));
        }
    }
    assert!(
        missing.is_empty(),
        "keys of scenes/ not in docs/scenes.md: {missing:?}"
    );
}
