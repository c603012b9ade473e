//! The calibration report (`deflex calibrate --report DIR`): the search's iteration table, the
//! identified stiffnesses and centre shifts (one unit per column: N·m/rad for stiffnesses, mm
//! for δr), the residual summary with the χ²/dof note, and plots: residuals per load case,
//! predicted versus measured displacement per axis (mm), and the parameter correlation as a
//! heatmap; the tables as CSV beside the page (`residuals.csv` in SI units), listed with links
//! under a contents list. Data a file's header calls SIMULATED (a `deflex sim campaign`) is
//! labelled so on the page, in every plot title and in `residuals.csv`.
//!
//! The caller gives the folder; `deflex calibrate` builds it aside (`deflex_files::AtomicDir`)
//! so a failure leaves no half-written report.

use crate::report::DrawError;
use crate::report::PageError;
use crate::report::calibration_tables::{
    COUPLING_HEADERS, ITERATION_HEADERS, REFIT_HEADERS, SHIFT_HEADERS, STIFFNESS_HEADERS,
    correlated_pairs_text, correlation_table, coupling_rows, coupling_summary, iteration_rows,
    refit_rows, residual_summary, shift_rows, stiffness_rows,
};
use crate::report::draw::{heatmap, line_plot, parity_plot, write_page, write_text};
use crate::report::text_table::table_csv;
use deflex_calibrate::measurements::MeasurementRow;
use deflex_calibrate::stiffness::search::SearchStep;
use deflex_calibrate::stiffness::stiffness_fit::Calibration;
use deflex_plot::{FileLink, HtmlReport, PlotSpec, Series, SeriesStyle};
use std::path::{Path, PathBuf};

/// Longest plot title (characters), with the `SIMULATED — ` prefix of simulated data: short
/// enough to be drawn on one line at the full title size on the report's 600–900 px images
/// (deflex-plot would wrap a longer one, never shrink it below its minimum).
pub const MAX_TITLE_CHARS: usize = 40;

/// What the report shows.
pub struct CalibrationReport<'a> {
    /// Start model's name.
    pub start_name: &'a str,
    /// Measurement file, as named to the user.
    pub data_name: &'a str,
    /// Where the calibrated model was written.
    pub output_name: &'a str,
    /// The calibration.
    pub calibration: &'a Calibration,
    /// The calibrated robot's prediction of every row's displacement (m, world axes):
    /// `deflex_calibrate::stiffness::validation::predict`.
    pub predicted: &'a [[f64; 3]],
    /// The search's steps (empty for a fixed structure).
    pub steps: &'a [SearchStep],
    /// Why the search stopped.
    pub stop_reason: Option<&'a str>,
    /// The measurement rows.
    pub rows: &'a [MeasurementRow],
    /// Warnings to show (file checks, calibration warnings).
    pub warnings: &'a [String],
    /// The measurement file's header comments (`FileHeader::notes`); a note
    /// containing `SIMULATED` marks the whole report as simulated.
    pub data_notes: &'a [String],
    /// The couplings fitted after the structure (`deflex calibrate --couplings`), if any.
    pub couplings: Option<CouplingSection<'a>>,
}

/// The off-diagonal compliances fitted after the structure, for the report.
#[derive(Clone, Copy, Debug)]
pub struct CouplingSection<'a> {
    /// The diagonal calibration as a robot (its stiffnesses before the refit).
    pub diagonal: &'a deflex_model::Robot,
    /// The fit: the written robot, the couplings with their standard errors.
    pub fit: &'a deflex_calibrate::stiffness::CouplingFit,
}

impl CalibrationReport<'_> {
    /// The header note that says the data is simulated, if any.
    pub fn simulated_note(&self) -> Option<&str> {
        self.data_notes
            .iter()
            .find(|n| n.contains("SIMULATED"))
            .map(String::as_str)
    }
}

/// The CSV text of a table for the file `path`, or why it could not be made, naming the file.
fn csv_of(path: &Path, text: std::io::Result<String>) -> Result<String, DrawError> {
    text.map_err(DrawError::content_of(path))
}

/// A plot's spec, its title prefixed with `SIMULATED — ` for simulated data.
fn spec(simulated: bool, title: &str, x: &str, y: &str) -> PlotSpec {
    let title = if simulated {
        format!("SIMULATED — {title}")
    } else {
        title.to_string()
    };
    debug_assert!(title.chars().count() <= MAX_TITLE_CHARS, "{title}");
    PlotSpec::new(title, x, y)
}

/// What each file of the report holds.
const FILES: [(&str, &str); 4] = [
    (
        "iterations.csv",
        "the structure search step by step (the table above)",
    ),
    (
        "stiffness.csv",
        "identified stiffnesses with standard errors and 95 % intervals (N·m/rad)",
    ),
    (
        "shifts.csv",
        "identified centre shifts δr with standard errors and 95 % intervals (mm)",
    ),
    (
        "residuals.csv",
        "per measured row: measured, predicted and residual displacement, world axes (m)",
    ),
];

/// Write the report's files into `dir` (which must exist). Returns the files written.
pub fn write_calibration_report(
    dir: &Path,
    report: &CalibrationReport,
) -> Result<Vec<PathBuf>, PageError> {
    write_into(dir, report).map_err(PageError::of("calibration report"))
}

/// What the page's parts share while it is written.
struct PageParts<'a> {
    dir: &'a Path,
    report: &'a CalibrationReport<'a>,
    sim: bool,
    predicted: &'a [[f64; 3]],
    residual: Vec<[f64; 3]>,
    html: HtmlReport,
    files: Vec<PathBuf>,
}

fn write_into(dir: &Path, report: &CalibrationReport) -> Result<Vec<PathBuf>, DrawError> {
    let cal = report.calibration;
    let simulated = report.simulated_note();
    let mut files = Vec::new();
    let it_rows = iteration_rows(report.steps);
    let st_rows = stiffness_rows(cal);
    let sh_rows = shift_rows(cal);
    for (name, text) in [
        ("iterations.csv", table_csv(&ITERATION_HEADERS, &it_rows)),
        ("stiffness.csv", table_csv(&STIFFNESS_HEADERS, &st_rows)),
        ("shifts.csv", table_csv(&SHIFT_HEADERS, &sh_rows)),
    ] {
        let path = dir.join(name);
        write_text(&path, &csv_of(&path, text)?)?;
        files.push(path);
    }
    let predicted = report.predicted;
    let residual: Vec<[f64; 3]> = report
        .rows
        .iter()
        .zip(predicted)
        .map(|(r, p)| {
            let m = r.displacement_m.unwrap_or([f64::NAN; 3]);
            [m[0] - p[0], m[1] - p[1], m[2] - p[2]]
        })
        .collect();
    let path = dir.join("residuals.csv");
    write_text(&path, &residuals_csv(report, &residual))?;
    files.push(path);
    if let Some(section) = &report.couplings {
        let path = dir.join("couplings.csv");
        let text = table_csv(&COUPLING_HEADERS, &coupling_rows(section.fit));
        write_text(&path, &csv_of(&path, text)?)?;
        files.push(path);
    }
    let mut c = PageParts {
        dir,
        report,
        sim: simulated.is_some(),
        predicted,
        residual,
        html: page_head(report, &it_rows, &st_rows, &sh_rows),
        files,
    };
    residual_plot(&mut c)?;
    parity_plots(&mut c)?;
    correlation_section(&mut c)?;
    let PageParts {
        mut html,
        mut files,
        sim,
        ..
    } = c;
    html.section("Files");
    html.paragraph(format!(
        "Beside this page{}:",
        if sim { " (SIMULATED data)" } else { "" }
    ));
    let mut links: Vec<FileLink> = FILES
        .iter()
        .map(|(name, what)| FileLink::new(*name, *what))
        .collect();
    if report.couplings.is_some() {
        links.push(FileLink::new(
            "couplings.csv",
            "the fitted off-diagonal compliances with standard errors, 95 % intervals and correlations",
        ));
    }
    html.files(&links);
    let page = dir.join("calibration.html");
    write_page(&html, &page)?;
    files.push(page);
    Ok(files)
}

/// `residuals.csv`: per row the measured, predicted and residual displacement (m), with the
/// data's SIMULATED note.
fn residuals_csv(report: &CalibrationReport, residual: &[[f64; 3]]) -> String {
    let simulated = report.simulated_note();
    let predicted = report.predicted;
    let mut csv = String::new();
    if let Some(note) = simulated {
        csv.push_str(&format!("# data: {note}\n"));
    }
    csv.push_str(
        "load_case,point,point_link,dx_m,dy_m,dz_m,pred_dx_m,pred_dy_m,pred_dz_m,res_dx_m,res_dy_m,res_dz_m\n",
    );
    for ((r, p), e) in report.rows.iter().zip(predicted).zip(residual) {
        let m = r.displacement_m.unwrap_or([f64::NAN; 3]);
        csv.push_str(&format!(
            "{},{},{},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e}\n",
            quote(&r.load_case),
            quote(&r.point),
            r.point_link,
            m[0],
            m[1],
            m[2],
            p[0],
            p[1],
            p[2],
            e[0],
            e[1],
            e[2]
        ));
    }

    csv
}

/// The page's title, notes, search, stiffness and shift tables and the residual summary.
fn page_head(
    report: &CalibrationReport,
    it_rows: &[Vec<String>],
    st_rows: &[Vec<String>],
    sh_rows: &[Vec<String>],
) -> HtmlReport {
    let cal = report.calibration;
    let simulated = report.simulated_note();
    let sim = simulated.is_some();
    let mut html = HtmlReport::new(format!(
        "Calibration of {}{}",
        report.start_name,
        if sim { " (SIMULATED data)" } else { "" }
    ));
    if let Some(note) = simulated {
        html.note(format!(
            "SIMULATED: the measurement file says \"{note}\". Every displacement, residual and \
             plot on this page comes from the digital twin, not from a robot."
        ));
    }
    html.paragraph(format!(
        "Data: {} ({} rows). Structure: {}. Output model: {}. The tables are also beside this \
         page as CSV (listed under \"Files\").",
        report.data_name,
        cal.rows,
        cal.structure.label(),
        report.output_name
    ));
    html.contents();
    if let Some(note) = cal.model_form_note() {
        html.note(note);
    }
    for w in report.warnings {
        html.note(w.clone());
    }
    if !report.steps.is_empty() {
        html.section("Structure search (test-model loop, cf. Tables A1/A2)");
        html.table(&ITERATION_HEADERS, it_rows);
        if let Some(s) = report.stop_reason {
            html.paragraph(format!("Stopped: {s}."));
        }
    }
    html.section("Identified stiffnesses (cf. Table 1)");
    html.table(&STIFFNESS_HEADERS, st_rows);
    if !sh_rows.is_empty() {
        html.section("Centre shifts");
        html.table(&SHIFT_HEADERS, sh_rows);
    }
    if let Some(section) = &report.couplings {
        html.section("Joint-compliance couplings (written into the output model)");
        html.paragraph(format!(
            "Off-diagonal compliances {}",
            coupling_summary(section.fit).trim_end()
        ));
        html.table(&COUPLING_HEADERS, &coupling_rows(section.fit));
        html.paragraph(
            "The output model's stiffnesses are the ones refitted with the couplings (the table \
             of identified stiffnesses above is the diagonal calibration's):",
        );
        html.table(&REFIT_HEADERS, &refit_rows(section.diagonal, section.fit));
    }
    html.section("Residuals");
    html.preformatted(residual_summary(cal));

    html
}

/// The residual norm per load case, one series per measured point.
fn residual_plot(c: &mut PageParts) -> Result<(), DrawError> {
    let (dir, report, sim) = (c.dir, c.report, c.sim);
    let residual = &c.residual;
    let html = &mut c.html;
    let files = &mut c.files;
    // Residual norm per load case, one series per measured point.
    let mut cases: Vec<&str> = Vec::new();
    for r in report.rows {
        if !cases.contains(&r.load_case.as_str()) {
            cases.push(&r.load_case);
        }
    }
    let mut labels: Vec<&str> = Vec::new();
    for r in report.rows {
        if !labels.contains(&r.point.as_str()) && labels.len() < 12 {
            labels.push(&r.point);
        }
    }
    let series: Vec<Series> = labels
        .iter()
        .map(|label| {
            let (x, y): (Vec<f64>, Vec<f64>) = report
                .rows
                .iter()
                .zip(residual)
                .filter(|(r, _)| r.point == *label)
                .map(|(r, e)| {
                    let case = cases.iter().position(|c| *c == r.load_case).unwrap_or(0);
                    (
                        (case + 1) as f64,
                        (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt() * 1e3,
                    )
                })
                .unzip();
            Series::new(label.to_string(), x, y, SeriesStyle::Points)
        })
        .collect();
    let path = dir.join("residuals_per_load_case.png");
    line_plot(
        &path,
        &spec(
            sim,
            "Residual per load case",
            "load case # (order of residuals.csv)",
            "|measured − predicted| [mm]",
        )
        .size(900, 500),
        &series,
    )?;
    html.image(
        &path,
        caption(
            sim,
            "Norm of the residual (measured − predicted displacement) of every measured point, \
             per load case"
                .into(),
        ),
    );
    files.push(path);

    Ok(())
}

/// Predicted vs measured displacement, one plot per world axis.
fn parity_plots(c: &mut PageParts) -> Result<(), DrawError> {
    let (dir, report, sim) = (c.dir, c.report, c.sim);
    let predicted = c.predicted;
    let html = &mut c.html;
    let files = &mut c.files;
    html.section("Predicted vs measured");
    for (axis, name) in ["x", "y", "z"].iter().enumerate() {
        let path = dir.join(format!("parity_{name}.png"));
        let measured: Vec<f64> = report
            .rows
            .iter()
            .map(|r| r.displacement_m.map_or(f64::NAN, |d| d[axis] * 1e3))
            .collect();
        let pred: Vec<f64> = predicted.iter().map(|p| p[axis] * 1e3).collect();
        parity_plot(
            &path,
            &spec(
                sim,
                &format!("δp{name}: predicted vs measured"),
                &format!("measured δp{name} [mm]"),
                &format!("predicted δp{name} [mm]"),
            )
            .size(600, 600),
            &pred,
            &measured,
            "calibrated model",
        )?;
        html.image(
            &path,
            caption(
                sim,
                format!("Displacement along world {name}: calibrated model against the tracker"),
            ),
        );
        files.push(path);
    }

    Ok(())
}

/// The correlation of the fitted parameters as a heatmap and a table, and the calibration's
/// warnings.
fn correlation_section(c: &mut PageParts) -> Result<(), DrawError> {
    let (dir, report, sim) = (c.dir, c.report, c.sim);
    let cal = report.calibration;
    let html = &mut c.html;
    let files = &mut c.files;
    html.section("Parameter correlation");
    let flagged = correlated_pairs_text(cal);
    if !flagged.is_empty() {
        html.note(flagged);
    }
    let p = cal.parameter_labels.len();
    if p >= 2 {
        let centers: Vec<f64> = (1..=p).map(|i| i as f64).collect();
        let mut values = Vec::with_capacity(p * p);
        for j in 0..p {
            for i in 0..p {
                values.push(cal.correlation[(j, i)]);
            }
        }
        let path = dir.join("correlation.png");
        heatmap(
            &path,
            &spec(
                sim,
                "Parameter correlation",
                "parameter # (list below)",
                "parameter #",
            )
            .size(760, 680)
            .color_range(-1.0, 1.0),
            &centers,
            &centers,
            &values,
            "correlation [-]",
        )?;
        html.image(
            &path,
            caption(sim, "Correlation of the fitted parameters (−1 … +1)".into()),
        );
        files.push(path);
        html.paragraph(
            cal.parameter_labels
                .iter()
                .enumerate()
                .map(|(i, l)| format!("{} = {l}", i + 1))
                .collect::<Vec<_>>()
                .join(", "),
        );
    }
    html.preformatted(correlation_table(cal));
    for w in &cal.warnings {
        html.note(w.clone());
    }
    Ok(())
}

/// A plot caption, marked SIMULATED for simulated data.
fn caption(sim: bool, text: String) -> String {
    if sim {
        format!("{text} (SIMULATED)")
    } else {
        text
    }
}

/// A CSV field, quoted when needed.
fn quote(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_string()
    }
}
