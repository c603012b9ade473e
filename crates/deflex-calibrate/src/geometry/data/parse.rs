//! Parsing absolute measurement CSV text (the caller reads the file, bounded by
//! [`limits::MAX_FILE_BYTES`]): every value checked once, here, with typed errors that name the
//! file, the line, the column and what was expected.

use super::{
    APPROACH, AbsoluteRow, ORIENTATION, PAYLOAD_COM, POSITION, RowOrientation, RowPayload, WRENCH,
    limits,
};
use std::collections::HashMap;
use thiserror::Error;

/// A bad absolute measurement file. Nothing of a file with an error is used.
#[derive(Debug, Error)]
pub enum AbsoluteDataError {
    /// A problem with the header.
    #[error("{path}: header: {problem}")]
    Header {
        /// File.
        path: String,
        /// What is wrong.
        problem: HeaderProblem,
    },
    /// A problem with one row.
    #[error("{path}:{line}: column `{column}`: {problem}")]
    Row {
        /// File.
        path: String,
        /// 1-based line.
        line: u64,
        /// Column concerned (`-` for the record as a whole).
        column: String,
        /// What is wrong.
        problem: RowProblem,
    },
    /// More rows than [`limits::MAX_ROWS`].
    #[error("{path}: more than {limit} rows")]
    TooManyRows {
        /// File.
        path: String,
        /// The bound.
        limit: usize,
    },
    /// A header and no data row.
    #[error("{path}: no data rows")]
    NoRows {
        /// File.
        path: String,
    },
}

/// What is wrong with a header.
#[derive(Debug, Error)]
pub enum HeaderProblem {
    /// Not CSV.
    #[error("{0}")]
    Csv(#[source] csv::Error),
    /// A column name appears twice.
    #[error("column `{0}` appears twice")]
    Duplicate(String),
    /// The `q1_rad…` columns do not match the robot.
    #[error("the file has {found} joint columns (q1_rad…) but the robot has {expected} joints")]
    JointColumns {
        /// `q{i}_rad` columns found (consecutive from 1).
        found: usize,
        /// Robot joints.
        expected: usize,
    },
    /// Required columns are missing.
    #[error("missing column(s) {}", .0.iter().map(|c| format!("`{c}`")).collect::<Vec<_>>().join(", "))]
    Missing(Vec<String>),
    /// A column the format does not have (a typo such as `sigma_mm` would otherwise be ignored
    /// and its values replaced by the default).
    #[error("unknown column `{name}`{}; a column kept on purpose must be named as ignored (`deflex … --ignore-column {name}`)", closest.as_ref().map(|c| format!(" (did you mean `{c}`?)")).unwrap_or_default())]
    Unknown {
        /// The column.
        name: String,
        /// The closest column of the format.
        closest: Option<String>,
    },
    /// A column asked to be ignored is one the format reads.
    #[error(
        "column `{0}` is read by the format and cannot be ignored (only columns the format does not know can be)"
    )]
    IgnoredKnown(String),
    /// Some but not all columns of a group.
    #[error("columns {} go together: give all or none", .0.join(", "))]
    PartialGroup(Vec<String>),
}

/// What is wrong with a value of one row.
#[derive(Debug, Error)]
pub enum RowProblem {
    /// Not CSV.
    #[error("{0}")]
    Csv(#[source] csv::Error),
    /// Not as many fields as the header.
    #[error("expected {expected} fields as in the header, found {found}")]
    FieldCount {
        /// Header width.
        expected: usize,
        /// Fields in this record.
        found: usize,
    },
    /// Not a number.
    #[error("expected a number in {unit}, got \"{text}\"")]
    NotANumber {
        /// The cell.
        text: String,
        /// Unit expected.
        unit: &'static str,
    },
    /// Not finite or beyond the bound.
    #[error("expected a finite value within ±{limit} {unit}, got {text}")]
    OutOfRange {
        /// The cell.
        text: String,
        /// The bound.
        limit: f64,
        /// Unit.
        unit: &'static str,
    },
    /// A standard deviation that is zero or negative.
    #[error("must be positive, got {0}")]
    NotPositive(f64),
    /// A negative payload.
    #[error("must not be negative, got {0}")]
    Negative(f64),
    /// A temperature outside [`limits::TEMPERATURE_RANGE_C`].
    #[error("expected {}…{} °C, got {value}", .range[0], .range[1])]
    Temperature {
        /// Value.
        value: f64,
        /// Range accepted.
        range: [f64; 2],
    },
    /// An empty label.
    #[error("empty label")]
    EmptyLabel,
    /// A label longer than [`limits::MAX_LABEL_BYTES`].
    #[error("label longer than {0} bytes")]
    LongLabel(usize),
}

/// Index of the header's columns.
struct Columns {
    index: HashMap<String, usize>,
    width: usize,
    orientation: bool,
    payload_com: bool,
    wrench: bool,
    approach: bool,
}

fn header(
    reader: &mut csv::Reader<&[u8]>,
    origin: &str,
    joint_count: usize,
    ignored: &[String],
) -> Result<Columns, AbsoluteDataError> {
    let error = |problem| AbsoluteDataError::Header {
        path: origin.to_string(),
        problem,
    };
    let headers = reader
        .headers()
        .map_err(|e| error(HeaderProblem::Csv(e)))?
        .clone();
    let mut index: HashMap<String, usize> = HashMap::new();
    for (i, name) in headers.iter().enumerate() {
        if index.insert(name.to_string(), i).is_some() {
            return Err(error(HeaderProblem::Duplicate(name.to_string())));
        }
    }
    let mut found = 0;
    while index.contains_key(&format!("q{}_rad", found + 1)) {
        found += 1;
    }
    if found != joint_count {
        return Err(error(HeaderProblem::JointColumns {
            found,
            expected: joint_count,
        }));
    }
    let mut required: Vec<&str> = vec!["setup", "target"];
    required.extend(POSITION);
    let missing: Vec<String> = required
        .iter()
        .filter(|c| !index.contains_key(**c))
        .map(|c| c.to_string())
        .collect();
    if !missing.is_empty() {
        return Err(error(HeaderProblem::Missing(missing)));
    }
    let all_or_none = |group: &[String]| -> Result<bool, AbsoluteDataError> {
        let present = group.iter().filter(|c| index.contains_key(*c)).count();
        if present != 0 && present != group.len() {
            return Err(error(HeaderProblem::PartialGroup(group.to_vec())));
        }
        Ok(present == group.len())
    };
    let strings = |group: &[&str]| group.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    let approach: Vec<String> = (1..=joint_count)
        .map(|i| format!("{APPROACH}{i}_rad"))
        .collect();
    let mut known: Vec<String> = ["setup", "target", "config", "sigma_m", "sigma_rad"]
        .iter()
        .chain(&POSITION)
        .chain(&ORIENTATION)
        .chain(&PAYLOAD_COM)
        .chain(&WRENCH)
        .chain(&["payload_kg", "temperature_C", "time_s"])
        .map(|c| c.to_string())
        .collect();
    known.extend((1..=joint_count).map(|i| format!("q{i}_rad")));
    known.extend(approach.iter().cloned());
    for name in ignored {
        if known.contains(name)
            || crate::measurements::is_joint_column(name)
            || name.starts_with(APPROACH)
        {
            return Err(error(HeaderProblem::IgnoredKnown(
                name.chars().take(80).collect(),
            )));
        }
    }
    if let Some(name) = headers
        .iter()
        .find(|h| !known.iter().any(|k| k == h) && !ignored.iter().any(|i| i == h))
    {
        return Err(error(HeaderProblem::Unknown {
            name: name.chars().take(80).collect(),
            closest: crate::measurements::closest_column(name, &known),
        }));
    }
    Ok(Columns {
        orientation: all_or_none(&strings(&ORIENTATION))?,
        payload_com: all_or_none(&strings(&PAYLOAD_COM))?,
        wrench: all_or_none(&strings(&WRENCH))?,
        approach: all_or_none(&approach)?,
        width: headers.len(),
        index,
    })
}

/// One record's cells, looked up by column name, with the checks every value goes through.
struct Record<'a> {
    columns: &'a Columns,
    record: &'a csv::StringRecord,
    origin: &'a str,
    line: u64,
}

impl Record<'_> {
    fn error(&self, column: &str, problem: RowProblem) -> AbsoluteDataError {
        AbsoluteDataError::Row {
            path: self.origin.to_string(),
            line: self.line,
            column: column.to_string(),
            problem,
        }
    }

    fn text(&self, name: &str) -> &str {
        self.columns
            .index
            .get(name)
            .and_then(|&i| self.record.get(i))
            .unwrap_or("")
    }

    fn present(&self, name: &str) -> bool {
        self.columns.index.contains_key(name) && !self.text(name).is_empty()
    }

    fn number(&self, name: &str, limit: f64, unit: &'static str) -> Result<f64, AbsoluteDataError> {
        let text = self.text(name);
        let value: f64 = text.parse().map_err(|_| {
            self.error(
                name,
                RowProblem::NotANumber {
                    text: text.to_string(),
                    unit,
                },
            )
        })?;
        if !value.is_finite() || value.abs() > limit {
            return Err(self.error(
                name,
                RowProblem::OutOfRange {
                    text: text.to_string(),
                    limit,
                    unit,
                },
            ));
        }
        Ok(value)
    }

    fn optional(
        &self,
        name: &str,
        limit: f64,
        unit: &'static str,
    ) -> Result<Option<f64>, AbsoluteDataError> {
        if self.present(name) {
            self.number(name, limit, unit).map(Some)
        } else {
            Ok(None)
        }
    }

    fn positive(
        &self,
        name: &str,
        limit: f64,
        unit: &'static str,
    ) -> Result<Option<f64>, AbsoluteDataError> {
        match self.optional(name, limit, unit)? {
            Some(v) if v <= 0.0 => Err(self.error(name, RowProblem::NotPositive(v))),
            other => Ok(other),
        }
    }

    fn label(&self, name: &str) -> Result<String, AbsoluteDataError> {
        let text = self.text(name);
        if text.is_empty() {
            return Err(self.error(name, RowProblem::EmptyLabel));
        }
        if text.len() > limits::MAX_LABEL_BYTES {
            return Err(self.error(name, RowProblem::LongLabel(limits::MAX_LABEL_BYTES)));
        }
        Ok(text.to_string())
    }

    fn triple(
        &self,
        names: [&str; 3],
        limit: f64,
        unit: &'static str,
    ) -> Result<[f64; 3], AbsoluteDataError> {
        let mut out = [0.0; 3];
        for (v, name) in out.iter_mut().zip(names) {
            *v = self.number(name, limit, unit)?;
        }
        Ok(out)
    }

    fn orientation(&self) -> Result<Option<RowOrientation>, AbsoluteDataError> {
        if !self.columns.orientation || !self.present(ORIENTATION[0]) {
            return Ok(None);
        }
        Ok(Some(RowOrientation {
            rotation_vector_rad: self.triple(ORIENTATION, limits::MAX_ROTATION_RAD, "rad")?,
            sigma_rad: self.positive("sigma_rad", limits::MAX_SIGMA_RAD, "rad")?,
        }))
    }

    fn payload(&self) -> Result<Option<RowPayload>, AbsoluteDataError> {
        let Some(mass_kg) = self.optional("payload_kg", limits::MAX_PAYLOAD_KG, "kg")? else {
            return Ok(None);
        };
        if mass_kg < 0.0 {
            return Err(self.error("payload_kg", RowProblem::Negative(mass_kg)));
        }
        let mut com_m = [0.0; 3];
        if self.columns.payload_com {
            for (v, name) in com_m.iter_mut().zip(PAYLOAD_COM) {
                *v = self.optional(name, limits::MAX_COM_M, "m")?.unwrap_or(0.0);
            }
        }
        Ok(Some(RowPayload { mass_kg, com_m }))
    }

    fn wrench(&self) -> Result<Option<[f64; 6]>, AbsoluteDataError> {
        if !self.columns.wrench || !self.present(WRENCH[0]) {
            return Ok(None);
        }
        let mut w = [0.0; 6];
        for (k, (value, name)) in w.iter_mut().zip(WRENCH).enumerate() {
            let (limit, unit) = if k < 3 {
                (limits::MAX_FORCE_N, "N")
            } else {
                (limits::MAX_MOMENT_NM, "N·m")
            };
            *value = self.number(name, limit, unit)?;
        }
        Ok(Some(w))
    }

    fn temperature(&self) -> Result<Option<f64>, AbsoluteDataError> {
        let range = limits::TEMPERATURE_RANGE_C;
        match self.optional("temperature_C", 1e3, "°C")? {
            Some(value) if !(range[0]..=range[1]).contains(&value) => {
                Err(self.error("temperature_C", RowProblem::Temperature { value, range }))
            }
            other => Ok(other),
        }
    }

    fn approach(&self, joint_count: usize) -> Result<Option<Vec<f64>>, AbsoluteDataError> {
        let first = format!("{APPROACH}1_rad");
        if !self.columns.approach || !self.present(&first) {
            return Ok(None);
        }
        (1..=joint_count)
            .map(|i| {
                self.number(
                    &format!("{APPROACH}{i}_rad"),
                    2.0 * limits::MAX_JOINT_RAD,
                    "rad",
                )
            })
            .collect::<Result<Vec<_>, _>>()
            .map(Some)
    }

    fn row(&self, joint_count: usize) -> Result<AbsoluteRow, AbsoluteDataError> {
        if self.record.len() != self.columns.width {
            return Err(self.error(
                "-",
                RowProblem::FieldCount {
                    expected: self.columns.width,
                    found: self.record.len(),
                },
            ));
        }
        let q_rad = (1..=joint_count)
            .map(|i| self.number(&format!("q{i}_rad"), limits::MAX_JOINT_RAD, "rad"))
            .collect::<Result<Vec<_>, _>>()?;
        let position_m = self.triple(POSITION, limits::MAX_POSITION_M, "m")?;
        let config = if self.present("config") {
            Some(self.label("config")?)
        } else {
            None
        };
        Ok(AbsoluteRow {
            line: self.line,
            setup: self.label("setup")?,
            target: self.label("target")?,
            config,
            q_rad,
            position_m,
            sigma_m: self.positive("sigma_m", limits::MAX_SIGMA_M, "m")?,
            orientation: self.orientation()?,
            payload: self.payload()?,
            wrench: self.wrench()?,
            temperature_c: self.temperature()?,
            time_s: self.optional("time_s", limits::MAX_TIME_S, "s")?,
            approach_rad: self.approach(joint_count)?,
        })
    }
}

/// Parse absolute measurement CSV text; `origin` names the file in errors. A column the format
/// does not know is an error naming the closest one ([`parse_absolute_ignoring`] skips named
/// columns).
pub fn parse_absolute(
    text: &str,
    origin: &str,
    joint_count: usize,
) -> Result<Vec<AbsoluteRow>, AbsoluteDataError> {
    parse_absolute_ignoring(text, origin, joint_count, &[])
}

/// [`parse_absolute`], skipping the columns named in `ignored` (a user's own columns, kept
/// knowingly; a column the format reads cannot be ignored). A name the file does not have is
/// not an error here: one list serves every file of a command.
pub fn parse_absolute_ignoring(
    text: &str,
    origin: &str,
    joint_count: usize,
    ignored: &[String],
) -> Result<Vec<AbsoluteRow>, AbsoluteDataError> {
    let mut reader = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .flexible(true)
        .comment(Some(b'#'))
        .from_reader(text.as_bytes());
    let columns = header(&mut reader, origin, joint_count, ignored)?;
    let mut rows = Vec::new();
    for record in reader.records() {
        let record = record.map_err(|e| AbsoluteDataError::Row {
            path: origin.to_string(),
            line: e.position().map(|p| p.line()).unwrap_or(0),
            column: "-".into(),
            problem: RowProblem::Csv(e),
        })?;
        if rows.len() >= limits::MAX_ROWS {
            return Err(AbsoluteDataError::TooManyRows {
                path: origin.to_string(),
                limit: limits::MAX_ROWS,
            });
        }
        let cells = Record {
            columns: &columns,
            record: &record,
            origin,
            line: record.position().map(|p| p.line()).unwrap_or(0),
        };
        rows.push(cells.row(joint_count)?);
    }
    if rows.is_empty() {
        return Err(AbsoluteDataError::NoRows {
            path: origin.to_string(),
        });
    }
    Ok(rows)
}
