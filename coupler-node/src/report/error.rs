//! Why a figure could not be made from a run's outputs.

use std::path::PathBuf;

/// Why reading a run's numbers or drawing them failed.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// A CSV table without a header line.
    #[error("{what}: empty")]
    Empty {
        /// The table (its file).
        what: String,
    },
    /// A value of a CSV table that is not a number.
    #[error("{what}: line {line}, column {column}: {value:?} is not a number ({source})")]
    Number {
        /// The table.
        what: String,
        /// Line of the file, from 1.
        line: u64,
        /// The column's name (header).
        column: String,
        /// The value as the file has it (trimmed).
        value: String,
        /// The parser's error.
        source: std::num::ParseFloatError,
    },
    /// A CSV row of another length than the header.
    #[error("{what}: line {line} has {values} values, the header {columns}")]
    RowLength {
        /// The table.
        what: String,
        /// Line of the file, from 1.
        line: u64,
        /// Values in the row.
        values: usize,
        /// Columns of the header.
        columns: usize,
    },
    /// A CSV table that could not be read as CSV (not UTF-8, say); the error names the line.
    #[error("{what}: {source}")]
    Csv {
        /// The table.
        what: String,
        /// The CSV reader's error.
        source: csv::Error,
    },
    /// A diagnostics object that is not JSON.
    #[error("diagnostics object {index}: {source}")]
    Json {
        /// Its index, from 0.
        index: usize,
        /// The parser's error.
        source: serde_json::Error,
    },
    /// A diagnostics object without a number the energy history needs.
    #[error("diagnostics object {index}: no number at {path}")]
    Missing {
        /// Its index, from 0.
        index: usize,
        /// The key path, dotted.
        path: String,
    },
    /// `plotters` failed to draw or write a figure.
    #[error("drawing {}: {message}", path.display())]
    Draw {
        /// The figure's file.
        path: PathBuf,
        /// The drawing library's error.
        message: String,
    },
}
