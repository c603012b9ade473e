//! Calibration results and entry points: stiffness identification, validation, elasto-geometric
//! calibration, prediction and re-registration, the UR10 tracker importer.

use super::convert::{json_to_py, make_log, rows_to_numpy, run, to_numpy, to_py, type_error};
use super::robot::{PyRobot, robot_arg};
use crate::calibration::{self, CalibrateOptions, Criterion, Source, StructureChoice};
use crate::error::Error;
use crate::geometry::{self, GeometryOptions};
use pyo3::prelude::*;
use pyo3::types::PyTuple;
use serde_json::json;
use std::path::PathBuf;

/// A data source from the Python layer: `("file", path)` or `("table", csv_text, origin)`.
pub fn source_arg(py: Python<'_>, obj: &Bound<'_, PyAny>) -> PyResult<Source> {
    let bad = || type_error(py, "data", "a file path or a table", obj);
    let tuple = obj.cast::<PyTuple>().map_err(|_| bad())?;
    let kind: String = tuple.get_item(0)?.extract().map_err(|_| bad())?;
    match (kind.as_str(), tuple.len()) {
        ("file", 2) => Ok(Source::File(tuple.get_item(1)?.extract::<PathBuf>()?)),
        ("table", 3) => Ok(Source::Table {
            text: tuple.get_item(1)?.extract()?,
            origin: tuple.get_item(2)?.extract()?,
        }),
        _ => Err(bad()),
    }
}

fn sources(py: Python<'_>, list: &[Bound<'_, PyAny>]) -> PyResult<Vec<Source>> {
    list.iter().map(|o| source_arg(py, o)).collect()
}

/// The result of a stiffness identification (``deflex.calibrate``): the estimates with their
/// standard errors and 95 % intervals, the residuals, the search's iteration table and the
/// calibrated robot.
#[pyclass(module = "deflex", frozen, name = "StiffnessCalibration")]
pub struct PyStiffnessCalibration {
    inner: calibration::StiffnessCalibration,
}

#[pymethods]
impl PyStiffnessCalibration {
    /// The calibrated robot (the start geometry with the identified eDoFs and centre shifts).
    #[getter]
    fn robot(&self) -> PyRobot {
        PyRobot::new(self.inner.model.clone())
    }

    /// The identified structure (``base.xy J1.xyz … δr3 …``).
    #[getter]
    fn structure(&self) -> String {
        self.inner.calibration.structure.label()
    }

    /// eDoF labels of the estimates.
    #[getter]
    fn edofs(&self) -> Vec<String> {
        self.inner
            .calibration
            .edofs
            .iter()
            .map(|e| e.label.clone())
            .collect()
    }

    /// Per eDoF: ``identified``, ``weak`` (the 95 % interval reaches k = ∞) or
    /// ``not_identifiable``.
    #[getter]
    fn status(&self) -> Vec<&'static str> {
        self.inner
            .calibration
            .edofs
            .iter()
            .map(|e| calibration::status_name(&e.status))
            .collect()
    }

    /// Stiffness estimates k (N·m/rad), NaN where not identifiable.
    #[getter]
    fn stiffness<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let v: Vec<f64> = self
            .inner
            .calibration
            .edofs
            .iter()
            .map(|e| e.stiffness.unwrap_or(f64::NAN))
            .collect();
        let n = v.len();
        to_numpy(py, v, &[n])
    }

    /// Standard errors of k (N·m/rad, delta method), NaN where unavailable.
    #[getter]
    fn stiffness_se<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let v: Vec<f64> = self
            .inner
            .calibration
            .edofs
            .iter()
            .map(|e| e.stiffness_se.unwrap_or(f64::NAN))
            .collect();
        let n = v.len();
        to_numpy(py, v, &[n])
    }

    /// 95 % intervals of k, shape ``(k, 2)`` (N·m/rad; the upper bound may be ``inf``), NaN
    /// where unavailable.
    #[getter]
    fn interval95<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let rows: Vec<[f64; 2]> = self
            .inner
            .calibration
            .edofs
            .iter()
            .map(|e| e.interval95.map_or([f64::NAN; 2], |(a, b)| [a, b]))
            .collect();
        rows_to_numpy(py, &rows)
    }

    /// Compliance estimates c = 1/k (rad/(N·m)).
    #[getter]
    fn compliance<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let v: Vec<f64> = self
            .inner
            .calibration
            .edofs
            .iter()
            .map(|e| e.compliance)
            .collect();
        let n = v.len();
        to_numpy(py, v, &[n])
    }

    /// Standard errors of the compliances (rad/(N·m)).
    #[getter]
    fn compliance_se<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let v: Vec<f64> = self
            .inner
            .calibration
            .edofs
            .iter()
            .map(|e| e.compliance_se)
            .collect();
        let n = v.len();
        to_numpy(py, v, &[n])
    }

    /// Measured − predicted displacement of every row with the calibrated model, ``(N, 3)`` (m).
    #[getter]
    fn residuals<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        rows_to_numpy(py, &self.inner.residuals)
    }

    /// Predicted displacement of every row, ``(N, 3)`` (m).
    #[getter]
    fn predicted<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        rows_to_numpy(py, &self.inner.predicted)
    }

    /// Parameter correlation matrix (order of ``parameter_labels``).
    #[getter]
    fn correlation<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let c = &self.inner.calibration.correlation;
        let (r, k) = (c.nrows(), c.ncols());
        let v: Vec<f64> = (0..r)
            .flat_map(|i| (0..k).map(move |j| c[(i, j)]))
            .collect();
        to_numpy(py, v, &[r, k])
    }

    /// The fit as a dict (the CLI's ``--json``: estimates, shifts, χ²/dof, BIC, residual
    /// statistics, iterations, file check, warnings).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        json_to_py(py, &calibration::summary_json(&self.inner).to_string())
    }

    /// The CLI's text report (iteration table, estimates, residuals, correlation, file check).
    fn report(&self) -> String {
        calibration::report_text(&self.inner)
    }

    fn __str__(&self) -> String {
        calibration::report_text(&self.inner)
    }

    fn __repr__(&self) -> String {
        format!(
            "StiffnessCalibration({}, {} rows, reduced χ² {:.2})",
            self.inner.calibration.structure.label(),
            self.inner.calibration.rows,
            self.inner.calibration.reduced_chi2
        )
    }

    /// Write the calibrated robot file to ``path`` (whole or not at all), and with ``report``
    /// the HTML report with plots and CSV tables into that folder first (as ``deflex
    /// calibrate --out … --report …``).
    #[pyo3(signature = (path, report = None))]
    fn save(&self, py: Python<'_>, path: PathBuf, report: Option<PathBuf>) -> PyResult<()> {
        let inner = &self.inner;
        run(py, || {
            if let Some(dir) = &report {
                calibration::write_report(inner, dir, &path.display().to_string())?;
            }
            crate::model::save(&inner.model, &path)
        })
    }
}

/// ``deflex.calibrate``'s engine call (see the Python wrapper for the documentation).
#[pyfunction]
#[pyo3(signature = (robot, data, structure, fit_shifts, criterion, folds, min_cv_gain, target_rms_m, min_bic_gain, allow_base, fk_tolerance_m, ignore_fk_check))]
#[allow(clippy::too_many_arguments)]
pub fn _calibrate(
    py: Python<'_>,
    robot: &Bound<'_, PyAny>,
    data: &Bound<'_, PyAny>,
    structure: &str,
    fit_shifts: bool,
    criterion: &str,
    folds: usize,
    min_cv_gain: f64,
    target_rms_m: Option<f64>,
    min_bic_gain: f64,
    allow_base: bool,
    fk_tolerance_m: f64,
    ignore_fk_check: bool,
) -> PyResult<PyStiffnessCalibration> {
    let start = robot_arg(py, robot, "robot")?;
    let source = source_arg(py, data)?;
    let structure = match structure {
        "auto" => StructureChoice::Auto,
        "fixed" => StructureChoice::Fixed { fit_shifts },
        other => {
            return Err(to_py(
                py,
                Error::invalid(
                    "structure",
                    format!("expected \"auto\" or \"fixed\", got \"{other}\""),
                ),
            ));
        }
    };
    let criterion = match criterion {
        "bic" => Criterion::Bic,
        "cv" => Criterion::CrossValidated {
            folds,
            min_relative_gain: min_cv_gain,
        },
        other => {
            return Err(to_py(
                py,
                Error::invalid(
                    "criterion",
                    format!("expected \"bic\" or \"cv\", got \"{other}\""),
                ),
            ));
        }
    };
    let options = CalibrateOptions {
        structure,
        criterion,
        folds,
        target_rms_m,
        min_bic_gain,
        allow_base,
        fk_tolerance_m,
        ignore_fk_check,
    };
    let inner = run(py, || calibration::calibrate(&start, &source, &options))?;
    Ok(PyStiffnessCalibration { inner })
}

/// Prediction errors of a model (and a baseline) on measured rows (``deflex.validate``).
#[pyclass(module = "deflex", frozen, name = "Validation")]
pub struct PyValidation {
    inner: calibration::Validation,
}

#[pymethods]
impl PyValidation {
    /// Measured displacements, ``(N, 3)`` (m).
    #[getter]
    fn measured<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        rows_to_numpy(py, &self.inner.validation.measured)
    }

    /// The model's predictions, ``(N, 3)`` (m).
    #[getter]
    fn predicted<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        rows_to_numpy(py, &self.inner.validation.model.predicted)
    }

    /// Measured − predicted with the model, ``(N, 3)`` (m).
    #[getter]
    fn errors<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        rows_to_numpy(py, &self.inner.validation.model.errors)
    }

    /// Measured − predicted with the baseline, ``(N, 3)`` (m), or ``None``.
    #[getter]
    fn baseline_errors<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        self.inner
            .validation
            .baseline
            .as_ref()
            .map(|b| rows_to_numpy(py, &b.errors))
            .transpose()
    }

    /// Error statistics as a dict (the CLI's ``--json``).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        json_to_py(py, &calibration::validation_json(&self.inner).to_string())
    }

    /// The validation's plots and HTML page (``validation.html``) into the folder ``dir``,
    /// replaced whole; returns the files written.
    fn save(&self, py: Python<'_>, dir: PathBuf) -> PyResult<Vec<PathBuf>> {
        let inner = &self.inner;
        run(py, || calibration::write_validation_report(inner, &dir))
    }
}

/// ``deflex.validate``'s engine call.
#[pyfunction]
pub fn _validate(
    py: Python<'_>,
    robot: &Bound<'_, PyAny>,
    data: &Bound<'_, PyAny>,
    baseline: Option<&Bound<'_, PyAny>>,
    fk_tolerance_m: f64,
    ignore_fk_check: bool,
) -> PyResult<PyValidation> {
    let model = robot_arg(py, robot, "robot")?;
    let baseline = baseline.map(|b| robot_arg(py, b, "baseline")).transpose()?;
    let source = source_arg(py, data)?;
    let inner = run(py, || {
        calibration::validate(
            &model,
            baseline.as_ref(),
            &source,
            fk_tolerance_m,
            ignore_fk_check,
        )
    })?;
    Ok(PyValidation { inner })
}

/// ``deflex.predict_displacements``'s engine call: ``(N, 6)`` predicted ``[δp; δφ]``.
#[pyfunction]
pub fn _predict_displacements<'py>(
    py: Python<'py>,
    robot: &Bound<'py, PyAny>,
    data: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyAny>> {
    let model = robot_arg(py, robot, "robot")?;
    let source = source_arg(py, data)?;
    let rows = run(py, || calibration::predict_displacements(&model, &source))?;
    rows_to_numpy(py, &rows)
}

/// The result of an elasto-geometric calibration (``deflex.calibrate_geometry``): the iteration
/// table with fit, cross-validated and held-out errors, the identified parameters with their
/// standard errors, the residual of every reading and the calibrated robot.
#[pyclass(module = "deflex", frozen, name = "GeometryCalibration")]
pub struct PyGeometryCalibration {
    inner: geometry::GeometryCalibration,
}

#[pymethods]
impl PyGeometryCalibration {
    /// The calibrated robot (DH rows, stiffness, masses, ``[[setup]]`` and ``[[target]]``).
    #[getter]
    fn robot(&self) -> PyRobot {
        PyRobot::new(self.inner.robot.clone())
    }

    /// Names of the identified parameters (final step).
    #[getter]
    fn parameters(&self) -> Vec<String> {
        self.inner
            .result
            .estimates
            .iter()
            .map(|e| e.name.clone())
            .collect()
    }

    /// SI unit of each parameter (``m``, ``rad``, ``rad/(N·m)``, ``kg``, ``kg·m``).
    #[getter]
    fn units(&self) -> Vec<&'static str> {
        self.inner
            .result
            .estimates
            .iter()
            .map(|e| e.unit.si())
            .collect()
    }

    /// Nominal (starting) values.
    #[getter]
    fn nominal<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let v: Vec<f64> = self
            .inner
            .result
            .estimates
            .iter()
            .map(|e| e.start)
            .collect();
        let n = v.len();
        to_numpy(py, v, &[n])
    }

    /// Estimates.
    #[getter]
    fn estimates<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let v: Vec<f64> = self
            .inner
            .result
            .estimates
            .iter()
            .map(|e| e.value)
            .collect();
        let n = v.len();
        to_numpy(py, v, &[n])
    }

    /// Standard errors, scaled by the residual (√(χ²/dof) × formal).
    #[getter]
    fn standard_errors<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let v: Vec<f64> = self
            .inner
            .result
            .estimates
            .iter()
            .map(|e| e.standard_error)
            .collect();
        let n = v.len();
        to_numpy(py, v, &[n])
    }

    /// 95 % intervals ``estimate ± 1.96 SE``, shape ``(p, 2)``.
    #[getter]
    fn intervals95<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        rows_to_numpy(py, &geometry::intervals95(&self.inner))
    }

    /// Bootstrap standard errors (NaN without ``bootstrap``).
    #[getter]
    fn bootstrap_se<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let v: Vec<f64> = self
            .inner
            .result
            .estimates
            .iter()
            .map(|e| e.bootstrap_se.unwrap_or(f64::NAN))
            .collect();
        let n = v.len();
        to_numpy(py, v, &[n])
    }

    /// Covariance of the estimates (scaled by the residual), ``(p, p)``.
    #[getter]
    fn covariance<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let c = &self.inner.result.covariance;
        let (r, k) = (c.nrows(), c.ncols());
        let v: Vec<f64> = (0..r)
            .flat_map(|i| (0..k).map(move |j| c[(i, j)]))
            .collect();
        to_numpy(py, v, &[r, k])
    }

    /// Measured − predicted of every reading with the final model, ``(N, 3)`` (m; tracker frame
    /// for absolute readings, then the loaded readings).
    #[getter]
    fn residuals<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let rows: Vec<[f64; 3]> = self
            .inner
            .result
            .residuals
            .iter()
            .map(|r| [r.residual.x, r.residual.y, r.residual.z])
            .collect();
        rows_to_numpy(py, &rows)
    }

    /// Role of every reading in ``residuals``: ``fit``, ``test`` or ``registration``.
    #[getter]
    fn roles(&self) -> Vec<&'static str> {
        self.inner.result.residuals.iter().map(|r| r.role).collect()
    }

    /// χ²/dof of the final fit with the stated σ.
    #[getter]
    fn chi2_per_dof(&self) -> f64 {
        self.inner.result.chi2_per_dof
    }

    /// Wall time of the fit (s).
    #[getter]
    fn elapsed_s(&self) -> f64 {
        self.inner.elapsed_s
    }

    /// The CLI's ``--json`` report as a dict: ``steps`` (each with ``fit``, ``cv_rms_m`` and
    /// ``held_out`` groups), ``estimates``, ``not_identifiable``, ``outliers``, χ²/dof….
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        json_to_py(py, &geometry::report_json(&self.inner))
    }

    /// The CLI's text report.
    fn report(&self) -> String {
        geometry::report_text(&self.inner)
    }

    fn __str__(&self) -> String {
        geometry::report_text(&self.inner)
    }

    /// Write the calibrated robot file to ``path``, and with ``report`` the report folder (text,
    /// JSON, CSV, plots, HTML), each whole.
    #[pyo3(signature = (path, report = None))]
    fn save(&self, py: Python<'_>, path: PathBuf, report: Option<PathBuf>) -> PyResult<()> {
        let inner = &self.inner;
        run(py, || {
            crate::model::save(&inner.robot, &path)?;
            if let Some(dir) = &report {
                geometry::write_report(inner, dir)?;
            }
            Ok(())
        })
    }
}

/// ``deflex.calibrate_geometry``'s engine call.
#[pyfunction]
#[pyo3(signature = (robot, data, loaded, test_data, steps, elastic, loss, folds, bootstrap, test_fraction, seed))]
#[allow(clippy::too_many_arguments)]
pub fn _calibrate_geometry(
    py: Python<'_>,
    robot: &Bound<'_, PyAny>,
    data: Vec<Bound<'_, PyAny>>,
    loaded: Vec<Bound<'_, PyAny>>,
    test_data: Vec<Bound<'_, PyAny>>,
    steps: Vec<String>,
    elastic: Vec<String>,
    loss: &str,
    folds: usize,
    bootstrap: usize,
    test_fraction: f64,
    seed: u64,
) -> PyResult<PyGeometryCalibration> {
    let start = robot_arg(py, robot, "robot")?;
    let data = sources(py, &data)?;
    let loaded = sources(py, &loaded)?;
    let test = sources(py, &test_data)?;
    let options = GeometryOptions {
        steps: geometry::parse_steps(&steps).map_err(|e| to_py(py, e))?,
        loss: geometry::parse_loss(loss).map_err(|e| to_py(py, e))?,
        folds,
        bootstrap,
        test_fraction,
        seed,
        elastic,
    };
    let inner = run(py, || {
        geometry::calibrate_geometry(&start, &data, &loaded, &test, &options)
    })?;
    Ok(PyGeometryCalibration { inner })
}

/// Per-row predictions of a calibrated robot (``deflex.predict``).
#[pyclass(module = "deflex", frozen, name = "Prediction")]
pub struct PyPrediction {
    csv: String,
    text: String,
    json: String,
}

#[pymethods]
impl PyPrediction {
    /// The predictions as a ``deflex.Log`` of columns: ``line``, ``setup``, ``target``,
    /// ``q1_rad…``, ``predicted_x_m…``, ``x_m…`` and ``error_m`` (NaN where not measured).
    #[getter]
    fn table<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let csv = self.csv.clone();
        let table = run(py, move || crate::table::parse(&csv, "prediction"))?;
        make_log(py, table)
    }

    /// Summary: error statistics and the registered set-ups (``xyz_m``, ``rpy_rad``).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        json_to_py(py, &self.json)
    }

    /// The CLI's summary line.
    fn report(&self) -> String {
        self.text.clone()
    }

    /// Write the prediction CSV (``deflex predict --out``), whole.
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let csv = &self.csv;
        run(py, || crate::table::write_text(&path, csv))
    }
}

/// ``deflex.predict``'s engine call.
#[pyfunction]
pub fn _predict(
    py: Python<'_>,
    robot: &Bound<'_, PyAny>,
    data: &Bound<'_, PyAny>,
    fit_setup: bool,
) -> PyResult<PyPrediction> {
    let model = robot_arg(py, robot, "robot")?;
    let source = source_arg(py, data)?;
    let p = run(py, || geometry::predict(&model, &source, fit_setup))?;
    Ok(PyPrediction {
        csv: p.csv,
        text: p.text,
        json: p.json.to_string(),
    })
}

/// ``deflex.import_ur10_tracker``'s engine call: the absolute CSV text and a summary dict.
#[pyfunction]
pub fn _import_ur10_tracker<'py>(
    py: Python<'py>,
    series: PathBuf,
    setup: String,
    target: String,
    tracker_sigma: bool,
    every: usize,
) -> PyResult<(String, Bound<'py, PyAny>)> {
    let (text, summary, kept) = run(py, || {
        geometry::import_ur10_tracker(&series, &setup, &target, tracker_sigma, every)
    })?;
    let value = json!({
        "file": summary.file.display().to_string(),
        "rows_read": summary.rows,
        "rows_written": kept,
        "rows_without_time": summary.rows_without_time,
        "median_tracker_std_m": summary.median_tracker_std_m,
        "temperature_range_C": summary.temperature_range_c,
    });
    Ok((text, json_to_py(py, &value.to_string())?))
}
