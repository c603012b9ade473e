//! Residual plots of an elasto-geometric fit: per axis, against each joint, a map over the
//! measured volume, the held-out error distribution, and the joint-angle error maps.

use crate::report::DrawError;
use crate::report::draw::{line_plot, panels_plot, scatter_heatmap};
use deflex_calibrate::geometry::campaign::{Campaign, ReadingKind};
use deflex_calibrate::geometry::fit::{FitResult, Role, RowResidual};
use deflex_plot::{PanelLayout, PlotSpec, Series};
use std::path::Path;

/// Draw the plots into `dir`; returns `(file name, caption)` pairs.
pub fn draw(
    result: &FitResult,
    campaign: &Campaign,
    dir: &Path,
) -> Result<Vec<(String, String)>, DrawError> {
    let mut images = Vec::new();
    let absolute: Vec<&RowResidual> = result
        .residuals
        .iter()
        .filter(|r| campaign.kind(r.index) == ReadingKind::Position)
        .collect();
    if absolute.is_empty() {
        return Ok(images);
    }
    let fit: Vec<&&RowResidual> = absolute.iter().filter(|r| r.role == Role::Fit).collect();
    let held: Vec<&&RowResidual> = absolute.iter().filter(|r| r.role != Role::Fit).collect();
    if !fit.is_empty() {
        images.extend(fitted_residual_plots(result, campaign, &fit, dir)?);
    }
    if let Some(maps) = &result.model.joint_maps {
        images.push(joint_maps_plot(maps, dir)?);
    }
    // Held-out error distribution (cumulative), final model.
    let mut series = Vec::new();
    for (label, rows) in [("fitted readings", &fit), ("held-out readings", &held)] {
        if rows.is_empty() {
            continue;
        }
        let mut e: Vec<f64> = rows.iter().map(|r| r.residual.norm() * 1e3).collect();
        e.sort_by(f64::total_cmp);
        let n = e.len() as f64;
        let p: Vec<f64> = (1..=e.len()).map(|k| 100.0 * k as f64 / n).collect();
        series.push(Series::line(label, e, p));
    }
    if !series.is_empty() {
        let name = "error_distribution.png";
        line_plot(
            &dir.join(name),
            &PlotSpec::new(
                "Error distribution, final model",
                "|error| [mm]",
                "readings below [%]",
            )
            .y_range(0.0, 100.0),
            &series,
        )?;
        images.push((
            name.to_string(),
            "Cumulative distribution of the error norm: fitted and held-out readings".into(),
        ));
    }
    Ok(images)
}

/// The fitted readings' residuals: per tracker axis in file order, against each joint angle,
/// and as maps over the measured volume (x–y and x–z projections).
fn fitted_residual_plots(
    result: &FitResult,
    campaign: &Campaign,
    fit: &[&&RowResidual],
    dir: &Path,
) -> Result<Vec<(String, String)>, DrawError> {
    let mut images = Vec::new();
    // Per axis, fit readings in file order.
    let panels: Vec<(PlotSpec, Vec<Series>)> = ["x", "y", "z"]
        .iter()
        .enumerate()
        .map(|(k, axis)| {
            let y: Vec<f64> = fit.iter().map(|r| r.residual[k] * 1e3).collect();
            (
                PlotSpec::new(
                    format!("{axis} (tracker frame)"),
                    "reading",
                    "residual [mm]",
                )
                .size(1100, 300),
                vec![Series::indexed("", y, deflex_plot::SeriesStyle::Points)],
            )
        })
        .collect();
    let name = "residuals_per_axis.png";
    panels_plot(
        &dir.join(name),
        "Residuals per axis (fitted readings, final model)",
        PanelLayout::Column,
        &panels,
    )?;
    images.push((
        name.to_string(),
        "Residuals (measured − predicted) per tracker axis, fitted readings, final model".into(),
    ));
    // Against each joint.
    let n = result.model.robot.joint_count();
    let panels: Vec<(PlotSpec, Vec<Series>)> = (0..n)
        .map(|j| {
            let x: Vec<f64> = fit
                .iter()
                .map(|r| campaign.absolute[r.index].q_rad[j].to_degrees())
                .collect();
            let y: Vec<f64> = fit.iter().map(|r| r.residual.norm() * 1e3).collect();
            (
                PlotSpec::new(
                    format!("J{}", j + 1),
                    format!("q{} [deg]", j + 1),
                    "|residual| [mm]",
                )
                .size(550, 320),
                vec![Series::points("", x, y)],
            )
        })
        .collect();
    let name = "residuals_vs_joints.png";
    panels_plot(
        &dir.join(name),
        "Residual norm against each joint angle (fitted readings)",
        PanelLayout::Grid { columns: 2 },
        &panels,
    )?;
    images.push((name.to_string(), "Residual norm against each joint angle: structure here is model error (e.g. gear eccentricity)".into()));
    // Map over the measured volume (projection on the tracker's x-y plane).
    let x: Vec<f64> = fit
        .iter()
        .map(|r| campaign.absolute[r.index].position_m[0] * 1e3)
        .collect();
    let y: Vec<f64> = fit
        .iter()
        .map(|r| campaign.absolute[r.index].position_m[1] * 1e3)
        .collect();
    let v: Vec<f64> = fit.iter().map(|r| r.residual.norm() * 1e3).collect();
    let name = "residual_map_xy.png";
    scatter_heatmap(
        &dir.join(name),
        &PlotSpec::new(
            "Residual norm over the measured volume (tracker x–y projection)",
            "x [mm]",
            "y [mm]",
        )
        .size(800, 700),
        &x,
        &y,
        &v,
        "|residual| [mm]",
    )?;
    images.push((
        name.to_string(),
        "Residual norm at each measured position, seen from above in the tracker frame".into(),
    ));
    let z: Vec<f64> = fit
        .iter()
        .map(|r| campaign.absolute[r.index].position_m[2] * 1e3)
        .collect();
    let name = "residual_map_xz.png";
    scatter_heatmap(
        &dir.join(name),
        &PlotSpec::new(
            "Residual norm over the measured volume (tracker x–z projection)",
            "x [mm]",
            "z [mm]",
        )
        .size(800, 700),
        &x,
        &z,
        &v,
        "|residual| [mm]",
    )?;
    images.push((
        name.to_string(),
        "Residual norm at each measured position, side view in the tracker frame".into(),
    ));
    Ok(images)
}

/// One panel per mapped joint: its angle error `Δθ_j` against its angle, over the range the map
/// was trained on (sampled at a tenth of the knot spacing).
fn joint_maps_plot(
    maps: &deflex_calibrate::geometry::joint_maps::JointMaps,
    dir: &Path,
) -> Result<(String, String), DrawError> {
    let panels: Vec<(PlotSpec, Vec<Series>)> = maps
        .maps
        .iter()
        .map(|map| {
            let (lo, hi) = map.range_rad();
            let step = map.spacing_rad / 10.0;
            let samples = ((hi - lo) / step).ceil() as usize + 1;
            let x: Vec<f64> = (0..samples)
                .map(|k| (lo + k as f64 * step).to_degrees())
                .collect();
            let y: Vec<f64> = (0..samples)
                .map(|k| map.value(lo + k as f64 * step) * 1e6)
                .collect();
            (
                PlotSpec::new(
                    format!("J{}", map.joint + 1),
                    format!("q{} [deg]", map.joint + 1),
                    "Δθ [µrad]",
                )
                .size(550, 320),
                vec![Series::line("", x, y)],
            )
        })
        .collect();
    let name = "joint_maps.png";
    panels_plot(
        &dir.join(name),
        "Joint-angle error maps (what each joint's angle is off by)",
        PanelLayout::Grid { columns: 2 },
        &panels,
    )?;
    Ok((
        name.to_string(),
        format!(
            "Joint-angle error maps Δθ_j(q_j) added to the measured joint angles ({}); zero outside the trained range",
            maps.hyper.describe()
        ),
    ))
}
