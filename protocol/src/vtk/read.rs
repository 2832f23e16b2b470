//! Decoding what [`super::image_data`] and [`super::poly_data`] write: the XML head, each
//! array's compression header and zlib blocks, and `.pvd` series. Every size is checked against
//! the bytes there are.

use std::collections::BTreeMap;

use super::write::Values;

/// A file that is not what this module reads, or is damaged.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct VtkReadError(pub String);

/// A decoded `.vti` or `.vtp` file.
#[derive(Clone, Debug, PartialEq)]
pub struct VtkFile {
    /// `ImageData` or `PolyData`.
    pub kind: String,
    /// Attributes of the dataset element (`WholeExtent`, `Origin`, `Spacing` for image data).
    pub dataset: BTreeMap<String, String>,
    /// Attributes of the one `Piece` (`NumberOfPoints`, `NumberOfLines`, ...).
    pub piece: BTreeMap<String, String>,
    /// Every data array, in file order.
    pub arrays: Vec<Array>,
}

/// One decoded data array.
#[derive(Clone, Debug, PartialEq)]
pub struct Array {
    /// The element that holds it: `CellData`, `PointData`, `Points`, `Verts`, `Lines`, `Polys`.
    pub section: String,
    /// Its `Name`.
    pub name: String,
    /// `NumberOfComponents`.
    pub components: usize,
    /// The values.
    pub values: Values,
}

impl Array {
    /// The values if they are `Float64`.
    pub fn as_f64(&self) -> Option<&[f64]> {
        match &self.values {
            Values::Float64(v) => Some(v),
            _ => None,
        }
    }

    /// The values if they are `Int64`.
    pub fn as_i64(&self) -> Option<&[i64]> {
        match &self.values {
            Values::Int64(v) => Some(v),
            _ => None,
        }
    }
}

impl VtkFile {
    /// The array `name` of `section`.
    pub fn array(&self, section: &str, name: &str) -> Option<&Array> {
        self.arrays
            .iter()
            .find(|a| a.section == section && a.name == name)
    }
}

/// Decodes a `.vti` or `.vtp` file with zlib-compressed arrays appended raw.
pub fn parse(bytes: &[u8]) -> Result<VtkFile, VtkReadError> {
    parse_some(bytes, |_, _| true)
}

/// [`parse`], decoding only the arrays for which `wanted(section, name)` holds: the others are
/// neither inflated nor listed in [`VtkFile::arrays`], and their damage goes unnoticed. The
/// record's views read three of the five arrays of a fluid file (issue 39 item 4: inflating the
/// rest was a sixth of the record thread's time on `clamped-beam-2d`).
pub fn parse_some(
    bytes: &[u8],
    wanted: impl Fn(&str, &str) -> bool,
) -> Result<VtkFile, VtkReadError> {
    let err = |m: String| VtkReadError(m);
    let marker = b"<AppendedData encoding=\"raw\">";
    let head_end = find(bytes, marker)
        .ok_or_else(|| err("no <AppendedData encoding=\"raw\"> element".into()))?;
    let underscore = find(&bytes[head_end..], b"_")
        .ok_or_else(|| err("no '_' opening the appended data".into()))?;
    let data = &bytes[head_end + underscore + 1..];
    let head = std::str::from_utf8(&bytes[..head_end])
        .map_err(|e| err(format!("the XML head is not UTF-8: {e}")))?;
    let mut file = VtkFile {
        kind: String::new(),
        dataset: BTreeMap::new(),
        piece: BTreeMap::new(),
        arrays: Vec::new(),
    };
    let mut section = String::new();
    let mut rest = head;
    while let Some(open) = rest.find('<') {
        let close = rest[open..]
            .find('>')
            .ok_or_else(|| err("an unclosed tag".into()))?;
        let tag = &rest[open + 1..open + close];
        rest = &rest[open + close + 1..];
        if tag.starts_with('?') || tag.starts_with('!') {
            continue;
        }
        if let Some(name) = tag.strip_prefix('/') {
            if name == section {
                section.clear();
            }
            continue;
        }
        let (name, attrs) = tag_attributes(tag.trim_end_matches('/'))?;
        match name.as_str() {
            "VTKFile" => {
                for (key, want) in [
                    ("byte_order", "LittleEndian"),
                    ("header_type", "UInt64"),
                    ("compressor", "vtkZLibDataCompressor"),
                ] {
                    let got = attrs.get(key).map_or("none", String::as_str);
                    if got != want {
                        return Err(err(format!("VTKFile {key} is {got}, expected {want}")));
                    }
                }
                file.kind = attrs.get("type").cloned().unwrap_or_default();
            }
            "ImageData" | "PolyData" => file.dataset = attrs,
            "Piece" => file.piece = attrs,
            "CellData" | "PointData" | "Points" | "Verts" | "Lines" | "Polys" | "Strips" => {
                section = name;
            }
            "DataArray" => {
                let name = attrs.get("Name").map_or("", String::as_str);
                if wanted(&section, name) {
                    file.arrays.push(decode_array(&attrs, &section, data)?);
                }
            }
            _ => {}
        }
    }
    if file.kind.is_empty() {
        return Err(err("no VTKFile element with a type".into()));
    }
    Ok(file)
}

/// The `(timestep, file)` entries of a `.pvd` collection, in file order.
pub fn pvd(text: &str) -> Result<Vec<(f64, String)>, VtkReadError> {
    if !text.contains("<VTKFile type=\"Collection\"") {
        return Err(VtkReadError("not a VTK collection (.pvd)".into()));
    }
    let mut entries = Vec::new();
    let mut rest = text;
    while let Some(open) = rest.find("<DataSet ") {
        let close = rest[open..]
            .find("/>")
            .ok_or_else(|| VtkReadError("an unclosed DataSet".into()))?;
        let (_, attrs) = tag_attributes(&rest[open + 1..open + close])?;
        rest = &rest[open + close..];
        let t = attrs
            .get("timestep")
            .and_then(|t| t.parse::<f64>().ok())
            .ok_or_else(|| VtkReadError("a DataSet without a numeric timestep".into()))?;
        let file = attrs
            .get("file")
            .ok_or_else(|| VtkReadError("a DataSet without a file".into()))?;
        entries.push((t, file.clone()));
    }
    Ok(entries)
}

fn decode_array(
    attrs: &BTreeMap<String, String>,
    section: &str,
    data: &[u8],
) -> Result<Array, VtkReadError> {
    let err = |m: String| VtkReadError(m);
    let name = attrs.get("Name").cloned().unwrap_or_default();
    let get = |key: &str| {
        attrs
            .get(key)
            .ok_or_else(|| err(format!("DataArray {name:?} has no {key}")))
    };
    if get("format")? != "appended" {
        return Err(err(format!("DataArray {name:?} is not appended")));
    }
    let number = |key: &str| -> Result<usize, VtkReadError> {
        let v = get(key)?;
        v.parse()
            .map_err(|_| err(format!("DataArray {name:?}: {key} {v:?} is not a count")))
    };
    let offset = number("offset")?;
    let components = number("NumberOfComponents")?;
    let raw = decompress(data, offset).map_err(|m| err(format!("DataArray {name:?}: {m}")))?;
    let ty = get("type")?.as_str();
    let width = match ty {
        "Float64" | "Int64" => 8,
        "Int32" => 4,
        "UInt8" => 1,
        other => return Err(err(format!("DataArray {name:?}: type {other} is not read"))),
    };
    if raw.len() % width != 0 || components == 0 || (raw.len() / width) % components != 0 {
        return Err(err(format!(
            "DataArray {name:?}: {} bytes are not whole {components}-component {ty} tuples",
            raw.len()
        )));
    }
    let values = match ty {
        "Float64" => Values::Float64(
            raw.chunks_exact(8)
                .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
                .collect(),
        ),
        "Int64" => Values::Int64(
            raw.chunks_exact(8)
                .map(|c| i64::from_le_bytes(c.try_into().expect("8 bytes")))
                .collect(),
        ),
        "Int32" => Values::Int32(
            raw.chunks_exact(4)
                .map(|c| i32::from_le_bytes(c.try_into().expect("4 bytes")))
                .collect(),
        ),
        _ => Values::UInt8(raw),
    };
    Ok(Array {
        section: section.to_string(),
        name,
        components,
        values,
    })
}

/// The uncompressed bytes of the array whose compression header starts at `offset`.
fn decompress(data: &[u8], offset: usize) -> Result<Vec<u8>, String> {
    let word = |at: usize| -> Result<u64, String> {
        let bytes = data
            .get(at..at + 8)
            .ok_or_else(|| format!("the header word at byte {at} lies past the data"))?;
        Ok(u64::from_le_bytes(bytes.try_into().expect("8 bytes")))
    };
    let n_blocks = usize::try_from(word(offset)?).map_err(|e| e.to_string())?;
    let block_size = word(offset + 8)? as usize;
    let last = word(offset + 16)? as usize;
    if n_blocks > data.len() / 8 {
        return Err(format!(
            "{n_blocks} blocks cannot fit in {} bytes",
            data.len()
        ));
    }
    let mut at = offset + 24 + 8 * n_blocks;
    let mut out = Vec::new();
    for b in 0..n_blocks {
        let size = word(offset + 24 + 8 * b)? as usize;
        let block = data
            .get(at..at.saturating_add(size))
            .ok_or_else(|| format!("block {b} ({size} bytes at {at}) lies past the data"))?;
        at += size;
        let expected = if b + 1 == n_blocks && last != 0 {
            last
        } else {
            block_size
        };
        inflate_block(block, expected, &mut out).map_err(|e| format!("block {b}: {e}"))?;
    }
    Ok(out)
}

/// Inflates one zlib stream `block` onto the end of `out`, which must then have grown by
/// exactly `expected` bytes.
///
/// NOTE (issue 39 item 4): straight into `out`, sized once, instead of through a reader and a
/// buffer of its own per block: the Foxglove views inflate the arrays of every output on the
/// record's thread. A stream that would give more than `expected` bytes is found by inflating
/// into one byte more; one that claims more than deflate can give for its size (1032 bytes a
/// byte) is refused before anything is allocated.
fn inflate_block(block: &[u8], expected: usize, out: &mut Vec<u8>) -> Result<(), String> {
    if expected > block.len().saturating_mul(1032).saturating_add(64) {
        return Err(format!(
            "its header says {expected} bytes, more than its {} compressed bytes can hold",
            block.len()
        ));
    }
    let start = out.len();
    out.resize(start + expected + 1, 0);
    let mut z = flate2::Decompress::new(true);
    let status = z
        .decompress(block, &mut out[start..], flate2::FlushDecompress::Finish)
        .map_err(|e| e.to_string())?;
    let got = z.total_out() as usize;
    out.truncate(start + got.min(expected));
    match status {
        flate2::Status::StreamEnd if got == expected => Ok(()),
        flate2::Status::StreamEnd => {
            Err(format!("it holds {got} bytes, its header says {expected}"))
        }
        _ if got > expected => Err(format!(
            "it holds more than the {expected} bytes its header says"
        )),
        _ => Err(format!(
            "its stream ends early, after {got} of the {expected} bytes its header says"
        )),
    }
}

/// The name and attributes of a tag's text (without `<` and `>`).
fn tag_attributes(tag: &str) -> Result<(String, BTreeMap<String, String>), VtkReadError> {
    let tag = tag.trim();
    let (name, mut rest) = tag.split_once(char::is_whitespace).unwrap_or((tag, ""));
    let mut attrs = BTreeMap::new();
    loop {
        rest = rest.trim_start();
        if rest.is_empty() {
            break;
        }
        let (key, after) = rest
            .split_once("=\"")
            .ok_or_else(|| VtkReadError(format!("a malformed attribute in <{name} {rest}>")))?;
        let (value, after) = after
            .split_once('"')
            .ok_or_else(|| VtkReadError(format!("an unclosed attribute in <{name}>")))?;
        attrs.insert(key.trim().to_string(), unescape(value));
        rest = after;
    }
    Ok((name.to_string(), attrs))
}

fn unescape(text: &str) -> String {
    text.replace("&quot;", "\"")
        .replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&amp;", "&")
}

fn find(haystack: &[u8], needle: &[u8]) -> Option<usize> {
    haystack.windows(needle.len()).position(|w| w == needle)
}
