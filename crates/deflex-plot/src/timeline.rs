//! State timelines: named on/off states over time as horizontal bars, one lane per state (a
//! controller's flags: active, ramping, saturated, faulted, …), on a shared time axis.

use std::path::Path;

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::colormap::palette_rgb;
use crate::render::{
    axis_desc_style, check_range, err, label_count, padded, render, text_width_px, tick_formatter,
    tick_style, titled_area,
};
use crate::{Image, PlotError, PlotSpec};

/// One lane of a [`timeline_plot`]: a named state and the time intervals during which it held.
#[derive(Debug, Clone, PartialEq)]
pub struct Lane {
    /// Name shown left of the lane (say what "never" means when `intervals` is empty).
    pub label: String,
    /// `(start, end)` intervals, `start ≤ end`, in the x axis' unit.
    pub intervals: Vec<(f64, f64)>,
    /// Bar colour `(r, g, b)`; `None`: the palette colour of the lane's position.
    pub color: Option<(u8, u8, u8)>,
}

impl Lane {
    /// A lane from given intervals.
    pub fn new(label: impl Into<String>, intervals: Vec<(f64, f64)>) -> Self {
        Lane {
            label: label.into(),
            intervals,
            color: None,
        }
    }

    /// A lane from a sampled state: sample `k` (at `time[k]`) holds until `time[k + 1]`; the
    /// last sample holds for the previous sample spacing. Consecutive samples that hold merge
    /// into one interval. `time` must be non-decreasing; the shorter length of the two slices
    /// is used.
    pub fn from_samples(label: impl Into<String>, time: &[f64], on: &[bool]) -> Self {
        let n = time.len().min(on.len());
        let mut intervals: Vec<(f64, f64)> = Vec::new();
        let mut open: Option<f64> = None;
        for k in 0..n {
            let end = if k + 1 < n {
                time[k + 1]
            } else if k > 0 {
                time[k] + (time[k] - time[k - 1])
            } else {
                time[k]
            };
            match (on[k], open) {
                (true, None) => open = Some(time[k]),
                (false, Some(start)) => {
                    intervals.push((start, time[k]));
                    open = None;
                }
                _ => {}
            }
            if k + 1 == n
                && let Some(start) = open
            {
                intervals.push((start, end));
            }
        }
        Lane::new(label, intervals)
    }

    /// The same lane drawn in `color`.
    pub fn with_color(mut self, color: (u8, u8, u8)) -> Self {
        self.color = Some(color);
        self
    }

    /// Total time the state held (sum of the interval lengths).
    pub fn duration(&self) -> f64 {
        self.intervals.iter().map(|(a, b)| b - a).sum()
    }
}

/// Draws on/off states over time, one lane per [`Lane`] (top to bottom in the given order), with
/// the lane names left of the chart and `spec`'s x label below it, as the bytes of a `.png` or
/// `.svg` file (by `path`'s extension; `path` also names the image in errors, nothing is written).
/// `spec.y_label` is ignored; `spec.x_range` fixes the time axis (give it when every lane may be
/// empty). Intervals shorter than a pixel are still drawn one pixel wide, so a single faulted
/// cycle stays visible.
///
/// Errors if `lanes` is empty, an interval is not finite or has `end < start`, or there is no
/// interval and no `x_range`.
pub fn timeline_plot(path: &Path, spec: &PlotSpec, lanes: &[Lane]) -> Result<Image, PlotError> {
    if lanes.is_empty() {
        return Err(PlotError::invalid(path, "no lanes given"));
    }
    for lane in lanes {
        if let Some((a, b)) = lane
            .intervals
            .iter()
            .find(|(a, b)| !(a.is_finite() && b.is_finite() && a <= b))
        {
            return Err(PlotError::invalid(
                path,
                format!(
                    "lane {:?}: interval ({a}, {b}) must be finite with start ≤ end",
                    lane.label
                ),
            ));
        }
    }
    let extent = lanes.iter().flat_map(|l| l.intervals.iter()).fold(
        None,
        |acc: Option<(f64, f64)>, &(a, b)| match acc {
            None => Some((a, b)),
            Some((lo, hi)) => Some((lo.min(a), hi.max(b))),
        },
    );
    let xr = match (spec.x_range, extent) {
        (Some(r), _) => r,
        (None, Some(e)) => padded(e, 0.0),
        (None, None) => {
            return Err(PlotError::invalid(
                path,
                "no interval in any lane and no x range",
            ));
        }
    };
    check_range(path, "x", xr)?;
    let n = lanes.len();
    let label_px = lanes
        .iter()
        .map(|l| text_width_px(&l.label, 15))
        .max()
        .unwrap_or(0);
    // At least the 86 px of the line charts, so that stacked figures share their left edge.
    let label_area = (label_px + 24).max(86);
    render!(path, (spec.width, spec.height), |root| {
        let body = titled_area(root, &spec.title, 24)?;
        let mut chart = ChartBuilder::on(&body)
            .margin(14)
            .x_label_area_size(58)
            .y_label_area_size(label_area)
            .build_cartesian_2d(xr.0..xr.1, -0.5..(n as f64 - 0.5))
            .map_err(err)?;
        let fx = tick_formatter(xr);
        let (pw, _) = chart.plotting_area().dim_in_pixel();
        chart
            .configure_mesh()
            .disable_y_mesh()
            .y_labels(0)
            .x_desc(spec.x_label.as_str())
            .axis_desc_style(axis_desc_style())
            .label_style(tick_style())
            .x_labels(label_count(pw, 75))
            .x_label_formatter(&fx)
            .bold_line_style(RGBColor(215, 215, 215))
            .light_line_style(RGBColor(240, 240, 240))
            .draw()
            .map_err(err)?;
        // Lane k is drawn at y = n − 1 − k so that the first lane is on top; bars fill 70 % of it.
        let lane_y = |k: usize| (n - 1 - k) as f64;
        let px_per_x = pw as f64 / (xr.1 - xr.0);
        for (k, lane) in lanes.iter().enumerate() {
            let color = match lane.color {
                Some((r, g, b)) => RGBColor(r, g, b),
                None => palette_rgb(k),
            };
            let y = lane_y(k);
            chart
                .draw_series(std::iter::once(Rectangle::new(
                    [(xr.0, y - 0.5), (xr.1, y + 0.5)],
                    RGBColor(248, 248, 248).filled(),
                )))
                .map_err(err)?;
            let min_width = 1.0 / px_per_x;
            chart
                .draw_series(lane.intervals.iter().map(|&(a, b)| {
                    let b = b.max(a + min_width);
                    Rectangle::new([(a, y - 0.35), (b, y + 0.35)], color.filled())
                }))
                .map_err(err)?;
            let (px, py) = chart.backend_coord(&(xr.0, y));
            let style = tick_style().pos(Pos::new(HPos::Right, VPos::Center));
            root.draw_text(&lane.label, &style, (px - 8, py))
                .map_err(err)?;
        }
        chart
            .draw_series(std::iter::once(Rectangle::new(
                [(xr.0, -0.5), (xr.1, n as f64 - 0.5)],
                RGBColor(160, 160, 160).stroke_width(1),
            )))
            .map_err(err)?;
        Ok(())
    })
}
