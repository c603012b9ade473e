//! The one reader of the crate's measurement files: loaded displacements and plans
//! ([`crate::measurements`]) and absolute tracker readings ([`crate::geometry::data`]). A
//! [`MeasurementFormat`] names its columns and builds its row from the cells; [`read`] does the
//! rest, the same way for every format:
//!
//! * lines starting with `#` are comments; those before the column names may say which robot the
//!   file was made for (`# robot:`, `# geometry:`: [`FileHeader`]);
//! * cells are trimmed; columns are found by exact name, in any order; a name given twice is an
//!   error;
//! * a column the format does not know is an error naming the closest known one
//!   ([`closest_column`]), unless the user names it as ignored (`--ignore-column`); a column the
//!   format reads (the joint columns of any robot included) cannot be ignored
//!   ([`Columns::check_names`]);
//! * at most the format's number of rows ([`RowLimit`]), each as wide as the header;
//! * every number finite and within its column's bound ([`Cells::number`], [`Cells::number_in`]),
//!   every label non-empty and bounded ([`Cells::label`]);
//! * nothing of a file with an error is used; the error ([`DataError`]) names the file, the line
//!   and the column.
//!
//! Reading the file from disk (bounded in size) is the caller's job.

use crate::measurements::{
    DataError, FileHeader, HeaderProblem, LabelLength, RowError, RowProblem,
};
use std::collections::HashMap;

/// A measurement format: its columns and its row.
pub trait MeasurementFormat {
    /// One row of the format.
    type Row;
    /// What the format found in a file's header (its joint count, which optional columns it has).
    type Columns;
    /// How many rows a file may have, and how one more is told.
    const ROW_LIMIT: RowLimit;
    /// The column named by a problem of a record as a whole (a CSV error, a field count): none,
    /// or a placeholder such as `-`.
    const RECORD_COLUMN: Option<&'static str>;

    /// Check the header's column names (required, known, ignored) and note what the rows will
    /// need.
    fn columns(&self, columns: &Columns) -> Result<Self::Columns, HeaderProblem>;

    /// One row from its cells (the record is as wide as the header).
    fn row(&self, columns: &Self::Columns, cells: &Cells<'_>) -> Result<Self::Row, RowError>;
}

/// How many rows a format reads, and how a file with more is refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RowLimit {
    /// At most this many rows: the next one is refused as a problem of its line, once its width
    /// is checked ([`RowProblem::TooManyRows`]).
    PerLine(usize),
    /// At most this many rows: the next record is refused as a problem of the file, before
    /// anything else of it is checked ([`DataError::TooManyRows`]).
    PerFile(usize),
}

/// A file as read: its header comments, its rows and the line of each row.
#[derive(Clone, Debug, PartialEq)]
pub struct MeasurementTable<R> {
    /// The header comments.
    pub header: FileHeader,
    /// The rows.
    pub rows: Vec<R>,
    /// 1-based line number of each row in the file.
    pub lines: Vec<u64>,
}

/// Read CSV text of `format`; `origin` names the file in errors. A file without data rows is an
/// error.
pub fn read<F: MeasurementFormat>(
    format: &F,
    text: &str,
    origin: &str,
) -> Result<MeasurementTable<F::Row>, DataError> {
    let mut reader = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .flexible(true)
        .comment(Some(b'#'))
        .from_reader(text.as_bytes());
    let header_error = |problem: HeaderProblem| DataError::Header {
        path: origin.to_string(),
        problem,
    };
    let headers = reader
        .headers()
        .map_err(|e| header_error(HeaderProblem::Csv(e)))?;
    let columns = Columns::of(headers).map_err(header_error)?;
    let resolved = format.columns(&columns).map_err(header_error)?;
    let row_error = |line: u64, error: RowError| DataError::Row {
        path: origin.to_string(),
        line,
        error,
    };
    let record_error = |line: u64, problem: RowProblem| {
        row_error(
            line,
            RowError {
                column: F::RECORD_COLUMN.map(String::from),
                problem,
            },
        )
    };
    let mut rows = Vec::new();
    let mut lines = Vec::new();
    for record in reader.records() {
        let record = record.map_err(|e| {
            let line = e.position().map(|p| p.line()).unwrap_or(0);
            record_error(line, RowProblem::Csv(e))
        })?;
        let line = record.position().map(|p| p.line()).unwrap_or(0);
        if let RowLimit::PerFile(limit) = F::ROW_LIMIT
            && rows.len() >= limit
        {
            return Err(DataError::TooManyRows {
                path: origin.to_string(),
                limit,
            });
        }
        if record.len() != columns.width() {
            return Err(record_error(
                line,
                RowProblem::FieldCount {
                    expected: columns.width(),
                    found: record.len(),
                },
            ));
        }
        if let RowLimit::PerLine(max) = F::ROW_LIMIT
            && rows.len() >= max
        {
            return Err(record_error(line, RowProblem::TooManyRows { max }));
        }
        let cells = Cells {
            columns: &columns,
            record: &record,
            line,
        };
        rows.push(
            format
                .row(&resolved, &cells)
                .map_err(|error| row_error(line, error))?,
        );
        lines.push(line);
    }
    if rows.is_empty() {
        return Err(DataError::NoRows {
            path: origin.to_string(),
        });
    }
    Ok(MeasurementTable {
        header: FileHeader::parse(text),
        rows,
        lines,
    })
}

/// The column names of a file's header, looked up by exact name.
#[derive(Clone, Debug)]
pub struct Columns {
    index: HashMap<String, usize>,
    names: Vec<String>,
}

impl Columns {
    /// The columns of a header record; a name given twice is an error.
    pub fn of(headers: &csv::StringRecord) -> Result<Columns, HeaderProblem> {
        let mut index: HashMap<String, usize> = HashMap::new();
        for (i, name) in headers.iter().enumerate() {
            if index.insert(name.to_string(), i).is_some() {
                return Err(HeaderProblem::Duplicate {
                    name: name.to_string(),
                });
            }
        }
        Ok(Columns {
            index,
            names: headers.iter().map(String::from).collect(),
        })
    }

    /// Whether the header has the column `name`.
    pub fn has(&self, name: &str) -> bool {
        self.index.contains_key(name)
    }

    /// Number of columns.
    pub fn width(&self) -> usize {
        self.names.len()
    }

    /// Number of joint columns `q1_rad`, `q2_rad`, … present from `q1_rad` on without a gap.
    pub fn joint_count(&self) -> usize {
        let mut found = 0;
        while self.has(&format!("q{}_rad", found + 1)) {
            found += 1;
        }
        found
    }

    /// Every column of `required` is present; the error names the missing ones, in that order.
    pub fn require(&self, required: &[&str]) -> Result<(), HeaderProblem> {
        let names: Vec<String> = required
            .iter()
            .filter(|c| !self.has(c))
            .map(|c| c.to_string())
            .collect();
        if names.is_empty() {
            Ok(())
        } else {
            Err(HeaderProblem::Missing { names })
        }
    }

    /// Whether every column of `group` is present (`false` when none is); some but not all is
    /// an error.
    pub fn all_or_none(&self, group: &[String]) -> Result<bool, HeaderProblem> {
        let present = group.iter().filter(|c| self.has(c)).count();
        if present != 0 && present != group.len() {
            return Err(HeaderProblem::PartialGroup {
                names: group.to_vec(),
            });
        }
        Ok(present == group.len())
    }

    /// Every column is `known` to the format or named in `ignored`; a name of `ignored` is
    /// neither known nor a joint column nor `also_read` by the format (ignoring it would change
    /// what the file means). A name of `ignored` the file does not have is not an error: one
    /// list serves every file of a command, and a misspelt name leaves the column it meant
    /// unknown, which is one. An unknown column is named with the closest known one.
    pub fn check_names(
        &self,
        known: &[String],
        ignored: &[String],
        also_read: impl Fn(&str) -> bool,
    ) -> Result<(), HeaderProblem> {
        for name in ignored {
            if known.iter().any(|k| k == name) || is_joint_column(name) || also_read(name) {
                return Err(HeaderProblem::IgnoredKnown {
                    name: name.chars().take(80).collect(),
                });
            }
        }
        if let Some(name) = self
            .names
            .iter()
            .find(|h| !known.iter().any(|k| k == *h) && !ignored.iter().any(|i| i == *h))
        {
            return Err(HeaderProblem::Unknown {
                name: name.chars().take(80).collect(),
                closest: closest_column(name, known),
            });
        }
        Ok(())
    }
}

/// The cells of one record, read by column name, with the checks every value goes through.
pub struct Cells<'a> {
    columns: &'a Columns,
    record: &'a csv::StringRecord,
    line: u64,
}

impl Cells<'_> {
    /// 1-based line of the record in the file.
    pub fn line(&self) -> u64 {
        self.line
    }

    /// The cell of a column (`""` when the column is absent).
    pub fn text(&self, name: &str) -> &str {
        self.columns
            .index
            .get(name)
            .and_then(|&i| self.record.get(i))
            .unwrap_or("")
    }

    /// Whether the column is present and its cell not empty.
    pub fn present(&self, name: &str) -> bool {
        self.columns.has(name) && !self.text(name).is_empty()
    }

    /// A finite number within ±`limit` (`unit`); refused as not a number, not finite or beyond
    /// the bound, with at most 40 characters of the cell shown.
    pub fn number(&self, name: &str, limit: f64, unit: &'static str) -> Result<f64, RowError> {
        let text = self.text(name);
        let shown = || text.chars().take(40).collect::<String>();
        let problem = match text.parse::<f64>() {
            Err(_) => RowProblem::NotANumber {
                text: shown(),
                unit: None,
            },
            Ok(value) if !value.is_finite() => RowProblem::NotFinite { text: shown() },
            Ok(value) if value.abs() > limit => RowProblem::BeyondBound { value, limit, unit },
            Ok(value) => return Ok(value),
        };
        Err(RowError::in_column(name, problem))
    }

    /// A finite number within ±`limit` (`unit`), refused with the range expected: "expected a
    /// number in UNIT" or "expected a finite value within ±LIMIT UNIT", the whole cell shown.
    pub fn number_in(&self, name: &str, limit: f64, unit: &'static str) -> Result<f64, RowError> {
        let text = self.text(name);
        let problem = match text.parse::<f64>() {
            Err(_) => RowProblem::NotANumber {
                text: text.to_string(),
                unit: Some(unit),
            },
            Ok(value) if !value.is_finite() || value.abs() > limit => RowProblem::OutOfRange {
                text: text.to_string(),
                limit,
                unit,
            },
            Ok(value) => return Ok(value),
        };
        Err(RowError::in_column(name, problem))
    }

    /// A non-empty label no longer than `max`.
    pub fn label(&self, name: &str, max: LabelLength) -> Result<String, RowError> {
        let text = self.text(name);
        if text.is_empty() {
            return Err(RowError::in_column(name, RowProblem::EmptyLabel));
        }
        if max.exceeded_by(text) {
            return Err(RowError::in_column(name, RowProblem::LabelTooLong { max }));
        }
        Ok(text.to_string())
    }
}

/// The column of `known` closest to `name` (a typo's likely meaning), within 3 edits; the
/// first of equally close ones.
pub fn closest_column(name: &str, known: &[String]) -> Option<String> {
    known
        .iter()
        .map(|k| (edit_distance(k, name), k))
        .filter(|(d, _)| *d <= 3)
        .min_by_key(|(d, _)| *d)
        .map(|(_, k)| k.clone())
}

/// `q7_rad` and the like: a joint column (of this robot or another), never an ignorable one.
pub fn is_joint_column(name: &str) -> bool {
    name.strip_prefix('q')
        .and_then(|rest| rest.strip_suffix("_rad"))
        .is_some_and(|digits| !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit()))
}

/// Levenshtein distance between two column names (short strings: the quadratic table is fine).
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().take(200).collect();
    let mut previous: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().take(200).enumerate() {
        let mut current = vec![i + 1];
        for (j, cb) in b.iter().enumerate() {
            let substitution = previous[j] + usize::from(ca != *cb);
            current.push(substitution.min(previous[j + 1] + 1).min(current[j] + 1));
        }
        previous = current;
    }
    previous[b.len()]
}
