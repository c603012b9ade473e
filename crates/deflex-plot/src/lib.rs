//! # deflex-plot
//!
//! Plots (PNG, and SVG where cheap) and self-contained HTML pages, built from plain data: slices
//! of `f64` and strings. The toolkit knows no robot: what deflex's computations look like on
//! disk (the calibration, validation, forming-run and study pages) is `deflex-app`'s.
//!
//! It draws into memory and reads and writes no file: a plot function returns the [`Image`]
//! (the bytes of its `.png` or `.svg` file), a page renders to text ([`HtmlReport::render`],
//! the bytes of its images given by the caller). Writing them, whole or not at all, is the
//! caller's: deflex's application layer does it in `deflex_app::report::draw`, with the same
//! function names and arguments. Text tables (aligned text, CSV) draw nothing and are not here:
//! they are `deflex_app::report::text_table`, in every build of the application layer, where
//! this crate is behind its `report` feature.
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
//! | [`HtmlReport`] | one self-contained page embedding all of them |
//!
//! The image format is chosen by the extension of the path each plot is drawn for (`.png` or
//! `.svg`); the path also names the image in every error.
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
//! ```
//! use deflex_plot::{line_plot, ImageFormat, PlotSpec, Series};
//! let spec = PlotSpec::new("Deflection along path", "time [s]", "deflection [mm]");
//! let s = Series::line("z", vec![0.0, 1.0, 2.0], vec![0.0, 0.3, 0.1]);
//! let image = line_plot(std::path::Path::new("out.png"), &spec, &[s]).unwrap();
//! assert_eq!(image.format, ImageFormat::Png);
//! assert!(image.bytes.starts_with(b"\x89PNG\r\n\x1a\n"));
//! ```

#![warn(missing_docs)]

mod cloud;
mod colormap;
mod font;
mod heatmap;
mod html;
mod plot;
mod render;
mod timeline;

use std::path::{Path, PathBuf};

pub use cloud::{Cloud3, Plot3Spec, cloud_3d};
pub use colormap::{PALETTE, palette_color, viridis};
pub use font::DEJAVU_SANS;
pub use heatmap::{cell_edges, cell_value_text, heatmap, scatter_heatmap};
pub use html::{FileLink, HtmlReport, html_escape, inline_html};
pub use plot::{PanelLayout, clip_segment, line_plot, panels_plot, parity_plot, strokable_pieces};
pub use render::{
    Image, ImageFormat, MAX_TITLE_LINES, MIN_TITLE_PX, TitleLayout, finite_extent, padded,
    text_width_px, tick_formatter, title_layout,
};
pub use timeline::{Lane, timeline_plot};

/// Errors from drawing plots or rendering pages (and from writing them, for the callers that
/// do). Every variant names the file concerned.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// The data given cannot be plotted (empty, mismatched lengths, no
    /// finite values, bad ranges, ...).
    #[error("{path}: invalid input: {reason}")]
    InvalidInput {
        /// Image (or embedded image) file concerned.
        path: PathBuf,
        /// What is wrong with the input.
        reason: String,
    },
    /// The file extension is not one this crate can write or embed.
    #[error("{path}: unsupported file extension (expected {expected})")]
    UnsupportedFormat {
        /// File concerned.
        path: PathBuf,
        /// The extensions that are supported here.
        expected: &'static str,
    },
    /// The plotting backend failed; a caller writing the image reports a failure to write
    /// its bytes this way too (as when this crate saved the files itself).
    #[error("{path}: drawing failed: {reason}")]
    Draw {
        /// Image file concerned.
        path: PathBuf,
        /// The backend's message.
        reason: String,
    },
    /// Reading or writing a file failed: an image's loader failed ([`HtmlReport::render`]), or
    /// the caller could not write a page or replace an image.
    #[error("{path}: {source}")]
    Io {
        /// File concerned.
        path: PathBuf,
        /// The underlying I/O error.
        #[source]
        source: std::io::Error,
    },
}

impl PlotError {
    /// An [`PlotError::InvalidInput`] about `path`.
    pub fn invalid(path: &Path, reason: impl Into<String>) -> Self {
        PlotError::InvalidInput {
            path: path.to_path_buf(),
            reason: reason.into(),
        }
    }

    /// The file this error is about.
    pub fn path(&self) -> &Path {
        match self {
            PlotError::InvalidInput { path, .. }
            | PlotError::UnsupportedFormat { path, .. }
            | PlotError::Draw { path, .. }
            | PlotError::Io { path, .. } => path,
        }
    }
}

/// How a [`Series`] is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SeriesStyle {
    /// A polyline through the points (broken where a value is not finite).
    #[default]
    Line,
    /// Markers only.
    Points,
    /// A polyline with markers.
    LineAndPoints,
}

/// How the line of a [`Series`] is stroked (markers are unaffected). Give series that share a
/// chart different dash patterns as well as colours, so they stay apart in print, for readers
/// who do not see the colours, and where they overlap.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LineStyle {
    /// A continuous 2 px line.
    #[default]
    Solid,
    /// 10 px dashes, 6 px gaps.
    Dashed,
    /// 3 px dots, 4 px gaps.
    Dotted,
}

impl LineStyle {
    /// `(dash, gap)` lengths in pixels, `None` for a solid line.
    pub fn pattern_px(self) -> Option<(u32, u32)> {
        match self {
            LineStyle::Solid => None,
            LineStyle::Dashed => Some((10, 6)),
            LineStyle::Dotted => Some((3, 4)),
        }
    }
}

/// One named data series of a 2D plot. `x` and `y` must have equal lengths.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend text (an empty label leaves the series out of the legend).
    pub label: String,
    /// Abscissae.
    pub x: Vec<f64>,
    /// Ordinates.
    pub y: Vec<f64>,
    /// How the series is drawn.
    pub style: SeriesStyle,
    /// How its line is stroked.
    pub line: LineStyle,
    /// Its colour as `(r, g, b)`; `None`: the [`PALETTE`] colour of its position in the chart.
    pub color: Option<(u8, u8, u8)>,
}

impl Series {
    /// A series drawn with the given style.
    pub fn new(label: impl Into<String>, x: Vec<f64>, y: Vec<f64>, style: SeriesStyle) -> Self {
        Series {
            label: label.into(),
            x,
            y,
            style,
            line: LineStyle::Solid,
            color: None,
        }
    }

    /// The same series stroked with `line`.
    pub fn with_line(mut self, line: LineStyle) -> Self {
        self.line = line;
        self
    }

    /// The same series drawn in `color` (`(r, g, b)`) instead of its palette colour.
    pub fn with_color(mut self, color: (u8, u8, u8)) -> Self {
        self.color = Some(color);
        self
    }

    /// A series drawn as a line.
    pub fn line(label: impl Into<String>, x: Vec<f64>, y: Vec<f64>) -> Self {
        Self::new(label, x, y, SeriesStyle::Line)
    }

    /// A series drawn as markers.
    pub fn points(label: impl Into<String>, x: Vec<f64>, y: Vec<f64>) -> Self {
        Self::new(label, x, y, SeriesStyle::Points)
    }

    /// A series drawn as a line with markers.
    pub fn line_and_points(label: impl Into<String>, x: Vec<f64>, y: Vec<f64>) -> Self {
        Self::new(label, x, y, SeriesStyle::LineAndPoints)
    }

    /// A series whose abscissa is the sample index 0, 1, 2, ... (e.g. the
    /// point number along a path).
    pub fn indexed(label: impl Into<String>, y: Vec<f64>, style: SeriesStyle) -> Self {
        let x = (0..y.len()).map(|i| i as f64).collect();
        Self::new(label, x, y, style)
    }
}

/// Title, axis labels (with units), size and optional fixed ranges of a 2D
/// plot.
#[derive(Debug, Clone, PartialEq)]
pub struct PlotSpec {
    /// Plot title, drawn above the chart.
    pub title: String,
    /// X axis label, with units, e.g. `"x [mm]"`.
    pub x_label: String,
    /// Y axis label, with units.
    pub y_label: String,
    /// Image width in pixels (for a panel: the panel's width).
    pub width: u32,
    /// Image height in pixels (for a panel: the panel's height).
    pub height: u32,
    /// Fixed x range; `None` fits the data.
    pub x_range: Option<(f64, f64)>,
    /// Fixed y range; `None` fits the data.
    pub y_range: Option<(f64, f64)>,
    /// Fixed colour-scale range for heatmaps; `None` fits the data. Ignored by
    /// other plot kinds.
    pub color_range: Option<(f64, f64)>,
}

impl PlotSpec {
    /// A spec with the default size of 900 × 560 pixels and ranges fitted to
    /// the data.
    pub fn new(
        title: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
    ) -> Self {
        PlotSpec {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            width: 900,
            height: 560,
            x_range: None,
            y_range: None,
            color_range: None,
        }
    }

    /// Sets the image (or panel) size in pixels.
    pub fn size(mut self, width: u32, height: u32) -> Self {
        self.width = width;
        self.height = height;
        self
    }

    /// Fixes the x range.
    pub fn x_range(mut self, min: f64, max: f64) -> Self {
        self.x_range = Some((min, max));
        self
    }

    /// Fixes the y range.
    pub fn y_range(mut self, min: f64, max: f64) -> Self {
        self.y_range = Some((min, max));
        self
    }

    /// Fixes the colour-scale range of a heatmap.
    pub fn color_range(mut self, min: f64, max: f64) -> Self {
        self.color_range = Some((min, max));
        self
    }
}
