"""An RTDE client deflex did not write (SDU's ur_rtde, PyPI `ur-rtde`) reads the twin's RTDE
controller: it negotiates the protocol and its output recipe with the server the twin plays
(deflex_io::rtde::server) and prints what it received, one line per controller cycle: timestamp, actual_q (6), actual_TCP_pose (6),
ft_raw_wrench (6), robot_mode, runtime_state, output_int_register_36, separated by spaces, the
doubles in Python's repr (the shortest text that reads back to the same double).
The Rust side (crates/deflex-io/tests/it/rtde_python.rs) compares them with what it sent.

Usage: rtde_client_check.py HOST SAMPLES
ur_rtde always connects to port 30004 of HOST.
"""

import os
import sys
import time

import rtde_receive

VARIABLES = [
    "timestamp",
    "actual_q",
    "actual_TCP_pose",
    "ft_raw_wrench",
    "robot_mode",
    "runtime_state",
    "output_int_register_36",
]


def main() -> int:
    host, wanted = sys.argv[1], int(sys.argv[2])
    # Upper-range registers (36-43): the ones ur_rtde reads when the lower ones are a fieldbus's.
    r = rtde_receive.RTDEReceiveInterface(
        host, 500.0, VARIABLES, os.environ.get("RTDE_VERBOSE") == "1", True
    )
    if not r.isConnected():
        print("not connected", file=sys.stderr)
        return 1
    seen = set()
    deadline = time.monotonic() + 60.0  # a hang guard, not a synchronisation
    out = []
    while len(out) < wanted and time.monotonic() < deadline:
        t0 = r.getTimestamp()
        if t0 in seen or t0 == 0.0:
            time.sleep(0.0005)
            continue
        record = {
            "timestamp": t0,
            "q": list(r.getActualQ()),
            "pose": list(r.getActualTCPPose()),
            "wrench": list(r.getFtRawWrench()),
            "robot_mode": r.getRobotMode(),
            "runtime_state": r.getRuntimeState(),
            "register": r.getOutputIntRegister(36),
        }
        # Read again: a record is kept only when no package arrived while it was read.
        if r.getTimestamp() != t0:
            continue
        seen.add(t0)
        out.append(record)
    r.disconnect()
    for rec in out:
        fields = [rec["timestamp"], *rec["q"], *rec["pose"], *rec["wrench"]]
        ints = [rec["robot_mode"], rec["runtime_state"], rec["register"]]
        print(" ".join([repr(float(v)) for v in fields] + [str(int(v)) for v in ints]))
    return 0 if len(out) >= wanted else 1


if __name__ == "__main__":
    sys.exit(main())
