//! The tests of `deflex-calibrate`, through its public API: one test binary (one module per
//! module of the library), so a fresh clone links one executable for this package and compiles
//! the library once (it has no test build of its own).
//!
//! * [`measurements`]: the loaded-displacement measurement and plan format (round trips, error
//!   messages);
//! * [`stiffness`]: the stiffness calibration, structure search, planning and validation;
//! * [`geometry`]: the elasto-geometric calibration from absolute readings (simulated and the
//!   real UR10 laser-tracker series under `tests/data/ur10-tracker`).
//!
//! The fuzz tests of the readers live in the facade's test binary
//! (`crates/deflex/tests/it/fuzz/calibrate.rs`).

mod geometry;
mod measurements;
mod stiffness;
