//! `index.html`: one page with a run's summary and every figure `report figures` drew, in the
//! order a reader looks for them (the conservation ledger, the probes, the fields at each
//! output time). The figures are linked by their names, so the page goes into the folder they
//! are in. No script or style from elsewhere: the page opens from a file.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::report::field::escape;

/// The output times of a run, `(k, t)`, from its `outputs.csv`.
pub type Outputs = Vec<(String, f64)>;

/// Writes `out/index.html` for the run `name`, its `summary.json` text (if any), the figures
/// `written` (paths in `out`) and its output times; returns the page's path.
pub fn write_page(
    out: &Path,
    name: &str,
    summary: Option<&str>,
    written: &[PathBuf],
    outputs: &Outputs,
) -> std::io::Result<PathBuf> {
    let page = out.join("index.html");
    std::fs::write(&page, page_text(name, summary, written, outputs))?;
    Ok(page)
}

/// The page's HTML.
pub fn page_text(
    name: &str,
    summary: Option<&str>,
    written: &[PathBuf],
    outputs: &Outputs,
) -> String {
    let files: Vec<String> = written
        .iter()
        .filter_map(|p| p.file_name())
        .map(|n| n.to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".svg"))
        .collect();
    let mut s = String::new();
    let _ = write!(
        s,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <title>{0}: run report</title>\n<style>\n\
         body {{ font-family: sans-serif; margin: 2em; max-width: 1400px; }}\n\
         img {{ max-width: 100%; margin: 0.5em; border: 1px solid #ddd; }}\n\
         table {{ border-collapse: collapse; }} td, th {{ padding: 0.2em 0.8em; text-align: left; \
         border-bottom: 1px solid #eee; }}\n</style>\n</head>\n<body>\n<h1>{0}</h1>\n",
        escape(name)
    );
    s.push_str("<h2>Summary</h2>\n");
    match summary.and_then(|t| serde_json::from_str::<Value>(t).ok()) {
        Some(v) => summary_table(&mut s, &v),
        None => s.push_str("<p>No <code>summary.json</code> in the run's folder.</p>\n"),
    }
    let section = |s: &mut String, title: &str, names: &[&String]| {
        if names.is_empty() {
            return;
        }
        let _ = writeln!(s, "<h2>{title}</h2>");
        for n in names {
            let _ = writeln!(s, "<img src=\"{0}\" alt=\"{0}\">", escape(n));
        }
    };
    let of = |pred: &dyn Fn(&str) -> bool| -> Vec<&String> {
        files.iter().filter(|n| pred(n)).collect()
    };
    section(
        &mut s,
        "Conservation",
        &of(&|n| n.starts_with("ledger_") || n.starts_with("energy_error")),
    );
    section(&mut s, "Probes", &of(&|n| n.starts_with("probe")));
    section(&mut s, "Solid", &of(&|n| n.starts_with("solid_")));
    let fields = of(&|n| n.starts_with("field_"));
    if !fields.is_empty() {
        s.push_str("<h2>Fields</h2>\n");
        for (k, t) in outputs {
            let mine: Vec<&String> = fields
                .iter()
                .copied()
                .filter(|n| n.starts_with(&format!("field_{k}_")))
                .collect();
            if mine.is_empty() {
                continue;
            }
            let _ = writeln!(s, "<h3>Output {} (t = {t:e} s)</h3>", escape(k));
            for n in mine {
                let _ = writeln!(s, "<img src=\"{0}\" alt=\"{0}\">", escape(n));
            }
        }
    }
    // Marks each image with the width it loaded at: a headless browser's dump of the DOM then
    // shows which images did not load (naturalWidth 0).
    s.push_str(
        "<script>\nwindow.addEventListener('load', function () {\n  \
         for (const img of document.images) { img.dataset.naturalWidth = img.naturalWidth; }\n  \
         document.body.dataset.loaded = 'yes';\n});\n</script>\n</body>\n</html>\n",
    );
    s
}

/// The summary's fields as a table (objects one level deep as `key.sub`).
fn summary_table(s: &mut String, v: &Value) {
    s.push_str("<table>\n");
    let mut row = |key: &str, value: &Value| {
        let text = match value {
            Value::String(t) => t.clone(),
            other => other.to_string(),
        };
        let _ = writeln!(
            s,
            "<tr><th>{}</th><td>{}</td></tr>",
            escape(key),
            escape(&text)
        );
    };
    if let Value::Object(map) = v {
        for (key, value) in map {
            match value {
                Value::Object(inner) => {
                    for (sub, value) in inner {
                        row(&format!("{key}.{sub}"), value);
                    }
                }
                other => row(key, other),
            }
        }
    }
    s.push_str("</table>\n");
}
