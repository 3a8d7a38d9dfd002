"""Poses per second of Machine.tool_pose, with every error family active.

Run: ``.venv/bin/python benchmarks/kinematics.py`` (prints medians of several runs).
Compares, in the same run, the batched evaluator with a Python loop over Pinocchio's
forwardKinematics on the same error-augmented model.
"""

from __future__ import annotations

import statistics
import time

import numpy as np

from machinesim import load_machine
from machinesim.sampling import random_axis_values, random_errors

N = 100_000
REPEATS = 5


def main() -> None:
    machine = load_machine("robonano_ui")
    rng = np.random.default_rng(0)
    errors = random_errors(machine, rng)
    q = random_axis_values(machine, rng, N)
    machine.tool_pose(q[:10], errors)  # build the plan once, as any later call reuses it
    times = []
    for _ in range(REPEATS):
        start = time.perf_counter()
        machine.tool_pose(q, errors)
        times.append(time.perf_counter() - start)
    batched = statistics.median(times)
    n_loop = 5_000
    loop_times = []
    for _ in range(3):
        start = time.perf_counter()
        for qn in q[:n_loop]:
            machine.pinocchio_pose(qn, errors)
        loop_times.append(time.perf_counter() - start)
    loop = statistics.median(loop_times) / n_loop * N
    print(f"robonano_ui, {N} configurations, every error family active "
          f"({len(errors.parameters())} parameters, {machine.model.njoints - 1} joints)")
    print(f"  batched tool_pose:              {batched * 1e3:8.1f} ms  "
          f"{N / batched / 1e6:6.2f} M poses/s  (median of {REPEATS})")
    print(f"  loop over Pinocchio FK:         {loop * 1e3:8.1f} ms  "
          f"{N / loop / 1e6:6.2f} M poses/s  (median of 3 x {n_loop}, scaled)")
    print(f"  speed-up: {loop / batched:.1f}x")


if __name__ == "__main__":
    main()
