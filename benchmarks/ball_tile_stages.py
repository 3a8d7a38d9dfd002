"""Where a tile's time goes when a ball end mill's spiral of short G01 moves is cut
(`benchmarks/ball_sweeps.py`'s program): the engine's tile loop in stages, on the first
``--members`` sweeps of the fullest tile, timed apart (wall and CPU seconds, the CPU time
counting manifold3d's threads):

- the tile plan: tiles and sweeps in each (`tiling.grid_tiles`, as `engine.remove` makes it);
- rebuild: each sweep's solid made again as the tile reads it (`RebuiltSolid`);
- union: each run of `tiling.union_runs` united (``batch_boolean``), evaluated;
- subtract: the united runs taken one by one from the tile's stock, as `engine.remove` does.

The cut runs through ``machinesim cut`` up to the tile loop: `SweepSet.hulls` is watched to
keep the sweeps, and `contained_sweeps` stops the cut when it is handed the tiles. Stages
are timed with the engine's own functions; evaluating each run's union before subtracting
it is what manifold3d does when the difference is evaluated (the same solid).

    .venv/bin/python benchmarks/ball_tile_stages.py [--moves 8000] [--members 500 --members 1000]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import manifold3d
import numpy as np
from ball_sweeps import spiral_program
from manifold3d import OpType

import machinesim.cutting.engine as engine
from machinesim.cli import main as cli_main
from machinesim.cutting.stitch import exact_box
from machinesim.cutting.tiling import union_runs


class _Planned(BaseException):
    """The cut reached its tile loop: what the benchmark needs is kept (not an Exception,
    which the command line would report as an internal error)."""


def captured(moves: int, folder: Path) -> dict:
    """The sweeps and the tile plan of the spiral of ``moves`` moves, and the build time."""
    program = folder / f"spiral{moves}.nc"
    program.write_text(spiral_program(moves))
    kept: dict = {}
    hulls_method, contained = engine.SweepSet.hulls, engine.contained_sweeps

    def hulls(self, *args, **kwargs):
        start = time.perf_counter()
        result = hulls_method(self, *args, **kwargs)
        kept.update(result=result, build_s=time.perf_counter() - start, run_id=self.run_id)
        return result

    def stop(hull_list, lower, upper, tiles, tol):
        kept["tiles"] = tiles
        raise _Planned

    engine.SweepSet.hulls, engine.contained_sweeps = hulls, stop
    try:
        cli_main(["cut", str(program), "--machine", "grooving_4axis", "--tool", "ball:0.5",
                  "--stock", "block:10x10x2", "--out", str(folder / "part.ply"), "--quiet"])
    except _Planned:
        pass
    finally:
        engine.SweepSet.hulls, engine.contained_sweeps = hulls_method, contained
    return kept


def timed(function):
    wall, cpu = time.perf_counter(), time.process_time()
    value = function()
    return value, time.perf_counter() - wall, time.process_time() - cpu


def stages(kept: dict, count: int) -> str:
    hulls, lower, upper, direction = kept["result"][:4]
    keys = engine._direction_keys(direction)
    box, members = max(kept["tiles"], key=lambda tile: len(tile[1]))
    rest = members[:count]
    stock = exact_box(box[0], box[1], box[2], box[3], -2e-3, 1e-6)
    _, rebuild_w, rebuild_c = timed(lambda: [hulls[i].num_tri() for i in rest])
    runs = [run for key in np.unique(keys[rest])
            for run in union_runs(rest[keys[rest] == key], lower, upper)]

    def unite():
        united = [manifold3d.Manifold.batch_boolean([hulls[i] for i in run], OpType.Add)
                  for run in runs]
        for solid in united:
            solid.num_tri()
        return united

    united, union_w, union_c = timed(unite)

    def subtract():
        piece = stock
        for solid in united:
            piece = piece - solid
            piece.num_tri()
        return piece

    piece, sub_w, sub_c = timed(subtract)
    return (f"  {len(rest)} sweeps, {len(runs)} runs: rebuild {rebuild_w:.2f} s "
            f"(CPU {rebuild_c:.2f}), union {union_w:.2f} s (CPU {union_c:.2f}), subtract "
            f"{sub_w:.2f} s (CPU {sub_c:.2f}); tile part {piece.num_tri()} triangles")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--moves", type=int, default=8000)
    parser.add_argument("--members", type=int, action="append",
                        help="sweeps of the fullest tile to cut (repeatable; default 250, "
                             "500, 1000)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        kept = captured(args.moves, Path(folder))
    print(f"spiral of {args.moves} moves: {len(kept['result'][0])} sweeps built in "
          f"{kept['build_s']:.1f} s; tiles {len(kept['tiles'])}, sweeps per tile "
          f"{sorted(len(members) for _, members in kept['tiles'])}")
    for count in args.members or (250, 500, 1000):
        print(stages(kept, count), flush=True)


if __name__ == "__main__":
    main()
