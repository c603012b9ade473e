//! Measurement files: the crate's one reader and one error type ([`reader`], [`DataError`]),
//! used by every measurement format of the crate, and the loaded-displacement measurement and
//! plan format of the stiffness calibration (Johra et al. 2022, Section 3.1: one row per measured
//! point per load case, CSV, SI units) with the list of measured points of a plan ([`points`]).
//! The absolute tracker readings of the elasto-geometric calibration are read by the same reader
//! in [`crate::geometry::data`].
//!
//! Here: the row types, parsing from text (validated once, at parse time: every field bounded,
//! links within the arm, so code downstream never checks a row again) and formatting to text. No
//! file is touched here: reading and writing files is the job of the I/O layers (`deflex_app`'s
//! `load`, `deflex-files`).
//!
//! **The measurement and plan format.** Columns, by exact name (order free): `load_case`, `q1_rad` … `qN_rad`,
//! `fx_N, fy_N, fz_N, mx_Nm, my_Nm, mz_Nm` (applied wrench, world axes, moment about the load
//! point), `load_link`, `load_x_m, load_y_m, load_z_m` (load point, world, unloaded pose),
//! `point`, `point_link`, `x_m, y_m, z_m` (measured point, world, unloaded),
//! `dx_m, dy_m, dz_m` (displacement, loaded − unloaded, world axes).
//! A plan is the same file without the displacement columns.
//!
//! Optional columns:
//!
//! | column | unit | meaning |
//! |---|---|---|
//! | `sigma_m` | m | standard deviation of each displacement component of this row (default [`DEFAULT_SIGMA_M`], 15 µm) |
//! | `drx_rad, dry_rad, drz_rad` | rad | measured small rotation of the measured point's link, loaded − unloaded, world axes (e.g. a 6-DoF tracker probe); all three or none per row |
//! | `sigma_rad` | rad | standard deviation of each rotation component of this row (default [`DEFAULT_SIGMA_RAD`], 20 µrad); only used on rows with a rotation |
//! | `purpose` | – | free text (plans) |
//!
//! Rows with a rotation add three rotation equations to the calibration, weighted by
//! `1/sigma_rad`; rows without one are used exactly as before. Cells of optional columns may be
//! left empty.
//!
//! **Header comments.** Lines starting with `#` are comments. Those before the column names may
//! say which robot the file was made for ([`FileHeader`]): `# robot: <name>` and
//! `# geometry: <16 hex digits>` (`Robot::geometry_fingerprint`). Plans and simulated
//! measurements carry them; `calibrate` and `validate` compare them with the robot they are
//! given (`crate::stiffness::consistency`).
//!
//! **Bounds.** Every number must be finite and within a physical bound, checked with the line
//! and column named: joint values ±[`MAX_JOINT_RAD`], forces ±[`MAX_FORCE_N`], moments
//! ±[`MAX_MOMENT_NM`], coordinates ±[`MAX_COORDINATE_M`], displacements ±[`MAX_DISPLACEMENT_M`],
//! rotations ±[`MAX_ROTATION_RAD`], `sigma_m` in [[`MIN_SIGMA_M`], [`MAX_SIGMA_M`]], `sigma_rad`
//! in [[`MIN_SIGMA_RAD`], [`MAX_SIGMA_RAD`]]; labels at most [`MAX_LABEL_CHARS`] characters; a file at most
//! [`MAX_FILE_BYTES`] bytes and [`MAX_ROWS`] rows.
//!
//! [`DEFAULT_SIGMA_M`]: crate::measurements::DEFAULT_SIGMA_M
//! [`DEFAULT_SIGMA_RAD`]: crate::measurements::DEFAULT_SIGMA_RAD

mod bounds;
mod error;
mod format;
mod header;
mod parse;
pub mod points;
pub mod reader;
mod row;

pub use bounds::{
    MAX_COORDINATE_M, MAX_DISPLACEMENT_M, MAX_FILE_BYTES, MAX_FORCE_N, MAX_JOINT_RAD,
    MAX_LABEL_CHARS, MAX_MOMENT_NM, MAX_ROTATION_RAD, MAX_ROWS, MAX_SIGMA_M, MAX_SIGMA_RAD,
    MIN_SIGMA_M, MIN_SIGMA_RAD, check_row_values,
};
pub use error::{
    DataError, HeaderProblem, LabelLength, LoadCaseConflict, RowError, RowProblem, RowValueError,
    SigmaColumn,
};
pub use format::{format_rows, format_rows_for, format_rows_with_header};
pub use header::FileHeader;
pub use parse::{check_joint_columns, parse_file, parse_file_ignoring, parse_rows};
pub use row::{
    DEFAULT_SIGMA_M, DEFAULT_SIGMA_RAD, MeasuredRotation, MeasurementFile, MeasurementRow,
    load_case_count,
};
