//! The stiffness calibration: identification of the VJM stiffness model from loaded
//! displacements measured by a laser tracker (Johra et al. 2022, Section 3: identification in
//! 3.1, validation in 3.2), with the automatic model-structure search and experiment planning.
//! The measurement and plan files it reads are [`crate::measurements`]'.
//!
//! * [`design`]: the design matrix of eqs. 13–15, linear in the compliances c = 1/k and
//!   quadratic in each centre shift δr;
//! * [`nnls`]: Lawson–Hanson non-negative least squares (c ≥ 0);
//! * [`stiffness_fit`]: fixed-structure calibration (positions and, when measured, link
//!   rotations) with standard errors, intervals, correlations (`uncertainty`, internal);
//! * [`coupling`]: off-diagonal compliances between eDoF pairs;
//! * [`search`]: the paper's test-model loop (Fig. 6, Tables A1/A2) automated with BIC or
//!   cross-validated error ([`crossval`], k folds by load case);
//! * [`plan`]: axis-by-axis and D-optimal experiment design, within the cell of
//!   [`campaign_cell`] (floor, table, measured points, cable or dead-weight loads, off-axis
//!   bracket);
//! * [`validation`]: prediction errors against measurements (Section 3.2; their tables, plots
//!   and page are `deflex_app::report`'s);
//! * [`synthetic`]: measurement generation from a known model (tests, benches, demos);
//! * [`consistency`]: do a file's coordinates agree with the robot's forward kinematics?
//!
//! Pure maths on data: reading files is `deflex_app::load`'s.

mod calibration;
pub mod campaign_cell;
pub mod consistency;
pub mod coupling;
pub mod crossval;
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

pub use coupling::{CouplingFit, EdofPair, fit_couplings};
pub use design::{Design, EdofId, edof_label};
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
