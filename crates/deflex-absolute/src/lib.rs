//! # deflex-absolute
//!
//! Elasto-geometric calibration from absolute laser-tracker measurements: the robot's kinematic
//! errors (DH rows with Hayati β), where each tracker set-up stands, where each target sits on
//! the flange, the arm's sag under its own weight and payload through the VJM eDoFs, and the
//! compliances that loaded-displacement campaigns measure, identified together in one robust,
//! reduced, uncertainty-quantified least-squares fit.
//!
//! * [`data`]: the absolute measurement file format;
//! * [`ur10_tracker`]: importer for the public UR10 laser-tracker data set (Landgraf et al.,
//!   CASE 2021);
//! * [`params`]: the error parameters and the model state they correct;
//! * [`model`]: prediction and analytic Jacobians;
//! * [`identify`]: reduction to the identifiable parameter set;
//! * [`solve`]: Levenberg–Marquardt with robust (Huber/Cauchy) reweighting;
//! * [`fit`]: registration, model steps, uncertainty; [`outcome`]: what a fit produces;
//! * [`resample`]: cross-validation and bootstrap by configuration;
//! * [`report`], [`plots`]: text, JSON and HTML outputs;
//! * [`predict`]: per-row predictions of a calibrated robot file.

#![warn(missing_docs)]

pub mod campaign;
pub mod data;
pub mod fit;
pub mod identify;
pub mod model;
pub mod outcome;
pub mod params;
pub mod plots;
pub mod predict;
pub mod register;
pub mod report;
pub mod resample;
pub mod solve;
pub mod ur10_tracker;
