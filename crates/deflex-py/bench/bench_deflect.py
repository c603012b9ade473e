"""Benchmark (not a test): TCP deflection of 100 000 random TX200 configurations under one
wrench, δs = J_e K_θ⁻¹ J_eᵀ w (eq. 15), three ways side by side in one run:

1. deflex-Python, one batched call ``robot.deflect(q, w)`` (Rust, GIL released, rayon);
2. deflex-Python, a Python loop of single calls ``robot.deflect(q[i], w)``;
3. Pinocchio's Python bindings (``pip install pin``), per configuration: the TX200 built in
   Pinocchio from the same modified-DH table (the J3.x eDoF as a virtual revolute joint at its
   400 mm shifted centre), ``computeJointJacobians`` + ``updateFramePlacements`` +
   ``getFrameJacobian(LOCAL_WORLD_ALIGNED)`` at the TCP, then the compliance product
   ``C = J_e K⁻¹ J_eᵀ`` and ``C w`` in numpy.

The three agree to ~1e-12 m (printed). Run: ``python bench/bench_deflect.py [N]``. Prints a
Markdown table and the machine's load (the numbers depend on what else runs).
"""

from __future__ import annotations

import math
import os
import platform
import statistics
import sys
import time
from typing import Any, Callable, List, Tuple

import numpy as np

import deflex

N = int(sys.argv[1]) if len(sys.argv) > 1 else 100_000
WRENCH = np.array([150.0, -300.0, -1200.0, 10.0, -5.0, 2.0])


def timed(f: Callable[[], Any], repeat: int) -> Tuple[List[float], Any]:
    times, out = [], None
    for _ in range(repeat):
        t = time.perf_counter()
        out = f()
        times.append(time.perf_counter() - t)
    return times, out


def pinocchio_tx200() -> Tuple[Any, Any, int, List[int], np.ndarray]:
    """The TX200 of crates/deflex-model/robots/tx200.toml in Pinocchio: returns model, data, TCP frame id, the
    velocity indices of the eDoFs and their compliances 1/k."""
    import pinocchio as pin  # type: ignore[import-not-found,unused-ignore]

    robot = deflex.Robot.builtin("tx200")
    # The modified DH table of crates/deflex-model/robots/tx200.toml: (alpha, a, d, theta_offset).
    rows = [
        (0.0, 0.0, 0.0, 0.0),
        (-math.pi / 2, 0.250, 0.0, -math.pi / 2),
        (0.0, 0.950, 0.0, -math.pi / 2),
        (-math.pi / 2, 0.0, 0.800, 0.0),
        (math.pi / 2, 0.0, 0.0, 0.0),
        (-math.pi / 2, 0.0, 0.194, math.pi),
    ]
    shift3 = 0.400  # δr3: the J3.x spring's centre slides 400 mm along z3

    def rx(a: float) -> np.ndarray:
        return np.array(pin.utils.rotate("x", a))

    def rz(a: float) -> np.ndarray:
        return np.array(pin.utils.rotate("z", a))

    model = pin.Model()
    parent = 0
    edof_v: List[int] = []
    for i, (alpha, a, d, off) in enumerate(rows, start=1):
        # Craig: RotX(α)·TransX(a)·RotZ(θ+off)·TransZ(d) = RotX(α)·TransX(a)·TransZ(d)·RotZ(off)·RotZ(θ).
        rot = rx(alpha) @ rz(off)
        trans = rx(alpha) @ np.array([a, 0.0, d])
        placement = pin.SE3(rot, trans)
        if i == 4:
            placement = pin.SE3(np.eye(3), np.array([0.0, 0.0, -shift3])) * placement
        parent = model.addJoint(parent, pin.JointModelRZ(), placement, f"joint_{i}")
        if i == 3:
            # The J3.x eDoF: a virtual revolute joint about x3 through O3 + δr3·z3, held at 0.
            parent = model.addJoint(parent, pin.JointModelRX(), pin.SE3(np.eye(3), np.array([0.0, 0.0, shift3])), "edof_3x")
    tcp = model.addFrame(pin.Frame("tcp", parent, 0, pin.SE3.Identity(), pin.FrameType.OP_FRAME))
    # Velocity index of each eDoF, in deflex's order J1.z J2.z J3.x J3.z J4.z J5.z.
    names = {"J1.z": "joint_1", "J2.z": "joint_2", "J3.x": "edof_3x", "J3.z": "joint_3", "J4.z": "joint_4", "J5.z": "joint_5"}
    for label in robot.edofs:
        edof_v.append(model.joints[model.getJointId(names[label])].idx_v)
    compliance = 1.0 / robot.stiffness
    return model, model.createData(), tcp, edof_v, compliance


def main() -> None:
    robot = deflex.Robot.builtin("tx200")
    rng = np.random.default_rng(1)
    lim = robot.limits
    q = rng.uniform(lim[:, 0], lim[:, 1], size=(N, 6))

    # Warm up (rayon pool, caches), then time the batch.
    robot.deflect(q[:1000], WRENCH)
    batch_times, batch = timed(lambda: robot.deflect(q, WRENCH), 15)

    loop_n = N
    loop_times, loop_out = timed(lambda: np.array([robot.deflect(q[i], WRENCH) for i in range(loop_n)]), 1)
    loop_diff = float(np.abs(loop_out - batch[:loop_n]).max())

    pin_row: Tuple[str, str, str, str] = ("Pinocchio-Python loop (pin)", "not installed", "", "")
    pin_s = math.nan
    try:
        import pinocchio as pin  # type: ignore[import-not-found,unused-ignore]

        model, data, tcp, cols, kinv = pinocchio_tx200()

        def pin_loop() -> np.ndarray:
            out = np.empty((N, 6))
            qv = np.zeros(model.nq)
            for i in range(N):
                qv[[0, 1, 2]] = q[i, :3]
                qv[4:] = q[i, 3:]
                pin.computeJointJacobians(model, data, qv)
                pin.updateFramePlacements(model, data)
                j = pin.getFrameJacobian(model, data, tcp, pin.LOCAL_WORLD_ALIGNED)[:, cols]
                c = (j * kinv) @ j.T
                out[i] = c @ WRENCH
            return out

        pin_times, pin_out = timed(pin_loop, 1)
        pin_s = pin_times[0]
        pin_diff = float(np.abs(pin_out - batch).max())
        pin_row = (
            f"Pinocchio {pin.__version__} Python loop (computeJointJacobians + C = J K⁻¹ Jᵀ)",
            f"{pin_s * 1e3:.0f} ms",
            f"{pin_s / N * 1e6:.2f} µs",
            f"{pin_diff:.1e} m",
        )
    except ImportError:
        pass

    best = min(batch_times)
    median = statistics.median(batch_times)
    load = os.getloadavg() if hasattr(os, "getloadavg") else (math.nan,) * 3
    print(f"TX200, {N} random configurations within the joint limits, one wrench; deflex {deflex.__version__}, "
          f"numpy {np.__version__}, Python {platform.python_version()}, {os.cpu_count()} cores, "
          f"load average {load[0]:.1f} / {load[1]:.1f} / {load[2]:.1f}")
    print()
    print("| method | time for all | per configuration | max difference to the batch |")
    print("| --- | --- | --- | --- |")
    print(f"| deflex-Python batch `robot.deflect(q, w)` (best / median of 15) | {best * 1e3:.1f} / {median * 1e3:.1f} ms | {best / N * 1e9:.0f} ns | – |")
    print(f"| deflex-Python loop of single calls | {loop_times[0] * 1e3:.0f} ms | {loop_times[0] / loop_n * 1e6:.2f} µs | {loop_diff:.1e} m |")
    print(f"| {pin_row[0]} | {pin_row[1]} | {pin_row[2]} | {pin_row[3]} |")
    print()
    if not math.isnan(pin_s):
        print(f"batch vs Pinocchio loop: {pin_s / best:.0f}× (best), {pin_s / median:.0f}× (median)")
    print(f"batch vs single-call loop: {loop_times[0] / best:.0f}×")


if __name__ == "__main__":
    main()
