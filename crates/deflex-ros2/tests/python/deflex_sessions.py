"""SIMULATED deflex sessions for the DDS interoperability tests (no DDS here): the `deflex`
binary, a cell file for `deflex cell --sim` (a KUKA RSI robot and an ATI Net F/T on loopback)
and `deflex run` with or without `[ros2]`, a session of both, the run's CSV log and the
correction-against-force profile. Used by test_ros2_interop.py (Cyclone DDS) and
../fastdds/test_fastdds_interop.py (Fast DDS)."""

import csv
import json
import os
import socket
import subprocess
import threading
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[4]
MODEL = ROOT / "docs" / "tx200_cell.toml"
SENSOR_FRAME = "ati_ft"
NS = "/deflex_it"
RATE_HZ = 50.0


def domain_base():
    """This process's own DDS domains (other processes on the machine may use DDS): the base
    and the three after it, all below 100, so a domain's RTPS ports (7400 + 250 d + …) lie under
    Linux's ephemeral range (32768 on) and no socket a test binds to port 0 (the relay's, the
    links') can take a DDS port or be sent DDS traffic."""
    return 12 + (os.getpid() % 28) * 3


@pytest.fixture(scope="module")
def deflex():
    """The `deflex` binary: $DEFLEX_BIN when set, otherwise built here with cargo."""
    if os.environ.get("DEFLEX_BIN"):
        return Path(os.environ["DEFLEX_BIN"])
    subprocess.run(["cargo", "build", "-q", "-p", "deflex-cli", "--features", "ros2"], cwd=ROOT,
                   check=True)
    target = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    return target / "debug" / "deflex"


def free_port():
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


ROBOT_PORT = free_port()
NETFT_PORT = free_port()
NETFT = f'kind = "netft"\naddress = "127.0.0.1:{NETFT_PORT}"\nbind = "127.0.0.1:0"'
# The ROS 2 sensor's readings pass through a relay process on a shared machine: the sensor
# timeout (which also latches a fault) is 0.5 s there instead of the Net F/T's 0.1 s.
ROS2_SENSOR = ('kind = "ros2"\ntopic = "/ati/wrench"\nmax_age_s = 0.25\nqueue_depth = 16\n'
               'timeout_s = 0.5')


def cell_toml(sensor, ros2, log="run.csv"):
    return f"""[robot]
kind = "kuka-rsi"
bind = "127.0.0.1:{ROBOT_PORT}"
timeout_s = 0.1
[sensor]
{sensor if "timeout_s" in sensor else sensor + chr(10) + "timeout_s = 0.1"}
range = [1500.0, 1500.0, 3750.0, 240.0, 240.0, 240.0]
[mounting]
sensor_xyz_m = [0.0, 0.0, 0.030]
tool_mass_kg = 3.2
tool_com_m = [0.003, -0.002, 0.075]
[model]
file = "{MODEL}"
[control]
realtime = false
lock_memory = false
[log]
path = "{log}"
{ros2}
"""


def ros2_section(domain, topics=None, qos="reliable", depth=100):
    text = (f'[ros2]\ndomain_id = {domain}\nnamespace = "{NS}"\nqos = "{qos}"\n'
            f'depth = {depth}\npublish_rate_hz = {RATE_HZ}\ndiagnostics_rate_hz = 5.0\n'
            f'sensor_frame = "{SENSOR_FRAME}"\n')
    if topics is not None:
        text += "topics = [" + ", ".join(f'"{t}"' for t in topics) + "]\n"
    return text


def session(deflex, workdir, cell_config, run_config, length_mm, during=None):
    """`deflex cell --sim` and `deflex run` together; `during(stop)` runs alongside in a thread.
    Returns the run's and the cell's JSON summaries."""
    cell = subprocess.Popen(
        [str(deflex), "cell", "--sim", "--config", str(cell_config), "--length-mm",
         str(length_mm), "--quiet", "--json", "--wait-s", "60"],
        cwd=workdir, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    stop = threading.Event()
    helper = None
    if during is not None:
        helper = threading.Thread(target=during, args=(stop,), daemon=True)
        helper.start()
    try:
        run = subprocess.run(
            [str(deflex), "run", "--config", str(run_config), "--idle-exit-s", "0.5",
             "--startup-timeout-s", "60", "--quiet", "--json"],
            cwd=workdir, capture_output=True, text=True, timeout=300)
        cell_out, cell_err = cell.communicate(timeout=120)
    finally:
        stop.set()
        if cell.poll() is None:
            cell.kill()
        if helper is not None:
            helper.join(timeout=30)
    assert run.returncode == 0, run.stdout + run.stderr
    assert cell.returncode == 0, cell_out + cell_err
    return json.loads(run.stdout), json.loads(cell_out)


def netft_baseline(deflex, tmp_path, length_mm):
    """The Net F/T session a ROS 2 sensor session is compared with, in `tmp_path/netft`: that
    folder and the run's and the cell's summaries."""
    netft_dir = tmp_path / "netft"
    netft_dir.mkdir()
    cell = netft_dir / "cell.toml"
    cell.write_text(cell_toml(NETFT, ""))
    run, cell_out = session(deflex, netft_dir, cell, cell, length_mm)
    return netft_dir, run, cell_out


def ros2_sensor_configs(tmp_path, domain, qos):
    """A session folder `tmp_path/ros2` whose twin streams its Net F/T while `deflex run` takes
    the wrench from ROS 2 (`domain`, the subscription's `qos`): the folder, the cell's config and
    the run's."""
    ros_dir = tmp_path / "ros2"
    ros_dir.mkdir()
    cell = ros_dir / "cell.toml"
    cell.write_text(cell_toml(NETFT, ""))
    run_config = ros_dir / "run.toml"
    run_config.write_text(cell_toml(ROS2_SENSOR, ros2_section(domain, topics=[], qos=qos)))
    return ros_dir, cell, run_config


def read_log(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def correction_profile(rows):
    """ξz against the TCP force fz (what the loop settles to), sampled in 8 force bins."""
    pairs = [(float(r["w_fz_n"]), float(r["xi_z_m"])) for r in rows if r["status"] != "taring"]
    lo, hi = min(p[0] for p in pairs), max(p[0] for p in pairs)
    bins = []
    for b in range(8):
        a, c = lo + (hi - lo) * b / 8, lo + (hi - lo) * (b + 1) / 8
        xs = [x for f, x in pairs if a <= f < c]
        if len(xs) >= 10:
            bins.append(((a + c) / 2, sum(xs) / len(xs)))
    return bins


def assert_same_correction(run_dir, base_dir, cell_out, base_cell):
    """The same correction as the Net F/T session: the twin's truth (largest correction and
    force, within 5 %) and the law's ξz against force (within 5 % of the largest)."""
    for key in ("max_correction_mm", "max_force_norm_n"):
        a, b = cell_out[key], base_cell[key]
        print(f"\n{key}: ROS 2 sensor {a:.4f}, Net F/T {b:.4f}")
        assert abs(a - b) <= 0.05 * abs(b), (key, a, b)
    profile = correction_profile(read_log(run_dir / "run.csv"))
    base_profile = correction_profile(read_log(base_dir / "run.csv"))
    assert len(profile) >= 6 and len(base_profile) >= 6
    scale = max(abs(x) for _, x in base_profile)
    for (f, x) in profile:
        (fb, xb) = min(base_profile, key=lambda p: abs(p[0] - f))
        if abs(fb - f) < 1.0:
            print(f"fz {f:.1f} N: xi_z ROS 2 {x * 1e3:.4f} mm, Net F/T {xb * 1e3:.4f} mm")
            assert abs(x - xb) <= 0.05 * scale, (f, x, xb, scale)


class LogRows:
    """The run's CSV log looked up by a message's stamp: a stamp is the session time plus one
    fixed offset, found from one raw wrench (the joints barely move between cycles, the wrench
    does), so every message can then be compared with its own row."""

    def __init__(self, rows, raw_stamp_s, raw_fx, raw_fz):
        self.rows = rows
        self.times = [float(r["time_s"]) for r in rows]
        candidates = [r for r in rows
                      if abs(float(r["raw_fz_n"]) - raw_fz) < 6e-5
                      and abs(float(r["raw_fx_n"]) - raw_fx) < 6e-5]
        assert len(candidates) == 1, len(candidates)
        self.offset = raw_stamp_s - float(candidates[0]["time_s"])

    def at(self, stamp_s):
        t = stamp_s - self.offset
        i = min(range(len(self.times)), key=lambda k: abs(self.times[k] - t))
        assert abs(self.times[i] - t) < 5e-6, (t, self.times[i])
        return self.rows[i]


Q_COLUMNS = [f"q{i}_rad" for i in range(1, 7)]
RAW_COLUMNS = ["raw_fx_n", "raw_fy_n", "raw_fz_n", "raw_mx_nm", "raw_my_nm", "raw_mz_nm"]
