//! 2D line/point plots: single charts, grids of panels and parity
//! (predicted vs measured) plots.

use std::path::Path;

use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;

use crate::colormap::palette_rgb;
use crate::render::{
    BackendError, check_range, draw_axes, draw_legend, err, finite_extent, fmt_tick, padded,
    render, titled_area,
};
use crate::{Image, LineStyle, PlotError, PlotSpec, Series, SeriesStyle};

/// How the panels of [`panels_plot`] are arranged.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PanelLayout {
    /// One column, panels stacked top to bottom (e.g. x, y, z error and
    /// norm along a path, Fig. A1).
    #[default]
    Column,
    /// One row, panels side by side left to right (e.g. forces without and
    /// with compensation, Fig. 18).
    Row,
    /// A grid with this many columns, filled row by row.
    Grid {
        /// Number of columns (at least 1).
        columns: usize,
    },
}

/// A validated series broken into runs of finite points.
pub(crate) struct Prepared<'a> {
    pub(crate) series: &'a Series,
    pub(crate) runs: Vec<Vec<(f64, f64)>>,
}

/// A chart's finite runs per series, and its x and y ranges.
pub(crate) type PreparedChart<'a> = (Vec<Prepared<'a>>, (f64, f64), (f64, f64));

/// Checks the series of one chart and returns their finite runs and the
/// chart's x and y ranges.
pub(crate) fn prepare<'a>(
    path: &Path,
    spec: &PlotSpec,
    series: &'a [Series],
) -> Result<PreparedChart<'a>, PlotError> {
    let ctx = |msg: String| {
        if spec.title.is_empty() {
            msg
        } else {
            format!("plot {:?}: {msg}", spec.title)
        }
    };
    if series.is_empty() {
        return Err(PlotError::invalid(path, ctx("no series given".into())));
    }
    let mut prepared = Vec::with_capacity(series.len());
    let (mut xs, mut ys) = (Vec::new(), Vec::new());
    for s in series {
        if s.x.len() != s.y.len() {
            return Err(PlotError::invalid(
                path,
                ctx(format!(
                    "series {:?}: x has {} values but y has {}",
                    s.label,
                    s.x.len(),
                    s.y.len()
                )),
            ));
        }
        if s.x.is_empty() {
            return Err(PlotError::invalid(
                path,
                ctx(format!("series {:?} is empty", s.label)),
            ));
        }
        let mut runs = Vec::new();
        let mut run = Vec::new();
        for (&x, &y) in s.x.iter().zip(&s.y) {
            if x.is_finite() && y.is_finite() {
                run.push((x, y));
                xs.push(x);
                ys.push(y);
            } else if !run.is_empty() {
                runs.push(std::mem::take(&mut run));
            }
        }
        if !run.is_empty() {
            runs.push(run);
        }
        prepared.push(Prepared { series: s, runs });
    }
    let (Some(xe), Some(ye)) = (finite_extent(&xs), finite_extent(&ys)) else {
        return Err(PlotError::invalid(
            path,
            ctx("no finite (x, y) point in any series".into()),
        ));
    };
    let xr = spec.x_range.unwrap_or_else(|| padded(xe, 0.02));
    let yr = spec.y_range.unwrap_or_else(|| padded(ye, 0.06));
    check_range(path, "x", xr)?;
    check_range(path, "y", yr)?;
    Ok((prepared, xr, yr))
}

/// The plot corner where the legend box (estimated from its labels and the
/// plot's pixel size) covers the least data (lines are sampled along their
/// segments), so the legend hides as little as possible. Ties go to upper
/// right, then upper left, lower right, lower left.
fn legend_corner(
    prepared: &[Prepared<'_>],
    (x0, x1): (f64, f64),
    (y0, y1): (f64, f64),
    (pw, ph): (u32, u32),
) -> SeriesLabelPosition {
    let labels: Vec<&str> = prepared
        .iter()
        .map(|p| p.series.label.as_str())
        .filter(|l| !l.is_empty())
        .collect();
    let chars = labels.iter().map(|l| l.chars().count()).max().unwrap_or(0);
    // Legend size in pixels (15 px font: ~8.5 px per character, 20 px rows)
    // plus its 10 px margin, as a fraction of the plotting area.
    let fw = ((chars as f64 * 8.5 + 60.0) / pw.max(1) as f64).min(1.0);
    let fh = ((labels.len() as f64 * 20.0 + 30.0) / ph.max(1) as f64).min(1.0);
    // Corner boxes in normalised coordinates: (x from, x to, y from, y to).
    let boxes = [
        (
            SeriesLabelPosition::UpperRight,
            (1.0 - fw, 1.0, 1.0 - fh, 1.0),
        ),
        (SeriesLabelPosition::UpperLeft, (0.0, fw, 1.0 - fh, 1.0)),
        (SeriesLabelPosition::LowerRight, (1.0 - fw, 1.0, 0.0, fh)),
        (SeriesLabelPosition::LowerLeft, (0.0, fw, 0.0, fh)),
    ];
    let mut counts = [0usize; 4];
    let mut visit = |x: f64, y: f64| {
        let (u, v) = ((x - x0) / (x1 - x0), (y - y0) / (y1 - y0));
        for (k, (_, (ua, ub, va, vb))) in boxes.iter().enumerate() {
            if (*ua..=*ub).contains(&u) && (*va..=*vb).contains(&v) {
                counts[k] += 1;
            }
        }
    };
    for p in prepared {
        for run in &p.runs {
            if let [only] = run.as_slice() {
                visit(only.0, only.1);
            }
            for w in run.windows(2) {
                for s in 0..8 {
                    let f = s as f64 / 8.0;
                    visit(
                        w[0].0 + f * (w[1].0 - w[0].0),
                        w[0].1 + f * (w[1].1 - w[0].1),
                    );
                }
            }
            if let Some(last) = run.last() {
                visit(last.0, last.1);
            }
        }
    }
    let best = (0..4).min_by_key(|&k| counts[k]).unwrap_or(0);
    boxes[best].0.clone()
}

/// The part of the segment `a`–`b` inside the rectangle `[x0, x1] × [y0, y1]`, as fractions
/// `(t_in, t_out)` of the way from `a` to `b`, or `None` when no part is inside (Liang–Barsky:
/// each of the four edges bounds `t` from one side, by `p t ≤ q`). [`strokable_pieces`] clips
/// with it.
pub fn clip_segment(
    a: (f64, f64),
    b: (f64, f64),
    (x0, x1): (f64, f64),
    (y0, y1): (f64, f64),
) -> Option<(f64, f64)> {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let (mut t_in, mut t_out) = (0.0f64, 1.0f64);
    for (p, q) in [
        (-dx, a.0 - x0),
        (dx, x1 - a.0),
        (-dy, a.1 - y0),
        (dy, y1 - a.1),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return None; // parallel to this edge and outside it
            }
        } else if p < 0.0 {
            t_in = t_in.max(q / p);
        } else {
            t_out = t_out.min(q / p);
        }
    }
    (t_in <= t_out).then_some((t_in, t_out))
}

/// Shortest segment (px) [`strokable_pieces`] keeps: shorter steps are merged into the next one.
const MIN_STEP_PX: f64 = 3.0;

/// The polylines that draw `run` on a plotting area of `pw × ph` pixels showing
/// `[x0, x1] × [y0, y1]`: clipped to that rectangle (nothing is drawn over the axes and tick
/// labels), with vertices at least 3 px apart, and cut at every vertex where the line turns by
/// more than 60° on screen. Every line series here is drawn this way; a front end stroking its
/// own wide lines with plotters can use it the same way.
///
/// Why: plotters strokes a wide line as one polygon whose corners are where the offset edges of
/// neighbouring segments meet; at a near-reversal (a spike one pixel wide, common in dense logs)
/// the inner corner lies at `d / cos(φ/2)` from the line for a turn of φ, unbounded as φ → 180°,
/// and draws long needles through the chart and its labels. Each stroke here ends at a sharp
/// vertex instead (the two strokes overlap there). The backend rounds pixels its own way, which
/// can turn a 1 px step anywhere; on steps of 3 px or more that moves a direction by at most
/// ~50°, so no stroke it draws turns by more than ~110° and no corner lies more than
/// `d / cos 55° ≈ 1.7 d` from the line.
pub fn strokable_pieces(
    run: &[(f64, f64)],
    (x0, x1): (f64, f64),
    (y0, y1): (f64, f64),
    (pw, ph): (u32, u32),
) -> Vec<Vec<(f64, f64)>> {
    let (sx, sy) = (pw as f64 / (x1 - x0), ph as f64 / (y1 - y0));
    let pixel = |(x, y): (f64, f64)| ((x - x0) * sx, (y1 - y) * sy);
    let cos_60 = 0.5;
    let mut pieces: Vec<Vec<(f64, f64)>> = Vec::new();
    // The piece being built, and the point merged into its next step (closer than the minimum).
    let mut current: Vec<(f64, f64)> = Vec::new();
    let mut pending: Option<(f64, f64)> = None;
    let mut finish = |current: &mut Vec<(f64, f64)>, pending: &mut Option<(f64, f64)>| {
        if current.len() == 1
            && let Some(p) = pending.take()
        {
            current.push(p); // a run shorter than the minimum step: drawn as it is
        }
        *pending = None;
        if current.len() > 1 {
            pieces.push(std::mem::take(current));
        } else {
            current.clear();
        }
    };
    for w in run.windows(2) {
        let (a, b) = (w[0], w[1]);
        let Some((t_in, t_out)) = clip_segment(a, b, (x0, x1), (y0, y1)) else {
            finish(&mut current, &mut pending);
            continue;
        };
        let at = |t: f64| (a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1));
        let (start, end) = (at(t_in), at(t_out));
        if t_in > 0.0 || current.is_empty() {
            // Entering the rectangle (or starting): a new piece.
            finish(&mut current, &mut pending);
            current.push(start);
        }
        let last = pixel(*current.last().unwrap_or(&start));
        let p = pixel(end);
        let step = (p.0 - last.0, p.1 - last.1);
        if step.0.hypot(step.1) < MIN_STEP_PX {
            pending = Some(end);
        } else {
            if let [.., before, vertex] = current.as_slice() {
                let o = pixel(*before);
                let u = (last.0 - o.0, last.1 - o.1);
                let cos = (u.0 * step.0 + u.1 * step.1) / (u.0.hypot(u.1) * step.0.hypot(step.1));
                if cos < cos_60 {
                    // A sharp turn: end this piece at the vertex, start the next there.
                    let vertex = *vertex;
                    pending = None;
                    finish(&mut current, &mut pending);
                    current.push(vertex);
                }
            }
            current.push(end);
            pending = None;
        }
        if t_out < 1.0 {
            finish(&mut current, &mut pending);
        }
    }
    finish(&mut current, &mut pending);
    pieces
}

/// A polyline in `color`, solid or with the dash pattern of `line`, as a dynamic element.
fn stroke<DB: DrawingBackend, C: Clone + 'static>(
    points: Vec<C>,
    line: LineStyle,
    style: ShapeStyle,
) -> DynElement<'static, DB, C>
where
    PathElement<C>: IntoDynElement<'static, DB, C>,
    DashedPathElement<std::vec::IntoIter<C>, u32>: IntoDynElement<'static, DB, C>,
{
    match line.pattern_px() {
        None => PathElement::new(points, style).into_dyn(),
        Some((dash, gap)) => DashedPathElement::new(points, dash, gap, style).into_dyn(),
    }
}

/// Draws one chart with its title, series and legend onto `area`.
fn draw_chart<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    spec: &PlotSpec,
    prepared: &[Prepared<'_>],
    (x0, x1): (f64, f64),
    (y0, y1): (f64, f64),
    marker_size: u32,
    colors: &[RGBColor],
) -> Result<(), BackendError> {
    let body = titled_area(area, &spec.title, 24)?;
    let mut chart = ChartBuilder::on(&body)
        .margin(14)
        .x_label_area_size(58)
        .y_label_area_size(86)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(err)?;
    let (pw, ph) = chart.plotting_area().dim_in_pixel();
    draw_axes(&mut chart, spec, (x0, x1), (y0, y1), true)?;

    let mut any_label = false;
    for (i, p) in prepared.iter().enumerate() {
        let color = match p.series.color {
            Some((r, g, b)) => RGBColor(r, g, b),
            None => colors.get(i).copied().unwrap_or_else(|| palette_rgb(i)),
        };
        let style = p.series.style;
        let line = p.series.line;
        let with_line = matches!(style, SeriesStyle::Line | SeriesStyle::LineAndPoints);
        let with_points = matches!(style, SeriesStyle::Points | SeriesStyle::LineAndPoints);
        let inside = |&(x, y): &(f64, f64)| (x0..=x1).contains(&x) && (y0..=y1).contains(&y);
        let mut first = true;
        for run in &p.runs {
            let mut elements: Vec<DynElement<'static, DB, (f64, f64)>> = Vec::new();
            if with_line && run.len() > 1 {
                for piece in strokable_pieces(run, (x0, x1), (y0, y1), (pw, ph)) {
                    elements.push(stroke(piece, line, color.stroke_width(2)));
                }
            }
            if with_points || run.len() == 1 {
                for &pt in run.iter().filter(|pt| inside(pt)) {
                    elements.push(Circle::new(pt, marker_size, color.filled()).into_dyn());
                }
            }
            let anno = chart.draw_series(elements).map_err(err)?;
            if first && !p.series.label.is_empty() {
                any_label = true;
                anno.label(p.series.label.as_str()).legend(
                    move |(x, y)| -> DynElement<'static, DB, (i32, i32)> {
                        if with_line {
                            // 30 px: room for two dashes or several dots of the pattern.
                            stroke(vec![(x - 4, y), (x + 26, y)], line, color.stroke_width(3))
                        } else {
                            Circle::new((x + 11, y), 4, color.filled()).into_dyn()
                        }
                    },
                );
            }
            first = false;
        }
    }
    if any_label {
        let corner = legend_corner(prepared, (x0, x1), (y0, y1), (pw, ph));
        draw_legend(&mut chart, corner)?;
    }
    Ok(())
}

/// Draws a 2D chart of one or more series (lines and/or markers) with title, axis labels and a
/// legend, as the bytes of a `.png` or `.svg` file (by `path`'s extension; `path` also names
/// the image in errors, nothing is written).
///
/// Errors if `series` is empty, a series is empty or has `x`/`y` of different
/// lengths, or no point is finite. Non-finite points are skipped and break
/// lines.
pub fn line_plot(path: &Path, spec: &PlotSpec, series: &[Series]) -> Result<Image, PlotError> {
    let (prepared, xr, yr) = prepare(path, spec, series)?;
    render!(path, (spec.width, spec.height), |root| draw_chart(
        root,
        spec,
        &prepared,
        xr,
        yr,
        3,
        &[]
    ))
}

/// Draws several charts in one image, under a common `title`, arranged by
/// `layout`. Each panel uses its own [`PlotSpec`] for title, labels and
/// ranges; every cell gets the largest panel width and height. Give panels
/// the same `y_range` to compare them directly. Returns the bytes of the `.png` or `.svg` file
/// (by `path`'s extension, as [`line_plot`]).
pub fn panels_plot(
    path: &Path,
    title: &str,
    layout: PanelLayout,
    panels: &[(PlotSpec, Vec<Series>)],
) -> Result<Image, PlotError> {
    if panels.is_empty() {
        return Err(PlotError::invalid(path, "no panels given"));
    }
    let (rows, cols) = match layout {
        PanelLayout::Column => (panels.len(), 1),
        PanelLayout::Row => (1, panels.len()),
        PanelLayout::Grid { columns: 0 } => {
            return Err(PlotError::invalid(path, "grid layout with 0 columns"));
        }
        PanelLayout::Grid { columns } => (panels.len().div_ceil(columns), columns),
    };
    let mut prepared = Vec::with_capacity(panels.len());
    for (spec, series) in panels {
        prepared.push(prepare(path, spec, series)?);
    }
    let cell_w = panels.iter().map(|(s, _)| s.width).max().unwrap_or(800);
    let cell_h = panels.iter().map(|(s, _)| s.height).max().unwrap_or(400);
    let title_h: u32 = if title.is_empty() { 0 } else { 50 };
    let w = cell_w.saturating_mul(cols as u32);
    let h = cell_h.saturating_mul(rows as u32).saturating_add(title_h);
    render!(path, (w, h), |root| {
        let body = titled_area(root, title, 28)?;
        let cells = body.split_evenly((rows, cols));
        let mut result = Ok(());
        for (cell, ((spec, _), (p, xr, yr))) in cells.iter().zip(panels.iter().zip(&prepared)) {
            result = draw_chart(cell, spec, p, *xr, *yr, 3, &[]);
            if result.is_err() {
                break;
            }
        }
        result
    })
}

/// Draws predicted against measured values as points, with the `y = x`
/// line. Measured values are on the x axis, predicted on the y axis (label
/// the axes accordingly in `spec`); both axes share one range so that
/// perfect predictions lie on the diagonal. The legend shows `label`, the
/// number of points and the RMSE of `predicted - measured`. A square `spec`
/// size (e.g. `.size(700, 700)`) reads best.
///
/// Pairs where either value is not finite are skipped. Returns the bytes of the `.png` or `.svg`
/// file (by `path`'s extension, as [`line_plot`]).
pub fn parity_plot(
    path: &Path,
    spec: &PlotSpec,
    predicted: &[f64],
    measured: &[f64],
    label: &str,
) -> Result<Image, PlotError> {
    if predicted.len() != measured.len() {
        return Err(PlotError::invalid(
            path,
            format!(
                "predicted has {} values but measured has {}",
                predicted.len(),
                measured.len()
            ),
        ));
    }
    if predicted.is_empty() {
        return Err(PlotError::invalid(path, "no values given"));
    }
    let (mx, py): (Vec<f64>, Vec<f64>) = measured
        .iter()
        .zip(predicted)
        .filter(|(m, p)| m.is_finite() && p.is_finite())
        .map(|(&m, &p)| (m, p))
        .unzip();
    if mx.is_empty() {
        return Err(PlotError::invalid(
            path,
            "no finite (predicted, measured) pair",
        ));
    }
    let n = mx.len();
    let rmse = (mx
        .iter()
        .zip(&py)
        .map(|(m, p)| (p - m).powi(2))
        .sum::<f64>()
        / n as f64)
        .sqrt();
    let extent = finite_extent(mx.iter().chain(&py)).unwrap_or((0.0, 1.0));
    let (lo, hi) = padded(extent, 0.05);
    let mut spec = spec.clone();
    spec.x_range = Some(spec.x_range.unwrap_or((lo, hi)));
    spec.y_range = Some(spec.y_range.unwrap_or((lo, hi)));
    let (dlo, dhi) = (
        spec.x_range
            .map_or(lo, |r| r.0)
            .min(spec.y_range.map_or(lo, |r| r.0)),
        spec.x_range
            .map_or(hi, |r| r.1)
            .max(spec.y_range.map_or(hi, |r| r.1)),
    );
    let legend = if label.is_empty() {
        format!("n = {n}, RMSE = {}", fmt_tick(rmse))
    } else {
        format!("{label} (n = {n}, RMSE = {})", fmt_tick(rmse))
    };
    // The diagonal is drawn first (in grey) so the points stay on top.
    let series = [
        Series::line("y = x", vec![dlo, dhi], vec![dlo, dhi]),
        Series::points(legend, mx, py),
    ];
    let (prepared, xr, yr) = prepare(path, &spec, &series)?;
    let colors = [RGBColor(120, 120, 120), palette_rgb(0)];
    render!(path, (spec.width, spec.height), |root| draw_chart(
        root, &spec, &prepared, xr, yr, 4, &colors
    ))
}
