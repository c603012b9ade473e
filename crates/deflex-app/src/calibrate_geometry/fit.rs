//! `calibrate-geometry`: the options, the fit, its refusals, the files written and the text and
//! JSON shown.

use super::OptionNames;
use super::files::{read_absolute, read_loaded, shown_all, terms_path, write_unit};
use crate::calibrate::{MeasurementSource, UnknownChoice};
use crate::error::{Error, Result};
use crate::report::absolute_report;
use deflex_calibrate::geometry::campaign::Campaign;
use deflex_calibrate::geometry::data::AbsoluteRow;
use deflex_calibrate::geometry::fit::{
    ChoiceError, FitOptions, FitResult, HeldOutProtocol, Role, Step, fit, session_groups,
};
use deflex_calibrate::geometry::params::EgModel;
use deflex_calibrate::geometry::plausible::{ChangeBounds, large_fit_changes};
use deflex_calibrate::geometry::solve::Loss;
use deflex_calibrate::geometry::terms::CalibrationTerms;
use deflex_model::Robot;
use std::path::{Path, PathBuf};

/// Gap between time stamps that starts a new measuring session ([`CvBy::Session`]).
pub const SESSION_GAP_S: f64 = 3600.0;

/// Largest RMS of the fitted readings' residuals a calibration may end with (m). A calibrated
/// arm fits its tracker readings to a fraction of a millimetre; readings of another robot, or
/// of another tool on an unknown target, leave residuals of centimetres to metres.
pub const MAX_PLAUSIBLE_RMS_M: f64 = 0.02;

/// Model steps from their names (`registration`, `geometry`, `compliance`, `masses`,
/// `harmonics:N`, `periodic:N`, `backlash`, `torsion:cubic`, `torsion:soft:T`, `residual`,
/// `joint-maps`); an unknown one is refused naming the option (`--steps`, `steps`).
pub fn parse_steps(items: &[String], names: OptionNames) -> Result<Vec<Step>> {
    items
        .iter()
        .map(|item| item.parse().map_err(choice_error("steps", names)))
        .collect()
}

/// A robust loss from its name (`huber`, `cauchy`, `none`, `huber:K`, `cauchy:K`); an unknown
/// one is refused naming the option (`--loss`, `loss`).
pub fn parse_loss(text: &str, names: OptionNames) -> Result<Loss> {
    text.parse().map_err(choice_error("loss", names))
}

fn choice_error(keyword: &str, names: OptionNames) -> impl FnOnce(ChoiceError) -> Error {
    let option = names.name(keyword);
    move |source| Error::Choice { option, source }
}

/// Groups of `--cv-by`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum CvBy {
    /// Measuring sessions (time stamps more than an hour apart; one per set-up without them).
    Session,
    /// Tracker set-ups.
    Setup,
    /// Data files (`--data`), one series each.
    Series,
}

impl CvBy {
    /// Every choice with its name, as `cv_by=` takes it.
    pub const NAMES: [(CvBy, &'static str); 3] = [
        (CvBy::Session, "session"),
        (CvBy::Setup, "setup"),
        (CvBy::Series, "series"),
    ];

    /// The choice's name (`session`, `setup`, `series`).
    pub fn name(self) -> &'static str {
        Self::NAMES
            .iter()
            .find(|(by, _)| *by == self)
            .map_or("", |(_, name)| name)
    }
}

impl std::str::FromStr for CvBy {
    type Err = UnknownChoice;

    fn from_str(text: &str) -> std::result::Result<CvBy, UnknownChoice> {
        Self::NAMES
            .iter()
            .find(|(_, name)| *name == text)
            .map(|(by, _)| *by)
            .ok_or_else(|| UnknownChoice {
                expected: "\"session\", \"setup\" or \"series\"",
                got: text.to_string(),
            })
    }
}

/// The steps every calibration fits: the set-ups and targets, the geometry, the gravity sag.
pub const BASE_STEPS: [Step; 3] = [Step::Registration, Step::Geometry, Step::Compliance];

/// The steps a calibration fits when none are named, and why: [`BASE_STEPS`], and the joint
/// maps when the data is grouped (`cv_by`) so that the held-out vote by those groups can judge
/// them (they are kept only when they lower the left-out groups' error). Without groups the
/// maps are not tried: their hyper-parameters would be chosen on the test readings; `sessions`
/// and `setups` (how many the fitted readings hold) say which grouping would let them vote,
/// in the front end's words (`names`).
pub fn default_steps(
    cv_by: Option<CvBy>,
    sessions: usize,
    setups: usize,
    names: OptionNames,
) -> (Vec<Step>, String) {
    let mut steps = BASE_STEPS.to_vec();
    let why = match cv_by {
        Some(by) => {
            steps.push(Step::JointMaps);
            format!(
                "default steps: registration, geometry, compliance, and joint-maps (the vote by \
                 {} left out in turn judges them)",
                by.name()
            )
        }
        None => {
            let hint = if sessions >= 2 {
                format!(
                    "; the data has {sessions} sessions: {} lets them vote",
                    names.give_text("cv_by", "session")
                )
            } else if setups >= 2 {
                format!(
                    "; the data has {setups} set-ups: {} lets them vote",
                    names.give_text("cv_by", "setup")
                )
            } else {
                String::new()
            };
            format!(
                "default steps: registration, geometry, compliance; joint-maps not tried (no \
                 groups to vote with: {} session, setup or series{hint})",
                names.name("cv_by")
            )
        }
    };
    (steps, why)
}

/// Options of [`calibrate_geometry`] (the CLI's flags, SI).
#[derive(Clone, Debug)]
pub struct GeometryOptions {
    /// Model steps, each adding to the previous; `None`: [`default_steps`].
    pub steps: Option<Vec<Step>>,
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
    /// Columns of the data files that deflex does not read, kept knowingly.
    pub ignored_columns: Vec<String>,
    /// Write a fit that moves the geometry beyond a calibration's bounds
    /// ([`deflex_calibrate::geometry::plausible`]): for a robot file that is only a rough
    /// first guess. Off: such a fit is refused.
    pub allow_large_changes: bool,
    /// How the messages name the options.
    pub names: OptionNames,
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
    /// Which steps were chosen by default and why, when none were named.
    pub default_steps: Option<String>,
    /// The warning of a fit beyond a calibration's bounds that was written because the front
    /// end allowed it (`--allow-large-changes`), naming the largest changes.
    pub large_changes: Option<String>,
}

/// The readings of a calibration: fitted ones first, then the test ones (never fitted).
struct Readings {
    /// Every absolute reading.
    absolute: Vec<AbsoluteRow>,
    /// Which data source each fitted reading comes from.
    series_of: Vec<usize>,
    /// Loaded displacements.
    loaded: Vec<deflex_calibrate::measurements::MeasurementRow>,
}

fn read_readings(
    start: &Robot,
    data: &[MeasurementSource],
    loaded: &[MeasurementSource],
    test: &[MeasurementSource],
    options: &GeometryOptions,
) -> Result<Readings> {
    let n = start.joint_count();
    let ignored = &options.ignored_columns;
    let series = data
        .iter()
        .map(|source| read_absolute(source, n, ignored))
        .collect::<Result<Vec<_>>>()?;
    let tests = test
        .iter()
        .map(|source| read_absolute(source, n, ignored))
        .collect::<Result<Vec<_>>>()?;
    let mut loaded_rows = Vec::new();
    for source in loaded {
        loaded_rows.extend(read_loaded(start, source, ignored, options.names)?);
    }
    let series_of = series
        .iter()
        .enumerate()
        .flat_map(|(k, rows)| std::iter::repeat_n(k, rows.len()))
        .collect();
    let absolute = series.into_iter().chain(tests).flatten().collect();
    Ok(Readings {
        absolute,
        series_of,
        loaded: loaded_rows,
    })
}

/// `deflex calibrate-geometry`: absolute readings (`data`, one series per source), loaded
/// displacements (`loaded`, the `deflex calibrate` format, checked against the robot) and
/// never-fitted test readings (`test`). Refused, with nothing to write: data with fewer
/// independent equations than parameters, and a fit that leaves the readings centimetres away
/// (another robot's data).
pub fn calibrate_geometry(
    start: &Robot,
    data: &[MeasurementSource],
    loaded: &[MeasurementSource],
    test: &[MeasurementSource],
    options: &GeometryOptions,
) -> Result<GeometryCalibration> {
    if let Some(sigma) = options.orientations {
        crate::error::bounded(
            &options.names.name("sigma_rad"),
            sigma,
            1e-9,
            deflex_calibrate::measurements::MAX_SIGMA_RAD,
            "rad",
        )?;
    }
    let readings = read_readings(start, data, loaded, test, options)?;
    let fit_count = readings.series_of.len();
    let distinct = distinct_readings(&readings.absolute[..fit_count]);
    let mut model = EgModel::from_robot(start);
    let mut campaign = Campaign::new(&mut model, readings.absolute, readings.loaded)?;
    if let Some(sigma) = options.orientations {
        campaign.use_orientations(sigma);
        if campaign.orientation_rows.is_empty() {
            return Err(Error::invalid(
                options.names.name("orientations"),
                "no row of the data has rx_rad, ry_rad, rz_rad",
            ));
        }
    }
    // Test readings go after the fitted ones and are held out by index.
    let total = campaign.absolute.len();
    let groups = options.cv_by.map(|by| {
        let mut g: Vec<usize> = match by {
            CvBy::Session => session_groups(&campaign, SESSION_GAP_S),
            CvBy::Setup => campaign.setup_of.clone(),
            CvBy::Series => readings.series_of.clone(),
        };
        // Test rows are never fitted: their group does not matter.
        g.resize(total, usize::MAX);
        g
    });
    let (steps, default_steps) = match &options.steps {
        Some(steps) => (steps.clone(), None),
        None => {
            let fitted = |groups: &[usize]| {
                let mut seen: Vec<usize> = groups[..fit_count].to_vec();
                seen.sort_unstable();
                seen.dedup();
                seen.len()
            };
            let sessions = fitted(&session_groups(&campaign, SESSION_GAP_S));
            let setups = fitted(&campaign.setup_of);
            let (steps, why) = default_steps(options.cv_by, sessions, setups, options.names);
            (steps, Some(why))
        }
    };
    let fit_options = FitOptions {
        steps: steps.clone(),
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
    // As many independent equations as parameters at least (3 per distinct reading): fewer,
    // and the standard errors and χ² of 0 would claim what the data cannot give.
    if 3 * distinct <= result.estimates.len() {
        return Err(Error::TooFewReadings {
            files: shown_all(data),
            distinct,
            readings: fit_count,
            equations: 3 * distinct,
            parameters: result.estimates.len(),
        });
    }
    check_plausible_fit(&result, &start.name, data, options.names)?;
    let large_changes = large_changes_of(&result, start);
    if let Some(changes) = &large_changes
        && !options.allow_large_changes
    {
        return Err(Error::LargeChanges {
            files: shown_all(data),
            robot: start.name.clone(),
            count: changes.count,
            changes: changes.named.clone(),
            names: options.names,
        });
    }
    let large_changes = large_changes.map(|changes| {
        format!(
            "WARNING: the fit reshapes robot \"{}\" beyond what a calibration changes ({} \
             parameter(s): {}); written because {} was given",
            start.name,
            changes.count,
            changes.named,
            options.names.switch("allow_large_changes")
        )
    });
    let robot = result.model.to_robot();
    let terms = CalibrationTerms::of(&result);
    Ok(GeometryCalibration {
        result,
        campaign,
        robot,
        terms,
        elapsed_s,
        default_steps,
        large_changes,
    })
}

/// Readings that differ in set-up, target, configuration or measured position (bit for bit):
/// a repeated reading is not a new equation.
fn distinct_readings(rows: &[AbsoluteRow]) -> usize {
    let mut keys: Vec<(&str, &str, Vec<u64>)> = rows
        .iter()
        .map(|r| {
            let mut k: Vec<u64> = r.q_rad.iter().map(|v| v.to_bits()).collect();
            k.extend(r.position_m.iter().map(|v| v.to_bits()));
            (r.setup.as_str(), r.target.as_str(), k)
        })
        .collect();
    keys.sort_unstable();
    keys.dedup();
    keys.len()
}

/// Refuse a fit whose readings the calibrated robot still misses by more than
/// [`MAX_PLAUSIBLE_RMS_M`] RMS (data of another robot): nothing is written.
fn check_plausible_fit(
    result: &FitResult,
    robot: &str,
    data: &[MeasurementSource],
    names: OptionNames,
) -> Result<()> {
    let fitted: Vec<f64> = result
        .residuals
        .iter()
        .filter(|r| r.role == Role::Fit)
        .map(|r| r.residual.norm_squared())
        .collect();
    if fitted.is_empty() {
        return Ok(());
    }
    let rms = (fitted.iter().sum::<f64>() / fitted.len() as f64).sqrt();
    if rms.is_finite() && rms <= MAX_PLAUSIBLE_RMS_M {
        return Ok(());
    }
    Err(Error::ImplausibleFit {
        files: shown_all(data),
        robot: robot.to_string(),
        rms_mm: rms * 1e3,
        limit_mm: MAX_PLAUSIBLE_RMS_M * 1e3,
        robot_option: names.give("robot"),
    })
}

/// How many of the largest changes a refusal names.
const CHANGES_NAMED: usize = 8;

/// The parameters a fit moved beyond their bounds ([`deflex_calibrate::geometry::plausible`]).
struct LargeChanges {
    /// How many.
    count: usize,
    /// The largest ones named with their changes and bounds.
    named: String,
}

/// The fit's changes beyond their bounds, the largest [`CHANGES_NAMED`] named; `None` when
/// every change is within its bound.
fn large_changes_of(result: &FitResult, start: &Robot) -> Option<LargeChanges> {
    let bounds = ChangeBounds::for_robot(start);
    let large = large_fit_changes(result, &bounds);
    if large.is_empty() {
        return None;
    }
    let mut changes: Vec<String> = large
        .iter()
        .take(CHANGES_NAMED)
        .map(ToString::to_string)
        .collect();
    if large.len() > CHANGES_NAMED {
        changes.push(format!("and {} more", large.len() - CHANGES_NAMED));
    }
    Some(LargeChanges {
        count: large.len(),
        named: changes.join(", "),
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

/// The text report (iteration table, held-out errors, estimates, warnings).
pub fn report_text(cal: &GeometryCalibration) -> String {
    let text = absolute_report::text(&cal.result, &cal.campaign);
    match preamble(cal) {
        Some(lines) => format!("{lines}\n{text}"),
        None => text,
    }
}

/// The lines before the report: why the steps were chosen by default, and the warning of
/// changes beyond a calibration's bounds that were allowed.
fn preamble(cal: &GeometryCalibration) -> Option<String> {
    let lines: Vec<&str> = [&cal.default_steps, &cal.large_changes]
        .into_iter()
        .filter_map(|line| line.as_deref())
        .collect();
    (!lines.is_empty()).then(|| lines.join("\n"))
}

/// The JSON report (SI), as text.
pub fn report_json(cal: &GeometryCalibration) -> String {
    report_value(cal).to_string()
}

/// The JSON report with `default_steps` (why the steps were chosen, `null` when named).
fn report_value(cal: &GeometryCalibration) -> serde_json::Value {
    let mut value = absolute_report::json(&cal.result, &cal.campaign);
    value["default_steps"] = serde_json::json!(cal.default_steps);
    value["large_changes_allowed"] = serde_json::json!(cal.large_changes);
    value
}

/// What the report folder is, in the words of [`Error::ReportsNotBuilt`].
const GEOMETRY_REPORT: &str = "the elasto-geometric calibration report (`deflex calibrate-geometry --report`; Python: `GeometryCalibration.save(report=…)`)";

/// The report folder (text, JSON, CSV, plots, HTML), written whole or not at all. Needs the
/// `report` feature: refused without it, nothing written.
pub fn write_report(cal: &GeometryCalibration, dir: &Path) -> Result<Vec<PathBuf>> {
    crate::report::require(GEOMETRY_REPORT)?.geometry_report(
        &cal.result,
        &cal.campaign,
        &report_text(cal),
        &report_value(cal),
        dir,
    )
}

/// What [`save`] wrote.
#[derive(Clone, Debug)]
pub struct SavedCalibration {
    /// The calibrated robot file.
    pub robot: PathBuf,
    /// Its terms file (`NAME.terms.json`).
    pub terms: PathBuf,
    /// The report folder, when one was asked for.
    pub report: Option<PathBuf>,
    /// The report's files.
    pub report_files: Vec<PathBuf>,
}

/// Write the calibrated robot file, its terms file beside it and, with `report`, the report
/// folder, as one unit (whole or not at all: a report that fails leaves the earlier robot,
/// terms and report as they were). The report needs the `report` feature: without it a
/// `report` is refused before anything is written.
pub fn save(
    cal: &GeometryCalibration,
    path: &Path,
    report: Option<&Path>,
) -> Result<SavedCalibration> {
    let report_to = match report {
        Some(dir) => Some((dir, crate::report::require(GEOMETRY_REPORT)?)),
        None => None,
    };
    let terms = cal.terms.to_json().map_err(|e| Error::Serialise {
        what: "the terms file",
        reason: e.to_string(),
    })?;
    let report_files = write_unit(&cal.robot, Some(&terms), path, || {
        report_to.map_or(Ok(Vec::new()), |(dir, drawing)| {
            drawing.geometry_report(
                &cal.result,
                &cal.campaign,
                &report_text(cal),
                &report_value(cal),
                dir,
            )
        })
    })?;
    Ok(SavedCalibration {
        robot: path.to_path_buf(),
        terms: terms_path(path),
        report: report.map(Path::to_path_buf),
        report_files,
    })
}

/// The text the CLI prints after a calibration it saved: the report, the fit time and the
/// files written.
pub fn saved_text(cal: &GeometryCalibration, saved: &SavedCalibration) -> String {
    let mut text = report_text(cal);
    text.push_str(&format!(
        "fit time {:.2} s; calibrated robot written to {} (terms: {})\n",
        cal.elapsed_s,
        saved.robot.display(),
        saved.terms.display()
    ));
    if let Some(dir) = &saved.report {
        text.push_str(&format!("report: {}\n", dir.join("index.html").display()));
    }
    text
}

/// The JSON report of a saved calibration (the CLI's `--json`): the report with the fit time
/// (`elapsed_s`) and the files written (`out`, `terms`, `report_files`).
pub fn saved_json(cal: &GeometryCalibration, saved: &SavedCalibration) -> serde_json::Value {
    let mut value = report_value(cal);
    value["elapsed_s"] = serde_json::json!(cal.elapsed_s);
    value["out"] = serde_json::json!(saved.robot.display().to_string());
    value["terms"] = serde_json::json!(saved.terms.display().to_string());
    value["report_files"] = serde_json::json!(
        saved
            .report_files
            .iter()
            .map(|f| f.display().to_string())
            .collect::<Vec<_>>()
    );
    value
}
