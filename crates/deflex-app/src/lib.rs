//! # deflex-app
//!
//! deflex's workflows, the one layer under the command-line tool and the Python package.
//!
//! ## Features
//!
//! - `report` (default): the reports and figures, drawn with `deflex-plot` (plotters, png):
//!   the calibration report (`calibrate::save` with a report folder), the validation report
//!   (`calibrate::write_validation_report`), the elasto-geometric calibration report
//!   (`calibrate_geometry::save` with a report folder, `calibrate_geometry::write_report`), a
//!   forming run's folder (`twin::RunFolder`, `twin::write_outputs`), the sensitivity sweep's
//!   folder (`twin::sensitivity::SensitivitySweep::write`), the study's folder
//!   (`study::demo`), the deflection map (`robot::map::write_map`) and the figures of run logs
//!   (`report::plot_logs`). Without it every text output stays (the tables of
//!   [`report::text_table`], summaries, CSV files, JSON) and those calls return
//!   [`Error::ReportsNotBuilt`] before they compute or write anything ([`report::require`]).
//!   The command line and the facade turn it on; the Python package through its own `report`
//!   feature, on in the wheel maturin builds.
//! - `clap`: the choice enums derive `clap::ValueEnum` for the command line.
//!
//! ## Front ends' words
//!
//! A workflow that names an option in a message (which set-up to choose, the seed that tilts the
//! tool, the tolerance to widen) takes an [`OptionNames`] and names the option in the words of
//! the front end that called it: `--seed-deg` on the command line, `seed_q` in Python.

#![warn(missing_docs)]

pub mod calibrate;
pub mod calibrate_geometry;
pub mod cell;
pub mod compensate;
pub mod error;
pub mod export;
pub mod load;
pub mod option_names;
pub mod report;
pub mod robot;
pub mod study;
pub mod table;
pub mod twin;

pub use error::{Error, ErrorKind, Result};
pub use option_names::OptionNames;
