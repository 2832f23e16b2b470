//! Output writers (only binaries open files): the particle table as CSV, and for ParaView VTK
//! polydata of the particles (their centres with their fields, and their faces moved rigidly)
//! and of the wet surface, as XML `.vtp` bytes or legacy ASCII to any `std::io::Write`.

use std::io::{self, Write};

use protocol::vtk::{DataArray, PolyCells, PolyData, Values, poly_data};

use crate::dem::{ParticleId, Solid, WetSurfaceData};

/// The particles as VTK XML polydata (`.vtp` bytes): one vertex per particle centre \[m\] with
/// point data `id`, `velocity` [m/s], `angular_velocity` [rad/s] (space frame; 2-D about z),
/// the orientation relative to t = 0 (`theta` \[rad\] in 2-D, `orientation` the quaternion
/// `(w, x, y, z)` in 3-D) and `sigma_n` \[Pa\] as [`Solid::normal_stress`].
pub fn particles_vtp(solid: &Solid, title: &str) -> Vec<u8> {
    let dim = solid.dim();
    let n = solid.n_particles();
    let (mut points, mut velocity, mut omega) = (
        Vec::with_capacity(3 * n),
        Vec::with_capacity(3 * n),
        Vec::with_capacity(3 * n),
    );
    let mut orientation = Vec::with_capacity(if dim == 3 { 4 * n } else { n });
    for p in 0..n {
        let id = ParticleId(p as u32);
        points.extend_from_slice(&planar(solid.position(id), dim));
        velocity.extend_from_slice(&planar(solid.velocity(id), dim));
        omega.extend_from_slice(&solid.angular_velocity(id));
        let q = solid.orientation(id);
        orientation.extend_from_slice(if dim == 3 { &q[..] } else { &q[..1] });
    }
    let mut poly = PolyData::vertices(points);
    poly.point_data = vec![
        DataArray::scalar("id", Values::Int64((0..n as i64).collect())),
        DataArray::vector("velocity", velocity),
        DataArray::vector("angular_velocity", omega),
        if dim == 3 {
            DataArray {
                name: "orientation".into(),
                components: 4,
                values: Values::Float64(orientation),
            }
        } else {
            DataArray::scalar("theta", Values::Float64(orientation))
        },
        DataArray::scalar("sigma_n", Values::Float64(solid.normal_stress())),
    ];
    poly_data(&poly, title)
}

/// The particles' faces moved rigidly with their particles as VTK XML polydata (`.vtp` bytes;
/// polygons in 3-D, edges as lines in 2-D), with cell data `particle`, `sigma_n` \[Pa\] and
/// `velocity` [m/s]: the arrays of [`write_particles_vtk`].
pub fn solid_faces_vtp(solid: &Solid, title: &str) -> Vec<u8> {
    let model = solid.model();
    let sigma = solid.normal_stress();
    let mut connectivity = Vec::new();
    let mut offsets = Vec::with_capacity(model.faces.len());
    let (mut particle, mut sigma_n, mut velocity) = (Vec::new(), Vec::new(), Vec::new());
    for f in &model.faces {
        connectivity.extend(f.slots.iter().map(|&s| i64::from(s)));
        offsets.push(connectivity.len() as i64);
        particle.push(i64::from(f.particle));
        sigma_n.push(sigma[f.particle as usize]);
        velocity.extend_from_slice(&solid.velocity(ParticleId(f.particle)));
    }
    let poly = PolyData {
        points: face_points(solid),
        kind: PolyCells::surface(solid.dim()),
        connectivity,
        offsets,
        point_data: Vec::new(),
        cell_data: vec![
            DataArray::scalar("particle", Values::Int64(particle)),
            DataArray::scalar("sigma_n", Values::Float64(sigma_n)),
            DataArray::vector("velocity", velocity),
        ],
    };
    poly_data(&poly, title)
}

/// The wet surface as VTK XML polydata (`.vtp` bytes; triangles in 3-D, segments in 2-D), with
/// cell data `wet` (1/0), `particle`, `area` \[m²\] (2-D: length \[m\]), `normal` and `velocity`
/// [m/s]: the arrays of [`write_wet_surface_vtk`] and the area.
pub fn wet_surface_vtp(wet: &WetSurfaceData, title: &str) -> Vec<u8> {
    let dim = wet.dim.max(1);
    let n = wet.n_elements();
    let pad = |data: &[f64]| -> Vec<f64> {
        data.chunks(dim)
            .flat_map(|v| {
                [
                    v[0],
                    v.get(1).copied().unwrap_or(0.0),
                    v.get(2).copied().unwrap_or(0.0),
                ]
            })
            .collect()
    };
    let poly = PolyData {
        points: pad(&wet.vertices),
        kind: PolyCells::surface(wet.dim),
        connectivity: wet.elements.iter().map(|&v| i64::from(v)).collect(),
        offsets: (1..=n as i64).map(|e| e * dim as i64).collect(),
        point_data: Vec::new(),
        cell_data: vec![
            DataArray::scalar(
                "wet",
                Values::UInt8(wet.wet.iter().map(|w| u8::from(*w)).collect()),
            ),
            DataArray::scalar(
                "particle",
                Values::Int64(wet.element_particle.iter().map(|&p| i64::from(p)).collect()),
            ),
            DataArray::scalar("area", Values::Float64(wet.area.clone())),
            DataArray::vector("normal", pad(&wet.normal)),
            DataArray::vector("velocity", pad(&wet.velocity)),
        ],
    };
    poly_data(&poly, title)
}

/// Replaces `path` with `bytes` through a temporary file beside it and a rename, so that a
/// reader (or a run killed while writing) sees the old file or the new one, never a part.
pub fn replace_file(path: &std::path::Path, bytes: &[u8]) -> io::Result<()> {
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    std::fs::write(&tmp, bytes)?;
    std::fs::rename(&tmp, path)
}

/// Every face slot's position, its particle's vertex moved rigidly, xyz (z = 0 in 2-D) \[m\].
fn face_points(solid: &Solid) -> Vec<f64> {
    let model = solid.model();
    let dim = solid.dim();
    let mut points = Vec::with_capacity(3 * model.slots.len());
    for slot in &model.slots {
        let p = slot.particle as usize;
        let id = ParticleId(slot.particle);
        let q = solid.rotation_matrix(id);
        let x = solid.position(id);
        let a = model.vertices0[slot.vertex as usize] - model.particles[p].x0;
        let pos: [f64; 3] =
            std::array::from_fn(|r| x[r] + q[r][0] * a.x + q[r][1] * a.y + q[r][2] * a.z);
        points.extend_from_slice(&planar(pos, dim));
    }
    points
}

/// `v` with z = 0 in 2-D.
fn planar(v: [f64; 3], dim: usize) -> [f64; 3] {
    if dim == 3 { v } else { [v[0], v[1], 0.0] }
}

/// Writes one row per particle:
/// `id,x,y\[,z\],vx,vy\[,vz\],theta|qw,qx,qy,qz,omega|wx,wy,wz,sigma_n` (SI units; orientation
/// relative to t = 0; `sigma_n` as [`Solid::normal_stress`], positive in tension).
pub fn write_particles_csv(w: &mut impl Write, solid: &Solid) -> io::Result<()> {
    let dim = solid.dim();
    let axes = ["x", "y", "z"];
    let mut header = vec!["id".to_string()];
    header.extend(axes[..dim].iter().map(|a| a.to_string()));
    header.extend(axes[..dim].iter().map(|a| format!("v{a}")));
    if dim == 3 {
        header.extend(["qw", "qx", "qy", "qz", "wx", "wy", "wz"].map(String::from));
    } else {
        header.extend(["theta", "omega"].map(String::from));
    }
    header.push("sigma_n".into());
    let mut table = csv::Writer::from_writer(w);
    table.write_record(&header)?;
    let sigma = solid.normal_stress();
    for (p, s) in sigma.iter().enumerate() {
        let id = ParticleId(p as u32);
        let mut row = vec![p.to_string()];
        let x = solid.position(id);
        let v = solid.velocity(id);
        row.extend(x[..dim].iter().map(|c| format!("{c:e}")));
        row.extend(v[..dim].iter().map(|c| format!("{c:e}")));
        let q = solid.orientation(id);
        let omega = solid.angular_velocity(id);
        if dim == 3 {
            row.extend(q.iter().map(|c| format!("{c:e}")));
            row.extend(omega.iter().map(|c| format!("{c:e}")));
        } else {
            row.push(format!("{:e}", q[0]));
            row.push(format!("{:e}", omega[2]));
        }
        row.push(format!("{s:e}"));
        table.write_record(&row)?;
    }
    table.flush()
}

/// Writes the particles as legacy-VTK polydata: every face moved rigidly with its particle
/// (2-D: edges as lines), with cell data `particle`, `sigma_n` and `velocity`.
pub fn write_particles_vtk(w: &mut impl Write, solid: &Solid, title: &str) -> io::Result<()> {
    let model = solid.model();
    let dim = solid.dim();
    writeln!(
        w,
        "# vtk DataFile Version 3.0\n{}\nASCII\nDATASET POLYDATA",
        one_line(title)
    )?;
    writeln!(w, "POINTS {} double", model.slots.len())?;
    for pos in face_points(solid).chunks_exact(3) {
        writeln!(w, "{:e} {:e} {:e}", pos[0], pos[1], pos[2])?;
    }
    let size: usize = model.faces.iter().map(|f| f.slots.len() + 1).sum();
    let keyword = if dim == 3 { "POLYGONS" } else { "LINES" };
    writeln!(w, "{keyword} {} {size}", model.faces.len())?;
    for f in &model.faces {
        let ids: Vec<String> = f.slots.iter().map(|s| s.to_string()).collect();
        writeln!(w, "{} {}", f.slots.len(), ids.join(" "))?;
    }
    let sigma = solid.normal_stress();
    writeln!(w, "CELL_DATA {}", model.faces.len())?;
    writeln!(w, "SCALARS particle int 1\nLOOKUP_TABLE default")?;
    for f in &model.faces {
        writeln!(w, "{}", f.particle)?;
    }
    writeln!(w, "SCALARS sigma_n double 1\nLOOKUP_TABLE default")?;
    for f in &model.faces {
        writeln!(w, "{:e}", sigma[f.particle as usize])?;
    }
    writeln!(w, "VECTORS velocity double")?;
    for f in &model.faces {
        let v = solid.velocity(ParticleId(f.particle));
        writeln!(w, "{:e} {:e} {:e}", v[0], v[1], v[2])?;
    }
    Ok(())
}

/// Writes the wet surface as legacy-VTK polydata (triangles in 3-D, line segments in 2-D), with
/// cell data `wet` (1/0), `particle`, `normal` and `velocity`.
pub fn write_wet_surface_vtk(
    w: &mut impl Write,
    wet: &WetSurfaceData,
    title: &str,
) -> io::Result<()> {
    let dim = wet.dim;
    writeln!(
        w,
        "# vtk DataFile Version 3.0\n{}\nASCII\nDATASET POLYDATA",
        one_line(title)
    )?;
    let n_vertices = wet.vertices.len().checked_div(dim).unwrap_or(0);
    writeln!(w, "POINTS {n_vertices} double")?;
    for v in wet.vertices.chunks(dim.max(1)) {
        let z = if dim == 3 { v[2] } else { 0.0 };
        writeln!(w, "{:e} {:e} {:e}", v[0], v[1], z)?;
    }
    let n = wet.n_elements();
    let keyword = if dim == 3 { "POLYGONS" } else { "LINES" };
    writeln!(w, "{keyword} {n} {}", n * (dim + 1))?;
    for el in wet.elements.chunks(dim.max(1)) {
        let ids: Vec<String> = el.iter().map(|s| s.to_string()).collect();
        writeln!(w, "{dim} {}", ids.join(" "))?;
    }
    writeln!(w, "CELL_DATA {n}")?;
    writeln!(w, "SCALARS wet int 1\nLOOKUP_TABLE default")?;
    for flag in &wet.wet {
        writeln!(w, "{}", u8::from(*flag))?;
    }
    writeln!(w, "SCALARS particle int 1\nLOOKUP_TABLE default")?;
    for p in &wet.element_particle {
        writeln!(w, "{p}")?;
    }
    for (name, data) in [("normal", &wet.normal), ("velocity", &wet.velocity)] {
        writeln!(w, "VECTORS {name} double")?;
        for v in data.chunks(dim.max(1)) {
            let z = if dim == 3 { v[2] } else { 0.0 };
            writeln!(w, "{:e} {:e} {:e}", v[0], v[1], z)?;
        }
    }
    Ok(())
}

fn one_line(title: &str) -> String {
    title.replace(['\n', '\r'], " ").chars().take(255).collect()
}

/// Writes `bytes` to `path`: appended when `append`, else into a new (or emptied) file. An error
/// names the file.
pub fn append_or_create(path: &std::path::Path, append: bool, bytes: &[u8]) -> std::io::Result<()> {
    use std::io::Write as _;
    let named =
        |e: std::io::Error| std::io::Error::new(e.kind(), format!("{}: {e}", path.display()));
    let mut file = std::fs::OpenOptions::new()
        .create(true)
        .write(true)
        .append(append)
        .truncate(!append)
        .open(path)
        .map_err(named)?;
    file.write_all(bytes).map_err(named)
}

#[cfg(test)]
mod tests {
    use protocol::scene::Scene;
    use protocol::vtk::read;

    use super::*;

    fn solid(dim: usize) -> Solid {
        let shape = if dim == 3 {
            "{ box = { center = [0.0, 0.0, 0.0], size = [0.2, 0.1, 0.1] } }\ndivisions = [2, 1, 1]"
        } else {
            "{ box = { center = [0.0, 0.0], size = [0.2, 0.1] } }\ndivisions = [2, 1]"
        };
        let text = format!(
            "name = \"t\"\n[solid]\ndensity = 1000.0\nyoung = 1e6\npoisson = 0.2\n[[solid.bodies]]\nshape = {shape}\n"
        );
        let scene = Scene::from_toml_str(&text, "test").expect("scene");
        Solid::from_scene(scene.solid.as_ref().expect("solid"), dim, 1).expect("builds")
    }

    #[test]
    fn csv_has_a_header_and_one_row_per_particle() {
        for dim in [2, 3] {
            let s = solid(dim);
            let mut buf = Vec::new();
            write_particles_csv(&mut buf, &s).expect("writes");
            let text = String::from_utf8(buf).expect("utf8");
            let lines: Vec<&str> = text.lines().collect();
            assert_eq!(lines.len(), 1 + s.n_particles());
            let cols = lines[0].split(',').count();
            assert!(lines[0].starts_with(if dim == 3 {
                "id,x,y,z,vx,vy,vz"
            } else {
                "id,x,y,vx,vy"
            }));
            assert!(lines[0].ends_with(",sigma_n"));
            assert!(lines[1..].iter().all(|l| l.split(',').count() == cols));
        }
    }

    /// A solid moving and spinning, so that every particle's fields differ from zero.
    fn moving_solid(dim: usize) -> Solid {
        let (shape, init) = if dim == 3 {
            (
                "{ box = { center = [0.0, 0.0, 0.0], size = [0.2, 0.1, 0.1] } }\ndivisions = [2, 1, 1]",
                "velocity = [0.5, -0.25, 0.125]\nangular_velocity = [1.0, 2.0, -3.0]",
            )
        } else {
            (
                "{ box = { center = [0.0, 0.0], size = [0.2, 0.1] } }\ndivisions = [3, 1]",
                "velocity = [0.5, -0.25]\nangular_velocity = [2.0]",
            )
        };
        let text = format!(
            "name = \"t\"\n[solid]\ndensity = 1000.0\nyoung = 1e6\npoisson = 0.2\n[[solid.bodies]]\nshape = {shape}\n[[solid.init]]\nregion = \"all\"\n{init}\n"
        );
        let scene = Scene::from_toml_str(&text, "test").expect("scene");
        Solid::from_scene(scene.solid.as_ref().expect("solid"), dim, 1).expect("builds")
    }

    fn f64s<'a>(
        file: &'a read::VtkFile,
        section: &str,
        name: &str,
        components: usize,
    ) -> &'a [f64] {
        let a = file.array(section, name).expect(name);
        assert_eq!(a.components, components, "{name}");
        a.as_f64().expect("Float64")
    }

    fn same_bits(a: &[f64], b: &[f64]) -> bool {
        a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
    }

    #[test]
    fn particles_vtp_round_trips_every_particle_field() {
        for dim in [2, 3] {
            let s = moving_solid(dim);
            let n = s.n_particles();
            let file = read::parse(&particles_vtp(&s, "particles")).expect("decodes");
            assert_eq!(file.piece["NumberOfPoints"], n.to_string());
            assert_eq!(file.piece["NumberOfVerts"], n.to_string());
            let points = f64s(&file, "Points", "Points", 3);
            let velocity = f64s(&file, "PointData", "velocity", 3);
            let omega = f64s(&file, "PointData", "angular_velocity", 3);
            let sigma = f64s(&file, "PointData", "sigma_n", 1);
            let (name, nq) = if dim == 3 {
                ("orientation", 4)
            } else {
                ("theta", 1)
            };
            let q = f64s(&file, "PointData", name, nq);
            assert!(same_bits(sigma, &s.normal_stress()));
            let mut moving = 0;
            for p in 0..n {
                let id = ParticleId(p as u32);
                let mut x = s.position(id);
                let mut v = s.velocity(id);
                if dim == 2 {
                    (x[2], v[2]) = (0.0, 0.0);
                }
                assert!(same_bits(&points[3 * p..3 * p + 3], &x), "particle {p}");
                assert!(same_bits(&velocity[3 * p..3 * p + 3], &v), "particle {p}");
                assert!(same_bits(&omega[3 * p..3 * p + 3], &s.angular_velocity(id)));
                assert!(same_bits(
                    &q[nq * p..nq * (p + 1)],
                    &s.orientation(id)[..nq]
                ));
                moving += usize::from(v.iter().any(|c| *c != 0.0));
            }
            assert_eq!(
                moving, n,
                "every particle moves, so a zeroed field would show"
            );
            let ids = file.array("PointData", "id").and_then(|a| a.as_i64());
            assert_eq!(ids, Some(&(0..n as i64).collect::<Vec<_>>()[..]));
        }
    }

    #[test]
    fn faces_and_wet_surface_vtp_hold_the_legacy_arrays() {
        for dim in [2, 3] {
            let s = moving_solid(dim);
            let model = s.model();
            let file = read::parse(&solid_faces_vtp(&s, "solid")).expect("decodes");
            let tag = if dim == 3 { "Polys" } else { "Lines" };
            assert_eq!(file.piece["NumberOfPoints"], model.slots.len().to_string());
            assert_eq!(
                file.piece[&format!("NumberOf{tag}")],
                model.faces.len().to_string()
            );
            let connectivity = file.array(tag, "connectivity").and_then(|a| a.as_i64());
            let expected: Vec<i64> = model
                .faces
                .iter()
                .flat_map(|f| f.slots.iter().map(|&v| i64::from(v)))
                .collect();
            assert_eq!(connectivity, Some(&expected[..]));
            // The points are those of the legacy file, written there with `{:e}` (exact).
            let mut legacy = Vec::new();
            write_particles_vtk(&mut legacy, &s, "solid").expect("writes");
            let legacy = String::from_utf8(legacy).expect("utf8");
            let legacy_points: Vec<f64> = legacy
                .lines()
                .skip_while(|l| !l.starts_with("POINTS"))
                .skip(1)
                .take(model.slots.len())
                .flat_map(|l| l.split(' ').map(|w| w.parse::<f64>().expect("number")))
                .collect();
            assert!(same_bits(
                f64s(&file, "Points", "Points", 3),
                &legacy_points
            ));
            let sigma = f64s(&file, "CellData", "sigma_n", 1);
            let stress = s.normal_stress();
            for (f, face) in model.faces.iter().enumerate() {
                assert_eq!(sigma[f].to_bits(), stress[face.particle as usize].to_bits());
            }

            let wet = s.wet_surface();
            let n = wet.n_elements();
            assert!(n > 0);
            let file = read::parse(&wet_surface_vtp(wet, "wet")).expect("decodes");
            assert_eq!(file.piece[&format!("NumberOf{tag}")], n.to_string());
            let pad = |v: &[f64]| -> Vec<f64> {
                v.chunks(dim)
                    .flat_map(|c| [c[0], c[1], if dim == 3 { c[2] } else { 0.0 }])
                    .collect()
            };
            assert!(same_bits(
                f64s(&file, "Points", "Points", 3),
                &pad(&wet.vertices)
            ));
            assert!(same_bits(
                f64s(&file, "CellData", "normal", 3),
                &pad(&wet.normal)
            ));
            assert!(same_bits(
                f64s(&file, "CellData", "velocity", 3),
                &pad(&wet.velocity)
            ));
            assert!(same_bits(f64s(&file, "CellData", "area", 1), &wet.area));
            let flags: Vec<u8> = wet.wet.iter().map(|w| u8::from(*w)).collect();
            assert_eq!(
                file.array("CellData", "wet").map(|a| &a.values),
                Some(&protocol::vtk::Values::UInt8(flags))
            );
            let offsets = file.array(tag, "offsets").and_then(|a| a.as_i64());
            assert_eq!(offsets.map(|o| o.len()), Some(n));
            assert_eq!(
                offsets.and_then(|o| o.last().copied()),
                Some((n * dim) as i64)
            );
        }
    }

    #[test]
    fn vtk_files_have_consistent_counts() {
        for dim in [2, 3] {
            let s = solid(dim);
            let mut buf = Vec::new();
            write_particles_vtk(&mut buf, &s, "particles").expect("writes");
            let text = String::from_utf8(buf).expect("utf8");
            assert!(text.contains(&format!("POINTS {} double", s.model().slots.len())));
            assert!(text.contains(&format!("CELL_DATA {}", s.model().faces.len())));
            let mut buf = Vec::new();
            write_wet_surface_vtk(&mut buf, s.wet_surface(), "wet").expect("writes");
            let text = String::from_utf8(buf).expect("utf8");
            let n = s.wet_surface().n_elements();
            assert!(text.contains(&format!("CELL_DATA {n}")));
            let kw = if dim == 3 { "POLYGONS" } else { "LINES" };
            assert!(text.contains(&format!("{kw} {n} {}", n * (dim + 1))));
        }
    }
}
