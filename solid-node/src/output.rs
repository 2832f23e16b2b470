//! Output writers to any `std::io::Write` (only binaries open files): the particle table as
//! CSV, and legacy-VTK polydata of the particles (their faces, moved rigidly) and of the wet
//! surface, for ParaView.

use std::io::{self, Write};

use crate::dem::{ParticleId, Solid, WetSurfaceData};

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
    writeln!(w, "{}", header.join(","))?;
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
        writeln!(w, "{}", row.join(","))?;
    }
    Ok(())
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
    for slot in &model.slots {
        let p = slot.particle as usize;
        let id = ParticleId(slot.particle);
        let q = solid.rotation_matrix(id);
        let x = solid.position(id);
        let a = model.vertices0[slot.vertex as usize] - model.particles[p].x0;
        let pos: Vec<f64> = (0..3)
            .map(|r| x[r] + q[r][0] * a.x + q[r][1] * a.y + q[r][2] * a.z)
            .collect();
        writeln!(
            w,
            "{:e} {:e} {:e}",
            pos[0],
            pos[1],
            if dim == 3 { pos[2] } else { 0.0 }
        )?;
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

#[cfg(test)]
mod tests {
    use protocol::scene::Scene;

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
