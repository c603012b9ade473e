"""deflex for Python: robots that stay accurate under load.

The elasto-geometrical robot model of Johra et al. (Robotics 2022, 11, 48) — serial kinematics
plus the torsional "eDoF" springs of the Virtual Joint Method — and everything the ``deflex``
CLI does with it, numpy in and numpy out, computed in Rust with the GIL released:

* :class:`Robot`: ``Robot.builtin("tx200")``, ``Robot.load(path)``; ``pose``, ``jacobian``,
  ``compliance`` (eq. 15's ``C = J K⁻¹ Jᵀ``), ``deflect`` and ``ik`` on one configuration
  ``(n,)`` or a batch ``(N, n)`` spread over the cores;
* calibration: :func:`calibrate` (stiffness identification and structure search),
  :func:`validate`, :func:`calibrate_geometry` (elasto-geometric, absolute tracker readings),
  :func:`predict` (with set-up re-registration), :func:`register` (a new session or probe
  from a few readings), :func:`import_ur10_tracker`;
* compensation: :func:`compensate` and its robot programs (KRL, RAPID, VAL3, URScript, G-code);
* the twin: :func:`deflex.sim.form` (SIMULATED forming runs, open or closed loop) and logs:
  :func:`read_log`.

SI units everywhere (m, rad, N, N·m); errors are :class:`DeflexError` subclasses carrying the
CLI's messages.
"""

from __future__ import annotations

from . import sim
from ._deflex import (
    Compensation,
    GeometryCalibration,
    Prediction,
    Registration,
    Robot,
    StiffnessCalibration,
    TwinRun,
    Validation,
    __version__,
)
from ._errors import (
    CalibrationError,
    CompensationError,
    DataError,
    DeflexError,
    DeflexIOError,
    InputError,
    InputTypeError,
    InternalError,
    ModelError,
    ProgramError,
    SimulationError,
)
from .calibration import (
    AbsoluteData,
    calibrate,
    calibrate_geometry,
    import_ur10_tracker,
    predict,
    predict_displacements,
    register,
    validate,
)
from .compensation import FORMATS, compensate
from .log import Log, read_log

__all__ = [
    "Robot",
    "StiffnessCalibration",
    "Validation",
    "GeometryCalibration",
    "Prediction",
    "Registration",
    "Compensation",
    "TwinRun",
    "AbsoluteData",
    "Log",
    "calibrate",
    "validate",
    "predict_displacements",
    "calibrate_geometry",
    "predict",
    "register",
    "import_ur10_tracker",
    "compensate",
    "FORMATS",
    "read_log",
    "sim",
    "DeflexError",
    "InputError",
    "InputTypeError",
    "ModelError",
    "DataError",
    "CalibrationError",
    "CompensationError",
    "ProgramError",
    "SimulationError",
    "DeflexIOError",
    "InternalError",
    "__version__",
]
