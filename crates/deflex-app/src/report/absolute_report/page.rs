//! The report folder of an elasto-geometric calibration (`deflex calibrate-geometry --report`):
//! the text, JSON and CSV of [`super`], the plots ([`super::plots`]) and `index.html`.

use super::{
    ESTIMATE_HEADERS, HELDOUT_HEADERS, estimate_rows, heldout_rows, iteration_rows, plots, tables,
};
use crate::report::draw::{write_page, write_text};
use crate::report::{DrawError, PageError};
use deflex_calibrate::geometry::campaign::Campaign;
use deflex_calibrate::geometry::fit::FitResult;
use deflex_plot::{HtmlReport, html_escape};
use std::path::{Path, PathBuf};

/// Write the report folder (whole or not at all): `report.txt`, `report.json`,
/// `iterations.csv`, `estimates.csv`, `residuals.csv`, `outliers.csv`, `joint_maps.csv` (with
/// joint maps), plots and `index.html`. `summary` is the text report and `summary_json` the
/// JSON one as the workflow shows them ([`super::text`] and [`super::json()`] with what the
/// workflow adds before them: why the steps were chosen, a warning of changes allowed beyond
/// their bounds).
pub fn write_report(
    result: &FitResult,
    campaign: &Campaign,
    summary: &str,
    summary_json: &serde_json::Value,
    dir: &Path,
) -> Result<Vec<PathBuf>, PageError> {
    let page = PageError::of("elasto-geometric calibration report");
    let io = |source| page(DrawError::io_on(dir)(source));
    let staging = deflex_files::AtomicDir::create(dir).map_err(io)?;
    let root = staging.path().to_path_buf();
    let mut files = Vec::new();
    // A table or JSON text that cannot be made is reported as the file it was for.
    let unwritable = |name: &str| {
        let (path, page) = (root.join(name), &page);
        move |source: std::io::Error| page(DrawError::content_of(&path)(source))
    };
    let mut put = |name: &str, text: &str| -> Result<(), PageError> {
        write_text(&root.join(name), text).map_err(&page)?;
        files.push(dir.join(name));
        Ok(())
    };
    put("report.txt", summary)?;
    let json_text = serde_json::to_string_pretty(summary_json)
        .map_err(|e| unwritable("report.json")(e.into()))?;
    put("report.json", &json_text)?;
    for table in tables::csv_tables(result, campaign) {
        let text = tables::csv_text(&table.headers, &table.rows).map_err(unwritable(table.file))?;
        put(table.file, &text)?;
    }
    let images = plots::draw(result, campaign, &root).map_err(&page)?;
    let mut html = HtmlReport::new("deflex: elasto-geometric calibration");
    html.section("Summary").preformatted(summary.to_string());
    if let Some(w) = &result.warning {
        html.note(html_escape(w));
    }
    let (headers, rows) = iteration_rows(result);
    let h: Vec<&str> = headers.iter().map(String::as_str).collect();
    html.section("Iteration table").table(&h, &rows);
    let held = heldout_rows(result);
    if !held.is_empty() {
        html.section("Held-out error distribution")
            .table(&HELDOUT_HEADERS, &held);
    }
    html.section("Identified parameters")
        .table(&ESTIMATE_HEADERS, &estimate_rows(result));
    html.section("Residual plots");
    for (file, caption) in &images {
        html.image(root.join(file), caption.clone());
        files.push(dir.join(file));
    }
    write_page(&html, &root.join("index.html")).map_err(&page)?;
    files.push(dir.join("index.html"));
    staging.commit().map_err(io)?;
    Ok(files)
}
