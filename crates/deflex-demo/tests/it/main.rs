//! Integration tests of `deflex-demo`: one test binary (modules below), so a fresh clone links one
//! executable for this crate instead of one per file.

// The quick study end to end, with its files: deflex-report (study), which writes them.
mod stiff_contact;
mod twin_calibration;
