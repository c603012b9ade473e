"""Offline compensation from arrays, G-code and logs, checked with the independent reference:
the robot at the commanded joints, deflected by the reference's C(q)·w, must put the tool on
the desired path; the five program formats; the CLI's refusals."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import deflex
from reference import ReferenceRobot, log_so3

W = np.array([150.0, -250.0, 1100.0, 0.0, 0.0, 0.0])


def square(side_m: float = 0.03, step_m: float = 0.002) -> np.ndarray:
    k = int(round(side_m / step_m))
    edge = np.linspace(0, side_m, k + 1)
    xs = np.concatenate([edge, np.full(k, side_m), edge[::-1][1:], np.zeros(k)])
    ys = np.concatenate([np.zeros(k + 1), edge[1:], np.full(k, side_m), edge[::-1][1:]])
    return np.column_stack([xs, ys, np.full(xs.size, -0.002)])


def test_an_array_path_under_given_wrenches_lands_on_the_desired_path() -> None:
    ref = ReferenceRobot("tx200")
    path = square()
    comp = deflex.compensate("tx200", path, wrench=W, feed_m_s=0.02, tolerance_m=1e-8)
    assert comp.converged and set(comp.status) == {"ok"} and len(comp) == len(path)
    # One tool per cell: the built-in file has none, the compensation uses the TX200 cell's
    # 200 mm forming tool (as the twin does), and says so.
    summary = comp.to_dict()
    assert summary["tool_xyz_m"] == [0.0, 0.0, 0.2] and "forming tool" in summary["tool"]
    ref.tool = np.eye(4)
    ref.tool[2, 3] = 0.2
    assert comp.desired.shape == (len(path), 3)
    # The part frame sits at the cell's [1500, 0, −183] mm.
    np.testing.assert_allclose(comp.desired, path + [1.5, 0.0, -0.183], atol=1e-12)
    for i in range(0, len(path), 5):
        q = comp.q[i]
        commanded = ref.pose(q)
        np.testing.assert_allclose(commanded, comp.commanded_poses[i], atol=1e-9)
        d = ref.deflect(q, comp.wrench[i])
        reached = commanded[:3, 3] + d[:3]
        np.testing.assert_allclose(reached, comp.desired[i], atol=2e-8)
        # Orientation compensated too: the deflected tool keeps the desired orientation.
        desired_rotation = deflex.Robot.builtin("tx200").pose(np.radians([0, 49.7, 89.3, 0, 41, 0]))[:3, :3]
        rotated = log_so3(desired_rotation.T @ commanded[:3, :3]) + desired_rotation.T @ d[3:]
        assert np.abs(rotated).max() < 1e-7
    np.testing.assert_allclose(comp.wrench, np.tile(W, (len(path), 1)))
    summary = comp.to_dict()
    assert summary["simulated"] is False and summary["final_max_predicted_error_m"] < 1e-7
    # (N, 6) poses in the world frame, one wrench per point, position only.
    poses = np.column_stack([comp.desired, np.zeros((len(path), 3))])
    poses[:, 3] = np.pi  # tool pointing down: a half turn about x
    per_point = np.tile(W, (len(path), 1)) * np.linspace(0.5, 1.0, len(path))[:, None]
    comp2 = deflex.compensate("tx200", poses, wrench=per_point, frame="world", position_only=True)
    assert comp2.converged
    np.testing.assert_allclose(comp2.wrench, per_point)
    assert np.abs(comp2.compensation[:, 3:]).max() == 0.0


def test_a_gcode_part_with_the_process_model_and_the_five_programs(tmp_path: Path) -> None:
    gcode = tmp_path / "part.gcode"
    # Each step down ramps along the first side, as incremental forming enters a level (a
    # vertical plunge at a corner, under the TX200 cell's 200 mm tool, leaves one point
    # oscillating between contact and none: that compensation is refused as not converged).
    lines = ["G21", "G90", "G0 X0 Y0 Z5", "G1 Z0 F600"]
    for k in range(1, 4):
        z = -0.5 * k
        lines += [f"G1 X20 Y0 Z{z} F1200", "G1 X20 Y20", "G1 X0 Y20", "G1 X0 Y0"]
    gcode.write_text("\n".join(lines) + "\n")
    comp = deflex.compensate("tx200", gcode, wrench="process", max_segment_m=0.002)
    assert comp.simulated and comp.converged, comp
    assert "SIMULATED" in comp.to_csv().splitlines()[0]
    out = tmp_path / "compensated_path.csv"
    comp.save(out)
    table = deflex.read_log(out)
    np.testing.assert_allclose(table["dz_m"], comp.compensation[:, 2], atol=1e-9)
    for fmt in deflex.FORMATS:
        files = comp.program(fmt)
        assert files and all(text for text in files.values()), fmt
    written = comp.write_programs(tmp_path / "programs")
    names = {Path(p).name for p in written}
    assert {"deflex_path.src", "deflex_path.mod", "deflex_path.script", "deflex_path.gcode"} <= names
    assert "/PROG  DEFLEX_PATH" in comp.program("fanuc")["DEFLEX_PATH.ls"]
    assert "//NAME DEFLEX_PATH\r\n" in comp.program("inform")["DEFLEX_PATH.JBI"]
    with pytest.raises(deflex.InputError, match='unknown format "yaskawa"'):
        comp.program("yaskawa")


def test_points_beyond_a_joint_limit_are_named_and_no_program_is_written(tmp_path: Path) -> None:
    path = square(0.02, 0.004)
    free = deflex.compensate("tx200", path, wrench=W)
    lo, hi = free.q[:, 2].min(), free.q[:, 2].max()
    text = deflex.Robot.builtin("tx200").to_toml()
    # Joint 3 stopped just around the uncompensated joint values: the compensation needs more.
    nominal = deflex.compensate("tx200", path, wrench=np.zeros(6))
    q3 = nominal.q[:, 2]
    tight = text.replace("limits = [-2.5307, 2.5307]", f"limits = [{float(q3.min()) - 1e-6!r}, {float(q3.max()) + 1e-6!r}]")
    assert tight != text and (lo < q3.min() - 1e-6 or hi > q3.max() + 1e-6)
    robot = deflex.Robot.from_toml(tight)
    comp = deflex.compensate(robot, path, wrench=W)
    failed = [s for s in comp.status if s != "ok"]
    assert failed and all(s == "compensated:joint_limit:J3" for s in failed)
    with pytest.raises(deflex.CompensationError, match=r"(?s)cannot be compensated.*point \d+: .*joint 3"):
        comp.program("krl")
    assert not (tmp_path / "programs").exists()


def test_a_twin_log_serves_as_the_wrench_source(tmp_path: Path) -> None:
    run = deflex.sim.form("cone", length_m=0.2)
    run.save(tmp_path / "open")
    comp = deflex.compensate("tx200", "cone", wrench=f"log:{tmp_path / 'open' / 'log.csv'}", length_m=0.15)
    assert comp.simulated and "SIMULATED deflex sim isf log" in comp.source
    assert np.abs(comp.wrench[:, 2]).max() > 10.0
    # The default (log_forces="auto") says whether the log's force-depth law was used and why.
    law = comp.to_dict()["log_law"]
    assert law["decision"] in ("chosen", "rejected") and law["reason"]
    assert law["evidence"] is None or "r2_commanded_depth" in law["evidence"]
    fixed = deflex.compensate(
        "tx200", "cone", wrench=f"log:{tmp_path / 'open' / 'log.csv'}", length_m=0.15, log_forces="fixed"
    )
    assert fixed.to_dict()["log_law"] is None
    with pytest.raises(deflex.InputError, match="log_forces"):
        deflex.compensate("tx200", "cone", wrench=f"log:{tmp_path / 'open' / 'log.csv'}", log_forces="maybe")


def test_compensation_options_are_checked() -> None:
    path = square()
    with pytest.raises(deflex.InputError, match="wrench: expected \"process\""):
        deflex.compensate("tx200", path, wrench="sensor")
    with pytest.raises(deflex.InputError, match="3 wrenches for the"):
        deflex.compensate("tx200", path, wrench=np.zeros((3, 6)))
    with pytest.raises(deflex.InputError, match="tolerance_m"):
        deflex.compensate("tx200", path, wrench=W, tolerance_m=0.0)
    with pytest.raises(deflex.InputError, match="max_iterations"):
        deflex.compensate("tx200", path, wrench=W, max_iterations=0)
    with pytest.raises(deflex.InputError, match="seed_q: robot .* has 6 joints, 3 values given"):
        deflex.compensate("tx200", path, wrench=W, seed_q=[0, 1, 2])
    with pytest.raises(deflex.InputError, match=r"path: expected shape \(N, 3\)"):
        deflex.compensate("tx200", np.zeros((5, 4)), wrench=W)
    with pytest.raises(deflex.InputError, match=r"path\[2, 1\] is NaN"):
        bad = path.copy()
        bad[2, 1] = np.nan
        deflex.compensate("tx200", bad, wrench=W)
    with pytest.raises(deflex.SimulationError, match="part.gcode"):
        deflex.compensate("tx200", "/nonexistent/part.gcode")
    with pytest.raises(deflex.InputError, match="frame"):
        deflex.compensate("tx200", path, wrench=W, frame="tool")
