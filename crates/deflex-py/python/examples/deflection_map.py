"""A batch deflection map: the TCP deflection of the TX200 over a horizontal grid of TCP
positions with the tool pointing down (the paper's Fig. 10 set-up, ``deflex map``), as two
batched calls: ``robot.ik`` over every grid pose, then ``robot.deflect`` over every
configuration.

Usage: ``python deflection_map.py [OUT_DIR]``. Prints the extremes; with matplotlib installed,
writes ``deflection_map.png`` (δz and |δp| in mm) into OUT_DIR (default: the current folder).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

import deflex


def deflection_map(
    robot: deflex.Robot,
    center_m: tuple = (1.5, 0.0),
    z_m: float = 0.1,
    size_m: float = 0.6,
    step_m: float = 0.02,
    wrench: tuple = (0.0, 0.0, -1100.0, 0.0, 0.0, 0.0),
) -> tuple:
    """Grid x, y (m) and the deflection ``[δp; δφ]`` at every node, shape ``(ny, nx, 6)`` (NaN
    where the pose is out of reach)."""
    seed = np.radians([0, 49.7, 89.3, 0, 41, 0])
    down = robot.pose(seed)
    xs = center_m[0] + np.arange(-size_m / 2, size_m / 2 + 1e-9, step_m)
    ys = center_m[1] + np.arange(-size_m / 2, size_m / 2 + 1e-9, step_m)
    gx, gy = np.meshgrid(xs, ys)
    poses = np.repeat(down[None, :, :], gx.size, axis=0)
    poses[:, 0, 3] = gx.ravel()
    poses[:, 1, 3] = gy.ravel()
    poses[:, 2, 3] = z_m
    q = robot.ik(poses, seed=seed, on_failure="nan")
    reached = ~np.isnan(q).any(axis=1)
    d = np.full((gx.size, 6), np.nan)
    d[reached] = robot.deflect(q[reached], np.asarray(wrench))
    return xs, ys, d.reshape(len(ys), len(xs), 6)


def main(out: Path) -> None:
    robot = deflex.Robot.builtin("tx200")
    t = time.perf_counter()
    xs, ys, d = deflection_map(robot)
    elapsed = time.perf_counter() - t
    dz = d[:, :, 2] * 1e3
    norm = np.linalg.norm(d[:, :, :3], axis=2) * 1e3
    nodes = np.isfinite(dz).sum()
    print(f"{robot.name}: {nodes} of {dz.size} grid nodes reached, IK + deflection in {elapsed * 1e3:.0f} ms")
    print(f"under F = (0, 0, −1100) N: δz {np.nanmin(dz):.3f} … {np.nanmax(dz):.3f} mm, |δp| max {np.nanmax(norm):.3f} mm")
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("(matplotlib not installed: no plot)")
        return
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5))
    extent = (xs[0] * 1e3, xs[-1] * 1e3, ys[0] * 1e3, ys[-1] * 1e3)
    for ax, values, label in [(axes[0], dz, "δz [mm]"), (axes[1], norm, "|δp| [mm]")]:
        image = ax.imshow(values, origin="lower", extent=extent, cmap="viridis")
        ax.set_xlabel("x [mm]")
        ax.set_ylabel("y [mm]")
        ax.set_title(label)
        fig.colorbar(image, ax=ax, label=label)
    fig.suptitle("TX200, tool down at z = 100 mm, F = (0, 0, −1100) N: predicted deflection")
    out.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    fig.savefig(out / "deflection_map.png", dpi=100)
    print(f"wrote {out / 'deflection_map.png'}")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path("."))
