//! Shared plumbing: image format by extension, backend dispatch (drawing into memory), input
//! checks, axis ranges and text styles.

use std::path::Path;

use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::{PlotError, PlotSpec};

/// The image formats the plots are drawn in, chosen by the image file's extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ImageFormat {
    /// `.png` (any case): a bitmap.
    Png,
    /// `.svg` (any case): vector graphics.
    Svg,
}

impl ImageFormat {
    /// The format of `path` by its extension, case-insensitive (`plot.PNG` is a PNG); any other
    /// extension, or none, is [`PlotError::UnsupportedFormat`] naming the file. A front end
    /// can check an output path with it before computing what is to be drawn there.
    pub fn from_path(path: &Path) -> Result<Self, PlotError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase());
        match ext.as_deref() {
            Some("png") => Ok(ImageFormat::Png),
            Some("svg") => Ok(ImageFormat::Svg),
            _ => Err(PlotError::UnsupportedFormat {
                path: path.to_path_buf(),
                expected: ".png or .svg",
            }),
        }
    }
}

/// An image drawn into memory: the bytes of its `.png` or `.svg` file, exactly as they are to be
/// written (this crate writes no file: the caller writes them, whole or not at all, or embeds
/// them in a page).
#[derive(Debug, Clone, PartialEq, Eq)]
#[must_use = "an image drawn into memory is lost unless its bytes are written or embedded"]
pub struct Image {
    /// Its format (the extension of the path it was drawn for).
    pub format: ImageFormat,
    /// The file's bytes: a PNG, or SVG text in UTF-8.
    pub bytes: Vec<u8>,
}

impl Image {
    /// The file's bytes.
    pub fn into_bytes(self) -> Vec<u8> {
        self.bytes
    }
}

/// Runs `$body` (an expression of type `Result<(), BackendError>` using `$root`, a
/// `&DrawingArea<_, Shift>`) on a PNG or SVG backend drawing into memory, chosen by the path's
/// extension. Evaluates to `Result<Image, PlotError>`: the bytes of the file the image would be
/// (nothing is written; `$path` names the image in errors and chooses its format).
macro_rules! render {
    // One backend: white background, `$body`, present. Each backend has its own drawing-area
    // type, so `$body` is expanded once per backend. The area (and the buffer it borrows) is
    // dropped at the end of this block.
    (@draw $backend:expr, $fail:ident, |$root:ident| $body:expr) => {{
        let $root = &::plotters::prelude::IntoDrawingArea::into_drawing_area($backend);
        $root
            .fill(&::plotters::prelude::WHITE)
            .map_err(|e| $fail(e.to_string()))?;
        #[allow(clippy::redundant_closure_call)]
        let drawn: Result<(), $crate::render::BackendError> =
            (|| -> Result<(), $crate::render::BackendError> { $body })();
        drawn.map_err(|e| $fail(e.0))?;
        $root.present().map_err(|e| $fail(e.to_string()))
    }};
    ($path:expr, ($w:expr, $h:expr), |$root:ident| $body:expr) => {{
        let path: &::std::path::Path = $path;
        let size: (u32, u32) = ($w, $h);
        let fail = |reason: String| $crate::PlotError::Draw {
            path: path.to_path_buf(),
            reason,
        };
        $crate::render::check_size(path, size)?;
        $crate::font::ensure_registered();
        let format = $crate::render::ImageFormat::from_path(path)?;
        let bytes: Vec<u8> = match format {
            $crate::render::ImageFormat::Png => {
                // Drawn into memory (RGB, 3 bytes a pixel; `check_size` bounds it) and encoded
                // by `png`: plotters' own PNG saving would pull in the `image` crate.
                let mut rgb = ::std::vec![0u8; $crate::render::rgb_len(size)];
                $crate::render::render!(
                    @draw ::plotters::prelude::BitMapBackend::with_buffer(&mut rgb, size),
                    fail,
                    |$root| $body
                )?;
                $crate::render::encode_png(&rgb, size).map_err(|e| fail(e.0))?
            }
            $crate::render::ImageFormat::Svg => {
                let mut svg = ::std::string::String::new();
                $crate::render::render!(
                    @draw ::plotters::prelude::SVGBackend::with_string(&mut svg, size),
                    fail,
                    |$root| $body
                )?;
                svg.into_bytes()
            }
        };
        Ok($crate::Image { format, bytes })
    }};
}
pub(crate) use render;

/// A failure of the plotting backend inside drawing code: its message, which becomes the
/// `reason` of [`PlotError::Draw`] naming the file.
#[derive(Debug)]
pub(crate) struct BackendError(pub(crate) String);

/// Converts any displayable error of the backend into a [`BackendError`].
pub(crate) fn err<E: std::fmt::Display>(e: E) -> BackendError {
    BackendError(e.to_string())
}

/// Bytes of an RGB buffer of `size` pixels (3 a pixel).
pub(crate) fn rgb_len((w, h): (u32, u32)) -> usize {
    w as usize * h as usize * 3
}

/// Encodes `rgb`, `size` pixels of 8-bit RGB row by row, as the bytes of a PNG file, with the
/// settings plotters' bitmap encoder (the `image` crate's) used: fast compression, adaptive
/// filtering. A failure carries the encoder's message.
pub(crate) fn encode_png(rgb: &[u8], (w, h): (u32, u32)) -> Result<Vec<u8>, BackendError> {
    let mut out = Vec::new();
    let mut encoder = png::Encoder::new(&mut out, w, h);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_compression(png::Compression::Fast);
    encoder.set_filter(png::FilterType::Sub);
    encoder.set_adaptive_filter(png::AdaptiveFilterType::Adaptive);
    let mut writer = encoder.write_header().map_err(err)?;
    writer.write_image_data(rgb).map_err(err)?;
    writer.finish().map_err(err)?;
    Ok(out)
}

/// Rejects degenerate or absurd image sizes.
pub(crate) fn check_size(path: &Path, (w, h): (u32, u32)) -> Result<(), PlotError> {
    if !(64..=16_384).contains(&w) || !(64..=16_384).contains(&h) {
        return Err(PlotError::invalid(
            path,
            format!("image size {w}x{h} outside 64..=16384 pixels"),
        ));
    }
    Ok(())
}

/// Min and max of the finite values, or `None` when there are none (NaN and ±∞ are skipped, as
/// every plot here skips them): the data extent a plot's axis is fitted to.
pub fn finite_extent<'a>(values: impl IntoIterator<Item = &'a f64>) -> Option<(f64, f64)> {
    values
        .into_iter()
        .copied()
        .filter(|v| v.is_finite())
        .fold(None, |acc, v| match acc {
            None => Some((v, v)),
            Some((lo, hi)) => Some((lo.min(v), hi.max(v))),
        })
}

/// Widens a data extent by `pad` (a fraction of its span) on both sides, and
/// gives a zero-width extent a sensible non-zero width (±1 around zero, ±10 % around any other
/// value): the axis range a plot shows for a [`finite_extent`] when [`PlotSpec`] fixes none.
pub fn padded((lo, hi): (f64, f64), pad: f64) -> (f64, f64) {
    let span = hi - lo;
    if span > 0.0 && span.is_finite() {
        (lo - pad * span, hi + pad * span)
    } else {
        let half = if lo == 0.0 { 1.0 } else { lo.abs() * 0.1 };
        (lo - half, hi + half)
    }
}

/// Validates a user-given range.
pub(crate) fn check_range(path: &Path, what: &str, (lo, hi): (f64, f64)) -> Result<(), PlotError> {
    if !(lo.is_finite() && hi.is_finite() && lo < hi) {
        return Err(PlotError::invalid(
            path,
            format!("{what} range ({lo}, {hi}) must be finite with min < max"),
        ));
    }
    Ok(())
}

/// Smallest font size (px) a plot title is ever drawn at. A title too long for its image at this
/// size is wrapped onto more lines (at most [`MAX_TITLE_LINES`]) and only then shortened with an
/// ellipsis; it is never drawn smaller. 18 px is the axis labels' size: a title shrunk further
/// would read as a footnote, and the report pages scale wide images down.
pub const MIN_TITLE_PX: u32 = 18;

/// Most lines a plot title is wrapped onto.
pub const MAX_TITLE_LINES: usize = 3;

/// Free space (px) kept on each side of a title line.
const TITLE_SIDE_MARGIN: u32 = 10;
/// Space (px) above the first title line.
const TITLE_TOP_MARGIN: u32 = 10;
/// Space (px) between the last title line and what follows.
const TITLE_BOTTOM_MARGIN: u32 = 6;

/// How a plot title is drawn: its font size and its lines (see [`title_layout`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TitleLayout {
    /// Font size (px), never below [`MIN_TITLE_PX`].
    pub size_px: u32,
    /// The lines, top to bottom (empty for an empty title).
    pub lines: Vec<String>,
}

impl TitleLayout {
    /// Line pitch (px).
    pub fn line_height_px(&self) -> u32 {
        (self.size_px as f64 * 1.25).round() as u32
    }

    /// Height (px) the title takes above the chart, margins included (0 when empty).
    pub fn height_px(&self) -> u32 {
        if self.lines.is_empty() {
            0
        } else {
            TITLE_TOP_MARGIN + self.lines.len() as u32 * self.line_height_px() + TITLE_BOTTOM_MARGIN
        }
    }
}

/// Width (px) of `text` in the embedded font at `size_px`.
pub fn text_width_px(text: &str, size_px: u32) -> u32 {
    crate::font::ensure_registered();
    let font: FontDesc = (crate::font::FAMILY, size_px as f64).into_font();
    match font.box_size(text) {
        Ok((w, _)) => w,
        // The embedded font always lays out; if it ever did not, a generous estimate keeps the
        // title inside the image.
        Err(_) => (text.chars().count() as u32).saturating_mul(size_px),
    }
}

/// Greedy word wrap of `text` into lines of at most `width` px at `size` px; a word wider than
/// `width` on its own is split between characters only when `split_words` is set (otherwise it
/// overflows its line, which the caller treats as "does not fit").
fn wrap(text: &str, size: u32, width: u32, split_words: bool) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    let mut line = String::new();
    for word in text.split_whitespace() {
        let candidate = if line.is_empty() {
            word.to_string()
        } else {
            format!("{line} {word}")
        };
        if text_width_px(&candidate, size) <= width {
            line = candidate;
            continue;
        }
        if !line.is_empty() {
            lines.push(std::mem::take(&mut line));
        }
        if text_width_px(word, size) <= width || !split_words {
            line = word.to_string();
            continue;
        }
        for c in word.chars() {
            let mut longer = line.clone();
            longer.push(c);
            if !line.is_empty() && text_width_px(&longer, size) > width {
                lines.push(std::mem::take(&mut line));
                longer = c.to_string();
            }
            line = longer;
        }
    }
    if !line.is_empty() {
        lines.push(line);
    }
    lines
}

/// Lays out a title for an image (or panel) `width_px` wide: the largest size from
/// `preferred_px` down to [`MIN_TITLE_PX`] at which it fits on one line; else on two lines, then
/// three; else at [`MIN_TITLE_PX`] with over-long words split and the last line ended by "…".
/// Every line fits `width_px` less a 10 px margin on each side, except when the width cannot hold
/// a single character at the minimum size.
pub fn title_layout(text: &str, width_px: u32, preferred_px: u32) -> TitleLayout {
    let preferred = preferred_px.max(MIN_TITLE_PX);
    if text.trim().is_empty() {
        return TitleLayout {
            size_px: preferred,
            lines: Vec::new(),
        };
    }
    let available = width_px.saturating_sub(2 * TITLE_SIDE_MARGIN).max(1);
    for max_lines in 1..=MAX_TITLE_LINES {
        for size in (MIN_TITLE_PX..=preferred).rev() {
            let lines = wrap(text, size, available, false);
            if lines.len() <= max_lines && lines.iter().all(|l| text_width_px(l, size) <= available)
            {
                return TitleLayout {
                    size_px: size,
                    lines,
                };
            }
        }
    }
    let mut lines = wrap(text, MIN_TITLE_PX, available, true);
    if lines.len() > MAX_TITLE_LINES {
        lines.truncate(MAX_TITLE_LINES);
        let last = &mut lines[MAX_TITLE_LINES - 1];
        loop {
            let shortened = format!("{}…", last.trim_end());
            if text_width_px(&shortened, MIN_TITLE_PX) <= available || last.is_empty() {
                *last = shortened;
                break;
            }
            last.pop();
        }
    }
    TitleLayout {
        size_px: MIN_TITLE_PX,
        lines,
    }
}

/// Draws `title` at the top of `root` (laid out by [`title_layout`] for `root`'s width) and
/// returns the area below it (`root` itself when the title is empty).
pub(crate) fn titled_area<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
    preferred: u32,
) -> Result<DrawingArea<DB, plotters::coord::Shift>, BackendError> {
    let (width, height) = root.dim_in_pixel();
    let layout = title_layout(title, width, preferred);
    if layout.lines.is_empty() {
        return Ok(root.clone());
    }
    let style = (crate::font::FAMILY, layout.size_px)
        .into_font()
        .color(&BLACK)
        .pos(Pos::new(HPos::Center, VPos::Top));
    for (i, line) in layout.lines.iter().enumerate() {
        let y = TITLE_TOP_MARGIN + i as u32 * layout.line_height_px();
        root.draw_text(line, &style, ((width / 2) as i32, y as i32))
            .map_err(err)?;
    }
    let split = layout.height_px().min(height.saturating_sub(1));
    Ok(root.split_vertically(split).1)
}

/// Draws the axes of a 2D chart: axis descriptions from `spec`, tick labels formatted for the
/// ranges `x` and `y` and spaced by the plotting area's size, and light grid lines (left out
/// when `grid_lines` is false).
pub(crate) fn draw_axes<DB: DrawingBackend>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    spec: &PlotSpec,
    x: (f64, f64),
    y: (f64, f64),
    grid_lines: bool,
) -> Result<(), BackendError> {
    let (fx, fy) = (tick_formatter(x), tick_formatter(y));
    let (pw, ph) = chart.plotting_area().dim_in_pixel();
    let mut mesh = chart.configure_mesh();
    mesh.x_desc(spec.x_label.as_str())
        .y_desc(spec.y_label.as_str())
        .axis_desc_style(axis_desc_style())
        .label_style(tick_style())
        .x_labels(label_count(pw, 75))
        .y_labels(label_count(ph, 40))
        .x_label_formatter(&fx)
        .y_label_formatter(&fy)
        .bold_line_style(RGBColor(215, 215, 215))
        .light_line_style(RGBColor(240, 240, 240));
    if !grid_lines {
        mesh.disable_mesh();
    }
    mesh.draw().map_err(err)
}

/// Draws the legend of the labelled series of `chart` in a framed, slightly transparent box.
pub(crate) fn draw_legend<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
) -> Result<(), BackendError> {
    chart
        .configure_series_labels()
        .position(position)
        .background_style(WHITE.mix(0.88))
        .border_style(RGBColor(160, 160, 160))
        .label_font(legend_style())
        .margin(10)
        .draw()
        .map_err(err)
}

/// Axis description (label) text style.
pub(crate) fn axis_desc_style() -> TextStyle<'static> {
    (crate::font::FAMILY, 18).into_font().color(&BLACK)
}

/// Tick label text style.
pub(crate) fn tick_style() -> TextStyle<'static> {
    (crate::font::FAMILY, 15).into_font().color(&BLACK)
}

/// Legend text style.
pub(crate) fn legend_style() -> TextStyle<'static> {
    (crate::font::FAMILY, 15).into_font().color(&BLACK)
}

/// A tick-label formatter for an axis spanning `(lo, hi)`: values that are
/// zero up to rounding print as `0`, the number of decimals follows the span,
/// and very large or small magnitudes use scientific notation. Every plot here labels its axes
/// with it; a front end drawing its own chart of the same data can label it the same way.
pub fn tick_formatter((lo, hi): (f64, f64)) -> impl Fn(&f64) -> String {
    let span = (hi - lo).abs();
    let mag = lo.abs().max(hi.abs());
    let sci = !(1e-3..1e5).contains(&mag);
    let decimals = if span > 0.0 {
        ((-span.log10()).ceil() as i32 + 2).clamp(0, 6) as usize
    } else {
        3
    };
    move |v: &f64| {
        let v = if v.abs() <= span * 1e-9 { 0.0 } else { *v };
        if sci && v != 0.0 {
            fmt_tick(v)
        } else {
            let s = format!("{v:.decimals$}");
            let s = if s.contains('.') {
                s.trim_end_matches('0').trim_end_matches('.')
            } else {
                &s
            };
            if s == "-0" {
                "0".to_string()
            } else {
                s.to_string()
            }
        }
    }
}

/// How many tick labels fit along `pixels` at roughly one per `spacing`.
pub(crate) fn label_count(pixels: u32, spacing: u32) -> usize {
    ((pixels / spacing.max(1)) as usize).clamp(5, 12)
}

/// Compact tick label: few significant digits, scientific for extremes.
pub(crate) fn fmt_tick(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".to_string()
    } else if !(1e-3..1e5).contains(&a) {
        let s = format!("{v:.2e}");
        // Tidy "1.50e-4" -> "1.5e-4".
        match s.split_once('e') {
            Some((m, e)) => {
                let m = m.trim_end_matches('0').trim_end_matches('.');
                format!("{m}e{e}")
            }
            None => s,
        }
    } else {
        let s = format!("{v:.4}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        if s == "-0" {
            "0".to_string()
        } else {
            s.to_string()
        }
    }
}
