//! Reading measurement and plan CSV text with the crate's one reader ([`reader`]): the format's
//! columns are checked once, then every row is parsed and validated into a [`MeasurementRow`]
//! (every number finite and within its column's bound, links within the arm, labels non-empty
//! and short, standard deviations in range), so code downstream never checks a row again.

use crate::measurements::bounds::{
    DISPLACEMENT_COLUMNS, LOAD_POINT_COLUMNS, POINT_COLUMNS, ROTATION_COLUMNS, WRENCH_COLUMNS,
    column_bound,
};
use crate::measurements::reader::{self, Cells, Columns, MeasurementFormat, RowLimit};
use crate::measurements::{
    DataError, HeaderProblem, LabelLength, LoadCaseConflict, MAX_LABEL_CHARS, MAX_ROWS,
    MeasuredRotation, MeasurementFile, MeasurementRow, RowError, RowProblem, SigmaColumn,
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
    let format = LoadedDisplacements {
        require_displacement,
        ignored,
    };
    let file = reader::read(&format, text, origin)?;
    check_load_case_configurations(&file.rows, &file.lines, origin)?;
    Ok(file)
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

/// The measurement and plan format, as [`reader::read`] reads it: with `require_displacement`
/// (a measurement file) every row carries a displacement.
struct LoadedDisplacements<'a> {
    require_displacement: bool,
    ignored: &'a [String],
}

/// What a measurement or plan file's header holds.
struct Found {
    joint_count: usize,
    has_displacement: bool,
    has_rotation: bool,
    has_purpose: bool,
}

impl MeasurementFormat for LoadedDisplacements<'_> {
    type Row = MeasurementRow;
    type Columns = Found;
    const ROW_LIMIT: RowLimit = RowLimit::PerLine(MAX_ROWS);
    const RECORD_COLUMN: Option<&'static str> = None;

    fn columns(&self, columns: &Columns) -> Result<Found, HeaderProblem> {
        let joint_count = columns.joint_count();
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
        if self.require_displacement {
            required.extend(DISPLACEMENT_COLUMNS);
        }
        columns.require(&required)?;
        let mut known: Vec<String> = required.iter().map(|c| c.to_string()).collect();
        known.extend((1..=joint_count).map(|i| format!("q{i}_rad")));
        known.extend(
            DISPLACEMENT_COLUMNS
                .iter()
                .chain(&ROTATION_COLUMNS)
                .chain(&["sigma_m", "sigma_rad", "purpose"])
                .map(|c| c.to_string()),
        );
        columns.check_names(&known, self.ignored, |_| false)?;
        Ok(Found {
            joint_count,
            has_displacement: DISPLACEMENT_COLUMNS.iter().all(|c| columns.has(c)),
            has_rotation: ROTATION_COLUMNS.iter().all(|c| columns.has(c)),
            has_purpose: columns.has("purpose"),
        })
    }

    /// One row, every field checked (see the module documentation).
    fn row(&self, found: &Found, cells: &Cells<'_>) -> Result<MeasurementRow, RowError> {
        let number = |name: &str| {
            let (limit, unit) = column_bound(name);
            cells.number(name, limit, unit)
        };
        let triple = |names: &[&str; 3]| -> Result<[f64; 3], RowError> {
            Ok([number(names[0])?, number(names[1])?, number(names[2])?])
        };
        let link = |column: &str| link_index(cells, column, found.joint_count);
        let label = |column: &str| cells.label(column, LabelLength::Characters(MAX_LABEL_CHARS));
        let q_rad = (1..=found.joint_count)
            .map(|i| number(&format!("q{i}_rad")))
            .collect::<Result<Vec<_>, _>>()?;
        let mut wrench = [0.0; 6];
        for (value, name) in wrench.iter_mut().zip(WRENCH_COLUMNS) {
            *value = number(name)?;
        }
        let load_case = label("load_case")?;
        let point = label("point")?;
        let sigma_m = sigma(cells, SigmaColumn::Position)?;
        let displacement_m =
            if found.has_displacement && (self.require_displacement || cells.present("dx_m")) {
                Some(triple(&DISPLACEMENT_COLUMNS)?)
            } else {
                None
            };
        let rotation_rad = if found.has_rotation && cells.present("drx_rad") {
            let sigma_rad = sigma(cells, SigmaColumn::Rotation)?;
            Some(MeasuredRotation {
                value_rad: triple(&ROTATION_COLUMNS)?,
                sigma_rad,
            })
        } else {
            None
        };
        let purpose = (found.has_purpose && cells.present("purpose")).then(|| {
            cells
                .text("purpose")
                .chars()
                .take(MAX_LABEL_CHARS)
                .collect()
        });
        Ok(MeasurementRow {
            load_case,
            q_rad,
            wrench,
            load_link: link("load_link")?,
            load_point_m: triple(&LOAD_POINT_COLUMNS)?,
            point,
            point_link: link("point_link")?,
            point_m: triple(&POINT_COLUMNS)?,
            displacement_m,
            sigma_m,
            rotation_rad,
            purpose,
        })
    }
}

/// A link index 0 (base) … `joint_count` (last link).
fn link_index(cells: &Cells<'_>, column: &str, joint_count: usize) -> Result<usize, RowError> {
    let text = cells.text(column);
    let link: usize = text.parse().map_err(|_| {
        RowError::in_column(
            column,
            RowProblem::NotALink {
                text: text.to_string(),
                joint_count,
            },
        )
    })?;
    if link > joint_count {
        return Err(RowError::in_column(
            column,
            RowProblem::NoSuchLink { link, joint_count },
        ));
    }
    Ok(link)
}

/// An optional standard deviation (an empty cell or an absent column: none), in range.
fn sigma(cells: &Cells<'_>, sigma: SigmaColumn) -> Result<Option<f64>, RowError> {
    let column = sigma.column();
    if !cells.present(column) {
        return Ok(None);
    }
    let (limit, unit) = column_bound(column);
    let value = cells.number(column, limit, unit)?;
    if !sigma.accepts(value) {
        return Err(RowError::in_column(
            column,
            RowProblem::Sigma { sigma, value },
        ));
    }
    Ok(Some(value))
}
