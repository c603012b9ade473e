"""deflex's FANUC Stream Motion link against an independent controller: the fake Stream Motion
controller of PyPI's `airo-fanuc` (its strict-conformance mode records every command that a real
controller would refuse or that breaks the protocol: data style, motion flag, I/O, version,
sequence numbers, double sends, a stop without a last command, a step beyond 5 degrees).

Run by scripts/check-fanuc-stream: starts the fake on an ephemeral loopback port at the
controller's 8 ms cycle (wall-paced), lets the TP program's side be "running" (the fake couples
ready to its RMI call; set directly here), runs deflex's session (the example binary given as
argv[1]) against it and checks the session from the fake's side. Exit status 0 when it passed.
"""

import json
import subprocess
import sys

from airo_fanuc.testing.fake_crx import FakeCRXConfig, FakeCRXController
from airo_fanuc.testing.plant import WallClock

START_DEG = [0.0, -20.0, 20.0, 0.0, 30.0, 0.0]
# The robot stands 2 degrees from the path's start on axes 2 and 5: deflex approaches first.
ROBOT_DEG = [0.0, -18.0, 20.0, 0.0, 28.0, 0.0, 0.0, 0.0, 0.0]


def main() -> int:
    session_binary = sys.argv[1]
    fake = FakeCRXController(FakeCRXConfig(strict=True), clock=WallClock(), initial_q_deg=ROBOT_DEG)
    fake.start()
    with fake.state.lock:
        # What FRC_Call("STREAM_MOTN") over RMI does on the fake: the TP program runs IBGN.
        fake.state.stream_motn_launched = True
    fake.start_realtime()
    try:
        run = subprocess.run(
            [session_binary, f"127.0.0.1:{fake.sm_port}", ",".join(str(v) for v in START_DEG)],
            capture_output=True,
            text=True,
            timeout=120,
        )
    finally:
        fake.stop_realtime()
    # What deflex sent last (the stop packet) may still wait in the fake's socket: take it in.
    fake.sm._drain_rx()
    print(run.stderr, end="", file=sys.stderr)
    print(run.stdout, end="")
    failures = []
    if run.returncode != 0:
        failures.append(f"deflex's session exited with {run.returncode}")
    summary = json.loads(run.stdout.strip().splitlines()[-1])
    sm = fake.sm
    if fake.violations:
        failures.append(f"the fake recorded {len(fake.violations)} violations: {fake.violations[:3]}")
    if fake.sm.realtime_error is not None:
        failures.append(f"the fake's loop failed: {fake.sm.realtime_error!r}")
    if sm.streaming:
        failures.append("the fake still streams: no stop packet")
    if not sm._last_cmd_is_last:
        failures.append("the last command did not carry is_last_command")
    if sm._commands_seen < 500:
        failures.append(f"only {sm._commands_seen} commands reached the fake")
    if sm._commands_seen != summary["answers"]:
        failures.append(f"deflex sent {summary['answers']} commands, the fake took {sm._commands_seen}")
    if fake.plant.watchdog_tripped:
        failures.append("the fake's deviation watchdog tripped")
    if fake.state.in_error:
        failures.append("the fake is in error")
    # The fake's last target is deflex's last command (the wire's doubles, to 1e-6 degree).
    target = list(fake.plant._target[:6])
    last = summary["last_command_deg"]
    if max(abs(a - b) for a, b in zip(target, last)) > 1e-6:
        failures.append(f"the fake's last target {target} is not deflex's last command {last}")
    # The path ends where it started (the correction's sine on axis 3 aside): the fake's joints
    # followed, within its 125 ms servo lag.
    measured = list(fake.q_meas_deg[:6])
    for i in (0, 1, 3, 4, 5):
        if abs(measured[i] - START_DEG[i]) > 0.5:
            failures.append(f"axis {i + 1} ended at {measured[i]:.3f} deg, not {START_DEG[i]}")
    fake.close()
    print(
        f"fake controller: {sm._commands_seen} commands, {len(fake.violations)} violations, "
        f"last command {'is_last' if sm._last_cmd_is_last else 'not last'}, "
        f"stop packet {'received' if not sm.streaming else 'missing'}, "
        f"final joints {[round(float(v), 3) for v in measured]} deg"
    )
    for f in failures:
        print(f"FAIL: {f}", file=sys.stderr)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
