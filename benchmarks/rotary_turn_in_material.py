"""A rotary axis turned in a feed while a flat end mill stands in the material: how the cut's
time grows with the angle (docs/cutting.md, "A rotary turn inside the material").

Each case plunges ``flat:1.0`` 0.1 mm into a 20 x 20 x 5 mm block at the origin, turns one
rotary axis by the angle in a feed (``G01 A..`` or ``G01 B..``) and retracts, through
`machinesim.cut` as a user calls it (the tool's default 100 nm chord; the flat face's tilt
sub-steps of `machinesim.motion.faces`; the exact, boolean engine). Two machines:

* planer_4axis, ``A``: the A axis on the head turns the tool about an X line 120.5 mm from
  its tip, so the tool slides 2.1 mm along Y a degree as it tilts;
* robonano_a0ib, ``B``: B turns the tool about the Y line through its tip (its edge point),
  so it tilts in place.

Printed per case: the sweeps cut, the median CPU and wall time of ``--repeat`` runs (the
process's CPU time: other jobs on a shared machine stretch the wall time, not it), the
part's triangles and the removed volume. On planer_4axis the part's triangles, and with them
the cost of each later subtraction, grow faster than the sweeps (62,342 and 168,586 at 1 and
2 deg); on robonano_a0ib they stay under 500.

    .venv/bin/python benchmarks/rotary_turn_in_material.py [--degrees 1,2,4] [--repeat 3]
        [--machines planer_4axis:A,robonano_a0ib:B] [--depth-mm 0.1] [--stock SPEC]

planer_4axis's tip rises out of a 0.1 mm plunge after about 2.3 deg (its arc is 120.5 mm);
``--depth-mm 1.5 --stock block:60x60x5@-30,-30,0`` keeps it in to 8 deg.
"""

from __future__ import annotations

import argparse
import statistics
import time

import machinesim
from machinesim.nc import parse_program

TOOL = "flat:1.0"
STOCK = "block:20x20x5@-10,-10,0"


def program_text(axis: str, degrees: float, depth_mm: float) -> str:
    """Plunge ``depth_mm`` at the origin, turn ``axis`` by ``degrees`` in a feed, retract."""
    return (f"G21 G90 G17\nG00 Z1.\nG00 X0. Y0.\nG01 Z-{depth_mm:g} F50.\n"
            f"G01 {axis}{degrees:g} F100.\nG00 Z20.\nM30\n")


def one(machine: str, axis: str, degrees: float, depth_mm: float,
        stock: str) -> tuple[float, float, int, int, float]:
    """CPU s, wall s, sweeps, part triangles, removed mm^3 of one cut."""
    program = parse_program(program_text(axis, degrees, depth_mm), chord_tolerance=1e-7)
    cpu, wall = time.process_time(), time.perf_counter()
    part, report = machinesim.cut(program, machine, tool=TOOL, stock=stock)
    cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
    return cpu, wall, report.sweeps, part.manifold.num_tri(), report.removed_volume_m3 * 1e9


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--degrees", default="1,2,4", help="angles of the turn, deg")
    parser.add_argument("--repeat", type=int, default=3, help="runs per case (median)")
    parser.add_argument("--machines", default="planer_4axis:A,robonano_a0ib:B",
                        help="machine:AXIS pairs")
    parser.add_argument("--depth-mm", type=float, default=0.1, help="plunge depth, mm")
    parser.add_argument("--stock", default=STOCK, help="stock spec (machinesim cut --stock)")
    args = parser.parse_args()
    print(f"{TOOL} {args.depth_mm:g} mm deep in {args.stock}, one rotary feed; medians of "
          f"{args.repeat} runs")
    print(f"{'machine':14} {'axis':>4} {'deg':>5} {'sweeps':>7} {'CPU s':>8} {'wall s':>8} "
          f"{'CPU/sweep ms':>12} {'triangles':>10} {'removed mm^3':>13}")
    for pair in args.machines.split(","):
        machine, axis = pair.split(":")
        for degrees in (float(d) for d in args.degrees.split(",")):
            runs = [one(machine, axis, degrees, args.depth_mm, args.stock)
                    for _ in range(args.repeat)]
            cpu = statistics.median(r[0] for r in runs)
            wall = statistics.median(r[1] for r in runs)
            _, _, sweeps, triangles, removed = runs[0]
            print(f"{machine:14} {axis:>4} {degrees:5g} {sweeps:7d} {cpu:8.2f} {wall:8.2f} "
                  f"{1e3 * cpu / sweeps:12.1f} {triangles:10d} {removed:13.9f}", flush=True)


if __name__ == "__main__":
    main()
