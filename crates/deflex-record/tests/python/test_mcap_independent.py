"""A deflex MCAP recording read by an independent reader: PyPI's `mcap` and `mcap-ros2-support`
(Foxglove's own Python libraries), which parse the ros2msg schemas in the file and decode the CDR
messages without any deflex code.

Run from the repository root:
    pip install mcap==1.6.0 mcap-ros2-support==0.6.0 pytest
    python3 -m pytest crates/deflex-record/tests/python

The recording is the SIMULATED synthetic stream written by the crate's example
`synthetic_recording` (built and run here with cargo).
"""

import math
import os
import subprocess
from pathlib import Path

import pytest
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

ROOT = Path(__file__).resolve().parents[4]

EXPECTED = {
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

SECONDS = 4.0
CYCLES = 400


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    out = tmp_path_factory.mktemp("mcap") / "synthetic.mcap"
    subprocess.run(
        [
            "cargo", "run", "-q", "-p", "deflex-record", "--example", "synthetic_recording",
            "--", str(out), str(SECONDS), "twin",
        ],
        cwd=ROOT, check=True, env=dict(os.environ),
    )
    return out


def test_channels_and_schemas(recording):
    with open(recording, "rb") as f:
        reader = make_reader(f)
        header = reader.get_header()
        summary = reader.get_summary()
    assert header.profile == "ros2"
    by_topic = {c.topic: c for c in summary.channels.values()}
    for topic, schema_name in EXPECTED.items():
        channel = by_topic[topic]
        schema = summary.schemas[channel.schema_id]
        assert channel.message_encoding == "cdr", topic
        assert schema.encoding == "ros2msg", topic
        assert schema.name == schema_name, topic
    assert by_topic["/deflex/session"].message_encoding == "json"
    counts = summary.statistics.channel_message_counts
    for topic in EXPECTED:
        if topic != "/diagnostics":
            assert counts[by_topic[topic].id] == CYCLES, topic
    assert 40 <= counts[by_topic["/diagnostics"].id] <= CYCLES


def decoded(recording):
    """topic -> list of (log_time, decoded message), every message decoded by mcap_ros2."""
    out = {}
    with open(recording, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        for schema, channel, message, ros_msg in reader.iter_decoded_messages(
            topics=list(EXPECTED)
        ):
            out.setdefault(channel.topic, []).append((message.log_time, message.sequence, ros_msg))
    return out


def test_values_obey_the_controllers_identities(recording):
    msgs = decoded(recording)
    assert set(msgs) == set(EXPECTED)
    # Same log time and sequence (the cycle) for every channel of a cycle.
    times = [t for t, _, _ in msgs["/deflex/wrench_tcp"]]
    assert times == sorted(times) and len(set(times)) == CYCLES
    for topic in ["/deflex/correction", "/deflex/deflection", "/deflex/tcp_pose", "/joint_states"]:
        assert [t for t, _, _ in msgs[topic]] == times, topic
    # Header stamps equal the log time.
    for t, _, m in msgs["/deflex/wrench_tcp"]:
        assert m.header.stamp.sec * 10**9 + m.header.stamp.nanosec == t
        assert m.header.frame_id == "base"
    assert msgs["/deflex/wrench_raw"][0][2].header.frame_id == "ft_sensor"
    for (_, _, xi), (_, _, ds), (_, _, eps) in zip(
        msgs["/deflex/correction"], msgs["/deflex/deflection"], msgs["/deflex/error"]
    ):
        # eq. 5: ε = −ξ − δŝ, per axis, linear and angular.
        for part in ("linear", "angular"):
            for axis in "xyz":
                a = getattr(getattr(xi.twist, part), axis)
                b = getattr(getattr(ds.twist, part), axis)
                c = getattr(getattr(eps.twist, part), axis)
                assert math.isclose(c, -a - b, rel_tol=0, abs_tol=1e-15)
    for (_, _, tcp), (_, _, prog), (_, _, xi) in zip(
        msgs["/deflex/tcp_pose"], msgs["/deflex/program_pose"], msgs["/deflex/correction"]
    ):
        # The program TCP is the corrected TCP minus ξ; orientations are unit quaternions.
        for axis in "xyz":
            got = getattr(prog.pose.position, axis)
            want = getattr(tcp.pose.position, axis) - getattr(xi.twist.linear, axis)
            assert math.isclose(got, want, abs_tol=1e-12)
        q = tcp.pose.orientation
        assert math.isclose(q.x**2 + q.y**2 + q.z**2 + q.w**2, 1.0, abs_tol=1e-12)
    # Contact: the force norm at the TCP rises to hundreds of newtons.
    last = msgs["/deflex/wrench_tcp"][-1][2].wrench.force
    assert 300 < math.sqrt(last.x**2 + last.y**2 + last.z**2) < 3000
    joints = msgs["/joint_states"][0][2]
    assert list(joints.name) == [f"joint_{i}" for i in range(1, 7)]
    assert len(joints.position) == 6 and len(joints.velocity) == 0


def test_diagnostics_name_the_state(recording):
    msgs = decoded(recording)
    phases = []
    for _, _, m in msgs["/diagnostics"]:
        (status,) = m.status
        assert status.name == "deflex/controller"
        values = {kv.key: kv.value for kv in status.values}
        assert {"phase", "flags", "status", "fault", "cycle_time_s", "late_answers"} <= set(values)
        assert 0 < float(values["cycle_time_s"]) < 0.01
        phases.append(values["phase"])
        if values["phase"] == "running":
            assert "active" in values["status"].split("|")
    assert phases[0] == "taring" and phases[-1] == "running"


def test_session_json(recording):
    import json

    with open(recording, "rb") as f:
        reader = make_reader(f)
        (session,) = [m for _, c, m in reader.iter_messages(topics=["/deflex/session"])]
        metadata = {m.name: m.metadata for m in reader.iter_metadata()}
    record = json.loads(session.data)
    assert record["label"] == "SIMULATED" and record["simulated"] is True
    assert record["source"] == "twin"
    assert metadata["deflex"]["label"] == "SIMULATED"
