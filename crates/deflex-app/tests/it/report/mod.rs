//! The report pages (`deflex_app::report`), through the public API: files are written to a
//! unique temp dir and inspected, a module per page. The plotting toolkit's own tests (plots,
//! HTML, colour maps, fonts, …) are in deflex-plot's tests.

mod calibration;
mod forming_folder;
mod plan;
mod run_figures;
mod study;
mod validation;
