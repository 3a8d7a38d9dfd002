"""The grooves of paper 002 (`machinesim.cam.crown.groove_program`, the nose:2.0:90 tool,
robonano_a0ib) cut with the README's example error model, its C table (ECC over -180 ..
180 deg) stepped where C wraps (1, 0, -1 arcsec: the example before 2f2e3b7) or closed
(1, 0, 1 arcsec: the example now), each in its own process with a time limit.

A table of a whole turn repeats each turn (`machinesim.errors.turns.each_turn`); stepped,
the tool path jumped ~53 nm where the grooves' third C move (180 -> 270 deg) left 180 deg,
no number of sub-steps held the 1 nm chord, and the planner raised the move's count by 10 %
a round from 1842 towards a million, minutes a round. It is refused now, at once.

    .venv/bin/python benchmarks/wrapped_tables.py [--repeat 3] [--limit 300]
        [--root SOURCE_TREE ...]   (e.g. an old checkout exported with git archive)

Median of --repeat 5 runs (time inside the process, cut() alone), 2 cores shared with
other jobs, 2026-11-30, old = 21eaf5d exported with git archive (--limit 60):

    case     old (21eaf5d)                      new
    stepped  not done in 60 s (5 of 5 runs)     refused in 0.063 s (line 23, 53 nm step)
    closed   1.50 s                             1.54 s

The same removed volume closed (4.94446e6 um^3) and the same sub-step counts (2027 for each
of the three quarter turns). A first measurement, on a machine loaded by three other jobs,
had put the closed case at 1.44 s old and 3.37 s new; profiled warm (0.71 s both, 0.62 s of
it planning) and re-run cold, the two trees take the same time.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

RUNNER = """
import sys, time
import machinesim
import machinesim.exceptions
from machinesim.cam.crown import GROOVE_ROI, PARK, groove_program
from machinesim.errors import ErrorModel
from machinesim.procedures.workpiece_setting import GROOVE_TOOL, RobotLoadedWorkpiece
ends = {"stepped": [1.0, 0.0, -1.0], "closed": [1.0, 0.0, 1.0]}[sys.argv[1]]
import tomllib
example = tomllib.loads(open("models/errors/example.toml").read())
example["component"]["C"]["ECC_arcsec"] = ends
errors = ErrorModel.from_dict(example)
stock = RobotLoadedWorkpiece("grooves").stock
start = time.perf_counter()
try:
    part, report = machinesim.cut(groove_program(), "robonano_a0ib", GROOVE_TOOL, stock,
                                  errors, roi=GROOVE_ROI, start=PARK)
    outcome = f"cut, {report.removed_volume_m3 * 1e18:.6g} um^3 removed"
except machinesim.exceptions.NCProgramError as error:
    outcome = "refused: " + str(error)[:70]
print(f"{time.perf_counter() - start:.3f} {outcome}")
"""


def run(root: Path, case: str, limit: float) -> tuple[float | None, str]:
    env = {**os.environ, "PYTHONPATH": str(root)}
    began = time.perf_counter()
    try:
        done = subprocess.run([sys.executable, "-c", RUNNER, case], cwd=root, env=env,
                              capture_output=True, text=True, timeout=limit, check=True)
    except subprocess.TimeoutExpired:
        return None, f"not done in {limit:g} s"
    wall = time.perf_counter() - began
    inner, _, outcome = done.stdout.strip().partition(" ")
    return float(inner), f"{outcome} (wall {wall:.2f} s)"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--limit", type=float, default=300.0, help="seconds a run may take")
    parser.add_argument("--case", nargs="+", default=["stepped", "closed"])
    parser.add_argument("--root", nargs="+", type=Path, default=[ROOT])
    args = parser.parse_args()
    for case in args.case:
        for root in args.root:
            times, outcomes = [], []
            for _ in range(args.repeat):
                seconds, outcome = run(root, case, args.limit)
                outcomes.append(outcome)
                if seconds is not None:
                    times.append(seconds)
            median = f"{statistics.median(times):.3f} s" if times else "-"
            print(f"{case:8} {str(root):40} median {median:>10}  {outcomes[-1]}", flush=True)


if __name__ == "__main__":
    main()
