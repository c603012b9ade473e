//! `deflex.Robot`: the elasto-geometrical model, batched over configurations.

use super::convert::{FloatArray, float_array, rows_of, run, shape_error, to_numpy, to_py};
use deflex_app::robot::{self, OnFailure};
use pyo3::prelude::*;
use std::path::PathBuf;
use std::str::FromStr;

/// A serial robot with its elastic structure (modified/standard DH or URDF geometry plus the
/// torsional eDoF springs of the Virtual Joint Method). Immutable; SI units throughout (m, rad,
/// N, N·m); poses are 4×4 homogeneous matrices in the world frame.
///
/// Every computation takes one configuration ``q`` of shape ``(n,)`` or a batch of shape
/// ``(N, n)`` and returns arrays of shape ``(…)`` or ``(N, …)``; batches run in Rust with the GIL
/// released, spread over the cores.
#[pyclass(module = "deflex", frozen, name = "Robot")]
pub struct PyRobot {
    pub(crate) robot: deflex_model::Robot,
}

impl PyRobot {
    pub(crate) fn new(robot: deflex_model::Robot) -> PyRobot {
        PyRobot { robot }
    }

    /// `q` as `(rows, batched)`, checked against the joint count.
    fn joints<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
    ) -> PyResult<(FloatArray<'py>, usize, bool)> {
        let n = self.robot.joint_count();
        let q = float_array(py, q, "q", &format!("({n},) or (N, {n})"))?;
        let (rows, batched) = rows_of(
            py,
            &q,
            "q",
            n,
            &format!("{n} joint values per row for \"{}\"", self.robot.name),
        )?;
        Ok((q, rows, batched))
    }
}

fn shape(batched: bool, rows: usize, tail: &[usize]) -> Vec<usize> {
    let mut s = if batched { vec![rows] } else { Vec::new() };
    s.extend_from_slice(tail);
    s
}

#[pymethods]
impl PyRobot {
    /// A built-in robot by name: ``tx200``, ``tx200-1edof``, ``ur10``, ``ur10e``,
    /// ``kr210-r2700``, ``irb4600``, ``r2000ic-165f``, ``gp180`` (see ``Robot.builtins()``).
    #[staticmethod]
    fn builtin(py: Python<'_>, name: &str) -> PyResult<PyRobot> {
        let name = name.to_string();
        run(py, move || robot::builtin(&name)).map(PyRobot::new)
    }

    /// Names of the built-in robots.
    #[staticmethod]
    fn builtins() -> Vec<&'static str> {
        robot::builtin_names()
    }

    /// A robot from a robot file (TOML, possibly naming a URDF, resolved beside the file) or a
    /// built-in name, as every CLI command takes ``--robot``.
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<PyRobot> {
        run(py, move || robot::load(&path.display().to_string())).map(PyRobot::new)
    }

    /// A robot from robot-file TOML text; ``origin`` names it in errors and ``base_dir``
    /// resolves a URDF path it names.
    #[staticmethod]
    #[pyo3(signature = (text, origin = "<text>", base_dir = None))]
    fn from_toml(
        py: Python<'_>,
        text: &str,
        origin: &str,
        base_dir: Option<PathBuf>,
    ) -> PyResult<PyRobot> {
        let (text, origin) = (text.to_string(), origin.to_string());
        run(py, move || {
            robot::from_toml(&text, &origin, base_dir.as_deref())
        })
        .map(PyRobot::new)
    }

    /// Human-readable name.
    #[getter]
    fn name(&self) -> &str {
        &self.robot.name
    }

    /// Number of motorised joints ``n``.
    #[getter]
    fn joint_count(&self) -> usize {
        self.robot.joint_count()
    }

    /// Joint names, base to flange.
    #[getter]
    fn joint_names(&self) -> Vec<String> {
        self.robot.joints.iter().map(|j| j.name.clone()).collect()
    }

    /// Joint limits, shape ``(n, 2)`` (rad): ``[min, max]`` per joint, NaN where a joint has none.
    #[getter]
    fn limits<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let l = robot::limits(&self.robot);
        to_numpy(py, l.iter().flatten().copied().collect(), &[l.len(), 2])
    }

    /// eDoF labels in the column order of the eDoF Jacobian (``base.x``, ``J1.z``, ``J3.x``…).
    #[getter]
    fn edofs(&self) -> Vec<String> {
        self.robot.edofs().map(|e| e.label()).collect()
    }

    /// eDoF stiffnesses k_θ (N·m/rad), same order as ``edofs``.
    #[getter]
    fn stiffness<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let k: Vec<f64> = self.robot.edofs().map(|e| e.stiffness).collect();
        let len = k.len();
        to_numpy(py, k, &[len])
    }

    /// Geometry fingerprint (16 hex digits), as measurement files record it.
    #[getter]
    fn geometry_fingerprint(&self) -> String {
        self.robot.geometry_fingerprint()
    }

    /// Flange → TCP placement, 4×4.
    #[getter]
    fn tool<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let mut out = vec![0.0; 16];
        robot::write_pose(&self.robot.tool, &mut out);
        to_numpy(py, out, &[4, 4])
    }

    /// World → robot base frame R0 placement, 4×4.
    #[getter]
    fn base<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let mut out = vec![0.0; 16];
        robot::write_pose(&self.robot.base, &mut out);
        to_numpy(py, out, &[4, 4])
    }

    /// TCP pose (eq. 1) as a 4×4 homogeneous matrix in the world frame: shape ``(4, 4)`` for
    /// ``q`` of shape ``(n,)``, ``(N, 4, 4)`` for ``(N, n)``.
    fn pose<'py>(&self, py: Python<'py>, q: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        let (q, rows, batched) = self.joints(py, q)?;
        let robot = &self.robot;
        let qv = q.values();
        let out = run(py, || robot::poses(robot, qv, rows))?;
        to_numpy(py, out, &shape(batched, rows, &[4, 4]))
    }

    /// Geometric Jacobian of the motorised joints at the TCP, rows ``[v; ω]`` in world axes:
    /// shape ``(6, n)`` or ``(N, 6, n)``.
    fn jacobian<'py>(&self, py: Python<'py>, q: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        let (q, rows, batched) = self.joints(py, q)?;
        let robot = &self.robot;
        let n = robot.joint_count();
        let qv = q.values();
        let out = run(py, || robot::jacobians(robot, qv, rows))?;
        to_numpy(py, out, &shape(batched, rows, &[6, n]))
    }

    /// Cartesian compliance at the TCP, ``C = J K_θ⁻¹ Jᵀ`` (eq. 15), mapping a wrench at the
    /// TCP (world axes, moment about the TCP) to ``[δp; δφ]``: shape ``(6, 6)`` or ``(N, 6, 6)``.
    fn compliance<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let (q, rows, batched) = self.joints(py, q)?;
        let robot = &self.robot;
        let qv = q.values();
        let out = run(py, || robot::compliances(robot, qv, rows))?;
        to_numpy(py, out, &shape(batched, rows, &[6, 6]))
    }

    /// TCP deflection ``δs = J K_θ⁻¹ Jᵀ w`` (eq. 15) under ``wrench = [fx, fy, fz, mx, my, mz]``
    /// (N, N·m; world axes, moment about the TCP): ``[δx, δy, δz, δφx, δφy, δφz]`` (m, rad).
    /// ``wrench`` is ``(6,)`` (the same for every configuration) or ``(N, 6)``; the result is
    /// ``(6,)`` or ``(N, 6)``.
    fn deflect<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
        wrench: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let (q, rows, batched) = self.joints(py, q)?;
        let w = float_array(py, wrench, "wrench", "(6,) or (N, 6)")?;
        let (w_rows, w_batched) = rows_of(py, &w, "wrench", 6, "fx, fy, fz, mx, my, mz")?;
        if w_batched && (w_rows != rows || !batched) {
            return Err(shape_error(
                py,
                "wrench",
                format!(
                    "(6,) or ({}, 6) to match q of shape {}",
                    rows,
                    super::convert::shape_text(&q.shape)
                ),
                &w.shape,
            ));
        }
        let robot = &self.robot;
        let (qv, wv) = (q.values(), w.values());
        let out = run(py, || robot::deflections(robot, qv, rows, wv))?;
        to_numpy(py, out, &shape(batched, rows, &[6]))
    }

    /// Sag of the TCP under the arm's own weight and payload ``[δp; δφ]`` (m, rad), shape
    /// ``(6,)`` or ``(N, 6)``; ``None`` when the model has no masses (as ``deflex pose``).
    fn gravity_sag<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
    ) -> PyResult<Option<Bound<'py, PyAny>>> {
        let (q, rows, batched) = self.joints(py, q)?;
        let robot = &self.robot;
        let qv = q.values();
        match run(py, || robot::gravity_sags(robot, qv, rows))? {
            Some(out) => Ok(Some(to_numpy(py, out, &shape(batched, rows, &[6]))?)),
            None => Ok(None),
        }
    }

    /// Joint values (rad) that put the TCP at ``pose`` (4×4 world, or ``(N, 4, 4)``), from
    /// ``seed`` (``(n,)`` or ``(N, n)``; default the CLI's: the paper's forming configuration
    /// for 6 joints, else zeros) and then 36 spread seeds, as ``deflex ik``. A pose that is not
    /// reached raises ``deflex.InputError`` naming it ("out of reach", "not reached from 37
    /// seeds"), or with ``on_failure="nan"`` gives a row of NaN.
    #[pyo3(signature = (pose, seed = None, on_failure = "raise"))]
    fn ik<'py>(
        &self,
        py: Python<'py>,
        pose: &Bound<'py, PyAny>,
        seed: Option<&Bound<'py, PyAny>>,
        on_failure: &str,
    ) -> PyResult<Bound<'py, PyAny>> {
        let robot = &self.robot;
        let n = robot.joint_count();
        let on_failure = OnFailure::from_str(on_failure).map_err(|e| to_py(py, e))?;
        let p = float_array(py, pose, "pose", "(4, 4) or (N, 4, 4)")?;
        let (rows, batched) = match p.shape.as_slice() {
            [4, 4] => (1, false),
            [r, 4, 4] if *r > 0 => (*r, true),
            other => {
                return Err(shape_error(
                    py,
                    "pose",
                    "(4, 4) or (N, 4, 4) with N ≥ 1 (homogeneous matrices)".into(),
                    other,
                ));
            }
        };
        let seeds = match seed {
            None => robot::default_seed(robot),
            Some(s) => {
                let s = float_array(py, s, "seed", &format!("({n},) or (N, {n})"))?;
                let (s_rows, s_batched) =
                    rows_of(py, &s, "seed", n, &format!("{n} joint values per row"))?;
                if s_batched && (s_rows != rows || !batched) {
                    return Err(shape_error(
                        py,
                        "seed",
                        format!("({n},) or ({rows}, {n}) to match the poses"),
                        &s.shape,
                    ));
                }
                s.into_vec()
            }
        };
        let pv = p.values();
        let out = run(py, || {
            robot::inverse_kinematics(robot, pv, rows, &seeds, on_failure)
        })?;
        to_numpy(py, out, &shape(batched, rows, &[n]))
    }

    /// The robot file (TOML) text.
    fn to_toml(&self) -> String {
        robot::to_toml(&self.robot, None)
    }

    /// Write the robot file (TOML) to ``path``, whole or not at all; a URDF path it names is
    /// rewritten relative to the new file's folder.
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let robot = &self.robot;
        run(py, || robot::save(robot, &path))
    }

    fn __repr__(&self) -> String {
        format!(
            "Robot('{}', {} joints, {} eDoFs: {})",
            self.robot.name,
            self.robot.joint_count(),
            self.robot.edof_count(),
            self.robot
                .edofs()
                .map(|e| e.label())
                .collect::<Vec<_>>()
                .join(" ")
        )
    }
}

/// A robot argument: a `Robot`, or a built-in name / robot file path.
pub fn robot_arg(
    py: Python<'_>,
    obj: &Bound<'_, PyAny>,
    name: &str,
) -> PyResult<deflex_model::Robot> {
    if let Ok(r) = obj.cast::<PyRobot>() {
        return Ok(r.get().robot.clone());
    }
    if let Ok(path) = obj.extract::<PathBuf>() {
        let spec = path.display().to_string();
        return run(py, move || robot::load(&spec));
    }
    Err(super::convert::type_error(
        py,
        name,
        "a deflex.Robot, a built-in robot name or a robot file path",
        obj,
    ))
}
