//! Elasto-geometric calibration from absolute tracker readings (`deflex calibrate-geometry`),
//! per-row prediction and set-up re-registration (`deflex predict [--fit-setup]`) and the UR10
//! tracker importer (`deflex import ur10-tracker`), with the CLI's checks and messages.
//!
//! Thin layer over `deflex-absolute` (re-pointed at merge time): [`parse_steps`], [`parse_loss`],
//! [`calibrate_geometry`], [`predict`], [`import_ur10_tracker`], [`report_text`],
//! [`report_json`], [`write_report`].

use crate::calibration::{Source, table_row_error};
use crate::error::{Error, Result};
use deflex_absolute::campaign::Campaign;
use deflex_absolute::data::{AbsoluteDataError, AbsoluteRow, format_absolute, parse_absolute};
use deflex_absolute::fit::{FitOptions, FitResult, Step, fit};
use deflex_absolute::params::EgModel;
use deflex_absolute::solve::Loss;
use deflex_absolute::ur10_tracker::{ImportOptions, ImportSummary, import_series};
use deflex_model::Robot;
use std::path::Path;

/// Model steps from their names (`registration`, `geometry`, `compliance`, `masses`,
/// `harmonics:N`), as `--steps` takes them.
pub fn parse_steps(names: &[String]) -> Result<Vec<Step>> {
    names
        .iter()
        .map(|item| match item.trim() {
            "registration" => Ok(Step::Registration),
            "geometry" => Ok(Step::Geometry),
            "compliance" | "gravity" => Ok(Step::Compliance),
            "masses" => Ok(Step::Masses),
            other => match other.strip_prefix("harmonics:").map(str::parse::<u8>) {
                Some(Ok(n)) if (1..=4).contains(&n) => Ok(Step::Harmonics(n)),
                _ => Err(Error::invalid(
                    "steps",
                    format!(
                        "unknown step \"{other}\" (registration, geometry, compliance, masses, harmonics:N with N 1…4)"
                    ),
                )),
            },
        })
        .collect()
}

/// A robust loss from its name (`huber`, `cauchy`, `none`, `huber:K`, `cauchy:K`).
pub fn parse_loss(text: &str) -> Result<Loss> {
    let (name, k) = match text.split_once(':') {
        Some((n, k)) => (
            n,
            Some(
                k.parse::<f64>()
                    .ok()
                    .filter(|k| k.is_finite() && (0.1..=100.0).contains(k))
                    .ok_or_else(|| {
                        Error::invalid(
                            "loss",
                            format!("threshold \"{k}\" must be a number in 0.1…100"),
                        )
                    })?,
            ),
        ),
        None => (text, None),
    };
    match name {
        "huber" => Ok(Loss::Huber(k.unwrap_or(3.0))),
        "cauchy" => Ok(Loss::Cauchy(k.unwrap_or(2.4))),
        "none" | "squared" => Ok(Loss::Squared),
        other => Err(Error::invalid(
            "loss",
            format!("expected huber, cauchy or none, got \"{other}\""),
        )),
    }
}

/// Absolute readings of one source for a robot of `joints` joints.
pub fn read_absolute(source: &Source, joints: usize) -> Result<Vec<AbsoluteRow>> {
    match source {
        Source::File(path) => Ok(deflex_absolute::data::read_absolute(path, joints)?),
        Source::Table { text, origin } => {
            parse_absolute(text, origin, joints).map_err(|e| match e {
                AbsoluteDataError::Row {
                    path,
                    line,
                    column,
                    message,
                } => table_row_error(&path, line, format!("column `{column}`: {message}")),
                other => other.into(),
            })
        }
    }
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
}

/// An elasto-geometric calibration: the fit, its campaign and the calibrated robot.
pub struct GeometryCalibration {
    /// The fit.
    pub result: FitResult,
    /// The readings as fitted (absolute then loaded; test readings after the fitted ones).
    pub campaign: Campaign,
    /// The calibrated robot (DH rows, stiffness, masses, set-ups, targets).
    pub robot: Robot,
    /// Wall time of the fit (s).
    pub elapsed_s: f64,
}

/// `deflex calibrate-geometry`: absolute readings (`data`), loaded displacements (`loaded`,
/// the `deflex calibrate` format) and never-fitted test readings (`test`).
pub fn calibrate_geometry(
    start: &Robot,
    data: &[Source],
    loaded: &[Source],
    test: &[Source],
    options: &GeometryOptions,
) -> Result<GeometryCalibration> {
    let n = start.joint_count();
    let mut absolute = Vec::new();
    for source in data {
        absolute.extend(read_absolute(source, n)?);
    }
    let fit_count = absolute.len();
    for source in test {
        absolute.extend(read_absolute(source, n)?);
    }
    let mut loaded_rows = Vec::new();
    for source in loaded {
        loaded_rows.extend(crate::calibration::read_rows(source, n, true)?.rows);
    }
    let mut model = EgModel::from_robot(start);
    let campaign = Campaign::new(&mut model, absolute, loaded_rows)?;
    let fit_options = FitOptions {
        steps: options.steps.clone(),
        loss: options.loss,
        folds: options.folds,
        bootstrap: options.bootstrap,
        test_fraction: options.test_fraction,
        seed: options.seed,
        elastic_edofs: options.elastic.clone(),
        held_out_readings: (fit_count..campaign.absolute.len()).collect(),
        ..FitOptions::default()
    };
    let started = std::time::Instant::now();
    let result = fit(&model, &campaign, &fit_options)?;
    let elapsed_s = started.elapsed().as_secs_f64();
    let robot = result.model.to_robot();
    Ok(GeometryCalibration {
        result,
        campaign,
        robot,
        elapsed_s,
    })
}

/// 95 % intervals `estimate ± 1.96 SE` of the identified parameters.
pub fn intervals95(cal: &GeometryCalibration) -> Vec<[f64; 2]> {
    cal.result
        .estimates
        .iter()
        .map(|e| {
            let h = deflex_stiffness::fit::Z95 * e.standard_error;
            [e.value - h, e.value + h]
        })
        .collect()
}

/// The CLI's text report.
pub fn report_text(cal: &GeometryCalibration) -> String {
    deflex_absolute::report::text(&cal.result, &cal.campaign)
}

/// The CLI's JSON report (`--json`), as text.
pub fn report_json(cal: &GeometryCalibration) -> String {
    deflex_absolute::report::json(&cal.result, &cal.campaign).to_string()
}

/// The report folder (text, JSON, CSV, plots, HTML), written whole.
pub fn write_report(cal: &GeometryCalibration, dir: &Path) -> Result<Vec<std::path::PathBuf>> {
    Ok(deflex_absolute::report::write_report(
        &cal.result,
        &cal.campaign,
        dir,
    )?)
}

/// Per-row predictions of a calibrated robot (`deflex predict`): the prediction CSV (with the
/// error where measured), the summary text and JSON. With `fit_setup`, the registration of
/// the rows' set-ups is fitted on the rows first (re-registration).
pub fn predict(
    robot: &Robot,
    source: &Source,
    fit_setup: bool,
) -> Result<deflex_absolute::predict::Prediction> {
    let rows = read_absolute(source, robot.joint_count())?;
    Ok(deflex_absolute::predict::predict_rows(robot, rows, fit_setup)?)
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
    let (rows, summary) = import_series(series, &options)?;
    let kept: Vec<AbsoluteRow> = rows.into_iter().step_by(every).collect();
    let comments = vec![
        "UR10 laser-tracker data: Landgraf, Ernst, Schleth, Fabritius, Huber, IEEE CASE 2021 (MIT licence)".to_string(),
        format!(
            "imported by deflex from {} (every {} reading(s)); T-Mac probe in the tracker frame",
            summary.file.display(),
            every
        ),
    ];
    Ok((format_absolute(&kept, &comments), summary, kept.len()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_and_losses_are_parsed_with_the_cli_messages() {
        let steps = parse_steps(&["registration".into(), "harmonics:2".into()]).unwrap();
        assert_eq!(steps, vec![Step::Registration, Step::Harmonics(2)]);
        let e = parse_steps(&["harmonics:9".into()]).unwrap_err();
        assert!(e.to_string().starts_with("steps: unknown step"), "{e}");
        assert!(matches!(parse_loss("cauchy:2").unwrap(), Loss::Cauchy(k) if k == 2.0));
        let e = parse_loss("l1").unwrap_err();
        assert_eq!(
            e.to_string(),
            "loss: expected huber, cauchy or none, got \"l1\""
        );
    }
}
