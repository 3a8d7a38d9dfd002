"""Speed of cutting a tilted crown face by face (`machinesim.cutting.cut_turned`).

Paper 002's crown before compensation, as the scenario cuts it by default: the rough crown
set 100 um high and tilted 1.93 deg about X (scenarios/workpiece_setting.py), its nominal
program's passes that reach the quick measuring windows, the last finishing layer. Timed
here: the two face groups at C = 45 and 90 deg (each C group is cut on its own, so the
whole crown scales with them), the same cut two ways in one run:

- ``aligned``: the default; each group turned back by its C angle and by the workpiece's
  tilt, so its sweeps run along the machine's axes;
- ``by C alone``: ``align=False``, the sweeps tilted 1.93 deg in the engine's frame.

Both make the same part (the volumes printed agree to round-off). Times are medians of
``--repeat`` runs, wall clock, on the engine's cut of the two groups (`CutReport.engine_s`)
and the whole call.

Run: ``.venv/bin/python benchmarks/crown_cut.py [--repeat 3]``
"""

from __future__ import annotations

import argparse
import math
import statistics
import time

from machinesim import ErrorModel, Lab, WorkpieceSetting, load_machine
from machinesim.cam import crown as cam
from machinesim.cutting import cut_turned
from machinesim.procedures.workpiece_setting import RobotLoadedWorkpiece
from machinesim.realism import Realism
from machinesim.units import M_PER_UM

TILT = ErrorModel(workpiece=WorkpieceSetting([0.0, 0.0, 100 * M_PER_UM],
                                             math.radians(1.93), 0.0, 0.0))
FACES_DEG = (45.0, 90.0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    machine = load_machine("robonano_a0ib")
    procedure = RobotLoadedWorkpiece("crown", quick=True)
    lab = Lab(machine, TILT, realism=Realism.ideal())
    found = procedure.identify(procedure.measure(lab)).detail.found
    layout = procedure.layout(found)
    groups = [g for g in cam.crown_passes(procedure.crown, [0.0], **layout.rows)
              if any(math.isclose(g.c, math.radians(a)) for a in FACES_DEG)]
    program = cam.passes_program(groups)
    stock = procedure.stock
    print(f"crown tilted 1.93 deg, 100 um high; faces at C = {FACES_DEG} deg, "
          f"{len(groups)} pass groups, quick windows; median of {args.repeat}")
    for label, align in (("aligned", True), ("by C alone", False)):
        wall, engine = [], []
        for _ in range(args.repeat):
            began = time.perf_counter()
            part, report = cut_turned(program, machine, layout.tool, stock, TILT,
                                      roi=layout.boxes, floor=layout.floor, start=cam.PARK,
                                      align=align)
            wall.append(time.perf_counter() - began)
            engine.append(report.engine_s)
        print(f"{label:>11}: {statistics.median(wall):7.1f} s the call, "
              f"{statistics.median(engine):7.1f} s the engine; {report.sweeps} sweeps cut, "
              f"volume {part.volume * 1e9:.12f} mm^3")


if __name__ == "__main__":
    main()
