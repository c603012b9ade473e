#!/usr/bin/env bash
# The ROS 2 bridge against an independent DDS: PyPI's cyclonedds (Eclipse Cyclone DDS) in a
# virtual environment, the tests of this folder run with pytest. Called by .ci/run; usable alone
# from anywhere: crates/deflex-ros2/tests/python/run.sh [VENV] (default target/ci-python).
# The tests build `deflex` (cargo build -p deflex-cli --features ros2) and run `deflex cell --sim` (SIMULATED)
# with `deflex run` on loopback, on DDS domains chosen from the process id.
set -euo pipefail
cd "$(dirname "$0")/../../../.."
venv=${1:-target/ci-python}
[ -x "$venv/bin/python" ] || python3 -m venv "$venv"
"$venv/bin/pip" install -q cyclonedds==11.0.1 pytest==9.0.3
exec "$venv/bin/python" -m pytest -q -s crates/deflex-ros2/tests/python
