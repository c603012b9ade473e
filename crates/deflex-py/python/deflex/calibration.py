"""Calibration from Python: stiffness identification with structure search
(``deflex calibrate``), validation (``deflex validate``), elasto-geometric calibration from
absolute tracker readings (``deflex calibrate-geometry``), per-row prediction and set-up
re-registration (``deflex predict [--fit-setup]``), registration of a new session or probe
from a few readings (``deflex register``), and the UR10 tracker importer. Data is a
CSV path, a pandas DataFrame or a mapping of columns in the CLI's formats (column names with
units: ``q1_rad``, ``fz_N``, ``dx_m``…); the checks and messages are the CLI's."""

from __future__ import annotations

import os
from typing import Any, Dict, List, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

from . import _deflex
from ._deflex import (
    GeometryCalibration,
    Prediction,
    Registration,
    Robot,
    StiffnessCalibration,
    Validation,
)
from ._tables import Source, Table, source, sources
from .log import Log

__all__ = [
    "calibrate",
    "validate",
    "predict_displacements",
    "calibrate_geometry",
    "predict",
    "register",
    "import_ur10_tracker",
    "AbsoluteData",
]

RobotLike = Union[Robot, str, "os.PathLike[str]"]
CalibratedLike = Union[GeometryCalibration, Robot, str, "os.PathLike[str]"]
DEFAULT_ORIENTATION_SIGMA_RAD = 1e-4


def calibrate(
    robot: RobotLike,
    data: Table,
    *,
    structure: str = "auto",
    fit_shifts: bool = False,
    criterion: str = "bic",
    folds: int = 5,
    min_cv_gain: float = 0.02,
    target_rms_m: Optional[float] = None,
    min_bic_gain: float = 10.0,
    allow_base: bool = True,
    fk_tolerance_m: float = 1e-3,
    ignore_fk_check: bool = False,
) -> StiffnessCalibration:
    """Identify the VJM stiffness model from loaded-minus-unloaded displacements
    (``deflex calibrate``).

    ``robot`` is the start model (a :class:`Robot`, a built-in name or a robot file): its
    geometry, and with ``structure="fixed"`` its eDoFs and centre shifts. ``data`` is the
    measurement table (CSV path, DataFrame or mapping of columns; columns ``load_case``,
    ``q1_rad…``, ``fx_N…``, ``load_link``, ``load_x_m…``, ``point``, ``point_link``, ``x_m…``,
    ``dx_m…``). Every row is first checked against the forward kinematics within
    ``fk_tolerance_m`` (a file of another robot is refused naming its rows; ``ignore_fk_check``
    goes on with a warning). ``structure="auto"`` grows the structure from one z-eDoF per joint
    by BIC (``criterion="bic"``) or by the held-out χ² of ``folds``-fold cross-validation by load
    case (``criterion="cv"``, a refinement must gain ``min_cv_gain``), stopping at
    ``target_rms_m`` when given. Raises :class:`deflex.CalibrationError` when nothing is
    identifiable, :class:`deflex.DataError` for a bad table, :class:`deflex.InputError` for bad
    options."""
    result: StiffnessCalibration = _deflex._calibrate(
        robot,
        source(data),
        structure,
        fit_shifts,
        criterion,
        folds,
        min_cv_gain,
        target_rms_m,
        min_bic_gain,
        allow_base,
        fk_tolerance_m,
        ignore_fk_check,
    )
    return result


def validate(
    robot: RobotLike,
    data: Table,
    *,
    baseline: Optional[RobotLike] = None,
    fk_tolerance_m: float = 1e-3,
    ignore_fk_check: bool = False,
) -> Validation:
    """Prediction errors (measured − predicted) of ``robot`` on measured displacements, beside
    a ``baseline`` model when given (``deflex validate``), after the same file check as
    :func:`calibrate`."""
    result: Validation = _deflex._validate(
        robot, source(data), baseline, fk_tolerance_m, ignore_fk_check
    )
    return result


def predict_displacements(robot: RobotLike, data: Table) -> npt.NDArray[np.float64]:
    """Predicted ``[δx, δy, δz, δφx, δφy, δφz]`` (m, rad) of every row of a measurement or plan
    table (the point's displacement under the row's load), shape ``(N, 6)``."""
    result: npt.NDArray[np.float64] = _deflex._predict_displacements(robot, source(data))
    return result


class AbsoluteData:
    """Absolute tracker readings in the CLI's absolute CSV format (``setup``, ``target``,
    ``q1_rad…``, ``x_m, y_m, z_m``…), as :func:`import_ur10_tracker` makes them: pass it
    wherever a table is taken; ``save(path)`` writes the CSV the CLI would."""

    def __init__(self, text: str, summary: Dict[str, Any], name: str) -> None:
        self.text = text
        self.summary = summary
        self.name = name

    def to_csv(self, index: bool = False, lineterminator: str = "\n", float_format: Any = None) -> str:
        """The CSV text (comments first)."""
        return self.text

    @property
    def columns(self) -> Dict[str, Any]:
        """The readings as columns (numpy arrays; text columns of dtype object)."""
        return self.table().columns

    def table(self) -> Log:
        """The readings as a :class:`deflex.Log`."""
        result: Log = _deflex._parse_table(self.text, self.name)
        return result

    def __len__(self) -> int:
        return int(self.summary.get("rows_written", 0))

    def save(self, path: Union[str, "os.PathLike[str]"]) -> None:
        """Write the CSV to ``path``."""
        tmp = os.fspath(path) + ".tmp-deflex"
        with open(tmp, "w", encoding="utf-8") as f:
            f.write(self.text)
        os.replace(tmp, path)

    def __repr__(self) -> str:
        return f"AbsoluteData({self.name}, {len(self)} readings)"


def import_ur10_tracker(
    series: Union[str, "os.PathLike[str]"],
    *,
    setup: str,
    target: str = "tmac",
    tracker_sigma: bool = False,
    every: int = 1,
) -> AbsoluteData:
    """Read a series of the public UR10 laser-tracker data set (Landgraf et al., CASE 2021;
    a series folder or its ``measurements_*.csv``) into the absolute measurement format, as
    ``deflex import ur10-tracker``: every row labelled with set-up ``setup`` and target
    ``target``, every ``every``-th reading kept, the tracker's per-reading σ in ``sigma_m`` when
    ``tracker_sigma``."""
    text, summary = _deflex._import_ur10_tracker(os.fspath(series), setup, target, tracker_sigma, every)
    return AbsoluteData(text, summary, f"{os.fspath(series)} (set-up {setup})")


def _absolute_sources(
    data: Union[Table, AbsoluteData, Sequence[Union[Table, AbsoluteData]], None], name: str
) -> List[Source]:
    items: Sequence[Any]
    if data is None:
        items = []
    elif isinstance(data, (list, tuple)):
        items = data
    else:
        items = [data]
    out: List[Source] = []
    for d in items:
        if isinstance(d, AbsoluteData):
            out.append(("table", d.text, d.name))
        else:
            out.extend(sources(d, name))
    return out


def calibrate_geometry(
    robot: RobotLike,
    data: Union[Table, AbsoluteData, Sequence[Union[Table, AbsoluteData]]],
    *,
    loaded: Union[Table, Sequence[Table], None] = None,
    test_data: Union[Table, AbsoluteData, Sequence[Union[Table, AbsoluteData]], None] = None,
    steps: Union[str, Sequence[str], None] = None,
    elastic: Union[str, Sequence[str], None] = None,
    loss: str = "huber",
    folds: int = 5,
    bootstrap: int = 0,
    test_fraction: float = 0.0,
    seed: int = 1,
    orientations: bool = False,
    sigma_rad: float = DEFAULT_ORIENTATION_SIGMA_RAD,
    cv_by: Optional[str] = None,
    register_readings: int = 0,
    register_draws: int = 1,
    register_target: bool = False,
    allow_large_changes: bool = False,
) -> GeometryCalibration:
    """Elasto-geometric calibration from absolute tracker readings (``deflex
    calibrate-geometry``): DH errors with Hayati β, tracker set-up registrations, target
    offsets, gravity sag and the compliances of ``elastic`` eDoFs (e.g. ``["J2.z", "J3.z"]``;
    default all of the robot's), with ``loaded`` displacement tables fitted together.

    ``steps`` are added one after the other (``registration``, ``geometry``, ``compliance``,
    and the opt-in ``masses``, ``harmonics:N``, ``periodic:N``, ``backlash``,
    ``torsion:cubic``, ``torsion:soft:T``, ``residual``, ``joint-maps``, each kept only when
    it lowers the held-out error); by default ``registration``, ``geometry``, ``compliance``
    and, when ``cv_by`` gives groups to vote with, ``joint-maps`` (the report's first line says
    which and why); ``loss`` is ``huber``, ``cauchy`` or ``none`` (``huber:K``
    sets the threshold). ``test_fraction`` of the configurations and every ``test_data``
    reading are never fitted; a test set-up the fit has not seen gets only its own registration.
    ``folds``-fold cross-validation by configuration runs inside the fit set, ``bootstrap``
    replicates resample configurations. ``orientations`` fits the measured orientations
    (``rx_rad…``; σ ``sigma_rad`` where a row has none) with the positions. ``cv_by``
    (``"session"``, ``"setup"`` or ``"series"``: each ``data`` table one series) leaves each
    group of the fit data out in turn and registers it by the protocol: ``register_readings``
    readings drawn at random (0: every other configuration), ``register_draws`` draws, the
    target's offset too with ``register_target``. A fit that moves a length, an angle, a set-up
    or a target further than a calibration does (another robot's or another target's readings)
    is refused, naming the parameters, unless ``allow_large_changes`` (a robot file that is
    only a rough first guess). The result's ``to_dict()["steps"]`` is the
    iteration table (fit, cross-validated and held-out errors); ``save(path)`` writes the robot
    file and its terms (``NAME.terms.json``) as the CLI does."""
    step_list: Optional[List[str]]
    if steps is None:
        step_list = None
    elif isinstance(steps, str):
        step_list = [s.strip() for s in steps.split(",")]
    else:
        step_list = list(steps)
    if elastic is None:
        elastic_list: List[str] = []
    elif isinstance(elastic, str):
        elastic_list = [e.strip() for e in elastic.split(",") if e.strip()]
    else:
        elastic_list = list(elastic)
    result: GeometryCalibration = _deflex._calibrate_geometry(
        robot,
        _absolute_sources(data, "data"),
        sources(loaded, "loaded"),
        _absolute_sources(test_data, "test_data"),
        step_list,
        elastic_list,
        loss,
        folds,
        bootstrap,
        test_fraction,
        seed,
        orientations,
        sigma_rad,
        cv_by,
        register_readings,
        register_draws,
        register_target,
        allow_large_changes,
    )
    return result


def predict(
    robot: CalibratedLike,
    data: Union[Table, AbsoluteData],
    *,
    fit_setup: bool = False,
) -> Prediction:
    """Each absolute reading's predicted target position in its set-up's tracker frame with a
    calibrated robot (its ``[[setup]]`` and ``[[target]]``), and the error where measured
    (``deflex predict``). With ``fit_setup`` the registration of the readings' set-ups is fitted
    on them first (optimistic: :func:`register` registers from a few readings instead).

    ``robot`` is a :class:`GeometryCalibration`, a robot file path (its ``NAME.terms.json`` is
    used when present, as the CLI's ``--robot FILE``) or a :class:`Robot` (no joint terms)."""
    src = ("table", data.text, data.name) if isinstance(data, AbsoluteData) else source(data)
    result: Prediction = _deflex._predict(robot, src, fit_setup)
    return result


def register(
    robot: CalibratedLike,
    data: Union[Table, AbsoluteData],
    *,
    setup: Optional[str] = None,
    target: Optional[str] = None,
    orientations: bool = False,
    sigma_rad: float = DEFAULT_ORIENTATION_SIGMA_RAD,
    recalibrate_above_m: Optional[float] = None,
    allow_large_changes: bool = False,
) -> Registration:
    """Register a new measuring session (``deflex register``): the set-up ``setup`` (default:
    the one set-up the readings name; a new name is registered from scratch, a known one
    re-registered) and, with ``target``, that target's offset on the flange (a new or remounted
    probe: 3 parameters, 6 with ``orientations``), fitted on a few readings (30 recommended,
    spread over the working volume and the wrist orientations) with the calibrated robot
    frozen. Warns (``.warnings``) when the readings are too few or too close together, and when
    the residual is above ``recalibrate_above_m`` (default 1.5 × the largest held-out RMS its
    calibration recorded in its terms): the robot itself has changed. A registration that moves
    a known set-up by more than the arm's size or puts the target further from the flange than
    half of it is refused unless ``allow_large_changes``. ``.robot`` (or ``.save(path)``) is the
    updated robot for :func:`predict` and everything else.

    ``robot`` as for :func:`predict`."""
    src = ("table", data.text, data.name) if isinstance(data, AbsoluteData) else source(data)
    result: Registration = _deflex._register(
        robot, src, setup, target, orientations, sigma_rad, recalibrate_above_m, allow_large_changes
    )
    return result
