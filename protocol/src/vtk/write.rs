//! Encoding: arrays, image data, polydata and the `.pvd` series into bytes.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::io::Write as _;

/// Uncompressed bytes per compressed block (VTK's default).
pub const BLOCK_SIZE: usize = 32768;

/// The values of one data array.
#[derive(Clone, Debug, PartialEq)]
pub enum Values {
    /// `Float64`.
    Float64(Vec<f64>),
    /// `Int64` (connectivity, offsets, ids).
    Int64(Vec<i64>),
    /// `Int32`.
    Int32(Vec<i32>),
    /// `UInt8` (flags).
    UInt8(Vec<u8>),
}

impl Values {
    /// VTK's name of the element type.
    pub fn type_name(&self) -> &'static str {
        match self {
            Values::Float64(_) => "Float64",
            Values::Int64(_) => "Int64",
            Values::Int32(_) => "Int32",
            Values::UInt8(_) => "UInt8",
        }
    }

    /// Number of scalar entries (tuples times components).
    pub fn len(&self) -> usize {
        match self {
            Values::Float64(v) => v.len(),
            Values::Int64(v) => v.len(),
            Values::Int32(v) => v.len(),
            Values::UInt8(v) => v.len(),
        }
    }

    /// No entries.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    fn to_le_bytes(&self) -> Vec<u8> {
        match self {
            Values::Float64(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
            Values::Int64(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
            Values::Int32(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
            Values::UInt8(v) => v.clone(),
        }
    }
}

/// A named array of `components` values per tuple (point or cell).
#[derive(Clone, Debug, PartialEq)]
pub struct DataArray {
    /// Name shown in ParaView.
    pub name: String,
    /// Values per tuple (1 for a scalar, 3 for a vector).
    pub components: usize,
    /// The values, tuple after tuple.
    pub values: Values,
}

impl DataArray {
    /// A scalar array.
    pub fn scalar(name: &str, values: Values) -> Self {
        DataArray {
            name: name.into(),
            components: 1,
            values,
        }
    }

    /// A 3-component vector array (pad 2-D vectors with a zero z).
    pub fn vector(name: &str, values: Vec<f64>) -> Self {
        DataArray {
            name: name.into(),
            components: 3,
            values: Values::Float64(values),
        }
    }
}

/// A uniform grid of `cells` cells (one along an inactive axis) from `origin` with `spacing`.
/// An axis of one cell with a spacing of 0 is flat: the image has no thickness along it (a
/// 2-D fluid lies in the plane z = origin, so a top view shows the solid drawn in that plane).
#[derive(Clone, Debug, PartialEq)]
pub struct ImageData {
    /// Cells per axis.
    pub cells: [usize; 3],
    /// Lower corner \[m\].
    pub origin: [f64; 3],
    /// Cell size per axis \[m\].
    pub spacing: [f64; 3],
    /// Arrays with one tuple per cell, x fastest.
    pub cell_data: Vec<DataArray>,
}

/// Which kind of cell a [`PolyData`] holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PolyCells {
    /// Vertices (one point each, or several).
    Verts,
    /// Polylines (segments in 2-D).
    Lines,
    /// Polygons (faces in 3-D).
    Polys,
}

impl PolyCells {
    /// The cells of a surface in `dim` dimensions: segments in 2-D, polygons in 3-D.
    pub fn surface(dim: usize) -> PolyCells {
        if dim == 3 {
            PolyCells::Polys
        } else {
            PolyCells::Lines
        }
    }

    fn tag(self) -> &'static str {
        match self {
            PolyCells::Verts => "Verts",
            PolyCells::Lines => "Lines",
            PolyCells::Polys => "Polys",
        }
    }
}

/// Points and cells of one kind, with point and cell arrays.
#[derive(Clone, Debug, PartialEq)]
pub struct PolyData {
    /// Point coordinates, xyz per point \[m\] (z = 0 in 2-D).
    pub points: Vec<f64>,
    /// Kind of the cells.
    pub kind: PolyCells,
    /// Point indices of every cell, cell after cell.
    pub connectivity: Vec<i64>,
    /// End of each cell in `connectivity` (VTK's `offsets`).
    pub offsets: Vec<i64>,
    /// Arrays with one tuple per point.
    pub point_data: Vec<DataArray>,
    /// Arrays with one tuple per cell.
    pub cell_data: Vec<DataArray>,
}

impl PolyData {
    /// One vertex cell per point.
    pub fn vertices(points: Vec<f64>) -> Self {
        let n = points.len() / 3;
        PolyData {
            points,
            kind: PolyCells::Verts,
            connectivity: (0..n as i64).collect(),
            offsets: (1..=n as i64).collect(),
            point_data: Vec::new(),
            cell_data: Vec::new(),
        }
    }
}

/// Encodes image data as a `.vti` file.
///
/// # Panics
///
/// If an array does not hold one tuple per cell (a bug of the caller).
pub fn image_data(image: &ImageData, comment: &str) -> Vec<u8> {
    let n_cells: usize = image.cells.iter().product();
    let mut file = XmlFile::new("ImageData", comment);
    // A flat axis has one layer of points (extent 0 0), whose spacing VTK never uses: 1.
    let flat = |a: usize| image.cells[a] == 1 && image.spacing[a] == 0.0;
    let points = |a: usize| if flat(a) { 0 } else { image.cells[a] };
    let extent = format!("0 {} 0 {} 0 {}", points(0), points(1), points(2));
    let spacing = std::array::from_fn(|a| if flat(a) { 1.0 } else { image.spacing[a] });
    let triple = |v: [f64; 3]| format!("{} {} {}", v[0], v[1], v[2]);
    let _ = writeln!(
        file.xml,
        "  <ImageData WholeExtent=\"{extent}\" Origin=\"{}\" Spacing=\"{}\">",
        triple(image.origin),
        triple(spacing)
    );
    let _ = writeln!(file.xml, "    <Piece Extent=\"{extent}\">");
    file.xml.push_str("      <CellData>\n");
    for array in &image.cell_data {
        check_tuples(array, n_cells, "cell");
        file.array(array, 8);
    }
    file.xml
        .push_str("      </CellData>\n    </Piece>\n  </ImageData>\n");
    file.finish()
}

/// Encodes polydata as a `.vtp` file.
///
/// # Panics
///
/// If an array does not hold one tuple per point or cell, or an offset or index is out of
/// range (bugs of the caller).
pub fn poly_data(poly: &PolyData, comment: &str) -> Vec<u8> {
    assert_eq!(poly.points.len() % 3, 0, "points are xyz triples");
    let n_points = poly.points.len() / 3;
    let n_cells = poly.offsets.len();
    assert!(
        poly.offsets.windows(2).all(|w| w[0] <= w[1])
            && poly.offsets.last().copied().unwrap_or(0) == poly.connectivity.len() as i64,
        "offsets rise to the length of the connectivity"
    );
    assert!(
        poly.connectivity
            .iter()
            .all(|&i| (0..n_points as i64).contains(&i)),
        "every connectivity entry names a point"
    );
    let mut file = XmlFile::new("PolyData", comment);
    file.xml.push_str("  <PolyData>\n");
    let counts = [PolyCells::Verts, PolyCells::Lines, PolyCells::Polys]
        .map(|k| {
            let n = if k == poly.kind { n_cells } else { 0 };
            format!("NumberOf{}=\"{n}\"", k.tag())
        })
        .join(" ");
    let _ = writeln!(
        file.xml,
        "    <Piece NumberOfPoints=\"{n_points}\" {counts} NumberOfStrips=\"0\">"
    );
    file.xml.push_str("      <PointData>\n");
    for array in &poly.point_data {
        check_tuples(array, n_points, "point");
        file.array(array, 8);
    }
    file.xml.push_str("      </PointData>\n      <CellData>\n");
    for array in &poly.cell_data {
        check_tuples(array, n_cells, "cell");
        file.array(array, 8);
    }
    file.xml.push_str("      </CellData>\n      <Points>\n");
    file.array(
        &DataArray {
            name: "Points".into(),
            components: 3,
            values: Values::Float64(poly.points.clone()),
        },
        8,
    );
    let _ = writeln!(file.xml, "      </Points>\n      <{}>", poly.kind.tag());
    file.array(
        &DataArray::scalar("connectivity", Values::Int64(poly.connectivity.clone())),
        8,
    );
    file.array(
        &DataArray::scalar("offsets", Values::Int64(poly.offsets.clone())),
        8,
    );
    let _ = writeln!(
        file.xml,
        "      </{}>\n    </Piece>\n  </PolyData>",
        poly.kind.tag()
    );
    file.finish()
}

/// The files of one kind written so far, by output index, and the `.pvd` that lists them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Series {
    entries: BTreeMap<u32, (f64, String)>,
}

impl Series {
    /// Records that output `k` at simulated time `t` \[s\] is `file` (relative to the `.pvd`),
    /// replacing an earlier entry of the same `k`, and returns the `.pvd` text listing every
    /// entry in output order.
    pub fn record(&mut self, k: u32, t: f64, file: &str) -> String {
        self.entries.insert(k, (t, file.to_string()));
        self.to_pvd()
    }

    /// The `.pvd` text (`<DataSet timestep="t" file="..."/>` per output, in output order).
    pub fn to_pvd(&self) -> String {
        let mut text = String::from(
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n  <Collection>\n",
        );
        for (t, file) in self.entries.values() {
            let _ = writeln!(
                text,
                "    <DataSet timestep=\"{t:e}\" group=\"\" part=\"0\" file=\"{}\"/>",
                escape(file)
            );
        }
        text.push_str("  </Collection>\n</VTKFile>\n");
        text
    }
}

/// The XML head and the appended binary block being built.
struct XmlFile {
    xml: String,
    appended: Vec<u8>,
}

impl XmlFile {
    fn new(kind: &str, comment: &str) -> Self {
        let mut xml = String::from("<?xml version=\"1.0\"?>\n");
        let comment: String = comment
            .chars()
            .filter(|c| !c.is_control())
            .collect::<String>()
            .replace("--", "- -");
        let _ = writeln!(xml, "<!-- {comment} -->");
        let _ = writeln!(
            xml,
            "<VTKFile type=\"{kind}\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\" compressor=\"vtkZLibDataCompressor\">"
        );
        XmlFile {
            xml,
            appended: Vec::new(),
        }
    }

    fn array(&mut self, array: &DataArray, indent: usize) {
        let _ = writeln!(
            self.xml,
            "{:indent$}<DataArray type=\"{}\" Name=\"{}\" NumberOfComponents=\"{}\" format=\"appended\" offset=\"{}\"/>",
            "",
            array.values.type_name(),
            escape(&array.name),
            array.components,
            self.appended.len()
        );
        compress_into(&array.values.to_le_bytes(), &mut self.appended);
    }

    fn finish(mut self) -> Vec<u8> {
        self.xml.push_str("  <AppendedData encoding=\"raw\">\n   _");
        let mut bytes = self.xml.into_bytes();
        bytes.append(&mut self.appended);
        bytes.extend_from_slice(b"\n  </AppendedData>\n</VTKFile>\n");
        bytes
    }
}

/// Appends VTK's compression header and the zlib blocks of `raw` to `out`.
///
/// NOTE: the blocks are compressed independently (VTK's format), so a writer called on a rayon
/// pool (the fluid node calls it on its own) compresses them on that pool, with the same bytes in
/// the same order; called from any other thread, on that thread alone (no global pool behind a
/// node's `threads`).
///
/// NOTE: zlib's fastest level (1), not its default (6): on the fluid's outputs (doubles, whose
/// low bytes hardly repeat) the default spent 3.6–5.4 times the CPU for a file 3.5 % smaller
/// (`cube-mobile-walls` on 50³, profiles of two runs; its output at t = 0.1 s 3.20 against
/// 3.31 MB, 2026-12-06).
/// The decoded arrays are the same at any level.
fn compress_into(raw: &[u8], out: &mut Vec<u8>) {
    use rayon::prelude::*;
    let deflate = |block: &[u8]| {
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::fast());
        z.write_all(block).expect("writing to a Vec cannot fail");
        z.finish().expect("writing to a Vec cannot fail")
    };
    let blocks: Vec<Vec<u8>> = if rayon::current_thread_index().is_some() {
        raw.par_chunks(BLOCK_SIZE).map(deflate).collect()
    } else {
        raw.chunks(BLOCK_SIZE).map(deflate).collect()
    };
    let last = raw.len() % BLOCK_SIZE;
    let mut header = vec![blocks.len() as u64, BLOCK_SIZE as u64, last as u64];
    header.extend(blocks.iter().map(|b| b.len() as u64));
    for h in header {
        out.extend_from_slice(&h.to_le_bytes());
    }
    for b in blocks {
        out.extend_from_slice(&b);
    }
}

fn check_tuples(array: &DataArray, n: usize, what: &str) {
    assert!(
        array.components > 0 && array.values.len() == n * array.components,
        "array {} has {} values, expected {n} {what}s x {} components",
        array.name,
        array.values.len(),
        array.components
    );
}

fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('"', "&quot;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}
