//! `register`: a new measuring session's set-up (and a new or remounted probe's offset) fitted
//! from a few readings with the calibrated robot frozen.

use super::OptionNames;
use super::files::{CalibratedModel, read_absolute, write_unit};
use crate::calibrate::MeasurementSource;
use crate::error::{Error, Result};
use crate::report::absolute_report;
use deflex_calibrate::geometry::campaign::Campaign;
use deflex_calibrate::geometry::data::AbsoluteRow;
use deflex_calibrate::geometry::params::EgModel;
use deflex_calibrate::geometry::plausible::{ChangeBounds, large_registration_moves};
use deflex_calibrate::geometry::register::{RegisterOptions, Registration};
use deflex_calibrate::geometry::solve::Loss;
use deflex_calibrate::geometry::terms::CalibrationTerms;
use deflex_model::Robot;
use std::path::Path;

/// Readings that do not say which set-up or target to register. The command line names the
/// data first and its flags (`--setup`); Python names the keyword first, as every keyword
/// error, and its keywords (`setup=`).
#[derive(Debug, thiserror::Error)]
pub enum RegisterInputError {
    /// Several set-ups and none chosen.
    #[error("{}{data}: the data names set-ups {setups}: choose one with {}", .names.subject("setup"), .names.give("setup"))]
    WhichSetup {
        /// The data.
        data: String,
        /// The set-ups it names.
        setups: String,
        /// How the messages name the options.
        names: OptionNames,
    },
    /// No reading of the set-up asked for.
    #[error("{}{data}: no reading of set-up `{setup}`", .names.subject("setup"))]
    NoSetupReadings {
        /// The data.
        data: String,
        /// The set-up.
        setup: String,
        /// How the messages name the options.
        names: OptionNames,
    },
    /// A reading of a target the robot file does not know, and not the one to register.
    #[error("{}{data}:{line}: target `{target}` is not in the robot file: register it with {}", .names.subject("target"), .names.give_text("target", .target))]
    UnknownTarget {
        /// The data.
        data: String,
        /// Its line.
        line: u64,
        /// The target.
        target: String,
        /// How the messages name the options.
        names: OptionNames,
    },
    /// The target to register names a target no reading has.
    #[error("{}{data}: no reading of target `{target}`", .names.subject("target"))]
    NoTargetReadings {
        /// The data.
        data: String,
        /// The target.
        target: String,
        /// How the messages name the options.
        names: OptionNames,
    },
}

/// Options of [`register`] (the CLI's `deflex register` flags, SI).
#[derive(Clone, Debug)]
pub struct RegisterRequest {
    /// Set-up to register (default: the one set-up the data names).
    pub setup: Option<String>,
    /// Target whose offset is fitted too (a new or remounted probe).
    pub target: Option<String>,
    /// Fit the measured orientations with this σ (rad) for rows without `sigma_rad`.
    pub orientations: Option<f64>,
    /// Residual RMS (m) above which the robot is deemed changed (default: 1.5 × the
    /// calibration's held-out RMS from its terms).
    pub recalibrate_above_m: Option<f64>,
    /// Columns of the data that deflex does not read, kept knowingly.
    pub ignored_columns: Vec<String>,
    /// Write a registration that moves a known set-up by more than the arm's size or puts the
    /// target further from the flange than half of it
    /// ([`deflex_calibrate::geometry::plausible`]). Off: such a registration is refused.
    pub allow_large_changes: bool,
    /// How the messages name the options.
    pub names: OptionNames,
}

/// A registration and the updated robot.
pub struct SessionRegistration {
    /// The fit of the set-up (and target).
    pub registration: Registration,
    /// The set-up registered.
    pub setup: String,
    /// The target registered, if any.
    pub target: Option<String>,
    /// The robot with the new set-up (and target), everything else as it was.
    pub robot: Robot,
    /// The calibration's terms, carried over unchanged.
    pub terms: Option<CalibrationTerms>,
    /// The terms file's text, written unchanged beside the updated robot.
    pub terms_text: Option<String>,
}

/// The set-up to register: the one asked for, or the data's only one.
fn chosen_setup(rows: &[AbsoluteRow], request: &RegisterRequest, data: &str) -> Result<String> {
    if let Some(s) = &request.setup {
        return Ok(s.clone());
    }
    let mut names: Vec<&str> = rows.iter().map(|r| r.setup.as_str()).collect();
    names.sort_unstable();
    names.dedup();
    match names.as_slice() {
        [one] => Ok(one.to_string()),
        _ => Err(RegisterInputError::WhichSetup {
            data: data.to_string(),
            setups: names.join(", "),
            names: request.names,
        }
        .into()),
    }
}

/// The readings of `setup`, each of a target the robot knows or the one to register.
fn setup_readings(
    rows: Vec<AbsoluteRow>,
    setup: &str,
    model: &EgModel,
    request: &RegisterRequest,
    data: &str,
) -> Result<Vec<AbsoluteRow>> {
    let rows: Vec<AbsoluteRow> = rows.into_iter().filter(|r| r.setup == setup).collect();
    if rows.is_empty() {
        return Err(RegisterInputError::NoSetupReadings {
            data: data.to_string(),
            setup: setup.to_string(),
            names: request.names,
        }
        .into());
    }
    for row in &rows {
        let known = model.target_index(&row.target).is_some();
        if !known && request.target.as_deref() != Some(row.target.as_str()) {
            return Err(RegisterInputError::UnknownTarget {
                data: data.to_string(),
                line: row.line,
                target: row.target.clone(),
                names: request.names,
            }
            .into());
        }
    }
    Ok(rows)
}

/// `deflex register`: a new measuring session's set-up (and a new target's offset) fitted from
/// a few readings with the calibrated robot frozen, with the checks (the set-up named or the
/// data's only one, every target known or registered, orientations present when asked).
pub fn register(
    calibrated: CalibratedModel,
    source: &MeasurementSource,
    request: &RegisterRequest,
) -> Result<SessionRegistration> {
    let names = request.names;
    if let Some(sigma) = request.orientations {
        crate::error::bounded(
            &names.name("sigma_rad"),
            sigma,
            1e-9,
            deflex_calibrate::measurements::MAX_SIGMA_RAD,
            "rad",
        )?;
    }
    if let Some(m) = request.recalibrate_above_m {
        // The command line checks its flag in mm before: this names Python's keyword.
        crate::error::bounded("recalibrate_above_m", m, 1e-6, 1.0, "m")?;
    }
    let CalibratedModel {
        mut model,
        terms,
        terms_text,
    } = calibrated;
    let data = source.name();
    let rows = read_absolute(source, model.robot.joint_count(), &request.ignored_columns)?;
    let setup_name = chosen_setup(&rows, request, &data)?;
    let rows = setup_readings(rows, &setup_name, &model, request, &data)?;
    let new_setup = model.setup_index(&setup_name).is_none();
    // The calibrated set-ups, to bound how far a known one moves.
    let calibrated_setups = model.setups.clone();
    if let Some(t) = request
        .target
        .as_deref()
        .and_then(|t| model.target_index(t))
    {
        // A remounted or replaced probe: found from scratch.
        model.targets[t].position = nalgebra::Vector3::zeros();
        model.targets[t].rotation = None;
    }
    let mut campaign = Campaign::new(&mut model, rows, Vec::new())?;
    if let Some(sigma) = request.orientations {
        campaign.use_orientations(sigma);
        if campaign.orientation_rows.is_empty() {
            return Err(Error::invalid(
                names.name("orientations"),
                "no reading has rx_rad, ry_rad, rz_rad",
            ));
        }
    }
    // Campaign::new adds the readings' new set-ups and targets to the model.
    let setup = model.setup_index(&setup_name).ok_or_else(|| {
        Error::from(RegisterInputError::NoSetupReadings {
            data: data.clone(),
            setup: setup_name.clone(),
            names,
        })
    })?;
    let target = match &request.target {
        Some(t) => Some(model.target_index(t).ok_or_else(|| {
            Error::from(RegisterInputError::NoTargetReadings {
                data: data.clone(),
                target: t.clone(),
                names,
            })
        })?),
        None => None,
    };
    let options = RegisterOptions {
        setup,
        target,
        loss: Loss::HUBER_DEFAULT,
        recalibrate_above_m: request
            .recalibrate_above_m
            .or_else(|| terms.as_ref().and_then(|t| t.recalibrate_above_m())),
        restart_setup: new_setup,
    };
    let all = vec![1.0; campaign.len()];
    let registration =
        deflex_calibrate::geometry::register::register(&mut model, &campaign, &all, &options)?;
    if !request.allow_large_changes {
        check_moves(&model, &calibrated_setups, setup, target, &data, names)?;
    }
    // Orientations measured but not fitted: the new target's frame in closed form, so that
    // predictions can report orientation errors.
    if let Some(t) = target.filter(|&t| model.targets[t].rotation.is_none()) {
        deflex_calibrate::geometry::register::start::initialise_target_rotations(
            &mut model,
            &campaign,
            &[t],
            &all,
        );
    }
    Ok(SessionRegistration {
        registration,
        setup: setup_name,
        target: request.target.clone(),
        robot: model.to_robot(),
        terms,
        terms_text,
    })
}

/// Refuse a registration that moves a known set-up (one of `calibrated_setups`) or puts the
/// target beyond its bound ([`large_registration_moves`]): nothing is written.
fn check_moves(
    model: &EgModel,
    calibrated_setups: &[deflex_model::NamedPose],
    setup: usize,
    target: Option<usize>,
    data: &str,
    names: OptionNames,
) -> Result<()> {
    let bounds = ChangeBounds::for_robot(&model.robot);
    let large = large_registration_moves(calibrated_setups, model, setup, target, &bounds);
    if large.is_empty() {
        return Ok(());
    }
    Err(Error::LargeRegistration {
        data: data.to_string(),
        changes: large
            .iter()
            .map(ToString::to_string)
            .collect::<Vec<_>>()
            .join(", "),
        names,
    })
}

/// The registration as text: residual, parameters, warnings.
pub fn registration_text(r: &SessionRegistration) -> String {
    absolute_report::registration::text(&r.registration, &r.setup, r.target.as_deref())
}

/// The text the CLI prints after a registration it saved to `path`.
pub fn saved_registration_text(r: &SessionRegistration, path: &Path) -> String {
    format!(
        "{}updated robot written to {}\n",
        registration_text(r),
        path.display()
    )
}

/// The registration as JSON (SI); `out` the robot file written (`null` when none was).
pub fn registration_json(r: &SessionRegistration, out: Option<&Path>) -> serde_json::Value {
    let mut v = absolute_report::registration::json(
        &r.registration,
        &r.setup,
        r.target.as_deref(),
        out.unwrap_or(Path::new("")),
    );
    if out.is_none() {
        v["out"] = serde_json::Value::Null;
    }
    v
}

/// Write the updated robot file and the calibration's terms file beside it, unchanged, as one
/// unit (whole or not at all).
pub fn save_registration(r: &SessionRegistration, path: &Path) -> Result<()> {
    write_unit(&r.robot, r.terms_text.as_deref(), path, || Ok(Vec::new()))?;
    Ok(())
}
