//! Per-row predictions of a calibrated model (`deflex predict`): each absolute reading's
//! target in its set-up's tracker frame (and its orientation when the target's frame is
//! known), with the error where measured.

use crate::geometry::campaign::Campaign;
use crate::geometry::data::AbsoluteRow;
use crate::geometry::params::{EgModel, Param};
use crate::geometry::protocol::row_errors;
use crate::geometry::solve::{Loss, SolveOptions};
use crate::stats::ErrorNormStats;
use deflex_model::NamedPose;

/// One row's prediction.
#[derive(Clone, Debug, PartialEq)]
pub struct RowPrediction {
    /// The input row.
    pub row: AbsoluteRow,
    /// Predicted target position, tracker frame (m).
    pub predicted_m: [f64; 3],
    /// Predicted target orientation, tracker frame (rotation vector, rad), when the target's
    /// frame is known.
    pub predicted_rotation_rad: Option<[f64; 3]>,
    /// Position error norm (m).
    pub error_m: f64,
    /// Orientation error angle (rad), when measured and predicted.
    pub orientation_error_rad: Option<f64>,
}

/// Per-row predictions of a calibrated model.
#[derive(Clone, Debug)]
pub struct Prediction {
    /// Each row.
    pub rows: Vec<RowPrediction>,
    /// Position error distribution (m).
    pub position: ErrorNormStats,
    /// Orientation error distribution (rad), when measured and predicted.
    pub orientation: Option<ErrorNormStats>,
    /// Whether the set-ups were registered on these rows first.
    pub fit_setup: bool,
    /// The set-ups used.
    pub setups: Vec<NamedPose>,
}

/// Why rows cannot be predicted.
#[derive(Debug, thiserror::Error)]
pub enum PredictError {
    /// A row names a set-up or target the robot file does not have.
    #[error("line {line}: {what} `{name}` is not in the robot file (it knows: {known}); {hint}")]
    Unknown {
        /// Line.
        line: u64,
        /// `set-up` or `target`.
        what: &'static str,
        /// Name.
        name: String,
        /// Known names.
        known: String,
        /// What to do.
        hint: &'static str,
    },
    /// Campaign error.
    #[error(transparent)]
    Campaign(#[from] crate::geometry::campaign::CampaignError),
}

fn known(names: impl Iterator<Item = String>) -> String {
    names.collect::<Vec<_>>().join(", ")
}

/// Predict each row's target in its set-up's tracker frame with the model's calibrated
/// geometry, gravity sag, joint terms and set-ups. With `fit_setup`, the registration of every
/// set-up in the rows is fitted first (on all rows; new set-ups are registered from scratch):
/// optimistic, for a quick look — `deflex register` registers from a few readings instead.
pub fn predict_rows(
    model: &EgModel,
    rows: Vec<AbsoluteRow>,
    fit_setup: bool,
) -> Result<Prediction, PredictError> {
    let mut model = model.clone();
    for row in &rows {
        if model.target_index(&row.target).is_none() {
            return Err(PredictError::Unknown {
                line: row.line,
                what: "target",
                name: row.target.clone(),
                known: known(model.targets.iter().map(|t| t.name.clone())),
                hint: "register it first (deflex register --target NAME)",
            });
        }
        if !fit_setup && model.setup_index(&row.setup).is_none() {
            return Err(PredictError::Unknown {
                line: row.line,
                what: "set-up",
                name: row.setup.clone(),
                known: known(model.setups.iter().map(|s| s.name.clone())),
                hint: "register it first (deflex register --setup NAME), or use --fit-setup",
            });
        }
    }
    let campaign = Campaign::new(&mut model, rows, Vec::new())?;
    if fit_setup {
        register_all(&mut model, &campaign);
    }
    let mut out = Vec::with_capacity(campaign.absolute.len());
    for (i, row) in campaign.absolute.iter().enumerate() {
        let (s, t) = (campaign.setup_of[i], campaign.target_of[i]);
        let ev = model.evaluate(&row.q_rad, t, &campaign.conditions(&model, i));
        let p = model.tracker_position(&ev, s);
        let rotation = model.targets[t].rotation.map(|_| {
            let v = deflex_model::spatial::rotation_log(&model.tracker_orientation(&ev, s));
            [v.x, v.y, v.z]
        });
        let (error_m, orientation_error_rad) = row_errors(&model, &campaign, i);
        out.push(RowPrediction {
            row: row.clone(),
            predicted_m: [p.x, p.y, p.z],
            predicted_rotation_rad: rotation,
            error_m,
            orientation_error_rad,
        });
    }
    let position = ErrorNormStats::of(&out.iter().map(|r| r.error_m).collect::<Vec<_>>());
    let orientation: Vec<f64> = out.iter().filter_map(|r| r.orientation_error_rad).collect();
    Ok(Prediction {
        rows: out,
        position,
        orientation: (!orientation.is_empty()).then(|| ErrorNormStats::of(&orientation)),
        fit_setup,
        setups: model.setups.clone(),
    })
}

/// Register every set-up of the campaign on all its rows.
fn register_all(model: &mut EgModel, campaign: &Campaign) {
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
    crate::geometry::register::start::initialise(model, campaign, &fresh, &[], &all, 1);
    let params: Vec<Param> = setups.iter().flat_map(|&s| Param::setup_pose(s)).collect();
    let options = SolveOptions {
        loss: Loss::HUBER_DEFAULT,
        ..SolveOptions::default()
    };
    crate::geometry::solve::solve(model, campaign, &params, &all, &options);
}
