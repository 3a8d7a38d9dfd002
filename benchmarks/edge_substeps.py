"""The planar tool's edge rule (`machinesim.motion.faces.edge_substeps`) on a C turn, end to
end in `motion.plan`: every edge's waist read at every sub-step (as before) against only
the edges its bound cannot clear (`faces._uncleared`, the default), and the plan without
the profile, in the same run.

C360 at X5 on grooving_4axis under ``nose:1.0:90`` (559 edges: the arc's 556 chords of
2.8 um, two flanks and the top) 50 um deep, at its default 1 nm chord: 8,258 samples, the
same with each rule (printed). Each variant is planned ``--repeat`` times, alternating;
the medians of the wall time and of the process's CPU time of the whole plan and of the
edge rule in it are printed (the CPU time is the steadier figure on a shared machine).

    .venv/bin/python benchmarks/edge_substeps.py [--repeat 5] [--variants every bounded none]
"""

from __future__ import annotations

import argparse
import functools
import statistics
import time
from unittest import mock

import numpy as np

import machinesim
from machinesim import motion
from machinesim.motion import faces
from machinesim.nc import parse_program
from machinesim.tool_specs import tool_from_spec

PROGRAM = "G21 G90\nG00 X5. Y0. Z1. C0.\nG01 Z-0.05 F10.\nC360. F100.\nM30\n"
CHORD = 1e-9


def _plan(machine, program, tool, variant: str):
    """One plan: (samples, wall s, CPU s, edge rule's wall s, its CPU s)."""
    points = np.asarray(tool.vertices())
    profile = None if variant == "none" else faces.ProfileEdges(points[tool.edges()], 0.0)
    rule = faces.edge_substeps
    spent = [0.0, 0.0]

    def timed(*args):
        began, cpu = time.perf_counter(), time.process_time()
        found = rule(*args)
        spent[0] += time.perf_counter() - began
        spent[1] += time.process_time() - cpu
        return found

    every = functools.partial(faces._largest_waists, bounded=False)
    with mock.patch.object(faces, "edge_substeps", timed), \
            mock.patch.object(faces, "_largest_waists",
                              every if variant == "every" else faces._largest_waists):
        began, cpu = time.perf_counter(), time.process_time()
        plan = motion.plan(program, machine, tool_points=points, chord_tolerance=CHORD,
                           profile=profile)
        return (len(plan.q), time.perf_counter() - began, time.process_time() - cpu,
                *spent)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--variants", nargs="+", default=["every", "bounded", "none"],
                        choices=["every", "bounded", "none"])
    args = parser.parse_args()
    machine = machinesim.load_machine("grooving_4axis")
    tool = tool_from_spec("nose:1.0:90")
    program = parse_program(PROGRAM, "c360.nc")
    titles = {"every": "every edge read (before)", "bounded": "bounded (default)",
              "none": "no profile"}
    names = {name: titles[name] for name in args.variants}
    runs = {name: [] for name in names}
    for _ in range(args.repeat):
        for name in names:
            runs[name].append(_plan(machine, program, tool, name))
    for name, title in names.items():
        samples = {run[0] for run in runs[name]}
        wall, cpu, rule, rule_cpu = (statistics.median(run[i] for run in runs[name])
                                     for i in range(1, 5))
        print(f"{title:26s} samples {sorted(samples)}  plan {wall:6.2f} s (CPU {cpu:5.2f} s)"
              f"  edge rule {rule:6.3f} s (CPU {rule_cpu:6.3f} s)")


if __name__ == "__main__":
    main()
