//! Integration tests of `deflex-absolute`: one test binary (modules below), so a fresh clone links one
//! executable for this crate instead of one per file.

mod fuzz;
mod jacobian;
mod joint_maps;
mod registration;
mod simulated;
mod torsion;
mod ur10_real;
