//! The tests of `deflex-cam`, through its public API: one test binary (one module per module of
//! the library), so a fresh clone links one executable for this package and compiles the
//! library once (it has no test build of its own).
//!
//! * [`gcode`]: the G-code reader against the corpus in `docs/parts/` (and `tests/data/`), what
//!   it refuses, one line into words, the arc geometry;
//! * [`program`]: every exporter read back, streaming to files, the arm configuration words,
//!   names, comment wrapping (the orientation conventions are tested in `deflex-model`, which
//!   holds them);
//! * [`export`]: the calibrated robot written as URDF, a UR calibration file or a DH table and
//!   read back.
//!
//! The fuzz test of the G-code reader lives in the facade's test binary
//! (`crates/deflex/tests/it/fuzz/cam.rs`).

mod export;
mod gcode;
mod program;
