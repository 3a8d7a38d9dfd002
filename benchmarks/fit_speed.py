"""Seconds of identification.fit and plan_quality for N readings on robonano_a0ib, by the
batched evaluator and by the two pose-by-pose paths it replaced, in the same run.

The variants: ``all batched`` (the model readings by `Machine.frame_pose` and the error
Jacobian by `Machine.error_jacobian`, each over every pose at once: the code), ``readings
pose by pose`` (the readings one Pinocchio pass a pose, `Machine.pinocchio_pose`: the code
before the readings were batched) and ``pose by pose`` (the Jacobian too, by
`Machine.pinocchio_error_jacobian`: the code before that). Each is set on the machine
instance the fit reads, then removed.

Run: ``.venv/bin/python benchmarks/fit_speed.py`` (prints medians of 3 runs; the
pose-by-pose path at 100,000 readings takes some 40-50 s a fit, the whole run 4-5 min), or
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
from functools import partial

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
    return q, u, observations(q, directions=u, values=np.einsum("ni,ni->n", u, moved),
                              sigma=SIGMA_M)


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
        rows = []
        for label, patches in variants(machine):
            vars(machine).update(patches)  # the instance's, read by the fit's model
            try:
                t_fit, estimate = timed(args.repeat, fit, machine, obs, PARAMETERS)
                t_plan, _ = timed(args.repeat, partial(plan_quality, directions=u,
                                                       sigma=SIGMA_M), machine, q, PARAMETERS)
            finally:
                for name in patches:
                    vars(machine).pop(name)
            rows.append((label, t_fit, t_plan, estimate))
        new = rows[-1]
        print(f"  N = {n:,} ({new[3].iterations} steps, rank {new[3].rank}):")
        for label, t_fit, t_plan, estimate in rows:
            print(f"    {label:<24} fit {t_fit:8.3f} s ({t_fit / new[1]:4.1f}x), plan_quality "
                  f"{t_plan:8.3f} s ({t_plan / new[2]:4.1f}x); values apart from all batched "
                  f"by {np.max(np.abs(estimate.values - new[3].values)):.1e} (m, rad)")


def variants(machine) -> tuple[tuple[str, dict], ...]:
    """(label, instance attributes to set) of each variant, the code last."""
    def pose_by_pose(frame, q, errors=None):
        return machine.pinocchio_pose(q, errors, frame)

    return (("pose by pose", {"frame_pose": pose_by_pose,
                              "error_jacobian": machine.pinocchio_error_jacobian}),
            ("readings pose by pose", {"frame_pose": pose_by_pose}),
            ("all batched", {}))

if __name__ == "__main__":
    main()
