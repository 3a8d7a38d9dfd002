"""Poses per second of Machine.tool_pose, and axis values solved per second by
Machine.axis_values, with every error family active.

Run: ``.venv/bin/python benchmarks/kinematics.py`` (prints medians of several runs).
Compares, in the same run, the batched evaluator with a Python loop over Pinocchio's
forwardKinematics on the same error-augmented model; and the inverse kinematics of a
program's poses (each started from its nominal axis values, as model-based compensation
does) solved in one batch against the same poses solved one at a time; and the poses of
paper 002's crown program as `cut_turned` takes them, one `tool_pose` call per feed segment
(before) against `Machine.tool_poses` of each C group's segments (now), alternating, checked
equal bit for bit; and what the singularity check (`inverse._singular_parts`) adds to a
batch whose every orientation is left unmatched (a tilted tool on grooving_4axis, robonano_ui
at B = 0), timed alone beside the whole solve.
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
    inverse(machine, rng)
    singular_check()
    crown_segments()


def inverse(machine, rng, n: int = 5_000, n_loop: int = 300) -> None:
    """Model-based compensation's solve: the nominal poses of ``n`` axis vectors on the
    machine with errors of a well-set machine, each started from its nominal values."""
    errors = random_errors(machine, rng, tool_offset=20e-6, tool_rotation=1e-4,
                           workpiece_delta=5e-6, workpiece_rotation=1e-4)
    q = random_axis_values(machine, rng, 2 * n, fraction=0.5)
    # away from B = 0, where A and C line up and the tool's roll has no unique solution
    q = q[np.abs(q[:, machine.axes.index("B")]) > 0.05][:n]
    target = machine.tool_pose(q)
    batch, loop = [], []
    for _ in range(3):
        start = time.perf_counter()
        machine.axis_values(target, errors, q_start=q, check_limits=False)
        batch.append(time.perf_counter() - start)
        start = time.perf_counter()
        for k in range(n_loop):
            machine.axis_values(target[k], errors, q_start=q[k], check_limits=False)
        loop.append((time.perf_counter() - start) / n_loop * n)
    batched, looped = statistics.median(batch), statistics.median(loop)
    print(f"robonano_ui, {n} poses solved for axis values (errors of a set-up machine)")
    print(f"  one batch:                      {batched * 1e3:8.1f} ms  "
          f"{n / batched / 1e3:6.1f} k poses/s  (median of 3)")
    print(f"  one pose at a time (Pinocchio): {looped * 1e3:8.1f} ms  "
          f"{n / looped / 1e3:6.1f} k poses/s  (median of 3 x {n_loop}, scaled)")
    print(f"  speed-up: {looped / batched:.1f}x")


def singular_check(n: int = 5_000, repeats: int = 5) -> None:
    """`axis_values` of ``n`` poses whose orientation is all left unmatched, and the part
    of it that tells a singularity from the structure (`inverse._singular_parts`)."""
    from machinesim import ErrorModel, inverse

    for name, tilt, b_zero in (("grooving_4axis", [-1700.0, -560.0, 0.0], False),
                               ("robonano_ui", [10.0, 0.0, 0.0], True)):
        machine = load_machine(name)
        errors = ErrorModel.from_dict({"tool": {"rotation_urad": tilt}})
        q = random_axis_values(machine, np.random.default_rng(0), n, fraction=0.5)
        if b_zero:
            q[:, machine.axes.index("B")] = 0.0
        target = machine.tool_pose(q)
        binding = machine.binding(errors)
        whole, check = [], []
        for _ in range(repeats):
            start = time.perf_counter()
            solution = machine.axis_values(target, errors, q_start=q, check_limits=False)
            whole.append(time.perf_counter() - start)
            rres = solution.rotation_residual
            start = time.perf_counter()
            inverse._singular_parts(machine, binding, solution.q, rres,
                                    np.ones(n, dtype=bool), False)
            check.append(time.perf_counter() - start)
        print(f"{name}, {n} poses, every orientation left unmatched "
              f"({'at B = 0' if b_zero else 'a tilted tool'})")
        print(f"  axis_values:                    {statistics.median(whole) * 1e3:8.1f} ms  "
              f"(median of {repeats})")
        print(f"  of it the singularity check:    {statistics.median(check) * 1e3:8.1f} ms")


def crown_segments(repeats: int = 5) -> None:
    """Paper 002's crown after compensation (`make demo`'s default run, seed 0): the poses
    of its feed segments, grouped by C as `machinesim.cutting.cut_turned` groups them."""
    import math

    from _crown import crown_errors

    from machinesim import Lab, motion
    from machinesim.cam.crown import PARK
    from machinesim.procedures.workpiece_setting import RobotLoadedWorkpiece
    from machinesim.realism import Realism

    machine = load_machine("robonano_a0ib")
    errors = crown_errors()
    procedure = RobotLoadedWorkpiece("crown")
    identified = procedure.identify(procedure.measure(Lab(machine, errors, seed=0,
                                                          realism=Realism.lab())))
    program = procedure.compensate(identified)["crown_compensated"]
    tool = procedure.layout(identified.detail.found).tool
    trajectory = motion.plan(program, machine, errors, start=PARK,
                             tool_points=tool.vertices())
    column = machine.axes.index("C")
    groups: dict[int, list] = {}
    for segment in trajectory.segments:
        if segment.kind == "linear":
            key = round(float(segment.q[0, column]) / (math.pi / 4))
            groups.setdefault(key, []).append(segment.q)
    count = sum(len(g) for g in groups.values())
    each, batched = [], []
    for _ in range(repeats):
        start = time.perf_counter()
        one = [machine.tool_pose(q, errors) for g in groups.values() for q in g]
        each.append(time.perf_counter() - start)
        start = time.perf_counter()
        many = [p for g in groups.values() for p in machine.tool_poses(g, errors)]
        batched.append(time.perf_counter() - start)
    same = all(np.array_equal(a, b) for a, b in zip(one, many, strict=True))
    print(f"robonano_a0ib, paper 002's crown after compensation: {count} feed segments in "
          f"{len(groups)} C groups (cut_turned's poses)")
    print(f"  tool_pose per segment:          {statistics.median(each) * 1e3:8.1f} ms  "
          f"(median of {repeats}, alternating)")
    print(f"  tool_poses per C group:         {statistics.median(batched) * 1e3:8.1f} ms  "
          f"bit for bit the same: {same}")


if __name__ == "__main__":
    main()
