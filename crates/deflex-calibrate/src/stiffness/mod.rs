//! # deflex-stiffness
//!
//! Identification of the VJM stiffness model from laser-tracker measurements (Johra et al. 2022,
//! Section 3): the measurement and plan file formats, calibration, the automatic model-structure
//! search, experiment planning and validation.
//!
//! * [`design`]: the design matrix of eqs. 13–15, linear in the compliances c = 1/k and
//!   quadratic in each centre shift δr;
//! * [`nnls`]: Lawson–Hanson non-negative least squares (c ≥ 0);
//! * [`stiffness_fit`]: fixed-structure calibration (positions and, when measured, link rotations) with
//!   standard errors, intervals, correlations (`uncertainty`, internal);
//! * [`search`]: the paper's test-model loop (Fig. 6, Tables A1/A2) automated with BIC or
//!   cross-validated error ([`crossval`], k folds by load case);
//! * [`plan`]: axis-by-axis and D-optimal experiment design, within the cell of [`campaign_cell`]
//!   (floor, table, measured points, cable or dead-weight loads, off-axis bracket);
//! * [`validation`]: prediction errors against measurements (their report is `deflex-report`'s);
//! * [`synthetic`]: measurement generation from a known model (tests, benches, demos);
//! * [`consistency`]: do a file's coordinates agree with the robot's forward kinematics?
//!
//! The measurement and plan formats are `deflex-measurements`' (re-exported as [`data`]); the
//! tables, plots and HTML of a calibration are `deflex-report`'s; reading files is
//! `deflex-load`'s. This crate takes and returns data.

#![warn(missing_docs)]

pub mod calibration;
pub mod campaign_cell;
pub mod consistency;
pub mod coupling;
pub mod crossval;
pub use crate::measurements as data;
pub mod design;
mod error;
pub mod nnls;
pub mod plan;
pub mod search;
mod shift;
pub mod stiffness_fit;
pub mod synthetic;
mod uncertainty;
pub mod validation;

pub use crate::measurements::{
    DataError, FileHeader, MeasuredRotation, MeasurementFile, MeasurementRow, format_rows,
    format_rows_for,
};
pub use coupling::{CouplingFit, EdofPair, fit_couplings};
pub use design::{DEFAULT_SIGMA_M, DEFAULT_SIGMA_RAD, Design, EdofId, edof_label};
pub use error::{CalibError, DirectionError, PlanError, RowRef, RowsError, StructureError};
pub use search::{Criterion, SearchOptions, SearchResult, SearchStep, search_structure};
pub use shift::MAX_SHIFT_M;
pub use stiffness_fit::{
    Calibration, EdofEstimate, ResidualStats, ShiftEstimate, Status, Structure, calibrate_fixed,
};

/// Whether every entry of a matrix is finite: checked before any decomposition, since an SVD or
/// eigen-decomposition of a matrix holding NaN may not terminate.
pub(crate) fn all_finite(m: &nalgebra::DMatrix<f64>) -> bool {
    m.iter().all(|v| v.is_finite())
}
