//! The measurement data of a stiffness calibration or validation: where the rows come from (a
//! file or an in-memory table), and the check of every row against the robot's forward
//! kinematics that refuses another robot's data.

use crate::OptionNames;
use crate::error::{Error, Result};
use deflex_calibrate::measurements::{DataError, MeasurementFile, MeasurementRow};
use deflex_calibrate::stiffness::consistency::{
    GeometryCheck, ROWS_NAMED, check_geometry, enforce,
};
pub use deflex_calibrate::stiffness::consistency::{MAX_FK_TOLERANCE_M, MIN_FK_TOLERANCE_M};
use deflex_model::Robot;
use serde_json::{Value, json};
use std::path::PathBuf;

/// Where measurement rows come from.
#[derive(Clone, Debug)]
pub enum MeasurementSource {
    /// A CSV file.
    File(PathBuf),
    /// CSV text made from an in-memory table (a DataFrame or a mapping of columns): its rows
    /// are named by index in errors (`DataFrame row 3: …`).
    Table {
        /// The CSV text (header on the first line).
        text: String,
        /// What the table is, for messages (`DataFrame`).
        origin: String,
    },
}

impl MeasurementSource {
    /// The data as named to the user.
    pub fn name(&self) -> String {
        match self {
            MeasurementSource::File(p) => p.display().to_string(),
            MeasurementSource::Table { origin, .. } => origin.clone(),
        }
    }

    /// The data as messages show it: a file's path (control characters escaped), a table's
    /// origin.
    pub fn shown(&self) -> String {
        match self {
            MeasurementSource::File(path) => deflex_files::shown_path(path),
            MeasurementSource::Table { origin, .. } => origin.clone(),
        }
    }
}

/// The error of a table made in memory: a row's `path:line: message` re-told as
/// `origin row i: message` (the header is line 1, row 0 is line 2), any other as it is.
pub fn table_error(error: DataError) -> Error {
    match error {
        DataError::Row { path, line, error } => Error::TableRow {
            origin: path,
            row: line.saturating_sub(2),
            message: error.to_string(),
        },
        other => other.into(),
    }
}

/// Read measurement rows (displacements required when `measured`).
pub fn read_rows(
    source: &MeasurementSource,
    joint_count: usize,
    measured: bool,
) -> Result<MeasurementFile> {
    read_rows_ignoring(source, joint_count, measured, &[])
}

/// [`read_rows`], skipping the columns named in `ignored` (columns the format does not read,
/// kept knowingly; any other unknown column is refused naming the closest known one).
pub fn read_rows_ignoring(
    source: &MeasurementSource,
    joint_count: usize,
    measured: bool,
    ignored: &[String],
) -> Result<MeasurementFile> {
    match source {
        MeasurementSource::File(path) => Ok(crate::load::read_file_ignoring(
            path,
            Some(joint_count),
            measured,
            ignored,
        )?),
        MeasurementSource::Table { text, origin } => {
            deflex_calibrate::measurements::check_joint_columns(text, origin, joint_count)?;
            deflex_calibrate::measurements::parse_file_ignoring(text, origin, measured, ignored)
                .map_err(table_error)
        }
    }
}

/// How the data is checked against the robot's forward kinematics.
#[derive(Clone, Debug)]
pub struct DataCheck {
    /// Largest distance between a row's point coordinates and the forward kinematics of its
    /// joint values (m, [`MIN_FK_TOLERANCE_M`] to [`MAX_FK_TOLERANCE_M`]): more refuses the data.
    pub fk_tolerance_m: f64,
    /// Use the data even when it disagrees (the disagreement becomes a warning).
    pub ignore_fk_check: bool,
    /// Columns the format does not read, kept knowingly.
    pub ignore_columns: Vec<String>,
}

/// Named before an error of the forward-kinematics check: the file on the command line (its
/// messages name the file first), nothing in Python (the call is in the traceback).
fn check_context(source: &MeasurementSource, names: OptionNames) -> Option<String> {
    (names == OptionNames::Cli).then(|| source.name())
}

/// Named before an error of the identification: `--data FILE` on the command line, nothing in
/// Python.
pub(crate) fn fit_context(source: &MeasurementSource, names: OptionNames) -> Option<String> {
    names.context("data", &source.shown())
}

/// Said when the data disagrees with the forward kinematics: how to widen the tolerance or use
/// the data anyway, in the front end's option names.
fn fk_advice(source: &MeasurementSource, names: OptionNames) -> String {
    let data = match source {
        MeasurementSource::File(_) => "file",
        MeasurementSource::Table { .. } => "data",
    };
    format!(
        "Is this the robot the {data} was measured on? Widen the tolerance with {}, or use the {data} anyway with {}.",
        names.name("fk_tolerance_m"),
        names.switch("ignore_fk_check")
    )
}

/// `result` with its error named after `context`, when there is one.
pub(crate) fn named<T>(context: Option<&str>, result: Result<T>) -> Result<T> {
    match context {
        Some(context) => result.map_err(Error::in_context(context)),
        None => result,
    }
}

/// Rows read and checked against the robot's forward kinematics.
pub struct CheckedRows {
    /// The rows.
    pub rows: Vec<MeasurementRow>,
    /// The forward-kinematics check.
    pub check: GeometryCheck,
    /// Warnings (a mismatch used anyway, a header naming another robot).
    pub warnings: Vec<String>,
    /// The file's header comments (`SIMULATED` marks simulated data).
    pub notes: Vec<String>,
}

/// The data read (displacements required) and every point checked where the robot's forward
/// kinematics puts it: data that disagrees is refused naming its rows (or used with a warning
/// with `ignore_fk_check`), the advice in the words of the front end `names`.
pub fn read_checked(
    robot: &Robot,
    source: &MeasurementSource,
    check: &DataCheck,
    names: OptionNames,
) -> Result<CheckedRows> {
    let tolerance_m = check.fk_tolerance_m;
    if !(tolerance_m.is_finite()
        && (MIN_FK_TOLERANCE_M..=MAX_FK_TOLERANCE_M).contains(&tolerance_m))
    {
        return Err(Error::invalid(
            "fk_tolerance_m",
            format!("expected {MIN_FK_TOLERANCE_M:e} to {MAX_FK_TOLERANCE_M} m, got {tolerance_m}"),
        ));
    }
    let file = read_rows_ignoring(source, robot.joint_count(), true, &check.ignore_columns)?;
    let name = source.name();
    let geometry = named(
        check_context(source, names).as_deref(),
        check_geometry(
            robot,
            &file.rows,
            Some(&file.lines),
            Some(&file.header),
            tolerance_m,
        )
        .map_err(Error::from),
    )?;
    let warnings = enforce(
        &geometry,
        &name,
        check.ignore_fk_check,
        &fk_advice(source, names),
    )?;
    Ok(CheckedRows {
        rows: file.rows,
        check: geometry,
        warnings,
        notes: file.header.notes,
    })
}

/// The forward-kinematics check as JSON (SI; `geometry_check` of the `--json` outputs).
pub fn geometry_json(check: &GeometryCheck) -> Value {
    json!({
        "robot": check.robot,
        "geometry": check.geometry,
        "tolerance_m": check.tolerance_m,
        "rows": check.rows,
        "checked_points": check.checked_points,
        "checked_loads": check.checked_loads,
        "disagreeing_rows": check.disagreeing_rows(),
        "max_distance_m": check.max_distance_m,
        "first_disagreements": check.disagreements.iter().take(ROWS_NAMED).map(|d| json!({"row": d.row + 1, "line": d.line, "load_case": d.load_case, "point": d.point, "distance_m": d.distance_m, "text": d.to_string()})).collect::<Vec<_>>(),
        "unchecked": check.unchecked,
        "header_mismatch": check.header_mismatch,
    })
}

/// The line of the text outputs that says how well the data agreed with the forward kinematics.
pub fn geometry_text(check: &GeometryCheck) -> String {
    format!(
        "file check: {} points and {} load points agree with the forward kinematics within {:.3} mm (largest {:.3} mm)\n",
        check.checked_points,
        check.checked_loads,
        check.tolerance_m * 1e3,
        check.max_distance_m * 1e3
    )
}
