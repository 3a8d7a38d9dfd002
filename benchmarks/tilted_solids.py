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
from unittest import mock

import numpy as np
from _tilted import alternate, nearest_material, swept_cut, swing

from machinesim.cutting.tilted_solids import SolidSplitter
from machinesim.end_mills import BallEndMill

RADIUS = 0.5e-3
HALF = math.radians(1.0)
UNDER_TOP = 50e-6


def _poses(n: int) -> np.ndarray:
    tip = np.array([5e-3, 5e-3, -(RADIUS + 2 * UNDER_TOP)])
    return swing(n, tip, np.array([5e-3, 5e-3, -UNDER_TOP]), HALF)


def _cut(poses, split: bool):
    if split:
        return swept_cut(BallEndMill(RADIUS), poses)
    with mock.patch.object(SolidSplitter, "pieces", lambda self, *args: None):
        return swept_cut(BallEndMill(RADIUS), poses)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--sweeps", type=int, default=20)
    args = parser.parse_args()
    poses = _poses(args.sweeps)
    level = np.array([5e-3, 5e-3, -UNDER_TOP])
    for name, results, engine in alternate(lambda split: _cut(poses, split), args.repeat,
                                           "split pieces (default)"):
        part, report = results[-1]
        gap = nearest_material(part, level, [0.0, math.pi])
        print(f"{name:24s} sweeps {args.sweeps:5d}  engine {engine:6.2f} s  past the side "
              f"{(gap - RADIUS / math.cos(HALF)) * 1e9:7.3f} nm  removed "
              f"{report.removed_volume * 1e18:.6g} um^3")


if __name__ == "__main__":
    main()
