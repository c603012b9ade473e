//! deflex's CSV outputs as columns: `deflex run` logs, `deflex sim isf` logs, compensated
//! paths, predictions, measurement files. Header comments (`# …`) are kept; a column whose every
//! cell is a number (or empty, read as NaN) is numeric, any other is text. Bounded: at most
//! [`MAX_TABLE_BYTES`], [`MAX_TABLE_ROWS`] rows and [`MAX_TABLE_COLUMNS`] columns.

use crate::error::{Error, Result};
use std::path::Path;

/// Largest table read (bytes), as the compensation's log reader.
pub const MAX_TABLE_BYTES: u64 = 1 << 30;
/// Most rows.
pub const MAX_TABLE_ROWS: usize = 20_000_000;
/// Most columns.
pub const MAX_TABLE_COLUMNS: usize = 4096;

/// One column.
#[derive(Clone, Debug, PartialEq)]
pub enum Column {
    /// Every cell a number (empty cells NaN).
    Number(Vec<f64>),
    /// Text.
    Text(Vec<String>),
}

/// A table read from CSV.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Table {
    /// Header comment lines, without the leading `#` and space.
    pub comments: Vec<String>,
    /// Column names and values, in file order.
    pub columns: Vec<(String, Column)>,
    /// Number of rows.
    pub rows: usize,
}

impl Table {
    /// Whether a header comment says the data is SIMULATED.
    pub fn simulated(&self) -> bool {
        self.comments.iter().any(|c| c.contains("SIMULATED"))
    }
}

/// Write `text` to `path`, whole or not at all.
pub fn write_text(path: &Path, text: &str) -> Result<()> {
    deflex_files::write_atomic(path, text).map_err(|source| Error::Io {
        path: path.display().to_string(),
        source,
    })
}

/// Read a table file (bounded).
pub fn read(path: &Path) -> Result<Table> {
    let origin = path.display().to_string();
    let io = |source| Error::Io {
        path: origin.clone(),
        source,
    };
    let size = std::fs::metadata(path).map_err(io)?.len();
    if size > MAX_TABLE_BYTES {
        return Err(Error::Table {
            origin,
            line: 0,
            message: format!("{size} bytes, more than the {MAX_TABLE_BYTES} bytes read"),
        });
    }
    let text = std::fs::read_to_string(path).map_err(io)?;
    parse(&text, &origin)
}

/// Parse CSV text; `origin` names it in errors.
pub fn parse(text: &str, origin: &str) -> Result<Table> {
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
    let mut reader = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .from_reader(text.as_bytes());
    let headers = reader
        .headers()
        .map_err(|e| error(0, format!("header: {e}")))?
        .clone();
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
    for record in reader.records() {
        let record =
            record.map_err(|e| error(e.position().map_or(0, |p| p.line()), e.to_string()))?;
        if rows >= MAX_TABLE_ROWS {
            return Err(error(
                record.position().map_or(0, |p| p.line()),
                format!("more than {MAX_TABLE_ROWS} rows"),
            ));
        }
        for (column, value) in cells.iter_mut().zip(record.iter()) {
            column.push(value.to_string());
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
                Some(n) => Column::Number(n),
                None => Column::Text(values),
            };
            (name.to_string(), column)
        })
        .collect();
    Ok(Table {
        comments,
        columns,
        rows,
    })
}
