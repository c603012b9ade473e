//! The report pages (`deflex_app::report`), through the public API: files are written to a
//! unique temp dir and inspected, a module per page, and `draw` for the plots and pages written
//! whole or not at all. The plotting toolkit's own tests (plots drawn into memory, HTML, colour
//! maps, fonts, …) are in deflex-plot's tests.

mod calibration;
mod draw;
mod forming_folder;
mod plan;
mod run_figures;
mod study;
mod validation;
