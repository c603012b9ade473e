//! # deflex-calibrate
//!
//! Calibration of a robot from measurements:
//!
//! * [`measurements`]: the loaded-displacement measurement and plan formats (CSV, SI units);
//! * [`stiffness`]: the stiffness of the VJM model from loaded displacements (Johra et al. 2022,
//!   Section 3): calibration, structure search, experiment planning, validation;
//! * [`geometry`]: the elasto-geometric calibration from absolute laser-tracker readings.

#![warn(missing_docs)]

pub mod geometry;
pub mod measurements;
pub mod stiffness;
