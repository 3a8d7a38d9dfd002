"""NC reading and motion planning speed on 10^6-line straight-move programs (issue 12, item 4).

Two programs are written to a temporary file and read with `machinesim.nc.read_program`, then
planned with `machinesim.motion.plan` (nominal machine, default 1 nm chord tolerance):

* **STS**: a slow-tool-servo point list on ``sts_lathe``, one ``X.. Z.. C..`` point a line
  (modal G01): a spiral from X 10 mm to the centre, 1000 points a turn (0.36 deg), Z waving
  +-10 um three times a turn. C counts on (0 .. 360,000 deg) instead of wrapping at 360:
  the planner has no rotary roll-over, so a wrap would be a real 359.64-deg turn back.
  Every move turns C, so every move is split to the chord tolerance (1 to 8 sub-steps,
  by the radius).
* **XYZ**: a raster of ``X.. Y.. Z..`` points on ``grooving_4axis`` (no rotary move).

Reading is timed on the vectorised fast path and, on the STS program, on the word-by-word
path too (``--slow-repeats`` runs, 0 to skip; ~10 us a line), for the speed-up.

Goals: reading >= 1,000,000 lines/s, planning >= 1,000,000 moves/s, memory < 1 GB.

Also timed: `plan` of the 2000-groove program of ``benchmarks/cutting.py`` (case e, 8000
moves) with and without the V tool's points, i.e. the planner's share of ``cut``; and the
line-by-line planner of before (kept in ``tests/motion_reference.py``) on the first moves of
each program, in the same run, for the speed-up.

Times are medians of ``--repeats`` runs; peak memory is the traced peak (tracemalloc:
Python and numpy allocations) of one read and of one plan, and the resident peak of a fresh
process that only reads the program and plans it (what a user's run costs).

    .venv/bin/python benchmarks/nc.py                      # 1,000,000 lines each
    .venv/bin/python benchmarks/nc.py --lines 100000 --repeats 3
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

import numpy as np

from machinesim import load_machine
from machinesim.motion import chords, plan
from machinesim.nc import ProgramBuilder, read_program

TESTS = Path(__file__).resolve().parent.parent / "tests"


def write_sts(path: Path, n: int) -> int:
    """The STS point list (see the module docstring); returns its number of lines."""
    with open(path, "w") as file:
        file.write(f"%\nO0001 (STS POINT LIST, {n} POINTS)\nG90 G21 G94 G54\n"
                   "G00 X10. Z1. C0.\nG01 Z0. F20.\n")
        for first in range(0, n, 100_000):
            k = np.arange(first, min(n, first + 100_000))
            x = 10.0 * (1.0 - k / n)
            c = k * 0.36
            z = 0.01 * np.sin(np.radians(c) * 3.0)
            file.write("".join(f"X{a:.6f} Z{b:.6f} C{d:.5f}\n"
                               for a, b, d in zip(x, z, c, strict=True)))
        file.write("M30\n%\n")
    return n + 7


def write_xyz(path: Path, n: int) -> int:
    """A raster of X Y Z points, 1000 a row, 10 um between rows; returns its lines."""
    with open(path, "w") as file:
        file.write(f"%\nO0002 (XYZ RASTER, {n} POINTS)\nG90 G21 G94 G54\n"
                   "G00 X0. Y0. Z1.\nG01 Z0. F500.\n")
        for first in range(0, n, 100_000):
            k = np.arange(first, min(n, first + 100_000))
            x = (k % 1000) * 0.01
            y = (k // 1000) * 0.01
            z = 0.005 * np.sin(x) * np.cos(y)
            file.write("".join(f"X{a:.4f} Y{b:.4f} Z{c:.6f}\n"
                               for a, b, c in zip(x, y, z, strict=True)))
        file.write("M30\n%\n")
    return n + 7


def groove_program(count: int = 2000, pitch: float = 20e-6, depth: float = 10e-6):
    """benchmarks/cutting.py case e: grooves along X across a 10 mm block, rapids beside."""
    builder = ProgramBuilder(1, source="benchmark case e")
    for i in range(count):
        builder.rapid(X=-0.5e-3, Y=pitch / 2 + pitch * i, Z=0.1e-3).rapid(Z=-depth)
        builder.linear(X=10.5e-3, feed_mm_per_min=500.0).rapid(Z=0.1e-3)
    return builder.build()


def median_time(call, repeats: int) -> tuple[float, object]:
    times, result = [], None
    for _ in range(repeats):
        result = None
        start = time.perf_counter()
        result = call()
        times.append(time.perf_counter() - start)
    return statistics.median(times), result


def traced_peak(call) -> int:
    tracemalloc.start()
    result = call()
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    del result
    return peak


def reference_rate(program, machine, moves: int) -> float | None:
    """Moves/s of the line-by-line planner of before on the first ``moves`` moves."""
    if moves <= 0:
        return None
    sys.path.insert(0, str(TESTS))
    try:
        import motion_reference
    except ImportError:
        return None
    finally:
        sys.path.pop(0)
    from machinesim.nc import Program

    head = Program.from_arrays(program.targets[:moves], program.kinds[:moves],
                               program.feeds[:moves], program.dwells[:moves],
                               program.lines[:moves])
    start = time.perf_counter()
    motion_reference.plan(head, machine)
    return len(head) / (time.perf_counter() - start)


def resident_peak(path: Path, machine_name: str) -> float:
    """Peak resident size (MiB) of a fresh process that reads ``path`` and plans it."""
    out = subprocess.run([sys.executable, __file__, "--child", str(path), machine_name],
                         check=True, capture_output=True, text=True).stdout
    return float(out.split()[-1])


def child(path: str, machine_name: str) -> None:
    trajectory = plan(read_program(path), load_machine(machine_name))
    assert len(trajectory) > 0
    # VmHWM belongs to this program's memory; ru_maxrss would carry the parent's peak over
    # fork and exec on Linux
    status = Path("/proc/self/status")
    if status.exists():
        for line in status.read_text().splitlines():
            if line.startswith("VmHWM:"):
                print(float(line.split()[1]) / 1024)
                return
    print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)


def main() -> None:
    if len(sys.argv) == 4 and sys.argv[1] == "--child":
        child(sys.argv[2], sys.argv[3])
        return
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--lines", type=int, default=1_000_000)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--slow-repeats", type=int, default=1,
                        help="runs of the word-by-word reader on the STS program (0: skip)")
    parser.add_argument("--reference-moves", type=int, default=5000,
                        help="moves planned by the line-by-line planner for the speed-up")
    args = parser.parse_args()
    print(f"{os.cpu_count()} cores, planner threads {chords.WORKERS}, load average "
          f"{' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    cases = (("STS  (sts_lathe, X Z C)", write_sts, "sts_lathe"),
             ("XYZ  (grooving_4axis)", write_xyz, "grooving_4axis"))
    with tempfile.TemporaryDirectory() as folder:
        for name, write, machine_name in cases:
            path = Path(folder) / "program.nc"
            lines = write(path, args.lines)
            machine = load_machine(machine_name)
            print(f"\n{name}: {lines:,} lines, {path.stat().st_size / 1e6:.1f} MB")
            read_s, program = median_time(lambda p=path: read_program(p), args.repeats)
            read_peak = traced_peak(lambda p=path: read_program(p))
            print(f"  reading : {lines / read_s:12,.0f} lines/s (median of {args.repeats}: "
                  f"{read_s:.3f} s, {len(program):,} moves), peak traced "
                  f"{read_peak / 2**20:,.0f} MiB")
            if write is write_sts and args.slow_repeats > 0:
                slow_s, _ = median_time(lambda p=path: read_program(p, fast=False),
                                        args.slow_repeats)
                print(f"  reading word by word: {lines / slow_s:12,.0f} lines/s (median of "
                      f"{args.slow_repeats}: {slow_s:.3f} s; fast path x{slow_s / read_s:.1f})")
            plan_s, trajectory = median_time(lambda p=program, m=machine: plan(p, m),
                                             args.repeats)
            del trajectory
            trajectory = plan(program, machine)
            plan_peak = traced_peak(lambda p=program, m=machine: plan(p, m))
            print(f"  planning: {len(program) / plan_s:12,.0f} moves/s (median of "
                  f"{args.repeats}: {plan_s:.3f} s; {trajectory.substeps:,} sub-steps, "
                  f"{len(trajectory.t):,} samples), peak traced {plan_peak / 2**20:,.0f} MiB")
            print(f"  read and plan in a fresh process: peak resident "
                  f"{resident_peak(path, machine_name):,.0f} MiB")
            rate = reference_rate(program, machine, args.reference_moves)
            if rate is not None:
                print(f"  line-by-line planner of before, first {args.reference_moves:,} "
                      f"moves: {rate:,.0f} moves/s (x{len(program) / plan_s / rate:,.0f})")
            del program, trajectory
    machine = load_machine("grooving_4axis")
    program = groove_program()
    from machinesim.tools import VTool

    points = VTool(np.pi / 2).vertices()
    print(f"\n2000 grooves (benchmarks/cutting.py case e): {len(program):,} moves")
    for label, kwargs in (("edge only", {}), ("V tool points", {"tool_points": points})):
        seconds, _ = median_time(lambda k=kwargs: plan(program, machine, **k), 21)
        print(f"  plan, {label:13s}: {seconds * 1e3:7.2f} ms a call (median of 21), "
              f"{len(program) / seconds:12,.0f} moves/s")
    print(f"\nload average now {' '.join(f'{x:.2f}' for x in os.getloadavg())}")


if __name__ == "__main__":
    main()
