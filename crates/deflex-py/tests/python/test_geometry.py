"""Elasto-geometric calibration, prediction and re-registration on the shipped subset of the
public UR10 laser-tracker data (crates/deflex-calibrate/tests/data/ur10-tracker). The fitted model's
readings are recomposed here in numpy — tracker set-up · flange pose · target, from the saved
robot file — and must give the fit's own error statistics."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

import deflex
from reference import rpy_matrix, trans

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib


@pytest.fixture
def series(repo: Path) -> Path:
    return repo / "crates" / "deflex-calibrate" / "tests" / "data" / "ur10-tracker"


def test_import_fit_and_recomposed_predictions(series: Path, tmp_path: Path) -> None:
    a = deflex.import_ur10_tracker(series / "Series_A", setup="A")
    assert len(a) == 298 and a.summary["rows_read"] == 298
    table = a.table()
    assert table["setup"][0] == "A" and table["q1_rad"].shape == (298,)
    cal = deflex.calibrate_geometry("ur10", a, steps="registration,geometry", folds=0)
    steps = cal.to_dict()["steps"]
    assert [s["step"] for s in steps][:2] == ["registration", "+ geometry"] or len(steps) == 2
    rms_registration = steps[0]["fit"]["rms_m"]
    rms_geometry = steps[-1]["fit"]["rms_m"]
    assert rms_geometry < rms_registration < 2e-3, steps
    assert set(cal.roles) == {"fit"} and cal.residuals.shape == (298, 3)
    assert len(cal.parameters) == len(cal.estimates) == len(cal.standard_errors)
    assert (cal.standard_errors > 0).all() and cal.covariance.shape == (len(cal.parameters),) * 2
    lo, hi = cal.intervals95.T
    assert (lo < cal.estimates).all() and (cal.estimates < hi).all()
    # Recompose every reading from the saved file: p = T_setup · F(q) · t (no compliance step:
    # no gravity sag), with deflex's FK (checked against the textbook DH chain elsewhere).
    path = tmp_path / "ur10-cal.toml"
    cal.save(path)
    with open(path, "rb") as f:
        spec = tomllib.load(f)
    setup = spec["setup"][0]
    target = np.array(spec["target"][0]["xyz"])
    t_setup = trans(*setup["xyz"]) @ rpy_matrix(setup["rpy"])
    robot = deflex.Robot.load(path)
    q = np.column_stack([table[f"q{i}_rad"] for i in range(1, 7)])
    flange = robot.pose(q) @ np.linalg.inv(robot.tool)
    p = flange[:, :3, :3] @ target + flange[:, :3, 3]
    p = p @ t_setup[:3, :3].T + t_setup[:3, 3]
    measured = np.column_stack([table["x_m"], table["y_m"], table["z_m"]])
    errors = np.linalg.norm(measured - p, axis=1)
    assert math.isclose(float(np.sqrt(np.mean(errors**2))), rms_geometry, rel_tol=1e-6)
    np.testing.assert_allclose(np.linalg.norm(cal.residuals, axis=1), errors, atol=1e-9)
    # deflex.predict gives the same errors per row.
    pred = deflex.predict(path, a)
    np.testing.assert_allclose(pred.table["error_m"], errors, atol=1e-9)
    pred.save(tmp_path / "pred.csv")
    assert deflex.read_log(tmp_path / "pred.csv")["error_m"].shape == (298,)


def test_held_out_series_and_re_registration(series: Path) -> None:
    a = deflex.import_ur10_tracker(series / "Series_A", setup="A")
    b = deflex.import_ur10_tracker(series / "Series_B", setup="B")
    cal = deflex.calibrate_geometry(
        "ur10", a, test_data=b, elastic=["J2.z", "J3.z"], folds=3, test_fraction=0.3
    )
    steps = cal.to_dict()["steps"]
    final = steps[-1]
    groups = {g["group"]: g["stats"] for g in final["held_out"]}
    assert any(k.startswith("A") for k in groups) and any(k.startswith("B") for k in groups), groups
    assert final["cv_rms_m"] is not None
    for stats in groups.values():
        assert stats["rms_m"] < 1e-3
    assert set(cal.roles) >= {"fit", "test"}
    # B's registration (fitted on its other configurations) is in the calibrated file.
    known = deflex.predict(cal.robot, b).to_dict()
    assert known["rms_m"] < 1e-3
    # The tracker moved (set-up C, unknown to the file): refused, or re-registered on the rows.
    c = deflex.import_ur10_tracker(series / "Series_B", setup="C")
    with pytest.raises(deflex.CalibrationError, match="set-up `C` is not in the robot file"):
        deflex.predict(cal.robot, c)
    reg = deflex.predict(cal.robot, c, fit_setup=True).to_dict()
    assert reg["fit_setup"] and any(s["name"] == "C" for s in reg["setups"])
    # Registered on all of its rows, C fits at least as well as B registered on the others.
    assert reg["rms_m"] <= known["rms_m"] * 1.05
    # A robot file without the target cannot predict: the CLI's message.
    with pytest.raises(deflex.CalibrationError, match="target `tmac` is not in the robot file"):
        deflex.predict("ur10", c, fit_setup=True)


def test_geometry_options_are_checked(series: Path) -> None:
    a = deflex.import_ur10_tracker(series / "Series_A", setup="A", every=10)
    with pytest.raises(deflex.InputError, match="steps: unknown step"):
        deflex.calibrate_geometry("ur10", a, steps="registration,wobble")
    with pytest.raises(deflex.InputError, match="loss: expected huber"):
        deflex.calibrate_geometry("ur10", a, loss="l1")
    with pytest.raises(deflex.CalibrationError, match="J9.z"):
        deflex.calibrate_geometry("ur10", a, elastic="J9.z")
    with pytest.raises(deflex.InputError, match="every"):
        deflex.import_ur10_tracker(series / "Series_A", setup="A", every=0)
    with pytest.raises(deflex.DataError):
        deflex.import_ur10_tracker(series / "nowhere", setup="A")


def test_another_robots_geometry_is_refused_unless_allowed(series: Path) -> None:
    a = deflex.import_ur10_tracker(series / "Series_A", setup="A", every=4)
    with pytest.raises(deflex.CalibrationError, match="look like another robot") as refused:
        deflex.calibrate_geometry("tx200", a, folds=0)
    assert "allowed with allow_large_changes=True; nothing written" in str(refused.value)
    assert "check robot= and the targets" in str(refused.value)
    try:
        deflex.calibrate_geometry("tx200", a, folds=0, allow_large_changes=True)
    except deflex.CalibrationError as e:  # only the residual guard may still refuse
        assert "these are not this robot's readings" in str(e)
    own = deflex.calibrate_geometry("ur10", a, folds=0)
    assert own.report().startswith("default steps: registration, geometry, compliance;")
    assert own.to_dict()["default_steps"].startswith("default steps")


def test_register_a_new_session_from_a_few_readings(series: Path, tmp_path: Path) -> None:
    """``deflex register`` from Python: the calibration saved with its terms, then set-up B
    registered from 30 of its readings with the robot frozen. The registered set-up is checked by
    recomposing those readings in numpy from the updated robot file (set-up · flange · target,
    no compliance step: no gravity sag) and by scoring B's other readings with it."""
    a = deflex.import_ur10_tracker(series / "Series_A", setup="A")
    b = deflex.import_ur10_tracker(series / "Series_B", setup="B")
    cal = deflex.calibrate_geometry("ur10", a, steps="registration,geometry", folds=0)
    calibrated = tmp_path / "ur10-cal.toml"
    cal.save(calibrated)
    assert (tmp_path / "ur10-cal.terms.json").is_file()
    table = b.table()
    n = len(table["setup"])
    rng = np.random.default_rng(7)
    pick = np.sort(rng.choice(n, size=30, replace=False))
    columns = {name: table[name][pick] for name in table.names}
    reg = deflex.register(calibrated, columns)
    assert reg.setup == "B" and reg.target is None and reg.readings == 30
    assert len(reg.parameters) == 6 == len(reg.estimates) == len(reg.standard_errors)
    assert (reg.standard_errors > 0).all()
    assert "Registered set-up `B`" in reg.report()
    d = reg.to_dict()
    assert d["setup"] == "B" and d["readings"] == 30 and math.isclose(d["position_m"]["rms"], reg.rms_m)
    out = tmp_path / "today.toml"
    reg.save(out)
    assert (tmp_path / "today.terms.json").read_text() == (tmp_path / "ur10-cal.terms.json").read_text()
    with open(out, "rb") as f:
        spec = tomllib.load(f)
    setup = next(s for s in spec["setup"] if s["name"] == "B")
    target = np.array(spec["target"][0]["xyz"])
    t_setup = trans(*setup["xyz"]) @ rpy_matrix(setup["rpy"])
    robot = deflex.Robot.load(out)
    q = np.column_stack([table[f"q{i}_rad"] for i in range(1, 7)])
    flange = robot.pose(q) @ np.linalg.inv(robot.tool)
    p = flange[:, :3, :3] @ target + flange[:, :3, 3]
    p = p @ t_setup[:3, :3].T + t_setup[:3, 3]
    measured = np.column_stack([table["x_m"], table["y_m"], table["z_m"]])
    errors = np.linalg.norm(measured - p, axis=1)
    assert math.isclose(float(np.sqrt(np.mean(errors[pick] ** 2))), reg.rms_m, rel_tol=1e-6)
    others = np.setdiff1d(np.arange(n), pick)
    assert float(np.sqrt(np.mean(errors[others] ** 2))) < 1.5e-3
    # predict with the updated file gives the same errors.
    np.testing.assert_allclose(deflex.predict(out, b).table["error_m"], errors, atol=1e-9)
    # The CLI's checks: two set-ups need setup=, an unknown target needs target=.
    both = {name: np.concatenate([a.table()[name][:20], table[name][:20]]) for name in table.names}
    with pytest.raises(deflex.InputError, match="the data names set-ups A, B: choose one with setup="):
        deflex.register(calibrated, both)
    probe = dict(columns, target=np.array(["probe2"] * 30, dtype=object))
    with pytest.raises(deflex.InputError, match="target `probe2` is not in the robot file"):
        deflex.register(calibrated, probe)
    new_probe = deflex.register(calibrated, probe, target="probe2")
    assert new_probe.target == "probe2" and len(new_probe.parameters) == 9
    positions = {k: v for k, v in columns.items() if k not in ("rx_rad", "ry_rad", "rz_rad", "sigma_rad")}
    with pytest.raises(deflex.InputError, match="orientations: no reading has rx_rad"):
        deflex.register(calibrated, positions, orientations=True)
