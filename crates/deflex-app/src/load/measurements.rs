//! Measurement, plan and point files from disk (the formats are `deflex_calibrate::measurements`').

use deflex_calibrate::measurements::points::{
    MAX_POINTS_FILE_BYTES, PointSpec, PointsError, parse_points,
};
use deflex_calibrate::measurements::{
    DataError, MAX_FILE_BYTES, MeasurementFile, MeasurementRow, check_joint_columns,
    parse_file_ignoring,
};
use std::path::Path;

/// Read a measurement (or plan) file with its header comments and row line numbers. With
/// `joint_count`, a file written for another joint count is reported as such before any
/// row-level check. Files over [`MAX_FILE_BYTES`] are not read.
pub fn read_file(
    path: &Path,
    joint_count: Option<usize>,
    require_displacement: bool,
) -> Result<MeasurementFile, DataError> {
    read_file_ignoring(path, joint_count, require_displacement, &[])
}

/// [`read_file`], skipping the columns named in `ignored` (columns unknown to the format:
/// `deflex_calibrate::measurements::parse_file_ignoring`).
pub fn read_file_ignoring(
    path: &Path,
    joint_count: Option<usize>,
    require_displacement: bool,
    ignored: &[String],
) -> Result<MeasurementFile, DataError> {
    let origin = path.display().to_string();
    let text = deflex_files::read_bounded(path, MAX_FILE_BYTES)
        .map_err(|e| e.reported_as::<DataError>("a measurement file"))?;
    if let Some(joint_count) = joint_count {
        check_joint_columns(&text, &origin, joint_count)?;
    }
    parse_file_ignoring(&text, &origin, require_displacement, ignored)
}

/// Read a measurement (or plan) file for a robot with `joint_count` joints: like
/// [`read_measurements`] / [`read_plan`], but a file written for a different joint count is
/// reported as such ("the data has 5 joint columns … but the robot has 6 joints") before any
/// row-level check.
pub fn read_for_robot(
    path: &Path,
    joint_count: usize,
    require_displacement: bool,
) -> Result<Vec<MeasurementRow>, DataError> {
    Ok(read_file(path, Some(joint_count), require_displacement)?.rows)
}

/// Read a measurement file: every row must carry the displacement columns.
pub fn read_measurements(path: &Path) -> Result<Vec<MeasurementRow>, DataError> {
    Ok(read_file(path, None, true)?.rows)
}

/// Read a plan file: displacement columns are not expected (read when present).
pub fn read_plan(path: &Path) -> Result<Vec<MeasurementRow>, DataError> {
    Ok(read_file(path, None, false)?.rows)
}

/// Read measured points from a CSV file with columns `name, link, x_m, y_m, z_m` (position in
/// the link's frame; `#` comments) for a robot with `joint_count` joints.
pub fn read_points(path: &Path, joint_count: usize) -> Result<Vec<PointSpec>, PointsError> {
    let origin = path.display().to_string();
    let text = deflex_files::read_bounded(path, MAX_POINTS_FILE_BYTES)
        .map_err(|e| e.reported_as::<PointsError>("a list of points"))?;
    parse_points(&text, &origin, joint_count)
}
