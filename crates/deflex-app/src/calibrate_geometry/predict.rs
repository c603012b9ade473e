//! `predict`: each absolute reading's target position predicted by a calibrated robot, with the
//! error where measured.

use super::files::{CalibratedModel, read_absolute};
use crate::calibrate::MeasurementSource;
use crate::error::{Error, Result};
use crate::report::absolute_report::prediction;
use crate::table::write_text;
use std::path::Path;

/// A prediction with its renderings.
pub struct PredictionRun {
    /// The prediction CSV (`deflex predict --out`).
    pub csv: String,
    /// The summary text.
    pub text: String,
    /// The summary JSON (SI).
    pub json: serde_json::Value,
}

/// Per-row predictions of a calibrated robot (`deflex predict`): the prediction CSV (with the
/// error where measured), the summary text and JSON. With `fit_setup`, the registration of the
/// rows' set-ups is fitted on the rows first. `ignored`: columns of the data that deflex does
/// not read, kept knowingly.
pub fn predict(
    model: &CalibratedModel,
    source: &MeasurementSource,
    fit_setup: bool,
    ignored: &[String],
) -> Result<PredictionRun> {
    let rows = read_absolute(source, model.model.robot.joint_count(), ignored)?;
    let p = deflex_calibrate::geometry::predict::predict_rows(&model.model, rows, fit_setup)?;
    let csv = prediction::prediction_csv(&p).map_err(|e| Error::Serialise {
        what: "the prediction CSV",
        reason: e.to_string(),
    })?;
    Ok(PredictionRun {
        csv,
        text: prediction::prediction_text(&p),
        json: prediction::prediction_json(&p),
    })
}

impl PredictionRun {
    /// Write the prediction CSV, whole or not at all.
    pub fn save(&self, path: &Path) -> Result<()> {
        write_text(path, &self.csv)
    }

    /// The text the CLI prints after a prediction it saved to `path`.
    pub fn saved_text(&self, path: &Path) -> String {
        format!("{}predictions written to {}\n", self.text, path.display())
    }
}
