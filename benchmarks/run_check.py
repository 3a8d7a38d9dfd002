"""What the check of each run's subtraction costs (`machinesim.cutting.run_check`,
`engine.remove`'s ``check_runs``), ``machinesim.cut`` end to end, every setting in the same
process, interleaved: "turning" (the default: runs with a sweep that turns the tool), "all"
and "off".

Cases (``--cases``, comma-separated):

* ``trunnion``: ``flat:1.0`` plunged 0.1 mm into ``block:20x20x5@-10,-10,0`` and turned
  ``G01 A1.`` 10.1 mm from the A axis (planer_4axis with its tool moved up under A, written
  to a temporary URDF), where manifold3d 3.5.4 left a wedge in a run (docs/cutting.md, "A
  rotary turn inside the material"); ``planer``: the same on planer_4axis itself (120.5 mm
  from A); both from benchmarks/rotary_turn_in_material.py;
* ``helix``, ``raster``: benchmarks/end_mill_passes.py's helical bore (``flat:0.8``, 8 turns
  of G02 with Z) and Fusion-style ball raster (``ball:0.5``, 3,800 sweeps), on grooving_4axis;
* ``crown``: paper 002's crown before compensation as its default run cuts it
  (benchmarks/cutting.py's case g: robonano_a0ib, lab realism, seed 0, `cut_turned`; the
  crown measured once), minutes a cut.

Printed per case and setting: the median process CPU and wall time of ``--repeat`` cuts (CPU
counts manifold3d's threads; the wall time moves with other jobs on a shared machine), the
runs checked, the runs cut again one sweep at a time, and the removed volume.

    .venv/bin/python benchmarks/run_check.py [--cases trunnion,planer,helix,raster]
        [--repeat 3] [--settings turning,all,off]
"""

from __future__ import annotations

import argparse
import functools
import statistics
import tempfile
import time
from pathlib import Path

import machinesim
from machinesim.cutting import engine, run_check
from machinesim.nc import parse_program

ROOT = Path(__file__).resolve().parents[1]
SUBTRACT_RUN, ONE_AT_A_TIME = engine.subtract_run, run_check.one_at_a_time


def trunnion_urdf(folder: Path) -> Path:
    """planer_4axis with A 10.1 mm above the tool's tip (its arm 120.5 mm long, A 79.5 mm
    under the Z carriage): A 189.9 mm under the carriage, the tool mount 9.9 mm above A's
    link, so that the tip stays at the workpiece origin at zero."""
    text = (ROOT / "models" / "planer_4axis.urdf").read_text()
    for old, new in (('<origin xyz="0.0 0.0 -0.07950000000000002" rpy="0.0 0.0 0.0"/>',
                      '<origin xyz="0.0 0.0 -0.1899" rpy="0.0 0.0 0.0"/>'),
                     ('<origin xyz="0.0 0.0 -0.10049999999999999" rpy="0.0 0.0 0.0"/>',
                      '<origin xyz="0.0 0.0 0.0099" rpy="0.0 0.0 0.0"/>')):
        if text.count(old) != 1:
            raise SystemExit(f"models/planer_4axis.urdf no longer has {old!r} once")
        text = text.replace(old, new)
    path = folder / "trunnion_like.urdf"
    path.write_text(text.replace('robot name="planer_4axis"', 'robot name="trunnion_like"'))
    return path


def cases(folder: Path) -> dict:
    """Name -> a function that cuts the case once and returns its removed volume (m^3)."""
    from end_mill_passes import helix_program, raster_program
    from rotary_turn_in_material import program_text

    turn = parse_program(program_text("A", 1.0, 0.1), chord_tolerance=1e-7)

    def rotary(machine):
        return lambda: machinesim.cut(turn, machine, tool="flat:1.0",
                                      stock="block:20x20x5@-10,-10,0")[1].removed_volume_m3

    def grooving(name, text, tool):
        # read from a file as the command line reads it: arcs split within the tool's
        # chord (100 nm for these), not parse_program's 1 nm
        program = folder / f"{name}.nc"
        program.write_text(text)
        return lambda: machinesim.cut(program, "grooving_4axis", tool=tool,
                                      stock="block:8x8x4@-4,-4,0")[1].removed_volume_m3

    return {"trunnion": rotary(machinesim.load_machine(trunnion_urdf(folder))),
            "planer": rotary("planer_4axis"),
            "helix": grooving("helix", helix_program(), "flat:0.8"),
            "raster": grooving("raster", raster_program(), "ball:0.5"),
            "crown": crown_cut}


@functools.cache
def crown_setup():
    """The lab, procedure, layout and program of paper 002's crown before compensation,
    measured once (`_crown.crown_before`, benchmarks/cutting.py's case g too)."""
    from _crown import crown_before

    return crown_before()


def crown_cut() -> float:
    """Paper 002's crown before compensation, cut as benchmarks/cutting.py's case g cuts it
    (`Lab.cut`, `cut_turned`)."""
    import math

    from machinesim.cam.crown import PARK

    lab, procedure, layout, program = crown_setup()
    _, report = lab.cut(program, layout.tool, procedure.workpiece(lab), roi=layout.boxes,
                        floor=layout.floor, start=PARK, turn_step=math.pi / 4)
    return report.removed_volume_m3


def counted(tally: dict):
    """engine.subtract_run, counting the runs it checks and those it cuts again."""
    def one_at_a_time(piece, solids):
        tally["again"] += 1
        return ONE_AT_A_TIME(piece, solids)

    def subtract_run(piece, solids, sweeps, check=True, pieces=None):
        tally["checked"] += bool(check)
        return SUBTRACT_RUN(piece, solids, sweeps, check, pieces)

    run_check.one_at_a_time = one_at_a_time
    return subtract_run


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cases", default="trunnion,planer,helix,raster",
                        help="comma-separated: trunnion, planer, helix, raster, crown")
    parser.add_argument("--repeat", type=int, default=3, help="cuts per setting (median)")
    parser.add_argument("--settings", default="turning,all,off",
                        help="check_runs values, comma-separated")
    args = parser.parse_args()
    settings = args.settings.split(",")
    defaults = engine.remove.__kwdefaults__
    print(f"median of {args.repeat} cuts per setting, settings interleaved")
    print(f"{'case':9} {'setting':8} {'CPU s':>8} {'wall s':>8} {'checked':>8} "
          f"{'again':>6} {'removed m^3':>22}")
    with tempfile.TemporaryDirectory() as folder:
        table = cases(Path(folder))
        for name in args.cases.split(","):
            runs = {setting: [] for setting in settings}
            for _ in range(args.repeat):
                for setting in settings:
                    tally = {"checked": 0, "again": 0}
                    engine.subtract_run = counted(tally)
                    defaults["check_runs"] = setting
                    cpu, wall = time.process_time(), time.perf_counter()
                    try:
                        removed = table[name]()
                    finally:
                        defaults["check_runs"] = "turning"
                        engine.subtract_run = SUBTRACT_RUN
                        run_check.one_at_a_time = ONE_AT_A_TIME
                    runs[setting].append((time.process_time() - cpu,
                                          time.perf_counter() - wall, tally, removed))
            for setting, done in runs.items():
                tally, removed = done[0][2], done[0][3]
                print(f"{name:9} {setting:8} {statistics.median(r[0] for r in done):8.2f} "
                      f"{statistics.median(r[1] for r in done):8.2f} {tally['checked']:8d} "
                      f"{tally['again']:6d} {removed:22.15e}", flush=True)


if __name__ == "__main__":
    main()
