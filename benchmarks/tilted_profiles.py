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
import math
import statistics
import time
from unittest import mock

import numpy as np

import machinesim
from machinesim.cutting import tilted_profiles
from machinesim.nc import parse_program

DEPTH_MM = 0.05


def _nearest_material(part, origin, angles) -> float:
    """Shortest distance (m) from ``origin`` along horizontal rays at ``angles`` to the
    part's surface; 0 where the origin lies inside the part."""
    vertices, triangles = part.mesh()
    tri = vertices[np.asarray(triangles, dtype=np.int64)] - origin
    low, high = tri[:, :, 2].min(axis=1), tri[:, :, 2].max(axis=1)
    a, b, c = (tri[(low <= 0.0) & (high >= 0.0), i] for i in range(3))
    e1, e2 = b - a, c - a
    best = math.inf
    for angle in angles:
        d = np.array([math.cos(angle), math.sin(angle), 0.0])
        p = np.cross(d, e2)
        det = np.einsum("ij,ij->i", e1, p)
        with np.errstate(divide="ignore", invalid="ignore"):
            u = np.einsum("ij,ij->i", -a, p) / det
            q = np.cross(-a, e1)
            v = (q @ d) / det
            t = np.einsum("ij,ij->i", e2, q) / det
            hit = (det != 0.0) & (u >= 0.0) & (v >= 0.0) & (u + v <= 1.0) & (t >= 0.0)
        first = float(t[hit].min()) if hit.any() else math.inf
        best = min(best, 0.0 if first > 1e-3 else first)
    return best


def _cut(program, split: bool):
    began = time.perf_counter()
    if split:
        part, report = machinesim.cut(program, "robonano_ui", tool="v:90",
                                      stock="block:10x10x2")
    else:
        def never(p0, p1, x0, x1):
            return np.zeros(len(p0), dtype=bool)
        with mock.patch.object(tilted_profiles, "crossing", never):
            part, report = machinesim.cut(program, "robonano_ui", tool="v:90",
                                          stock="block:10x10x2")
    return part, report, time.perf_counter() - began


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--degrees", type=float, default=20.0)
    args = parser.parse_args()
    program = parse_program(f"G21 G90\nG00 X5. Y5. Z1.\nG01 Z-{DEPTH_MM} F10.\n"
                            f"A{args.degrees:g} F100.\nG00 Z1.\nM30\n", "spin.nc")
    unswept = np.radians(np.linspace(91.0 + args.degrees, 269.0, 80))
    runs = {True: [], False: []}
    for _ in range(args.repeat):
        for split in (True, False):
            runs[split].append(_cut(program, split))
    for split, name in ((True, "split halves (default)"), (False, "one hull (before)")):
        part, report, _ = runs[split][-1]
        gap = _nearest_material(part, np.array([5e-3, 5e-3, -1e-8]), unswept)
        engine = statistics.median(r[1].engine_s for r in runs[split])
        whole = statistics.median(r[2] for r in runs[split])
        print(f"{name:24s} sweeps {report.sweeps:5d}  engine {engine:6.2f} s  cut "
              f"{whole:6.2f} s  into the unswept wedge {gap * 1e9:7.3f} nm  removed "
              f"{report.removed_volume_m3 * 1e18:.6g} um^3")


if __name__ == "__main__":
    main()
