//! The tests of `deflex-absolute`, through its public API: one test binary (modules below), so a
//! fresh clone links one executable for this crate instead of one per file, and compiles the
//! library once (it has no test build of its own).

mod data;
mod fit_options;
mod fuzz;
mod jacobian;
mod joint_maps;
mod registration;
mod simulated;
mod terms;
mod torsion;
mod ur10_real;
mod ur10_tracker;
