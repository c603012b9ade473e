//! Integration tests of `deflex-stiffness`: one test binary (modules below), so a fresh clone links one
//! executable for this crate instead of one per file.

mod bad_data;
mod base_point;
mod common;
mod consistency;
mod coupling;
mod crossval;
mod design;
mod expected_shift;
mod fuzz;
mod nnls;
mod plan_floor;
mod planner;
mod recovery;
mod rotation;
mod search;
// The calibration and validation reports (their files, plots and tables) are tested in
// deflex-report, which renders them.
