//! # deflex-demo
//!
//! The paper's whole study in one call, on the built-in **SIMULATED** TX200 cell (the digital
//! twin of `deflex-sim`): plan the calibration campaign, run it on the twin with tracker noise,
//! identify the model structure and stiffnesses (automatic structure search, Section 3), validate
//! on the paper's 200-pose grid at 600 N and 1100 N and on the Figure 14 spiral, and form the
//! paper's cone without and with the online correction (Section 4). Everything lands in one
//! folder: the CSV data behind every number, PNG figures and a self-contained `index.html`.
//!
//! The twin's plant is read only to *label* ground truth in the report (e.g. the plant's
//! stiffnesses beside the identified ones); the calibration sees only campaign measurements and
//! the controller sees only joint values and raw F/T samples.

mod figures;
mod page;
pub mod paper;
mod study;
mod tables;
pub mod twin_controller;

pub use study::{
    DemoOptions, DemoSummary, FormingNumbers, ModelErrorNumbers, Progress, StiffnessRow, run_demo,
};
pub use tables::paper_vs_deflex as paper_vs_deflex_rows;
