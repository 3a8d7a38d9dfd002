"""The rapid check (`machinesim.cutting.rapids`), ``machinesim cut`` end to end, by size: the
whole run and the time in `rapids_that_cut`, with the box grid (`cutting.boxgrid`, the
default) and with every earlier box compared for each rapid (``every``: the old scan, which
grew as the square of the rapids), or with the earlier sweeps a rapid meets united before
they are taken away from what it met (``union``: as before `_Earlier.subtract` took them
away one at a time), in the same run; the lines listed must be the same.

Three programs on grooving_4axis, a ``block:10x10x2``:

- ``slot``: a flat:0.5 end mill cuts a slot 0.1 mm deep along X, then N rapids hop to random
  X along it 0.05 mm deep (each reaches the stock, none cuts: the check is most of the run);
- ``grid``: N/3 short cuts 10 um deep with a ball:0.05 over the block, each joined by rapids
  over, down to 50 um above the top, and back up out of the cut (N rapids, N/3 reach);
- ``plunge``: a field of plunges 0.1 mm apart with a flat:0.2, 10 um deep, then a second
  field between them, each begun by a rapid down into the first's cut to 2 um above its
  floor, 20 um deep (N moves, four a plunge: each rapid of the second field meets some 100
  earlier sweeps; those past the first field's edge cut).

Each variant runs in its own process (``--repeat`` times, median quoted).

    .venv/bin/python benchmarks/rapids.py [--repeat 3] [--case slot grid] [--rapids 2000 8000]
        [--variants grid every union]
"""

from __future__ import annotations

import argparse
import json
import random
import statistics
import tempfile
from pathlib import Path

from _timed_cut import timed_cut

RUNNER = """
import sys, time
import numpy as np
import machinesim.cutting.program as program
import machinesim.cutting.rapids as rapids
from machinesim.cli import main
if sys.argv[1] == "every":  # every earlier box read for each rapid
    from machinesim.cutting.boxgrid import BoxGrid
    BoxGrid.candidates = lambda self, low, high, k: np.arange(min(k, self.n))
    BoxGrid.at = lambda self, point, k: (np.arange(min(k, self.n)), self.wide[:0])
if sys.argv[1] == "union":  # the sweeps a rapid meets united, then taken away at once
    rapids._Earlier.subtract = lambda self, hit, sweeps: hit - self.union(sweeps)
spent = []
def timed(*args):
    start = time.perf_counter()
    lines = rapids.rapids_that_cut(*args)
    spent.append(time.perf_counter() - start)
    return lines
program.rapids_that_cut = timed
status = main(sys.argv[2:])
print(sum(spent), file=sys.stderr)
sys.exit(status)
"""

TOOLS = {"slot": "flat:0.5", "grid": "ball:0.05", "plunge": "flat:0.2"}


def slot(rapids: int) -> str:
    rng = random.Random(0)
    lines = ["%", f"O1 (a slot, then {rapids} rapids along it)", "G90 G21 G17 G94",
             "G00 X-1. Y5. Z1.", "G01 Z-0.1 F500.", "X11.", "G00 Z-0.05"]
    lines += [f"G00 X{rng.uniform(0.5, 9.5):.4f}" for _ in range(rapids)]
    return "\n".join(lines + ["G00 Z1.", "M30", "%"]) + "\n"


def grid(rapids: int) -> str:
    cuts = max(1, rapids // 3)
    side = int(cuts ** 0.5) + 1
    pitch = 9.0 / side
    lines = ["%", f"O2 ({cuts} short cuts joined by rapids)", "G90 G21 G17 G94", "G00 Z1."]
    for k in range(cuts):
        x, y = 0.5 + (k // side) * pitch, 0.5 + (k % side) * pitch
        lines += [f"G00 X{x:.4f} Y{y:.4f}", "G00 Z0.05", "G01 Z-0.01 F500.",
                  f"X{x + 0.5 * pitch:.4f}", "G00 Z0.05"]
    return "\n".join(lines + ["G00 Z1.", "M30", "%"]) + "\n"


def plunge(moves: int) -> str:
    holes = max(1, moves // 8)
    side, pitch = int(holes ** 0.5) + 1, 0.1
    lines = ["%", f"O3 (two fields of {holes} plunges)", "G90 G21 G17 G94", "G00 Z0.005"]
    for shift, top, floor in [(0.0, 0.005, -0.01), (0.5, -0.008, -0.02)]:
        for k in range(holes):
            x, y = 0.5 + (k // side + shift) * pitch, 0.5 + (k % side + shift) * pitch
            lines += [f"G00 X{x:.4f} Y{y:.4f}", f"G00 Z{top}", f"G01 Z{floor} F500.",
                      "G00 Z0.005"]
    return "\n".join(lines + ["G00 Z1.", "M30", "%"]) + "\n"


PROGRAMS = {"slot": slot, "grid": grid, "plunge": plunge}


def cut(folder: Path, case: str, rapids: int, variant: str) -> dict:
    program = folder / f"{case}{rapids}.nc"
    program.write_text(PROGRAMS[case](rapids))
    out, report = folder / f"{case}{rapids}.ply", folder / f"{case}{rapids}_{variant}.json"
    seconds, summary, stderr = timed_cut(
        RUNNER, variant, [str(program), "--machine", "grooving_4axis", "--tool", TOOLS[case],
                          "--stock", "block:10x10x2", "--out", str(out), "--report",
                          str(report), "--quiet"], report, f"{case} {rapids}")
    return {"seconds": seconds, "check": float(stderr.split()[-1]),
            "lines": json.dumps(summary["rapids_that_cut_lines"])}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--case", nargs="+", choices=sorted(TOOLS), default=["slot", "grid"])
    parser.add_argument("--rapids", type=int, nargs="+", default=[2000, 8000])
    parser.add_argument("--variants", nargs="+", choices=["grid", "every", "union"],
                        default=["grid", "every"])
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        for case in args.case:
            for rapids in args.rapids:
                runs = {v: [cut(Path(folder), case, rapids, v) for _ in range(args.repeat)]
                        for v in args.variants}
                cells = [f"{v}: {statistics.median(r['seconds'] for r in rs):.2f} s, check "
                         f"{statistics.median(r['check'] for r in rs):.2f} s"
                         for v, rs in runs.items()]
                same = len({r["lines"] for rs in runs.values() for r in rs}) == 1
                print(f"{case}, {rapids} rapids, median of {args.repeat}: " + "; ".join(cells)
                      + f"; lines listed {'the same' if same else 'DIFFER'}")


if __name__ == "__main__":
    main()
