//! The joint path a FANUC Stream Motion link streams ([`deflex_io::fanuc_stream`]): the joints
//! of `compensated_path.csv` (`q1_rad … q6_rad`, the commanded poses' IK that `deflex compensate`
//! writes) timed by its `t_s` (the program's feeds), sampled every controller cycle with
//! jerk-limited start and stop ([`StreamTrajectory::from_waypoints`]) and checked against the
//! path's share of the stream's limits. Every point must have been compensated (`status` `ok`).

use crate::table::{CsvTable, TableColumn};
use deflex_io::fanuc_stream::motion::{AXES, StreamLimits, StreamTrajectory, TrajectoryError};
use std::path::Path;

/// Why a compensated path cannot be streamed.
#[derive(Debug, thiserror::Error)]
pub enum StreamPathError {
    /// The table cannot be read.
    #[error(transparent)]
    Table(#[from] Box<crate::Error>),
    /// A column is missing or not numeric.
    #[error("{file}: column `{column}` is missing or not numeric")]
    Column {
        /// The table.
        file: String,
        /// The column.
        column: &'static str,
    },
    /// The table has another number of joints than a Stream Motion arm's six.
    #[error("{file}: {joints} joint columns (q1_rad …); Stream Motion streams six-axis arms")]
    JointCount {
        /// The table.
        file: String,
        /// Its joint columns.
        joints: usize,
    },
    /// A point the compensation failed at.
    #[error("{file}: point {index} has status \"{status}\": not compensated, not streamed")]
    NotCompensated {
        /// The table.
        file: String,
        /// Point index (0-based row).
        index: usize,
        /// Its status.
        status: String,
    },
    /// The points cannot be a trajectory (times, values, limits).
    #[error("{file}: {error}")]
    Trajectory {
        /// The table.
        file: String,
        /// Why.
        error: TrajectoryError,
    },
}

const JOINTS: [&str; AXES] = ["q1_rad", "q2_rad", "q3_rad", "q4_rad", "q5_rad", "q6_rad"];

fn numbers<'a>(
    t: &'a CsvTable,
    file: &str,
    column: &'static str,
) -> Result<&'a [f64], StreamPathError> {
    match t.columns.iter().find(|(name, _)| name == column) {
        Some((_, TableColumn::Number(v))) => Ok(v),
        _ => Err(StreamPathError::Column {
            file: file.to_string(),
            column,
        }),
    }
}

/// The trajectory of the compensated-path table `table` (read from `file`), sampled every
/// `period_s` with start and stop ramps of `ramp_s`, within `limits` (the path's share).
pub fn stream_trajectory_of(
    table: &CsvTable,
    file: &str,
    period_s: f64,
    ramp_s: f64,
    limits: &StreamLimits,
) -> Result<StreamTrajectory, StreamPathError> {
    let joints = table
        .columns
        .iter()
        .filter(|(name, _)| {
            name.strip_prefix('q')
                .and_then(|r| r.strip_suffix("_rad"))
                .is_some_and(|n| n.parse::<usize>().is_ok())
        })
        .count();
    if joints != AXES {
        return Err(StreamPathError::JointCount {
            file: file.to_string(),
            joints,
        });
    }
    if let Some((_, TableColumn::Text(status))) = table.columns.iter().find(|(n, _)| n == "status")
        && let Some((index, s)) = status.iter().enumerate().find(|(_, s)| *s != "ok")
    {
        return Err(StreamPathError::NotCompensated {
            file: file.to_string(),
            index,
            status: s.clone(),
        });
    }
    let time = numbers(table, file, "t_s")?;
    let q: Vec<&[f64]> = JOINTS
        .iter()
        .map(|c| numbers(table, file, c))
        .collect::<Result<_, _>>()?;
    let waypoints: Vec<(f64, [f64; AXES])> = (0..table.rows)
        .map(|r| (time[r], std::array::from_fn(|i| q[i][r])))
        .collect();
    StreamTrajectory::from_waypoints(period_s, ramp_s, &waypoints, limits).map_err(|error| {
        StreamPathError::Trajectory {
            file: file.to_string(),
            error,
        }
    })
}

/// [`stream_trajectory_of`] the table at `path` (`compensated_path.csv`).
pub fn stream_trajectory(
    path: &Path,
    period_s: f64,
    ramp_s: f64,
    limits: &StreamLimits,
) -> Result<StreamTrajectory, StreamPathError> {
    let table = crate::table::read(path).map_err(Box::new)?;
    stream_trajectory_of(
        &table,
        &path.display().to_string(),
        period_s,
        ramp_s,
        limits,
    )
}
