//! Stiffness calibration, the one implementation under `deflex calibrate`, `validate` and `plan`
//! and Python's `deflex.calibrate`, `validate` and `predict_displacements`:
//!
//! * [`data`]: where the rows come from ([`MeasurementSource`]: a file or an in-memory table)
//!   and their check against the robot's forward kinematics ([`read_checked`]);
//! * [`choice`]: the options' choices, one type each for both front ends ([`StructureChoice`],
//!   [`CriterionChoice`], [`LoadChoice`], [`PointsChoice`]);
//! * [`stiffness`]: the identification ([`calibrate`]: the structure search or the fixed fit,
//!   the couplings, the calibrated model named after its data) and its outputs ([`save`]: the
//!   robot file and the report folder);
//! * [`couplings`]: the off-diagonal compliances fitted after the structure;
//! * [`summary`]: the calibration as text ([`report_text`]) and JSON ([`summary_json`]);
//! * [`validate`](mod@validate): prediction errors on measured rows, their page, text and JSON;
//! * [`plan`](mod@plan): the measurement campaign, its file, text and JSON.
//!
//! The front ends convert their arguments (the CLI its flags in mm and %, checked and named in
//! its units; Python its keywords) into these options and print or return what comes back; the
//! [`crate::OptionNames`] says how each names the data and its options in messages.

pub mod choice;
pub mod couplings;
pub mod data;
pub mod plan;
pub mod stiffness;
pub mod summary;
pub mod validate;

pub use choice::{CriterionChoice, LoadChoice, PointsChoice, StructureChoice, UnknownChoice};
pub use couplings::CouplingRequest;
pub use data::{
    CheckedRows, DataCheck, MAX_FK_TOLERANCE_M, MIN_FK_TOLERANCE_M, MeasurementSource,
    geometry_json, read_checked, read_rows, read_rows_ignoring, table_error,
};
pub use stiffness::{CalibrateOptions, StiffnessCalibration, calibrate, calibrated_name, save};
pub use summary::{report_text, status_name, summary_json, written_text};
pub use validate::{
    ValidationRun, predict_displacements, validate, validation_json, validation_text,
    validation_written_text, write_validation_report,
};
