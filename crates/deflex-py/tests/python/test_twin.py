"""The twin in-process (SIMULATED): open and closed loop on the paper's cone, logs as arrays
and DataFrames, and deflex's own log files read back."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest

import deflex


def test_closed_loop_reduces_the_path_error_of_the_open_loop(tmp_path: Path) -> None:
    model = deflex.sim.cell_robot()
    assert "tx200" in model.name.lower() or "TX200" in model.name
    open_run = deflex.sim.form("cone", length_m=0.8)
    closed = deflex.sim.form("cone", correction="on", model=model, length_m=0.8)
    o, c = open_run.summary, closed.summary
    assert o["simulated"] and not o["correction"] and c["correction"]
    assert c["max_error_norm_mm"] < 0.85 * o["max_error_norm_mm"], (o, c)
    assert closed.controller_status is not None and "no fault" in closed.controller_status
    log = open_run.log
    assert log.simulated and len(log) > 100
    err = np.linalg.norm(log.array("err_x_m", "err_y_m", "err_z_m"), axis=1)
    np.testing.assert_allclose(err, log["err_norm_m"], atol=1e-15)
    true = log.array("true_x_m", "true_y_m", "true_z_m")
    des = log.array("des_x_m", "des_y_m", "des_z_m")
    np.testing.assert_allclose(true - des, log.array("err_x_m", "err_y_m", "err_z_m"), atol=1e-15)
    assert abs(err.max() * 1e3 - o["max_error_norm_mm"]) < 0.05 * o["max_error_norm_mm"] + 1e-3
    assert np.abs(closed.log.array("corr_x_m", "corr_y_m", "corr_z_m")).max() > 1e-5
    assert open_run.profile.shape[1] == 3
    files = closed.save(tmp_path / "closed")
    assert any(str(f).endswith("log.csv") for f in files)
    read = deflex.read_log(tmp_path / "closed" / "log.csv")
    assert read.simulated and len(read) == len(closed.log)
    np.testing.assert_allclose(read["err_norm_mm"], closed.log["err_norm_m"] * 1e3, atol=1e-5)


def test_logs_become_dataframes_when_pandas_is_installed() -> None:
    pd = pytest.importorskip("pandas")
    run = deflex.sim.form("pyramid", length_m=0.1)
    frame = run.log.to_pandas()
    assert isinstance(frame, pd.DataFrame) and frame.attrs["simulated"]
    assert list(frame.columns) == run.log.names


def test_a_deflex_run_log_is_read_with_its_text_columns(tmp_path: Path) -> None:
    path = tmp_path / "run.csv"
    path.write_text(
        "time_s,q1_rad,w_fz_n,loop_gain,flags,status\n"
        "0.00,0.1,-900.5,,4,active\n"
        "0.01,0.2,-901.0,0.7,4,active|taring\n"
    )
    log = deflex.read_log(path)
    np.testing.assert_array_equal(log["w_fz_n"], [-900.5, -901.0])
    assert np.isnan(log["loop_gain"][0]) and log["flags"][1] == 4
    assert list(log["status"]) == ["active", "active|taring"] and not log.simulated
    with pytest.raises(KeyError, match="columns: time_s"):
        log["fz"]
    (tmp_path / "ragged.csv").write_text("a,b\n1,2\n3\n")
    with pytest.raises(deflex.DataError, match=r"ragged\.csv:3"):
        deflex.read_log(tmp_path / "ragged.csv")
    with pytest.raises(deflex.DeflexIOError):
        deflex.read_log(tmp_path / "missing.csv")


def test_runs_in_threads_proceed_in_parallel_and_match_serial_runs() -> None:
    def run(seed: int) -> float:
        return float(deflex.sim.form("cone", length_m=0.15, seed=seed).summary["max_error_norm_mm"])

    serial = [run(s) for s in (1, 2)]
    with ThreadPoolExecutor(2) as pool:
        threaded = list(pool.map(run, (1, 2)))
    assert serial == threaded


def test_twin_options_are_checked() -> None:
    with pytest.raises(deflex.InputError, match="correction=\"on\" needs model="):
        deflex.sim.form("cone", correction="on")
    with pytest.raises(deflex.InputError, match="only used with correction"):
        deflex.sim.form("cone", model="tx200")
    with pytest.raises(deflex.InputError, match="correction: expected"):
        deflex.sim.form("cone", correction="yes")
    with pytest.raises(deflex.InputError, match="fixture_stiffness_n_m"):
        deflex.sim.form("cone", fixture_stiffness_n_m=1e7)
    with pytest.raises(deflex.InputError, match="length_m"):
        deflex.sim.form("cone", length_m=-1.0)
    with pytest.raises(deflex.SimulationError):
        deflex.sim.form("/nonexistent.gcode")
    plunge = deflex.sim.form("plunge", fixture_stiffness_n_m=1e6, length_m=0.005)
    assert plunge.summary["max_force_norm_N"] > 0
