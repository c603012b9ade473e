//! The files of the elasto-geometric workflows: absolute readings, loaded displacements checked
//! against the robot, the calibrated robot with its terms file (read, and written with the
//! report as one unit).

use super::OptionNames;
use crate::calibrate::{MeasurementSource, table_error};
use crate::error::{Error, Result};
use deflex_calibrate::geometry::data::{AbsoluteRow, limits, parse_absolute_ignoring};
use deflex_calibrate::geometry::params::EgModel;
use deflex_calibrate::geometry::terms::CalibrationTerms;
use deflex_calibrate::measurements::{MeasurementRow, check_joint_columns, parse_file_ignoring};
use deflex_calibrate::stiffness::consistency::{DEFAULT_FK_TOLERANCE_M, check_geometry, enforce};
use deflex_model::Robot;
use std::io::Write as _;
use std::path::{Path, PathBuf};

/// Largest terms file read (bytes).
pub const MAX_TERMS_BYTES: u64 = 64 << 20;

/// Several data as messages show them, comma-separated.
pub(super) fn shown_all(sources: &[MeasurementSource]) -> String {
    sources
        .iter()
        .map(MeasurementSource::shown)
        .collect::<Vec<_>>()
        .join(", ")
}

/// Absolute readings of one source for a robot of `joints` joints, skipping the columns named in
/// `ignored` (unknown to the format, kept knowingly: `--ignore-column`).
pub fn read_absolute(
    source: &MeasurementSource,
    joints: usize,
    ignored: &[String],
) -> Result<Vec<AbsoluteRow>> {
    match source {
        MeasurementSource::File(path) => {
            let text = deflex_files::read_bounded(path, limits::MAX_FILE_BYTES)?;
            Ok(parse_absolute_ignoring(
                &text,
                &path.display().to_string(),
                joints,
                ignored,
            )?)
        }
        MeasurementSource::Table { text, origin } => {
            parse_absolute_ignoring(text, origin, joints, ignored).map_err(table_error)
        }
    }
}

/// Loaded displacements (the `deflex calibrate` format) to fit with absolute readings. They are
/// in the robot's world, so they are checked against its forward kinematics as `calibrate`
/// checks them: another robot's campaign is refused.
pub fn read_loaded(
    robot: &Robot,
    source: &MeasurementSource,
    ignored: &[String],
    names: OptionNames,
) -> Result<Vec<MeasurementRow>> {
    let n = robot.joint_count();
    let file = match source {
        MeasurementSource::File(path) => {
            crate::load::read_file_ignoring(path, Some(n), true, ignored)?
        }
        MeasurementSource::Table { text, origin } => {
            check_joint_columns(text, origin, n)?;
            parse_file_ignoring(text, origin, true, ignored).map_err(table_error)?
        }
    };
    let origin = source.shown();
    let check = check_geometry(
        robot,
        &file.rows,
        Some(&file.lines),
        Some(&file.header),
        DEFAULT_FK_TOLERANCE_M,
    )
    .map_err(|e| Error::in_context(origin.clone())(e.into()))?;
    let hint = format!(
        "Is this the robot the loaded campaign was measured on? Give the robot with {}.",
        names.give("robot")
    );
    enforce(&check, &origin, false, &hint)?;
    Ok(file.rows)
}

/// The terms file beside a calibrated robot file: `NAME.toml` → `NAME.terms.json`.
pub fn terms_path(robot_file: &Path) -> PathBuf {
    robot_file.with_extension("terms.json")
}

/// A calibrated model for prediction and registration: the robot and, when it was read from a
/// file with a `NAME.terms.json` beside it (or comes from a calibration), the joint terms and
/// residual model it keeps.
pub struct CalibratedModel {
    /// The model with its terms applied.
    pub model: EgModel,
    /// The terms, when there are any.
    pub terms: Option<CalibrationTerms>,
    /// The terms file's text, written unchanged beside a robot registered from this one.
    pub terms_text: Option<String>,
}

/// [`CalibratedModel`] of a robot; `file` is the robot file it was loaded from, whose terms
/// file is read when both are files.
pub fn calibrated_model(robot: &Robot, file: Option<&Path>) -> Result<CalibratedModel> {
    let mut model = EgModel::from_robot(robot);
    let Some(terms_file) = file
        .filter(|p| p.is_file())
        .map(terms_path)
        .filter(|p| p.is_file())
    else {
        return Ok(CalibratedModel {
            model,
            terms: None,
            terms_text: None,
        });
    };
    let text = deflex_files::read_bounded(&terms_file, MAX_TERMS_BYTES)?;
    let in_file = |source| Error::Terms {
        path: terms_file.display().to_string(),
        source,
    };
    let terms = CalibrationTerms::from_json(&text).map_err(in_file)?;
    terms.apply(&mut model).map_err(in_file)?;
    Ok(CalibratedModel {
        model,
        terms: Some(terms),
        terms_text: Some(text),
    })
}

/// [`CalibratedModel`] of a robot given as the command line gives it: a built-in name or a
/// robot file (with its terms file beside it when there is one).
pub fn load_calibrated(spec: &str) -> Result<CalibratedModel> {
    let robot = crate::load::load_robot(spec)?;
    calibrated_model(&robot, Some(Path::new(spec)))
}

/// [`CalibratedModel`] of a calibration just made (its terms applied).
pub fn calibrated_model_of(cal: &super::GeometryCalibration) -> Result<CalibratedModel> {
    let mut model = EgModel::from_robot(&cal.robot);
    cal.terms.apply(&mut model).map_err(|source| Error::Terms {
        path: "the calibration's terms".into(),
        source,
    })?;
    Ok(CalibratedModel {
        model,
        terms: Some(cal.terms.clone()),
        terms_text: Some(cal.terms.to_json().map_err(|e| Error::Serialise {
            what: "the terms file",
            reason: e.to_string(),
        })?),
    })
}

/// A file written aside, renamed in by its commit.
fn staged(path: &Path, text: &str) -> Result<deflex_files::AtomicFile> {
    let mut file = deflex_files::AtomicFile::create(path).map_err(Error::io_on(path))?;
    file.write_all(text.as_bytes())
        .and_then(|()| file.flush())
        .map_err(Error::io_on(path))?;
    Ok(file)
}

/// Write a robot file, its terms file beside it (when there are terms) and a report as one
/// unit: the robot and terms are written aside first, the report (`write_report`, itself whole
/// or not at all) swapped in, and only then the terms and robot renamed in. A report that fails
/// (a full disk) leaves the earlier robot, terms and report as they were. Returns the report's
/// files.
pub(super) fn write_unit(
    robot: &Robot,
    terms: Option<&str>,
    path: &Path,
    write_report: impl FnOnce() -> Result<Vec<PathBuf>>,
) -> Result<Vec<PathBuf>> {
    let terms_file = terms_path(path);
    let terms_staged = terms.map(|text| staged(&terms_file, text)).transpose()?;
    let robot_staged = staged(path, &crate::robot::to_toml(robot, Some(path)))?;
    let report_files = write_report()?;
    if let Some(file) = terms_staged {
        file.commit().map_err(Error::io_on(&terms_file))?;
    }
    robot_staged.commit().map_err(Error::io_on(path))?;
    Ok(report_files)
}
