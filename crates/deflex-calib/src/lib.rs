//! # deflex-calib
//!
//! Identification of the VJM stiffness model from laser-tracker measurements (Johra et al. 2022,
//! Section 3): the measurement and plan file formats, calibration, the automatic model-structure
//! search, experiment planning and validation.

pub mod data;
