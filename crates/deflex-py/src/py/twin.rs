//! The digital twin (SIMULATED) and deflex's logs: results and entry points.

use super::convert::{json_to_py, make_log, run, to_numpy, to_py};
use super::robot::{PyRobot, robot_arg};
use deflex_app::OptionNames;
use deflex_app::error::{Error, bounded};
use deflex_app::twin::form::{CorrectionModel, FIXTURE_STIFFNESS_RANGE_N_M};
use deflex_app::twin::{self, FormCorrection, FormOptions, PathChoice, TwinRun};
use pyo3::prelude::*;
use std::path::PathBuf;
use std::str::FromStr;

/// A forming run on the digital twin (SIMULATED): its log, summary and formed profile.
#[pyclass(module = "deflex", frozen, name = "TwinRun")]
pub struct PyTwinRun {
    inner: TwinRun,
}

#[pymethods]
impl PyTwinRun {
    /// The run's log as a ``deflex.Log`` (SI columns: ``time_s``, desired/commanded/true/tracked
    /// TCP ``des_x_m…`` in the part frame, the error ``err_x_m…``/``err_norm_m``, the wrench on
    /// the tool ``fx_N…``, the raw sensor sample, the correction ``corr_x_m…``, the plant's
    /// deflection and the contact state), labelled SIMULATED.
    #[getter]
    fn log<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let inner = &self.inner;
        let table = run(py, || Ok(twin::log_table(inner)))?;
        make_log(py, table)
    }

    /// The summary (``summary.json``): max/RMS path error (mm), forces (N), part depth….
    #[getter]
    fn summary<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let inner = &self.inner;
        let text = run(py, || twin::summary_json(inner))?;
        json_to_py(py, &text)
    }

    /// The correction controller's status line (closed loop), else ``None``.
    #[getter]
    fn controller_status(&self) -> Option<String> {
        self.inner.controller_status.clone()
    }

    /// Formed and programmed profile along θ = 0: ``(M, 3)`` rows ``[r_m, depth_m,
    /// programmed_depth_m]`` (NaN where not programmed).
    #[getter]
    fn profile<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let run = &self.inner.run;
        let values: Vec<f64> = run
            .profile_mm
            .iter()
            .enumerate()
            .flat_map(|(k, (r, d))| {
                let p = run
                    .programmed_profile_mm
                    .get(k)
                    .map_or(f64::NAN, |(_, p)| *p);
                [r * 1e-3, d * 1e-3, p * 1e-3]
            })
            .collect();
        to_numpy(py, values, &[run.profile_mm.len(), 3])
    }

    /// Write ``log.csv``, ``summary.json``, ``profile.csv`` and the plots into the folder
    /// ``dir`` (as ``deflex sim isf --out``), replaced whole; returns the files.
    fn save(&self, py: Python<'_>, dir: PathBuf) -> PyResult<Vec<PathBuf>> {
        let inner = &self.inner;
        run(py, || twin::write_outputs(inner, &dir))
    }

    fn __repr__(&self) -> String {
        let s = &self.inner.run.summary;
        format!(
            "TwinRun(SIMULATED, {}, '{}', {}, max error {:.3} mm, RMS {:.3} mm, max |F| {:.0} N)",
            s.robot,
            s.path,
            if s.correction {
                "closed loop"
            } else {
                "open loop"
            },
            s.max_error_norm_mm,
            s.rms_error_norm_mm,
            s.max_force_norm_N
        )
    }
}

/// ``deflex.sim.form``'s engine call.
#[pyfunction]
#[pyo3(signature = (path, correction, model, robot, config, seed, length_m, feed_m_s, fixture_stiffness_n_m))]
#[allow(clippy::too_many_arguments)]
pub fn _form(
    py: Python<'_>,
    path: PathBuf,
    correction: &str,
    model: Option<&Bound<'_, PyAny>>,
    robot: Option<PathBuf>,
    config: Option<PathBuf>,
    seed: u64,
    length_m: Option<f64>,
    feed_m_s: Option<f64>,
    fixture_stiffness_n_m: Option<f64>,
) -> PyResult<PyTwinRun> {
    let correction = FormCorrection::from_str(correction).map_err(|e| to_py(py, e))?;
    let Ok(path) = PathChoice::from_str(&path.display().to_string());
    twin::check_correction(correction, model.is_some(), OptionNames::Python)
        .map_err(|e| to_py(py, e))?;
    let model = match (correction, model) {
        (FormCorrection::On, None) => {
            return Err(to_py(
                py,
                Error::invalid(
                    "model",
                    "correction=\"on\" needs model= (the identified robot model: a deflex.Robot or a robot file)",
                ),
            ));
        }
        (_, Some(m)) => Some(CorrectionModel::Robot(Box::new(robot_arg(py, m, "model")?))),
        (_, None) => None,
    };
    // The keywords in their units (m, m/s), then in the tool-path generator's (mm, mm/s).
    let checked = |name: &str, value: Option<f64>, lo: f64, hi: f64, unit: &str| {
        value
            .map(|v| bounded(name, v, lo, hi, unit))
            .transpose()
            .map_err(|e| to_py(py, e))
    };
    let (k_lo, k_hi) = FIXTURE_STIFFNESS_RANGE_N_M;
    let fixture_stiffness_n_m = checked(
        "fixture_stiffness_n_m",
        fixture_stiffness_n_m,
        k_lo,
        k_hi,
        "N/m",
    )?;
    let feed_m_s = checked("feed_m_s", feed_m_s, 1e-4, 1.0, "m/s")?;
    let length_m = checked("length_m", length_m, 1e-6, 1e3, "m")?;
    let options = FormOptions {
        robot: robot.map(|r| r.display().to_string()),
        config,
        path,
        seed,
        length_mm: length_m.map(|l| l * 1e3),
        feed_mm_s: feed_m_s.map(|f| f * 1e3),
        fixture_stiffness_n_m,
        correction,
        model,
        names: OptionNames::Python,
    };
    let inner = run(py, || twin::form(&options))?;
    Ok(PyTwinRun { inner })
}

/// ``deflex.sim.cell_robot``'s engine call.
#[pyfunction]
#[pyo3(signature = (robot = None, config = None))]
pub fn _cell_robot(
    py: Python<'_>,
    robot: Option<PathBuf>,
    config: Option<PathBuf>,
) -> PyResult<PyRobot> {
    let robot = robot.map(|r| r.display().to_string());
    run(py, || {
        let cell = twin::cell_config(robot.as_deref(), config.as_deref())?;
        twin::cell_robot(&cell)
    })
    .map(PyRobot::new)
}

/// ``deflex.read_log``'s engine call: a ``deflex.Log`` of the CSV file's columns.
#[pyfunction]
pub fn _read_table<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyAny>> {
    let table = run(py, || deflex_app::table::read(&path))?;
    make_log(py, table)
}

/// CSV text as a ``deflex.Log``.
#[pyfunction]
pub fn _parse_table<'py>(
    py: Python<'py>,
    text: String,
    origin: String,
) -> PyResult<Bound<'py, PyAny>> {
    let table = run(py, || deflex_app::table::parse(&text, &origin))?;
    make_log(py, table)
}
