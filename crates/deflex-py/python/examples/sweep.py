"""A sweep of twin runs mapped over ``concurrent.futures``, written so the same function maps
unchanged over a cluster.

``run_case`` is a plain, top-level function of plain data (a dict in, a dict out): it imports
nothing but deflex, holds no open file or client, and returns only numbers and strings, so it
pickles to another process or machine. deflex releases the GIL while the twin runs, so threads
run cases in parallel on one machine; processes or a cluster spread them further:

* threads (this script): ``ThreadPoolExecutor().map(run_case, cases)``;
* processes: ``ProcessPoolExecutor().map(run_case, cases)``;
* Dask (``pip install dask distributed``, not a deflex dependency)::

      from dask.distributed import Client
      client = Client("scheduler:8786")
      results = client.gather(client.map(run_case, cases))

* Ray (``pip install ray``)::

      import ray
      remote = ray.remote(run_case)
      results = ray.get([remote.remote(c) for c in cases])

Each worker needs deflex installed (``pip install ./crates/deflex-py``); everything is
SIMULATED.

Usage: ``python sweep.py [LENGTH_M]`` (default 0.6 m of the cone per case).
"""

from __future__ import annotations

import sys
import time
from concurrent.futures import ThreadPoolExecutor
from typing import Any, Dict, List


def run_case(case: Dict[str, Any]) -> Dict[str, Any]:
    """One twin run: ``case`` has ``seed``, ``correction`` (``"on"``/``"off"``), ``length_m``
    and ``robot`` (the arm the twin plays); returns the case with the run's errors and forces."""
    import deflex

    model = deflex.sim.cell_robot(case["robot"]) if case["correction"] == "on" else None
    run = deflex.sim.form(
        "cone",
        correction=case["correction"],
        model=model,
        robot=case["robot"],
        seed=case["seed"],
        length_m=case["length_m"],
    )
    s = run.summary
    return {
        **case,
        "max_error_mm": s["max_error_norm_mm"],
        "rms_error_mm": s["rms_error_norm_mm"],
        "max_force_N": s["max_force_norm_N"],
        "wall_time_s": s["wall_time_s"],
    }


def cases(length_m: float) -> List[Dict[str, Any]]:
    return [
        {"robot": robot, "seed": seed, "correction": correction, "length_m": length_m}
        for robot in ("tx200", "ur10e", "kr210-r2700", "irb4600")
        for seed in (1,)
        for correction in ("off", "on")
    ]


def main(length_m: float) -> None:
    todo = cases(length_m)
    t = time.perf_counter()
    with ThreadPoolExecutor() as pool:
        results = list(pool.map(run_case, todo))
    wall = time.perf_counter() - t
    print(f"SIMULATED sweep: {len(results)} twin runs in {wall:.2f} s wall, threads of one process")
    print("| robot | seed | correction | max error (mm) | RMS error (mm) | max force (N) |")
    print("| --- | --- | --- | --- | --- | --- |")
    for r in results:
        print(f"| {r['robot']} | {r['seed']} | {r['correction']} | {r['max_error_mm']:.3f} | {r['rms_error_mm']:.3f} | {r['max_force_N']:.0f} |")


if __name__ == "__main__":
    main(float(sys.argv[1]) if len(sys.argv) > 1 else 0.6)
