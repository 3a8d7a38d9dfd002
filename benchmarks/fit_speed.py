"""Seconds of identification.fit and plan_quality for N readings on robonano_a0ib, with the
error Jacobian batched (`Machine.error_jacobian`) and built pose by pose by Pinocchio
(`Machine.pinocchio_error_jacobian`, the path before), in the same run.

Run: ``.venv/bin/python benchmarks/fit_speed.py`` (prints medians of 3 runs; the
pose-by-pose path at 100,000 readings takes some 30 s a fit, the whole run some 3 min), or
for other sizes ``.venv/bin/python benchmarks/fit_speed.py --readings 1000 10000 --repeat 5``.
Each reading is taken at its own pose (random axis values, a random sensing
direction of the tool edge), so that every reading costs one pose; the readings are those
of workpiece.x, workpiece.y, location.C.EX0C and location.C.EA0C set to a few um and urad,
all four seen by the readings (rank 4), and the fit starts from no error (three Gauss-Newton
steps).
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from machinesim import load_machine
from machinesim.errors import ErrorModel
from machinesim.identification import fit, observations, plan_quality
from machinesim.sampling import random_axis_values

MACHINE = "robonano_a0ib"
PARAMETERS = ("workpiece.x", "workpiece.y", "location.C.EX0C", "location.C.EA0C")
TRUTH = (3e-6, -2e-6, 5e-6, 20e-6)
SIGMA_M = 10e-9


def readings(machine, n: int, rng):
    """N readings of the tool edge along random directions at random poses."""
    q = random_axis_values(machine, rng, n)
    u = rng.normal(size=(n, 3))
    truth = ErrorModel().with_parameters(dict(zip(PARAMETERS, TRUTH, strict=True)))
    moved = machine.tool_pose(q, truth)[:, :3, 3] - machine.tool_pose(q)[:, :3, 3]
    u /= np.linalg.norm(u, axis=1)[:, None]
    return q, u, observations(q, u, np.einsum("ni,ni->n", u, moved), SIGMA_M)


def timed(repeat: int, function, *args) -> tuple[float, object]:
    """Median seconds of ``function(*args)`` over ``repeat`` runs, and its last result."""
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        out = function(*args)
        times.append(time.perf_counter() - start)
    return statistics.median(times), out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--readings", type=int, nargs="+", default=[1000, 10_000, 100_000],
                        help="numbers of readings (default 1000 10000 100000)")
    parser.add_argument("--repeat", type=int, default=3, help="runs per median (default 3)")
    args = parser.parse_args()
    machine = load_machine(MACHINE)
    rng = np.random.default_rng(0)
    print(f"{MACHINE}, fit of {len(PARAMETERS)} parameters ({', '.join(PARAMETERS)}), one "
          f"reading per pose; medians of {args.repeat}")
    for n in args.readings:
        q, u, obs = readings(machine, n, rng)
        row = {}
        for label, jacobian in (("batched", None),
                                ("pose by pose", machine.pinocchio_error_jacobian)):
            if jacobian is not None:
                machine.error_jacobian = jacobian  # the instance's, read by the fit's model
            try:
                t_fit, estimate = timed(args.repeat, fit, machine, obs, PARAMETERS)
                t_plan, _ = timed(args.repeat, plan_quality, machine, q, "tool_tip", u,
                                  PARAMETERS, SIGMA_M)
            finally:
                vars(machine).pop("error_jacobian", None)
            row[label] = (t_fit, t_plan, estimate)
        (f_new, p_new, e_new), (f_old, p_old, e_old) = row["batched"], row["pose by pose"]
        print(f"  N = {n:>7,}: fit {f_old:8.3f} s pose by pose, {f_new:8.3f} s batched "
              f"({f_old / f_new:4.1f}x; {e_new.iterations} steps, rank {e_new.rank}); "
              f"plan_quality "
              f"{p_old:8.3f} s, {p_new:8.3f} s ({p_old / p_new:4.1f}x); values apart by "
              f"{np.max(np.abs(e_new.values - e_old.values)):.1e} (m, rad)")


if __name__ == "__main__":
    main()
