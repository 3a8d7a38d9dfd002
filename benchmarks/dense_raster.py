"""A dense raster, ``machinesim cut`` end to end: the height-field engine's groove envelopes
split between passes and merged (`machinesim.cutting.profiles.MOST_PAIRS`, the default)
against one table of every pair of profile segments over each interval, in the same run.

A finishing raster steps a ball end mill across a block by a few micrometres, so each point
across the passes lies under hundreds of them (a 1 mm ball at 4 um: 250). The envelope of
their profiles compared every pair of segments over each interval at once: memory grew with
the passes times the overlap squared, and 10,000 passes ran out of the machine's 24 GB.

The program: ``ball:0.5`` 10 um deep along X across ``block:10x10x2``, N passes stepped over
10 mm in Y (zigzag, step-overs outside the block), on grooving_4axis. Each variant runs in
its own process (``--repeat`` times, median quoted); peak memory is the process's maximum
resident set. The parts are compared by removed volume and vertex by vertex.

    .venv/bin/python benchmarks/dense_raster.py [--repeat 3] [--passes 1000 2500 10000]
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
from pathlib import Path

from _timed_cut import timed_cut

RUNNER = """
import resource
import sys
import machinesim.cutting.profiles as profiles
from machinesim.cli import main
if sys.argv[1] == "one":  # one table of every pair, whatever its size
    profiles.MOST_PAIRS = 2**62
status = main(sys.argv[2:])
print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss, file=sys.stderr)
sys.exit(status)
"""

#: The one table past this many passes needs more than 5 GB (5000: 5.8 GB, 37.6 s).
ONE_TABLE_MOST_PASSES = 2500


def raster(passes: int) -> str:
    lines = ["%", f"O1 (raster of {passes} passes)", "G90 G21 G17 G94", "G00 X-2. Y0. Z1.",
             "G01 Z-0.01 F1000."]
    step = 10.0 / passes
    for k in range(passes):
        lines.append(f"X{12.0 if k % 2 == 0 else -2.0:.4f}")
        if k + 1 < passes:
            lines.append(f"Y{(k + 1) * step:.6f}")
    lines += ["G00 Z1.", "M30", "%"]
    return "\n".join(lines) + "\n"


def cut(folder: Path, passes: int, variant: str) -> dict:
    program = folder / f"raster{passes}.nc"
    program.write_text(raster(passes))
    out, report = folder / f"raster{passes}_{variant}.ply", folder / f"r{passes}_{variant}.json"
    seconds, summary, stderr = timed_cut(
        RUNNER, variant, [str(program), "--machine", "grooving_4axis", "--tool", "ball:0.5",
                          "--stock", "block:10x10x2", "--out", str(out), "--report",
                          str(report), "--quiet"], report, f"{passes} passes")
    return {"seconds": seconds, "peak_mb": int(stderr.split()[-1]) / 1024,
            "removed_mm3": summary["removed_volume_mm3"], "engine": summary["engine"],
            "part": out}


def vertices_apart(a: Path, b: Path) -> float:
    """Largest difference between the two parts' sorted vertices, m (NaN: other counts)."""
    import numpy as np
    import trimesh

    p, q = (trimesh.load(path, process=False).vertices for path in (a, b))
    if p.shape != q.shape:
        return float("nan")
    return float(np.abs(np.sort(p, axis=0) - np.sort(q, axis=0)).max())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--passes", type=int, nargs="+", default=[1000, 2500, 10000])
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        for passes in args.passes:
            variants = ("split", "one") if passes <= ONE_TABLE_MOST_PASSES else ("split",)
            runs = {v: [cut(folder, passes, v) for _ in range(args.repeat)] for v in variants}
            cells = []
            for v, rs in runs.items():
                times = [r["seconds"] for r in rs]
                cells.append(f"{v} {statistics.median(times):.2f} s (runs "
                             f"{', '.join(f'{t:.2f}' for t in times)}), peak "
                             f"{max(r['peak_mb'] for r in rs):.0f} MB")
            last = {v: rs[-1] for v, rs in runs.items()}
            print(f"{passes} passes ({last['split']['engine']}), end to end, median of "
                  f"{args.repeat}: " + "; ".join(cells))
            line = f"  removed {last['split']['removed_mm3']:.12g} mm^3"
            if "one" in last:
                line += (f" against {last['one']['removed_mm3']:.12g}; vertices apart by "
                         f"{vertices_apart(last['split']['part'], last['one']['part']):.3g} m")
            else:
                line += (f" (the one table is not run past {ONE_TABLE_MOST_PASSES} passes: "
                         "5000 took 5.8 GB, 10,000 ran out of 24 GB)")
            print(line)


if __name__ == "__main__":
    main()
