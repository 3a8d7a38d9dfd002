"""What following the axes through servo loops costs a cut, ``machinesim.cut`` end to end,
in one process, the variants interleaved:

* ``exact``: no servo loops (the command cut as planned);
* ``per_step``: docs/cli.md's ``[X]`` and ``[C]`` loops, the followed path sampled again
  only where a step breaks the commanded sub-steps' rules (`machinesim.motion.following`);
* ``uniform``: the same loops, every step of a move split as finely as its worst followed
  step needs (the planner's method until 2026-12; kept here, `uniform_follow_plan`, to
  compare).

The case is a V tool (``v:90``) plunged 20 um at X 3 mm on grooving_4axis and led in a
spiral (``G01 C90. X1.``) from the machine's home, as ``machinesim cut`` starts, chords of
1 nm (the tool's path chord): one followed step near the spiral's start needs two pieces,
and splitting the whole move for it doubled the sweeps.

Printed per variant: the median CPU and wall time of ``--repeat`` cuts (CPU counts
manifold3d's threads), the sweeps, the removed volume and each axis' largest lag.

    .venv/bin/python benchmarks/servo_cut.py [--repeat 3] [--variants exact,per_step,uniform]
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

import machinesim
from machinesim.exceptions import NCProgramError
from machinesim.motion import following, planner
from machinesim.servo import servo_from_toml

ROOT = Path(__file__).resolve().parents[1]
SPIRAL = ("%\nO0001\nG21 G90 G17\nG00 X3. Y0. Z1.\nG01 Z-0.02 F100.\nG01 C90. X1. F100.\n"
          "G00 Z1.\nM30\n%\n")
PER_STEP = following.follow_plan


def loops_toml() -> str:
    """docs/cli.md's servo tables, as a user copies them (the ``[X]`` table to the end of
    ``[C]``'s)."""
    lines = (ROOT / "docs" / "cli.md").read_text().splitlines()
    first = lines.index("[X]                          # a linear axis")
    last = next(i for i in range(first, len(lines)) if lines[i] == "```")
    return "\n".join(lines[first:last]) + "\n"


def uniform_follow_plan(servo, sample, steps, kinds, exact_stops, rule, lines, source,
                        block_of):
    """`following.follow_plan` as it was: each round multiplies a move's sub-steps by what
    its worst followed step needs (the settling steps split as now)."""
    steps = np.asarray(steps, dtype=np.int64).copy()
    for _ in range(following.FOLLOW_ROUNDS):
        q, t, offsets = sample(steps)
        commanded = q.copy()
        settled = following.follow_runs(servo, q, t, offsets, kinds, exact_stops)
        move_of = np.repeat(np.arange(len(kinds)), np.diff(offsets))
        inner = np.ones(len(q), dtype=bool)
        inner[offsets[1:] - 1] = False
        inner[settled - 1] = False
        rows = np.flatnonzero(inner)
        need = rule.counts(q[rows], q[rows + 1] - q[rows])
        if np.all(need == 1):
            break
        factor = np.ones(len(kinds), dtype=np.int64)
        np.maximum.at(factor, move_of[rows], np.where(need == 0, following.MAX_SUBSTEPS + 1,
                                                      need))
        steps *= factor
    else:
        raise NCProgramError("uniform refinement did not converge", source=source)
    lag = np.abs(commanded - q)
    peak_lag = lag.max(axis=0)
    q[settled] = commanded[settled]
    last = settled - 1
    need = rule.counts(q[last], q[settled] - q[last])
    if np.any(need > 1):
        q, t, offsets = following._split_steps(q, t, offsets, settled, need, move_of)
    return q, t, offsets, peak_lag


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=3, help="cuts per variant (median)")
    parser.add_argument("--variants", default="exact,per_step,uniform",
                        help="comma-separated: exact, per_step, uniform")
    args = parser.parse_args()
    variants = args.variants.split(",")
    machine = machinesim.load_machine("grooving_4axis")
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "loops.toml"
        path.write_text(loops_toml())
        loops = servo_from_toml(path, machine)
        program = Path(folder) / "spiral.nc"
        program.write_text(SPIRAL)
        runs = {variant: [] for variant in variants}
        for _ in range(args.repeat):
            for variant in variants:
                planner.follow_plan = uniform_follow_plan if variant == "uniform" else PER_STEP
                cpu, wall = time.process_time(), time.perf_counter()
                try:
                    _, report = machinesim.cut(program, machine, tool="v:90",
                                               stock="block:10x10x2", start=machine.home,
                                               servo=None if variant == "exact" else loops)
                finally:
                    planner.follow_plan = PER_STEP
                runs[variant].append((time.process_time() - cpu, time.perf_counter() - wall,
                                      report))
    print(f"median of {args.repeat} cuts per variant, variants interleaved")
    print(f"{'variant':9} {'CPU s':>8} {'wall s':>8} {'sweeps':>7} {'removed m^3':>22}  "
          "largest lag X um, C urad")
    for variant, done in runs.items():
        report = done[0][2]
        lag = report.peak_following_error
        lags = (f"{lag['X'] * 1e6:.4f}, {lag['C'] * 1e6:.4f}" if lag else "-")
        print(f"{variant:9} {statistics.median(r[0] for r in done):8.2f} "
              f"{statistics.median(r[1] for r in done):8.2f} {report.sweeps:7d} "
              f"{report.removed_volume_m3:22.15e}  {lags}", flush=True)


if __name__ == "__main__":
    main()
