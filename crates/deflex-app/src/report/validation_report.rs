//! The validation of a model on measurements as PNG plots and one HTML page: the prediction
//! error tables ([`crate::report::validation_tables`]), predicted vs measured per axis
//! (Figs. 8–10, 12), δz along the measured points (Figs. 10, 12) and error heatmaps over the
//! measured grid (Figs. 11, 13).

use crate::report::DrawError;
use crate::report::PageError;
use crate::report::draw::{line_plot, parity_plot, scatter_heatmap, write_page};
use crate::report::validation_tables::{
    VALIDATION_HEADERS, VALIDATION_ROTATION_HEADERS, validation_rotation_rows, validation_rows,
};
use deflex_calibrate::stiffness::validation::Validation;
use deflex_plot::{HtmlReport, PlotSpec, Series, SeriesStyle};
use std::path::{Path, PathBuf};

/// Write PNG plots and `validation.html` into the folder `dir`, whole or not at all: the folder
/// is built aside and swapped in when complete (`deflex_files::AtomicDir`; an existing folder is
/// replaced, and kept as it was when anything fails). Returns the files (final paths).
pub fn write_validation_report(v: &Validation, dir: &Path) -> Result<Vec<PathBuf>, PageError> {
    let io = DrawError::io_on(dir);
    let page = PageError::of("validation report");
    let folder = deflex_files::AtomicDir::create(dir)
        .map_err(io)
        .map_err(&page)?;
    let files = write_report_into(v, folder.path()).map_err(&page)?;
    folder.commit().map_err(io).map_err(&page)?;
    Ok(files
        .iter()
        .filter_map(|f| f.file_name())
        .map(|name| dir.join(name))
        .collect())
}

/// [`write_validation_report`]'s files, written into an existing folder.
fn write_report_into(v: &Validation, dir: &Path) -> Result<Vec<PathBuf>, DrawError> {
    let mut files = Vec::new();
    let mut html = HtmlReport::new(format!("Validation of {}", v.model.name));
    html.paragraph(format!(
        "How well {} predicts {} measured displacements{}: error tables, predicted against \
         measured, and the error over the measured points.",
        v.model.name,
        v.measured.len(),
        v.baseline
            .as_ref()
            .map(|b| format!(", beside the baseline {}", b.name))
            .unwrap_or_default()
    ));
    html.contents();
    html.section("Prediction errors (measured − predicted)");
    html.table(&VALIDATION_HEADERS, &validation_rows(v));
    if v.model.rotation.is_some() {
        html.section("Rotation errors (measured − predicted)");
        html.table(&VALIDATION_ROTATION_HEADERS, &validation_rotation_rows(v));
    }
    html.paragraph(format!(
        "{} measured points; RMS of the measured displacement x/y/z: {:.4} / {:.4} / {:.4} mm.",
        v.measured.len(),
        v.measured_rms_m[0] * 1e3,
        v.measured_rms_m[1] * 1e3,
        v.measured_rms_m[2] * 1e3
    ));

    // Predicted vs measured (Figs. 8–10, 12).
    html.section("Predicted vs measured");
    let axes = ["x", "y", "z"];
    for (tag, m) in
        std::iter::once(("model", &v.model)).chain(v.baseline.as_ref().map(|b| ("baseline", b)))
    {
        for ax in 0..3 {
            let path = dir.join(format!("parity_{tag}_{}.png", axes[ax]));
            let meas: Vec<f64> = v.measured.iter().map(|d| d[ax] * 1e3).collect();
            let pred: Vec<f64> = m.predicted.iter().map(|d| d[ax] * 1e3).collect();
            let spec = PlotSpec::new(
                format!("δp{}: predicted vs measured ({tag})", axes[ax]),
                format!("measured δp{} [mm]", axes[ax]),
                format!("predicted δp{} [mm]", axes[ax]),
            )
            .size(700, 700);
            parity_plot(&path, &spec, &pred, &meas, tag)?;
            html.image(
                &path,
                format!("Predicted vs measured δp{} ({tag}: {})", axes[ax], m.name),
            );
            files.push(path);
        }
    }
    // δz along the measurement order (Figs. 10, 12).
    let path = dir.join("dz_along_points.png");
    let mut series = vec![Series::indexed(
        "measured",
        v.measured.iter().map(|d| d[2] * 1e3).collect(),
        SeriesStyle::LineAndPoints,
    )];
    for m in std::iter::once(&v.model).chain(v.baseline.as_ref()) {
        series.push(Series::indexed(
            m.name.clone(),
            m.predicted.iter().map(|d| d[2] * 1e3).collect(),
            SeriesStyle::Line,
        ));
    }
    let spec = PlotSpec::new("δp_z: measured and predicted", "point #", "δp_z [mm]");
    line_plot(&path, &spec, &series)?;
    html.image(
        &path,
        "Vertical displacement along the measured points (cf. Figs. 10, 12)",
    );
    files.push(path);

    // Heatmaps of the error norm over the measured points (Figs. 11, 13): one per model and per
    // load level (the paper's 600 N and 1100 N grids share their points), each with its own
    // colour scale so that a good model's pattern stays visible beside a poor one.
    html.section("Error over the measured grid");
    // The TCP grid when the TCP was measured (as in the paper), else every point.
    let tcp_only = v.labels.iter().any(|l| l == "TCP");
    let mut levels: Vec<f64> = Vec::new();
    for &f in &v.load_n {
        let level = (f / 10.0).round() * 10.0;
        if !levels.iter().any(|l| (l - level).abs() < 1e-9) {
            levels.push(level);
        }
    }
    levels.sort_by(f64::total_cmp);
    let many_levels = levels.len() > 4;
    for level in if many_levels { vec![f64::NAN] } else { levels } {
        let keep: Vec<usize> = (0..v.labels.len())
            .filter(|&i| !tcp_only || v.labels[i] == "TCP")
            .filter(|&i| {
                level.is_nan() || ((v.load_n[i] / 10.0).round() * 10.0 - level).abs() < 1e-9
            })
            .collect();
        if keep.is_empty() {
            continue;
        }
        let xs: Vec<f64> = keep.iter().map(|&i| v.points[i][0] * 1e3).collect();
        let ys: Vec<f64> = keep.iter().map(|&i| v.points[i][1] * 1e3).collect();
        let load = if level.is_nan() {
            "all loads".to_string()
        } else {
            format!("{level:.0} N")
        };
        let file_tag = if level.is_nan() {
            "all".to_string()
        } else {
            format!("{level:.0}N")
        };
        for (tag, m) in
            std::iter::once(("model", &v.model)).chain(v.baseline.as_ref().map(|b| ("baseline", b)))
        {
            let norm: Vec<f64> = keep
                .iter()
                .map(|&i| {
                    let e = m.errors[i];
                    (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt() * 1e3
                })
                .collect();
            let top = norm.iter().copied().fold(0.0, f64::max).max(1e-9);
            let path = dir.join(format!("heatmap_{tag}_{file_tag}.png"));
            let spec = PlotSpec::new(format!("|error| of the {tag}, {load}"), "x [mm]", "y [mm]")
                .size(800, 700)
                .color_range(0.0, top);
            scatter_heatmap(&path, &spec, &xs, &ys, &norm, "|measured − predicted| [mm]")?;
            html.image(
                &path,
                format!(
                    "Error norm over the measured points, {load}: {} (cf. Figs. 11, 13)",
                    m.name
                ),
            );
            files.push(path);
        }
    }
    let page = dir.join("validation.html");
    write_page(&html, &page)?;
    files.push(page);
    Ok(files)
}
