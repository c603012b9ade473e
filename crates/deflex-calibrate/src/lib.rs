//! Calibration of a robot from measurements, in three parts:
//!
//! * [`stiffness`]: the stiffness of the VJM model from loaded displacements (Johra et al. 2022,
//!   Section 3): calibration, structure search, experiment planning, validation;
//! * [`geometry`]: the elasto-geometric calibration from absolute laser-tracker readings
//!   (kinematic errors, set-ups, targets, sag and compliances in one fit; set-up registration,
//!   held-out scoring, prediction);
//! * [`measurements`]: their measurement files (CSV, SI units): one reader and one error type for
//!   every format, the loaded-displacement measurement and plan format, the points of a plan
//!   (the absolute format is [`geometry::data`]);
//!
//! and [`stats`], the error statistics both calibrations report (metres or radians).
//!
//! Pure maths on data: reading files from disk, reports and plots are `deflex_app`'s.

#![warn(missing_docs)]

pub mod geometry;
pub mod measurements;
pub mod stats;
pub mod stiffness;
