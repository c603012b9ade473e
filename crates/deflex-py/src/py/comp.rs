//! Offline compensation and robot programs: result and entry point.

use super::convert::{float_array, json_to_py, run, shape_error, to_numpy, to_py, type_error};
use super::robot::robot_arg;
use deflex_app::compensate::{
    self, CompensationRun, Frame, LogForces, Options, PathSpec, RobotChoice, WrenchSpec,
};
use deflex_app::error::{Error, bounded};
use deflex_app::option_names::OptionNames;
use pyo3::prelude::*;
use pyo3::types::PyString;
use std::collections::BTreeMap;
use std::path::PathBuf;

/// A compensated tool path (``deflex.compensate``): per point the desired pose, the
/// compensation, the commanded pose, the wrench, the predicted deflection and the joints, the
/// iterations, and the robot programs.
#[pyclass(module = "deflex", frozen, name = "Compensation")]
pub struct PyCompensation {
    inner: CompensationRun,
}

impl PyCompensation {
    fn per_point<'py, const N: usize>(
        &self,
        py: Python<'py>,
        f: impl Fn(usize) -> [f64; N],
    ) -> PyResult<Bound<'py, PyAny>> {
        let n = self.inner.result.points.len();
        let values: Vec<f64> = (0..n).flat_map(&f).collect();
        to_numpy(py, values, &[n, N])
    }
}

#[pymethods]
impl PyCompensation {
    /// Number of path points.
    fn __len__(&self) -> usize {
        self.inner.result.points.len()
    }

    /// Whether the compensation converged to the tolerance.
    #[getter]
    fn converged(&self) -> bool {
        self.inner.result.converged
    }

    /// Whether the wrenches came from a simulation (the process model, a twin log).
    #[getter]
    fn simulated(&self) -> bool {
        self.inner.result.simulated
    }

    /// What the wrenches are.
    #[getter]
    fn source(&self) -> String {
        self.inner.result.source.clone()
    }

    /// Desired TCP positions (world, m), ``(N, 3)``.
    #[getter]
    fn desired<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let pts = self.inner.setup.path.points();
        self.per_point(py, |i| pts[i].pose.translation.vector.into())
    }

    /// Commanded TCP positions (world, m): desired ⊕ compensation, ``(N, 3)``.
    #[getter]
    fn commanded<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let pts = self.inner.setup.path.points();
        let res = &self.inner.result.points;
        self.per_point(py, |i| {
            res[i].commanded(&pts[i].pose).translation.vector.into()
        })
    }

    /// Commanded TCP poses (world), ``(N, 4, 4)``.
    #[getter]
    fn commanded_poses<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let pts = self.inner.setup.path.points();
        let res = &self.inner.result.points;
        let mut out = vec![0.0; pts.len() * 16];
        for (i, o) in out.chunks_mut(16).enumerate() {
            deflex_app::robot::write_pose(&res[i].commanded(&pts[i].pose), o);
        }
        to_numpy(py, out, &[pts.len(), 4, 4])
    }

    /// Compensation ``[dx, dy, dz, drx, dry, drz]`` (m, rad), ``(N, 6)``.
    #[getter]
    fn compensation<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let res = &self.inner.result.points;
        self.per_point(py, |i| res[i].compensation.into())
    }

    /// Wrench at each point (world axes, at the TCP; N, N·m), ``(N, 6)``.
    #[getter]
    fn wrench<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let res = &self.inner.result.points;
        self.per_point(py, |i| res[i].wrench.into())
    }

    /// Predicted deflection at the commanded pose (m, rad), ``(N, 6)``.
    #[getter]
    fn deflection<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let res = &self.inner.result.points;
        self.per_point(py, |i| res[i].deflection.into())
    }

    /// Joint values reaching the commanded pose (rad), ``(N, n)``.
    #[getter]
    fn q<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let n = self.inner.setup.robot.joint_count();
        let res = &self.inner.result.points;
        let values: Vec<f64> = res.iter().flat_map(|p| p.q[..n].to_vec()).collect();
        to_numpy(py, values, &[res.len(), n])
    }

    /// Remaining predicted position error after compensation (m), ``(N,)``.
    #[getter]
    fn predicted_error<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let res = &self.inner.result.points;
        to_numpy(
            py,
            res.iter().map(|p| p.predicted_error_m).collect(),
            &[res.len()],
        )
    }

    /// Per point ``ok`` or the reason it was not compensated (``compensated:joint_limit:J3``…).
    #[getter]
    fn status(&self) -> Vec<String> {
        compensate::statuses(&self.inner)
    }

    /// Summary as a dict (the CLI's ``summary.json``, its ``compensation`` at the top):
    /// robot, path and placement, iterations (predicted error, force, change, failed points),
    /// convergence, final predicted error, largest compensation, failures.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        json_to_py(py, &compensate::summary_dict(&self.inner).to_string())
    }

    /// The compensated path as ``compensated_path.csv`` text (the CLI's, SI columns).
    fn to_csv(&self) -> String {
        compensate::table_csv(&self.inner)
    }

    /// Write ``compensated_path.csv`` (the CLI's table, usable as ``deflex run``'s
    /// ``[feedforward]``) to ``path``, whole.
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let inner = &self.inner;
        run(py, || {
            deflex_app::table::write_text(&path, &compensate::table_csv(inner))
        })
    }

    /// The robot program in ``format`` (``krl``, ``rapid``, ``val3``, ``urscript``, ``gcode``,
    /// ``fanuc``, ``inform``) as ``{relative path: text}``, with the template ``settings`` (a
    /// program TOML file, ``docs/program.example.toml``) or the defaults. Refused (``deflex.CompensationError``,
    /// the CLI's text) when points are not compensated or the iteration did not converge.
    #[pyo3(signature = (format, settings = None))]
    fn program(
        &self,
        py: Python<'_>,
        format: &str,
        settings: Option<PathBuf>,
    ) -> PyResult<BTreeMap<String, String>> {
        let formats = [format.to_string()];
        let files = run(py, || {
            compensate::program_files(&self.inner, &formats, settings.as_deref())
        })?;
        Ok(files.into_iter().map(|f| (f.path, f.contents)).collect())
    }

    /// Write the programs of every format in ``formats`` under the folder ``dir``, each read
    /// back first; returns the files written. Refused like ``program``.
    #[pyo3(signature = (dir, formats = vec!["krl".to_string(), "rapid".into(), "val3".into(), "urscript".into(), "gcode".into()], settings = None))]
    fn write_programs(
        &self,
        py: Python<'_>,
        dir: PathBuf,
        formats: Vec<String>,
        settings: Option<PathBuf>,
    ) -> PyResult<Vec<PathBuf>> {
        run(py, || {
            let files = compensate::program_files(&self.inner, &formats, settings.as_deref())?;
            compensate::write_program_files(&dir, &files)
        })
    }

    fn __repr__(&self) -> String {
        let r = &self.inner.result;
        format!(
            "Compensation('{}', {} points, {}, predicted error {:.4} → {:.5} mm, {} failed)",
            self.inner.setup.path.name(),
            r.points.len(),
            if r.converged {
                "converged"
            } else {
                "NOT converged"
            },
            r.iterations
                .first()
                .map_or(0.0, |i| i.max_predicted_error_m * 1e3),
            r.final_max_error_m * 1e3,
            r.failure_count()
        )
    }
}

fn array_or_name<'py>(
    py: Python<'py>,
    obj: &Bound<'py, PyAny>,
    name: &'static str,
) -> PyResult<Option<super::convert::FloatArray<'py>>> {
    if obj.is_instance_of::<PyString>() || obj.extract::<PathBuf>().is_ok() {
        return Ok(None);
    }
    float_array(py, obj, name, "(N, 3) or (N, 6)").map(Some)
}

/// The `path` argument: a built-in path's name or a G-code file, or an array of positions or
/// poses in the part frame (`frame`) at `feed_m_s`.
fn path_arg(
    py: Python<'_>,
    path: &Bound<'_, PyAny>,
    frame: Frame,
    feed_m_s: Option<f64>,
) -> PyResult<PathSpec> {
    Ok(match array_or_name(py, path, "path")? {
        None => PathSpec::named(&path.extract::<PathBuf>()?.display().to_string()),
        Some(a) => match a.shape.clone().as_slice() {
            [r, c @ (3 | 6)] if *r >= 2 => PathSpec::Array {
                values: a.into_vec(),
                cols: *c,
                frame,
                feed_m_s,
            },
            other => {
                return Err(shape_error(
                    py,
                    "path",
                    "(N, 3) positions or (N, 6) poses [x, y, z, rx, ry, rz] with N ≥ 2".into(),
                    other,
                ));
            }
        },
    })
}

/// The `wrench` argument: `"process"`, `"log:FILE"`, a log path or an array of wrenches.
fn wrench_arg(py: Python<'_>, wrench: &Bound<'_, PyAny>) -> PyResult<WrenchSpec> {
    if let Ok(text) = wrench.extract::<String>() {
        return WrenchSpec::parse(&text).ok_or_else(|| {
            to_py(
                py,
                Error::invalid(
                    "wrench",
                    format!(
                        "expected \"process\", \"log:FILE\", a log path or an array of wrenches, got \"{text}\""
                    ),
                ),
            )
        });
    }
    if let Ok(p) = wrench.extract::<PathBuf>() {
        return Ok(WrenchSpec::Log(p));
    }
    let w = float_array(py, wrench, "wrench", "(6,) or (N, 6)").map_err(|e| {
        if e.is_instance_of::<pyo3::exceptions::PyTypeError>(py) {
            type_error(
                py,
                "wrench",
                "\"process\", \"log:FILE\", a log path or an array of wrenches",
                wrench,
            )
        } else {
            e
        }
    })?;
    match w.shape.as_slice() {
        [6] | [_, 6] => Ok(WrenchSpec::Array(w.into_vec())),
        other => Err(shape_error(py, "wrench", "(6,) or (N, 6)".into(), other)),
    }
}

/// ``deflex.compensate``'s engine call: the keywords checked in SI (the messages name the
/// keyword), converted to the workflow's options (a log gives its force–depth law when it
/// supports it, `log_forces`: `auto`, `law` or `fixed`).
#[pyfunction]
#[pyo3(signature = (robot, path, wrench, frame, feed_m_s, twin_config, part_xyz_m, seed_q, length_m, max_segment_m, position_only, include_gravity, tolerance_m, max_iterations, log_forces = "auto"))]
#[allow(clippy::too_many_arguments)]
pub fn _compensate(
    py: Python<'_>,
    robot: &Bound<'_, PyAny>,
    path: &Bound<'_, PyAny>,
    wrench: &Bound<'_, PyAny>,
    frame: &str,
    feed_m_s: Option<f64>,
    twin_config: Option<PathBuf>,
    part_xyz_m: Option<[f64; 3]>,
    seed_q: Option<Vec<f64>>,
    length_m: Option<f64>,
    max_segment_m: Option<f64>,
    position_only: bool,
    include_gravity: bool,
    tolerance_m: f64,
    max_iterations: usize,
    log_forces: &str,
) -> PyResult<PyCompensation> {
    let model = robot_arg(py, robot, "robot")?;
    let frame: Frame = frame.parse().map_err(|e| to_py(py, e))?;
    let path_spec = path_arg(py, path, frame, feed_m_s)?;
    let wrench_spec = wrench_arg(py, wrench)?;
    let checked = || -> Result<Options, Error> {
        if let Some(xyz) = part_xyz_m
            && xyz.iter().any(|v| !v.is_finite() || v.abs() > 100.0)
        {
            return Err(Error::invalid(
                "part_xyz_m",
                format!("{xyz:?} is farther than 100 m"),
            ));
        }
        let length_mm = length_m
            .map(|l| bounded("length_m", l, 1e-6, 1e3, "m").map(|l| l * 1e3))
            .transpose()?;
        let max_segment_mm = max_segment_m
            .map(|m| bounded("max_segment_m", m, 1e-6, 10.0, "m").map(|m| m * 1e3))
            .transpose()?;
        bounded("tolerance_m", tolerance_m, 1e-9, 1e-3, "m")?;
        let log_forces: LogForces = log_forces.parse()?;
        if !(1..=200).contains(&max_iterations) {
            return Err(Error::invalid(
                "max_iterations",
                format!("expected 1 ..= 200, got {max_iterations}"),
            ));
        }
        Ok(Options {
            twin_config,
            part_xyz_mm: part_xyz_m.map(|xyz| xyz.map(|v| v * 1e3)),
            seed_q,
            length_mm,
            max_segment_mm,
            position_only,
            include_gravity,
            tolerance_m,
            max_iterations,
            log_forces,
            ..Options::default()
        })
    };
    let options = checked().map_err(|e| to_py(py, e))?;
    let robot = RobotChoice { model, spec: None };
    let inner = run(py, move || {
        let setup = compensate::setup(
            robot,
            &path_spec,
            wrench_spec,
            &options,
            OptionNames::Python,
        )?;
        compensate::compensate(setup, &mut |_| {})
    })?;
    Ok(PyCompensation { inner })
}
