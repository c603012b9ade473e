//! Stiffness identification and validation: results and entry points, and the data-source
//! argument every calibration takes.

use super::convert::{json_to_py, rows_to_numpy, run, to_numpy, to_py, type_error};
use super::robot::{PyRobot, robot_arg};
use deflex_app::OptionNames;
use deflex_app::calibrate::{
    self, CalibrateOptions, CriterionChoice, DataCheck, MeasurementSource, StructureChoice,
};
use deflex_app::error::Error;
use pyo3::prelude::*;
use pyo3::types::PyTuple;
use std::path::PathBuf;

/// A data source from the Python layer: `("file", path)` or `("table", csv_text, origin)`.
pub fn source_arg(py: Python<'_>, obj: &Bound<'_, PyAny>) -> PyResult<MeasurementSource> {
    let bad = || type_error(py, "data", "a file path or a table", obj);
    let tuple = obj.cast::<PyTuple>().map_err(|_| bad())?;
    let kind: String = tuple.get_item(0)?.extract().map_err(|_| bad())?;
    match (kind.as_str(), tuple.len()) {
        ("file", 2) => Ok(MeasurementSource::File(
            tuple.get_item(1)?.extract::<PathBuf>()?,
        )),
        ("table", 3) => Ok(MeasurementSource::Table {
            text: tuple.get_item(1)?.extract()?,
            origin: tuple.get_item(2)?.extract()?,
        }),
        _ => Err(bad()),
    }
}

pub fn sources(py: Python<'_>, list: &[Bound<'_, PyAny>]) -> PyResult<Vec<MeasurementSource>> {
    list.iter().map(|o| source_arg(py, o)).collect()
}

/// The result of a stiffness identification (``deflex.calibrate``): the estimates with their
/// standard errors and 95 % intervals, the residuals, the search's iteration table and the
/// calibrated robot.
#[pyclass(module = "deflex", frozen, name = "StiffnessCalibration")]
pub struct PyStiffnessCalibration {
    inner: calibrate::StiffnessCalibration,
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
            .map(|e| calibrate::status_name(&e.status))
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

    /// The fit as a dict (the CLI's ``--json``: estimates, shifts, correlations, χ²/dof, BIC,
    /// residual statistics, iterations, file check, warnings; and ``simulated_data``).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let mut dict = calibrate::summary_json(&self.inner, None);
        dict["simulated_data"] = self.inner.simulated_data().into();
        json_to_py(py, &dict.to_string())
    }

    /// The CLI's text report (iteration table, estimates, residuals, correlation, file check,
    /// warnings).
    fn report(&self) -> String {
        calibrate::report_text(&self.inner)
    }

    fn __str__(&self) -> String {
        calibrate::report_text(&self.inner)
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
        run(py, || calibrate::save(inner, &path, report.as_deref()))
    }
}

/// The check of the data against the forward kinematics (no column is ignored: a table's columns
/// are the caller's own).
fn data_check(fk_tolerance_m: f64, ignore_fk_check: bool) -> DataCheck {
    DataCheck {
        fk_tolerance_m,
        ignore_fk_check,
        ignore_columns: Vec::new(),
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
    let choice = |keyword: &str, e: calibrate::UnknownChoice| {
        to_py(py, Error::invalid(keyword, e.to_string()))
    };
    let structure: StructureChoice = structure.parse().map_err(|e| choice("structure", e))?;
    let criterion: CriterionChoice = criterion.parse().map_err(|e| choice("criterion", e))?;
    let options = CalibrateOptions {
        structure,
        fit_shifts,
        criterion,
        folds,
        min_cv_gain,
        target_rms_m,
        min_bic_gain,
        allow_base,
        check: data_check(fk_tolerance_m, ignore_fk_check),
        couplings: Vec::new(),
    };
    let inner = run(py, || {
        calibrate::calibrate(&start, &source, &options, OptionNames::Python, &mut |_| {})
    })?;
    Ok(PyStiffnessCalibration { inner })
}

/// Prediction errors of a model (and a baseline) on measured rows (``deflex.validate``).
#[pyclass(module = "deflex", frozen, name = "Validation")]
pub struct PyValidation {
    inner: calibrate::ValidationRun,
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

    /// Error statistics as a dict (the CLI's ``--json``, without the files of ``save``; and
    /// ``measured_rms_m``).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let mut dict = calibrate::validation_json(&self.inner, None);
        dict["measured_rms_m"] = self.inner.validation.measured_rms_m.to_vec().into();
        json_to_py(py, &dict.to_string())
    }

    /// The validation's plots and HTML page (``validation.html``) into the folder ``dir``,
    /// replaced whole; returns the files written.
    fn save(&self, py: Python<'_>, dir: PathBuf) -> PyResult<Vec<PathBuf>> {
        let inner = &self.inner;
        run(py, || calibrate::write_validation_report(inner, &dir))
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
        calibrate::validate(
            &model,
            baseline.as_ref(),
            &source,
            &data_check(fk_tolerance_m, ignore_fk_check),
            OptionNames::Python,
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
    let rows = run(py, || calibrate::predict_displacements(&model, &source))?;
    rows_to_numpy(py, &rows)
}
