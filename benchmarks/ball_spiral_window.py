"""A ball end mill's densely stepped spiral (`benchmarks/ball_sweeps.py`'s program) cut in one
tile, in variants compared in the same run:

- ``sequential``: the tile's runs of overlapping sweeps (`tiling.union_runs`) subtracted one
  after the other from the tile's growing part, each sweep on its own (the engine before
  `machinesim.cutting.collinear`);
- ``joined``: the same, moves exactly in line joined into one sweep first (the engine's
  default, `collinear.joined_ball_sweeps`).

The spiral of ``--moves`` moves is planned by ``machinesim cut`` (its poses caught where the
engine would be called); a window of ``--sweeps`` consecutive sweeps from the middle of the
path is cut from the block by `engine.remove` with tiling off, so the part a sweep is
subtracted from grows as in a tile of that many sweeps. Each variant runs ``--repeat``
times, alternating; the medians of wall and CPU seconds (CPU counting manifold3d's
threads) are quoted, with the removed volumes' relative difference.

    .venv/bin/python benchmarks/ball_spiral_window.py [--moves 100000] [--sweeps 500 --sweeps 1000]
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np
from ball_sweeps import spiral_program

import machinesim.cutting.engine as engine
import machinesim.cutting.program as program_module
from machinesim.cli import main as cli_main
from machinesim.workpiece import stock_from_spec

VARIANTS = ("sequential", "joined")


class _Caught(BaseException):
    """The cut reached the engine: its tool and paths are kept (not an Exception, which the
    command line would report as an internal error)."""


def captured(moves: int, folder: Path):
    """The tool and the pose paths ``machinesim cut`` hands the engine for the spiral."""
    program = folder / f"spiral{moves}.nc"
    program.write_text(spiral_program(moves))
    kept = {}
    remove = program_module.remove

    def catch(stock, tool, paths, **_):
        kept.update(tool=tool, paths=paths)
        raise _Caught

    program_module.remove = catch
    try:
        cli_main(["cut", str(program), "--machine", "grooving_4axis", "--tool", "ball:0.5",
                  "--stock", "block:10x10x2", "--out", str(folder / "part.ply"), "--quiet"])
    except _Caught:
        pass
    finally:
        program_module.remove = remove
    return kept["tool"], kept["paths"]


def _apart(sweeps, hulls, owners):
    """No sweeps joined (`collinear.joined_ball_sweeps` switched off)."""
    return None, hulls


def cut(tool, window: np.ndarray, variant: str):
    """engine.remove of one path in one tile; (wall s, CPU s, removed m^3, triangles)."""
    saved = engine.joined_ball_sweeps
    if variant == "sequential":
        engine.joined_ball_sweeps = _apart
    try:
        wall, cpu = time.perf_counter(), time.process_time()
        part, report = engine.remove(stock_from_spec("block:10x10x2"), tool, [window],
                                     sweeps_per_tile=1 << 62, sheets=False)
        wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    finally:
        engine.joined_ball_sweeps = saved
    return wall, cpu, report.removed_volume, part.manifold.num_tri()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--moves", type=int, default=100_000)
    parser.add_argument("--sweeps", type=int, action="append",
                        help="consecutive sweeps cut (repeatable; default 500 and 1000)")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--variant", action="append", choices=VARIANTS,
                        help="variants compared (repeatable; default all)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        tool, paths = captured(args.moves, Path(folder))
    poses = np.concatenate(paths)
    move = np.diff(poses[:, :3, 3], axis=0)
    in_line = ((np.cross(move[:-1], move[1:]) == 0.0).all(axis=1)
               & (np.einsum("ij,ij->i", move[:-1], move[1:]) > 0.0))
    print(f"spiral of {args.moves} moves: {len(poses)} poses, steps "
          f"{np.median(np.linalg.norm(move, axis=1)) * 1e6:.2f} um (median), "
          f"{int(in_line.sum())} pairs of consecutive moves exactly in line")
    for count in args.sweeps or (500, 1000):
        middle = len(poses) // 2
        window = poses[middle - count // 2:middle - count // 2 + count + 1]
        variants = args.variant or VARIANTS
        runs = {variant: [] for variant in variants}
        for _ in range(args.repeat):
            for variant in variants:
                runs[variant].append(cut(tool, window, variant))
        first = runs[variants[0]][-1]
        print(f"  {count} sweeps, median of {args.repeat}: " + "; ".join(
            f"{variant} wall {statistics.median(r[0] for r in rs):.2f} s, CPU "
            f"{statistics.median(r[1] for r in rs):.2f} s, removed {rs[-1][2]:.12g} m^3 "
            f"(relative to {variants[0]} {abs(rs[-1][2] - first[2]) / first[2]:.1e}), "
            f"{rs[-1][3]} triangles" for variant, rs in runs.items()), flush=True)


if __name__ == "__main__":
    main()
