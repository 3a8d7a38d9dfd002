"""A V tool's turning sweeps split where its tilt crosses the profile, against one hull each,
in the same run (`machinesim.cutting.tilted_profiles`).

A ``v:90`` 50 um deep spun 20 deg about its own axis on robonano_ui (A), at the default 1 nm
chord of a V tool: every sweep tilts the blade's plane about the tool's axis, across the
blade, and is cut as its two halves' hulls united (the default) or as the hull of the whole
blade (as before). Each variant is cut ``--repeat`` times, alternating, and the medians of
the engine's time and of the whole cut are printed, with the sweeps and how far the cut
reaches, from the axis, into the wedges the blade never swept (0 for the true sweep).

    .venv/bin/python benchmarks/tilted_profiles.py [--repeat 3] [--degrees 20]
"""

from __future__ import annotations

import argparse
import statistics
from unittest import mock

import numpy as np
from _tilted import alternate, nearest_material

import machinesim
from machinesim.cutting import tilted_profiles
from machinesim.nc import parse_program

DEPTH_MM = 0.05


def _cut(program, split: bool):
    if split:
        return machinesim.cut(program, "robonano_ui", tool="v:90", stock="block:10x10x2")

    def never(p0, p1, x0, x1):
        return np.zeros(len(p0), dtype=bool)
    with mock.patch.object(tilted_profiles, "crossing", never):
        return machinesim.cut(program, "robonano_ui", tool="v:90", stock="block:10x10x2")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--degrees", type=float, default=20.0)
    args = parser.parse_args()
    program = parse_program(f"G21 G90\nG00 X5. Y5. Z1.\nG01 Z-{DEPTH_MM} F10.\n"
                            f"A{args.degrees:g} F100.\nG00 Z1.\nM30\n", "spin.nc")
    unswept = np.radians(np.linspace(91.0 + args.degrees, 269.0, 80))
    for name, results, whole in alternate(lambda split: _cut(program, split), args.repeat,
                                          "split halves (default)"):
        part, report = results[-1]
        gap = nearest_material(part, np.array([5e-3, 5e-3, -1e-8]), unswept)
        engine = statistics.median(r.engine_s for _, r in results)
        print(f"{name:24s} sweeps {report.sweeps:5d}  engine {engine:6.2f} s  cut "
              f"{whole:6.2f} s  into the unswept wedge {gap * 1e9:7.3f} nm  removed "
              f"{report.removed_volume_m3 * 1e18:.6g} um^3")


if __name__ == "__main__":
    main()
