"""A ball end mill's many short sweeps, ``machinesim cut`` end to end: each sweep's solid
made again when a tile reads it and let go after (`machinesim.cutting.sweeps.RebuiltSolid`,
the default) against every sweep's solid built before the first tile and held to the end
(`machinesim.cutting.sweepset.REBUILD_BALL_SWEEPS` False, as before), in the same run.

The program is a spiral groove of short G01 moves, as a CAM post writes a point list:
``ball:0.5`` 0.05 mm deep, 3 turns from a radius of 3.5 mm to 1.5 mm about the middle of a
10 x 10 x 2 mm block on grooving_4axis, in ``--moves`` moves (default 2,000 and 8,000).
Each variant runs in its own process (``--repeat`` times, median quoted; peak memory is
the process's maximum resident set, its largest over the runs), and the parts are
compared: removed volumes and the PLYs byte for byte.

    .venv/bin/python benchmarks/ball_sweeps.py [--repeat 3] [--moves 2000 --moves 8000]
"""

from __future__ import annotations

import argparse
import math
import statistics
import tempfile
from pathlib import Path

from _timed_cut import timed_cut

RUNNER = """
import resource
import sys
from machinesim.cli import main
if sys.argv[1] == "held":  # every ball sweep's solid built first and held, as before
    import machinesim.cutting.sweepset as sweepset
    sweepset.REBUILD_BALL_SWEEPS = False
status = main(sys.argv[2:])
print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss, file=sys.stderr)
sys.exit(status)
"""


def spiral_program(moves: int) -> str:
    """A spiral of ``moves`` G01 moves, 3 turns in from 3.5 mm to 1.5 mm about (5, 5) mm."""
    lines = ["%", "O5000 (a ball end mill's spiral)", "G90 G21 G94 G17", "G00 X8.5 Y5. Z1.",
             "G01 Z-0.05 F500."]
    for step in range(1, moves + 1):
        t = step / moves
        radius, angle = 3.5 - 2.0 * t, 3 * 2 * math.pi * t
        lines.append(f"X{5.0 + radius * math.cos(angle):.4f} "
                     f"Y{5.0 + radius * math.sin(angle):.4f}")
    lines += ["G00 Z1.", "M30", "%"]
    return "\n".join(lines) + "\n"


def cut(folder: Path, moves: int, variant: str) -> dict:
    program = folder / f"spiral{moves}.nc"
    program.write_text(spiral_program(moves))
    out, report = folder / f"spiral{moves}_{variant}.ply", folder / f"spiral{moves}_{variant}.json"
    arguments = [str(program), "--machine", "grooving_4axis", "--tool", "ball:0.5", "--stock",
                 "block:10x10x2", "--out", str(out), "--report", str(report), "--quiet"]
    seconds, summary, stderr = timed_cut(RUNNER, variant, arguments, report,
                                         f"spiral of {moves} moves")
    return {"seconds": seconds, "peak_mb": int(stderr.split()[-1]) / 1024,
            "removed_mm3": summary["removed_volume_mm3"], "sweeps": summary["sweeps_count"],
            "part": out.read_bytes()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--moves", type=int, action="append",
                        help="moves in the spiral (repeatable; default 2000 and 8000)")
    args = parser.parse_args()
    variants = ("rebuilt", "held")
    with tempfile.TemporaryDirectory() as folder:
        for moves in args.moves or (2000, 8000):
            runs = {v: [cut(Path(folder), moves, v) for _ in range(args.repeat)]
                    for v in variants}
            times = {v: [r["seconds"] for r in rs] for v, rs in runs.items()}
            last = {v: rs[-1] for v, rs in runs.items()}
            print(f"spiral of {moves} moves: {last['rebuilt']['sweeps']} sweeps; end to end, "
                  f"median of {args.repeat}: "
                  + ", ".join(f"{v} {statistics.median(times[v]):.1f} s (runs "
                              f"{', '.join(f'{t:.1f}' for t in times[v])}; peak "
                              f"{max(r['peak_mb'] for r in runs[v]):.0f} MB)"
                              for v in variants))
            print(f"  removed {last['rebuilt']['removed_mm3']:.12g} against "
                  f"{last['held']['removed_mm3']:.12g} mm^3; parts byte-identical: "
                  f"{last['rebuilt']['part'] == last['held']['part']}")


if __name__ == "__main__":
    main()
