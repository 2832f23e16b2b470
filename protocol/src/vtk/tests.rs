//! Round trips of the VTK XML encoder through the decoder, the compression header checked by
//! hand, `.pvd` series, and damaged files refused.

use super::read::{self, VtkFile};
use super::*;

/// Values that exercise every bit pattern class: signs, subnormals, huge, tiny, non-round.
fn values(n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| match i % 5 {
            0 => (i as f64).sqrt() * 1e-3,
            1 => -(i as f64) * 1e300,
            2 => f64::MIN_POSITIVE / (i as f64 + 2.0),
            3 => 1.0 / 3.0 + i as f64,
            _ => -0.0,
        })
        .collect()
}

fn image(cells: [usize; 3]) -> ImageData {
    let n: usize = cells.iter().product();
    ImageData {
        cells,
        origin: [-0.5, 0.25, 1e-3],
        spacing: [0.1, 1.0 / 3.0, 2.0],
        cell_data: vec![
            DataArray::scalar("rho", Values::Float64(values(n))),
            DataArray::vector("velocity", values(3 * n)),
            DataArray::scalar(
                "flag",
                Values::UInt8((0..n).map(|i| (i % 3) as u8).collect()),
            ),
        ],
    }
}

fn same_bits(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
}

/// Where the appended data starts (after the `_`).
fn appended(bytes: &[u8]) -> &[u8] {
    let marker = b"<AppendedData encoding=\"raw\">";
    let at = bytes
        .windows(marker.len())
        .position(|w| w == marker)
        .expect("appended data");
    let underscore = bytes[at..].iter().position(|b| *b == b'_').expect("_");
    &bytes[at + underscore + 1..]
}

#[test]
fn image_data_round_trips_bit_for_bit() {
    // 1 cell, 4096 cells (rho exactly one full block: last = 0), 5000 (two blocks, last partial).
    for cells in [[1, 1, 1], [64, 64, 1], [10, 25, 20]] {
        let image = image(cells);
        let bytes = image_data(&image, "test -- with a double dash");
        let file: VtkFile = read::parse(&bytes).expect("parses");
        assert_eq!(file.kind, "ImageData");
        let extent = format!("0 {} 0 {} 0 {}", cells[0], cells[1], cells[2]);
        assert_eq!(file.dataset["WholeExtent"], extent);
        assert_eq!(file.piece["Extent"], extent);
        let parsed: Vec<f64> = file.dataset["Spacing"]
            .split(' ')
            .map(|s| s.parse().expect("number"))
            .collect();
        assert!(same_bits(&parsed, &image.spacing));
        assert_eq!(file.arrays.len(), 3);
        for (array, decoded) in image.cell_data.iter().zip(&file.arrays) {
            assert_eq!(decoded.section, "CellData");
            assert_eq!(decoded.name, array.name);
            assert_eq!(decoded.components, array.components);
            match (&array.values, &decoded.values) {
                (Values::Float64(a), Values::Float64(b)) => assert!(same_bits(a, b)),
                (a, b) => assert_eq!(a, b),
            }
        }
    }
}

#[test]
fn the_compression_header_is_vtks() {
    // 5000 doubles = 40000 bytes: a full block of 32768 and a last one of 7232.
    let image = ImageData {
        cells: [5000, 1, 1],
        origin: [0.0; 3],
        spacing: [1.0; 3],
        cell_data: vec![DataArray::scalar("x", Values::Float64(values(5000)))],
    };
    let bytes = image_data(&image, "");
    let data = appended(&bytes);
    let word = |i: usize| u64::from_le_bytes(data[8 * i..8 * i + 8].try_into().expect("8"));
    assert_eq!([word(0), word(1), word(2)], [2, 32768, 40000 - 32768]);
    let (c0, c1) = (word(3) as usize, word(4) as usize);
    let mut raw = Vec::new();
    for block in [&data[40..40 + c0], &data[40 + c0..40 + c0 + c1]] {
        std::io::Read::read_to_end(&mut flate2::read::ZlibDecoder::new(block), &mut raw)
            .expect("zlib");
    }
    let expected: Vec<u8> = values(5000).iter().flat_map(|x| x.to_le_bytes()).collect();
    assert_eq!(raw, expected);
    let head = String::from_utf8_lossy(&bytes[..200]);
    assert!(
        head.contains("header_type=\"UInt64\" compressor=\"vtkZLibDataCompressor\""),
        "{head}"
    );
}

#[test]
fn blocks_compressed_on_a_pool_give_the_bytes_of_one_thread() {
    // 10 x 25 x 20 cells: rho 40 000 bytes, velocity 120 000 (four blocks, the last partial).
    let image = image([10, 25, 20]);
    let alone = image_data(&image, "pool");
    for threads in [1, 2, 5] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        let on_pool = pool.install(|| image_data(&image, "pool"));
        assert!(on_pool == alone, "{threads} threads: the bytes differ");
    }
}

#[test]
fn poly_data_round_trips_with_point_and_cell_arrays() {
    for kind in [PolyCells::Lines, PolyCells::Polys] {
        let points = values(3 * 7);
        let (connectivity, offsets) = match kind {
            PolyCells::Lines => (vec![0, 1, 1, 2, 5, 6], vec![2, 4, 6]),
            _ => (vec![0, 1, 2, 2, 3, 4, 6], vec![3, 7, 7]),
        };
        let poly = PolyData {
            points: points.clone(),
            kind,
            connectivity: connectivity.clone(),
            offsets: offsets.clone(),
            point_data: vec![DataArray::scalar("id", Values::Int64((0..7).collect()))],
            cell_data: vec![
                DataArray::scalar("particle", Values::Int32(vec![4, -1, 9])),
                DataArray::vector("normal", values(9)),
            ],
        };
        let file = read::parse(&poly_data(&poly, "p")).expect("parses");
        assert_eq!(file.kind, "PolyData");
        assert_eq!(file.piece["NumberOfPoints"], "7");
        let tag = if kind == PolyCells::Lines {
            "Lines"
        } else {
            "Polys"
        };
        assert_eq!(file.piece[&format!("NumberOf{tag}")], "3");
        assert_eq!(file.piece["NumberOfVerts"], "0");
        assert!(same_bits(
            file.array("Points", "Points")
                .and_then(|a| a.as_f64())
                .expect("points"),
            &points
        ));
        assert_eq!(
            file.array(tag, "connectivity").and_then(|a| a.as_i64()),
            Some(&connectivity[..])
        );
        assert_eq!(
            file.array(tag, "offsets").and_then(|a| a.as_i64()),
            Some(&offsets[..])
        );
        assert_eq!(
            file.array("PointData", "id").map(|a| &a.values),
            Some(&Values::Int64((0..7).collect()))
        );
        assert_eq!(
            file.array("CellData", "particle").map(|a| &a.values),
            Some(&Values::Int32(vec![4, -1, 9]))
        );
        assert!(same_bits(
            file.array("CellData", "normal")
                .and_then(|a| a.as_f64())
                .expect("normal"),
            &values(9)
        ));
    }
}

#[test]
fn empty_poly_data_round_trips() {
    let file = read::parse(&poly_data(&PolyData::vertices(Vec::new()), "none")).expect("parses");
    assert_eq!(file.piece["NumberOfPoints"], "0");
    assert_eq!(
        file.array("Verts", "offsets").map(|a| a.values.len()),
        Some(0)
    );
}

#[test]
fn series_lists_each_output_once_in_order() {
    let mut series = Series::default();
    series.record(0, 0.0, "fluid_0.vti");
    series.record(2, 0.2, "fluid_2.vti");
    series.record(1, 0.1, "fluid_1.vti");
    // A rewritten output (the same k after a restore) replaces its entry.
    let text = series.record(1, 0.125, "fluid_1.vti");
    let entries = read::pvd(&text).expect("pvd");
    let expected = [
        (0.0_f64, "fluid_0.vti"),
        (0.125, "fluid_1.vti"),
        (0.2, "fluid_2.vti"),
    ];
    assert_eq!(entries.len(), expected.len());
    for ((t, file), (t0, file0)) in entries.iter().zip(expected) {
        assert_eq!((t.to_bits(), file.as_str()), (t0.to_bits(), file0));
    }
    // Times round-trip exactly through their text.
    let t = 0.1 + 0.2;
    let entries = read::pvd(&Series::default().record(0, t, "a&b.vti")).expect("pvd");
    assert_eq!(
        (entries[0].0.to_bits(), entries[0].1.as_str()),
        (t.to_bits(), "a&b.vti")
    );
}

#[test]
fn damaged_files_are_refused_with_the_reason() {
    let bytes = image_data(&image([10, 25, 20]), "");
    let truncated = &bytes[..bytes.len() - 2000];
    let err = read::parse(truncated).expect_err("truncated");
    assert!(err.to_string().contains("lies past the data"), "{err}");
    let data_at = bytes.len() - appended(&bytes).len();
    let mut flipped = bytes.clone();
    flipped[data_at + 60] ^= 0xff;
    let err = read::parse(&flipped).expect_err("flipped");
    assert!(err.to_string().contains("DataArray \"rho\""), "{err}");
    let other = String::from_utf8_lossy(&bytes[..data_at])
        .replace("UInt64", "UInt32")
        .into_bytes();
    let err = read::parse(&other).expect_err("header type");
    assert!(
        err.to_string()
            .contains("header_type is UInt32, expected UInt64"),
        "{err}"
    );
}

/// `parse_some` decodes the arrays asked for, bit for bit as `parse` does, and skips the others
/// without inflating them: damage in a skipped array goes unseen, in a wanted one it is refused.
#[test]
fn parse_some_decodes_only_the_arrays_asked_for() {
    let bytes = image_data(&image([10, 25, 20]), "");
    let whole = read::parse(&bytes).expect("parses");
    let some = read::parse_some(&bytes, |section, name| {
        section == "CellData" && (name == "rho" || name == "flag")
    })
    .expect("parses");
    assert_eq!((&some.dataset, &some.piece), (&whole.dataset, &whole.piece));
    let names: Vec<&str> = some.arrays.iter().map(|a| a.name.as_str()).collect();
    assert_eq!(names, ["rho", "flag"]);
    assert_eq!(some.arrays[0], *whole.array("CellData", "rho").unwrap());
    assert_eq!(some.arrays[1], *whole.array("CellData", "flag").unwrap());
    // Damage the velocity's blocks (the second array): skipped, it is not read.
    let data_at = bytes.len() - appended(&bytes).len();
    let velocity_at: usize = String::from_utf8_lossy(&bytes[..data_at])
        .split("Name=\"velocity\"")
        .nth(1)
        .and_then(|rest| rest.split("offset=\"").nth(1))
        .and_then(|rest| rest.split('"').next())
        .expect("the velocity's offset")
        .parse()
        .expect("a number");
    let mut damaged = bytes.clone();
    damaged[data_at + velocity_at + 100] ^= 0xff;
    let err = read::parse(&damaged).expect_err("damaged velocity");
    assert!(err.to_string().contains("DataArray \"velocity\""), "{err}");
    let some_again = read::parse_some(&damaged, |_, name| name == "rho").expect("velocity skipped");
    assert_eq!(some_again.arrays, some.arrays[..1]);
}

/// A block whose stream gives more or fewer bytes than the array's header says, or whose header
/// claims more than its compressed bytes can hold, is refused with the block and the reason
/// (`rho`, the first array: two blocks of 32 768 and 7 232 bytes).
#[test]
fn a_block_that_disagrees_with_its_header_is_refused() {
    let bytes = image_data(&image([10, 25, 20]), "");
    let data_at = bytes.len() - appended(&bytes).len();
    let word = |b: &[u8], i: usize| {
        u64::from_le_bytes(b[data_at + 8 * i..data_at + 8 * i + 8].try_into().unwrap())
    };
    assert_eq!(
        [word(&bytes, 0), word(&bytes, 1), word(&bytes, 2)],
        [2, 32_768, 7_232]
    );
    let with = |i: usize, value: u64| {
        let mut b = bytes.clone();
        b[data_at + 8 * i..data_at + 8 * i + 8].copy_from_slice(&value.to_le_bytes());
        read::parse(&b)
            .expect_err("a header that disagrees")
            .to_string()
    };
    let refused = [
        (
            with(2, 7_231),
            "block 1: it holds 7232 bytes, its header says 7231",
        ),
        (
            with(2, 100),
            "block 1: it holds more than the 100 bytes its header says",
        ),
        (
            with(2, 7_233),
            "block 1: it holds 7232 bytes, its header says 7233",
        ),
        (
            with(1, 1 << 40),
            "block 0: its header says 1099511627776 bytes, more than",
        ),
        (with(3, word(&bytes, 3) - 10), "block 0: "),
    ];
    for (err, reason) in refused {
        assert!(
            err.contains("DataArray \"rho\"") && err.contains(reason),
            "{err}"
        );
    }
}
