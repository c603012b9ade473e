//! The one reader of deflex's CSV logs: the `deflex run` log ([`crate::run_log`]) and the
//! `deflex sim isf` log ([`crate::isf_log`]), for every program that reads them back (the
//! compensation's logged forces, `deflex plot`, Python).
//!
//! A log is CSV text: comment lines starting with `#` (a `SIMULATED` in a leading one marks
//! the twin's data), a header of column names with their units, one row per sample; cells are
//! trimmed. The reader streams the rows, each with its 1-based line, and reads a cell as what
//! its column holds ([`LogRow::number`], [`LogRow::finite`], [`LogRow::unsigned`]): every error
//! names the file, the line and the column. Bounded: the caller reads at most
//! [`MAX_LOG_BYTES`] of a file, the reader at most [`MAX_LOG_ROWS`] rows.

/// Largest log read (bytes).
pub const MAX_LOG_BYTES: u64 = 1 << 30;
/// Most rows read from one log.
pub const MAX_LOG_ROWS: usize = 20_000_000;

/// Why a log's text cannot be read.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum LogReadError {
    /// The CSV is malformed (a row with another number of cells than the header, a cell that
    /// is not UTF-8).
    #[error("{file}:{line}: {message}")]
    Csv {
        /// The file.
        file: String,
        /// 1-based line (0 when unknown).
        line: usize,
        /// The parser's message.
        message: String,
    },
    /// More than [`MAX_LOG_ROWS`] rows.
    #[error("{file}: {message}")]
    TooLarge {
        /// The file.
        file: String,
        /// 1-based line of the first row beyond the bound.
        line: usize,
        /// Which bound.
        message: String,
    },
    /// A cell that is not what its column holds.
    #[error("{file}:{line}: column `{column}`: expected a number, got \"{value}\"")]
    BadValue {
        /// The file.
        file: String,
        /// 1-based line.
        line: usize,
        /// The column.
        column: String,
        /// The text found.
        value: String,
    },
}

/// The file's name and columns, shared by its rows.
#[derive(Clone, Debug)]
struct Header {
    file: String,
    columns: Vec<String>,
}

/// A log's text read row by row (see the module documentation).
pub struct LogReader<'t> {
    header: Header,
    simulated: bool,
    header_line: usize,
    csv: csv::Reader<&'t [u8]>,
    record: csv::StringRecord,
    rows: usize,
}

impl std::fmt::Debug for LogReader<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LogReader")
            .field("file", &self.header.file)
            .field("columns", &self.header.columns)
            .field("rows", &self.rows)
            .finish()
    }
}

impl<'t> LogReader<'t> {
    /// Reads the header of `text`; `file` names it in errors.
    pub fn new(text: &'t str, file: &str) -> Result<LogReader<'t>, LogReadError> {
        let simulated = text
            .lines()
            .take_while(|l| l.starts_with('#'))
            .any(|l| l.contains("SIMULATED"));
        let mut csv = csv::ReaderBuilder::new()
            .comment(Some(b'#'))
            .trim(csv::Trim::All)
            .flexible(false)
            .from_reader(text.as_bytes());
        let columns: Vec<String> = csv
            .headers()
            .map_err(|e| csv_error(file, e))?
            .iter()
            .map(String::from)
            .collect();
        let header_line = text
            .lines()
            .position(|l| !l.starts_with('#'))
            .map_or(csv.position().line() as usize, |i| i + 1);
        Ok(LogReader {
            header: Header {
                file: file.to_string(),
                columns,
            },
            simulated,
            header_line,
            csv,
            record: csv::StringRecord::new(),
            rows: 0,
        })
    }

    /// The file (as named in errors).
    pub fn file(&self) -> &str {
        &self.header.file
    }

    /// A leading comment line says the data is SIMULATED.
    pub fn simulated(&self) -> bool {
        self.simulated
    }

    /// The column names, in file order.
    pub fn columns(&self) -> &[String] {
        &self.header.columns
    }

    /// 1-based line of the header.
    pub fn header_line(&self) -> usize {
        self.header_line
    }

    /// Index of the column `name` (the first of that name).
    pub fn column(&self, name: &str) -> Option<usize> {
        self.header.columns.iter().position(|c| c == name)
    }

    /// The log has a column `name`.
    pub fn has(&self, name: &str) -> bool {
        self.column(name).is_some()
    }

    /// Indices of the columns `names`, or the names missing.
    pub fn columns_of(&self, names: &[&str]) -> Result<Vec<usize>, Vec<String>> {
        let missing: Vec<String> = names
            .iter()
            .filter(|n| !self.has(n))
            .map(|n| n.to_string())
            .collect();
        if missing.is_empty() {
            Ok(names.iter().filter_map(|n| self.column(n)).collect())
        } else {
            Err(missing)
        }
    }

    /// The next row; `None` after the last. More than [`MAX_LOG_ROWS`] rows is an error.
    pub fn next_row(&mut self) -> Result<Option<LogRow<'_>>, LogReadError> {
        let more = self
            .csv
            .read_record(&mut self.record)
            .map_err(|e| csv_error(&self.header.file, e))?;
        if !more {
            return Ok(None);
        }
        if self.rows >= MAX_LOG_ROWS {
            return Err(LogReadError::TooLarge {
                file: self.header.file.clone(),
                line: self.record.position().map_or(0, |p| p.line() as usize),
                message: format!("more than {MAX_LOG_ROWS} rows"),
            });
        }
        self.rows += 1;
        Ok(Some(LogRow {
            header: &self.header,
            line: self.record.position().map_or(0, |p| p.line() as usize),
            record: &self.record,
        }))
    }
}

fn csv_error(file: &str, e: csv::Error) -> LogReadError {
    LogReadError::Csv {
        file: file.to_string(),
        line: e.position().map_or(0, |p| p.line() as usize),
        message: e.to_string(),
    }
}

/// One row of a log, its cells read by column index ([`LogReader::column`]).
#[derive(Clone, Copy, Debug)]
pub struct LogRow<'r> {
    header: &'r Header,
    line: usize,
    record: &'r csv::StringRecord,
}

impl LogRow<'_> {
    /// 1-based line of the row.
    pub fn line(&self) -> usize {
        self.line
    }

    /// The cell's text (trimmed; empty beyond the row).
    pub fn text(&self, column: usize) -> &str {
        self.record.get(column).unwrap_or("")
    }

    fn bad_value(&self, column: usize) -> LogReadError {
        LogReadError::BadValue {
            file: self.header.file.clone(),
            line: self.line,
            column: self
                .header
                .columns
                .get(column)
                .map_or("?", String::as_str)
                .to_string(),
            value: self.text(column).to_string(),
        }
    }

    /// A number; an empty cell is an unknown value (NaN), a cell reading `NaN` or `inf` is
    /// that value; anything else is an error.
    pub fn number(&self, column: usize) -> Result<f64, LogReadError> {
        let text = self.text(column);
        if text.is_empty() {
            return Ok(f64::NAN);
        }
        text.parse::<f64>().map_err(|_| self.bad_value(column))
    }

    /// A finite number; anything else (an empty cell included) is an error.
    pub fn finite(&self, column: usize) -> Result<f64, LogReadError> {
        self.text(column)
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| self.bad_value(column))
    }

    /// An unsigned 32-bit integer (the flags); anything else is an error.
    pub fn unsigned(&self, column: usize) -> Result<u32, LogReadError> {
        self.text(column)
            .parse::<u32>()
            .map_err(|_| self.bad_value(column))
    }
}
