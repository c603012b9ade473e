//! Per-row predictions of a calibrated robot file (`deflex predict`): each absolute reading's
//! target in its set-up's tracker frame, with the error where measured.

use crate::campaign::Campaign;
use crate::data::AbsoluteRow;
use crate::fit::ErrorStats;
use crate::params::{EgModel, Param};
use crate::solve::{Loss, SolveOptions};
use deflex_model::Robot;
use serde_json::{Value, json};

fn mm(v: f64) -> String {
    format!("{:.3}", v * 1e3)
}

/// Per-row predictions of a calibrated robot (`deflex predict`).
pub struct Prediction {
    /// CSV: the input columns that identify the row, predicted position, error when measured.
    pub csv: String,
    /// Summary text.
    pub text: String,
    /// Summary JSON.
    pub json: Value,
}

/// Why rows cannot be predicted.
#[derive(Debug, thiserror::Error)]
pub enum PredictError {
    /// A row names a set-up or target the robot file does not have.
    #[error(
        "line {line}: {what} `{name}` is not in the robot file (it knows: {known}); calibrate with it, or use --fit-setup for a set-up"
    )]
    Unknown {
        /// Line.
        line: u64,
        /// `set-up` or `target`.
        what: &'static str,
        /// Name.
        name: String,
        /// Known names.
        known: String,
    },
    /// Campaign error.
    #[error(transparent)]
    Campaign(#[from] crate::campaign::CampaignError),
}

/// Predict each row's target in its set-up's tracker frame with the robot's calibrated
/// geometry, gravity sag and set-ups. With `fit_setup`, the registration of every set-up in the
/// rows is fitted first (on all rows; new set-ups are registered from scratch).
pub fn predict_rows(
    robot: &Robot,
    rows: Vec<AbsoluteRow>,
    fit_setup: bool,
) -> Result<Prediction, PredictError> {
    let mut model = EgModel::from_robot(robot);
    for row in &rows {
        if model.target_index(&row.target).is_none() {
            return Err(PredictError::Unknown {
                line: row.line,
                what: "target",
                name: row.target.clone(),
                known: model
                    .targets
                    .iter()
                    .map(|t| t.name.clone())
                    .collect::<Vec<_>>()
                    .join(", "),
            });
        }
        if !fit_setup && model.setup_index(&row.setup).is_none() {
            return Err(PredictError::Unknown {
                line: row.line,
                what: "set-up",
                name: row.setup.clone(),
                known: model
                    .setups
                    .iter()
                    .map(|t| t.name.clone())
                    .collect::<Vec<_>>()
                    .join(", "),
            });
        }
    }
    let campaign = Campaign::new(&mut model, rows, Vec::new())?;
    if fit_setup {
        let setups: Vec<usize> = campaign
            .setup_of
            .iter()
            .copied()
            .collect::<std::collections::BTreeSet<_>>()
            .into_iter()
            .collect();
        let all = vec![1.0; campaign.len()];
        let fresh: Vec<usize> = setups
            .iter()
            .copied()
            .filter(|&s| model.setups[s].pose == deflex_model::Pose::identity())
            .collect();
        crate::register::initialise(&mut model, &campaign, &fresh, &[], &all, 1);
        let params: Vec<Param> = setups
            .iter()
            .flat_map(|&s| {
                (0..3)
                    .map(move |k| Param::SetupRotation(s, k))
                    .chain((0..3).map(move |k| Param::SetupTranslation(s, k)))
            })
            .collect();
        let options = SolveOptions {
            loss: Loss::HUBER_DEFAULT,
            ..SolveOptions::default()
        };
        crate::solve::solve(&mut model, &campaign, &params, &all, &options);
    }
    let mut writer = csv::WriterBuilder::new().from_writer(Vec::new());
    let n = robot.joint_count();
    let mut header: Vec<String> = vec!["line".into(), "setup".into(), "target".into()];
    header.extend((1..=n).map(|i| format!("q{i}_rad")));
    header.extend(
        [
            "predicted_x_m",
            "predicted_y_m",
            "predicted_z_m",
            "x_m",
            "y_m",
            "z_m",
            "error_m",
        ]
        .map(String::from),
    );
    let _ = writer.write_record(&header);
    let mut norms = Vec::new();
    for (i, row) in campaign.absolute.iter().enumerate() {
        let loads = campaign.loads(&model, i);
        let p = model.predict_tracker(
            &row.q_rad,
            campaign.setup_of[i],
            campaign.target_of[i],
            &loads,
        );
        let error = (nalgebra::Vector3::from(row.position_m) - p).norm();
        norms.push(error);
        let mut record = vec![row.line.to_string(), row.setup.clone(), row.target.clone()];
        record.extend(row.q_rad.iter().map(|v| format!("{v:?}")));
        record.extend([p.x, p.y, p.z].iter().map(|v| format!("{v:?}")));
        record.extend(row.position_m.iter().map(|v| format!("{v:?}")));
        record.push(format!("{error:e}"));
        let _ = writer.write_record(&record);
    }
    let csv = String::from_utf8(writer.into_inner().unwrap_or_default()).unwrap_or_default();
    let stats = ErrorStats::of(&norms);
    let text = format!(
        "{} rows predicted{}; error norm (measured − predicted): RMS {} mm, mean {} mm, p95 {} mm, max {} mm\n",
        stats.count,
        if fit_setup {
            " (set-up registration fitted on these rows)"
        } else {
            ""
        },
        mm(stats.rms),
        mm(stats.mean),
        mm(stats.p95),
        mm(stats.max)
    );
    let json = json!({
        "rows": stats.count, "fit_setup": fit_setup,
        "rms_m": stats.rms, "mean_m": stats.mean, "p95_m": stats.p95, "max_m": stats.max,
        "setups": model.setups.iter().map(|s| json!({"name": s.name, "xyz_m": [s.pose.translation.vector.x, s.pose.translation.vector.y, s.pose.translation.vector.z], "rpy_rad": deflex_model::spatial::rpy_from_rotation(&s.pose.rotation)})).collect::<Vec<_>>(),
    });
    Ok(Prediction { csv, text, json })
}
