"""A ball end mill swung about a line inside the cut, its sweeps split where the tilt crosses
its sides, against one hull each (before), in the same run (`machinesim.cutting.
tilted_solids`).

``ball:0.5`` (1 um facets) with its tip 0.6 mm under the stock's top, swung +-1 deg about the
Y line 50 um above its equator (50 um under the top), in ``--sweeps`` sweeps, given to the
engine as poses. Each variant is cut ``--repeat`` times, alternating; the medians of the
engine's time (`remove`) are printed, with how far the stock at the line's height was cut past the
side's true sweep, R / cos(1 deg) from the pivot's column (0 for the true sweep).

    .venv/bin/python benchmarks/tilted_solids.py [--repeat 3] [--sweeps 20]
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
from pathlib import Path
from unittest import mock

import numpy as np

from machinesim.cutting.engine import remove
from machinesim.cutting.tilted_solids import SolidSplitter
from machinesim.end_mills import BallEndMill
from machinesim.workpiece import block

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
from test_cutting_tilted_profiles import _nearest_material  # noqa: E402

RADIUS = 0.5e-3
HALF = math.radians(1.0)
UNDER_TOP = 50e-6


def _poses(n: int) -> np.ndarray:
    tip = np.array([5e-3, 5e-3, -(RADIUS + 2 * UNDER_TOP)])
    pivot = np.array([5e-3, 5e-3, -UNDER_TOP])
    poses = np.zeros((n + 1, 4, 4))
    for i, angle in enumerate(np.linspace(-HALF, HALF, n + 1)):
        c, s = math.cos(angle), math.sin(angle)
        rotation = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
        poses[i, :3, :3] = rotation
        poses[i, :3, 3] = pivot - rotation @ (pivot - tip)
        poses[i, 3, 3] = 1.0
    return poses


def _cut(poses, split: bool):
    began = time.perf_counter()
    if split:
        part, report = remove(block(10e-3, 10e-3, 2e-3), BallEndMill(RADIUS), [poses])
    else:
        with mock.patch.object(SolidSplitter, "pieces", lambda self, *args: None):
            part, report = remove(block(10e-3, 10e-3, 2e-3), BallEndMill(RADIUS), [poses])
    return part, report, time.perf_counter() - began


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--sweeps", type=int, default=20)
    args = parser.parse_args()
    poses = _poses(args.sweeps)
    runs = {True: [], False: []}
    for _ in range(args.repeat):
        for split in (True, False):
            runs[split].append(_cut(poses, split))
    level = np.array([5e-3, 5e-3, -UNDER_TOP])
    for split, name in ((True, "split pieces (default)"), (False, "one hull (before)")):
        part, report, _ = runs[split][-1]
        gap = _nearest_material(part, level, [0.0, math.pi])
        engine = statistics.median(r[2] for r in runs[split])
        print(f"{name:24s} sweeps {args.sweeps:5d}  engine {engine:6.2f} s  past the side "
              f"{(gap - RADIUS / math.cos(HALF)) * 1e9:7.3f} nm  removed "
              f"{report.removed_volume * 1e18:.6g} um^3")


if __name__ == "__main__":
    main()
