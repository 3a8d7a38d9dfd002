"""A ball end mill's spiral of many short moves, ``machinesim cut`` end to end, tiled by the
grid rule of `machinesim.cutting.tiling.grid_tiles` ("fullest": the grid doubles while a
doubling leaves at most SPLIT_GAIN of the fullest tile's sweeps, 2 x 2 tiles on this spiral)
against a rule written out in the runner ("cost:L": once the fullest tile fails, doublings go
on along the axis that lowers the tiles' modelled cost, the sum of n^2 + L n, while it falls),
in the same run: whether finer tiles of a ring-shaped path pay for the sweeps they repeat
at their walls.

The program is benchmarks/ball_sweeps.py's spiral (``ball:0.5`` 0.05 mm deep, 3 turns from
a radius of 3.5 mm to 1.5 mm about the middle of a 10 x 10 x 2 mm block), in ``--moves``
moves (default 3,000 and 10,000). Each cut runs in its own process, capped at ``--timeout``
seconds (a capped run is quoted as "> cap"), ``--repeat`` times; medians of wall and CPU
seconds (the process's children, manifold3d's threads counted), the tiles, and the removed
volumes.

    .venv/bin/python benchmarks/ball_tiling.py [--repeat 3] [--timeout 1500] [--moves 10000]
        [--rule fullest --rule cost:3000]

Measured (one cut at a time, 2 cores shared; CPU is the figure to compare, the load moved):
3,000 moves, 1 run each at load ~11: fullest 4 tiles (910 sweeps the fullest) CPU 55.2 s,
wall 151.8 s; cost:1000 16 tiles (520) CPU 65.9 s, wall 186.3 s. 10,000 moves, 2 runs each:
fullest 4 tiles (3,026) CPU 219.4 and 210.7 s (wall 428.3 s at load ~10, 225.1 s at ~5);
cost:3000 16 tiles (1,730; 14,619 sweeps in all against 11,389) CPU 232.2 and 247.4 s (wall
276.8 s at load 7 -> 4, 255.0 s at ~4). Removed volumes equal to the 12 digits printed.
Finer tiles did not pay at either size: 19 % and 11 % more CPU.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from ball_sweeps import spiral_program

RUNNER = """
import sys
import machinesim.cutting.engine as engine
import machinesim.cutting.tiling as tiling
from machinesim.cli import main

def cost_rule(box, members, lower, upper, margin, target):
    # the grid rule, and then doublings while the sum of n^2 + linear n over the tiles falls
    def loads(counts):
        sizes = [len(inside) for _, inside in planned(counts)]
        return max(sizes, default=0), sum(n * (n + linear) for n in sizes)

    def planned(counts):
        walls = [tiling._walls(box[2 * a], box[2 * a + 1], counts[a]) for a in (0, 1)]
        low, high = lower[members], upper[members]
        (x0, x1), (y0, y1) = (tiling._grid_ranges(low, high, walls[a], a, margin)
                              for a in (0, 1))
        return [((walls[0][i], walls[0][i + 1], walls[1][j], walls[1][j + 1]),
                 members[(x0 <= i) & (x1 >= i) & (y0 <= j) & (y1 >= j)])
                for i in range(counts[0]) for j in range(counts[1])]

    counts, worst = [1, 1], len(members)
    cost, by_cost = worst * (worst + linear), False
    while worst > target and counts[0] * counts[1] < tiling.MAX_TILES:
        options = [(loads(c), c) for c in ([2 * counts[0], counts[1]],
                                           [counts[0], 2 * counts[1]])]
        (best, best_cost), choice = min(options, key=lambda option: option[0][0])
        if by_cost or best > tiling.SPLIT_GAIN * worst:
            by_cost = True
            (best, best_cost), choice = min(options, key=lambda option: option[0][1])
            if best_cost >= cost:
                break
        worst, cost, counts = best, best_cost, choice
    return planned(counts)

name, _, linear = sys.argv[1].partition(":")
linear = int(linear or 4500)
rule = engine.grid_tiles if name == "fullest" else cost_rule
def logged(*args):
    tiles = rule(*args)
    print("tiles", len(tiles), max(len(inside) for _, inside in tiles), file=sys.stderr)
    return tiles
engine.grid_tiles = logged
sys.exit(main(sys.argv[2:]))
"""


def cut(folder: Path, moves: int, rule: str, timeout: float) -> dict | None:
    """One cut in its own process: wall and CPU seconds, tiles and removed volume; None when
    it ran past ``timeout``."""
    program = folder / f"spiral{moves}.nc"
    program.write_text(spiral_program(moves))
    report = folder / f"spiral{moves}_{rule}.json"
    arguments = [str(program), "--machine", "grooving_4axis", "--tool", "ball:0.5", "--stock",
                 "block:10x10x2", "--out", str(folder / f"spiral{moves}_{rule}.ply"),
                 "--report", str(report), "--quiet"]
    before, start = os.times(), time.perf_counter()
    try:
        done = subprocess.run([sys.executable, "-c", RUNNER, rule, "cut", *arguments],
                              capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return None
    wall, after = time.perf_counter() - start, os.times()
    if done.returncode:
        raise SystemExit(f"spiral of {moves} moves ({rule}) failed, status "
                         f"{done.returncode}:\n{done.stderr}")
    tiles = [line.split()[1:] for line in done.stderr.splitlines() if line.startswith("tiles")]
    return {"wall": wall, "cpu": (after.children_user + after.children_system
                                  - before.children_user - before.children_system),
            "tiles": tiles[-1], "removed": json.loads(report.read_text())["removed_volume_mm3"]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=1)
    parser.add_argument("--timeout", type=float, default=1500.0,
                        help="seconds a cut may take (default 1500)")
    parser.add_argument("--moves", type=int, action="append",
                        help="moves in the spiral (repeatable; default 3000, 10000)")
    parser.add_argument("--rule", action="append",
                        help="'fullest' or 'cost:L' (repeatable; default fullest, cost:1000 "
                             "and cost:3000)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        for moves in args.moves or (3000, 10000):
            for rule in args.rule or ("fullest", "cost:1000", "cost:3000"):
                runs = [cut(Path(folder), moves, rule, args.timeout) for _ in range(args.repeat)]
                done = [run for run in runs if run is not None]
                if len(done) < len(runs):
                    print(f"spiral of {moves} moves, {rule}: {len(runs) - len(done)} of "
                          f"{len(runs)} runs > {args.timeout:.0f} s", flush=True)
                if done:
                    print(f"spiral of {moves} moves, {rule}: tiles {done[-1]['tiles'][0]} "
                          f"(fullest {done[-1]['tiles'][1]} sweeps); median of {len(done)}: "
                          f"wall {statistics.median(r['wall'] for r in done):.1f} s, CPU "
                          f"{statistics.median(r['cpu'] for r in done):.1f} s; removed "
                          f"{done[-1]['removed']:.12g} mm^3", flush=True)


if __name__ == "__main__":
    main()
