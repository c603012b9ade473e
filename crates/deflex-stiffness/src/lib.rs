//! # deflex-stiffness
//!
//! Identification of the VJM stiffness model from laser-tracker measurements (Johra et al. 2022,
//! Section 3): the measurement and plan file formats, calibration, the automatic model-structure
//! search, experiment planning and validation.
//!
//! * [`design`]: the design matrix of eqs. 13–15, linear in the compliances c = 1/k and
//!   quadratic in each centre shift δr;
//! * [`nnls`]: Lawson–Hanson non-negative least squares (c ≥ 0);
//! * [`fit`]: fixed-structure calibration (positions and, when measured, link rotations) with
//!   standard errors, intervals, correlations (`uncertainty`, internal);
//! * [`search`]: the paper's test-model loop (Fig. 6, Tables A1/A2) automated with BIC or
//!   cross-validated error ([`crossval`], k folds by load case);
//! * [`plan`]: axis-by-axis and D-optimal experiment design, within the cell of [`cell`]
//!   (floor, table, measured points, cable or dead-weight loads, off-axis bracket);
//! * [`validate`]: prediction errors against measurements, with plots and HTML;
//! * [`synthetic`]: measurement generation from a known model (tests, benches, demos);
//! * [`consistency`]: do a file's coordinates agree with the robot's forward kinematics?
//! * [`report`]: text tables; [`calib_report`]: the calibration's HTML report with plots.

#![warn(missing_docs)]

pub mod calib_report;
pub mod cell;
pub mod consistency;
pub mod crossval;
pub mod data;
pub mod design;
pub mod fit;
pub mod nnls;
pub mod plan;
pub mod report;
pub mod search;
mod shift;
pub mod synthetic;
mod uncertainty;
pub mod validate;

pub use data::{
    DataError, FileHeader, MeasuredRotation, MeasurementFile, MeasurementRow, format_rows_for,
    read_file, read_for_robot, read_measurements, read_plan, write_rows, write_rows_for,
};
pub use design::{DEFAULT_SIGMA_M, DEFAULT_SIGMA_RAD, Design, EdofId, edof_label};
pub use fit::{
    Calibration, EdofEstimate, ResidualStats, ShiftEstimate, Status, Structure, calibrate_fixed,
};
pub use search::{Criterion, SearchOptions, SearchResult, SearchStep, search_structure};

/// Whether every entry of a matrix is finite: checked before any decomposition, since an SVD or
/// eigen-decomposition of a matrix holding NaN may not terminate.
pub(crate) fn all_finite(m: &nalgebra::DMatrix<f64>) -> bool {
    m.iter().all(|v| v.is_finite())
}

/// Why a calibration, plan or validation could not be done. Messages are meant for the user.
#[derive(Debug, thiserror::Error)]
pub enum CalibError {
    /// Bad file.
    #[error(transparent)]
    Data(#[from] DataError),
    /// Data or request that cannot be used, with the reason.
    #[error("{0}")]
    Invalid(String),
    /// A file's rows do not match the robot's forward kinematics (another robot's file?).
    #[error("{0}")]
    GeometryMismatch(Box<consistency::GeometryMismatch>),
}
