"""The twin's cone with and without the online correction (SIMULATED): the paper's helical
cone formed on the digital twin of the TX200 cell, open loop and closed loop with the deflex
correction controller using the cell's robot file as its model, in-process. That model is the
nominal one (the paper's Table 1 stiffnesses with the cell's tool), not the twin's plant: the
README's 83 % come from a model identified on a twin campaign (``deflex demo``), this script
shows what the nominal file does.

Usage: ``python twin_cone.py [OUT_DIR] [LENGTH_M]`` (default the whole cone). Prints both
summaries; with matplotlib installed, writes ``twin_cone.png`` (path error and vertical force
over time) into OUT_DIR (default: the current folder).
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Optional

import deflex


def main(out: Path, length_m: Optional[float]) -> None:
    model = deflex.sim.cell_robot()
    runs = {
        "without correction": deflex.sim.form("cone", length_m=length_m),
        "with correction": deflex.sim.form("cone", correction="on", model=model, length_m=length_m),
    }
    for label, run in runs.items():
        s = run.summary
        print(f"SIMULATED cone {label}: max error {s['max_error_norm_mm']:.2f} mm, RMS {s['rms_error_norm_mm']:.2f} mm, "
              f"max |F| {s['max_force_norm_N']:.0f} N ({s['duration_s']:.0f} s simulated in {s['wall_time_s']:.2f} s)")
    before = runs["without correction"].summary["max_error_norm_mm"]
    after = runs["with correction"].summary["max_error_norm_mm"]
    print(f"improvement of the max error norm: {(1 - after / before) * 100:.1f} %")
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("(matplotlib not installed: no plot)")
        return
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(10, 6), sharex=True)
    for label, run in runs.items():
        log = run.log
        top.plot(log["time_s"], log["err_norm_m"] * 1e3, lw=0.8, label=label)
        bottom.plot(log["time_s"], log["fz_N"], lw=0.8, label=label)
    top.set_ylabel("|path error| [mm]")
    bottom.set_ylabel("F_z [N]")
    bottom.set_xlabel("time [s]")
    top.set_title("SIMULATED: the paper's cone on the TX200 twin")
    top.legend()
    out.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    fig.savefig(out / "twin_cone.png", dpi=100)
    print(f"wrote {out / 'twin_cone.png'}")


if __name__ == "__main__":
    main(
        Path(sys.argv[1]) if len(sys.argv) > 1 else Path("."),
        float(sys.argv[2]) if len(sys.argv) > 2 else None,
    )
