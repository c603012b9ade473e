//! # Report pages
//!
//! Plots (PNG, and SVG where cheap) and self-contained HTML reports, built
//! from plain data: slices of `f64` and strings; and, above them, what deflex's
//! computations look like on disk, one module per thing rendered:
//!
//! | module | renders |
//! | --- | --- |
//! | [`text_table`] | aligned text and CSV tables |
//! | [`calibration_tables`] | a calibration as tables: search steps, stiffnesses, shifts, residuals |
//! | [`calibration_report`] | the calibration's HTML report with plots (`deflex calibrate --report`) |
//! | [`plan_tables`] | an experiment plan: expected standard errors, the technician's sheet |
//! | [`validation_report`] | a validation: tables, plots and page (`deflex validate --out`) |
//! | [`absolute_report`] | an elasto-geometric calibration: text, JSON, CSV, plots, page (`deflex calibrate-geometry --report`) |
//! | [`forming_run`] | a forming run of the twin: its folder and plots (`deflex sim isf`) |
//! | [`study`] | the paper's study on the twin: its folder, figures and page (`deflex demo`) |
//!
//! The maths crates (`deflex-stiffness`, `deflex-sim`, …) take and return data; the files, plots
//! and pages are made here (and by the front ends).
//!
//! Plot kinds, matching the figures of Johra et al. (Robotics 2022, 11, 48):
//!
//! | function | figure kind |
//! | --- | --- |
//! | [`line_plot`] | displacement or force along a path, a spiral trajectory (Fig. 14) |
//! | [`panels_plot`] | per-axis errors plus norm (Fig. A1), with/without side by side (Fig. 18) |
//! | [`parity_plot`] | predicted vs measured displacement (Fig. 8–10, 12) |
//! | [`heatmap`] | prediction error over a regular grid (Fig. 11, 13) |
//! | [`scatter_heatmap`] | the same over scattered measurement points |
//! | [`cloud_3d`] | 3D deviation cloud (Fig. 17) |
//! | [`timeline_plot`] | on/off states over time (a controller's flags) |
//! | [`write_run_figures`] | one run's log, or two overlaid on path position (`deflex plot`) |
//! | [`HtmlReport`] | one self-contained page embedding all of them |
//!
//! The output format is chosen by the file extension: `.png` or `.svg`.
//! Text is drawn with an embedded DejaVu Sans font, so rendering needs no
//! system fonts. Titles are never drawn below [`MIN_TITLE_PX`]: a long one is
//! wrapped onto up to [`MAX_TITLE_LINES`] lines ([`title_layout`]), then
//! shortened with an ellipsis. Series can be dashed or dotted ([`LineStyle`])
//! as well as coloured, so that curves stay apart without colour. Everything is deterministic: colours come from a fixed
//! palette ([`palette_color`]) and heatmaps use the viridis colour map
//! ([`viridis`]).
//!
//! Inputs are checked: empty or mismatched-length inputs return
//! [`PlotError::InvalidInput`] rather than panicking. Non-finite values
//! (NaN, ±∞) are skipped (line series break at them, heatmap cells stay
//! blank); an input with no finite value at all is an error.
//!
//! ```no_run
//! use deflex_plot::{line_plot, PlotSpec, Series};
//! let spec = PlotSpec::new("Deflection along path", "time [s]", "deflection [mm]");
//! let s = Series::line("z", vec![0.0, 1.0, 2.0], vec![0.0, 0.3, 0.1]);
//! line_plot(std::path::Path::new("out.png"), &spec, &[s]).unwrap();
//! ```

pub mod absolute_report;
pub mod calibration_report;
pub mod calibration_tables;
pub mod forming_run;
pub mod plan_tables;
mod run_figures;
pub mod study;
pub mod validation_report;

use deflex_plot::PlotError;

pub use run_figures::{MAX_POINTS, RunFigures, thin_series, write_run_figures};

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
