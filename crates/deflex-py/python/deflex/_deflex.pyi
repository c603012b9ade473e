"""Type stubs of deflex's Rust extension module (``deflex._deflex``). The public API is the
``deflex`` package; the ``_``-prefixed functions are its engine calls."""

from __future__ import annotations

import os
from typing import Any, Dict, List, Literal, Optional, Sequence, Tuple, Union, final

import numpy as np
import numpy.typing as npt

from .log import Log

__all__ = [
    "Robot",
    "StiffnessCalibration",
    "Validation",
    "GeometryCalibration",
    "Prediction",
    "Registration",
    "Compensation",
    "TwinRun",
    "_calibrate",
    "_validate",
    "_predict_displacements",
    "_calibrate_geometry",
    "_predict",
    "_register",
    "_import_ur10_tracker",
    "_compensate",
    "_form",
    "_cell_robot",
    "_read_table",
    "_parse_table",
    "__version__",
]

__version__: str

_PathLike = Union[str, "os.PathLike[str]"]
_ArrayLike = npt.ArrayLike
_F64 = npt.NDArray[np.float64]
_Source = Union[Tuple[str, str], Tuple[str, str, str]]
_RobotLike = Union["Robot", str, "os.PathLike[str]"]

@final
class Robot:
    """A serial robot with its elastic structure (VJM eDoF springs); immutable, SI units."""

    @staticmethod
    def builtin(name: str) -> Robot:
        """A built-in robot by name (``tx200``, ``tx200-1edof``, ``ur10``, ``ur10e``, ``kr210-r2700``, ``irb4600``)."""
    @staticmethod
    def builtins() -> List[str]:
        """Names of the built-in robots."""
    @staticmethod
    def load(path: _PathLike) -> Robot:
        """A robot from a robot file (TOML, possibly naming a URDF) or a built-in name."""
    @staticmethod
    def from_toml(text: str, origin: str = "<text>", base_dir: Optional[_PathLike] = None) -> Robot:
        """A robot from robot-file TOML text."""
    @property
    def name(self) -> str:
        """Human-readable name."""
    @property
    def joint_count(self) -> int:
        """Number of motorised joints ``n``."""
    @property
    def joint_names(self) -> List[str]:
        """Joint names, base to flange."""
    @property
    def limits(self) -> _F64:
        """Joint limits ``(n, 2)`` (rad), NaN where none."""
    @property
    def edofs(self) -> List[str]:
        """eDoF labels (``J3.x``…), in eDoF Jacobian column order."""
    @property
    def stiffness(self) -> _F64:
        """eDoF stiffnesses (N·m/rad), same order as ``edofs``."""
    @property
    def geometry_fingerprint(self) -> str:
        """Geometry fingerprint (16 hex digits)."""
    @property
    def tool(self) -> _F64:
        """Flange → TCP placement, 4×4."""
    @property
    def base(self) -> _F64:
        """World → R0 placement, 4×4."""
    def pose(self, q: _ArrayLike) -> _F64:
        """TCP pose(s), ``(4, 4)`` or ``(N, 4, 4)``."""
    def jacobian(self, q: _ArrayLike) -> _F64:
        """Geometric Jacobian(s) at the TCP, ``(6, n)`` or ``(N, 6, n)``."""
    def compliance(self, q: _ArrayLike) -> _F64:
        """Cartesian compliance(s) ``J K⁻¹ Jᵀ`` (eq. 15), ``(6, 6)`` or ``(N, 6, 6)``."""
    def deflect(self, q: _ArrayLike, wrench: _ArrayLike) -> _F64:
        """TCP deflection(s) ``[δp; δφ]`` (m, rad), ``(6,)`` or ``(N, 6)``."""
    def gravity_sag(self, q: _ArrayLike) -> Optional[_F64]:
        """Sag under the arm's own weight ``[δp; δφ]``, or None without masses."""
    def ik(
        self,
        pose: _ArrayLike,
        seed: Optional[_ArrayLike] = None,
        on_failure: Literal["raise", "nan"] = "raise",
    ) -> _F64:
        """Joint values (rad) reaching the pose(s), ``(n,)`` or ``(N, n)``."""
    def to_toml(self) -> str:
        """The robot file text."""
    def save(self, path: _PathLike) -> None:
        """Write the robot file, whole or not at all."""

@final
class StiffnessCalibration:
    """A stiffness identification's estimates, uncertainties, residuals and calibrated robot."""

    @property
    def robot(self) -> Robot:
        """The calibrated robot."""
    @property
    def structure(self) -> str:
        """The identified structure."""
    @property
    def edofs(self) -> List[str]:
        """eDoF labels of the estimates."""
    @property
    def status(self) -> List[str]:
        """``identified``, ``weak`` or ``not_identifiable`` per eDoF."""
    @property
    def stiffness(self) -> _F64:
        """Stiffness estimates (N·m/rad)."""
    @property
    def stiffness_se(self) -> _F64:
        """Standard errors of the stiffnesses."""
    @property
    def interval95(self) -> _F64:
        """95 % intervals ``(k, 2)``."""
    @property
    def compliance(self) -> _F64:
        """Compliance estimates (rad/(N·m))."""
    @property
    def compliance_se(self) -> _F64:
        """Standard errors of the compliances."""
    @property
    def residuals(self) -> _F64:
        """Measured − predicted ``(N, 3)`` (m)."""
    @property
    def predicted(self) -> _F64:
        """Predicted displacements ``(N, 3)`` (m)."""
    @property
    def correlation(self) -> _F64:
        """Parameter correlation matrix."""
    def to_dict(self) -> Dict[str, Any]:
        """The CLI's JSON as a dict."""
    def report(self) -> str:
        """The CLI's text report."""
    def save(self, path: _PathLike, report: Optional[_PathLike] = None) -> None:
        """Write the calibrated robot file (and the report folder)."""

@final
class Validation:
    """Prediction errors of a model (and a baseline)."""

    @property
    def measured(self) -> _F64:
        """Measured displacements ``(N, 3)``."""
    @property
    def predicted(self) -> _F64:
        """Predictions ``(N, 3)``."""
    @property
    def errors(self) -> _F64:
        """Measured − predicted ``(N, 3)``."""
    @property
    def baseline_errors(self) -> Optional[_F64]:
        """The baseline's errors, or None."""
    def to_dict(self) -> Dict[str, Any]:
        """Error statistics."""
    def save(self, dir: _PathLike) -> List[str]:
        """Plots and HTML page into ``dir``."""

@final
class GeometryCalibration:
    """An elasto-geometric calibration's iteration table, estimates and calibrated robot."""

    @property
    def robot(self) -> Robot:
        """The calibrated robot."""
    @property
    def parameters(self) -> List[str]:
        """Identified parameter names."""
    @property
    def units(self) -> List[str]:
        """SI unit of each parameter."""
    @property
    def nominal(self) -> _F64:
        """Nominal values."""
    @property
    def estimates(self) -> _F64:
        """Estimates."""
    @property
    def standard_errors(self) -> _F64:
        """Standard errors (scaled)."""
    @property
    def intervals95(self) -> _F64:
        """95 % intervals ``(p, 2)``."""
    @property
    def bootstrap_se(self) -> _F64:
        """Bootstrap standard errors (NaN without bootstrap)."""
    @property
    def covariance(self) -> _F64:
        """Covariance ``(p, p)``."""
    @property
    def residuals(self) -> _F64:
        """Residual of every reading ``(N, 3)``."""
    @property
    def roles(self) -> List[str]:
        """``fit``, ``test`` or ``registration`` per reading."""
    @property
    def chi2_per_dof(self) -> float:
        """χ²/dof."""
    @property
    def elapsed_s(self) -> float:
        """Fit wall time (s)."""
    def to_dict(self) -> Dict[str, Any]:
        """The CLI's JSON report."""
    def report(self) -> str:
        """The CLI's text report."""
    def save(self, path: _PathLike, report: Optional[_PathLike] = None) -> None:
        """Write the calibrated robot file (and the report folder)."""

@final
class Prediction:
    """Per-row predictions of a calibrated robot."""

    @property
    def table(self) -> Log:
        """The predictions as columns."""
    def to_dict(self) -> Dict[str, Any]:
        """Summary."""
    def report(self) -> str:
        """The CLI's summary line."""
    def save(self, path: _PathLike) -> None:
        """Write the prediction CSV."""

@final
class Registration:
    """A new session's set-up (and target) registered from a few readings."""

    @property
    def robot(self) -> Robot:
        """The updated robot."""
    @property
    def setup(self) -> str:
        """The set-up registered."""
    @property
    def target(self) -> Optional[str]:
        """The target registered too."""
    @property
    def readings(self) -> int:
        """Readings used."""
    @property
    def parameters(self) -> List[str]:
        """Registered parameter names."""
    @property
    def estimates(self) -> _F64:
        """Registered values (SI)."""
    @property
    def standard_errors(self) -> _F64:
        """Their standard errors (SI)."""
    @property
    def rms_m(self) -> float:
        """Position residual RMS (m)."""
    @property
    def chi2_per_dof(self) -> float:
        """χ²/dof."""
    @property
    def warnings(self) -> List[str]:
        """What deserves a second look."""
    def to_dict(self) -> Dict[str, Any]:
        """The CLI's JSON output."""
    def report(self) -> str:
        """The CLI's text output."""
    def save(self, path: _PathLike) -> None:
        """Write the updated robot file (and the terms beside it)."""

@final
class Compensation:
    """A compensated tool path."""

    def __len__(self) -> int: ...
    @property
    def converged(self) -> bool:
        """Whether it converged."""
    @property
    def simulated(self) -> bool:
        """Whether the wrenches are simulated."""
    @property
    def source(self) -> str:
        """The wrench source."""
    @property
    def desired(self) -> _F64:
        """Desired positions ``(N, 3)``."""
    @property
    def commanded(self) -> _F64:
        """Commanded positions ``(N, 3)``."""
    @property
    def commanded_poses(self) -> _F64:
        """Commanded poses ``(N, 4, 4)``."""
    @property
    def compensation(self) -> _F64:
        """Compensation ``(N, 6)``."""
    @property
    def wrench(self) -> _F64:
        """Wrenches ``(N, 6)``."""
    @property
    def deflection(self) -> _F64:
        """Predicted deflections ``(N, 6)``."""
    @property
    def q(self) -> _F64:
        """Joint values ``(N, n)``."""
    @property
    def predicted_error(self) -> _F64:
        """Remaining predicted error ``(N,)``."""
    @property
    def status(self) -> List[str]:
        """``ok`` or the failure per point."""
    def to_dict(self) -> Dict[str, Any]:
        """Summary."""
    def to_csv(self) -> str:
        """``compensated_path.csv`` text."""
    def save(self, path: _PathLike) -> None:
        """Write ``compensated_path.csv``."""
    def program(self, format: str, settings: Optional[_PathLike] = None) -> Dict[str, str]:
        """The program in ``format`` as ``{path: text}``."""
    def write_programs(
        self,
        dir: _PathLike,
        formats: Sequence[str] = ...,
        settings: Optional[_PathLike] = None,
    ) -> List[str]:
        """Write programs under ``dir``."""

@final
class TwinRun:
    """A SIMULATED forming run."""

    @property
    def log(self) -> Log:
        """The run's log (SI columns)."""
    @property
    def summary(self) -> Dict[str, Any]:
        """``summary.json`` as a dict."""
    @property
    def controller_status(self) -> Optional[str]:
        """The correction controller's status line, or None."""
    @property
    def profile(self) -> _F64:
        """Formed and programmed profile ``(M, 3)``."""
    def save(self, dir: _PathLike) -> List[str]:
        """Write the run's outputs into ``dir``."""

def _calibrate(
    robot: _RobotLike,
    data: _Source,
    structure: str,
    fit_shifts: bool,
    criterion: str,
    folds: int,
    min_cv_gain: float,
    target_rms_m: Optional[float],
    min_bic_gain: float,
    allow_base: bool,
    fk_tolerance_m: float,
    ignore_fk_check: bool,
) -> StiffnessCalibration: ...
def _validate(
    robot: _RobotLike,
    data: _Source,
    baseline: Optional[_RobotLike],
    fk_tolerance_m: float,
    ignore_fk_check: bool,
) -> Validation: ...
def _predict_displacements(robot: _RobotLike, data: _Source) -> _F64: ...
def _calibrate_geometry(
    robot: _RobotLike,
    data: Sequence[_Source],
    loaded: Sequence[_Source],
    test_data: Sequence[_Source],
    steps: Optional[Sequence[str]],
    elastic: Sequence[str],
    loss: str,
    folds: int,
    bootstrap: int,
    test_fraction: float,
    seed: int,
    orientations: bool,
    sigma_rad: float,
    cv_by: Optional[str],
    register_readings: int,
    register_draws: int,
    register_target: bool,
    allow_large_changes: bool,
) -> GeometryCalibration: ...
def _predict(
    robot: Union[GeometryCalibration, _RobotLike], data: _Source, fit_setup: bool
) -> Prediction: ...
def _register(
    robot: Union[GeometryCalibration, _RobotLike],
    data: _Source,
    setup: Optional[str],
    target: Optional[str],
    orientations: bool,
    sigma_rad: float,
    recalibrate_above_m: Optional[float],
    allow_large_changes: bool,
) -> Registration: ...
def _import_ur10_tracker(
    series: str, setup: str, target: str, tracker_sigma: bool, every: int
) -> Tuple[str, Dict[str, Any]]: ...
def _compensate(
    robot: _RobotLike,
    path: Any,
    wrench: Any,
    frame: str,
    feed_m_s: Optional[float],
    twin_config: Optional[str],
    part_xyz_m: Optional[Sequence[float]],
    seed_q: Optional[Sequence[float]],
    length_m: Optional[float],
    max_segment_m: Optional[float],
    position_only: bool,
    include_gravity: bool,
    tolerance_m: float,
    max_iterations: int,
    log_forces: str = "auto",
) -> Compensation: ...
def _form(
    path: str,
    correction: str,
    model: Optional[_RobotLike],
    robot: Optional[str],
    config: Optional[str],
    seed: int,
    length_m: Optional[float],
    feed_m_s: Optional[float],
    fixture_stiffness_n_m: Optional[float],
) -> TwinRun: ...
def _cell_robot(robot: Optional[str] = None, config: Optional[str] = None) -> Robot: ...
def _read_table(path: str) -> Log: ...
def _parse_table(text: str, origin: str) -> Log: ...
