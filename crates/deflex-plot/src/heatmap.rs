//! Heatmaps with a viridis colour bar: over a regular grid of cells, and over
//! scattered points coloured by value.

use std::path::Path;

use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::colormap::viridis_rgb;
use crate::render::{
    BackendError, axis_desc_style, check_range, draw_axes, err, finite_extent, padded, render,
    tick_formatter, tick_style, titled_area,
};
use crate::{Image, PlotError, PlotSpec};

/// Width in pixels reserved at the right for the colour bar.
const BAR_AREA: u32 = 140;
/// Label areas shared by the main chart and the colour bar so they align.
const X_AREA: u32 = 58;
const Y_AREA: u32 = 86;
const MARGIN: u32 = 14;

/// Cell edges from strictly increasing centres: midpoints between
/// neighbours, and half a neighbour spacing beyond the ends (a single centre `c` gets ±5 % of
/// `|c|`, or ±0.5 at zero). The cells [`heatmap`] draws around its grid's `xs` and `ys`.
pub fn cell_edges(centers: &[f64]) -> Vec<f64> {
    let n = centers.len();
    if n == 1 {
        let c = centers[0];
        let half = if c == 0.0 { 0.5 } else { c.abs() * 0.05 };
        return vec![c - half, c + half];
    }
    let mut e = Vec::with_capacity(n + 1);
    e.push(centers[0] - 0.5 * (centers[1] - centers[0]));
    for w in centers.windows(2) {
        e.push(0.5 * (w[0] + w[1]));
    }
    e.push(centers[n - 1] + 0.5 * (centers[n - 1] - centers[n - 2]));
    e
}

fn check_centers(path: &Path, axis: &str, c: &[f64]) -> Result<(), PlotError> {
    if c.is_empty() {
        return Err(PlotError::invalid(path, format!("no {axis} centres given")));
    }
    if c.iter().any(|v| !v.is_finite()) {
        return Err(PlotError::invalid(
            path,
            format!("{axis} centres must be finite"),
        ));
    }
    if c.windows(2).any(|w| w[1] <= w[0]) {
        return Err(PlotError::invalid(
            path,
            format!("{axis} centres must be strictly increasing"),
        ));
    }
    Ok(())
}

fn color_range(path: &Path, spec: &PlotSpec, values: &[f64]) -> Result<(f64, f64), PlotError> {
    let range = match spec.color_range {
        Some(r) => r,
        None => {
            let e = finite_extent(values)
                .ok_or_else(|| PlotError::invalid(path, "no finite value to colour"))?;
            if e.0 < e.1 { e } else { padded(e, 0.0) }
        }
    };
    check_range(path, "colour", range)?;
    Ok(range)
}

fn normalized(v: f64, (lo, hi): (f64, f64)) -> f64 {
    (v - lo) / (hi - lo)
}

/// The main chart area and the colour-bar area.
type MainAndBar<DB> = (DrawingArea<DB, Shift>, DrawingArea<DB, Shift>);

/// Splits the (titled) root into the main area and the colour-bar area.
fn layout<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
) -> Result<MainAndBar<DB>, BackendError> {
    let body = titled_area(root, title, 24)?;
    let (w, _) = body.dim_in_pixel();
    Ok(body.split_horizontally(w.saturating_sub(BAR_AREA)))
}

fn main_chart<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    spec: &PlotSpec,
    (x0, x1): (f64, f64),
    (y0, y1): (f64, f64),
    grid_lines: bool,
) -> Result<ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>, BackendError> {
    let mut chart = ChartBuilder::on(area)
        .margin(MARGIN)
        .margin_right(4)
        .x_label_area_size(X_AREA)
        .y_label_area_size(Y_AREA)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(err)?;
    draw_axes(&mut chart, spec, (x0, x1), (y0, y1), grid_lines)?;
    Ok(chart)
}

/// Draws a vertical viridis colour bar for `range` with tick labels and
/// `label` on its right.
fn colorbar<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    (lo, hi): (f64, f64),
    label: &str,
) -> Result<(), BackendError> {
    let ticks = tick_formatter((lo, hi));
    let mut bar = ChartBuilder::on(area)
        .margin_top(MARGIN)
        .margin_bottom(MARGIN)
        .margin_left(14)
        .margin_right(4)
        .x_label_area_size(X_AREA)
        .set_label_area_size(LabelAreaPosition::Right, 84)
        .build_cartesian_2d(0.0..1.0, lo..hi)
        .map_err(err)?;
    bar.configure_mesh()
        .disable_mesh()
        .x_labels(0)
        .y_labels(8)
        .y_desc(label)
        .axis_desc_style(axis_desc_style())
        .label_style(tick_style())
        // A leading space keeps labels clear of the tick marks.
        .y_label_formatter(&|v| format!(" {}", ticks(v)))
        .draw()
        .map_err(err)?;
    let steps = 256;
    let step = (hi - lo) / steps as f64;
    bar.draw_series((0..steps).map(|k| {
        let v0 = lo + k as f64 * step;
        let color = viridis_rgb((k as f64 + 0.5) / steps as f64);
        Rectangle::new([(0.0, v0), (1.0, v0 + step)], color.filled())
    }))
    .map_err(err)?;
    bar.draw_series(std::iter::once(Rectangle::new(
        [(0.0, lo), (1.0, hi)],
        BLACK.stroke_width(1),
    )))
    .map_err(err)?;
    Ok(())
}

/// Draws a heatmap of `values` over a regular grid, with a viridis colour bar labelled
/// `colorbar_label`, as the bytes of a `.png` or `.svg` file (by `path`'s extension; `path` also
/// names the image in errors, nothing is written).
///
/// `values` is row-major with y outer: the value of the cell centred at
/// `(x_centers[i], y_centers[j])` is `values[j * x_centers.len() + i]`.
/// Centres must be finite and strictly increasing (spacing may vary); cells
/// extend half-way to their neighbours. Non-finite values leave their cell
/// blank. When cells are large enough their value is written inside.
/// `spec.color_range` fixes the colour scale (values outside are clamped),
/// e.g. to compare two heatmaps.
pub fn heatmap(
    path: &Path,
    spec: &PlotSpec,
    x_centers: &[f64],
    y_centers: &[f64],
    values: &[f64],
    colorbar_label: &str,
) -> Result<Image, PlotError> {
    check_centers(path, "x", x_centers)?;
    check_centers(path, "y", y_centers)?;
    let (nx, ny) = (x_centers.len(), y_centers.len());
    if values.len() != nx * ny {
        return Err(PlotError::invalid(
            path,
            format!(
                "values has {} entries but the grid is {nx} (x) × {ny} (y) = {}",
                values.len(),
                nx * ny
            ),
        ));
    }
    let crange = color_range(path, spec, values)?;
    let (xe, ye) = (cell_edges(x_centers), cell_edges(y_centers));
    let xr = spec.x_range.unwrap_or((xe[0], xe[nx]));
    let yr = spec.y_range.unwrap_or((ye[0], ye[ny]));
    check_range(path, "x", xr)?;
    check_range(path, "y", yr)?;
    render!(path, (spec.width, spec.height), |root| {
        let (main, bar) = layout(root, &spec.title)?;
        let mut chart = main_chart(&main, spec, xr, yr, false)?;
        let mut cells = Vec::new();
        for j in 0..ny {
            for i in 0..nx {
                let v = values[j * nx + i];
                if v.is_finite() {
                    let c = viridis_rgb(normalized(v, crange));
                    cells.push(Rectangle::new(
                        [(xe[i], ye[j]), (xe[i + 1], ye[j + 1])],
                        c.filled(),
                    ));
                }
            }
        }
        chart.draw_series(cells).map_err(err)?;
        // Annotate when every cell is at least ~56 × 24 pixels.
        let px = |x: f64, y: f64| chart.backend_coord(&(x, y));
        let min_w = (0..nx)
            .map(|i| px(xe[i + 1], ye[0]).0 - px(xe[i], ye[0]).0)
            .min();
        let min_h = (0..ny)
            .map(|j| px(xe[0], ye[j]).1 - px(xe[0], ye[j + 1]).1)
            .min();
        if min_w.unwrap_or(0) >= 56 && min_h.unwrap_or(0) >= 24 {
            let mut labels = Vec::new();
            for j in 0..ny {
                for i in 0..nx {
                    let v = values[j * nx + i];
                    if !v.is_finite() {
                        continue;
                    }
                    let t = normalized(v, crange);
                    let color = if t > 0.6 { BLACK } else { WHITE };
                    let style = (crate::font::FAMILY, 15)
                        .into_font()
                        .color(&color)
                        .pos(Pos::new(HPos::Center, VPos::Center));
                    labels.push(Text::new(
                        cell_value_text(v),
                        (x_centers[i], y_centers[j]),
                        style,
                    ));
                }
            }
            chart.draw_series(labels).map_err(err)?;
        }
        chart
            .draw_series(std::iter::once(Rectangle::new(
                [(xr.0, yr.0), (xr.1, yr.1)],
                BLACK.stroke_width(1),
            )))
            .map_err(err)?;
        colorbar(&bar, crange, colorbar_label)
    })
}

/// A value as [`heatmap`] prints it in its cells: three significant digits, scientific notation
/// below 0.01 and from 10 000 on.
pub fn cell_value_text(v: f64) -> String {
    let a = v.abs();
    if a != 0.0 && !(1e-2..1e4).contains(&a) {
        format!("{v:.2e}")
    } else if a >= 100.0 {
        format!("{v:.0}")
    } else if a >= 10.0 {
        format!("{v:.1}")
    } else if a >= 1.0 {
        format!("{v:.2}")
    } else {
        format!("{v:.3}")
    }
}

/// Draws scattered points at `(x[k], y[k])` coloured by `value[k]` on the viridis scale, with a
/// colour bar labelled `colorbar_label`, as the bytes of a `.png` or `.svg` file (by `path`'s
/// extension; `path` also names the image in errors, nothing is written). Use it for measured
/// grids that are not regular.
///
/// The three slices must have equal, non-zero lengths. Points with a
/// non-finite coordinate or value are skipped. `spec.color_range` fixes the
/// colour scale.
pub fn scatter_heatmap(
    path: &Path,
    spec: &PlotSpec,
    x: &[f64],
    y: &[f64],
    value: &[f64],
    colorbar_label: &str,
) -> Result<Image, PlotError> {
    if x.len() != y.len() || x.len() != value.len() {
        return Err(PlotError::invalid(
            path,
            format!(
                "x, y and value must have equal lengths (got {}, {}, {})",
                x.len(),
                y.len(),
                value.len()
            ),
        ));
    }
    if x.is_empty() {
        return Err(PlotError::invalid(path, "no points given"));
    }
    let pts: Vec<(f64, f64, f64)> = (0..x.len())
        .map(|k| (x[k], y[k], value[k]))
        .filter(|(a, b, c)| a.is_finite() && b.is_finite() && c.is_finite())
        .collect();
    if pts.is_empty() {
        return Err(PlotError::invalid(
            path,
            "no point with finite x, y and value",
        ));
    }
    let vals: Vec<f64> = pts.iter().map(|p| p.2).collect();
    let crange = color_range(path, spec, &vals)?;
    let xe = finite_extent(pts.iter().map(|p| &p.0)).unwrap_or((0.0, 1.0));
    let ye = finite_extent(pts.iter().map(|p| &p.1)).unwrap_or((0.0, 1.0));
    let xr = spec.x_range.unwrap_or_else(|| padded(xe, 0.06));
    let yr = spec.y_range.unwrap_or_else(|| padded(ye, 0.06));
    check_range(path, "x", xr)?;
    check_range(path, "y", yr)?;
    let radius = match pts.len() {
        0..=200 => 8,
        201..=1000 => 5,
        _ => 3,
    };
    render!(path, (spec.width, spec.height), |root| {
        let (main, bar) = layout(root, &spec.title)?;
        let mut chart = main_chart(&main, spec, xr, yr, true)?;
        let outline = RGBColor(60, 60, 60);
        chart
            .draw_series(pts.iter().map(|&(px, py, v)| {
                let c = viridis_rgb(normalized(v, crange));
                EmptyElement::at((px, py))
                    + Circle::new((0, 0), radius, c.filled())
                    + Circle::new((0, 0), radius, outline.stroke_width(1))
            }))
            .map_err(err)?;
        colorbar(&bar, crange, colorbar_label)
    })
}
