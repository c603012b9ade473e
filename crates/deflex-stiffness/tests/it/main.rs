//! Integration tests of `deflex-stiffness`: one test binary (modules below), so a fresh clone links one
//! executable for this crate instead of one per file.

mod bad_data;
mod base_point;
mod calibration_report;
mod common;
mod consistency;
mod expected_shift;
mod fuzz;
mod plan_floor;
mod planner;
mod recovery;
mod rotation;
mod validate_atomic;
