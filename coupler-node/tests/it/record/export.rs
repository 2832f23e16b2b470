//! MCAP record, exports: the tidy table of `inspect --export csv` and the diagnostics schema.

use super::*;

/// Issue 15, item 6: `inspect --export csv` is one tidy table, one row per number, that reads
/// back in Rust (and with numpy's `genfromtxt(names=True)` where numpy is installed).
#[test]
fn the_tidy_table_has_one_row_per_number_and_reads_back() {
    let (bytes, _, _) = record_run(3, RecordLevel::Exchange);
    let rec = read_recording(&bytes).unwrap();
    let csv = export_table(&rec, None).unwrap();
    assert_eq!(csv.lines().next(), Some(TABLE_HEADER));
    type Row = (u64, u32, String, String, u64, f64);
    // (A row of another length or a field of another type fails, naming its line.)
    let rows: Vec<Row> = csv::Reader::from_reader(csv.as_bytes())
        .deserialize()
        .collect::<Result<_, _>>()
        .unwrap_or_else(|e| panic!("{e}"));
    let pick = |step: u64, iteration: u32, channel: &str, field: &str| -> Vec<f64> {
        rows.iter()
            .filter(|r| r.0 == step && r.1 == iteration && r.2 == channel && r.3 == field)
            .map(|r| r.5)
            .collect()
    };
    // The loads of step 2, iteration 1: force[i] = 0.5 i + step, 12 numbers, exact.
    let force = pick(2, 1, "/fluid-to-coupler", "force");
    assert_eq!(force.len(), 12);
    for (i, f) in force.iter().enumerate() {
        assert!(
            (f - (0.5 * i as f64 + 2.0)).abs() <= 1e-15,
            "force[{i}] = {f}"
        );
    }
    // Diagnostics: residuals and the ledger, iteration 0.
    assert_eq!(pick(1, 0, "/diagnostics", "residuals"), [1e-3, 1e-9]);
    assert_eq!(pick(1, 0, "/diagnostics", "ledger.fluid_mass"), [1.5]);
    assert_eq!(pick(1, 0, "/diagnostics", "ledger.step"), [1.0]);
    assert_eq!(pick(1, 0, "/diagnostics", "converged"), [1.0]);
    // Every frame and diagnostics message contributes its stamp / step.
    assert_eq!(
        rows.iter().filter(|r| r.3 == "stamp.step").count() + rec.topic(DIAGNOSTICS_TOPIC).count(),
        rec.messages.len()
    );
    // Checkpoint bytes (a placeholder string) and strings are not rows.
    assert!(rows.iter().all(|r| r.3 != "bytes" && r.3 != "sender"));
    // One step only, and a step that is not there.
    let one = export_table(&rec, Some(1)).unwrap();
    assert!(one.lines().skip(1).all(|l| l.starts_with("1,")), "{one}");
    let err = export_table(&rec, Some(7)).unwrap_err().to_string();
    assert!(err.contains("step 7") && err.contains("0 to 2"), "{err}");

    // numpy, when the Python of the tests has it (COSIM_PYTHON; numpy is not required).
    let Ok(python) = std::env::var("COSIM_PYTHON") else {
        eprintln!("COSIM_PYTHON unset: numpy check not run");
        return;
    };
    let has_numpy = std::process::Command::new(&python)
        .args(["-c", "import numpy"])
        .status()
        .is_ok_and(|s| s.success());
    if !has_numpy {
        eprintln!("{python} has no numpy: numpy check not run");
        return;
    }
    let path = std::env::temp_dir().join(format!("cosim-table-{}.csv", std::process::id()));
    std::fs::write(&path, &csv).unwrap();
    let script = "import sys, numpy as np\n\
        a = np.genfromtxt(sys.argv[1], delimiter=',', names=True, dtype=None, encoding='utf-8')\n\
        m = (a['step'] == 2) & (a['iteration'] == 1) & (a['channel'] == '/fluid-to-coupler') & (a['field'] == 'force')\n\
        print(len(a), repr(float(a['value'][m].sum())))\n";
    let out = std::process::Command::new(&python)
        .arg("-c")
        .arg(script)
        .arg(&path)
        .output()
        .unwrap();
    let _ = std::fs::remove_file(&path);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    let mut it = text.split_whitespace();
    assert_eq!(it.next(), Some(rows.len().to_string().as_str()), "{text}");
    let sum: f64 = it.next().unwrap().parse().unwrap();
    // Σ (0.5 i + 2), i < 12 = 33 + 24.
    assert!((sum - 57.0).abs() <= 1e-12, "{text}");
}

/// Issue 15, item 5: the diagnostics schema is derived from the type: every key of a fully
/// filled diagnostics object, nested ones included, is a property of the schema at its level,
/// and the nested types are inlined (Foxglove resolves no `$ref`).
#[test]
fn the_diagnostics_schema_names_every_field_written() {
    let schema: serde_json::Value = serde_json::from_str(&diagnostics_schema()).unwrap();
    assert_eq!(schema["title"], "cosim.Diagnostics");
    assert!(!diagnostics_schema().contains("$ref"), "{schema:#}");
    let full = Diagnostics {
        output: Some(3),
        ledger: Some(LedgerEntry::default()),
        ..Diagnostics::default()
    };
    let value = serde_json::to_value(&full).unwrap();
    fn check(value: &serde_json::Value, schema: &serde_json::Value, path: &str, n: &mut usize) {
        let Some(object) = value.as_object() else {
            return;
        };
        // An optional struct is `anyOf: [{object}, {null}]` (or a type list).
        let props = schema.get("properties").or_else(|| {
            schema["anyOf"]
                .as_array()
                .and_then(|a| a.iter().find_map(|s| s.get("properties")))
        });
        let props = props.unwrap_or_else(|| panic!("{path}: no properties in {schema:#}"));
        for (key, v) in object {
            let sub = props
                .get(key)
                .unwrap_or_else(|| panic!("{path}.{key} is written but not in the schema"));
            *n += 1;
            check(v, sub, &format!("{path}.{key}"), n);
        }
    }
    let mut n = 0;
    check(&value, &schema, "", &mut n);
    // 15 top-level fields, 16 of the ledger entry, 3 busy seconds.
    assert_eq!(n, 15 + 16 + 3, "{value:#}");
}

/// A reader that hands out at most `piece` bytes a call (a file read in pieces of any size).
struct Pieces<'a> {
    bytes: &'a [u8],
    piece: usize,
}

impl std::io::Read for Pieces<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.piece.min(buf.len()).min(self.bytes.len());
        buf[..n].copy_from_slice(&self.bytes[..n]);
        self.bytes = &self.bytes[n..];
        Ok(n)
    }
}

/// The streamed table of `bytes` read in pieces of `piece` bytes, and its summary.
fn streamed(bytes: &[u8], piece: usize, filter: &TableFilter) -> (String, TableSummary) {
    let mut out = Vec::new();
    let summary = stream_table(Pieces { bytes, piece }, filter, &mut out).unwrap();
    (String::from_utf8(out).unwrap(), summary)
}

/// Issue 39, item 5: `inspect --export csv` streams: the same table, byte for byte, whatever
/// the pieces the file is read in, for a finished record, a killed run's (after each step) and
/// a file cut inside a record; the filters keep exactly the rows of their steps and channels.
#[test]
fn the_streamed_table_is_the_table_read_in_any_pieces() {
    let (bytes, _, snapshots) = record_run_with_snapshots(4, RecordLevel::Exchange);
    let rec = read_recording(&bytes).unwrap();
    let whole = export_table(&rec, None).unwrap();
    for piece in [1, 7, 4096, bytes.len()] {
        let (table, summary) = streamed(&bytes, piece, &TableFilter::default());
        assert!(table == whole, "pieces of {piece} bytes");
        assert_eq!(
            summary.end,
            End::Finished {
                summary_damage: None
            }
        );
        assert_eq!(summary.steps, Some((0, 3)));
        assert_eq!(summary.messages, rec.messages.len());
    }
    // Killed after each step (the recorder's provisional end), and cut inside the next record.
    for snapshot in &snapshots {
        let killed = read_recording(snapshot).unwrap();
        let (table, summary) = streamed(snapshot, 1000, &TableFilter::default());
        assert!(table == export_table(&killed, None).unwrap());
        assert_eq!(summary.end, End::Unfinished);
        let cut = &snapshot[..snapshot.len() - PROVISIONAL_END.len() - 5];
        let cut_rec = read_recording(cut).unwrap();
        let (table, summary) = streamed(cut, 333, &TableFilter::default());
        assert!(table == export_table(&cut_rec, None).unwrap());
        assert!(
            matches!(summary.end, End::CutShort { .. }),
            "{:?}",
            summary.end
        );
    }
    // Filters: steps 1 to 2 of one channel are exactly those rows of the whole table.
    let filter = TableFilter {
        steps: 1..=2,
        channels: vec!["/fluid-to-coupler".into()],
    };
    let (table, summary) = streamed(&bytes, 4096, &filter);
    let expected: Vec<&str> = whole
        .lines()
        .filter(|l| {
            let c: Vec<&str> = l.splitn(4, ',').collect();
            c[0] == "step" || ((c[0] == "1" || c[0] == "2") && c[2] == "/fluid-to-coupler")
        })
        .collect();
    assert_eq!(table.lines().collect::<Vec<_>>(), expected);
    assert!(expected.len() > 1 && summary.messages > 0);
    assert_eq!(summary.steps, Some((0, 3)));
}

/// An uncompressed record of `n_steps` steps, each with a fluid checkpoint of `cp_bytes` bytes.
fn record_with_checkpoints(n_steps: u64, cp_bytes: usize) -> Vec<u8> {
    let mut rec = Recorder::new(
        Cursor::new(Vec::new()),
        RecordLevel::Exchange,
        RecordCompression::None,
        "unit-scene",
        SCENE,
    )
    .unwrap();
    for step in 0..n_steps {
        record_step(&mut rec, step);
        let cp = Message::Checkpoint(Checkpoint {
            stamp: Stamp::step(step),
            node: NodeKind::Fluid,
            bytes: vec![step as u8; cp_bytes],
        });
        let frame = codec::encode(NodeKind::Fluid, &cp);
        rec.record_checkpoint(NodeKind::Fluid, step_start(step), 0, &frame)
            .unwrap();
        rec.end_step().unwrap();
    }
    rec.finish().unwrap().into_inner()
}

/// Issue 39, item 5: the streamed export holds the same heap whatever the record's size, a few
/// times its largest message: a checkpoint's bytes never become JSON numbers (2 MB of bytes held
/// 64 MB as a `serde_json::Value` array, the 105 MB peak of `inspect --export csv` on the
/// 310 MB record of `clamped-beam-2d`).
#[test]
fn the_streamed_export_holds_the_same_memory_whatever_the_record_size() {
    let cp = 2 << 20;
    let peak = |n_steps: u64| {
        let bytes = record_with_checkpoints(n_steps, cp);
        let (summary, peak) = crate::peak::peak_of(|| {
            stream_table(&bytes[..], &TableFilter::default(), &mut std::io::sink()).unwrap()
        });
        assert_eq!(summary.steps, Some((0, n_steps - 1)));
        (bytes.len(), peak)
    };
    let (small_len, small) = peak(3);
    let (big_len, big) = peak(12);
    assert!(big_len > 3 * small_len);
    // Measured: 9.5 MB for the 6.3 MB and the 25 MB record (the 1 MiB read buffer, the
    // record's bytes and the chunk read from them, the message and its decoded frame); 76.6 MB
    // for both before the checkpoint's bytes were kept out of JSON.
    assert!(
        big <= 8 * cp,
        "{big} bytes held for a record of {big_len} bytes (largest message {cp} bytes)"
    );
    assert!(
        big.abs_diff(small) <= cp / 2,
        "{small} bytes held for {small_len} record bytes, {big} for {big_len}"
    );
    // The checkpoint shows as its length in the JSON export.
    let rec = read_recording(&record_with_checkpoints(1, 10)).unwrap();
    let json = export_step(&rec, 0, ExportFormat::Json).unwrap();
    assert!(json.contains("\"bytes\": \"<10 bytes>\""), "{json}");
}
