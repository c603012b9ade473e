//! Elasto-geometric calibration from absolute tracker readings (`deflex calibrate-geometry`,
//! `deflex.calibrate_geometry`), per-row prediction (`predict`, with or without fitting the
//! set-ups), the registration of a new measuring session or probe (`register`) and the UR10
//! tracker importer (`import ur10-tracker`): the one implementation under the command line and
//! the Python package.
//!
//! Here: the files read (absolute readings, loaded displacements checked against the robot, the
//! robot's terms file), the choices (steps, loss, [`CvBy`]), the checks and refusals (which
//! set-up and target to register, too few readings, another robot's readings), the fit, the
//! files written (the robot, its terms file and the report folder as one unit: whole or not at
//! all) and the text and JSON both front ends show. The maths is `deflex_calibrate::geometry`'s,
//! the report pages [`crate::report::absolute_report`]'s. Messages name the options as the
//! front end that called does ([`OptionNames`]).
//!
//! * [`calibrate_geometry`] with [`GeometryOptions`] → [`GeometryCalibration`]; [`save`] writes
//!   it ([`SavedCalibration`], [`saved_text`], [`saved_json`]).
//! * [`predict`] with a [`CalibratedModel`] ([`load_calibrated`], [`calibrated_model`]) →
//!   [`PredictionRun`].
//! * [`register`] with a [`RegisterRequest`] → [`SessionRegistration`];
//!   [`save_registration`] writes it.
//! * [`import_ur10_tracker`] with an [`ImportRequest`] → [`TrackerImport`].

mod files;
mod fit;
mod import;
mod predict;
mod register;

pub use crate::option_names::OptionNames;
/// The option types and limits of these workflows, named here for both front ends.
pub use deflex_calibrate::geometry::{
    data::DEFAULT_ORIENTATION_SIGMA_RAD,
    fit::{HeldOutProtocol, Step},
    solve::Loss,
};
pub use deflex_calibrate::measurements::MAX_SIGMA_RAD;
pub use files::{
    CalibratedModel, MAX_TERMS_BYTES, calibrated_model, calibrated_model_of, load_calibrated,
    read_absolute, read_loaded, terms_path,
};
pub use fit::{
    BASE_STEPS, CvBy, GeometryCalibration, GeometryOptions, MAX_PLAUSIBLE_RMS_M, SESSION_GAP_S,
    SavedCalibration, calibrate_geometry, default_steps, intervals95, parse_loss, parse_steps,
    report_json, report_text, save, saved_json, saved_text, write_report,
};
pub use import::{ImportRequest, TrackerImport, import_ur10_tracker};
pub use predict::{PredictionRun, predict};
pub use register::{
    RegisterInputError, RegisterRequest, SessionRegistration, register, registration_json,
    registration_text, save_registration, saved_registration_text,
};
