//! The paper's study on the twin (`deflex demo`) on disk: one folder, swapped in whole, with the
//! CSV data behind every number ([`csv_files`]), `results.md` ([`readme`]), the PNG figures
//! after the paper's (`figures`) and the self-contained `index.html` (`page`). The numbers are
//! `crate::study::run_study`'s; this module only renders them.
//!
//! The text ([`csv_files`], [`readme`]) is in every build; the figures, the page and the folder
//! (`write_study`) only with the `report` feature, as `crate::study::demo` (which writes the
//! folder) refuses without it.

pub mod csv_files;
#[cfg(feature = "report")]
pub mod figures;
#[cfg(feature = "report")]
mod folder;
#[cfg(feature = "report")]
mod page;
pub mod readme;

#[cfg(feature = "report")]
pub use folder::write_study;
#[cfg(feature = "report")]
pub use page::headline_text;

/// A figure file and its caption.
#[cfg(feature = "report")]
pub type Figure = (std::path::PathBuf, String);

/// The study's figures, by page section.
#[cfg(feature = "report")]
#[derive(Default)]
pub(crate) struct StudyFigures {
    pub fig7: Vec<Figure>,
    pub grid: Vec<Figure>,
    pub spiral: Vec<Figure>,
    pub forming: Vec<Figure>,
    pub controller: Vec<Figure>,
    pub contact: Vec<Figure>,
    pub sensitivity: Vec<Figure>,
    pub compensation: Vec<Figure>,
}
