//! `import ur10-tracker`: a series of the public UR10 laser-tracker data set (Landgraf et al.,
//! CASE 2021) in the absolute measurement format.

use super::OptionNames;
use crate::error::{Error, Result};
use crate::table::write_text;
use deflex_calibrate::geometry::data::{AbsoluteRow, check_label, format_absolute, limits};
use deflex_calibrate::geometry::ur10_tracker::{
    ImportOptions, ImportSummary, MAX_SERIES_BYTES, parse_series,
};
use std::path::{Path, PathBuf};

/// Largest `every` (keep every n-th reading).
const MAX_EVERY: usize = 1_000_000;

/// Options of [`import_ur10_tracker`].
#[derive(Clone, Debug)]
pub struct ImportRequest {
    /// Set-up label written on every row (one per tracker placement).
    pub setup: String,
    /// Target label written on every row.
    pub target: String,
    /// Write the tracker's per-reading standard deviation into `sigma_m`.
    pub tracker_sigma: bool,
    /// Keep every n-th reading only (1 to 1 000 000).
    pub every: usize,
    /// How the messages name the options.
    pub names: OptionNames,
}

/// An imported series: the absolute CSV text and what was read.
pub struct TrackerImport {
    /// The absolute measurement CSV.
    pub text: String,
    /// What the series held (its file, readings, time stamps, σ, temperatures).
    pub summary: ImportSummary,
    /// Readings written (every `every`-th).
    pub rows_written: usize,
    /// The set-up label written.
    pub setup: String,
    /// The target label written.
    pub target: String,
}

/// `deflex import ur10-tracker`: the series (a folder holding one `measurements_*.csv`, or the
/// file itself) as absolute CSV text, every `every`-th reading kept. Labels its own reader
/// would not read back the same are refused, not rewritten (a silently changed set-up name
/// would no longer match the robot file's `[[setup]]`).
pub fn import_ur10_tracker(series: &Path, request: &ImportRequest) -> Result<TrackerImport> {
    let names = request.names;
    if request.every == 0 || request.every > MAX_EVERY {
        return Err(Error::invalid(
            names.name("every"),
            format!("expected 1…{MAX_EVERY}, got {}", request.every),
        ));
    }
    for (keyword, label) in [("setup", &request.setup), ("target", &request.target)] {
        check_label(label).map_err(|problem| Error::ImportLabel {
            option: names.name(keyword),
            label: deflex_files::shown(label).to_string(),
            problem,
            max_bytes: limits::MAX_LABEL_BYTES,
        })?;
    }
    let options = ImportOptions {
        setup: request.setup.clone(),
        target: request.target.clone(),
        tracker_sigma: request.tracker_sigma,
    };
    let file = series_file(series)?;
    let text = deflex_files::read_bounded(&file, MAX_SERIES_BYTES)?;
    let (rows, mut summary) = parse_series(&text, &file.display().to_string(), &options)?;
    summary.file = file;
    let kept: Vec<AbsoluteRow> = rows.into_iter().step_by(request.every).collect();
    let comments = vec![
        "UR10 laser-tracker data: Landgraf, Ernst, Schleth, Fabritius, Huber, IEEE CASE 2021 (MIT licence)".to_string(),
        format!(
            "imported by deflex from {} (every {} reading(s); approach_q*_rad from the whole time-ordered series); T-Mac probe in the tracker frame",
            summary.file.display(),
            request.every
        ),
    ];
    Ok(TrackerImport {
        text: format_absolute(&kept, &comments),
        summary,
        rows_written: kept.len(),
        setup: request.setup.clone(),
        target: request.target.clone(),
    })
}

impl TrackerImport {
    /// Write the absolute CSV, whole or not at all.
    pub fn save(&self, path: &Path) -> Result<()> {
        write_text(path, &self.text)
    }

    /// The summary (SI): `file`, `rows_read`, `rows_written`, `rows_without_time`,
    /// `median_tracker_std_m`, `temperature_range_C` and, when written, `out`.
    pub fn summary_json(&self, out: Option<&Path>) -> serde_json::Value {
        let s = &self.summary;
        let mut value = serde_json::json!({
            "file": s.file.display().to_string(),
            "rows_read": s.rows,
            "rows_written": self.rows_written,
            "rows_without_time": s.rows_without_time,
            "median_tracker_std_m": s.median_tracker_std_m,
            "temperature_range_C": s.temperature_range_c,
        });
        if let Some(out) = out {
            value["out"] = serde_json::json!(out.display().to_string());
        }
        value
    }

    /// The text the CLI prints after an import it saved to `path`.
    pub fn saved_text(&self, path: &Path) -> String {
        let s = &self.summary;
        let mut text = format!(
            "{}: {} readings, {} written to {} (set-up {}, target {})\n",
            s.file.display(),
            s.rows,
            self.rows_written,
            path.display(),
            self.setup,
            self.target
        );
        if let Some(sigma) = s.median_tracker_std_m {
            text.push_str(&format!(
                "tracker standard deviation per reading: median {:.1} µm\n",
                sigma * 1e6
            ));
        }
        if let Some([lo, hi]) = s.temperature_range_c {
            text.push_str(&format!("temperature {lo:.2} … {hi:.2} °C\n"));
        }
        if s.rows_without_time > 0 {
            text.push_str(&format!(
                "{} time stamps unreadable (left out of time_s)\n",
                s.rows_without_time
            ));
        }
        text
    }
}

/// The single `measurements_*.csv` of a series folder (or the file itself).
fn series_file(path: &Path) -> Result<PathBuf> {
    if path.is_file() {
        return Ok(path.to_path_buf());
    }
    let entries = std::fs::read_dir(path)
        .map_err(|source| Error::Input(deflex_files::FileIoError::new(path, source).into()))?;
    let mut found: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with("measurements") && n.ends_with(".csv"))
        })
        .collect();
    found.sort();
    match found.len() {
        1 => Ok(found.remove(0)),
        found => Err(Error::SeriesFiles {
            folder: path.display().to_string(),
            found,
        }),
    }
}
