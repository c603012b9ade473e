//! The feed-forward table of `[feedforward]`: `compensated_path.csv` of `deflex compensate`
//! read with deflex-compensate's reader (bounded in size), every point checked to have been
//! compensated, and handed to the law as data ([`FeedForwardPoint`],
//! [`FeedForwardTable::from_points`]). Errors name the table, its line and its column.

use deflex_compensate::table::{COMPENSATION, DEFLECTION, TableError, TableRow};
use deflex_control::{
    FeedForward, FeedForwardColumn, FeedForwardConfig, FeedForwardError, FeedForwardPoint,
    FeedForwardTable,
};
use deflex_files::{FileIoError, FileTooLarge};
use deflex_model::Robot;
use std::path::Path;

/// Largest feed-forward table read (bytes): a million rows of `deflex compensate` output.
pub const MAX_TABLE_BYTES: u64 = 512 << 20;

/// A feed-forward table that cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum TableLoadError {
    /// The file cannot be opened or read.
    #[error(transparent)]
    Read(#[from] FileIoError),
    /// The file is larger than [`MAX_TABLE_BYTES`].
    #[error(transparent)]
    TooLarge(#[from] FileTooLarge),
    /// Not a compensated-path table (deflex-compensate's reader).
    #[error(transparent)]
    Csv(#[from] TableError),
    /// A point the compensation could not compensate: no program was written from this table.
    #[error(
        "{file}:{line}: point {index} has status \"{status}\": the compensation failed there and no robot program was written from this table"
    )]
    NotCompensated {
        /// The table.
        file: String,
        /// 1-based line.
        line: usize,
        /// Point index.
        index: usize,
        /// Its status.
        status: String,
    },
    /// The points cannot be a feed-forward (the law's check), at `line` of `file`.
    #[error("{file}{}: {}", line.map(|l| format!(":{l}")).unwrap_or_default(), describe(error))]
    Points {
        /// The table.
        file: String,
        /// 1-based line of the point, when the error is about one.
        line: Option<usize>,
        /// The law's error.
        error: FeedForwardError,
    },
}

/// The column of `compensated_path.csv` that holds a table quantity.
pub fn column_name(column: FeedForwardColumn) -> &'static str {
    const POSITION: [&str; 3] = ["x_m", "y_m", "z_m"];
    match column {
        FeedForwardColumn::ArcLength => "s_m",
        FeedForwardColumn::Time => "t_s",
        FeedForwardColumn::CommandedPosition(i) => POSITION.get(i).copied().unwrap_or("?"),
        FeedForwardColumn::Deflection(i) => DEFLECTION.get(i).copied().unwrap_or("?"),
        FeedForwardColumn::Compensation(i) => COMPENSATION.get(i).copied().unwrap_or("?"),
    }
}

/// The law's error with the file's column names.
fn describe(error: &FeedForwardError) -> String {
    match *error {
        FeedForwardError::NotMonotone {
            column,
            value,
            previous,
            ..
        } => format!(
            "column `{}` decreases ({value} after {previous})",
            column_name(column)
        ),
        FeedForwardError::OutOfBounds {
            column,
            value,
            limit,
            ..
        } => format!(
            "column `{}`: {value} is beyond ±{limit}",
            column_name(column)
        ),
        ref other => other.to_string(),
    }
}

/// The points of `rows` (every status `ok`), in order.
pub fn points_of(rows: &[TableRow], file: &str) -> Result<Vec<FeedForwardPoint>, TableLoadError> {
    rows.iter()
        .enumerate()
        .map(|(index, row)| {
            if row.status != "ok" {
                return Err(TableLoadError::NotCompensated {
                    file: file.to_string(),
                    line: row.line,
                    index,
                    status: row.status.clone(),
                });
            }
            Ok(FeedForwardPoint {
                arc_length_m: row.arc_length_m,
                time_s: row.time_s,
                desired_m: row.desired.translation.vector,
                deflection: row.deflection,
                compensation: row.compensation,
            })
        })
        .collect()
}

/// The table of `rows` (`deflex_compensate::table::read_csv` of `file`) for the model `robot`.
pub fn table_of(
    rows: &[TableRow],
    robot: &Robot,
    file: &str,
) -> Result<FeedForwardTable, TableLoadError> {
    let points = points_of(rows, file)?;
    FeedForwardTable::from_points(&points, robot).map_err(|error| {
        let point = match error {
            FeedForwardError::NotMonotone { point, .. }
            | FeedForwardError::OutOfBounds { point, .. } => Some(point),
            _ => None,
        };
        TableLoadError::Points {
            file: file.to_string(),
            line: point.and_then(|i| rows.get(i)).map(|r| r.line),
            error,
        }
    })
}

/// Reads `compensated_path.csv` at `path` (at most [`MAX_TABLE_BYTES`]) into a feed-forward for
/// the model `robot` with `config`.
pub fn load_feedforward(
    path: &Path,
    robot: &Robot,
    config: FeedForwardConfig,
) -> Result<FeedForward, TableLoadError> {
    let file = path.display().to_string();
    let text = deflex_files::read_bounded(path, MAX_TABLE_BYTES)
        .map_err(|e| e.reported_as::<TableLoadError>("a feed-forward table"))?;
    let rows = deflex_compensate::table::read_csv(&text, &file)?;
    let table = table_of(&rows, robot, &file)?;
    FeedForward::new(table, config).map_err(|error| TableLoadError::Points {
        file,
        line: None,
        error,
    })
}
