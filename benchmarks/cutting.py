"""Speed and memory of the material-removal engine (machinesim.cutting.engine.remove).

Scenarios (poses built directly as 4x4 arrays, no kinematics):

a. 2000 parallel 90-deg V grooves, 20 um pitch, 10 um deep, on a 40 x 10 mm block.
   Goal >= 10,000 sweeps/s.
b. Crossing pattern, 500 x 500 grooves, 50 um pitch, 25 um deep (pyramids, seed 003).
   Goal >= 1,000,000 output triangles/s.
c. A 20-deg rotary sweep of a V tool about an axis 100 mm away, split into sub-steps whose
   chord error stays under 1 nm (`rotary_substeps`). Goal >= 5,000 sub-steps/s.
d. 400 x 400 mm plate, 8000 x 8000 grooves at 50 um pitch, cut only in 25 windows of 1 x 1 mm.
   Goal < 60 s and < 2 GB.
e. Case a end to end: an NC program of the 2000 grooves (each: rapid over its start, rapid
   down beside the block, feed across it, rapid up; 8000 moves) cut by `machinesim.cut` on
   the grooving_4axis machine, grooves along X (the tool's cutting direction at C = 0) on a
   10 x 40 x 2 mm block. Goals (issue 12): >= 10,000 grooves/s end to end, and the whole
   call within twice the engine's own time (`CutReport.engine_s`) in the same run.
f. Slanted pyramids end to end (issue 14): 500 x 500 crossing grooves, 50 um pitch, 25 um
   deep, as an NC program cut by `machinesim.cut` on grooving_4axis with the squareness and
   C-table errors of paper 003's default model (`models/errors/xy_plane_grooving_4axis.toml`:
   EC0Y, held at the 24 urad the figures were measured with, the C table's offsets and
   tilts EX0C, EY0C, EA0C, EB0C and its wobble EAC(C), EBC(C)), the first set along X at
   C = 0.3 deg, the second at C = 90.6 deg: both sets slanted on the block, 90.3 deg apart,
   and sloped along their length by the table's tilt, so the height field grids them in
   their own directions with a slope term each. Goal
   >= 1,000,000 output triangles/s end to end. In the same run: the boolean engine and the
   relief on a 100 x 100 pattern of the same slants (paths built directly, level), and, once,
   the 500 x 500 program with that model whole (its straightness and yaw tables bend and fan
   the grooves, which only the boolean engine cuts).
g. Paper 002's crown before compensation, as its default run cuts it (``make demo``: the
   nominal program on robonano_a0ib with the scenario's default errors and lab realism,
   seed 0; 3806 feed sweeps in 8 C groups, `cut_turned`): each parallel group subtracted
   in runs of overlapping pairs (`tiling.union_runs`, the engine's default) against one
   union per group (before), in the same run, and the two parts compared (heights over a
   grid, and the volume of each part less the other). A face's finishing passes, stacked
   down it, overlap each other: the case the runs exist for. Once each (``--repeat`` is
   not used: about 5 min).
h. A ball end mill on arcs, ``machinesim cut`` end to end (what the user waits for, the
   PLY written): a full circle (two G02 half arcs) of radius 3 mm, 0.2 mm deep, with
   ``ball:0.5`` on grooving_4axis, with the default chord tolerance (a tenth of the ball's
   1 um facets: 100 nm, `machinesim.tools.path_chord_tolerance`) against ``--chord-nm 1``
   (the 1 nm every cut took before) in the same run, and the two parts compared: removed
   volumes, and the largest height difference over a 10 um grid across the groove
   (`machinesim.metrology.surface.height_map` on each written PLY). Each in its own
   process; ``--repeat`` runs each (the 1 nm one takes about 2 min a run).

a, b and d are run twice, each in its own process: with the default engine (``method="auto"``,
which meshes straight grooves across a block as an exact height field,
`machinesim.cutting.relief`) and with the boolean engine alone (``method="boolean"``), so the
two are compared in one run. For b the relief mesh has more triangles than the boolean one
for the same solid (each pyramid face is split where the other groove set has a corner), so
its rate is also given per triangle of the boolean part.

For a and b the naive engine (subtract one sweep hull at a time, evaluating the mesh after
each) is too slow to run whole, so it is timed in the same run on a subset: per sweep on the
first sweeps (small mesh) and per sweep on the engine's final part (full-size mesh, grooves
shifted by a quarter pitch). Its cost per sweep grows with the mesh, which grows about
linearly with the sweeps done, so the whole naive job is estimated as the sweep count times
the mean of the two (for b, the first direction on the stock is priced separately: it leaves
a small mesh). The plain lower bound (every sweep at the first, small-mesh cost) is printed
too.

Each scenario runs in its own process so that its peak memory (ru_maxrss, which includes
manifold3d's C++ heap, unlike tracemalloc) is its own. Times are medians of ``--repeat`` runs.

Run: ``.venv/bin/python benchmarks/cutting.py [--scenarios abcdefgh] [--repeat 3] [--no-naive]``
"""

from __future__ import annotations

import argparse
import json
import math
import resource
import statistics
import subprocess
import sys
import time
import tomllib
from pathlib import Path

import manifold3d
import numpy as np

from machinesim.cutting import remove, rotary_substeps
from machinesim.tools import VTool
from machinesim.workpiece import block

V90 = VTool(math.pi / 2.0)
#: Tool X along workpiece +Y: the grooves of the Y set are cut with this orientation.
ALONG_Y = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])


def pose(rotation: np.ndarray, position) -> np.ndarray:
    """4x4 wMt from a rotation (3, 3) and a position (3,) in m."""
    matrix = np.eye(4)
    matrix[:3, :3] = rotation
    matrix[:3, 3] = position
    return matrix


def grooves_along_x(ys, depth: float, x0: float, x1: float) -> list[np.ndarray]:
    """One straight path per groove, tool along +X at height -depth, from x0 to x1 (m)."""
    return [np.array([pose(np.eye(3), (x0, y, -depth)), pose(np.eye(3), (x1, y, -depth))])
            for y in ys]


def grooves_along_y(xs, depth: float, y0: float, y1: float) -> list[np.ndarray]:
    """One straight path per groove, tool along +Y at height -depth, from y0 to y1 (m)."""
    return [np.array([pose(ALONG_Y, (x, y0, -depth)), pose(ALONG_Y, (x, y1, -depth))])
            for x in xs]


def naive(part: manifold3d.Manifold, tool, paths, count: int) -> float:
    """Seconds per sweep of naive one-at-a-time subtraction over the first ``count`` sweeps."""
    vertices = tool.vertices()
    start = time.perf_counter()
    done = 0
    for path in paths:
        for a, b in zip(path[:-1], path[1:], strict=True):
            points = np.concatenate([vertices @ a[:3, :3].T + a[:3, 3],
                                     vertices @ b[:3, :3].T + b[:3, 3]])
            part = part - manifold3d.Manifold.hull_points(points)
            part.num_tri()
            done += 1
            if done == count:
                return (time.perf_counter() - start) / done
    return (time.perf_counter() - start) / max(done, 1)


def shifted(paths, offset) -> list[np.ndarray]:
    """Copies of ``paths`` translated by ``offset`` (3,) m."""
    moved = [np.array(path) for path in paths]
    for path in moved:
        path[:, :3, 3] += offset
    return moved


def scenario_a():
    stock = block(40e-3, 10e-3, 2e-3)
    paths = grooves_along_y(10e-6 + 20e-6 * np.arange(2000), 10e-6, -0.5e-3, 10.5e-3)
    return stock, V90, paths, None


def crossing(count: int, height: float, overrun: float):
    """Block and paths of ``count`` x ``count`` crossing grooves, 50 um pitch, 25 um deep."""
    pitch = 50e-6
    side = pitch * count
    centres = pitch / 2 + pitch * np.arange(count)
    paths = (grooves_along_y(centres, 25e-6, -overrun, side + overrun)
             + grooves_along_x(centres, 25e-6, -overrun, side + overrun))
    return block(side, side, height), paths


def scenario_b():
    stock, paths = crossing(500, 2e-3, 0.5e-3)
    return stock, V90, paths, None


def scenario_c():
    radius, sweep = 0.1, math.radians(20.0)
    steps = rotary_substeps(radius, sweep, 1e-9)
    stock = block(10e-3, 4e-3, 2e-3)
    axis = np.array([5e-3, 2e-3, radius - 10e-6])
    poses = []
    # Decreasing angle moves the tip along +X, the cutting direction of the tool.
    for angle in np.linspace(sweep / 2, -sweep / 2, steps + 1):
        c, s = math.cos(angle), math.sin(angle)
        rotation = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
        poses.append(pose(rotation, axis + rotation @ np.array([0.0, 0.0, -radius])))
    return stock, V90, [np.array(poses)], None


def scenario_d():
    stock, paths = crossing(8000, 10e-3, 1e-3)
    starts = 40.0123e-3 + 80e-3 * np.arange(5)
    roi = [(x, x + 1e-3, y, y + 1e-3) for x in starts for y in starts]
    return stock, V90, paths, roi


def groove_program(count: int = 2000, pitch: float = 20e-6, depth: float = 10e-6):
    """Case a as an NC program: grooves along X across a 10 mm block, rapids beside it."""
    from machinesim.nc import ProgramBuilder

    builder = ProgramBuilder(1, source="benchmark case e")
    for i in range(count):
        builder.rapid(X=-0.5e-3, Y=pitch / 2 + pitch * i, Z=0.1e-3).rapid(Z=-depth)
        builder.linear(X=10.5e-3, feed_mm_per_min=500.0).rapid(Z=0.1e-3)
    return builder.build()


def run_end_to_end(repeat: int) -> dict:
    """Case e: machinesim.cut end to end, and the engine's share of each run."""
    from machinesim import load_machine
    from machinesim.cutting import cut

    program, machine = groove_program(), load_machine("grooving_4axis")
    stock = block(10e-3, 40e-3, 2e-3)
    times, engine = [], []
    for _ in range(repeat):
        start = time.perf_counter()
        part, report = cut(program, machine, tool=V90, stock=stock)
        times.append(time.perf_counter() - start)
        engine.append(report.engine_s)
    return {"scenario": "e", "method": report.engine, "median_s": statistics.median(times),
            "times_s": times, "median_engine_s": statistics.median(engine),
            "engine_s": engine, "grooves": 2000, "moves": len(program.moves),
            "sweeps_cut": report.sweeps, "removed_volume_m3": report.removed_volume_m3,
            "ratios": [t / e for t, e in zip(times, engine, strict=True)],
            "triangles": len(part.mesh()[1]),
            "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0}


#: Case f: C positions of the two groove sets (rad).
SLANT_C = (math.radians(0.3), math.radians(90.6))
#: Case f: paper 003's default error model; its squareness and C-table errors slant and
#: slope the grooves.
XY_PLANE_ERRORS = (Path(__file__).resolve().parents[1] / "models" / "errors"
                   / "xy_plane_grooving_4axis.toml")


def slant_errors(whole: bool = False):
    """Case f's errors: the squareness (24 urad) and C-table part of `XY_PLANE_ERRORS`, or
    all of it."""
    from machinesim.errors.model import ErrorModel

    with open(XY_PLANE_ERRORS, "rb") as handle:
        table = tomllib.load(handle)
    # the squareness case f's figures (docs/cutting.md) were measured with: the default
    # file's EC0Y is -12 urad since its figures are read in the paper's form of eq 1
    table["location"]["Y"]["EC0Y_urad"] = 24.0
    if not whole:
        table = {"location": table["location"], "component": {"C": table["component"]["C"]}}
    return ErrorModel.from_dict(table)


def pyramid_program(count: int, pitch: float = 50e-6, depth: float = 25e-6,
                    overrun: float = 1e-3):
    """Case f as an NC program: two sets of grooves along X, C turned between them.

    The block is centred on the C axis; each groove: rapid beside the block, down, feed
    across it, rapid up.
    """
    from machinesim.nc import ProgramBuilder

    side = count * pitch
    builder = ProgramBuilder(1, source="benchmark case f")
    ys = -side / 2 + pitch / 2 + pitch * np.arange(count)
    for c in SLANT_C:
        builder.rapid(Z=0.1e-3).rapid(C=c)
        for y in ys:
            builder.rapid(X=-side / 2 - overrun, Y=y, Z=0.1e-3).rapid(Z=-depth)
            builder.linear(X=side / 2 + overrun, feed_mm_per_min=500.0).rapid(Z=0.1e-3)
    return builder.build()


def slanted_crossing(count: int, pitch: float = 50e-6, depth: float = 25e-6):
    """Block and paths of case f's pattern built directly (no errors): each set along X
    turned by its C position, as the table's turn by C leaves it on the block."""
    side = count * pitch
    centres = -side / 2 + pitch / 2 + pitch * np.arange(count)
    paths = []
    for c in SLANT_C:
        turn = np.array([[math.cos(c), -math.sin(c), 0.0], [math.sin(c), math.cos(c), 0.0],
                         [0.0, 0.0, 1.0]])
        d, n = turn[:, 0], turn[:, 1]
        for y in centres:
            middle = y * n + np.array([0.0, 0.0, -depth])
            paths.append(np.array([pose(turn, middle - (side / 2 + 1e-3) * d),
                                   pose(turn, middle + (side / 2 + 1e-3) * d)]))
    return block(side, side, 2e-3, origin=(-side / 2, -side / 2, 0.0)), paths


def run_slanted(repeat: int) -> dict:
    """Case f: machinesim.cut end to end, and both engines on a smaller pattern."""
    from machinesim import load_machine
    from machinesim.cutting import cut

    count = 500
    program, machine = pyramid_program(count), load_machine("grooving_4axis")
    errors = slant_errors()
    side = count * 50e-6
    stock = block(side, side, 2e-3, origin=(-side / 2, -side / 2, 0.0))
    times, engine, cpu = [], [], []
    for _ in range(repeat):
        before = resource.getrusage(resource.RUSAGE_SELF)
        start = time.perf_counter()
        part, report = cut(program, machine, tool=V90, stock=stock, errors=errors)
        times.append(time.perf_counter() - start)
        after = resource.getrusage(resource.RUSAGE_SELF)
        cpu.append(after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime)
        engine.append(report.engine_s)
    small_stock, small_paths = slanted_crossing(100)
    small = {}
    for method in ("boolean", "auto"):
        start = time.perf_counter()
        small_part, small_report = remove(small_stock, V90, small_paths, method=method)
        small[small_report.method] = (time.perf_counter() - start,
                                      len(small_part.mesh()[1]))
    start = time.perf_counter()
    whole_part, whole_report = cut(program, machine, tool=V90, stock=stock,
                                   errors=slant_errors(whole=True))
    whole = (whole_report.engine, time.perf_counter() - start, len(whole_part.mesh()[1]))
    return {"scenario": "f", "method": report.engine, "median_s": statistics.median(times),
            "times_s": times, "median_engine_s": statistics.median(engine),
            "median_cpu_s": statistics.median(cpu),
            "triangles": len(part.mesh()[1]), "sweeps_cut": report.sweeps,
            "families": [f.normal.tolist() for f in part.reliefs[0].families]
            if part.reliefs else [],
            "slopes": [f.slope for f in part.reliefs[0].families] if part.reliefs else [],
            "small": small, "whole_model": whole,
            "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0}


SCENARIOS = {"a": scenario_a, "b": scenario_b, "c": scenario_c, "d": scenario_d}
#: Sweeps timed by the naive engine at the start, and on the final part (a, b only).
NAIVE_SWEEPS = {"a": (200, 10), "b": (20, 3)}
#: Quarter-pitch shift (m) for the sweeps timed on the final part: new grooves, not repeats.
NAIVE_SHIFT = {"a": (5e-6, 0.0, 0.0), "b": (0.0, 12.5e-6, 0.0)}


def naive_estimate(name: str, stock, tool, paths, final) -> dict:
    """Naive per-sweep costs (s) at the start and on the final part, and the whole estimate."""
    first, last = NAIVE_SWEEPS[name]
    end = naive(final.manifold, tool, shifted(paths[-last:], NAIVE_SHIFT[name]), last)
    if name == "a":
        start = naive(stock.manifold, tool, paths, first)
        return {"naive_start_s": start, "naive_end_s": end,
                "naive_lower_s": start * len(paths),
                "naive_estimate_s": len(paths) * (start + end) / 2}
    half = len(paths) // 2
    start_first = naive(stock.manifold, tool, paths[:half], first)
    sawtooth, _ = remove(stock, tool, paths[:half])
    start = naive(sawtooth.manifold, tool, paths[half:], first)
    return {"naive_start_s": start, "naive_end_s": end,
            "naive_lower_s": half * (start_first + start),
            "naive_estimate_s": half * start_first + half * (start + end) / 2}


def run_child(name: str, repeat: int, with_naive: bool, method: str) -> dict:
    """Run one scenario here and return its figures."""
    stock, tool, paths, roi = SCENARIOS[name]()
    times, cpu = [], []
    for _ in range(repeat):
        before = resource.getrusage(resource.RUSAGE_SELF)
        start = time.perf_counter()
        part, report = remove(stock, tool, paths, roi=roi, method=method)
        times.append(time.perf_counter() - start)
        after = resource.getrusage(resource.RUSAGE_SELF)
        cpu.append(after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime)
    figures = {
        "scenario": name,
        "method": report.method,
        "median_s": statistics.median(times),
        "times_s": times,
        "median_cpu_s": statistics.median(cpu),
        "sweeps": report.n_sweeps,
        "sweeps_cut": report.n_sweeps_cut,
        "cells": report.n_cells,
        "triangles": len(part.mesh()[1]),
        "removed_volume_m3": report.removed_volume,
        # Peak before the naive runs: the engine's own figure.
        "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
    }
    if with_naive and name in NAIVE_SWEEPS:
        figures.update(naive_estimate(name, stock, tool, paths, part))
    return figures


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenarios", default="abcdefgh")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--no-naive", action="store_true")
    parser.add_argument("--child", help=argparse.SUPPRESS)
    parser.add_argument("--method", default="auto", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child == "e":
        print(json.dumps(run_end_to_end(args.repeat)))
        return
    if args.child == "f":
        print(json.dumps(run_slanted(args.repeat)))
        return
    if args.child == "g":
        print(json.dumps(run_crown_before()))
        return
    if args.child == "h":
        print(json.dumps(run_ball_arcs(args.repeat, args.method)))
        return
    if args.child:
        print(json.dumps(run_child(args.child, args.repeat, not args.no_naive, args.method)))
        return
    boolean_triangles = {}
    for name in args.scenarios:
        if name == "e":
            run_end_to_end_child(args)
            continue
        if name == "f":
            run_slanted_child(args)
            continue
        if name == "g":
            run_crown_before_child()
            continue
        if name == "h":
            run_ball_arcs_children(args)
            continue
        for method in ("boolean", "auto") if name in "abd" else ("auto",):
            run_one(name, method, args, boolean_triangles)


def child_figures(name: str, *options: str) -> dict:
    """Run case ``name`` in a child process (its own peak memory) and return its figures."""
    command = [sys.executable, __file__, "--child", name, *options]
    out = subprocess.run(command, check=True, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def run_end_to_end_child(args) -> None:
    """Run case e in a child process and print its line: both figures from the same runs."""
    f = child_figures("e", "--repeat", str(args.repeat))
    print(f"(e, cut end to end, {f['method']}) median {f['median_s']:.3f} s over "
          f"{len(f['times_s'])} runs: {f['grooves'] / f['median_s']:,.0f} grooves/s "
          f"({f['moves']} moves, {f['sweeps_cut']} sweeps cut); the engine's own time in "
          f"the same runs median {f['median_engine_s']:.3f} s; end to end / engine: median "
          f"{statistics.median(f['ratios']):.2f}x (runs "
          f"{', '.join(f'{r:.2f}' for r in f['ratios'])}); peak RSS "
          f"{f['peak_rss_mb']:.0f} MB", flush=True)


def run_slanted_child(args) -> None:
    """Run case f in a child process and print its line."""
    f = child_figures("f", "--repeat", str(args.repeat))
    (b_s, b_tri), (r_s, r_tri) = f["small"]["boolean"], f["small"]["relief"]
    print(f"(f, slanted pyramids cut end to end, {f['method']}) median {f['median_s']:.3f} s "
          f"over {len(f['times_s'])} runs (runs {', '.join(f'{t:.3f}' for t in f['times_s'])}; "
          f"engine median {f['median_engine_s']:.3f} s); {f['sweeps_cut']} sweeps cut -> "
          f"{f['triangles']} triangles: {f['triangles'] / f['median_s']:,.0f} triangles/s "
          f"(cpu median {f['median_cpu_s']:.3f} s: "
          f"{f['triangles'] / f['median_cpu_s']:,.0f} per cpu second); "
          f"groove normals {[[round(c, 6) for c in n] for n in f['families']]}, slopes "
          f"{', '.join(f'{a * 1e6:.2f} urad' for a in f['slopes'])}; "
          f"100 x 100 of the same slants: boolean {b_s:.2f} s ({b_tri} triangles), relief "
          f"{r_s:.3f} s ({r_tri} triangles); the whole error model (grooves bent and fanned "
          f"by straightness and yaw), once: {f['whole_model'][0]} {f['whole_model'][1]:.1f} s "
          f"({f['whole_model'][2]} triangles, "
          f"{f['whole_model'][2] / f['whole_model'][1]:,.0f} triangles/s); peak RSS "
          f"{f['peak_rss_mb']:.0f} MB", flush=True)


def run_crown_before() -> dict:
    """Case g: paper 002's crown before compensation, cut with runs and with one union."""
    from _crown import crown_before

    from machinesim.cam.crown import PARK
    from machinesim.cutting import engine
    from machinesim.metrology.surface import height_map

    lab, procedure, layout, program = crown_before()

    def cut():
        start = time.perf_counter()
        part, report = lab.cut(program, layout.tool, procedure.workpiece(lab),
                               roi=layout.boxes, floor=layout.floor, start=PARK,
                               turn_step=math.pi / 4)
        return part, report, time.perf_counter() - start

    runs, (runs_part, report, runs_s) = engine.union_runs, cut()
    engine.union_runs = lambda members, lower, upper: [members]
    try:
        one_part, _, one_s = cut()
    finally:
        engine.union_runs = runs
    low, high = runs_part.bounds
    x, y = (np.linspace(low[a], high[a], 1000) for a in (0, 1))
    a, b = height_map(runs_part, x, y), height_map(one_part, x, y)
    return {"runs_s": runs_s, "one_union_s": one_s, "sweeps": report.sweeps,
            "engine_s": report.engine_s, "max_height_diff_m": float(np.nanmax(np.abs(a - b))),
            "nan_mismatch": int(np.count_nonzero(np.isnan(a) != np.isnan(b))),
            "runs_less_one_m3": (runs_part.manifold - one_part.manifold).volume(),
            "one_less_runs_m3": (one_part.manifold - runs_part.manifold).volume(),
            "triangles": [runs_part.manifold.num_tri(), one_part.manifold.num_tri()],
            "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0}


def run_crown_before_child() -> None:
    """Run case g in a child process and print its line."""
    f = child_figures("g")
    print(f"(g, paper 002's crown before compensation, cut_turned) runs "
          f"{f['runs_s']:.1f} s (engine {f['engine_s']:.1f} s), one union per group "
          f"{f['one_union_s']:.1f} s: {f['one_union_s'] / f['runs_s']:.1f}x; "
          f"{f['sweeps']} sweeps cut; the parts: heights over 1000 x 1000 apart by at most "
          f"{f['max_height_diff_m']:.2e} m ({f['nan_mismatch']} samples on one part only), "
          f"runs less one union {f['runs_less_one_m3']:.2e} m^3, one union less runs "
          f"{f['one_less_runs_m3']:.2e} m^3, triangles {f['triangles'][0]} and "
          f"{f['triangles'][1]}; peak RSS {f['peak_rss_mb']:.0f} MB", flush=True)


#: Case h: a full circle of radius 3 mm about (5, 5) mm, 0.2 mm deep, as two G02 half arcs.
BALL_ARCS_NC = ("%\nG90 G21 G94 G17\nG00 X2. Y5. Z1.\nG01 Z-0.2 F200.\n"
                "G02 X8. Y5. I3. J0. F300.\nG02 X2. Y5. I-3. J0.\nG00 Z1.\nM30\n%\n")


def run_ball_arcs(repeat: int, chord_nm: str) -> dict:
    """Case h, one chord setting (``"default"`` or nm): ``machinesim cut`` run ``repeat``
    times in this process, timed end to end; the part's heights over a grid across the
    groove, for the comparison."""
    import tempfile

    from machinesim.cli import main as cli
    from machinesim.metrology.surface import height_map
    from machinesim.viewer.meshes import read_ply
    from machinesim.workpiece import Part

    folder = Path(tempfile.mkdtemp())
    program, out, report = folder / "arcs.nc", folder / "part.ply", folder / "report.json"
    program.write_text(BALL_ARCS_NC)
    argv = ["cut", str(program), "--machine", "grooving_4axis", "--tool", "ball:0.5",
            "--stock", "block:10x10x2", "--quiet", "--out", str(out), "--report", str(report)]
    if chord_nm != "default":
        argv += ["--chord-nm", chord_nm]
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        if cli(argv) != 0:
            raise SystemExit("case h: machinesim cut failed")
        times.append(time.perf_counter() - start)
    summary = json.loads(report.read_text())
    vertices, faces = read_ply(out)
    part = Part(manifold3d.Manifold(manifold3d.Mesh64(vert_properties=vertices,
                                                      tri_verts=faces.astype(np.uint64))))
    # across the groove on the +X side of the circle (x 7.5..8.5 mm at y = 5 mm) and at
    # 45 deg, 10 um apart
    grid = np.arange(-0.5e-3, 0.5e-3 + 1e-9, 10e-6)
    heights = [height_map(part, 8e-3 + grid, np.array([5e-3]))[0].tolist()]
    diagonal = 5e-3 + (3e-3 + grid) / math.sqrt(2.0)
    heights += [[float(height_map(part, np.array([x]), np.array([x]))[0, 0])
                 for x in diagonal]]
    return {"chord": chord_nm, "median_s": statistics.median(times), "times_s": times,
            "sweeps": summary["sweeps_count"], "chord_nm": summary["path_chord_tolerance_nm"],
            "removed_mm3": summary["removed_volume_mm3"], "heights": heights,
            "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0}


def run_ball_arcs_children(args) -> None:
    """Case h: the default chord and 1 nm, each in its own process, compared in one run."""
    runs = [child_figures("h", "--repeat", str(args.repeat), "--method", chord)
            for chord in ("default", "1")]
    for f in runs:
        print(f"(h, ball on arcs end to end, chord {f['chord_nm']:g} nm) median "
              f"{f['median_s']:.2f} s over {len(f['times_s'])} runs (runs "
              f"{', '.join(f'{t:.2f}' for t in f['times_s'])}); {f['sweeps']} sweeps; "
              f"removed {f['removed_mm3']:.9f} mm^3; peak RSS {f['peak_rss_mb']:.0f} MB",
              flush=True)
    coarse, fine = runs
    difference = np.nanmax(np.abs(np.array(coarse["heights"]) - np.array(fine["heights"])))
    print(f"(h) {fine['median_s'] / coarse['median_s']:.1f}x faster at "
          f"{coarse['chord_nm']:g} nm; removed volumes differ by "
          f"{(coarse['removed_mm3'] - fine['removed_mm3']) / fine['removed_mm3']:+.2e} "
          f"relative; heights across the groove by at most {difference * 1e9:.1f} nm",
          flush=True)


def run_one(name: str, method: str, args, boolean_triangles: dict) -> None:
    """Run one scenario with one engine in a child process and print its line."""
    naive_off = ["--no-naive"] if args.no_naive or method == "boolean" else []
    f = child_figures(name, "--repeat", str(args.repeat), "--method", method, *naive_off)
    if f["method"] == "boolean":
        boolean_triangles[name] = f["triangles"]
    line = (f"({name}, {f['method']}) median {f['median_s']:.3f} s "
            f"(cpu {f['median_cpu_s']:.3f} s) over "
            f"{len(f['times_s'])} runs; {f['sweeps']} sweeps ({f['sweeps_cut']} cut, "
            f"{f['cells']} cells) -> {f['triangles']} triangles; "
            f"peak RSS {f['peak_rss_mb']:.0f} MB")
    rate = {"a": f["sweeps"] / f["median_s"], "b": f["triangles"] / f["median_s"],
            "c": f["sweeps"] / f["median_s"], "d": None}[name]
    unit = {"a": "sweeps/s", "b": "triangles/s", "c": "sub-steps/s", "d": ""}[name]
    if rate is not None:
        line += f"; {rate:,.0f} {unit}"
    if name == "b" and f["method"] == "relief" and name in boolean_triangles:
        line += (f" ({boolean_triangles[name] / f['median_s']:,.0f} per triangle of the "
                 f"boolean part, {boolean_triangles[name]})")
    if "naive_estimate_s" in f:
        line += (f"; naive {f['naive_start_s'] * 1e3:.2f} ms/sweep at the start, "
                 f"{f['naive_end_s'] * 1e3:.2f} ms/sweep on the final part -> about "
                 f"{f['naive_estimate_s']:.1f} s whole (at least "
                 f"{f['naive_lower_s']:.1f} s): ratio ~"
                 f"{f['naive_estimate_s'] / f['median_s']:.0f}x (>= "
                 f"{f['naive_lower_s'] / f['median_s']:.1f}x)")
    print(line, flush=True)


if __name__ == "__main__":
    main()
