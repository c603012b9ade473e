//! Elasto-geometric calibration from absolute tracker readings (`deflex calibrate-geometry`),
//! per-row prediction and set-up re-registration (`deflex predict [--fit-setup]`) and the UR10
//! tracker importer (`deflex import ur10-tracker`), with the CLI's checks and messages.
//!
//! Thin layer over `deflex-absolute` (files read here, through `deflex-load`'s bounded reads;
//! the report rendered by `deflex-report`): [`parse_steps`], [`parse_loss`],
//! [`calibrate_geometry`], [`predict`], [`register`], [`import_ur10_tracker`], [`report_text`],
//! [`report_json`], [`write_report`].

use crate::calibrate::{Source, table_error};
use crate::error::{Error, Result};
use crate::report::absolute_report;
use deflex_calibrate::geometry::campaign::Campaign;
use deflex_calibrate::geometry::data::{AbsoluteRow, format_absolute, limits, parse_absolute};
use deflex_calibrate::geometry::fit::{
    ChoiceError, FitOptions, FitResult, HeldOutProtocol, Step, fit, session_groups,
};
use deflex_calibrate::geometry::params::EgModel;
use deflex_calibrate::geometry::register::{RegisterOptions, Registration};
use deflex_calibrate::geometry::solve::Loss;
use deflex_calibrate::geometry::terms::CalibrationTerms;
use deflex_calibrate::geometry::ur10_tracker::{
    ImportOptions, ImportSummary, MAX_SERIES_BYTES, parse_series,
};
use deflex_model::Robot;
use std::path::{Path, PathBuf};

/// Gap between time stamps that starts a new measuring session (`cv_by="session"`), as the
/// CLI's `--cv-by session`.
pub const SESSION_GAP_S: f64 = 3600.0;
/// Largest terms file read (bytes), as the CLI.
const MAX_TERMS_BYTES: u64 = 64 << 20;

/// A bounded read of a file the user named, with the error naming it.
pub fn read_text(path: &Path, limit: u64) -> Result<String> {
    crate::load::read_bounded(path, limit).map_err(|e| match e {
        crate::load::BoundedReadError::Io(source) => Error::Read {
            path: path.display().to_string(),
            source,
        },
        crate::load::BoundedReadError::TooLarge(bytes) => Error::TooLarge {
            path: path.display().to_string(),
            bytes,
            limit,
        },
    })
}

/// Model steps from their names (`registration`, `geometry`, `compliance`, `masses`,
/// `harmonics:N`, `periodic:N`, `backlash`, `torsion:cubic`, `torsion:soft:T`, `residual`), as
/// `--steps` takes them.
pub fn parse_steps(names: &[String]) -> Result<Vec<Step>> {
    names
        .iter()
        .map(|item| {
            item.parse()
                .map_err(|e: ChoiceError| Error::invalid("steps", e.to_string()))
        })
        .collect()
}

/// A robust loss from its name (`huber`, `cauchy`, `none`, `huber:K`, `cauchy:K`).
pub fn parse_loss(text: &str) -> Result<Loss> {
    text.parse()
        .map_err(|e: ChoiceError| Error::invalid("loss", e.to_string()))
}

/// Absolute readings of one source for a robot of `joints` joints.
pub fn read_absolute(source: &Source, joints: usize) -> Result<Vec<AbsoluteRow>> {
    match source {
        Source::File(path) => {
            let text = read_text(path, limits::MAX_FILE_BYTES)?;
            Ok(parse_absolute(&text, &path.display().to_string(), joints)?)
        }
        Source::Table { text, origin } => parse_absolute(text, origin, joints).map_err(table_error),
    }
}

/// Groups left out in turn (`cv_by`, the CLI's `--cv-by`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CvBy {
    /// Measuring sessions (time stamps more than [`SESSION_GAP_S`] apart; one per set-up
    /// without them).
    Session,
    /// Tracker set-ups.
    Setup,
    /// Data tables (`data`), one series each.
    Series,
}

/// Options of [`calibrate_geometry`] (the CLI's flags).
#[derive(Clone, Debug)]
pub struct GeometryOptions {
    /// Model steps, each adding to the previous.
    pub steps: Vec<Step>,
    /// Robust loss.
    pub loss: Loss,
    /// Cross-validation folds by configuration (0 = none).
    pub folds: usize,
    /// Bootstrap replicates by configuration (0 = none).
    pub bootstrap: usize,
    /// Fraction of the configurations held out, never fitted.
    pub test_fraction: f64,
    /// Seed of the splits and the bootstrap.
    pub seed: u64,
    /// eDoFs whose compliance is fitted (`J2.z`); empty: all of the robot's.
    pub elastic: Vec<String>,
    /// Fit the measured orientations with this σ (rad) for rows without `sigma_rad`.
    pub orientations: Option<f64>,
    /// Groups of the fit data left out in turn.
    pub cv_by: Option<CvBy>,
    /// How held-out groups are registered (readings drawn, draws, target too).
    pub protocol: HeldOutProtocol,
}

/// An elasto-geometric calibration: the fit, its campaign and the calibrated robot.
pub struct GeometryCalibration {
    /// The fit.
    pub result: FitResult,
    /// The readings as fitted (absolute then loaded; test readings after the fitted ones).
    pub campaign: Campaign,
    /// The calibrated robot (DH rows, stiffness, masses, set-ups, targets).
    pub robot: Robot,
    /// The joint terms, residual model and accuracy kept beside the robot file
    /// (`NAME.terms.json`).
    pub terms: CalibrationTerms,
    /// Wall time of the fit (s).
    pub elapsed_s: f64,
}

/// `deflex calibrate-geometry`: absolute readings (`data`, one series per source), loaded
/// displacements (`loaded`, the `deflex calibrate` format) and never-fitted test readings
/// (`test`).
pub fn calibrate_geometry(
    start: &Robot,
    data: &[Source],
    loaded: &[Source],
    test: &[Source],
    options: &GeometryOptions,
) -> Result<GeometryCalibration> {
    if let Some(sigma) = options.orientations {
        crate::error::bounded(
            "sigma_rad",
            sigma,
            1e-9,
            deflex_calibrate::measurements::MAX_SIGMA_RAD,
            "rad",
        )?;
    }
    let n = start.joint_count();
    let mut absolute = Vec::new();
    let mut series_of = Vec::new();
    for (k, source) in data.iter().enumerate() {
        let rows = read_absolute(source, n)?;
        series_of.extend(std::iter::repeat_n(k, rows.len()));
        absolute.extend(rows);
    }
    let fit_count = absolute.len();
    for source in test {
        absolute.extend(read_absolute(source, n)?);
    }
    let mut loaded_rows = Vec::new();
    for source in loaded {
        loaded_rows.extend(crate::calibrate::read_rows(source, n, true)?.rows);
    }
    let mut model = EgModel::from_robot(start);
    let mut campaign = Campaign::new(&mut model, absolute, loaded_rows)?;
    if let Some(sigma) = options.orientations {
        campaign.use_orientations(sigma);
        if campaign.orientation_rows.is_empty() {
            return Err(Error::invalid(
                "orientations",
                "no row of the data has rx_rad, ry_rad, rz_rad",
            ));
        }
    }
    let total = campaign.absolute.len();
    let groups = options.cv_by.map(|by| {
        let mut g: Vec<usize> = match by {
            CvBy::Session => session_groups(&campaign, SESSION_GAP_S),
            CvBy::Setup => campaign.setup_of.clone(),
            CvBy::Series => series_of.clone(),
        };
        // Test rows are never fitted: their group does not matter.
        g.resize(total, usize::MAX);
        g
    });
    let fit_options = FitOptions {
        steps: options.steps.clone(),
        loss: options.loss,
        folds: options.folds,
        bootstrap: options.bootstrap,
        test_fraction: options.test_fraction,
        seed: options.seed,
        elastic_edofs: options.elastic.clone(),
        held_out_readings: (fit_count..total).collect(),
        groups,
        protocol: options.protocol.clone(),
        ..FitOptions::default()
    };
    let started = std::time::Instant::now();
    let result = fit(&model, &campaign, &fit_options)?;
    let elapsed_s = started.elapsed().as_secs_f64();
    let robot = result.model.to_robot();
    let terms = CalibrationTerms::of(&result);
    Ok(GeometryCalibration {
        result,
        campaign,
        robot,
        terms,
        elapsed_s,
    })
}

/// 95 % intervals `estimate ± 1.96 SE` of the identified parameters.
pub fn intervals95(cal: &GeometryCalibration) -> Vec<[f64; 2]> {
    cal.result
        .estimates
        .iter()
        .map(|e| {
            let h = deflex_calibrate::stiffness::stiffness_fit::Z95 * e.standard_error;
            [e.value - h, e.value + h]
        })
        .collect()
}

/// The CLI's text report.
pub fn report_text(cal: &GeometryCalibration) -> String {
    absolute_report::text(&cal.result, &cal.campaign)
}

/// The CLI's JSON report (`--json`), as text.
pub fn report_json(cal: &GeometryCalibration) -> String {
    absolute_report::json(&cal.result, &cal.campaign).to_string()
}

/// The report folder (text, JSON, CSV, plots, HTML), written whole.
pub fn write_report(cal: &GeometryCalibration, dir: &Path) -> Result<Vec<PathBuf>> {
    Ok(absolute_report::write_report(
        &cal.result,
        &cal.campaign,
        dir,
    )?)
}

/// The terms file beside a calibrated robot file: `NAME.toml` → `NAME.terms.json` (as the CLI).
pub fn terms_path(robot_file: &Path) -> PathBuf {
    robot_file.with_extension("terms.json")
}

/// Write the calibrated robot file and its terms file beside it (each whole or not at all).
pub fn save(cal: &GeometryCalibration, path: &Path) -> Result<()> {
    write_model(&cal.robot, Some(&cal.terms), path)
}

fn write_model(robot: &Robot, terms: Option<&CalibrationTerms>, path: &Path) -> Result<()> {
    let io = |p: &Path| {
        let shown = p.display().to_string();
        move |source| Error::Io {
            path: shown,
            source,
        }
    };
    if let Some(terms) = terms {
        let file = terms_path(path);
        deflex_files::write_atomic(&file, terms.to_json()).map_err(io(&file))?;
    }
    deflex_files::write_atomic(path, crate::robot::to_toml(robot, Some(path))).map_err(io(path))
}

/// A calibrated model for prediction and registration: the robot and, when it was read from a
/// file with a `NAME.terms.json` beside it (or comes from a calibration), the joint terms and
/// residual model it keeps.
pub struct CalibratedModel {
    /// The model with its terms applied.
    pub model: EgModel,
    /// The terms, when there are any.
    pub terms: Option<CalibrationTerms>,
}

/// [`CalibratedModel`] of a robot; `file` is the robot file it was loaded from, whose terms
/// file is read when present (as the CLI's `--robot FILE`).
pub fn calibrated_model(robot: &Robot, file: Option<&Path>) -> Result<CalibratedModel> {
    let mut model = EgModel::from_robot(robot);
    let Some(terms_file) = file.map(terms_path).filter(|p| p.is_file()) else {
        return Ok(CalibratedModel { model, terms: None });
    };
    let text = read_text(&terms_file, MAX_TERMS_BYTES)?;
    let in_file = |source| Error::Terms {
        path: terms_file.display().to_string(),
        source,
    };
    let terms = CalibrationTerms::from_json(&text).map_err(in_file)?;
    terms.apply(&mut model).map_err(in_file)?;
    Ok(CalibratedModel {
        model,
        terms: Some(terms),
    })
}

/// [`CalibratedModel`] of a calibration just made (its terms applied).
pub fn calibrated_model_of(cal: &GeometryCalibration) -> Result<CalibratedModel> {
    let mut model = EgModel::from_robot(&cal.robot);
    cal.terms.apply(&mut model).map_err(|source| Error::Terms {
        path: "the calibration's terms".into(),
        source,
    })?;
    Ok(CalibratedModel {
        model,
        terms: Some(cal.terms.clone()),
    })
}

/// A prediction with its renderings (the CLI's CSV, text and JSON).
pub struct Prediction {
    /// The prediction CSV (`deflex predict --out`).
    pub csv: String,
    /// The summary text.
    pub text: String,
    /// The summary JSON (SI).
    pub json: serde_json::Value,
}

/// Per-row predictions of a calibrated robot (`deflex predict`): the prediction CSV (with the
/// error where measured), the summary text and JSON. With `fit_setup`, the registration of
/// the rows' set-ups is fitted on the rows first.
pub fn predict(model: &CalibratedModel, source: &Source, fit_setup: bool) -> Result<Prediction> {
    let rows = read_absolute(source, model.model.robot.joint_count())?;
    let p = deflex_calibrate::geometry::predict::predict_rows(&model.model, rows, fit_setup)?;
    Ok(Prediction {
        csv: absolute_report::prediction::prediction_csv(&p),
        text: absolute_report::prediction::prediction_text(&p),
        json: absolute_report::prediction::prediction_json(&p),
    })
}

/// Options of [`register`] (the CLI's `deflex register` flags, SI).
#[derive(Clone, Debug, Default)]
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
}

/// `deflex register`: a new measuring session's set-up (and a new target's offset) fitted from
/// a few readings with the calibrated robot frozen, with the CLI's checks (the set-up named or
/// the data's only one, every target known or registered, orientations present when asked).
pub fn register(
    calibrated: CalibratedModel,
    source: &Source,
    request: &RegisterRequest,
) -> Result<SessionRegistration> {
    if let Some(sigma) = request.orientations {
        crate::error::bounded(
            "sigma_rad",
            sigma,
            1e-9,
            deflex_calibrate::measurements::MAX_SIGMA_RAD,
            "rad",
        )?;
    }
    if let Some(m) = request.recalibrate_above_m {
        crate::error::bounded("recalibrate_above_m", m, 1e-6, 1.0, "m")?;
    }
    let CalibratedModel { mut model, terms } = calibrated;
    let name = source.name();
    let rows = read_absolute(source, model.robot.joint_count())?;
    let setup_name = match &request.setup {
        Some(s) => s.clone(),
        None => {
            let mut names: Vec<&str> = rows.iter().map(|r| r.setup.as_str()).collect();
            names.sort_unstable();
            names.dedup();
            match names.as_slice() {
                [one] => one.to_string(),
                _ => {
                    return Err(Error::invalid(
                        "setup",
                        format!(
                            "{name}: the data names set-ups {}: choose one with setup=",
                            names.join(", ")
                        ),
                    ));
                }
            }
        }
    };
    let rows: Vec<AbsoluteRow> = rows.into_iter().filter(|r| r.setup == setup_name).collect();
    if rows.is_empty() {
        return Err(Error::invalid(
            "setup",
            format!("{name}: no reading of set-up `{setup_name}`"),
        ));
    }
    for row in &rows {
        let known = model.target_index(&row.target).is_some();
        if !known && request.target.as_deref() != Some(row.target.as_str()) {
            return Err(Error::invalid(
                "target",
                format!(
                    "{name}:{}: target `{}` is not in the robot file: register it with target=\"{}\"",
                    row.line, row.target, row.target
                ),
            ));
        }
    }
    let new_setup = model.setup_index(&setup_name).is_none();
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
                "orientations",
                "no reading has rx_rad, ry_rad, rz_rad",
            ));
        }
    }
    // Campaign::new adds the readings' new set-ups and targets to the model.
    let setup = model
        .setup_index(&setup_name)
        .ok_or_else(|| Error::invalid("setup", format!("set-up `{setup_name}` missing")))?;
    let target = match &request.target {
        Some(t) => Some(model.target_index(t).ok_or_else(|| {
            Error::invalid("target", format!("{name}: no reading of target `{t}`"))
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
    })
}

/// The registration as the CLI prints it.
pub fn registration_text(r: &SessionRegistration) -> String {
    absolute_report::registration::text(&r.registration, &r.setup, r.target.as_deref())
}

/// The registration as the CLI's `--json` (SI); `out` the robot file written, if any.
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

/// Write the updated robot file (and the calibration's terms beside it, as they were).
pub fn save_registration(r: &SessionRegistration, path: &Path) -> Result<()> {
    write_model(&r.robot, r.terms.as_ref(), path)
}

/// `deflex import ur10-tracker`: the absolute CSV text of a series (every `every`-th reading)
/// and the import summary.
pub fn import_ur10_tracker(
    series: &Path,
    setup: &str,
    target: &str,
    tracker_sigma: bool,
    every: usize,
) -> Result<(String, ImportSummary, usize)> {
    if every == 0 || every > 1_000_000 {
        return Err(Error::invalid(
            "every",
            format!("expected 1…1000000, got {every}"),
        ));
    }
    let options = ImportOptions {
        setup: setup.to_string(),
        target: target.to_string(),
        tracker_sigma,
    };
    let file = series_file(series)?;
    let text = read_text(&file, MAX_SERIES_BYTES)?;
    let (rows, mut summary) = parse_series(&text, &file.display().to_string(), &options)?;
    summary.file = file;
    let kept: Vec<AbsoluteRow> = rows.into_iter().step_by(every).collect();
    let comments = vec![
        "UR10 laser-tracker data: Landgraf, Ernst, Schleth, Fabritius, Huber, IEEE CASE 2021 (MIT licence)".to_string(),
        format!(
            "imported by deflex from {} (every {} reading(s); approach_q*_rad from the whole time-ordered series); T-Mac probe in the tracker frame",
            summary.file.display(),
            every
        ),
    ];
    Ok((format_absolute(&kept, &comments), summary, kept.len()))
}

/// The single `measurements_*.csv` of a series folder (or the file itself).
fn series_file(path: &Path) -> Result<PathBuf> {
    if path.is_file() {
        return Ok(path.to_path_buf());
    }
    let io = |source| Error::Read {
        path: path.display().to_string(),
        source,
    };
    let mut found: Vec<PathBuf> = std::fs::read_dir(path)
        .map_err(io)?
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
        n => Err(Error::invalid(
            "series",
            format!(
                "{}: expected one measurements_*.csv, found {n}",
                path.display()
            ),
        )),
    }
}
