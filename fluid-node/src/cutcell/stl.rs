//! Readers of surface files over bytes (pure, no IO): STL (ASCII or binary) for 3-D, and a CSV of
//! closed 2-D loops (`x,y` per line, loops separated by a blank line).
//!
//! Both return a *soup*: every element gets its own vertices, in file order, so that two files of
//! the same surface at two times correspond element by element (what [`crate::cutcell::swept_volumes`]
//! needs). The cut-cell geometry does not need shared vertices: coincident coordinates are enough.

use crate::cutcell::surface::Surface;

/// A surface read from a file: `dim` coordinates per vertex, `dim` vertices per element.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SurfaceMesh {
    /// 2 or 3.
    pub dim: usize,
    /// Vertex coordinates [file units, taken as m], flattened.
    pub vertices: Vec<f64>,
    /// Connectivity, `dim` indices per element.
    pub elements: Vec<u32>,
    /// Body of each element: the ASCII `solid` block (STL, binary: 0) or the loop (CSV).
    pub element_particle: Vec<u32>,
    /// Loops read clockwise and reversed to counter-clockwise (CSV only).
    pub n_reversed_loops: usize,
}

impl SurfaceMesh {
    /// The mesh as a borrowed [`Surface`].
    pub fn surface(&self) -> Surface<'_> {
        Surface {
            dim: self.dim,
            vertices: &self.vertices,
            elements: &self.elements,
            element_particle: &self.element_particle,
        }
    }

    /// Number of elements.
    pub fn n_elements(&self) -> usize {
        self.element_particle.len()
    }

    /// Signed enclosed volume, in m³ (2-D: area, in m²), by the divergence theorem; positive for a
    /// closed surface whose normals point outwards.
    pub fn enclosed_volume(&self) -> f64 {
        let surface = self.surface();
        let mut acc = 0.0;
        for e in 0..surface.n_elements() {
            let Some(t) = surface.element(e) else {
                continue;
            };
            acc += if self.dim == 3 {
                let [a, b, c] = t;
                (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                    + a[2] * (b[0] * c[1] - b[1] * c[0]))
                    / 6.0
            } else {
                0.5 * (t[0][0] * t[1][1] - t[0][1] * t[1][0])
            };
        }
        acc
    }
}

/// Why a surface file cannot be read (lines counted from 1).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SurfaceFileError {
    /// Neither a binary STL of the right size nor text.
    #[error("not a binary STL (size {size} != 84 + 50 × count) and not UTF-8 text")]
    NotStl {
        /// The file's size \[bytes\].
        size: usize,
    },
    /// Text without the ASCII STL header.
    #[error(
        "not an STL file: no binary triangle count matches the size and no ASCII `solid` header"
    )]
    NoSolidHeader,
    /// An ASCII STL vertex coordinate that is not a number.
    #[error("line {line}: bad vertex coordinate {token:?}")]
    BadCoordinate {
        /// The line.
        line: usize,
        /// The token found.
        token: String,
    },
    /// An ASCII STL facet with fewer than 3 vertices.
    #[error("line {line}: facet with {vertices} vertices")]
    ShortFacet {
        /// The line of `endfacet`.
        line: usize,
        /// The vertices found.
        vertices: usize,
    },
    /// A loops CSV line that is not `x,y`.
    #[error("line {line}: expected `x,y`, found {text:?}")]
    BadPoint {
        /// The line.
        line: usize,
        /// Its text.
        text: String,
    },
    /// A loop of fewer than 3 distinct vertices.
    #[error("loop ending near line {line}: {vertices} vertices, need at least 3")]
    ShortLoop {
        /// The line near the loop's end.
        line: usize,
        /// The vertices found.
        vertices: usize,
    },
}

/// Reads an STL file, binary (80-byte header, `u32` count, 50 bytes per triangle, little endian)
/// or ASCII (`solid … facet normal … outer loop vertex x y z … endloop endfacet … endsolid`).
/// The stored facet normals are ignored: orientation comes from the vertex order. ASCII facets
/// with more than 3 vertices are fanned.
pub fn parse_stl(bytes: &[u8]) -> Result<SurfaceMesh, SurfaceFileError> {
    if bytes.len() >= 84 {
        let count = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
        if count.checked_mul(50).and_then(|n| n.checked_add(84)) == Some(bytes.len()) {
            return Ok(parse_binary(bytes, count));
        }
    }
    let text =
        std::str::from_utf8(bytes).map_err(|_| SurfaceFileError::NotStl { size: bytes.len() })?;
    if !text.trim_start().starts_with("solid") {
        return Err(SurfaceFileError::NoSolidHeader);
    }
    parse_ascii(text)
}

fn parse_binary(bytes: &[u8], count: usize) -> SurfaceMesh {
    let mut mesh = SurfaceMesh {
        dim: 3,
        ..SurfaceMesh::default()
    };
    for t in 0..count {
        let record = &bytes[84 + 50 * t..84 + 50 * (t + 1)];
        for k in 0..9 {
            let at = 12 + 4 * k;
            let x =
                f32::from_le_bytes([record[at], record[at + 1], record[at + 2], record[at + 3]]);
            mesh.vertices.push(f64::from(x));
        }
        let base = 3 * t as u32;
        mesh.elements.extend_from_slice(&[base, base + 1, base + 2]);
        mesh.element_particle.push(0);
    }
    mesh
}

fn parse_ascii(text: &str) -> Result<SurfaceMesh, SurfaceFileError> {
    let mut mesh = SurfaceMesh {
        dim: 3,
        ..SurfaceMesh::default()
    };
    let mut solid = 0u32;
    let mut facet: Vec<[f64; 3]> = Vec::new();
    for (line_no, line) in text.lines().enumerate() {
        let mut tokens = line.split_whitespace();
        match tokens.next() {
            Some("vertex") => {
                let mut x = [0.0; 3];
                for value in &mut x {
                    let token = tokens.next().unwrap_or("");
                    *value = token.parse().map_err(|_| SurfaceFileError::BadCoordinate {
                        line: line_no + 1,
                        token: token.to_string(),
                    })?;
                }
                facet.push(x);
            }
            Some("endloop") | Some("endfacet") => {
                if facet.len() >= 3 {
                    for k in 1..facet.len() - 1 {
                        let base = (mesh.vertices.len() / 3) as u32;
                        for x in [facet[0], facet[k], facet[k + 1]] {
                            mesh.vertices.extend_from_slice(&x);
                        }
                        mesh.elements.extend_from_slice(&[base, base + 1, base + 2]);
                        mesh.element_particle.push(solid);
                    }
                } else if !facet.is_empty() {
                    return Err(SurfaceFileError::ShortFacet {
                        line: line_no + 1,
                        vertices: facet.len(),
                    });
                }
                facet.clear();
            }
            Some("endsolid") => solid += 1,
            _ => {}
        }
    }
    Ok(mesh)
}

/// Reads closed 2-D loops: one `x,y` vertex per line, one loop per body, loops separated by blank
/// lines; lines starting with `#` and a non-numeric first line (a header) are skipped, and a last
/// vertex repeating the first is dropped.
///
/// NOTE: each loop is one body, so it is oriented counter-clockwise (the convention of
/// `WetSurface`: normal `(dy, −dx)` out of the solid); clockwise loops are reversed and counted.
pub fn parse_loops_csv(text: &str) -> Result<SurfaceMesh, SurfaceFileError> {
    let mut mesh = SurfaceMesh {
        dim: 2,
        ..SurfaceMesh::default()
    };
    let mut current: Vec<[f64; 2]> = Vec::new();
    let mut seen_data = false;
    let mut n_loops = 0u32;
    for (line_no, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.starts_with('#') {
            continue;
        }
        if line.is_empty() {
            close_loop(&mut mesh, &mut current, &mut n_loops, line_no)?;
            continue;
        }
        let mut fields = line.split(',').map(str::trim);
        let parsed = (|| {
            let x: f64 = fields.next()?.parse().ok()?;
            let y: f64 = fields.next()?.parse().ok()?;
            Some([x, y])
        })();
        match parsed {
            Some(p) => {
                seen_data = true;
                current.push(p);
            }
            None if !seen_data && current.is_empty() && n_loops == 0 => {} // header
            None => {
                return Err(SurfaceFileError::BadPoint {
                    line: line_no + 1,
                    text: line.to_string(),
                });
            }
        }
    }
    close_loop(&mut mesh, &mut current, &mut n_loops, text.lines().count())?;
    Ok(mesh)
}

fn close_loop(
    mesh: &mut SurfaceMesh,
    current: &mut Vec<[f64; 2]>,
    n_loops: &mut u32,
    line_no: usize,
) -> Result<(), SurfaceFileError> {
    if current.is_empty() {
        return Ok(());
    }
    if current.len() > 1 && current.first() == current.last() {
        current.pop();
    }
    if current.len() < 3 {
        return Err(SurfaceFileError::ShortLoop {
            line: line_no + 1,
            vertices: current.len(),
        });
    }
    let mut area = 0.0;
    for i in 0..current.len() {
        let (p, q) = (current[i], current[(i + 1) % current.len()]);
        area += p[0] * q[1] - p[1] * q[0];
    }
    if area < 0.0 {
        current.reverse();
        mesh.n_reversed_loops += 1;
    }
    let base = (mesh.vertices.len() / 2) as u32;
    let n = current.len() as u32;
    for p in current.iter() {
        mesh.vertices.extend_from_slice(p);
    }
    for i in 0..n {
        mesh.elements
            .extend_from_slice(&[base + i, base + (i + 1) % n]);
        mesh.element_particle.push(*n_loops);
    }
    *n_loops += 1;
    current.clear();
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const TETRA: &str = "solid t\n\
        facet normal 0 0 -1\n outer loop\n vertex 0 0 0\n vertex 0 1 0\n vertex 1 0 0\n endloop\nendfacet\n\
        facet normal 0 -1 0\n outer loop\n vertex 0 0 0\n vertex 1 0 0\n vertex 0 0 1\n endloop\nendfacet\n\
        facet normal -1 0 0\n outer loop\n vertex 0 0 0\n vertex 0 0 1\n vertex 0 1 0\n endloop\nendfacet\n\
        facet normal 1 1 1\n outer loop\n vertex 1 0 0\n vertex 0 1 0\n vertex 0 0 1\n endloop\nendfacet\n\
        endsolid t\n";

    #[test]
    fn ascii_and_binary_stl_agree() {
        let ascii = parse_stl(TETRA.as_bytes()).unwrap();
        assert_eq!(ascii.n_elements(), 4);
        assert!((ascii.enclosed_volume() - 1.0 / 6.0).abs() < 1e-15);
        let mut bytes = vec![0u8; 80];
        bytes.extend_from_slice(&4u32.to_le_bytes());
        for t in ascii.elements.chunks(3) {
            bytes.extend_from_slice(&[0u8; 12]);
            for &v in t {
                for k in 0..3 {
                    let x = ascii.vertices[3 * v as usize + k] as f32;
                    bytes.extend_from_slice(&x.to_le_bytes());
                }
            }
            bytes.extend_from_slice(&[0u8; 2]);
        }
        let binary = parse_stl(&bytes).unwrap();
        assert_eq!(binary, ascii);
    }

    #[test]
    fn bad_stl_is_refused() {
        assert!(parse_stl(b"hello").is_err());
        let err = parse_stl(b"solid x\nfacet\nouter loop\nvertex 0 0 zz\n").unwrap_err();
        assert!(err.to_string().contains("line 4"), "{err}");
    }

    #[test]
    fn loops_are_read_and_oriented_counter_clockwise() {
        let text = "x,y\n0,0\n1,0\n1,1\n0,1\n\n# clockwise\n2,0\n2,1\n3,1\n3,0\n2,0\n";
        let mesh = parse_loops_csv(text).unwrap();
        assert_eq!(mesh.n_elements(), 8);
        assert_eq!(mesh.n_reversed_loops, 1);
        assert!((mesh.enclosed_volume() - 2.0).abs() < 1e-15);
        assert_eq!(mesh.element_particle[4..], [1, 1, 1, 1]);
        assert!(parse_loops_csv("0,0\n1,0\n\n").is_err());
        assert!(parse_loops_csv("0,0\n1,zz\n").is_err());
    }
}
