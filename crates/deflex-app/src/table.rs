//! deflex's CSV outputs as columns: `deflex run` logs, `deflex sim isf` logs, compensated
//! paths, predictions, measurement files, read with the recorder's one log reader
//! ([`deflex_record::log_reader`]). Header comments (`# …`) are kept; a column whose every
//! cell is a number (or empty, read as NaN) is numeric, any other is text. Bounded: at most
//! [`MAX_TABLE_BYTES`], [`MAX_TABLE_ROWS`] rows and [`MAX_TABLE_COLUMNS`] columns.

use crate::error::{Error, Result};
use deflex_record::log_reader::{LogReadError, LogReader};
use std::path::Path;

/// Largest table read (bytes): the log reader's bound.
pub const MAX_TABLE_BYTES: u64 = deflex_record::log_reader::MAX_LOG_BYTES;
/// Most rows: the log reader's bound.
pub const MAX_TABLE_ROWS: usize = deflex_record::log_reader::MAX_LOG_ROWS;
/// Most columns.
pub const MAX_TABLE_COLUMNS: usize = 4096;

/// One column.
#[derive(Clone, Debug, PartialEq)]
pub enum TableColumn {
    /// Every cell a number (empty cells NaN).
    Number(Vec<f64>),
    /// Text.
    Text(Vec<String>),
}

/// A table read from CSV.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct CsvTable {
    /// Header comment lines, without the leading `#` and space.
    pub comments: Vec<String>,
    /// Column names and values, in file order.
    pub columns: Vec<(String, TableColumn)>,
    /// Number of rows.
    pub rows: usize,
}

impl CsvTable {
    /// Whether a header comment says the data is SIMULATED.
    pub fn simulated(&self) -> bool {
        self.comments.iter().any(|c| c.contains("SIMULATED"))
    }
}

/// Write `text` to `path`, whole or not at all.
pub fn write_text(path: &Path, text: &str) -> Result<()> {
    deflex_files::write_atomic(path, text).map_err(Error::io_on(path))
}

/// Read a table file: a regular file of at most [`MAX_TABLE_BYTES`], counted while reading
/// ([`deflex_files::read_bounded`]).
pub fn read(path: &Path) -> Result<CsvTable> {
    let text = deflex_files::read_bounded(path, MAX_TABLE_BYTES)
        .map_err(|e| e.reported_as::<Error>("a table"))?;
    parse(&text, &path.display().to_string())
}

/// Parse CSV text; `origin` names it in errors.
pub fn parse(text: &str, origin: &str) -> Result<CsvTable> {
    let comments: Vec<String> = text
        .lines()
        .take_while(|l| l.trim_start().starts_with('#') || l.trim().is_empty())
        .filter(|l| !l.trim().is_empty())
        .map(|l| l.trim_start().trim_start_matches('#').trim().to_string())
        .collect();
    let error = |line: u64, message: String| Error::Table {
        origin: origin.to_string(),
        line,
        message,
    };
    let read_error = |e: LogReadError| match e {
        LogReadError::Csv { line, message, .. } | LogReadError::TooLarge { line, message, .. } => {
            error(line as u64, message)
        }
        LogReadError::BadValue { line, .. } => error(line as u64, e.to_string()),
    };
    let mut log = LogReader::new(text, origin).map_err(|e| match e {
        LogReadError::Csv { message, .. } => error(0, format!("header: {message}")),
        other => read_error(other),
    })?;
    let headers = log.columns().to_vec();
    if headers.len() > MAX_TABLE_COLUMNS {
        return Err(error(
            0,
            format!(
                "{} columns, more than the {MAX_TABLE_COLUMNS} read",
                headers.len()
            ),
        ));
    }
    let mut cells: Vec<Vec<String>> = vec![Vec::new(); headers.len()];
    let mut rows = 0;
    while let Some(row) = log.next_row().map_err(read_error)? {
        for (k, column) in cells.iter_mut().enumerate() {
            column.push(row.text(k).to_string());
        }
        rows += 1;
    }
    let columns = headers
        .iter()
        .zip(cells)
        .map(|(name, values)| {
            let numbers: Option<Vec<f64>> = values
                .iter()
                .map(|v| {
                    if v.is_empty() {
                        Some(f64::NAN)
                    } else {
                        v.parse::<f64>().ok()
                    }
                })
                .collect();
            let column = match numbers {
                Some(n) => TableColumn::Number(n),
                None => TableColumn::Text(values),
            };
            (name.to_string(), column)
        })
        .collect();
    Ok(CsvTable {
        comments,
        columns,
        rows,
    })
}
