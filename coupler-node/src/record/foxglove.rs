//! The record's Foxglove channels (issue 39 item 2): at each output time, the solid as a
//! `foxglove.SceneUpdate` on `/foxglove/solid` and a fluid field as a `foxglove.Grid` on
//! `/foxglove/fluid`, JSON messages with Foxglove's well-known schemas (schema encoding
//! `jsonschema`, as Foxglove documents for JSON), so that its 3-D panel shows the run with no
//! decoder (layout: `docs/foxglove/layout.json`).
//!
//! They are views of the output files the nodes wrote for output `k` (`fluid_k.vti`,
//! `solid_k.vtp`, `particles_k.vtp`; written before the nodes report the step's totals, so
//! they are complete when the coupler records the step), built on the record's thread, never
//! the coupler's. A run without VTK outputs (`output.formats` without `"vtk"`) has no such
//! files and records nothing on these topics. Every value is a function of the run (the log
//! time, publish time and the JSON `timestamp` are the simulated time), so two runs of a scene
//! record the same bytes on them.
//!
//! - Grid: the fluid's cell data `rho` \[kg/m³\] and `p` \[Pa\] as little-endian `FLOAT32`
//!   pairs (`cell_stride` 8), rows along y (row-major, y-major as Foxglove reads it), the
//!   2-D grid in the plane z = 0, a 3-D grid's mid-plane slice `k = nz / 2` at its cell centres'
//!   height; cells the solid covers (`vtkGhostType` hidden) are NaN, so the solid shows.
//! - SceneUpdate: one entity `solid` (frame `world`): the particles' faces (2-D: edges as a
//!   `LINE_LIST`; 3-D: polygons as a triangle fan) coloured by the particle's normal stress
//!   `sigma_n` (blue compression, white 0, red tension, scaled by the largest |sigma_n| of the
//!   output, in the entity's metadata `sigma_n_max_Pa`), and the links broken since the run
//!   (re)started as red lines between particle centres.

use std::path::Path;

use protocol::vtk::Values;
use protocol::vtk::read::{Array, VtkFile, parse_some};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Topic of the solid's scene updates.
pub const SOLID_TOPIC: &str = "/foxglove/solid";
/// Topic of the fluid's grid.
pub const FLUID_TOPIC: &str = "/foxglove/fluid";
/// Schema name of [`SOLID_TOPIC`] (Foxglove's well-known name).
pub const SCENE_UPDATE_SCHEMA_NAME: &str = "foxglove.SceneUpdate";
/// Schema name of [`FLUID_TOPIC`] (Foxglove's well-known name).
pub const GRID_SCHEMA_NAME: &str = "foxglove.Grid";
/// The frame every message is in.
pub const FRAME_ID: &str = "world";
/// `foxglove.NumericType` `FLOAT32`.
pub const FLOAT32: u8 = 7;
/// `foxglove.LineType` `LINE_LIST`.
pub const LINE_LIST: u8 = 2;

/// `time`: seconds and nanoseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct Time {
    /// Seconds.
    pub sec: u64,
    /// Nanoseconds, below 1e9.
    pub nsec: u32,
}

impl Time {
    /// Simulated time `t` \[s\] as the record's log time ([`protocol::topics::log_time`]).
    pub fn of(t: f64) -> Time {
        let ns = protocol::topics::log_time(t);
        Time {
            sec: ns / 1_000_000_000,
            nsec: (ns % 1_000_000_000) as u32,
        }
    }
}

/// `duration` (0: an entity stays until replaced).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct Duration {
    /// Seconds.
    pub sec: i64,
    /// Nanoseconds.
    pub nsec: u32,
}

/// `foxglove.Vector3`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[schemars(title = "foxglove.Vector3")]
pub struct Vector3 {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
}

/// `foxglove.Vector2`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[schemars(title = "foxglove.Vector2")]
pub struct Vector2 {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
}

/// `foxglove.Quaternion`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[schemars(title = "foxglove.Quaternion")]
pub struct Quaternion {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
    /// w.
    pub w: f64,
}

/// `foxglove.Pose`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[schemars(title = "foxglove.Pose")]
pub struct Pose {
    /// Position \[m\].
    pub position: Vector3,
    /// Orientation.
    pub orientation: Quaternion,
}

impl Pose {
    /// At `position`, not rotated.
    pub fn at(position: Vector3) -> Pose {
        Pose {
            position,
            orientation: Quaternion {
                x: 0.0,
                y: 0.0,
                z: 0.0,
                w: 1.0,
            },
        }
    }
}

/// `foxglove.Point3` (single precision is plenty for a picture and halves the text).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[schemars(title = "foxglove.Point3")]
pub struct Point3 {
    /// x \[m\].
    pub x: f32,
    /// y \[m\].
    pub y: f32,
    /// z \[m\].
    pub z: f32,
}

/// `foxglove.Color`, components in \[0, 1\].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[schemars(title = "foxglove.Color")]
pub struct Color {
    /// Red.
    pub r: f32,
    /// Green.
    pub g: f32,
    /// Blue.
    pub b: f32,
    /// Alpha.
    pub a: f32,
}

/// `foxglove.PackedElementField`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[schemars(title = "foxglove.PackedElementField")]
pub struct PackedElementField {
    /// Name of the field.
    pub name: String,
    /// Byte offset in a cell.
    pub offset: u32,
    /// `foxglove.NumericType` (7: `FLOAT32`).
    #[serde(rename = "type")]
    pub kind: u8,
}

/// `foxglove.Grid`: a 2-D grid of data.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[schemars(title = "foxglove.Grid", description = "A 2D grid of data")]
pub struct Grid {
    /// Timestamp (the simulated time).
    pub timestamp: Time,
    /// Frame of reference.
    pub frame_id: String,
    /// The grid's lower corner; the grid lies in the pose's x-y plane.
    pub pose: Pose,
    /// Cells along x.
    pub column_count: u32,
    /// Cell size along x and y \[m\].
    pub cell_size: Vector2,
    /// Bytes between rows of `data`.
    pub row_stride: u32,
    /// Bytes between cells of a row.
    pub cell_stride: u32,
    /// Fields of each cell.
    pub fields: Vec<PackedElementField>,
    /// Base64 of the packed cells, row-major (y-major).
    #[schemars(extend("contentEncoding" = "base64"))]
    pub data: String,
}

/// `foxglove.LinePrimitive`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[schemars(title = "foxglove.LinePrimitive")]
pub struct LinePrimitive {
    /// `foxglove.LineType` (2: `LINE_LIST`).
    #[serde(rename = "type")]
    pub kind: u8,
    /// Origin of the points.
    pub pose: Pose,
    /// Thickness (pixels when `scale_invariant`).
    pub thickness: f64,
    /// `thickness` in pixels.
    pub scale_invariant: bool,
    /// Points.
    pub points: Vec<Point3>,
    /// Colour of the whole line (used when `colors` is empty).
    pub color: Color,
    /// One colour per point, or none.
    pub colors: Vec<Color>,
    /// Indices into `points` (empty: all in order).
    pub indices: Vec<u32>,
}

/// `foxglove.TriangleListPrimitive`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[schemars(title = "foxglove.TriangleListPrimitive")]
pub struct TriangleListPrimitive {
    /// Origin of the points.
    pub pose: Pose,
    /// Vertices.
    pub points: Vec<Point3>,
    /// Colour of all triangles (used when `colors` is empty).
    pub color: Color,
    /// One colour per point, or none.
    pub colors: Vec<Color>,
    /// Three indices per triangle into `points`.
    pub indices: Vec<u32>,
}

/// `foxglove.KeyValuePair`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[schemars(title = "foxglove.KeyValuePair")]
pub struct KeyValuePair {
    /// Key.
    pub key: String,
    /// Value.
    pub value: String,
}

/// `foxglove.SceneEntity`; the primitive kinds it does not use are empty arrays.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[schemars(title = "foxglove.SceneEntity")]
pub struct SceneEntity {
    /// Timestamp (the simulated time).
    pub timestamp: Time,
    /// Frame of reference.
    pub frame_id: String,
    /// Identifier: an entity replaces the earlier one of the same id.
    pub id: String,
    /// Zero: stays until replaced.
    pub lifetime: Duration,
    /// Follows `frame_id`.
    pub frame_locked: bool,
    /// Key-value pairs shown with the entity.
    pub metadata: Vec<KeyValuePair>,
    /// Arrows (none).
    pub arrows: Vec<serde_json::Value>,
    /// Cubes (none).
    pub cubes: Vec<serde_json::Value>,
    /// Spheres (none).
    pub spheres: Vec<serde_json::Value>,
    /// Cylinders (none).
    pub cylinders: Vec<serde_json::Value>,
    /// Lines: 2-D faces, broken links.
    pub lines: Vec<LinePrimitive>,
    /// Triangles: 3-D faces.
    pub triangles: Vec<TriangleListPrimitive>,
    /// Texts (none).
    pub texts: Vec<serde_json::Value>,
    /// Models (none).
    pub models: Vec<serde_json::Value>,
}

/// `foxglove.SceneUpdate`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[schemars(
    title = "foxglove.SceneUpdate",
    description = "An update to the entities displayed in a 3D scene"
)]
pub struct SceneUpdate {
    /// Deletions (none).
    pub deletions: Vec<serde_json::Value>,
    /// Entities.
    pub entities: Vec<SceneEntity>,
}

/// JSON schema of `T`, nested types inlined (Foxglove resolves no `$ref`).
fn schema_of<T: JsonSchema>() -> String {
    let generator = schemars::generate::SchemaSettings::draft2020_12()
        .with(|s| s.inline_subschemas = true)
        .into_generator();
    serde_json::to_string(&generator.into_root_schema_for::<T>()).expect("a schema serializes")
}

/// JSON schema of [`SCENE_UPDATE_SCHEMA_NAME`] (the part of Foxglove's that these messages use).
pub fn scene_update_schema() -> String {
    schema_of::<SceneUpdate>()
}

/// JSON schema of [`GRID_SCHEMA_NAME`].
pub fn grid_schema() -> String {
    schema_of::<Grid>()
}

/// Standard base64 (RFC 4648, with padding).
///
/// NOTE: written into bytes three at a time, not a `char` at a time into the `String`: the
/// grid of every output passes through here, and `String::push` per character took 6.7 % of
/// the record thread's samples on `clamped-beam-2d` (issue 39 item 4).
pub fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let code = |n: u32, i: u32| ALPHABET[(n >> (18 - 6 * i) & 63) as usize];
    let mut out = Vec::with_capacity(bytes.len().div_ceil(3) * 4);
    let whole = bytes.chunks_exact(3);
    let rest = whole.remainder();
    for c in whole {
        let n = (u32::from(c[0]) << 16) | (u32::from(c[1]) << 8) | u32::from(c[2]);
        out.extend_from_slice(&[code(n, 0), code(n, 1), code(n, 2), code(n, 3)]);
    }
    if !rest.is_empty() {
        let b1 = rest.get(1).copied().unwrap_or(0);
        let n = (u32::from(rest[0]) << 16) | (u32::from(b1) << 8);
        let third = if rest.len() == 2 { code(n, 2) } else { b'=' };
        out.extend_from_slice(&[code(n, 0), code(n, 1), third, b'=']);
    }
    String::from_utf8(out).expect("the alphabet and padding are ASCII")
}

/// Why an output file gives no Foxglove message.
#[derive(Debug, thiserror::Error)]
pub enum ViewError {
    /// The file is not there (no VTK outputs, or no such node): nothing to record.
    #[error("{0} is missing")]
    Missing(String),
    /// The file is there and does not read as expected.
    #[error("{file}: {reason}")]
    Bad {
        /// The file.
        file: String,
        /// What is wrong.
        reason: String,
    },
}

/// `dir/name` with the arrays of `wanted` (section, name) decoded, the others skipped
/// ([`parse_some`]).
fn read_vtk(dir: &Path, name: &str, wanted: &[(&str, &str)]) -> Result<VtkFile, ViewError> {
    let path = dir.join(name);
    let bytes = match std::fs::read(&path) {
        Ok(bytes) => bytes,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(ViewError::Missing(path.display().to_string()));
        }
        Err(e) => {
            return Err(ViewError::Bad {
                file: path.display().to_string(),
                reason: e.to_string(),
            });
        }
    };
    parse_some(&bytes, |section, array| wanted.contains(&(section, array))).map_err(|e| {
        ViewError::Bad {
            file: path.display().to_string(),
            reason: e.to_string(),
        }
    })
}

fn bad(file: &str, reason: impl Into<String>) -> ViewError {
    ViewError::Bad {
        file: file.to_string(),
        reason: reason.into(),
    }
}

/// Three numbers of a dataset attribute (`Origin`, `Spacing`).
fn triple(file: &VtkFile, key: &str, name: &str) -> Result<[f64; 3], ViewError> {
    let text = file
        .dataset
        .get(key)
        .ok_or_else(|| bad(name, format!("no {key}")))?;
    let v: Vec<f64> = text
        .split_whitespace()
        .map(str::parse)
        .collect::<Result<_, _>>()
        .map_err(|e| bad(name, format!("{key} {text:?}: {e}")))?;
    <[f64; 3]>::try_from(v).map_err(|_| bad(name, format!("{key} {text:?} is not 3 numbers")))
}

/// The grid message of output `k`'s `fluid_k.vti` in `dir` at simulated time `t` \[s\].
pub fn fluid_grid(dir: &Path, k: u32, t: f64) -> Result<Grid, ViewError> {
    let name = format!("fluid_{k}.vti");
    let wanted = [
        ("CellData", "rho"),
        ("CellData", "p"),
        ("CellData", "vtkGhostType"),
    ];
    let file = read_vtk(dir, &name, &wanted)?;
    grid_of(&file, &name, t)
}

/// [`fluid_grid`] of a decoded file (`name` for errors).
pub fn grid_of(file: &VtkFile, name: &str, t: f64) -> Result<Grid, ViewError> {
    let extent = file
        .dataset
        .get("WholeExtent")
        .ok_or_else(|| bad(name, "no WholeExtent"))?;
    let ext: Vec<usize> = extent
        .split_whitespace()
        .map(str::parse)
        .collect::<Result<_, _>>()
        .map_err(|e| bad(name, format!("WholeExtent {extent:?}: {e}")))?;
    if ext.len() != 6 {
        return Err(bad(
            name,
            format!("WholeExtent {extent:?} is not 6 numbers"),
        ));
    }
    // A flat axis has extent 0 0: one layer of cells.
    let cells: [usize; 3] = std::array::from_fn(|a| ext[2 * a + 1].max(1));
    let origin = triple(file, "Origin", name)?;
    let spacing = triple(file, "Spacing", name)?;
    let n = cells.iter().product::<usize>();
    let field = |field: &str| -> Result<&[f64], ViewError> {
        let a = file
            .array("CellData", field)
            .ok_or_else(|| bad(name, format!("no cell array {field}")))?;
        let v = a
            .as_f64()
            .ok_or_else(|| bad(name, format!("{field} is not Float64")))?;
        if v.len() != n {
            return Err(bad(
                name,
                format!("{field} has {} values for {n} cells", v.len()),
            ));
        }
        Ok(v)
    };
    let (rho, p) = (field("rho")?, field("p")?);
    let hidden = match file.array("CellData", "vtkGhostType").map(|a| &a.values) {
        Some(Values::UInt8(g)) if g.len() == n => Some(g.as_slice()),
        Some(_) => return Err(bad(name, "vtkGhostType is not one UInt8 per cell")),
        None => None,
    };
    // A 3-D grid's mid-plane slice; a 2-D (or 1-D) grid's only layer.
    let (nx, ny) = (cells[0], cells[1]);
    let kz = cells[2] / 2;
    let flat_z = ext[5] == 0;
    let z = if flat_z {
        0.0
    } else {
        origin[2] + (kz as f64 + 0.5) * spacing[2]
    };
    let mut data = Vec::with_capacity(8 * nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let idx = i + nx * (j + ny * kz);
            let covered = hidden.is_some_and(|g| g[idx] & 32 != 0);
            for v in [rho[idx], p[idx]] {
                let v = if covered { f32::NAN } else { v as f32 };
                data.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    let field = |name: &str, offset| PackedElementField {
        name: name.into(),
        offset,
        kind: FLOAT32,
    };
    Ok(Grid {
        timestamp: Time::of(t),
        frame_id: FRAME_ID.into(),
        pose: Pose::at(Vector3 {
            x: origin[0],
            y: origin[1],
            z,
        }),
        column_count: nx as u32,
        cell_size: Vector2 {
            x: spacing[0],
            y: spacing[1],
        },
        row_stride: (8 * nx) as u32,
        cell_stride: 8,
        fields: vec![field("rho", 0), field("p", 4)],
        data: base64(&data),
    })
}

/// Blue (compression, `x` = -1) to white (0) to red (tension, 1), in steps of 1/1000.
pub fn stress_color(x: f64) -> Color {
    let t = x.abs().min(1.0);
    let fade = ((1.0 - t) * 1000.0).round() as f32 / 1000.0;
    let (r, g, b) = if x >= 0.0 {
        (1.0, fade, fade)
    } else {
        (fade, fade, 1.0)
    };
    Color { r, g, b, a: 1.0 }
}

fn point3(p: &[f64]) -> Point3 {
    Point3 {
        x: p[0] as f32,
        y: p[1] as f32,
        z: p[2] as f32,
    }
}

fn int_array<'a>(
    file: &'a VtkFile,
    section: &str,
    field: &str,
    name: &str,
) -> Result<&'a [i64], ViewError> {
    file.array(section, field)
        .and_then(Array::as_i64)
        .ok_or_else(|| bad(name, format!("no Int64 array {section}/{field}")))
}

/// The scene update of output `k` from `solid_k.vtp` and `particles_k.vtp` in `dir` at
/// simulated time `t` \[s\]; `broken` the links broken so far (particle ids).
pub fn solid_scene(
    dir: &Path,
    k: u32,
    t: f64,
    broken: &[[u32; 2]],
) -> Result<SceneUpdate, ViewError> {
    let faces_name = format!("solid_{k}.vtp");
    let faces = read_vtk(
        dir,
        &faces_name,
        &[
            ("Points", "Points"),
            ("Polys", "connectivity"),
            ("Polys", "offsets"),
            ("Lines", "connectivity"),
            ("Lines", "offsets"),
            ("CellData", "sigma_n"),
        ],
    )?;
    let centres = if broken.is_empty() {
        None
    } else {
        Some(read_vtk(
            dir,
            &format!("particles_{k}.vtp"),
            &[("Points", "Points")],
        )?)
    };
    scene_of(&faces, &faces_name, centres.as_ref(), t, broken)
}

/// [`solid_scene`] of decoded files.
pub fn scene_of(
    faces: &VtkFile,
    name: &str,
    centres: Option<&VtkFile>,
    t: f64,
    broken: &[[u32; 2]],
) -> Result<SceneUpdate, ViewError> {
    let points = faces
        .array("Points", "Points")
        .and_then(Array::as_f64)
        .ok_or_else(|| bad(name, "no Float64 Points"))?;
    let polygons = faces.array("Polys", "connectivity").is_some();
    let section = if polygons { "Polys" } else { "Lines" };
    let connectivity = int_array(faces, section, "connectivity", name)?;
    let offsets = int_array(faces, section, "offsets", name)?;
    let sigma = faces
        .array("CellData", "sigma_n")
        .and_then(Array::as_f64)
        .ok_or_else(|| bad(name, "no Float64 cell array sigma_n"))?;
    if sigma.len() != offsets.len() {
        return Err(bad(name, "sigma_n is not one value per face"));
    }
    let n_points = points.len() / 3;
    let sigma_max = sigma.iter().fold(0.0_f64, |m, s| m.max(s.abs()));
    let grey = Color {
        r: 0.6,
        g: 0.6,
        b: 0.6,
        a: 1.0,
    };
    let mut colors = vec![grey; n_points];
    let mut indices = Vec::new();
    let mut start = 0usize;
    for (face, &end) in offsets.iter().enumerate() {
        let end = end as usize;
        let slots = connectivity
            .get(start..end)
            .ok_or_else(|| bad(name, "offsets past the connectivity"))?;
        if slots.iter().any(|&s| s < 0 || s as usize >= n_points) {
            return Err(bad(name, format!("face {face} names a point out of range")));
        }
        let x = if sigma_max > 0.0 {
            sigma[face] / sigma_max
        } else {
            0.0
        };
        for &s in slots {
            colors[s as usize] = stress_color(x);
        }
        if polygons {
            for w in 1..slots.len().saturating_sub(1) {
                indices.extend([slots[0], slots[w], slots[w + 1]].map(|s| s as u32));
            }
        } else {
            for w in slots.windows(2) {
                indices.extend([w[0] as u32, w[1] as u32]);
            }
        }
        start = end;
    }
    let points: Vec<Point3> = points.chunks_exact(3).map(point3).collect();
    let origin = Pose::at(Vector3::default());
    let mut entity = SceneEntity {
        timestamp: Time::of(t),
        frame_id: FRAME_ID.into(),
        id: "solid".into(),
        lifetime: Duration::default(),
        frame_locked: false,
        metadata: vec![
            KeyValuePair {
                key: "sigma_n_max_Pa".into(),
                value: format!("{sigma_max:e}"),
            },
            KeyValuePair {
                key: "links_broken".into(),
                value: broken.len().to_string(),
            },
        ],
        arrows: Vec::new(),
        cubes: Vec::new(),
        spheres: Vec::new(),
        cylinders: Vec::new(),
        lines: Vec::new(),
        triangles: Vec::new(),
        texts: Vec::new(),
        models: Vec::new(),
    };
    if polygons {
        entity.triangles.push(TriangleListPrimitive {
            pose: origin,
            points,
            color: grey,
            colors,
            indices,
        });
    } else {
        entity.lines.push(LinePrimitive {
            kind: LINE_LIST,
            pose: origin,
            thickness: 1.5,
            scale_invariant: true,
            points,
            color: grey,
            colors,
            indices,
        });
    }
    if let Some(centres) = centres {
        entity.lines.push(broken_links(centres, broken)?);
    }
    Ok(SceneUpdate {
        deletions: Vec::new(),
        entities: vec![entity],
    })
}

/// Red segments between the centres (`particles_k.vtp` points, by particle id) of the
/// particles of each broken link.
fn broken_links(centres: &VtkFile, broken: &[[u32; 2]]) -> Result<LinePrimitive, ViewError> {
    let name = "particles.vtp";
    let x = centres
        .array("Points", "Points")
        .and_then(Array::as_f64)
        .ok_or_else(|| bad(name, "no Float64 Points"))?;
    let mut points = Vec::with_capacity(2 * broken.len());
    for pair in broken {
        for id in pair {
            let i = 3 * *id as usize;
            let p = x
                .get(i..i + 3)
                .ok_or_else(|| bad(name, format!("no particle {id}")))?;
            points.push(point3(p));
        }
    }
    Ok(LinePrimitive {
        kind: LINE_LIST,
        pose: Pose::at(Vector3::default()),
        thickness: 3.0,
        scale_invariant: true,
        points,
        color: Color {
            r: 1.0,
            g: 0.1,
            b: 0.1,
            a: 1.0,
        },
        colors: Vec::new(),
        indices: Vec::new(),
    })
}

#[cfg(test)]
mod tests {
    use super::base64;

    #[test]
    fn base64_gives_the_rfc_4648_test_vectors() {
        let cases = [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ];
        for (plain, coded) in cases {
            assert_eq!(base64(plain.as_bytes()), coded, "{plain:?}");
        }
    }

    /// Every byte value in each of a group's three places, and every length's padding: the
    /// text decodes back to the bytes (a decoder written here from RFC 4648's table).
    #[test]
    fn base64_decodes_back_to_every_byte() {
        const ALPHABET: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
        let decode = |text: &str| -> Vec<u8> {
            let mut bits = 0u32;
            let mut n = 0;
            let mut out = Vec::new();
            for c in text.bytes().take_while(|&c| c != b'=') {
                let v = ALPHABET
                    .iter()
                    .position(|&a| a == c)
                    .expect("in the alphabet");
                bits = (bits << 6) | v as u32;
                n += 6;
                if n >= 8 {
                    n -= 8;
                    out.push((bits >> n) as u8);
                }
            }
            out
        };
        let mut bytes: Vec<u8> = (0..=255u8).collect();
        bytes.extend((0..=255u8).rev());
        bytes.extend((0..=255u8).step_by(7));
        for len in (0..bytes.len())
            .step_by(61)
            .chain(bytes.len() - 3..=bytes.len())
        {
            let text = base64(&bytes[..len]);
            assert_eq!(text.len(), len.div_ceil(3) * 4);
            assert_eq!(decode(&text), &bytes[..len], "length {len}");
        }
    }
}
