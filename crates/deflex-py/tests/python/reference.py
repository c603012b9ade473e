"""An independent numpy reference of the elasto-geometrical model, written from the robot
file's DH table and the paper's definitions, sharing no code with deflex:

* forward kinematics as the textbook product of DH matrices (modified: Craig's
  ``RotX(α)·TransX(a)·RotZ(θ)·TransZ(d)``; standard: ``RotZ(θ)·TransZ(d)·TransX(a)·RotX(α)``);
* the joint Jacobian by central finite differences of that chain;
* the eDoF Jacobian by central finite differences of a small rotation inserted into the chain
  about each spring's axis through its shifted centre (the Virtual Joint Method's definition),
  and ``C = J_e K⁻¹ J_eᵀ``, ``δs = C w`` (eq. 15).
"""

from __future__ import annotations

import math
import sys
from pathlib import Path
from typing import Any, Dict, List, Tuple

import numpy as np

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

ROBOTS = Path(__file__).resolve().parents[3] / "deflex-model" / "robots"


def rot(axis: str, angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    m = np.eye(4)
    if axis == "x":
        m[1:3, 1:3] = [[c, -s], [s, c]]
    elif axis == "y":
        m[0, 0], m[0, 2], m[2, 0], m[2, 2] = c, s, -s, c
    else:
        m[0:2, 0:2] = [[c, -s], [s, c]]
    return m


def trans(x: float, y: float, z: float) -> np.ndarray:
    m = np.eye(4)
    m[:3, 3] = [x, y, z]
    return m


def rpy_matrix(rpy: List[float]) -> np.ndarray:
    return rot("z", rpy[2]) @ rot("y", rpy[1]) @ rot("x", rpy[0])


def log_so3(r: np.ndarray) -> np.ndarray:
    """Rotation vector of a rotation matrix (small and moderate angles)."""
    cos = max(-1.0, min(1.0, (np.trace(r) - 1.0) / 2.0))
    angle = math.acos(cos)
    w = np.array([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]]) / 2.0
    if angle < 1e-12:
        return w
    return w * angle / math.sin(angle)


class ReferenceRobot:
    """The robot of a DH robot file, computed the textbook way."""

    def __init__(self, name: str) -> None:
        with open(ROBOTS / f"{name}.toml", "rb") as f:
            spec: Dict[str, Any] = tomllib.load(f)
        self.standard = spec.get("dh", "modified") == "standard"
        self.rows = spec["joint"]
        tool = spec.get("tool", {})
        self.tool = trans(*tool.get("xyz", [0.0, 0.0, 0.0])) @ rpy_matrix(tool.get("rpy", [0.0, 0.0, 0.0]))
        flange = spec.get("flange", {})
        self.flange = trans(*flange.get("xyz", [0.0, 0.0, 0.0])) @ rpy_matrix(flange.get("rpy", [0.0, 0.0, 0.0]))
        base = spec.get("base", {})
        self.base = trans(*base.get("xyz", [0.0, 0.0, 0.0])) @ rpy_matrix(base.get("rpy", [0.0, 0.0, 0.0]))
        # Springs: (joint index 1.., axis letter, stiffness, centre shift along z_i).
        self.springs: List[Tuple[int, str, float, float]] = []
        for i, row in enumerate(self.rows, start=1):
            for axis in "xyz":
                k = row.get("stiffness", {}).get(axis)
                if k is not None:
                    self.springs.append((i, axis, float(k), float(row.get("center_shift", 0.0))))
        self.n = len(self.rows)

    def _frames(self, q: np.ndarray, spring: Tuple[int, str, float] | None = None) -> np.ndarray:
        """TCP pose; with ``spring = (i, axis, ε)`` a rotation ε about the spring's axis through
        its centre is inserted after joint frame i."""
        t = self.base.copy()
        for i, (row, qi) in enumerate(zip(self.rows, q), start=1):
            theta = qi + row.get("theta_offset", 0.0)
            if self.standard:
                # The joint frame R_i is after RotZ·TransZ; the link's TransX·RotX follows.
                t = t @ rot("z", theta) @ trans(0, 0, row["d"])
                joint_frame_end = trans(row["a"], 0, 0) @ rot("x", row["alpha"])
            else:
                t = t @ rot("x", row["alpha"]) @ trans(row["a"], 0, 0) @ rot("z", theta) @ trans(0, 0, row["d"])
                joint_frame_end = np.eye(4)
            if spring is not None and spring[0] == i:
                shift = self._shift(i)
                t = t @ trans(0, 0, shift) @ rot(spring[1], spring[2]) @ trans(0, 0, -shift)
            t = t @ joint_frame_end
        return t @ self.flange @ self.tool

    def _shift(self, i: int) -> float:
        return float(self.rows[i - 1].get("center_shift", 0.0))

    def pose(self, q: np.ndarray) -> np.ndarray:
        return self._frames(np.asarray(q, dtype=float))

    @staticmethod
    def _twist(a: np.ndarray, b: np.ndarray, h: float) -> np.ndarray:
        """[δp; δφ] from pose a to pose b over 2h (world axes)."""
        dp = (b[:3, 3] - a[:3, 3]) / (2 * h)
        dphi = log_so3(b[:3, :3] @ a[:3, :3].T) / (2 * h)
        return np.concatenate([dp, dphi])

    def jacobian(self, q: np.ndarray, h: float = 1e-6) -> np.ndarray:
        q = np.asarray(q, dtype=float)
        cols = []
        for j in range(self.n):
            e = np.zeros(self.n)
            e[j] = h
            cols.append(self._twist(self.pose(q - e), self.pose(q + e), h))
        return np.column_stack(cols)

    def edof_jacobian(self, q: np.ndarray, h: float = 1e-6) -> np.ndarray:
        q = np.asarray(q, dtype=float)
        cols = []
        for i, axis, _, _ in self.springs:
            a = self._frames(q, (i, axis, -h))
            b = self._frames(q, (i, axis, h))
            cols.append(self._twist(a, b, h))
        return np.column_stack(cols)

    def compliance(self, q: np.ndarray) -> np.ndarray:
        j = self.edof_jacobian(q)
        k_inv = np.diag([1.0 / k for _, _, k, _ in self.springs])
        return j @ k_inv @ j.T

    def deflect(self, q: np.ndarray, wrench: np.ndarray) -> np.ndarray:
        return self.compliance(q) @ np.asarray(wrench, dtype=float)
