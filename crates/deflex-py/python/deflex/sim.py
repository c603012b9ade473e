"""The digital twin of the robotised forming cell (everything it produces is SIMULATED): forming
runs open or closed loop with the deflex correction controller in-process, in simulated time
(``deflex sim isf``), and the cell's robot file (``deflex sim robot``)."""

from __future__ import annotations

import os
from typing import Optional, Union

from . import _deflex
from ._deflex import Robot, TwinRun

__all__ = ["form", "cell_robot", "TwinRun"]

PathLike = Union[str, "os.PathLike[str]"]


def form(
    path: Union[str, PathLike] = "cone",
    *,
    correction: str = "off",
    model: Union[Robot, PathLike, None] = None,
    robot: Optional[PathLike] = None,
    config: Optional[PathLike] = None,
    seed: int = 1,
    length_m: Optional[float] = None,
    feed_m_s: Optional[float] = None,
    fixture_stiffness_n_m: Optional[float] = None,
) -> TwinRun:
    """Form ``path`` on the twin (SIMULATED): ``"cone"`` (the paper's helical cone),
    ``"cone-contour"``, ``"pyramid"``, ``"plunge"`` (1 mm into a stiff fixture, then 20 mm
    along x; ``fixture_stiffness_n_m`` sets the contact stiffness) or a G-code file.

    ``correction="on"`` runs the deflex correction controller (eq. 17, every 10 ms) in the loop
    with ``model``, the identified robot model (a :class:`Robot` or a robot file, never the
    twin's plant), and the cell's nominal sensor mounting and tool. ``robot`` is the arm the twin
    plays (built-in name or robot file, default the TX200), ``config`` a twin settings file
    (``[cell]`` TOML). ``length_m`` keeps only the first part of the path, ``feed_m_s`` sets the
    built-in paths' feed. The GIL is released during the run, so runs in threads proceed in
    parallel. Returns a :class:`TwinRun` (``log``, ``summary``, ``profile``, ``save(dir)``)."""
    result: TwinRun = _deflex._form(
        os.fspath(path),
        correction,
        model,
        None if robot is None else os.fspath(robot),
        None if config is None else os.fspath(config),
        seed,
        length_m,
        feed_m_s,
        fixture_stiffness_n_m,
    )
    return result


def cell_robot(robot: Optional[PathLike] = None, config: Optional[PathLike] = None) -> Robot:
    """The robot file of the simulated cell of ``robot`` (default the TX200): the robot with the
    cell's tool and base pivot, the description a user would write for that cell: the start of
    a calibration on the twin, or a correction model (``deflex sim robot``)."""
    result: Robot = _deflex._cell_robot(
        None if robot is None else os.fspath(robot),
        None if config is None else os.fspath(config),
    )
    return result
