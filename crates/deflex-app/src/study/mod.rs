//! # The paper's study on the twin (`deflex demo`)
//!
//! The paper's whole study in one call, on the **SIMULATED** cell of the built-in TX200 or of any
//! other 6-joint robot (the digital twin of `deflex-sim`, with every error source of a real cell
//! on): plan the calibration campaign, run it on the twin with tracker noise, identify the model
//! structure and stiffnesses (automatic structure search, Section 3), validate on a grid of
//! dead-weight loads (the paper's 200-pose grid at 600 N and 1100 N for the TX200) and along a
//! spiral (Figure 14), form the paper's cone without and with the online correction (Section 4),
//! plunge into a stiff fixture without and with it ([`contact`]), and measure the sensitivity of
//! the closed loop to delay, model scale, sensor gain, bias drift and contact stiffness
//! ([`sensitivity`]), and compare offline compensation, online correction and both on the cone and
//! a CAM part ([`compensation`]).
//!
//! [`run_study`] computes it all in memory and returns it as a [`Study`]; the CSV data behind
//! every number, the PNG figures and the self-contained `index.html` are written by
//! `crate::report::study::write_study`; [`demo`] does both for `deflex demo`, and
//! [`summary_text`] and [`summary_json`] are what it shows.
//!
//! The twin's plant is read only to *label* ground truth in the report (e.g. the plant's
//! stiffnesses beside the identified ones); the calibration sees only campaign measurements and
//! the controller sees only joint values and raw F/T samples.

#![warn(missing_docs)]

pub mod compensation;
mod conditions;
pub mod contact;
mod demo;
mod error;
pub mod fig7;
pub mod numbers;
pub mod paper;
mod pipeline;
pub mod sensitivity;
mod summary;

pub use conditions::{conditions, one_edof_start};
pub use demo::{demo, summary_json, summary_text};
pub use error::DemoError;
pub use numbers::paper_vs_deflex as paper_vs_deflex_rows;
pub use pipeline::{DemoOptions, Predictions, STAGES, Study, run_study};
pub use summary::{
    BASELINE, DemoSummary, FormingNumbers, IDENTIFIED, ModelErrorNumbers, StiffnessRow, TABLE1,
};
