//! The elasto-geometric calibration from absolute laser-tracker readings (beyond Johra et al.
//! 2022, whose Section 3 identifies stiffness alone; validated on the public UR10 data set of
//! Landgraf et al., CASE 2021): the robot's kinematic errors (DH rows with Hayati β), where each
//! tracker set-up stands, where each target sits on the flange (and how its frame is turned, from
//! measured orientations), the arm's sag under its own weight and payload through the VJM eDoFs,
//! the compliances that loaded-displacement campaigns measure, and opt-in joint terms and a
//! residual model that must earn their place on held-out data, identified together in one
//! robust, reduced, uncertainty-quantified least-squares fit. Pure maths on data: no files, no
//! plots (`deflex_app` and the front ends do those).
//!
//! * [`data`]: the absolute measurement format (parse, with the crate's one reader
//!   [`crate::measurements::reader`], and format);
//! * [`ur10_tracker`]: importer for the public UR10 laser-tracker data set (Landgraf et al.,
//!   CASE 2021);
//! * [`params`]: the error parameters and the model state they correct;
//! * [`model`]: predictions; [`jacobian`]: their analytic Jacobians;
//! * [`campaign`]: readings resolved against a model;
//! * [`identify`]: reduction to the identifiable parameter set;
//! * [`solve`]: Levenberg–Marquardt with robust (Huber/Cauchy) reweighting;
//! * [`fit`]: registration, model steps, held-out acceptance, uncertainty, and what a fit
//!   produces ([`fit::FitResult`]; its error statistics are [`crate::stats::ErrorNormStats`]);
//! * [`plausible`]: how far a calibration may move a robot from its nominal geometry;
//! * [`register`]: a new session or probe registered from a few readings, robot frozen;
//! * [`protocol`]: the held-out protocol (register from some readings, score the rest);
//! * [`residual_model`]: a Gaussian-process residual model on the joint angles;
//! * [`joint_maps`]: joint-angle error maps (each joint's angle error as a smooth function of
//!   its own angle, learnt from the residuals);
//! * [`terms`]: what a calibration keeps beyond the robot file;
//! * [`resample`]: cross-validation and bootstrap by configuration;
//! * [`predict`]: per-row predictions of a calibrated model.

pub mod campaign;
pub mod data;
pub mod fit;
pub mod identify;
pub mod jacobian;
pub mod joint_maps;
pub mod model;
mod outcome;
pub mod params;
pub mod plausible;
pub mod predict;
pub mod protocol;
pub mod register;
pub mod resample;
pub mod residual_model;
pub mod solve;
pub mod terms;
pub mod ur10_tracker;
