//! deflex-py's Rust tests: the engine layer (plain Rust, no Python), a module per domain. The
//! Python package's own tests are in `tests/python`, run by `scripts/test-python`.

mod calibration;
mod compensation;
mod error;
mod geometry;
mod model;
mod table;
mod twin;
