"""Servo form error of paper 004's programs: the figures of docs/procedures/sts_turning.md.

Run: ``.venv/bin/python benchmarks/servo_form_error.py`` (about a minute; prints figures and
the time each followed path took).

Each program's tool path (compensated for the R 1.0 mm nose, `machinesim.cam.spiral`) is run
through Table 6's servo loops (`machinesim.cutting.servo_path.followed_edge_path`, at 20 rpm)
and turned by the engine; the servo form error is the lagged surface minus the commanded
one (the path joined straight, `edge_path_from_tips`):

* "Units of Table 6": along theta = 0, r 150-350 um at 0.5 um (`sts_plans.MEASURE_LINE`),
  piston and tilt removed (`sts_plans.profile_error`), the P-V; Table 4's two programs
  (spline, 10 samples per step) with the "before" and the "after" preset. The damping
  `TABLE6_DAMPING` was fitted to the paper's 13 nm with "before" on the "before" program.
* "Speed": benchmarks/turning.py's Case 4 path (Constant Angle 2 deg, 45,001 points, joined
  straight, not spline-interpolated): the same profile, and on the 1000 x 1000 grid over the
  ring r 200-300 um the P-V of lagged minus commanded with a plane removed, and the machined
  surface minus the design within r 0.45 mm (the P-V benchmarks/turning.py prints).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from machinesim.cam import spiral as sp
from machinesim.cutting.servo_path import followed_edge_path
from machinesim.cutting.turning import edge_path_from_tips, turned_heights, turned_surface
from machinesim.procedures.sts_plans import MEASURE_LINE, PLANS, profile_error
from machinesim.servo import table6_servo

GRID = 1000
PRESETS = ("before", "after")


def measure_line() -> np.ndarray:
    (x0, _), (x1, _), step = MEASURE_LINE
    return x0 + step * np.arange(int(np.floor((x1 - x0) / step + 1e-9)) + 1)


def case_4_path() -> sp.ToolPath:
    """benchmarks/turning.py's Case 4 path: Constant Angle 2 deg, joined straight."""
    spiral = sp.Spiral(sp.PART_RADIUS_M, sp.FEED_M)
    points = sp.cutting_points(sp.sine_grid(), spiral, sp.constant_angle(spiral, sp.CA_STEP_RAD))
    return sp.tool_path(points, sp.NOSE_RADIUS_M)


def lagged(path: sp.ToolPath, preset: str):
    """The followed edge path, and the seconds it took."""
    start = time.perf_counter()
    edge = followed_edge_path(path, table6_servo(preset))
    return edge, time.perf_counter() - start


def profile_pv(path: sp.ToolPath, edges: dict, r: np.ndarray) -> dict:
    """P-V (m) along theta = 0 of each preset's lagged surface minus the commanded one."""
    zero = np.zeros_like(r)
    commanded = turned_heights(edge_path_from_tips(path.tips(), path.c), sp.NOSE_RADIUS_M, r,
                               zero)
    return {preset: profile_error(r, turned_heights(edge, sp.NOSE_RADIUS_M, r, zero),
                                  commanded).pv for preset, edge in edges.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.parse_args()
    r = measure_line()
    print("Servo form error along theta = 0, r 150-350 um, piston and tilt removed (nm P-V):")
    print("| path | \"before\" | \"after\" |")
    print("|---|---|---|")
    names = {"before": "Table 4 \"before\" (CAL 30 um, spline; Cases 1, 2)",
             "after": "Table 4 \"after\" (CA 2 deg, spline; Cases 3, 4)"}
    timings = []
    for plan, name in names.items():
        path = PLANS[plan].path(sp.sine_grid(), sp.NOSE_RADIUS_M)
        edges = {}
        for preset in PRESETS:
            edges[preset], seconds = lagged(path, preset)
            timings.append(f"{name.split(' (')[0]} program, {len(path):,} points, Table 6 "
                           f"{preset}: {len(edges[preset].angle):,} followed samples, "
                           f"{seconds:.2f} s")
        pv = profile_pv(path, edges, r)
        print(f"| {name} | {pv['before'] * 1e9:.2f} nm | {pv['after'] * 1e9:.2f} nm |")

    path = case_4_path()
    edges = {}
    for preset in PRESETS:
        edges[preset], seconds = lagged(path, preset)
        timings.append(f"Case 4 path joined straight, {len(path):,} points, Table 6 {preset}: "
                       f"{len(edges[preset].angle):,} followed samples, {seconds:.2f} s")
    pv = profile_pv(path, edges, r)
    print(f"\nCase 4 path joined straight ({len(path):,} points), the same profile: "
          f"{pv['before'] * 1e9:.2f} nm (\"before\"), {pv['after'] * 1e9:.2f} nm (\"after\")")
    axis = np.linspace(-sp.PART_RADIUS_M, sp.PART_RADIUS_M, GRID)
    px, py = np.meshgrid(axis, axis)
    radius = np.hypot(px, py)
    ring, face = (radius >= 200e-6) & (radius <= 300e-6), radius <= 0.45e-3
    commanded = turned_surface(edge_path_from_tips(path.tips(), path.c), sp.NOSE_RADIUS_M,
                               axis, axis)
    design = sp.sine_grid()(px, py)
    plane = np.column_stack([np.ones(np.count_nonzero(ring)), px[ring], py[ring]])
    for preset in PRESETS:
        cut = turned_surface(edges[preset], sp.NOSE_RADIUS_M, axis, axis)
        servo = (cut - commanded)[ring]
        servo = servo - plane @ np.linalg.lstsq(plane, servo, rcond=None)[0]
        print(f"  Table 6 {preset}, {GRID} x {GRID} grid: lagged - commanded over r 200-300 um, "
              f"a plane removed, {np.ptp(servo) * 1e9:.2f} nm P-V; machined - design within "
              f"r 0.45 mm {np.ptp((cut - design)[face]) * 1e9:.2f} nm P-V")
    print("\nFollowed paths (followed_edge_path):")
    for line in timings:
        print(f"  {line}")


if __name__ == "__main__":
    main()
