//! The study's folder (`deflex demo`), written whole: the CSV data ([`super::csv_files`]), the
//! figures ([`super::figures`]), `results.md` ([`super::readme`]) and the page (`index.html`).

use super::{StudyFigures, csv_files, figures, page, readme};
use crate::report::DrawError;
use crate::report::PageError;
use crate::report::draw::write_text;
use crate::report::text_table::table_csv;
use crate::study::Study;
use deflex_calibrate::measurements::format_rows_for;
use deflex_model::robot_to_toml;
use deflex_sim::twin_campaign::campaign_text;
use std::path::Path;

/// Write the study into the folder `out_dir`, whole or not at all: the folder is built aside and
/// swapped in when complete (an existing folder is replaced only then, and kept as it was when
/// anything fails).
pub fn write_study(study: &Study, out_dir: &Path) -> Result<(), PageError> {
    let page_error = PageError::of("study report");
    let io = DrawError::io_on(out_dir);
    let building = deflex_files::AtomicDir::create(out_dir)
        .map_err(io)
        .map_err(&page_error)?;
    write_into(study, building.path()).map_err(&page_error)?;
    building.commit().map_err(io).map_err(&page_error)
}

/// Every file of the study, into the existing folder `out`.
fn write_into(study: &Study, out: &Path) -> Result<(), DrawError> {
    let mut figures = StudyFigures::default();
    write_calibration_files(study, out)?;
    write_validation_files(study, out, &mut figures)?;
    write_forming_files(study, out, &mut figures)?;
    write_contact_and_sensitivity(study, out, &mut figures)?;
    let compensation_files =
        csv_files::compensation_files(&study.summary.compensation, &study.compensation_runs);
    for file in &compensation_files {
        write_text(&out.join(&file.name), &file.text)?;
    }
    figures.compensation = figures::compensation_figures(out, &study.compensation_runs)?;
    let s = &study.summary;
    let json = serde_json::to_string_pretty(s)
        .map_err(DrawError::content_of(&out.join("summary.json")))?;
    write_text(&out.join("summary.json"), &json)?;
    write_text(&out.join("results.md"), &readme::results_markdown(s))?;
    write_text(
        &out.join("paper_vs_deflex.csv"),
        &csv_files::paper_vs_deflex_csv(s),
    )?;
    page::write(
        out,
        &page::Page {
            summary: s,
            search: &study.search,
            plan: &study.plan,
            grid: &study.grid_params,
            spiral: &study.spiral_params,
            figures: &figures,
            file_descriptions: compensation_files
                .into_iter()
                .map(|f| (f.name, f.description))
                .collect(),
        },
    )
}

/// The plan, the campaign, the two models, the search and the stiffnesses.
fn write_calibration_files(study: &Study, out: &Path) -> Result<(), DrawError> {
    let seed = study.summary.seed;
    write_text(
        &out.join("plan.csv"),
        &format_rows_for(&study.nominal, &study.plan.rows, &[]),
    )?;
    write_campaign(
        study,
        &out.join("campaign.csv"),
        &study.campaign,
        "calibration campaign",
        seed,
    )?;
    write_text(
        &out.join("identified.toml"),
        &robot_to_toml(&study.identified),
    )?;
    write_text(
        &out.join("baseline-1edof.toml"),
        &robot_to_toml(&study.baseline),
    )?;
    write_text(
        &out.join("search_iterations.csv"),
        &table_csv(
            &crate::report::calibration_tables::ITERATION_HEADERS,
            &crate::report::calibration_tables::iteration_rows(&study.search.steps),
        )
        .map_err(DrawError::content_of(&out.join("search_iterations.csv")))?,
    )?;
    write_text(
        &out.join("stiffness.csv"),
        &csv_files::stiffness_csv(&study.summary.stiffness),
    )
}

/// A campaign of the twin written to `path` in the measurement format (`# SIMULATED …`
/// header).
fn write_campaign(
    study: &Study,
    path: &Path,
    rows: &[deflex_calibrate::measurements::MeasurementRow],
    what: &str,
    seed: u64,
) -> Result<(), DrawError> {
    let text =
        campaign_text(&study.cell, rows, what, seed, None).map_err(DrawError::content_of(path))?;
    write_text(path, &text)
}

/// Figs. 7–9, the grid and the spiral: measurements, predictions and figures.
fn write_validation_files(
    study: &Study,
    out: &Path,
    figures: &mut StudyFigures,
) -> Result<(), DrawError> {
    let seed = study.summary.seed;
    if !study.summary.fig7.is_empty() {
        write_text(
            &out.join("fig7_points.csv"),
            &csv_files::fig7_csv(&study.fig7_rows, &study.summary.fig7),
        )?;
        let figure = out.join("fig7_displacements.png");
        figures::fig7_figure(&figure, &study.summary.fig7)?;
        figures.fig7.push((
            figure,
            "Elastic displacements δp_x (top, cf. Fig. 8) and δp_y (bottom, cf. Fig. 9) of M1, M2, \
             M3 and the TCP at q = (0, 90°, 0, 0, 0, 0) under f_y = 1400 N at the TCP: the \
             twin's tracker (SIMULATED) against each model"
                .to_string(),
        ));
    }
    write_campaign(
        study,
        &out.join("grid.csv"),
        &study.grid,
        "validation grid",
        seed.wrapping_add(1),
    )?;
    write_text(
        &out.join("grid_predictions.csv"),
        &csv_files::predictions_csv(&study.grid, &study.grid_predictions),
    )?;
    figures.grid = figures::grid_figures(
        out,
        &study.grid,
        &study.grid_params.loads_n,
        &study.grid_predictions,
    )?;
    write_campaign(
        study,
        &out.join("spiral.csv"),
        &study.spiral,
        "spiral",
        seed.wrapping_add(2),
    )?;
    write_text(
        &out.join("spiral_predictions.csv"),
        &csv_files::predictions_csv(&study.spiral, &study.spiral_predictions),
    )?;
    figures.spiral = figures::spiral_figures(
        out,
        &study.spiral,
        &study.spiral_params,
        &study.spiral_predictions,
    )?;
    Ok(())
}

/// The two cone runs' folders, the controller's log and the forming and controller figures.
fn write_forming_files(
    study: &Study,
    out: &Path,
    figures: &mut StudyFigures,
) -> Result<(), DrawError> {
    crate::report::forming_run::write_forming_run(&study.open, &out.join("forming_open"))?;
    crate::report::forming_run::write_forming_run(
        &study.closed.forming,
        &out.join("forming_closed"),
    )?;
    write_text(
        &out.join("forming_closed").join("controller_log.csv"),
        &csv_files::controller_log_csv(&study.closed.trace, &study.nominal.name),
    )?;
    figures.forming = figures::forming_figures(out, &study.open, &study.closed.forming)?;
    figures.controller = figures::controller_figures(out, &study.closed.trace)?;
    Ok(())
}

/// The plunge's figure, and the sensitivity's table and heatmap.
fn write_contact_and_sensitivity(
    study: &Study,
    out: &Path,
    figures: &mut StudyFigures,
) -> Result<(), DrawError> {
    let figure = out.join("stiff_contact_force.png");
    figures::contact_figure(&figure, &study.plunge, 1e7)?;
    figures.contact.push((
        figure,
        "Plunge into a 10⁷ N/m fixture: the contact force over time without correction, with \
         correction and no runaway guard, and with the runaway guard, whose curve lies on the \
         uncorrected one once the guard has withdrawn the correction along the runaway \
         direction (SIMULATED)"
            .to_string(),
    ));
    if let Some(result) = &study.summary.sensitivity {
        write_text(
            &out.join("sensitivity.csv"),
            &csv_files::sensitivity_csv(result),
        )?;
        let figure = out.join("sensitivity_heatmap.png");
        figures::sensitivity_heatmap(result, &figure)?;
        figures.sensitivity.push((
            figure,
            "Improvement of the max path error across the correction delay and the model's \
             compliance scale (SIMULATED, sensitivity cone)"
                .to_string(),
        ));
    }
    Ok(())
}
