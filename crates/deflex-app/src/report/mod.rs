//! # Report pages
//!
//! What deflex's computations look like on disk: plots (PNG, and SVG where cheap) and
//! self-contained HTML pages, drawn with `deflex-plot` from plain data and written here, one
//! module per thing rendered:
//!
//! | module | renders |
//! | --- | --- |
//! | [`draw`] | every plot kind and a page, written to their files whole or not at all |
//! | [`calibration_tables`] | a calibration as tables: search steps, stiffnesses, shifts, residuals |
//! | [`calibration_report`] | the calibration's HTML report with plots (`deflex calibrate --report`) |
//! | [`plan_tables`] | an experiment plan: expected standard errors, the technician's sheet |
//! | [`validation_report`] | a validation: tables, plots and page (`deflex validate --out`) |
//! | [`absolute_report`] | an elasto-geometric calibration: text, JSON, CSV, plots, page (`deflex calibrate-geometry --report`) |
//! | [`forming_run`] | a forming run of the twin: its folder and plots (`deflex sim isf`) |
//! | [`study`] | the paper's study on the twin: its folder, figures and page (`deflex demo`) |
//! | [`write_run_figures`] | one run's log, or two overlaid on path position; [`plot_logs`] reads the logs and writes the folder (`deflex plot`) |
//!
//! The maths crates (`deflex-calibrate`, `deflex-sim`, …) take and return data; `deflex-plot`
//! draws into memory and renders pages to text (its plot kinds, matching the figures of Johra
//! et al., Robotics 2022, 11, 48, are listed in its documentation); the files are written here
//! (and by the front ends, through [`draw`]).
//!
//! ```no_run
//! use deflex_app::report::draw::line_plot;
//! use deflex_plot::{PlotSpec, Series};
//! let spec = PlotSpec::new("Deflection along path", "time [s]", "deflection [mm]");
//! let s = Series::line("z", vec![0.0, 1.0, 2.0], vec![0.0, 0.3, 0.1]);
//! line_plot(std::path::Path::new("out.png"), &spec, &[s]).unwrap();
//! ```

pub mod absolute_report;
pub mod calibration_report;
pub mod calibration_tables;
pub mod draw;
pub mod forming_run;
pub mod plan_tables;
mod run_figures;
pub mod study;
pub mod validation_report;

use deflex_plot::PlotError;

pub use run_figures::{LogPlot, MAX_POINTS, RunFigures, plot_logs, thin_series, write_run_figures};

/// A report (a page with its plots and tables) that could not be written: which report, and
/// the file that failed.
#[derive(Debug, thiserror::Error)]
#[error("{report}: {source}")]
pub struct PageError {
    /// Which report (`validation report`, `calibration report`, …).
    pub report: &'static str,
    /// The file that failed, and why.
    #[source]
    pub source: PlotError,
}

impl PageError {
    /// A function turning a [`PlotError`] into a `PageError` of `report`.
    pub fn of(report: &'static str) -> impl Fn(PlotError) -> PageError {
        move |source| PageError { report, source }
    }
}
