"""NC reading speed and memory on a slow-tool-servo point list (issue 12, item 4).

Writes a program of ``--lines`` straight moves (``X.. Z.. C..`` per line, modal G01, as a
slow-tool-servo post writes them) to a temporary file and reads it with `read_program`, the
vectorised fast path against the word-by-word path in the same run. Prints lines/s (median
of ``--repeats`` runs) and the peak memory of one read (tracemalloc: Python and numpy
allocations; and the peak resident size of a fresh process that reads once).

    .venv/bin/python benchmarks/nc_read.py                 # 1,000,000 lines
    .venv/bin/python benchmarks/nc_read.py --lines 100000 --slow-repeats 1
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

import numpy as np

from machinesim.nc import read_program


def write_point_list(path: Path, n: int, seed: int = 0) -> int:
    """Write an STS program: a spiral in X and C with a wavy Z, 6 decimals in mm, 5 in deg.

    Written 100,000 points at a time, so that the benchmark's own memory stays small next
    to the reader's. Returns the number of lines.
    """
    rng = np.random.default_rng(seed)
    with open(path, "w") as file:
        file.write(f"%\nO0001 (STS POINT LIST, {n} POINTS)\nG90 G21 G94 G54\n"
                   "G00 X10. Z1. C0.\nG01 Z0. F20.\n")
        for first in range(0, n, 100_000):
            k = np.arange(first, min(n, first + 100_000))
            x = 10.0 * (1.0 - k / n)
            c = (k * 0.36) % 360.0
            z = 0.01 * np.sin(np.radians(c) * 3.0) + rng.uniform(-1e-4, 1e-4, k.size)
            file.write("".join(f"X{a:.6f} Z{b:.6f} C{d:.5f}\n"
                               for a, b, d in zip(x, z, c, strict=True)))
        file.write("M30\n%\n")
    return n + 7


def timed(path: Path, fast: bool, repeats: int) -> tuple[float, int]:
    times = []
    count = 0
    for _ in range(repeats):
        start = time.perf_counter()
        program = read_program(path, fast=fast)
        times.append(time.perf_counter() - start)
        count = len(program)
        del program
    return statistics.median(times), count


def peak_memory(path: Path, fast: bool) -> int:
    tracemalloc.start()
    program = read_program(path, fast=fast)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    del program
    return peak


def resident_peak(path: Path, fast: bool) -> float:
    """Peak resident size (MiB) of a fresh process that imports machinesim.nc and reads once."""
    # VmHWM of the child's own address space: getrusage's ru_maxrss would include this
    # parent's size at the fork
    code = ("import sys; from machinesim.nc import read_program; "
            f"read_program(sys.argv[1], fast={fast}); "
            "print(next(int(line.split()[1]) for line in open('/proc/self/status') "
            "if line.startswith('VmHWM')) / 1024)")
    out = subprocess.run([sys.executable, "-c", code, str(path)], capture_output=True,
                         text=True, check=True)
    return float(out.stdout)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--lines", type=int, default=1_000_000)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--slow-repeats", type=int, default=5,
                        help="runs of the word-by-word path (slow: ~10 us a line)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "sts.nc"
        lines = write_point_list(path, args.lines)
        print(f"program: {lines} lines, {path.stat().st_size / 1e6:.1f} MB, "
              f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f}")
        results = {}
        for name, fast, repeats in (("fast path", True, args.repeats),
                                    ("word by word", False, args.slow_repeats)):
            if repeats < 1:
                continue
            seconds, moves = timed(path, fast, repeats)
            peak = peak_memory(path, fast)
            rss = resident_peak(path, fast)
            results[name] = seconds
            print(f"{name:13s}: {lines / seconds:12,.0f} lines/s (median of {repeats}: "
                  f"{seconds:.3f} s, {moves} moves), peak traced memory {peak / 2**20:,.0f} "
                  f"MiB, peak resident size of one read in a fresh process {rss:,.0f} MiB")
        if len(results) == 2:
            print(f"speed-up: {results['word by word'] / results['fast path']:.1f}x")
        print(f"load average at the end: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
