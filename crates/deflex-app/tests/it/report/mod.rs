//! The report pages (`deflex_app::report`), through the public API: files are written to a
//! unique temp dir and inspected, a module per page, and `draw` for the plots and pages written
//! whole or not at all. The plotting toolkit's own tests (plots drawn into memory, HTML, colour
//! maps, fonts, …) are in deflex-plot's tests. The pages and plots need the `report` feature
//! (on by default); `unbuilt` checks that a build without it refuses them.

mod calibration;
#[cfg(feature = "report")]
mod draw;
#[cfg(feature = "report")]
mod forming_folder;
mod plan;
#[cfg(feature = "report")]
mod run_figures;
#[cfg(feature = "report")]
mod study;
mod text_table;
#[cfg(not(feature = "report"))]
mod unbuilt;
mod validation;
