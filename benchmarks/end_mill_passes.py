"""End mills on passes repeated deeper, ``machinesim cut`` end to end: the boolean engine
with sweeps inside another sweep dropped (`machinesim.cutting.containment.contained_sweeps`, the
default) against every sweep cut, in the same run.

CAM programs go down in levels over one path: a helical bore's turns, a contour's or a
pocket's depth passes. Each pass's sweep then lies inside the deeper one's, faces in the
same planes, and uniting coincident faces is manifold3d's slowest work. Two programs on
grooving_4axis, each written here as NC text and cut from the command line's entry point
(reading, planning, cutting, the PLY and the report written):

a. A helical bore: ``flat:0.8`` down a helix of radius 2 mm, 0.25 mm a turn, 8 turns to
   2 mm deep (G02 with Z, I), then a full circle at the bottom, at the default chord of an
   end mill (100 nm).
b. A contour in levels: the same circle cut at 5 depths, 0.4 mm apart (G02 full circles).
e. A zigzag pocket: ``flat:1`` 0.2 mm deep, 1000 passes 10 mm long at 10 um step-over (2006
   lines), its level passes united by their footprints (`machinesim.cutting.footprints`,
   the default) against in three dimensions.
f. A trochoidal slot: ``flat:0.5`` 0.3 mm deep, 60 loops of G02 (10,982 sweeps, all level
   passes on one floor): their solids made only when read and left out of the containment
   test (`machinesim.cutting.sweeps.DeferredSolid`, the default) against every solid made
   and tested (as before).
g. A star: ``flat:0.5`` 0.1 mm deep, 180 spokes 8 mm long from one hub, each after the
   first begun by a rapid down to 0.05 mm into the hub the spokes before cut (1,080 lines):
   the rapids judged first by whether one earlier sweep holds what they met
   (`machinesim.cutting.rapids.RAPID_HOLDERS`, the default) against by unions alone.
h. Plunge roughing: ``flat:0.5`` plunged 3000 times to 20 um, 1 um apart along X (9,004
   lines), a slot of overlapping plunges whose floor the booleans leave with slivers facing
   down: the search for sheets thinner than 1 pm on the finished part with faces no wider
   than that left out of its pairing (`machinesim.cutting.sheets`, the default) against
   every face paired.
i. A ball end mill's raster finish, as Fusion posts one: ``ball:0.5`` over a gently curved
   floor 0.03-0.08 mm deep, 19 passes along X 12 mm long at 0.5 mm step-over, each of 199
   lines (3,800 sweeps, every one a line that also moves in Z): each sweep the tool cut at
   its lowest ring wholly above the clip plane, untrimmed (`SweepSet._ball_cut`, the
   default) against the whole tool's sweep trimmed by the plane (as before).

With ``--tilted`` the same end mill cuts through ``models/errors/example.toml``, whose
workpiece stands tilted 0.01 and -0.02 deg against the machine's Z: the engine cuts in the
tool's frame (`machinesim.cutting.frame`, the default) against in the workpiece frame, where
the end mill's floors coincide only to round-off:

c. one circle of (b), both ways (in the workpiece frame 1.7 million triangles and 20.7 GB
   resident, 241 s, measured alone on 2026-11-30: run nothing large beside it on a 24 GB
   machine);
d. the contour in 5 levels, in the tool's frame only (in the workpiece frame it outgrew the
   machine's 24 GB).

Each variant runs in its own process (``--repeat`` times, median quoted; peak memory is the
process's maximum resident set), and the parts are compared: removed volumes and the volume
of each part less the other.

    .venv/bin/python benchmarks/end_mill_passes.py [--repeat 3] [--tilted] [--case plunges]
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
import numpy as np
import machinesim.cutting.engine as engine
from machinesim.cli import main
if sys.argv[1] == "all":  # every sweep cut: nothing dropped
    engine.contained_sweeps = lambda hulls, *rest: np.zeros(len(hulls), dtype=bool)
if sys.argv[1] == "workpiece":  # a tilted tool cut where it stands in the workpiece frame
    engine.tool_frame = lambda poses, tool: None
if sys.argv[1] == "eager":  # every level pass's solid made and tested for containment
    import machinesim.cutting.sweepset as sweepset
    from machinesim.cutting.sweeps import manifold_from
    sweepset.DeferredSolid = manifold_from
    engine.united_in_plane = lambda footprints: np.zeros(len(footprints), dtype=bool)
if sys.argv[1] == "unions":  # rapids judged by unions of the earlier sweeps alone
    import machinesim.cutting.rapids as rapids
    rapids.RAPID_HOLDERS = 0
if sys.argv[1] == "solids":  # level passes united in 3-D, not by their footprints
    import machinesim.cutting.footprints as footprints
    footprints.FEWEST = 10 ** 9
if sys.argv[1] == "slivers":  # every face paired in the search for sheets
    import machinesim.cutting.sheets as sheets
    sheets._wide = lambda corners, area, thickness: np.ones(len(corners), dtype=bool)
if sys.argv[1] == "trimmed":  # a ball end mill's whole sweep, trimmed by the clip plane
    from machinesim.cutting.sweepset import SweepSet
    SweepSet._ball_cut = lambda self, rotation, origin, move: "whole"
status = main(sys.argv[2:])
print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss, file=sys.stderr)
sys.exit(status)
"""


def helix_program() -> str:
    lines = ["%", "O1 (helical bore)", "G90 G21 G17 G94", "G00 X2. Y0. Z1.", "G01 Z0. F300."]
    for turn in range(1, 9):
        lines.append(f"G02 X2. Y0. Z{-0.25 * turn:.3f} I-2. J0. F300.")
    lines += ["G02 X2. Y0. I-2. J0.", "G00 Z1.", "M30", "%"]
    return "\n".join(lines) + "\n"


def levels_program(levels: int = 5) -> str:
    lines = ["%", "O2 (a contour in levels)", "G90 G21 G17 G94", "G00 X2. Y0. Z1."]
    for level in range(1, levels + 1):
        lines += [f"G01 Z{-0.4 * level:.3f} F300.", "G02 X2. Y0. I-2. J0. F300."]
    lines += ["G00 Z1.", "M30", "%"]
    return "\n".join(lines) + "\n"


def pocket_program(rows: int = 1000, step_mm: float = 0.01) -> str:
    lines = ["%", "O3 (a zigzag pocket)", "G90 G21 G17 G94", "G00 X-5. Y-5. Z1.",
             "G01 Z-0.2 F100."]
    for row in range(rows):
        lines += [f"G01 X{5.0 if row % 2 == 0 else -5.0:.4f} Y{-5.0 + row * step_mm:.4f}",
                  f"G01 Y{-5.0 + (row + 1) * step_mm:.4f}"]
    lines += ["G00 Z1.", "M30", "%"]
    return "\n".join(lines) + "\n"


def trochoid_program(loops: int = 60) -> str:
    lines = ["%", "O5 (a trochoidal slot)", "G90 G21 G17 G94", "G00 X0. Y0. Z1.",
             "G01 Z-0.3 F100."]
    x = 0.0
    for _ in range(loops):
        lines.append(f"G02 X{x + 0.1:.4f} Y0. I0.05 J0. F300.")
        x += 0.1
        lines += [f"G02 X{x:.4f} Y1.0 I0. J0.5", f"G02 X{x:.4f} Y0. I0. J-0.5"]
    lines += ["G00 Z1.", "M30", "%"]
    return "\n".join(lines) + "\n"


def star_program(spokes: int = 180, length_mm: float = 8.0) -> str:
    lines = ["%", "O4 (a star)", "G90 G21 G17 G94", "G00 X0. Y0. Z2."]
    for k in range(spokes):
        angle = 2 * math.pi * k / spokes
        lines.append("G00 X0. Y0.")
        if k:
            lines.append("G00 Z-0.05")  # down into the hub the spokes before cut
        lines += ["G01 Z-0.1 F100.", f"G01 X{length_mm * math.cos(angle):.4f} "
                  f"Y{length_mm * math.sin(angle):.4f} F200.", "G00 Z-0.05", "G00 Z2."]
    lines += ["M30", "%"]
    return "\n".join(lines) + "\n"


def plunges_program(plunges: int = 3000, step_mm: float = 0.001) -> str:
    lines = ["%", "O5 (plunge roughing)", "G90 G21 G17 G94", "G00 X0. Y2. Z1."]
    for k in range(plunges):
        lines += [f"G00 X{k * step_mm:.4f}", "G01 Z-0.02 F100.", "G00 Z1."]
    lines += ["M30", "%"]
    return "\n".join(lines) + "\n"


def raster_program(passes: int = 19, lines: int = 199) -> str:
    """A Fusion-style finishing raster: each pass plunges, then follows the floor
    z = -0.03 - 0.02 (x + 1) / 12 - 0.03 sin(pi y / 10) (mm) in ``lines`` lines, and
    retracts."""
    text = ["%", "O6 (a ball end mill's raster finish)", "G90 G21 G17 G94", "G00 X-1. Y0.5 Z5."]

    def z(x: float, y: float) -> float:
        return -0.03 - 0.02 * (x + 1.0) / 12.0 - 0.03 * math.sin(math.pi * y / 10.0)

    for k in range(passes):
        y = 0.5 + 0.5 * k
        xs = [-1.0 + 12.0 * i / lines for i in range(lines + 1)]
        if k % 2:
            xs.reverse()
        text += [f"G00 X{xs[0]:.4f} Y{y:.4f}", f"G01 Z{z(xs[0], y):.4f} F500."]
        text += [f"X{x:.4f} Z{z(x, y):.4f} F1500." for x in xs[1:]]
        text.append("G00 Z1.")
    text += ["M30", "%"]
    return "\n".join(text) + "\n"


def cut(folder: Path, name: str, text: str, variant: str, errors: Path | None = None,
        tool: str = "flat:0.8", stock: str = "block:8x8x4@-4,-4,0") -> dict:
    program = folder / f"{name}.nc"
    program.write_text(text)
    out, report = folder / f"{name}_{variant}.ply", folder / f"{name}_{variant}.json"
    arguments = [str(program), "--machine", "grooving_4axis", "--tool", tool, "--stock",
                 stock, "--out", str(out), "--report", str(report), "--quiet"]
    if errors is not None:
        arguments += ["--errors", str(errors)]
    seconds, summary, stderr = timed_cut(RUNNER, variant, arguments, report, name)
    with open(out, "rb") as ply:  # the header names the triangle count
        header = ply.read(512).decode("latin-1")
    triangles = int(header.split("element face ")[1].split()[0])
    return {"seconds": seconds, "peak_mb": int(stderr.split()[-1]) / 1024,
            "removed_mm3": summary["removed_volume_mm3"],
            "sweeps": summary["sweeps_count"], "part": out, "triangles": triangles,
            "rapids": summary["rapids_that_cut_lines"]}


def apart_mm3(a: Path, b: Path) -> float:
    """Volume of each part less the other (mm^3), read from the float64 PLYs."""
    import manifold3d
    import trimesh

    def solid(path):
        mesh = trimesh.load(path, process=False)
        return manifold3d.Manifold(manifold3d.Mesh64(
            vert_properties=mesh.vertices.astype("float64"),
            tri_verts=mesh.faces.astype("uint64")))

    p, q = solid(a), solid(b)
    return ((p - q).volume() + (q - p).volume()) * 1e9


def compare(folder: Path, name: str, text: str, variants: tuple[str, str], repeat: int,
            errors: Path | None = None, **where) -> None:
    """Cut ``text`` both ways ``repeat`` times each and print medians and the parts' gap."""
    runs = {variant: [cut(folder, name, text, variant, errors, **where) for _ in range(repeat)]
            for variant in variants}
    times = {v: [r["seconds"] for r in rs] for v, rs in runs.items()}
    last = {v: rs[-1] for v, rs in runs.items()}
    first, second = variants
    print(f"{name}: {last[second]['sweeps']} sweeps; end to end, median of {repeat}: "
          + ", ".join(f"{v} {statistics.median(times[v]):.2f} s (runs "
                      f"{', '.join(f'{t:.2f}' for t in times[v])}; "
                      f"{last[v]['triangles']:,} triangles, peak "
                      f"{max(r['peak_mb'] for r in runs[v]):.0f} MB)" for v in variants)
          + f": {statistics.median(times[second]) / statistics.median(times[first]):.2f} times")
    print(f"  removed {last[first]['removed_mm3']:.12g} against "
          f"{last[second]['removed_mm3']:.12g} mm^3; the parts apart by "
          f"{apart_mm3(last[first]['part'], last[second]['part']):.3g} mm^3; rapids that cut "
          f"at lines {last[first]['rapids']} against {last[second]['rapids']}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--tilted", action="store_true",
                        help="cut through models/errors/example.toml (cases c and d)")
    parser.add_argument("--case", action="append",
                        choices=("helix", "levels", "pocket", "trochoid", "star", "plunges",
                                 "raster"),
                        help="only this case (repeatable; default every untilted case)")
    args = parser.parse_args()
    chosen = set(args.case or ("helix", "levels", "pocket", "trochoid", "star", "plunges",
                               "raster"))
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        if not args.tilted:
            for name, text in (("helix", helix_program()), ("levels", levels_program())):
                if name in chosen:
                    compare(folder, name, text, ("dropped", "all"), args.repeat)
            if "pocket" in chosen:
                compare(folder, "pocket", pocket_program(), ("footprints", "solids"),
                        args.repeat, tool="flat:1", stock="block:20x20x5")
            if "trochoid" in chosen:
                compare(folder, "trochoid", trochoid_program(), ("deferred", "eager"),
                        args.repeat, tool="flat:0.5", stock="block:10x6x2@-2,-3,0")
            if "star" in chosen:
                compare(folder, "star", star_program(), ("holders", "unions"), args.repeat,
                        tool="flat:0.5", stock="block:20x20x2@-10,-10,0")
            if "plunges" in chosen:
                compare(folder, "plunges", plunges_program(), ("wide", "slivers"),
                        args.repeat, tool="flat:0.5", stock="block:10x10x2")
            if "raster" in chosen:
                compare(folder, "raster", raster_program(), ("rings", "trimmed"), args.repeat,
                        tool="ball:0.5", stock="block:12x10x1@-1,0,0")
            return
        errors = Path(__file__).resolve().parents[1] / "models" / "errors" / "example.toml"
        compare(folder, "circle, tilted", levels_program(1), ("frame", "workpiece"),
                args.repeat, errors)
        runs = [cut(folder, "levels, tilted", levels_program(), "frame", errors)
                for _ in range(args.repeat)]
        seconds = [r["seconds"] for r in runs]
        print(f"levels, tilted: {runs[-1]['sweeps']} sweeps; end to end in the tool's frame, "
              f"median of {args.repeat}: {statistics.median(seconds):.2f} s "
              f"(runs {', '.join(f'{t:.2f}' for t in seconds)}; "
              f"{runs[-1]['triangles']:,} triangles), removed {runs[-1]['removed_mm3']:.12g} "
              "mm^3")


if __name__ == "__main__":
    main()
