//! The study's figures, after the paper's: validation heatmaps and parity plots (Figs. 10–13),
//! the spiral (Fig. 14) and the forming comparisons (Figs. 17, A1, 18, 19). Every title says
//! SIMULATED.

use crate::study::{BASELINE, IDENTIFIED};
use deflex_calib::MeasurementRow;
use deflex_report::{
    Cloud3, PanelLayout, Plot3Spec, PlotSpec, Series, cloud_3d, line_plot, panels_plot,
    parity_plot, scatter_heatmap,
};
use deflex_sim::FormingRun;
use std::path::{Path, PathBuf};

/// A figure file and its caption.
pub(crate) type Figure = (PathBuf, String);

fn draw(result: Result<(), deflex_report::ReportError>) -> Result<(), String> {
    result.map_err(|e| e.to_string())
}

/// Heatmaps of the δz prediction error over the grid for the baseline and the identified model
/// for each dead weight (the paper's 600 N and 1100 N: Figs. 11, 13), and predicted-vs-measured
/// δz (Figs. 10, 12).
pub(crate) fn grid_figures(
    out: &Path,
    grid: &[MeasurementRow],
    loads_n: &[f64],
    predictions: &[(&str, Vec<[f64; 3]>)],
) -> Result<Vec<Figure>, String> {
    let mut figures = Vec::new();
    for (index, &load) in loads_n.iter().enumerate() {
        let selected = crate::tables::grid_rows(grid, load);
        let x: Vec<f64> = selected.iter().map(|&i| grid[i].point_m[0] * 1e3).collect();
        let y: Vec<f64> = selected.iter().map(|&i| grid[i].point_m[1] * 1e3).collect();
        let measured: Vec<f64> = selected
            .iter()
            .map(|&i| {
                grid[i]
                    .displacement_m
                    .map(|d| d[2] * 1e3)
                    .unwrap_or(f64::NAN)
            })
            .collect();
        // One colour scale for both models so the heatmaps compare at a glance.
        let errors: Vec<(&str, Vec<f64>)> = predictions
            .iter()
            .filter(|(name, _)| *name == BASELINE || *name == IDENTIFIED)
            .map(|(name, p)| {
                let e = selected
                    .iter()
                    .zip(&measured)
                    .map(|(&i, m)| (m - p[i][2] * 1e3).abs())
                    .collect();
                (*name, e)
            })
            .collect();
        let top = errors
            .iter()
            .flat_map(|(_, e)| e.iter().cloned())
            .fold(0.0f64, f64::max)
            .max(1e-6);
        for (name, error) in &errors {
            let tag = crate::tables::column_tag(name);
            let path = out.join(format!("grid_error_{tag}_{load:.0}N.png"));
            let spec = PlotSpec::new(
                format!(
                    "SIMULATED cell — |δz error| of the {name} model, {load:.0} N (cf. Fig. {})",
                    if index == 0 { 11 } else { 13 }
                ),
                "x [mm]",
                "y [mm]",
            )
            .size(900, 700)
            .color_range(0.0, top);
            draw(scatter_heatmap(
                &path,
                &spec,
                &x,
                &y,
                error,
                "|measured − predicted δz| [mm]",
            ))?;
            figures.push((path, format!("|δz error| of the {name} model over the grid, {load:.0} N dead weight (SIMULATED)")));
        }
        for (name, p) in predictions
            .iter()
            .filter(|(name, _)| *name == BASELINE || *name == IDENTIFIED)
        {
            let tag = crate::tables::column_tag(name);
            let predicted: Vec<f64> = selected.iter().map(|&i| p[i][2] * 1e3).collect();
            let path = out.join(format!("grid_parity_{tag}_{load:.0}N.png"));
            let spec = PlotSpec::new(
                format!(
                    "SIMULATED cell — δz predicted vs measured, {name}, {load:.0} N (cf. Fig. {})",
                    if index == 0 { 10 } else { 12 }
                ),
                "measured δz [mm]",
                "predicted δz [mm]",
            )
            .size(700, 650);
            draw(parity_plot(&path, &spec, &predicted, &measured, name))?;
            figures.push((
                path,
                format!("Predicted vs measured δz, {name} model, {load:.0} N (SIMULATED)"),
            ));
        }
    }
    Ok(figures)
}

/// The spiral trajectory (Fig. 14a) and δz measured vs predicted along it (Fig. 14b).
pub(crate) fn spiral_figures(
    out: &Path,
    rows: &[MeasurementRow],
    params: &deflex_sim::campaign::SpiralParams,
    predictions: &[(&str, Vec<[f64; 3]>)],
) -> Result<Vec<Figure>, String> {
    let mut figures = Vec::new();
    let x: Vec<f64> = rows.iter().map(|r| r.point_m[0] * 1e3).collect();
    let y: Vec<f64> = rows.iter().map(|r| r.point_m[1] * 1e3).collect();
    let path = out.join("spiral_path.png");
    let spec = PlotSpec::new(
        format!(
            "SIMULATED cell — spiral trajectory at z = {:.0} mm (cf. Fig. 14a)",
            params.center_m[2] * 1e3
        ),
        "x [mm]",
        "y [mm]",
    )
    .size(700, 700);
    draw(line_plot(&path, &spec, &[Series::line("TCP path", x, y)]))?;
    figures.push((
        path,
        format!(
            "Spiral trajectory, {:.0} N dead weight (SIMULATED)",
            params.load_n
        ),
    ));
    let per_sample_mm = params.speed_m_s * 1e3 / 50.0;
    let length: Vec<f64> = (0..rows.len()).map(|i| i as f64 * per_sample_mm).collect();
    let mut series = vec![Series::line(
        "measured (SIMULATED tracker)",
        length.clone(),
        rows.iter()
            .map(|r| r.displacement_m.map(|d| d[2] * 1e3).unwrap_or(f64::NAN))
            .collect(),
    )];
    for (name, p) in predictions
        .iter()
        .filter(|(name, _)| *name == BASELINE || *name == IDENTIFIED)
    {
        series.push(Series::line(
            format!("{name} model"),
            length.clone(),
            p.iter().map(|d| d[2] * 1e3).collect(),
        ));
    }
    let path = out.join("spiral_dz.png");
    let spec = PlotSpec::new(
        format!(
            "SIMULATED cell — δz along the spiral, {:.0} N (cf. Fig. 14b)",
            params.load_n
        ),
        "path length [mm]",
        "δz [mm]",
    )
    .size(1100, 500);
    draw(line_plot(&path, &spec, &series))?;
    figures.push((
        path,
        "δz along the spiral: measured and predicted (SIMULATED)".to_string(),
    ));
    Ok(figures)
}

/// Forming without vs with correction: deviation clouds (Fig. 17), error per axis and norm along
/// the path (Fig. A1), forces (Fig. 18) and error vs force norm (Fig. 19).
pub(crate) fn forming_figures(
    out: &Path,
    open: &FormingRun,
    closed: &FormingRun,
) -> Result<Vec<Figure>, String> {
    let mut figures = Vec::new();
    let runs = [("without correction", open), ("with correction", closed)];
    let cloud: Vec<Cloud3> = runs
        .iter()
        .map(|(label, run)| {
            Cloud3::new(
                *label,
                run.log
                    .rows
                    .iter()
                    .map(|r| {
                        let e = r.truth.true_m - r.truth.desired_m;
                        [e.x * 1e3, e.y * 1e3, e.z * 1e3]
                    })
                    .collect(),
            )
        })
        .collect();
    let path = out.join("forming_cloud.png");
    draw(cloud_3d(
        &path,
        &Plot3Spec::new(
            "SIMULATED cell — TCP deviation during cone forming (cf. Fig. 17)",
            "x_p [mm]",
            "y_p [mm]",
            "z_p [mm]",
        )
        .size(900, 750),
        &cloud,
    ))?;
    figures.push((
        path,
        "Deviation from the desired path, without and with correction (SIMULATED)".to_string(),
    ));

    let axis_names = ["x_p", "y_p", "z_p", "norm"];
    let panels: Vec<(PlotSpec, Vec<Series>)> = axis_names
        .iter()
        .enumerate()
        .map(|(k, axis)| {
            let series = runs
                .iter()
                .map(|(label, run)| {
                    let t = run.log.column(|r| r.time_s);
                    let v = run.log.column(|r| {
                        let e = r.truth.true_m - r.truth.desired_m;
                        if k < 3 { e[k] * 1e3 } else { e.norm() * 1e3 }
                    });
                    Series::line(*label, t, v)
                })
                .collect();
            (
                PlotSpec::new(format!("deviation {axis}"), "time [s]", "[mm]").size(1100, 300),
                series,
            )
        })
        .collect();
    let path = out.join("forming_error_along_path.png");
    draw(panels_plot(
        &path,
        "SIMULATED cell — deviation along the path (cf. Fig. A1)",
        PanelLayout::Column,
        &panels,
    ))?;
    figures.push((
        path,
        "Deviation per axis and in norm along the path (SIMULATED)".to_string(),
    ));

    let force_names = ["F_x", "F_y", "F_z"];
    let mut panels: Vec<(PlotSpec, Vec<Series>)> = runs
        .iter()
        .map(|(label, run)| {
            let t = run.log.column(|r| r.time_s);
            let series = force_names
                .iter()
                .enumerate()
                .map(|(k, name)| {
                    Series::line(*name, t.clone(), run.log.column(move |r| r.truth.wrench[k]))
                })
                .collect();
            (
                PlotSpec::new(format!("contact force, {label}"), "time [s]", "force [N]")
                    .size(700, 420),
                series,
            )
        })
        .collect();
    // Both runs' F_z on one axis: the correction pushes deeper, so the force builds up sooner.
    panels.push((
        PlotSpec::new("F_z without and with correction", "time [s]", "force [N]").size(700, 420),
        runs.iter()
            .map(|(label, run)| {
                Series::line(
                    format!("F_z, {label}"),
                    run.log.column(|r| r.time_s),
                    run.log.column(|r| r.truth.wrench[2]),
                )
            })
            .collect(),
    ));
    let path = out.join("forming_forces.png");
    draw(panels_plot(
        &path,
        "SIMULATED cell — contact force at the TCP, part axes (cf. Fig. 18)",
        PanelLayout::Row,
        &panels,
    ))?;
    figures.push((
        path,
        "Contact forces without and with correction (SIMULATED)".to_string(),
    ));

    let series: Vec<Series> = runs
        .iter()
        .map(|(label, run)| {
            Series::points(
                *label,
                run.log.column(|r| r.truth.wrench.fixed_rows::<3>(0).norm()),
                run.log
                    .column(|r| (r.truth.true_m - r.truth.desired_m).norm() * 1e3),
            )
        })
        .collect();
    let path = out.join("forming_error_vs_force.png");
    draw(line_plot(
        &path,
        &PlotSpec::new(
            "SIMULATED cell — deviation norm vs force norm (cf. Fig. 19)",
            "|F| [N]",
            "|deviation| [mm]",
        )
        .size(900, 560),
        &series,
    ))?;
    figures.push((
        path,
        "Deviation norm as a function of the force norm (SIMULATED)".to_string(),
    ));
    Ok(figures)
}
