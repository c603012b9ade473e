//! Lists of measured points for a plan (`deflex plan --points FILE`, `--point NAME,LINK,X,Y,Z`):
//! each a label, the link carrying it and its position in that link's frame. CSV columns
//! `name, link, x_m, y_m, z_m` (`#` comments), at most [`MAX_USER_POINTS`] rows.

use deflex_files::{FileIoError, FileTooLarge};
use thiserror::Error;

/// Most measured points per load case given by the user.
pub const MAX_USER_POINTS: usize = 32;
/// Largest points file read (bytes).
pub const MAX_POINTS_FILE_BYTES: u64 = 1 << 20;
/// Largest |coordinate| of a point in its link's frame (m).
pub const MAX_POINT_COORDINATE_M: f64 = 10.0;
/// The columns of a points file, in order.
pub const POINTS_COLUMNS: [&str; 5] = ["name", "link", "x_m", "y_m", "z_m"];

/// A measured point fixed to a link, given in that link's frame (R_link; link 0 = R0).
#[derive(Clone, Debug, PartialEq)]
pub struct PointSpec {
    /// Label in the plan (`M1`, `R2`, …).
    pub name: String,
    /// Link carrying it (0 = base … N = last link).
    pub link: usize,
    /// Position in the link frame (m).
    pub position_m: [f64; 3],
}

/// What is wrong with one point (a row of a points file or a `--point` flag).
#[derive(Clone, Debug, PartialEq, Error)]
pub enum PointProblem {
    /// A `--point` flag without five fields.
    #[error("expected NAME,LINK,X,Y,Z (metres in the link's frame), got {found} fields")]
    FieldCount {
        /// Fields given.
        found: usize,
    },
    /// An empty, long or comma-holding name.
    #[error("`name`: a label of 1 to 32 characters without commas")]
    BadName,
    /// `TCP` or `BR`.
    #[error("`name`: \"{name}\" is reserved (the TCP and the bracket are measured anyway)")]
    ReservedName {
        /// The name.
        name: String,
    },
    /// Not a link of the arm.
    #[error("`link`: expected 0 (base) … {joint_count} (last link), got \"{text}\"")]
    BadLink {
        /// The text given (at most 20 characters of it).
        text: String,
        /// Joints of the robot.
        joint_count: usize,
    },
    /// Not a coordinate within ±[`MAX_POINT_COORDINATE_M`].
    #[error("`{column}`: expected a number of metres within ±10 m, got \"{text}\"")]
    BadCoordinate {
        /// `x_m`, `y_m` or `z_m`.
        column: &'static str,
        /// The text given (at most 20 characters of it).
        text: String,
    },
    /// More rows than [`MAX_USER_POINTS`].
    #[error("more than {max} points")]
    TooMany {
        /// The limit.
        max: usize,
    },
}

/// A bad points file.
#[derive(Debug, Error)]
pub enum PointsError {
    /// The file could not be read (built by the crates that touch the disk).
    #[error(transparent)]
    Io(#[from] FileIoError),
    /// The file is larger than [`MAX_POINTS_FILE_BYTES`] (the reader names it
    /// `a list of points`).
    #[error(transparent)]
    TooLarge(#[from] FileTooLarge),
    /// The header line could not be read.
    #[error("{path}: header: {source}")]
    HeaderCsv {
        /// File.
        path: String,
        /// The CSV reader's error.
        source: csv::Error,
    },
    /// The columns are not [`POINTS_COLUMNS`].
    #[error("{path}: header: expected the columns name, link, x_m, y_m, z_m")]
    Header {
        /// File.
        path: String,
    },
    /// A line could not be read as CSV.
    #[error("{path}: {source}")]
    Csv {
        /// File.
        path: String,
        /// The CSV reader's error.
        source: csv::Error,
    },
    /// A bad row.
    #[error("{path}:{line}: {problem}")]
    Row {
        /// File.
        path: String,
        /// 1-based line.
        line: u64,
        /// What is wrong.
        problem: PointProblem,
    },
}

/// Parse the text of a points file for a robot with `joint_count` joints; `origin` names the
/// file in errors.
pub fn parse_points(
    text: &str,
    origin: &str,
    joint_count: usize,
) -> Result<Vec<PointSpec>, PointsError> {
    let mut reader = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .comment(Some(b'#'))
        .from_reader(text.as_bytes());
    let headers = reader
        .headers()
        .map_err(|source| PointsError::HeaderCsv {
            path: origin.to_string(),
            source,
        })?
        .clone();
    if headers.iter().collect::<Vec<_>>() != POINTS_COLUMNS {
        return Err(PointsError::Header {
            path: origin.to_string(),
        });
    }
    let mut out = Vec::new();
    for record in reader.records() {
        let record = record.map_err(|source| PointsError::Csv {
            path: origin.to_string(),
            source,
        })?;
        let line = record.position().map(|p| p.line()).unwrap_or(0);
        let error = |problem: PointProblem| PointsError::Row {
            path: origin.to_string(),
            line,
            problem,
        };
        if out.len() >= MAX_USER_POINTS {
            return Err(error(PointProblem::TooMany {
                max: MAX_USER_POINTS,
            }));
        }
        let field = |i: usize| record.get(i).unwrap_or("");
        let spec = point_spec(
            field(0),
            field(1),
            [field(2), field(3), field(4)],
            joint_count,
        )
        .map_err(error)?;
        out.push(spec);
    }
    Ok(out)
}

/// Parse a point given on the command line as `NAME,LINK,X,Y,Z` (m, link frame).
pub fn parse_point_flag(text: &str, joint_count: usize) -> Result<PointSpec, PointProblem> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    if parts.len() != 5 {
        return Err(PointProblem::FieldCount { found: parts.len() });
    }
    point_spec(
        parts[0],
        parts[1],
        [parts[2], parts[3], parts[4]],
        joint_count,
    )
}

fn point_spec(
    name: &str,
    link: &str,
    xyz: [&str; 3],
    joint_count: usize,
) -> Result<PointSpec, PointProblem> {
    if name.is_empty() || name.chars().count() > 32 || name.contains(',') {
        return Err(PointProblem::BadName);
    }
    if name == "TCP" || name == "BR" {
        return Err(PointProblem::ReservedName {
            name: name.to_string(),
        });
    }
    let link: usize = link
        .parse()
        .ok()
        .filter(|&l| l <= joint_count)
        .ok_or_else(|| PointProblem::BadLink {
            text: link.chars().take(20).collect(),
            joint_count,
        })?;
    let mut position_m = [0.0; 3];
    for (axis, (value, column)) in xyz.iter().zip(["x_m", "y_m", "z_m"]).enumerate() {
        position_m[axis] = value
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite() && v.abs() <= MAX_POINT_COORDINATE_M)
            .ok_or_else(|| PointProblem::BadCoordinate {
                column,
                text: value.chars().take(20).collect(),
            })?;
    }
    Ok(PointSpec {
        name: name.to_string(),
        link,
        position_m,
    })
}
