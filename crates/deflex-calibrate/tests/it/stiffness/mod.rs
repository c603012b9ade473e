//! The tests of `deflex_calibrate::stiffness` (the old `deflex-stiffness`), through its public
//! API. Its fuzz tests are in the facade's `tests/it/fuzz/calibrate.rs`.

mod bad_data;
mod base_point;
mod common;
mod consistency;
mod coupling;
mod crossval;
mod design;
mod expected_shift;
mod nnls;
mod plan_floor;
mod planner;
mod recovery;
mod rotation;
mod search;
// The calibration and validation reports (their files, plots and tables) are tested in
// deflex-app (`deflex_app::report`), which renders them.
