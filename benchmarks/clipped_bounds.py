"""The bounds of sweeps cut at the clip plane (`machinesim.cutting.sweeps.clipped_bounds`):
every segment cut at the plane (as before) against only the segments that cross it (the
default), alone and inside `SweepSet.hulls`, in the same run.

The sweeps are paper 002's crown passes' kind: Table 2's round nose (`crown_tool`,
``--height-um`` tall: 391 profile points at 150 um) moved level along X, ``--sweeps`` of
them at ``--depth-um`` below the clip plane, each pass ``--pitch-um`` over in Y. Each variant runs
``--repeat`` times, alternating; the medians of the wall and the process's CPU time are
printed (the CPU time is the steadier figure on a shared machine), and whether the two give
the same bounds bit for bit.

    .venv/bin/python benchmarks/clipped_bounds.py [--repeat 5] [--sweeps 1307]
"""

from __future__ import annotations

import argparse
import statistics
import time
from unittest import mock

import numpy as np

from machinesim.cam.crown import crown_tool
from machinesim.cutting import sweepset
from machinesim.cutting.sweeps import clipped_bounds
from machinesim.cutting.sweepset import SweepSet
from machinesim.units import M_PER_UM


def every_segment(points: np.ndarray, segments: np.ndarray, level: float):
    """`clipped_bounds` as it was: every segment cut at the plane, the crossing ones read."""
    below = points[:, :, 2] <= level
    a, b = points[:, segments[:, 0]], points[:, segments[:, 1]]
    crossing = below[:, segments[:, 0]] != below[:, segments[:, 1]]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (level - a[:, :, 2]) / (b[:, :, 2] - a[:, :, 2])
        cut = a + t[:, :, None] * (b - a)
    cut[:, :, 2] = level
    every = np.concatenate([points, cut], axis=1)
    valid = np.concatenate([below, crossing], axis=1)[:, :, None]
    return (np.where(valid, every, np.inf).min(axis=1),
            np.where(valid, every, -np.inf).max(axis=1))


VARIANTS = {"every": every_segment, "crossing": clipped_bounds}


def passes(count: int, depth: float, pitch: float, length: float = 0.6e-3) -> list:
    """``count`` level passes along X, ``depth`` below z = 0, ``pitch`` apart in Y."""
    paths = []
    for i in range(count):
        poses = np.repeat(np.eye(4)[None], 2, axis=0)
        poses[:, :3, 3] = [(0.0, i * pitch, -depth), (length, i * pitch, -depth)]
        paths.append(poses)
    return paths


def timed(function, *args):
    began, cpu = time.perf_counter(), time.process_time()
    value = function(*args)
    return value, time.perf_counter() - began, time.process_time() - cpu


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--sweeps", type=int, default=1307)
    parser.add_argument("--depth-um", type=float, default=10.0)
    parser.add_argument("--height-um", type=float, default=150.0)
    parser.add_argument("--pitch-um", type=float, default=1.0)
    args = parser.parse_args()
    tool = crown_tool(args.height_um * M_PER_UM)
    paths = passes(args.sweeps, args.depth_um * M_PER_UM, args.pitch_um * M_PER_UM)
    probe = SweepSet(tool, paths, 1e-9)
    segments = probe.translation_segments
    points = np.concatenate([probe.world(probe.pairs), probe.world(probe.pairs + 1)], axis=1)
    print(f"{args.sweeps} sweeps of {len(probe.vertices)} profile points, "
          f"{len(segments)} segments each, {args.depth_um:g} um deep")
    alone = {name: [] for name in VARIANTS}
    hulls = {name: [] for name in VARIANTS}
    bounds, built = {}, {}
    for _ in range(args.repeat):
        for name, function in VARIANTS.items():
            bounds[name], wall, cpu = timed(function, points, segments, 1e-9)
            alone[name].append((wall, cpu))
            with mock.patch.object(sweepset, "clipped_bounds", function):
                sweeps = SweepSet(tool, paths, 1e-9)
                built[name], wall, cpu = timed(sweeps.hulls, lambda low, high:
                                               np.ones(len(low), dtype=bool))
            hulls[name].append((wall, cpu))
    same = all(np.array_equal(x, y) for x, y in zip(bounds["every"], bounds["crossing"],
                                                     strict=True))
    same_hulls = all(np.array_equal(built["every"][i], built["crossing"][i]) for i in (1, 2))
    print(f"bounds the same bit for bit: {same}; hulls' bounds: {same_hulls}")
    for label, runs in (("clipped_bounds", alone), ("SweepSet.hulls", hulls)):
        for name, samples in runs.items():
            wall = statistics.median(s[0] for s in samples)
            cpu = statistics.median(s[1] for s in samples)
            print(f"{label:15s} {name:9s} median of {len(samples)}: wall {wall:7.3f} s, "
                  f"CPU {cpu:7.3f} s")


if __name__ == "__main__":
    main()
