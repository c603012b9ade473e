//! Reading measurement and plan CSV text: the header is resolved once into [`Columns`] (the one
//! place that decides which names are accepted), then every row is parsed and validated into a
//! [`MeasurementRow`] (every number finite and within its column's bound, links within the arm,
//! labels non-empty and short, standard deviations in range), so code downstream never checks a
//! row again.

use crate::measurements::bounds::{
    DISPLACEMENT_COLUMNS, LOAD_POINT_COLUMNS, POINT_COLUMNS, ROTATION_COLUMNS, WRENCH_COLUMNS,
    column_bound,
};
use crate::measurements::{
    DataError, FileHeader, HeaderProblem, LoadCaseConflict, MAX_LABEL_CHARS, MAX_ROWS,
    MeasuredRotation, MeasurementFile, MeasurementRow, RowProblem, SigmaColumn,
};
use std::collections::HashMap;

/// Check, before any row is read, that a file written for `expected` joints is not given to a
/// robot with another count: "the data has 5 joint columns … but the robot has 6 joints".
pub fn check_joint_columns(text: &str, origin: &str, expected: usize) -> Result<(), DataError> {
    let header = text
        .lines()
        .find(|l| !l.trim_start().starts_with('#'))
        .unwrap_or("");
    let names: Vec<&str> = header.split(',').map(str::trim).collect();
    let mut found = 0;
    while names.contains(&format!("q{}_rad", found + 1).as_str()) {
        found += 1;
    }
    if found > 0 && found != expected {
        return Err(DataError::JointColumns {
            path: origin.to_string(),
            found,
            expected,
        });
    }
    Ok(())
}

/// Parse measurement or plan CSV text. `origin` names the file in errors.
pub fn parse_rows(
    text: &str,
    origin: &str,
    require_displacement: bool,
) -> Result<Vec<MeasurementRow>, DataError> {
    Ok(parse_file(text, origin, require_displacement)?.rows)
}

/// Parse measurement or plan CSV text with its header comments and the line of every row.
/// `origin` names the file in errors; with `require_displacement` (a measurement file) every row
/// must carry `dx_m, dy_m, dz_m`, without it (a plan) they are read when present. A column the
/// format does not know is an error ([`parse_file_ignoring`] names columns to skip).
pub fn parse_file(
    text: &str,
    origin: &str,
    require_displacement: bool,
) -> Result<MeasurementFile, DataError> {
    parse_file_ignoring(text, origin, require_displacement, &[])
}

/// [`parse_file`], skipping the columns named in `ignored` (a user's own extra columns, kept
/// knowingly; a column the format reads cannot be ignored). A name the file does not have is
/// not an error: one list serves every file of a command, and a misspelt name leaves the
/// column it meant unknown, which is one.
pub fn parse_file_ignoring(
    text: &str,
    origin: &str,
    require_displacement: bool,
    ignored: &[String],
) -> Result<MeasurementFile, DataError> {
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
        .map_err(|e| header_error(HeaderProblem::Csv(e)))?
        .clone();
    let columns =
        Columns::resolve(&headers, require_displacement, ignored).map_err(header_error)?;
    let mut rows = Vec::new();
    let mut lines = Vec::new();
    for record in reader.records() {
        let record = record.map_err(|e| DataError::Row {
            path: origin.to_string(),
            line: e.position().map(|p| p.line()).unwrap_or(0),
            problem: RowProblem::Csv(e),
        })?;
        let line = record.position().map(|p| p.line()).unwrap_or(0);
        let row_error = |problem: RowProblem| DataError::Row {
            path: origin.to_string(),
            line,
            problem,
        };
        if record.len() != columns.width {
            return Err(row_error(RowProblem::FieldCount {
                expected: columns.width,
                found: record.len(),
            }));
        }
        if rows.len() >= MAX_ROWS {
            return Err(row_error(RowProblem::TooManyRows { max: MAX_ROWS }));
        }
        let row = columns
            .row(&record, require_displacement)
            .map_err(row_error)?;
        rows.push(row);
        lines.push(line);
    }
    if rows.is_empty() {
        return Err(DataError::NoRows {
            path: origin.to_string(),
        });
    }
    check_load_case_configurations(&rows, &lines, origin)?;
    Ok(MeasurementFile {
        header: FileHeader::parse(text),
        rows,
        lines,
    })
}

/// Every row of a load case holds the configuration of its first row (exactly: the files deflex
/// writes carry every digit, and two configurations a rounding apart are one typed twice).
fn check_load_case_configurations(
    rows: &[MeasurementRow],
    lines: &[u64],
    origin: &str,
) -> Result<(), DataError> {
    let mut first: HashMap<&str, usize> = HashMap::new();
    for (i, row) in rows.iter().enumerate() {
        let j = *first.entry(row.load_case.as_str()).or_insert(i);
        let reference = &rows[j];
        if let Some(k) = (0..row.q_rad.len()).find(|&k| row.q_rad[k] != reference.q_rad[k]) {
            return Err(DataError::LoadCaseConfigurations {
                path: origin.to_string(),
                conflict: Box::new(LoadCaseConflict {
                    load_case: row.load_case.chars().take(80).collect(),
                    first_line: lines[j],
                    line: lines[i],
                    joint: k + 1,
                    first_value: reference.q_rad[k],
                    value: row.q_rad[k],
                }),
            });
        }
    }
    Ok(())
}

/// The header of a file resolved to column positions. Every column name the format knows is
/// looked up here, once; a stricter header policy (unknown or duplicate names) belongs in
/// [`Columns::resolve`] alone.
struct Columns {
    index: HashMap<String, usize>,
    width: usize,
    joint_count: usize,
    has_displacement: bool,
    has_rotation: bool,
}

impl Columns {
    fn resolve(
        headers: &csv::StringRecord,
        require_displacement: bool,
        ignored: &[String],
    ) -> Result<Columns, HeaderProblem> {
        let mut index: HashMap<String, usize> = HashMap::new();
        for (i, name) in headers.iter().enumerate() {
            if index.insert(name.to_string(), i).is_some() {
                return Err(HeaderProblem::Duplicate {
                    name: name.to_string(),
                });
            }
        }
        let mut joint_count = 0;
        while index.contains_key(format!("q{}_rad", joint_count + 1).as_str()) {
            joint_count += 1;
        }
        if joint_count == 0 {
            return Err(HeaderProblem::NoJointColumns);
        }
        let mut required: Vec<&str> = vec!["load_case", "load_link", "point", "point_link"];
        required.extend(
            WRENCH_COLUMNS
                .iter()
                .chain(&LOAD_POINT_COLUMNS)
                .chain(&POINT_COLUMNS),
        );
        if require_displacement {
            required.extend(DISPLACEMENT_COLUMNS);
        }
        let names: Vec<String> = required
            .iter()
            .filter(|c| !index.contains_key(**c))
            .map(|c| c.to_string())
            .collect();
        if !names.is_empty() {
            return Err(HeaderProblem::Missing { names });
        }
        let mut known: Vec<String> = required.iter().map(|c| c.to_string()).collect();
        known.extend((1..=joint_count).map(|i| format!("q{i}_rad")));
        known.extend(
            DISPLACEMENT_COLUMNS
                .iter()
                .chain(&ROTATION_COLUMNS)
                .chain(&["sigma_m", "sigma_rad", "purpose"])
                .map(|c| c.to_string()),
        );
        for name in ignored {
            if known.iter().any(|k| k == name) || is_joint_column(name) {
                return Err(HeaderProblem::IgnoredKnown {
                    name: name.chars().take(80).collect(),
                });
            }
        }
        if let Some(name) = headers
            .iter()
            .find(|h| !known.iter().any(|k| k == h) && !ignored.iter().any(|i| i == h))
        {
            return Err(HeaderProblem::Unknown {
                name: name.chars().take(80).collect(),
                closest: closest_column(name, &known),
            });
        }
        Ok(Columns {
            has_displacement: DISPLACEMENT_COLUMNS.iter().all(|c| index.contains_key(*c)),
            has_rotation: ROTATION_COLUMNS.iter().all(|c| index.contains_key(*c)),
            width: headers.len(),
            joint_count,
            index,
        })
    }

    /// One row (of the header's width), every field checked (see the module documentation).
    fn row(
        &self,
        record: &csv::StringRecord,
        require_displacement: bool,
    ) -> Result<MeasurementRow, RowProblem> {
        let cells = Cells {
            columns: self,
            record,
        };
        let q_rad = (1..=self.joint_count)
            .map(|i| cells.number(&format!("q{i}_rad")))
            .collect::<Result<Vec<_>, _>>()?;
        let mut wrench = [0.0; 6];
        for (value, name) in wrench.iter_mut().zip(WRENCH_COLUMNS) {
            *value = cells.number(name)?;
        }
        let load_case = cells.label("load_case")?;
        let point = cells.label("point")?;
        let sigma_m = cells.sigma(SigmaColumn::Position)?;
        let displacement_m =
            if self.has_displacement && (require_displacement || !cells.text("dx_m").is_empty()) {
                Some(cells.triple(&DISPLACEMENT_COLUMNS)?)
            } else {
                None
            };
        let rotation_rad = if self.has_rotation && !cells.text("drx_rad").is_empty() {
            let sigma_rad = cells.sigma(SigmaColumn::Rotation)?;
            Some(MeasuredRotation {
                value_rad: cells.triple(&ROTATION_COLUMNS)?,
                sigma_rad,
            })
        } else {
            None
        };
        let purpose = self
            .index
            .get("purpose")
            .map(|_| {
                cells
                    .text("purpose")
                    .chars()
                    .take(MAX_LABEL_CHARS)
                    .collect::<String>()
            })
            .filter(|s| !s.is_empty());
        Ok(MeasurementRow {
            load_case,
            q_rad,
            wrench,
            load_link: cells.link("load_link")?,
            load_point_m: cells.triple(&LOAD_POINT_COLUMNS)?,
            point,
            point_link: cells.link("point_link")?,
            point_m: cells.triple(&POINT_COLUMNS)?,
            displacement_m,
            sigma_m,
            rotation_rad,
            purpose,
        })
    }
}

/// The cells of one record, read by column name.
struct Cells<'a> {
    columns: &'a Columns,
    record: &'a csv::StringRecord,
}

impl Cells<'_> {
    /// The cell of a column ("" when the column is absent).
    fn text(&self, name: &str) -> &str {
        self.columns
            .index
            .get(name)
            .and_then(|&i| self.record.get(i))
            .unwrap_or("")
    }

    /// A finite number within the column's bound.
    fn number(&self, name: &str) -> Result<f64, RowProblem> {
        let text = self.text(name);
        let shown = || text.chars().take(40).collect::<String>();
        let value: f64 = text.parse().map_err(|_| RowProblem::NotANumber {
            column: name.to_string(),
            text: shown(),
        })?;
        if !value.is_finite() {
            return Err(RowProblem::NotFinite {
                column: name.to_string(),
                text: shown(),
            });
        }
        let (limit, unit) = column_bound(name);
        if value.abs() > limit {
            return Err(RowProblem::BeyondBound {
                column: name.to_string(),
                value,
                limit,
                unit,
            });
        }
        Ok(value)
    }

    fn triple(&self, names: &[&str; 3]) -> Result<[f64; 3], RowProblem> {
        Ok([
            self.number(names[0])?,
            self.number(names[1])?,
            self.number(names[2])?,
        ])
    }

    /// A link index 0 (base) … N (last link).
    fn link(&self, column: &'static str) -> Result<usize, RowProblem> {
        let text = self.text(column);
        let joint_count = self.columns.joint_count;
        let link: usize = text.parse().map_err(|_| RowProblem::NotALink {
            column,
            text: text.to_string(),
            joint_count,
        })?;
        if link > joint_count {
            return Err(RowProblem::NoSuchLink {
                column,
                link,
                joint_count,
            });
        }
        Ok(link)
    }

    /// A non-empty label of at most [`MAX_LABEL_CHARS`] characters.
    fn label(&self, column: &'static str) -> Result<String, RowProblem> {
        let text = self.text(column);
        if text.is_empty() {
            return Err(RowProblem::EmptyLabel { column });
        }
        if text.chars().count() > MAX_LABEL_CHARS {
            return Err(RowProblem::LabelTooLong {
                column,
                max: MAX_LABEL_CHARS,
            });
        }
        Ok(text.to_string())
    }

    /// An optional standard deviation (an empty cell or an absent column: none), in range.
    fn sigma(&self, sigma: SigmaColumn) -> Result<Option<f64>, RowProblem> {
        let column = sigma.column();
        if !self.columns.index.contains_key(column) || self.text(column).is_empty() {
            return Ok(None);
        }
        let value = self.number(column)?;
        if !sigma.accepts(value) {
            return Err(RowProblem::Sigma { sigma, value });
        }
        Ok(Some(value))
    }
}

/// The column of `known` closest to `name` (a typo's likely meaning), within 3 edits.
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
