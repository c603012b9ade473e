"""Real `deflex sim isf` recordings (SIMULATED) read by the independent reader: PyPI's `mcap` and
`mcap-ros2-support` (Foxglove's own Python libraries) decode every channel from the ros2msg
schemas in the file, without any deflex code, and the values are compared with what deflex's
twin wrote in its CSV log (deflex-sim's own writer) and summary.

* Open loop: the twin's own stream, one sample per row of `log.csv`, at the row's time. Every
  row's path error, contact wrench at the TCP, raw sensor reading and applied correction must
  equal the CSV's within its print precision (the TX200 cell's base axes are the part frame's).
* Closed loop: the controller's stream (`deflex run`'s channels) at 100 Hz, with the twin's path
  error on every cycle, bounded by the summary's maximum over all robot cycles.

Run from the repository root (the `deflex` binary is built with cargo):
    python3 -m pytest crates/deflex-record/tests/python
"""

import csv
import json
import math
import os
import subprocess
from pathlib import Path

import pytest
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

ROOT = Path(__file__).resolve().parents[4]
LENGTH_MM = "300"

TYPES = {
    "/joint_states": "sensor_msgs/msg/JointState",
    "/deflex/wrench_raw": "geometry_msgs/msg/WrenchStamped",
    "/deflex/wrench_sensor": "geometry_msgs/msg/WrenchStamped",
    "/deflex/wrench_tcp": "geometry_msgs/msg/WrenchStamped",
    "/deflex/tcp_pose": "geometry_msgs/msg/PoseStamped",
    "/deflex/program_pose": "geometry_msgs/msg/PoseStamped",
    "/deflex/deflection": "geometry_msgs/msg/TwistStamped",
    "/deflex/correction": "geometry_msgs/msg/TwistStamped",
    "/deflex/error": "geometry_msgs/msg/TwistStamped",
    "/deflex/feedforward": "geometry_msgs/msg/TwistStamped",
    "/deflex/path_error": "geometry_msgs/msg/Vector3Stamped",
    "/diagnostics": "diagnostic_msgs/msg/DiagnosticArray",
}


def deflex_binary():
    subprocess.run(["cargo", "build", "-q", "-p", "deflex-cli"], cwd=ROOT, check=True)
    target = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    return str(target / "debug" / "deflex")


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    deflex = deflex_binary()
    tmp = tmp_path_factory.mktemp("isf")
    common = ["sim", "isf", "--path", "cone", "--length-mm", LENGTH_MM, "--no-plot"]
    subprocess.run([deflex, *common, "--out", str(tmp / "open")], check=True, capture_output=True)
    subprocess.run([deflex, "sim", "robot", "--out", str(tmp / "robot.toml")], check=True,
                   capture_output=True)
    subprocess.run([deflex, *common, "--correction", "on", "--model", str(tmp / "robot.toml"),
                    "--out", str(tmp / "closed")], check=True, capture_output=True)
    return tmp / "open", tmp / "closed"


def session(path):
    with open(path, "rb") as f:
        reader = make_reader(f)
        (message,) = [m for _, _, m in reader.iter_messages(topics=["/deflex/session"])]
    return json.loads(message.data)


def check_types(path):
    with open(path, "rb") as f:
        reader = make_reader(f)
        header = reader.get_header()
        summary = reader.get_summary()
    assert header.profile == "ros2"
    by_topic = {c.topic: c for c in summary.channels.values()}
    for topic, name in TYPES.items():
        channel = by_topic[topic]
        schema = summary.schemas[channel.schema_id]
        assert (schema.name, schema.encoding, channel.message_encoding) == (
            name, "ros2msg", "cdr"), topic
    return {t: summary.statistics.channel_message_counts.get(c.id, 0) for t, c in by_topic.items()}


def decoded(path):
    out = {}
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        for _, channel, message, ros in reader.iter_decoded_messages(topics=list(TYPES)):
            out.setdefault(channel.topic, []).append((message.log_time, ros))
    return out


def log_rows(folder):
    with open(folder / "log.csv") as f:
        return list(csv.DictReader(line for line in f if not line.startswith("#")))


def near(got, want, printed_decimals, what):
    # Half a unit of the last printed digit, plus the rounding of the value itself.
    tol = 0.5 * 10.0 ** -printed_decimals + 1e-9 * abs(want) + 1e-12
    assert abs(got - want) <= tol, f"{what}: {got} vs {want} (tolerance {tol})"


def test_open_loop_recording_equals_the_csv_log(runs):
    folder = runs[0]
    path = folder / "run.mcap"
    counts = check_types(path)
    record = session(path)
    assert record["source"] == "twin-cell" and record["label"] == "SIMULATED"
    rows = log_rows(folder)
    assert len(rows) > 100
    for topic in ["/joint_states", "/deflex/wrench_tcp", "/deflex/path_error", "/deflex/correction"]:
        assert counts[topic] == len(rows), topic
    msgs = decoded(path)
    start = record["start_unix_ns"]
    fields = zip(rows, msgs["/deflex/path_error"], msgs["/deflex/wrench_tcp"],
                 msgs["/deflex/wrench_raw"], msgs["/deflex/correction"], msgs["/deflex/error"])
    for k, (row, (t, err), (_, w), (_, raw), (_, xi), (_, eps)) in enumerate(fields):
        near((t - start) * 1e-9, float(row["time_s"]), 4, f"row {k} time")
        assert err.header.frame_id == "base" and raw.header.frame_id == "ft_sensor"
        for axis in "xyz":
            near(getattr(err.vector, axis) * 1e3, float(row[f"err_{axis}_mm"]), 5, f"row {k} err")
            near(getattr(w.wrench.force, axis), float(row[f"f{axis}_N"]), 3, f"row {k} force")
            near(getattr(w.wrench.torque, axis), float(row[f"m{axis}_Nm"]), 3, f"row {k} torque")
            near(getattr(raw.wrench.force, axis), float(row[f"sensor_f{axis}_N"]), 3,
                 f"row {k} raw force")
            near(getattr(raw.wrench.torque, axis), float(row[f"sensor_t{axis}_Nm"]), 3,
                 f"row {k} raw torque")
            near(getattr(xi.twist.linear, axis) * 1e3, float(row[f"corr_{axis}_mm"]), 5,
                 f"row {k} correction")
            near(getattr(xi.twist.angular, axis) * 1e3, float(row[f"corr_r{axis}_mrad"]), 5,
                 f"row {k} correction")
            # The twin's stream has no controller: no tracking error ε.
            assert math.isnan(getattr(eps.twist.linear, axis))
    # The forming pushes back on the tool: hundreds of newtons at the end of the rows.
    assert max(abs(float(r["fz_N"])) for r in rows) > 50
    states = []
    for _, m in msgs["/diagnostics"]:
        values = {kv.key: kv.value for kv in m.status[0].values}
        states.append(values["phase"])
    assert set(states) <= {"forming", "finished"} and states[-1] == "finished"


def test_closed_loop_recording_is_the_controllers_stream_with_the_path_error(runs):
    folder = runs[1]
    path = folder / "run.mcap"
    counts = check_types(path)
    record = session(path)
    assert record["source"] == "twin" and record["protocol"] == "in-process"
    summary = json.loads((folder / "summary.json").read_text())
    cycles = counts["/deflex/correction"]
    # One message per 10 ms control cycle over the run.
    assert abs(cycles - summary["duration_s"] / 0.01) <= 2, (cycles, summary["duration_s"])
    assert counts["/deflex/path_error"] == cycles
    msgs = decoded(path)
    for (_, xi), (_, ds), (_, eps) in zip(msgs["/deflex/correction"], msgs["/deflex/deflection"],
                                          msgs["/deflex/error"]):
        for part in ("linear", "angular"):
            for axis in "xyz":
                a = getattr(getattr(xi.twist, part), axis)
                b = getattr(getattr(ds.twist, part), axis)
                c = getattr(getattr(eps.twist, part), axis)
                assert math.isclose(c, -a - b, rel_tol=0, abs_tol=1e-15)
    norms = [math.sqrt(e.vector.x ** 2 + e.vector.y ** 2 + e.vector.z ** 2)
             for _, e in msgs["/deflex/path_error"]]
    largest = summary["max_error_norm_mm"] * 1e-3
    # Sampled every 10 ms of the 4 ms robot cycles: at most the summary's maximum, and close.
    assert max(norms) <= largest + 1e-9
    assert max(norms) >= 0.8 * largest, (max(norms), largest)
    assert max(abs(xi.twist.linear.z) for _, xi in msgs["/deflex/correction"]) > 1e-6
