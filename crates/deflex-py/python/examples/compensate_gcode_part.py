"""Offline compensation of a G-code part (``deflex compensate``) from Python: the repository's
CAM part ``docs/parts/pyramid-pocket.gcode`` (a square pyramid pocket, 6 mm deep in 0.4 mm
Z levels), its plunges split into 2 mm moves, compensated for the TX200's deflection under the
twin's forming-force model (SIMULATED), then written as KUKA KRL, ABB RAPID, Stäubli VAL3, UR
URScript and G-code programs.

Usage: ``python compensate_gcode_part.py [OUT_DIR] [PART.gcode]`` (default
``./compensated-part`` and the repository's part).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import deflex


PART = Path(__file__).resolve().parents[4] / "docs" / "parts" / "pyramid-pocket.gcode"


def main(out: Path, part: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    comp = deflex.compensate(
        "tx200", part, wrench="process", max_segment_m=0.002, tolerance_m=1e-6
    )
    summary = comp.to_dict()
    first = summary["iterations"][0]
    print(f"{'SIMULATED ' if comp.simulated else ''}{summary['path']}: {len(comp)} points, {summary['path_length_m'] * 1e3:.0f} mm")
    print(f"predicted error {first['max_predicted_error_m'] * 1e3:.3f} mm uncompensated → "
          f"{summary['final_max_predicted_error_m'] * 1e3:.5f} mm compensated "
          f"({len(summary['iterations'])} iterations, max force {summary['final_max_force_N']:.0f} N)")
    shift = np.linalg.norm(comp.compensation[:, :3], axis=1) * 1e3
    print(f"compensation: largest {shift.max():.3f} mm, mean {shift.mean():.3f} mm")
    comp.save(out / "compensated_path.csv")
    files = comp.write_programs(out / "programs", formats=list(deflex.FORMATS))
    for f in files:
        print(f"wrote {f}")


if __name__ == "__main__":
    main(
        Path(sys.argv[1]) if len(sys.argv) > 1 else Path("compensated-part"),
        Path(sys.argv[2]) if len(sys.argv) > 2 else PART,
    )
