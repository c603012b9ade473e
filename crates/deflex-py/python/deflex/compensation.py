"""Offline compensation (``deflex compensate``): the commanded path that puts the tool on the
desired one once the robot has deflected under the process wrenches, and robot programs for
KUKA (KRL), ABB (RAPID), Stäubli (VAL3), UR (URScript) and G-code."""

from __future__ import annotations

import os
from typing import Any, List, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

from . import _deflex
from ._deflex import Compensation, Robot

__all__ = ["compensate", "FORMATS"]

#: The program formats: KUKA KRL, ABB RAPID, Stäubli VAL3, UR URScript, G-code, FANUC TP (.ls),
#: Yaskawa INFORM (.JBI).
FORMATS = ("krl", "rapid", "val3", "urscript", "gcode", "fanuc", "inform")

PathLike = Union[str, "os.PathLike[str]"]


def compensate(
    robot: Union[Robot, PathLike],
    path: Union[PathLike, npt.ArrayLike] = "cone",
    *,
    wrench: Union[PathLike, npt.ArrayLike] = "process",
    frame: str = "part",
    feed_m_s: Optional[float] = None,
    twin_config: Optional[PathLike] = None,
    part_xyz_m: Optional[Sequence[float]] = None,
    seed_q: Optional[Sequence[float]] = None,
    length_m: Optional[float] = None,
    max_segment_m: Optional[float] = None,
    position_only: bool = False,
    include_gravity: bool = False,
    tolerance_m: float = 1e-6,
    max_iterations: int = 30,
    log_forces: str = "auto",
) -> Compensation:
    """Compensate a tool path for the deflection ``robot`` predicts (eq. 15) under the process
    wrenches, iterating until the commanded path changes by less than ``tolerance_m``
    (``tolerance_m`` rad for the orientation).

    ``path`` is ``"cone"``, ``"cone-contour"``, ``"pyramid"``, a G-code file (part frame, mm), or
    an array: ``(N, 3)`` TCP positions (m; the tool keeps the orientation of ``seed_q``) or
    ``(N, 6)`` poses ``[x, y, z, rx, ry, rz]`` (m, rotation vector in rad), in the part frame
    (``frame="part"``, placed at ``part_xyz_m``, default the twin cell's) or the robot's world
    frame (``frame="world"``); array moves run at ``feed_m_s`` (None: rapids).

    ``wrench`` is ``"process"`` (the twin's forming model, SIMULATED), ``"log:FILE"`` or a log
    path (a ``deflex run`` or ``deflex sim isf`` log of a previous run of this path, resampled on
    arc length), or an array of wrenches (world axes at the TCP, N and N·m): ``(6,)`` for every
    point or ``(N, 6)``, one per point.

    With a log, ``log_forces`` says what it gives: ``"auto"`` (default) the force–depth law
    identified from the log when the log supports it as a cause (the commanded depth explains
    the held-out force at least as well as the path position, the loop gain is below 0.8, the
    force does not fall with depth), else the logged wrenches by path position; ``"law"`` the
    law whatever the evidence; ``"fixed"`` the logged wrenches. Which and why is in
    ``to_dict()["log_law"]``. A law whose iteration does not converge falls back
    to the logged wrenches with a warning in the source lines.

    Points that cannot be compensated (limits, reach) keep their desired pose and are named in
    ``status``; ``program()`` and ``write_programs()`` then refuse, as the CLI does."""
    result: Compensation = _deflex._compensate(
        robot,
        os.fspath(path) if isinstance(path, os.PathLike) else path,
        os.fspath(wrench) if isinstance(wrench, os.PathLike) else wrench,
        frame,
        feed_m_s,
        None if twin_config is None else os.fspath(twin_config),
        None if part_xyz_m is None else _three(part_xyz_m, "part_xyz_m"),
        None if seed_q is None else [float(v) for v in seed_q],
        length_m,
        max_segment_m,
        position_only,
        include_gravity,
        tolerance_m,
        max_iterations,
        log_forces,
    )
    return result


def _three(values: Any, name: str) -> List[float]:
    from ._errors import InputError

    v = [float(x) for x in values]
    if len(v) != 3:
        raise InputError(f"{name}: expected 3 values (x, y, z in m), got {len(v)}")
    return v
