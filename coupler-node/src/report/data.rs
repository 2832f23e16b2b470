//! What the figures plot, read from a run's outputs: numeric CSV tables and the energy history
//! of the record's diagnostics. Pure functions of their inputs.

use serde_json::Value;

use crate::report::error::ReportError;

/// A numeric CSV table (header line, then numbers).
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    /// Column names.
    pub header: Vec<String>,
    /// Rows, each as long as the header.
    pub rows: Vec<Vec<f64>>,
}

impl Table {
    /// Parses `text` (`what` names it in errors): a header line, then rows of numbers as long
    /// as the header. Fields are trimmed; quoted fields, CRLF line ends and empty lines are
    /// read as CSV has them.
    pub fn parse(text: &str, what: &str) -> Result<Table, ReportError> {
        let csv_error = |source| ReportError::Csv {
            what: what.into(),
            source,
        };
        let mut reader = csv::ReaderBuilder::new()
            .trim(csv::Trim::All)
            .from_reader(text.as_bytes());
        let header: Vec<String> = reader
            .headers()
            .map_err(csv_error)?
            .iter()
            .map(str::to_string)
            .collect();
        if header.is_empty() {
            return Err(ReportError::Empty { what: what.into() });
        }
        let mut rows = Vec::new();
        for record in reader.records() {
            let record = record.map_err(|source| match source.kind() {
                csv::ErrorKind::UnequalLengths { pos, len, .. } => ReportError::RowLength {
                    what: what.into(),
                    line: pos.as_ref().map_or(0, |p| line_at(text, p.byte())),
                    values: *len as usize,
                    columns: header.len(),
                },
                _ => csv_error(source),
            })?;
            let line = record.position().map_or(0, |p| line_at(text, p.byte()));
            let row = record
                .iter()
                .zip(&header)
                .map(|(value, column)| {
                    value.parse::<f64>().map_err(|source| ReportError::Number {
                        what: what.into(),
                        line,
                        column: column.clone(),
                        value: value.to_string(),
                        source,
                    })
                })
                .collect::<Result<_, _>>()?;
            rows.push(row);
        }
        Ok(Table { header, rows })
    }

    /// Index of column `name`.
    pub fn column(&self, name: &str) -> Option<usize> {
        self.header.iter().position(|h| h == name)
    }

    /// The pairs (column `x`, column `y`), if both exist.
    pub fn pairs(&self, x: &str, y: &str) -> Option<Vec<(f64, f64)>> {
        let (i, j) = (self.column(x)?, self.column(y)?);
        Some(self.rows.iter().map(|r| (r[i], r[j])).collect())
    }
}

/// The line (from 1) of `text` on which the CSV record found at `byte` starts.
// NOTE: the `csv` reader (1.4) takes a record's position before the empty lines and the line
// end it skips, so its line is short by those (by one for every row of a CRLF file); its byte
// offset is right, and the line is counted from it.
fn line_at(text: &str, byte: u64) -> u64 {
    let (before, after) = text.as_bytes().split_at((byte as usize).min(text.len()));
    let newlines = |bytes: &[u8]| bytes.iter().filter(|b| **b == b'\n').count() as u64;
    let skipped = after.iter().take_while(|b| matches!(b, b'\r' | b'\n'));
    newlines(before) + skipped.filter(|b| **b == b'\n').count() as u64 + 1
}

/// One step's energy balance from the diagnostics.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EnergyPoint {
    /// Time at the end of the step \[s\].
    pub t: f64,
    /// |E(t) − E(0)| \[J\].
    pub error: f64,
    /// Largest |interface work| so far \[J\].
    pub exchange: f64,
}

/// The energy history of a run from its diagnostics objects (one JSON object per step, as
/// the record's `diagnostics` channel holds them).
pub fn energy_history<'a>(
    diagnostics: impl IntoIterator<Item = &'a [u8]>,
) -> Result<Vec<EnergyPoint>, ReportError> {
    let mut out = Vec::new();
    let mut exchange: f64 = 0.0;
    for (i, json) in diagnostics.into_iter().enumerate() {
        let v: Value = serde_json::from_slice(json)
            .map_err(|source| ReportError::Json { index: i, source })?;
        let num = |path: &[&str]| -> Result<f64, ReportError> {
            path.iter()
                .try_fold(&v, |v, k| v.get(k))
                .and_then(Value::as_f64)
                .ok_or_else(|| ReportError::Missing {
                    index: i,
                    path: path.join("."),
                })
        };
        let t = num(&["t"])?;
        exchange = exchange
            .max(num(&["ledger", "work_fluid"])?.abs())
            .max(num(&["ledger", "work_solid"])?.abs());
        // The ledger's error relative to the largest exchange so far, times that exchange.
        let error = num(&["ledger", "energy_err_vs_exchange"])? * exchange;
        out.push(EnergyPoint { t, error, exchange });
    }
    Ok(out)
}

/// The energy error against time as paper 003 plots it (Fig. 7): |E(t) − E(0)| over the
/// largest energy exchanged in the whole run, times `scale`.
pub fn relative_energy_error(history: &[EnergyPoint], scale: f64) -> Vec<(f64, f64)> {
    let max = history.iter().map(|p| p.exchange).fold(0.0, f64::max);
    history
        .iter()
        .map(|p| {
            (
                p.t,
                if max > 0.0 {
                    scale * p.error / max
                } else {
                    0.0
                },
            )
        })
        .collect()
}

/// Normal stress against the azimuthal angle about the particles' centroid (paper 003
/// Fig. 15): `(θ in degrees, σ_n)` sorted by θ ∈ (−180, 180].
pub fn stress_by_angle(solid: &Table) -> Option<Vec<(f64, f64)>> {
    let (x, y, s) = (
        solid.column("x")?,
        solid.column("y")?,
        solid.column("sigma_n")?,
    );
    let n = solid.rows.len() as f64;
    if n == 0.0 {
        return None;
    }
    let cx = solid.rows.iter().map(|r| r[x]).sum::<f64>() / n;
    let cy = solid.rows.iter().map(|r| r[y]).sum::<f64>() / n;
    let mut pts: Vec<(f64, f64)> = solid
        .rows
        .iter()
        .map(|r| ((r[y] - cy).atan2(r[x] - cx).to_degrees(), r[s]))
        .collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    Some(pts)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tables_parse_and_refuse_ragged_rows() {
        let t = Table::parse("t,x\n0,1\n0.5,2e0\n", "probe").expect("parses");
        assert_eq!(t.pairs("t", "x"), Some(vec![(0.0, 1.0), (0.5, 2.0)]));
        assert_eq!(t.pairs("t", "y"), None);
        let err = Table::parse("t,x\n0,1,2\n", "probe")
            .expect_err("ragged")
            .to_string();
        assert_eq!(err, "probe: line 2 has 3 values, the header 2");
        let err = Table::parse("t,x\n0,1\n\n1,2\n2\n", "probe")
            .expect_err("short")
            .to_string();
        assert_eq!(err, "probe: line 5 has 1 values, the header 2");
        let err = Table::parse("t,x\n0,1\n0.5,abc\n", "probe")
            .expect_err("not a number")
            .to_string();
        assert_eq!(
            err,
            "probe: line 3, column x: \"abc\" is not a number (invalid float literal)"
        );
        let err = Table::parse("", "probe").expect_err("empty").to_string();
        assert_eq!(err, "probe: empty");
    }

    #[test]
    fn tables_read_quoted_fields_crlf_and_padded_numbers() {
        let text = "\"t\", x\r\n0,\"1.5\"\r\n\r\n2e-3, -4 \r\n";
        let t = Table::parse(text, "probe").expect("parses");
        assert_eq!(t.header, ["t", "x"]);
        assert_eq!(t.rows, [[0.0, 1.5], [2e-3, -4.0]]);
        // The line of a bad row is counted past empty lines and CRLF line ends.
        let err = Table::parse(&format!("{text}\r\n5,x\r\n"), "probe")
            .expect_err("not a number")
            .to_string();
        assert!(err.starts_with("probe: line 6, column x: "), "{err}");
        let err = Table::parse(&format!("{text}\r\n\r\n5\r\n"), "probe")
            .expect_err("short")
            .to_string();
        assert_eq!(err, "probe: line 7 has 1 values, the header 2");
    }

    #[test]
    fn energy_error_is_normalised_by_the_largest_exchange_of_the_run() {
        // Errors 1, 2, 1 J; exchanges so far 10, 40, 40 J (the ledger's ratio is taken against
        // the exchange so far): relative to the run's largest exchange, 40 J.
        let steps = [(0.1, 10.0, 0.1), (0.2, 40.0, 0.05), (0.3, -20.0, 0.025)];
        let json: Vec<Vec<u8>> = steps
            .iter()
            .map(|(t, w, r)| {
                serde_json::to_vec(&serde_json::json!({
                    "t": t,
                    "ledger": {"work_fluid": w, "work_solid": -w, "energy_err_vs_exchange": r}
                }))
                .expect("json")
            })
            .collect();
        let h = energy_history(json.iter().map(Vec::as_slice)).expect("history");
        let rel = relative_energy_error(&h, 4.0);
        let want = [(0.1, 4.0 / 40.0), (0.2, 8.0 / 40.0), (0.3, 4.0 / 40.0)];
        for ((t, e), (wt, we)) in rel.iter().zip(want) {
            assert_eq!(*t, wt);
            assert!((e - we).abs() < 1e-15, "{e} vs {we}");
        }
        let bad = energy_history([b"{\"t\": 1}".as_slice()])
            .expect_err("no ledger")
            .to_string();
        assert!(bad.contains("ledger.work_fluid"), "{bad}");
    }

    #[test]
    fn stress_is_sorted_by_angle_about_the_centroid() {
        let t = Table::parse(
            "id,x,y,sigma_n\n0,1,0,5\n1,0,1,6\n2,-1,0,7\n3,0,-1,8\n",
            "solid",
        )
        .expect("parses");
        let s = stress_by_angle(&t).expect("columns");
        let angles: Vec<f64> = s.iter().map(|p| p.0).collect();
        assert_eq!(angles, [-90.0, 0.0, 90.0, 180.0]);
        assert_eq!(
            s.iter().map(|p| p.1).collect::<Vec<_>>(),
            [8.0, 5.0, 6.0, 7.0]
        );
    }
}
