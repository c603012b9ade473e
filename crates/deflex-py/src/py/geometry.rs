//! Elasto-geometric calibration, prediction and re-registration, the UR10 tracker importer:
//! results and entry points.

use super::calib::{source_arg, sources};
use super::convert::{json_to_py, make_log, rows_to_numpy, run, to_numpy, to_py};
use super::robot::{PyRobot, robot_arg};
use deflex_app::calibrate_geometry::{
    self, CalibratedModel, CvBy, GeometryOptions, HeldOutProtocol, ImportRequest, OptionNames,
    RegisterRequest,
};
use pyo3::prelude::*;
use std::path::PathBuf;

/// The result of an elasto-geometric calibration (``deflex.calibrate_geometry``): the iteration
/// table with fit, cross-validated and held-out errors, the identified parameters with their
/// standard errors, the residual of every reading and the calibrated robot.
#[pyclass(module = "deflex", frozen, name = "GeometryCalibration")]
pub struct PyGeometryCalibration {
    inner: calibrate_geometry::GeometryCalibration,
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
        rows_to_numpy(py, &calibrate_geometry::intervals95(&self.inner))
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
        self.inner
            .result
            .residuals
            .iter()
            .map(|r| r.role.name())
            .collect()
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
        json_to_py(py, &calibrate_geometry::report_json(&self.inner))
    }

    /// The CLI's text report.
    fn report(&self) -> String {
        calibrate_geometry::report_text(&self.inner)
    }

    fn __str__(&self) -> String {
        calibrate_geometry::report_text(&self.inner)
    }

    /// Write the calibrated robot file to ``path`` with its terms beside it
    /// (``NAME.terms.json``: joint terms, residual model, the held-out accuracy that
    /// ``deflex.register`` compares against), and with ``report`` the report folder (text,
    /// JSON, CSV, plots, HTML), as one unit: whole or not at all.
    #[pyo3(signature = (path, report = None))]
    fn save(&self, py: Python<'_>, path: PathBuf, report: Option<PathBuf>) -> PyResult<()> {
        let inner = &self.inner;
        run(py, || {
            calibrate_geometry::save(inner, &path, report.as_deref()).map(|_| ())
        })
    }
}

/// ``deflex.calibrate_geometry``'s engine call.
#[pyfunction]
#[pyo3(signature = (robot, data, loaded, test_data, steps, elastic, loss, folds, bootstrap, test_fraction, seed, orientations, sigma_rad, cv_by, register_readings, register_draws, register_target, allow_large_changes))]
#[allow(clippy::too_many_arguments)]
pub fn _calibrate_geometry(
    py: Python<'_>,
    robot: &Bound<'_, PyAny>,
    data: Vec<Bound<'_, PyAny>>,
    loaded: Vec<Bound<'_, PyAny>>,
    test_data: Vec<Bound<'_, PyAny>>,
    steps: Option<Vec<String>>,
    elastic: Vec<String>,
    loss: &str,
    folds: usize,
    bootstrap: usize,
    test_fraction: f64,
    seed: u64,
    orientations: bool,
    sigma_rad: f64,
    cv_by: Option<String>,
    register_readings: usize,
    register_draws: usize,
    register_target: bool,
    allow_large_changes: bool,
) -> PyResult<PyGeometryCalibration> {
    let cv_by = cv_by
        .map(|name| name.parse::<CvBy>())
        .transpose()
        .map_err(|e| to_py(py, deflex_app::Error::invalid("cv_by", e.to_string())))?;
    let start = robot_arg(py, robot, "robot")?;
    let data = sources(py, &data)?;
    let loaded = sources(py, &loaded)?;
    let test = sources(py, &test_data)?;
    let options = GeometryOptions {
        steps: steps
            .map(|names| calibrate_geometry::parse_steps(&names, OptionNames::Python))
            .transpose()
            .map_err(|e| to_py(py, e))?,
        loss: calibrate_geometry::parse_loss(loss, OptionNames::Python)
            .map_err(|e| to_py(py, e))?,
        folds,
        bootstrap,
        test_fraction,
        seed,
        elastic,
        orientations: orientations.then_some(sigma_rad),
        cv_by,
        protocol: HeldOutProtocol {
            register_readings,
            draws: register_draws,
            register_target,
        },
        ignored_columns: Vec::new(),
        allow_large_changes,
        names: OptionNames::Python,
    };
    let inner = run(py, || {
        calibrate_geometry::calibrate_geometry(&start, &data, &loaded, &test, &options)
    })?;
    Ok(PyGeometryCalibration { inner })
}

/// Per-row predictions of a calibrated robot (``deflex.predict``).
#[pyclass(module = "deflex", frozen, name = "Prediction")]
pub struct PyPrediction {
    inner: calibrate_geometry::PredictionRun,
}

#[pymethods]
impl PyPrediction {
    /// The predictions as a ``deflex.Log`` of columns: ``line``, ``setup``, ``target``,
    /// ``q1_rad…``, ``predicted_x_m…``, ``x_m…`` and ``error_m`` (NaN where not measured).
    #[getter]
    fn table<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let csv = self.inner.csv.clone();
        let table = run(py, move || deflex_app::table::parse(&csv, "prediction"))?;
        make_log(py, table)
    }

    /// Summary: error statistics and the registered set-ups (``xyz_m``, ``rpy_rad``).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        json_to_py(py, &self.inner.json.to_string())
    }

    /// The CLI's summary line.
    fn report(&self) -> String {
        self.inner.text.clone()
    }

    /// Write the prediction CSV (``deflex predict --out``), whole.
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let inner = &self.inner;
        run(py, || inner.save(&path))
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
    let model = calibrated_arg(py, robot)?;
    let source = source_arg(py, data)?;
    let inner = run(py, || {
        calibrate_geometry::predict(&model, &source, fit_setup, &[])
    })?;
    Ok(PyPrediction { inner })
}

/// A calibrated model from a ``GeometryCalibration`` (with its terms), a robot file path (with
/// the ``NAME.terms.json`` beside it when there is one, as the CLI's ``--robot FILE``) or a
/// ``Robot`` (no terms).
fn calibrated_arg(py: Python<'_>, obj: &Bound<'_, PyAny>) -> PyResult<CalibratedModel> {
    if let Ok(cal) = obj.cast::<PyGeometryCalibration>() {
        let inner = &cal.get().inner;
        return run(py, || calibrate_geometry::calibrated_model_of(inner));
    }
    let robot = robot_arg(py, obj, "robot")?;
    let file = if obj.cast::<PyRobot>().is_ok() {
        None
    } else {
        obj.extract::<PathBuf>().ok()
    };
    run(py, move || {
        calibrate_geometry::calibrated_model(&robot, file.as_deref())
    })
}

/// A new session's set-up (and a new target's offset) registered from a few readings with the
/// calibrated robot frozen (``deflex.register``).
#[pyclass(module = "deflex", frozen, name = "Registration")]
pub struct PyRegistration {
    inner: calibrate_geometry::SessionRegistration,
}

#[pymethods]
impl PyRegistration {
    /// The updated robot: the new set-up (and target) added, everything else as it was.
    #[getter]
    fn robot(&self) -> PyRobot {
        PyRobot::new(self.inner.robot.clone())
    }

    /// The set-up registered.
    #[getter]
    fn setup(&self) -> String {
        self.inner.setup.clone()
    }

    /// The target registered too, if any.
    #[getter]
    fn target(&self) -> Option<String> {
        self.inner.target.clone()
    }

    /// Readings used.
    #[getter]
    fn readings(&self) -> usize {
        self.inner.registration.readings
    }

    /// Names of the registered parameters (set-up first, then target).
    #[getter]
    fn parameters(&self) -> Vec<String> {
        self.inner
            .registration
            .params
            .iter()
            .map(|p| p.name.clone())
            .collect()
    }

    /// Registered values (SI: m, rad).
    #[getter]
    fn estimates<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let v: Vec<f64> = self
            .inner
            .registration
            .params
            .iter()
            .map(|p| p.value)
            .collect();
        let n = v.len();
        to_numpy(py, v, &[n])
    }

    /// Their standard errors (SI).
    #[getter]
    fn standard_errors<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let v: Vec<f64> = self
            .inner
            .registration
            .params
            .iter()
            .map(|p| p.standard_error)
            .collect();
        let n = v.len();
        to_numpy(py, v, &[n])
    }

    /// Position residual RMS of the readings (m).
    #[getter]
    fn rms_m(&self) -> f64 {
        self.inner.registration.position.rms
    }

    /// χ²/dof with the stated σ.
    #[getter]
    fn chi2_per_dof(&self) -> f64 {
        self.inner.registration.chi2_per_dof
    }

    /// What deserves a second look (too few readings, a small spread, a residual above the
    /// calibration's accuracy: the robot itself has changed).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.inner
            .registration
            .warnings
            .iter()
            .map(|w| w.to_string())
            .collect()
    }

    /// The CLI's ``--json`` output as a dict (SI; ``out`` is None).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        json_to_py(
            py,
            &calibrate_geometry::registration_json(&self.inner, None).to_string(),
        )
    }

    /// The CLI's text output.
    fn report(&self) -> String {
        calibrate_geometry::registration_text(&self.inner)
    }

    fn __str__(&self) -> String {
        calibrate_geometry::registration_text(&self.inner)
    }

    /// Write the updated robot file (with the calibration's terms beside it, unchanged), whole.
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let inner = &self.inner;
        run(py, || calibrate_geometry::save_registration(inner, &path))
    }
}

/// ``deflex.register``'s engine call.
#[pyfunction]
#[pyo3(signature = (robot, data, setup, target, orientations, sigma_rad, recalibrate_above_m, allow_large_changes))]
#[allow(clippy::too_many_arguments)]
pub fn _register(
    py: Python<'_>,
    robot: &Bound<'_, PyAny>,
    data: &Bound<'_, PyAny>,
    setup: Option<String>,
    target: Option<String>,
    orientations: bool,
    sigma_rad: f64,
    recalibrate_above_m: Option<f64>,
    allow_large_changes: bool,
) -> PyResult<PyRegistration> {
    let model = calibrated_arg(py, robot)?;
    let source = source_arg(py, data)?;
    let request = RegisterRequest {
        setup,
        target,
        orientations: orientations.then_some(sigma_rad),
        recalibrate_above_m,
        ignored_columns: Vec::new(),
        allow_large_changes,
        names: OptionNames::Python,
    };
    let inner = run(py, move || {
        calibrate_geometry::register(model, &source, &request)
    })?;
    Ok(PyRegistration { inner })
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
    let request = ImportRequest {
        setup,
        target,
        tracker_sigma,
        every,
        names: OptionNames::Python,
    };
    let imported = run(py, || {
        calibrate_geometry::import_ur10_tracker(&series, &request)
    })?;
    let summary = imported.summary_json(None).to_string();
    Ok((imported.text, json_to_py(py, &summary)?))
}
