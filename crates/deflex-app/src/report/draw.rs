//! Plots and pages written to their files: each function draws with `deflex-plot` (which draws
//! into memory and writes nothing) and writes the result whole or not at all, with the file
//! discipline of `deflex-files`.
//!
//! The plot functions have `deflex-plot`'s names and arguments and return `()`: the image's
//! format is chosen by the extension of `path` (`.png` or `.svg`), the file appears only once it
//! is complete, through a temporary sibling renamed over it ([`deflex_files::write_through`]),
//! and an error names the file. A page is rendered with its images read back from their files
//! ([`read_image`]) and written atomically ([`write_page`]).
//!
//! Errors ([`DrawError`]), each naming the file: the drawing's own ([`DrawError::Plot`]:
//! [`PlotError::InvalidInput`], [`PlotError::UnsupportedFormat`], [`PlotError::Draw`]; an
//! image a page embeds that cannot be read is the toolkit's [`PlotError::Io`]); a failure to
//! write the temporary file is [`PlotError::Draw`] (as when the plotting toolkit saved the files
//! itself: a missing folder, a full disk); an output that may not be replaced
//! ([`deflex_files::check_output`]), a failed rename or a page that cannot be written is
//! [`DrawError::Io`] (the shared [`deflex_files::FileIoError`]).
//!
//! ```no_run
//! use deflex_app::report::draw::line_plot;
//! use deflex_plot::{PlotSpec, Series};
//! let spec = PlotSpec::new("Deflection along path", "time [s]", "deflection [mm]");
//! let s = Series::line("z", vec![0.0, 1.0, 2.0], vec![0.0, 0.3, 0.1]);
//! line_plot(std::path::Path::new("out.png"), &spec, &[s]).unwrap();
//! ```

use crate::report::DrawError;
use deflex_plot::{
    Cloud3, HtmlReport, Image, Lane, PanelLayout, Plot3Spec, PlotError, PlotSpec, Series,
};
use std::path::Path;

/// Most bytes of one image embedded in a page: a figure is a few hundred kilobytes; the limit
/// is counted while reading.
pub const MAX_IMAGE_BYTES: u64 = 64 << 20;

/// Writes `image` (drawn for `path`) to `path`, whole or not at all: its bytes go to a
/// temporary sibling with the same extension, renamed over `path` once complete and removed
/// on failure.
pub fn write_image(path: &Path, image: Image) -> Result<(), DrawError> {
    deflex_files::write_through(
        path,
        |temporary| {
            std::fs::write(temporary, &image.bytes).map_err(|e| {
                DrawError::Plot(PlotError::Draw {
                    path: path.to_path_buf(),
                    reason: e.to_string(),
                })
            })
        },
        DrawError::io_on(path),
    )
}

/// The bytes of the image file `path` for a page ([`write_page`]), read bounded by
/// [`MAX_IMAGE_BYTES`].
pub fn read_image(path: &Path) -> std::io::Result<Vec<u8>> {
    deflex_files::read_bounded_bytes(path, MAX_IMAGE_BYTES).map_err(|e| e.into_io())
}

/// Renders `page`, its images read from their files ([`read_image`]), and writes it to `path`
/// whole or not at all. An image that cannot be read is the toolkit's [`PlotError::Io`] naming
/// the image.
pub fn write_page(page: &HtmlReport, path: &Path) -> Result<(), DrawError> {
    let html = page.render(read_image)?;
    deflex_files::write_atomic(path, html).map_err(DrawError::io_on(path))
}

/// Writes the text file `path` of a report (a table, JSON, Markdown) whole or not at all.
pub fn write_text(path: &Path, text: &str) -> Result<(), DrawError> {
    deflex_files::write_atomic(path, text).map_err(DrawError::io_on(path))
}

/// [`deflex_plot::line_plot`] written to `path` ([`write_image`]).
pub fn line_plot(path: &Path, spec: &PlotSpec, series: &[Series]) -> Result<(), DrawError> {
    write_image(path, deflex_plot::line_plot(path, spec, series)?)
}

/// [`deflex_plot::panels_plot`] written to `path` ([`write_image`]).
pub fn panels_plot(
    path: &Path,
    title: &str,
    layout: PanelLayout,
    panels: &[(PlotSpec, Vec<Series>)],
) -> Result<(), DrawError> {
    write_image(path, deflex_plot::panels_plot(path, title, layout, panels)?)
}

/// [`deflex_plot::parity_plot`] written to `path` ([`write_image`]).
pub fn parity_plot(
    path: &Path,
    spec: &PlotSpec,
    predicted: &[f64],
    measured: &[f64],
    label: &str,
) -> Result<(), DrawError> {
    let image = deflex_plot::parity_plot(path, spec, predicted, measured, label)?;
    write_image(path, image)
}

/// [`deflex_plot::heatmap`] written to `path` ([`write_image`]).
pub fn heatmap(
    path: &Path,
    spec: &PlotSpec,
    x_centers: &[f64],
    y_centers: &[f64],
    values: &[f64],
    colorbar_label: &str,
) -> Result<(), DrawError> {
    let image = deflex_plot::heatmap(path, spec, x_centers, y_centers, values, colorbar_label)?;
    write_image(path, image)
}

/// [`deflex_plot::scatter_heatmap`] written to `path` ([`write_image`]).
pub fn scatter_heatmap(
    path: &Path,
    spec: &PlotSpec,
    x: &[f64],
    y: &[f64],
    value: &[f64],
    colorbar_label: &str,
) -> Result<(), DrawError> {
    let image = deflex_plot::scatter_heatmap(path, spec, x, y, value, colorbar_label)?;
    write_image(path, image)
}

/// [`deflex_plot::cloud_3d`] written to `path` ([`write_image`]).
pub fn cloud_3d(path: &Path, spec: &Plot3Spec, clouds: &[Cloud3]) -> Result<(), DrawError> {
    write_image(path, deflex_plot::cloud_3d(path, spec, clouds)?)
}

/// [`deflex_plot::timeline_plot`] written to `path` ([`write_image`]).
pub fn timeline_plot(path: &Path, spec: &PlotSpec, lanes: &[Lane]) -> Result<(), DrawError> {
    write_image(path, deflex_plot::timeline_plot(path, spec, lanes)?)
}
