"""A machine whose URDF names big STL visuals (a CAD export's): loading it, and its view.

The machine is grooving_4axis with ``--meshes`` of its box and cylinder visuals replaced by
binary STL files of ``--triangles`` triangles each (a rippled 0.1 m square, made here in a
temporary folder beside the URDF, as a CAD export's meshes/ folder). Each figure is the
median over ``--repeat`` runs, each its own process, with that process's peak RSS:

- ``load``: `machinesim.load_machine` of the meshed URDF (what ``machinesim cut`` does
  with it), against ``load-plain``, the shipped file: loading reads no mesh;
- ``visuals-new`` and ``visuals-old``: the machine's visual geometry for the view,
  `machinesim.viewer.visuals.machine_visuals` with its STL files drawn from their paths
  (new), and with Pinocchio reading every one of them (old: no suffix deferred, as the
  viewer did before);
- ``scene-new`` and ``scene-old``: the whole `machinesim.viewer.machine_scene`, which sends
  each STL file's bytes to the page.

    .venv/bin/python benchmarks/urdf_visuals.py [--meshes 3] [--triangles 500000]
        [--repeat 3] [--methods load load-plain visuals-new visuals-old scene-new scene-old]
"""

from __future__ import annotations

import argparse
import json
import re
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

METHODS = ("load", "load-plain", "visuals-new", "visuals-old", "scene-new", "scene-old")


def write_stl(path: Path, triangles: int) -> None:
    """A binary STL of about ``triangles`` triangles (an even number): a rippled 0.1 m
    square, two triangles a grid cell."""
    n = max(1, round((triangles / 2) ** 0.5))
    x = np.linspace(-0.05, 0.05, n + 1)
    gx, gy = np.meshgrid(x, x, indexing="ij")
    grid = np.stack([gx, gy, 1e-3 * np.sin(300 * gx) * np.cos(300 * gy)], -1)
    a, b, c, d = grid[:-1, :-1], grid[1:, :-1], grid[1:, 1:], grid[:-1, 1:]
    corners = np.concatenate([np.stack([a, b, c], -2).reshape(-1, 3, 3),
                              np.stack([a, c, d], -2).reshape(-1, 3, 3)])
    records = np.zeros(len(corners), dtype=[("normal", "<f4", 3), ("v", "<f4", (3, 3)),
                                            ("attribute", "<u2")])
    records["v"] = corners
    with open(path, "wb") as file:
        file.write(b"benchmarks/urdf_visuals.py".ljust(80))
        file.write(np.uint32(len(records)).tobytes())
        file.write(records.tobytes())


def meshed_urdf(folder: Path, meshes: int, triangles: int) -> Path:
    """grooving_4axis with its first ``meshes`` shapes replaced by STL meshes in
    ``folder``/meshes (one file written, named by each visual)."""
    from machinesim import load_machine

    (folder / "meshes").mkdir()
    write_stl(folder / "meshes" / "part.stl", triangles)
    count = 0

    def mesh(match: re.Match) -> str:
        nonlocal count
        if count == meshes:
            return match.group(0)
        count += 1
        if count > 1:
            (folder / "meshes" / f"part{count}.stl").hardlink_to(folder / "meshes" / "part.stl")
        name = "part.stl" if count == 1 else f"part{count}.stl"
        return f'<geometry><mesh filename="meshes/{name}"/></geometry>'

    text = Path(load_machine("grooving_4axis").path).read_text()
    text = re.sub(r"<geometry>.*?</geometry>", mesh, text)
    if count < meshes:
        raise SystemExit(f"--meshes {meshes}: grooving_4axis has {count} visuals to replace")
    path = folder / "meshed.urdf"
    path.write_text(text)
    return path


def child(method: str, urdf: str) -> None:
    """One run of ``method`` in this process: print its seconds and peak RSS (kB) as JSON."""
    import machinesim.viewer.visuals as visuals
    from machinesim.machines import Machine
    from machinesim.viewer import machine_scene
    from machinesim.viewer.scene import Scene

    if method == "load-plain":
        from machinesim import load_machine

        urdf = load_machine("grooving_4axis").path
    machine = None if method.startswith("load") else Machine(Path(urdf))
    if method.endswith("-old"):
        visuals.DEFERRED_SUFFIXES = ()
    start = time.perf_counter()
    if method.startswith("load"):
        Machine(Path(urdf))
    elif method.startswith("visuals"):
        visuals.machine_visuals(machine, Scene("benchmark"))
    else:
        machine_scene(machine)
    seconds = time.perf_counter() - start
    print(json.dumps({"seconds": seconds,
                      "peak_rss_kb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss}))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--meshes", type=int, default=3)
    parser.add_argument("--triangles", type=int, default=500_000)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--methods", nargs="+", choices=METHODS, default=list(METHODS))
    parser.add_argument("--child", nargs=2, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        child(*args.child)
        return
    with tempfile.TemporaryDirectory() as folder:
        urdf = meshed_urdf(Path(folder), args.meshes, args.triangles)
        size = (Path(folder) / "meshes" / "part.stl").stat().st_size
        print(f"grooving_4axis with {args.meshes} STL visuals of {args.triangles:,} triangles "
              f"({size / 2**20:.1f} MB each); median of {args.repeat} runs, each a process")
        runs: dict[str, list[dict]] = {m: [] for m in args.methods}
        for _ in range(args.repeat):  # the methods alternate, so load drifts hit them alike
            for method in args.methods:
                done = subprocess.run([sys.executable, __file__, "--child", method, str(urdf)],
                                      capture_output=True, text=True)
                if done.returncode:
                    raise SystemExit(f"{method} failed:\n{done.stderr}")
                runs[method].append(json.loads(done.stdout.splitlines()[-1]))
        for method, found in runs.items():
            seconds = statistics.median(r["seconds"] for r in found)
            rss = statistics.median(r["peak_rss_kb"] for r in found) / 1024
            print(f"{method:12s} {seconds:8.3f} s   peak RSS {rss:7.0f} MB")


if __name__ == "__main__":
    main()
