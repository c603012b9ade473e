//! The tests of `deflex_calibrate::geometry` (the old `deflex-absolute`), through its public
//! API. Its fuzz tests are in the facade's `tests/it/fuzz/calibrate.rs`.

mod data;
mod fit_options;
mod jacobian;
mod joint_maps;
mod plausible;
mod registration;
mod simulated;
mod terms;
mod torsion;
mod ur10_real;
mod ur10_tracker;
