"""End mills on passes repeated deeper, ``machinesim cut`` end to end: the boolean engine
with sweeps inside another sweep dropped (`machinesim.cutting.engine.contained_sweeps`, the
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

Each variant runs in its own process (``--repeat`` times, median quoted), and the parts are
compared: removed volumes and the volume of each part less the other.

    .venv/bin/python benchmarks/end_mill_passes.py [--repeat 3]
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

RUNNER = """
import sys
import numpy as np
import machinesim.cutting.engine as engine
from machinesim.cli import main
if sys.argv[1] == "all":  # every sweep cut: nothing dropped
    engine.contained_sweeps = lambda hulls, *rest: np.zeros(len(hulls), dtype=bool)
sys.exit(main(sys.argv[2:]))
"""


def helix_program() -> str:
    lines = ["%", "O1 (helical bore)", "G90 G21 G17 G94", "G00 X2. Y0. Z1.", "G01 Z0. F300."]
    for turn in range(1, 9):
        lines.append(f"G02 X2. Y0. Z{-0.25 * turn:.3f} I-2. J0. F300.")
    lines += ["G02 X2. Y0. I-2. J0.", "G00 Z1.", "M30", "%"]
    return "\n".join(lines) + "\n"


def levels_program() -> str:
    lines = ["%", "O2 (a contour in levels)", "G90 G21 G17 G94", "G00 X2. Y0. Z1."]
    for level in range(1, 6):
        lines += [f"G01 Z{-0.4 * level:.3f} F300.", "G02 X2. Y0. I-2. J0. F300."]
    lines += ["G00 Z1.", "M30", "%"]
    return "\n".join(lines) + "\n"


def cut(folder: Path, name: str, text: str, variant: str) -> dict:
    program = folder / f"{name}.nc"
    program.write_text(text)
    out, report = folder / f"{name}_{variant}.ply", folder / f"{name}_{variant}.json"
    command = [sys.executable, "-c", RUNNER, variant, "cut", str(program), "--machine",
               "grooving_4axis", "--tool", "flat:0.8", "--stock", "block:8x8x4@-4,-4,0",
               "--out", str(out), "--report", str(report), "--quiet"]
    start = time.perf_counter()
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode:
        raise SystemExit(f"{name} ({variant}) failed:\n{done.stderr}")
    seconds = time.perf_counter() - start
    summary = json.loads(report.read_text())
    return {"seconds": seconds, "removed_mm3": summary["removed_volume_mm3"],
            "sweeps": summary["sweeps_count"], "part": out}


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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        for name, text in (("helix", helix_program()), ("levels", levels_program())):
            runs = {variant: [cut(folder, name, text, variant) for _ in range(args.repeat)]
                    for variant in ("dropped", "all")}
            times = {v: [r["seconds"] for r in rs] for v, rs in runs.items()}
            last = {v: rs[-1] for v, rs in runs.items()}
            print(f"{name}: {last['all']['sweeps']} sweeps; end to end, median of "
                  f"{args.repeat}: dropped {statistics.median(times['dropped']):.2f} s "
                  f"(runs {', '.join(f'{t:.2f}' for t in times['dropped'])}), all "
                  f"{statistics.median(times['all']):.2f} s "
                  f"(runs {', '.join(f'{t:.2f}' for t in times['all'])}): "
                  f"{statistics.median(times['all']) / statistics.median(times['dropped']):.2f}"
                  " times")
            print(f"  removed {last['dropped']['removed_mm3']:.12g} against "
                  f"{last['all']['removed_mm3']:.12g} mm^3; the parts apart by "
                  f"{apart_mm3(last['dropped']['part'], last['all']['part']):.3g} mm^3")


if __name__ == "__main__":
    main()
