//! 3D scatter plots of point clouds (e.g. deviation clouds, Fig. 17).

use std::path::Path;

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::colormap::palette_rgb;
use crate::render::{
    check_range, draw_legend, err, finite_extent, padded, render, tick_formatter, tick_style,
    titled_area,
};
use crate::{Image, PlotError};

/// One named cloud of 3D points.
#[derive(Debug, Clone, PartialEq)]
pub struct Cloud3 {
    /// Legend text (empty: not in the legend).
    pub label: String,
    /// Points as `[x, y, z]`.
    pub points: Vec<[f64; 3]>,
}

impl Cloud3 {
    /// A labelled cloud.
    pub fn new(label: impl Into<String>, points: Vec<[f64; 3]>) -> Self {
        Cloud3 {
            label: label.into(),
            points,
        }
    }
}

/// Title, axis labels (with units), size and view angles of a 3D plot.
#[derive(Debug, Clone, PartialEq)]
pub struct Plot3Spec {
    /// Plot title.
    pub title: String,
    /// X axis label, with units.
    pub x_label: String,
    /// Y axis label, with units.
    pub y_label: String,
    /// Z axis label, with units. Z is drawn vertical.
    pub z_label: String,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Rotation about the vertical axis, radians.
    pub yaw: f64,
    /// Tilt towards the viewer, radians.
    pub pitch: f64,
}

impl Plot3Spec {
    /// A spec with a 900 × 760 image and a default oblique view.
    pub fn new(
        title: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
        z_label: impl Into<String>,
    ) -> Self {
        Plot3Spec {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            z_label: z_label.into(),
            width: 900,
            height: 760,
            yaw: 0.6,
            pitch: 0.35,
        }
    }

    /// Sets the image size in pixels.
    pub fn size(mut self, width: u32, height: u32) -> Self {
        self.width = width;
        self.height = height;
        self
    }

    /// Sets the view angles in radians.
    pub fn view(mut self, yaw: f64, pitch: f64) -> Self {
        self.yaw = yaw;
        self.pitch = pitch;
        self
    }
}

/// Draws one or more 3D point clouds as a 3D scatter with labelled axes and a legend, as the
/// bytes of a `.png` or `.svg` file (by `path`'s extension; `path` also names the image in
/// errors, nothing is written). Data z is drawn vertical.
///
/// Errors if `clouds` is empty, any cloud is empty, or no point is finite;
/// points with a non-finite coordinate are skipped.
pub fn cloud_3d(path: &Path, spec: &Plot3Spec, clouds: &[Cloud3]) -> Result<Image, PlotError> {
    if clouds.is_empty() {
        return Err(PlotError::invalid(path, "no clouds given"));
    }
    if let Some(c) = clouds.iter().find(|c| c.points.is_empty()) {
        return Err(PlotError::invalid(
            path,
            format!("cloud {:?} has no points", c.label),
        ));
    }
    if !(spec.yaw.is_finite() && spec.pitch.is_finite()) {
        return Err(PlotError::invalid(path, "view angles must be finite"));
    }
    let finite: Vec<Vec<[f64; 3]>> = clouds
        .iter()
        .map(|c| {
            c.points
                .iter()
                .copied()
                .filter(|p| p.iter().all(|v| v.is_finite()))
                .collect()
        })
        .collect();
    let axis_range =
        |k: usize| finite_extent(finite.iter().flatten().map(|p| &p[k])).map(|e| padded(e, 0.05));
    let (Some(xr), Some(yr), Some(zr)) = (axis_range(0), axis_range(1), axis_range(2)) else {
        return Err(PlotError::invalid(path, "no point with finite x, y and z"));
    };
    for (name, r) in [("x", xr), ("y", yr), ("z", zr)] {
        check_range(path, name, r)?;
    }
    let n_total: usize = finite.iter().map(Vec::len).sum();
    let radius = if n_total > 2000 { 2 } else { 3 };

    render!(path, (spec.width, spec.height), |root| {
        let body = titled_area(root, &spec.title, 24)?;
        // Plotters' 3D "y" is vertical: map data (x, y, z) to (x, z, y).
        let mut chart = ChartBuilder::on(&body)
            .margin(30)
            .build_cartesian_3d(xr.0..xr.1, zr.0..zr.1, yr.0..yr.1)
            .map_err(err)?;
        chart.with_projection(|mut pb| {
            pb.yaw = spec.yaw;
            pb.pitch = spec.pitch;
            pb.scale = 0.78;
            pb.into_matrix()
        });
        let (fx, fy, fz) = (tick_formatter(xr), tick_formatter(yr), tick_formatter(zr));
        chart
            .configure_axes()
            .label_style(tick_style())
            .x_formatter(&fx)
            .y_formatter(&fz)
            .z_formatter(&fy)
            .x_labels(5)
            .y_labels(5)
            .z_labels(5)
            .light_grid_style(RGBColor(238, 238, 238))
            .bold_grid_style(RGBColor(205, 205, 205))
            .axis_panel_style(RGBColor(250, 250, 250))
            .draw()
            .map_err(err)?;

        // Axis titles, placed just outside the middle of the edges that
        // carry the tick labels (the x edge at the minimum plotted z, i.e.
        // data y, and so on).
        let label_style = (crate::font::FAMILY, 18)
            .into_font()
            .color(&BLACK)
            .pos(Pos::new(HPos::Center, VPos::Center));
        let (dx, dy, dz) = (xr.1 - xr.0, yr.1 - yr.0, zr.1 - zr.0);
        let xmid = 0.5 * (xr.0 + xr.1);
        let ymid = 0.5 * (yr.0 + yr.1);
        let zmid = 0.5 * (zr.0 + zr.1);
        let titles = [
            (&spec.x_label, (xmid, zr.0 - 0.0 * dz, yr.1 + 0.38 * dy)),
            (&spec.y_label, (xr.1 + 0.38 * dx, zr.0, ymid)),
            (&spec.z_label, (xr.0 - 0.0 * dx, zmid, yr.1 + 0.28 * dy)),
        ];
        chart
            .draw_series(
                titles
                    .iter()
                    .filter(|(t, _)| !t.is_empty())
                    .map(|(t, pos)| Text::new(t.to_string(), *pos, label_style.clone())),
            )
            .map_err(err)?;

        let mut any_label = false;
        for (i, (cloud, pts)) in clouds.iter().zip(&finite).enumerate() {
            let color = palette_rgb(i);
            let anno = chart
                .draw_series(
                    pts.iter()
                        .map(|p| Circle::new((p[0], p[2], p[1]), radius, color.mix(0.8).filled())),
                )
                .map_err(err)?;
            if !cloud.label.is_empty() {
                any_label = true;
                anno.label(cloud.label.as_str())
                    .legend(move |(x, y)| Circle::new((x + 10, y), 5, color.filled()));
            }
        }
        if any_label {
            draw_legend(&mut chart, SeriesLabelPosition::UpperRight)?;
        }
        Ok(())
    })
}
