//! # Report pages
//!
//! What deflex's computations look like on disk and on the terminal: text tables, CSV, and —
//! with the `report` feature (on by default; the command line and the Python package have it) —
//! plots (PNG, and SVG where cheap) and self-contained HTML pages, drawn with `deflex-plot` from
//! plain data and written here, one module per thing rendered.
//!
//! In every build, the text:
//!
//! | module | renders |
//! | --- | --- |
//! | [`text_table`] | aligned text and CSV tables |
//! | [`calibration_tables`] | a calibration as tables: search steps, stiffnesses, shifts, residuals |
//! | [`plan_tables`] | an experiment plan: expected standard errors, the technician's sheet |
//! | [`validation_tables`] | a validation's error tables |
//! | [`absolute_report`] | an elasto-geometric calibration: text, JSON, CSV (and, with the feature, its plots and page: `deflex calibrate-geometry --report`) |
//! | [`study`] | the paper's study on the twin: its CSV files and `results.md` (and, with the feature, its figures, page and folder: `deflex demo`) |
//! | [`plot_logs`] | `deflex plot`: reads one or two run logs and writes their figures and page (refused without the feature) |
//!
//! With the `report` feature only, the drawing:
//!
//! | module | renders |
//! | --- | --- |
//! | `draw` | every plot kind and a page, written to their files whole or not at all |
//! | `calibration_report` | the calibration's HTML report with plots (`deflex calibrate --report`) |
//! | `validation_report` | a validation's plots and page (`deflex validate --out`) |
//! | `forming_run` | a forming run of the twin: its folder and plots (`deflex sim isf`) |
//! | `write_run_figures` | one run's log, or two overlaid on path position (`deflex plot`) |
//!
//! A workflow draws only through a [`Drawing`], the leave [`require`] gives with the feature
//! and refuses without it ([`crate::Error::ReportsNotBuilt`]): a report asked of a build without
//! reports is refused before anything is computed or written, never silently left out.
//!
//! The maths crates (`deflex-calibrate`, `deflex-sim`, …) take and return data; `deflex-plot`
//! draws into memory and renders pages to text (its plot kinds, matching the figures of Johra
//! et al., Robotics 2022, 11, 48, are listed in its documentation); the files are written here
//! (and by the front ends, through `draw`).

pub mod absolute_report;
#[cfg(feature = "report")]
pub mod calibration_report;
pub mod calibration_tables;
#[cfg(feature = "report")]
pub mod draw;
mod drawing;
#[cfg(feature = "report")]
pub mod forming_run;
pub mod plan_tables;
mod plot_logs;
#[cfg(feature = "report")]
mod run_figures;
pub mod study;
pub mod text_table;
#[cfg(feature = "report")]
pub mod validation_report;
pub mod validation_tables;

pub use drawing::{Drawing, require};
pub use plot_logs::{LogPlot, RunFigures, plot_logs};
#[cfg(feature = "report")]
pub use run_figures::{MAX_POINTS, thin_series, write_run_figures};

/// A figure, page or file of a report that could not be drawn or written, naming the file: the
/// drawing's own failure (`deflex-plot`, which writes nothing) or the writing's (the shared
/// I/O error of `deflex-files`).
#[cfg(feature = "report")]
#[derive(Debug, thiserror::Error)]
pub enum DrawError {
    /// The drawing: data that cannot be plotted, a format that cannot be written, the
    /// backend's failure (also a failure to write a figure's temporary file, as when the
    /// plotting toolkit saved its files itself), an image a page embeds that cannot be read.
    #[error(transparent)]
    Plot(#[from] deflex_plot::PlotError),
    /// A file or folder of the report could not be written or replaced (or is one deflex may
    /// not replace).
    #[error(transparent)]
    Io(#[from] deflex_files::FileIoError),
    /// A text file of the report (JSON, CSV) whose content could not be made.
    #[error("{}: could not be written: {reason}", deflex_files::shown_path(.path))]
    Content {
        /// The file.
        path: std::path::PathBuf,
        /// Why.
        reason: String,
    },
}

#[cfg(feature = "report")]
impl DrawError {
    /// The file the error is about.
    pub fn path(&self) -> &std::path::Path {
        match self {
            DrawError::Plot(error) => error.path(),
            DrawError::Io(error) => error.path(),
            DrawError::Content { path, .. } => path,
        }
    }

    /// A write of `path` that failed, as a `map_err` argument: `.map_err(DrawError::io_on(path))`.
    pub fn io_on(path: &std::path::Path) -> impl Fn(std::io::Error) -> DrawError + Copy + '_ {
        move |source| DrawError::Io(deflex_files::FileIoError::new(path, source))
    }

    /// The content of `path` that could not be made (`reason`), as a `map_err` argument.
    pub fn content_of<E: std::fmt::Display>(
        path: &std::path::Path,
    ) -> impl Fn(E) -> DrawError + '_ {
        move |reason| DrawError::Content {
            path: path.to_path_buf(),
            reason: reason.to_string(),
        }
    }
}

/// A report (a page with its plots and tables) that could not be written: which report, and
/// the file that failed.
#[cfg(feature = "report")]
#[derive(Debug, thiserror::Error)]
#[error("{report}: {source}")]
pub struct PageError {
    /// Which report (`validation report`, `calibration report`, …).
    pub report: &'static str,
    /// The file that failed, and why.
    #[source]
    pub source: DrawError,
}

#[cfg(feature = "report")]
impl PageError {
    /// A function turning a [`DrawError`] into a `PageError` of `report`.
    pub fn of(report: &'static str) -> impl Fn(DrawError) -> PageError {
        move |source| PageError { report, source }
    }
}
