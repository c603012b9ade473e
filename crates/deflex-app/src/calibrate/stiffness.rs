//! The stiffness identification (`deflex calibrate`, `deflex.calibrate`): the data read and
//! checked, the structure search or the fixed fit, the couplings, the calibrated model named
//! after its data, and its outputs (the robot file, the report folder).

use super::choice::{CriterionChoice, StructureChoice};
use super::couplings::{self, CouplingRequest};
use super::data::{DataCheck, MeasurementSource, fit_context, named, read_checked};
use crate::OptionNames;
use crate::error::{Error, Result, bounded};
use deflex_calibrate::measurements::MeasurementRow;
use deflex_calibrate::stiffness::CouplingFit;
use deflex_calibrate::stiffness::consistency::GeometryCheck;
use deflex_calibrate::stiffness::search::{Criterion, SearchOptions, SearchStep, search_structure};
use deflex_calibrate::stiffness::stiffness_fit::{Calibration, Structure, calibrate_fixed};
use deflex_model::Robot;
use deflex_telemetry::OnProgress;
use std::io::Write as _;
use std::path::Path;

/// Options of [`calibrate`] (SI; the CLI converts its flags, Python passes its keywords).
#[derive(Clone, Debug)]
pub struct CalibrateOptions {
    /// Search or fixed structure.
    pub structure: StructureChoice,
    /// With a fixed structure: also fit the centre shift of every joint with an x or y eDoF.
    pub fit_shifts: bool,
    /// How the search ranks structures.
    pub criterion: CriterionChoice,
    /// Folds of the cross-validation (by load case; 2 to 100), for the criterion and the
    /// iteration table.
    pub folds: usize,
    /// With the cross-validated criterion: smallest relative decrease of the held-out χ² to
    /// accept a refinement (a fraction, 0 to 0.99999).
    pub min_cv_gain: f64,
    /// Stop once the RMS residual (all components) is at most this (m, 0 to 1).
    pub target_rms_m: Option<f64>,
    /// Smallest BIC decrease to accept a refinement (0 to 1e6).
    pub min_bic_gain: f64,
    /// Consider base tilt eDoFs in the search.
    pub allow_base: bool,
    /// The check of the data against the forward kinematics.
    pub check: DataCheck,
    /// Off-diagonal compliances to fit once the structure is identified (none: a diagonal
    /// model).
    pub couplings: Vec<CouplingRequest>,
}

/// A stiffness calibration and everything needed to print, save and report it.
pub struct StiffnessCalibration {
    /// The start model.
    pub start: Robot,
    /// The calibrated model: the start geometry with the identified eDoFs, centre shifts and
    /// couplings, named after its data ([`calibrated_name`]).
    pub model: Robot,
    /// The fit.
    pub calibration: Calibration,
    /// The calibration as a robot before the couplings (its stiffnesses before their refit).
    pub diagonal: Robot,
    /// The couplings fitted after the structure, if any were asked for.
    pub couplings: Option<CouplingFit>,
    /// The search's steps (empty for a fixed structure).
    pub steps: Vec<SearchStep>,
    /// Why the search stopped.
    pub stop_reason: Option<String>,
    /// The rows fitted.
    pub rows: Vec<MeasurementRow>,
    /// The forward-kinematics check.
    pub check: GeometryCheck,
    /// Warnings of the data's check (a mismatch used anyway, a header naming another robot);
    /// the fit's are the calibration's ([`StiffnessCalibration::warnings`] has both).
    pub data_warnings: Vec<String>,
    /// Header notes of the data.
    pub notes: Vec<String>,
    /// The data, as named.
    pub data_name: String,
    /// Measured − predicted displacement of every row (m), with the calibrated model.
    pub residuals: Vec<[f64; 3]>,
    /// Predicted displacement of every row (m), with the calibrated model.
    pub predicted: Vec<[f64; 3]>,
    /// Wall time of the identification (s).
    pub elapsed_s: f64,
}

impl StiffnessCalibration {
    /// Whether the data's header calls it simulated (`SIMULATED`, a `deflex sim campaign`).
    pub fn simulated_data(&self) -> bool {
        self.notes.iter().any(|n| n.contains("SIMULATED"))
    }

    /// Every warning: the data's check's, then the fit's.
    pub fn warnings(&self) -> Vec<String> {
        let mut all = self.data_warnings.clone();
        all.extend(self.calibration.warnings.iter().cloned());
        all
    }
}

/// The options' numbers in range, named by their Python keywords (the CLI checks its flags, in
/// its units, before).
fn check_options(options: &CalibrateOptions) -> Result<()> {
    if let Some(t) = options.target_rms_m {
        bounded("target_rms_m", t, 0.0, 1.0, "m")?;
    }
    bounded("min_bic_gain", options.min_bic_gain, 0.0, 1e6, "")?;
    if options.criterion == CriterionChoice::Cv {
        bounded("min_cv_gain", options.min_cv_gain, 0.0, 0.99999, "")?;
    }
    if !(2..=100).contains(&options.folds) {
        return Err(Error::invalid(
            "folds",
            format!("expected 2 to 100, got {}", options.folds),
        ));
    }
    Ok(())
}

/// Identify the stiffness model of `start` from the data: the data read and checked against the
/// forward kinematics, the structure searched (reporting to `progress`) or fixed, nothing
/// identified refused, the couplings fitted, the calibrated model named and its prediction of
/// every row. Nothing is written ([`save`] writes).
pub fn calibrate(
    start: &Robot,
    source: &MeasurementSource,
    options: &CalibrateOptions,
    names: OptionNames,
    progress: OnProgress<'_>,
) -> Result<StiffnessCalibration> {
    check_options(options)?;
    let checked = read_checked(start, source, &options.check, names)?;
    let t0 = std::time::Instant::now();
    let (calibration, steps, stop_reason) = named(
        fit_context(source, names).as_deref(),
        identify(start, &checked.rows, options, progress),
    )?;
    let elapsed_s = t0.elapsed().as_secs_f64();
    let data_name = source.name();
    if !calibration.edofs.iter().any(|e| e.stiffness.is_some()) {
        return Err(Error::NothingIdentified { data: data_name });
    }
    let diagonal = calibration.to_robot(start);
    let couplings = if options.couplings.is_empty() {
        None
    } else {
        Some(couplings::fit(
            &diagonal,
            &calibration.structure.label(),
            &checked.rows,
            &options.couplings,
        )?)
    };
    let mut model = couplings
        .as_ref()
        .map_or_else(|| diagonal.clone(), |fit| fit.robot.clone());
    model.name = calibrated_name(&model, &data_name, &calibration.structure.label());
    let predicted = deflex_calibrate::stiffness::validation::predict(&model, &checked.rows)?;
    let residuals = checked
        .rows
        .iter()
        .zip(&predicted)
        .map(|(row, p)| {
            let d = row.displacement_m.unwrap_or([f64::NAN; 3]);
            [d[0] - p[0], d[1] - p[1], d[2] - p[2]]
        })
        .collect();
    Ok(StiffnessCalibration {
        start: start.clone(),
        model,
        calibration,
        diagonal,
        couplings,
        steps,
        stop_reason,
        rows: checked.rows,
        check: checked.check,
        data_warnings: checked.warnings,
        notes: checked.notes,
        data_name,
        residuals,
        predicted,
        elapsed_s,
    })
}

/// The fit `options` ask for: the start model's structure, or the structure search. Returns the
/// calibration, the search's steps and why it stopped.
fn identify(
    start: &Robot,
    rows: &[MeasurementRow],
    options: &CalibrateOptions,
    progress: OnProgress<'_>,
) -> Result<(Calibration, Vec<SearchStep>, Option<String>)> {
    Ok(match options.structure {
        StructureChoice::Fixed => {
            let mut structure = Structure::from_robot(start);
            if options.fit_shifts {
                structure = structure.with_free_shifts();
            }
            (calibrate_fixed(start, rows, &structure)?, Vec::new(), None)
        }
        StructureChoice::Auto => {
            let criterion = match options.criterion {
                CriterionChoice::Cv => Criterion::CrossValidated {
                    folds: options.folds,
                    min_relative_gain: options.min_cv_gain,
                },
                CriterionChoice::Bic => Criterion::Bic,
            };
            let search = SearchOptions {
                criterion,
                report_folds: options.folds,
                target_rms_m: options.target_rms_m,
                min_bic_gain: options.min_bic_gain,
                allow_base: options.allow_base,
                ..SearchOptions::default()
            };
            let result = search_structure(start, rows, &search, progress)?;
            (result.calibration, result.steps, Some(result.stop_reason))
        }
    })
}

/// The calibrated model's name: the start geometry's name (without an earlier `— calibrated …`)
/// and where its elasticity comes from: the data, the structure and the couplings.
pub fn calibrated_name(model: &Robot, data_name: &str, structure: &str) -> String {
    let geometry = model.name.split(" — calibrated").next().unwrap_or("");
    format!(
        "{geometry} — calibrated from {data_name} ({structure}{})",
        model
            .couplings
            .iter()
            .map(|c| format!(", coupling {}", c.label()))
            .collect::<String>()
    )
}

/// What `save` asks for with `report`, in the words of [`Error::ReportsNotBuilt`].
const CALIBRATION_REPORT: &str = "the calibration report (`deflex calibrate --report`; Python: `StiffnessCalibration.save(report=…)`)";

/// Write the calibrated robot file to `out` and, with `report`, the HTML report with plots and
/// CSV tables into that folder: each whole or not at all, the report folder first, then the
/// model (so a model never appears without the report asked for). The report needs the
/// `report` feature: without it a `report` is refused before anything is written.
pub fn save(cal: &StiffnessCalibration, out: &Path, report: Option<&Path>) -> Result<()> {
    let report = match report {
        Some(dir) => Some((dir, crate::report::require(CALIBRATION_REPORT)?)),
        None => None,
    };
    let mut model_file = deflex_files::AtomicFile::create(out).map_err(Error::io_on(out))?;
    model_file
        .write_all(crate::load::robot_to_toml_for(&cal.model, out).as_bytes())
        .map_err(Error::io_on(out))?;
    if let Some((dir, drawing)) = report {
        let folder = deflex_files::AtomicDir::create(dir).map_err(Error::io_on(dir))?;
        drawing.calibration_report(cal, folder.path(), &out.display().to_string())?;
        folder.commit().map_err(Error::io_on(dir))?;
    }
    model_file.commit().map_err(Error::io_on(out))?;
    Ok(())
}
