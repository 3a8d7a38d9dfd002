"""How fast a large part opens in the viewer, in Python and in headless Chromium.

Run: ``.venv/bin/python benchmarks/viewer.py`` (prints medians of several runs; the browser
part needs the Debian package ``chromium`` and is skipped with a note without it).

The part is a field of 612 x 612 pyramids left by crossing 90-degree V grooves at 50 um pitch,
30 um deep, in a 30.6 x 30.6 x 1 mm block: 1.5M triangles, built directly as an exact float64
mesh (each pyramid is four triangles; the grooves' bottom lines run along the part's edges,
so the sides are plain walls). Its top is known in closed form,
z = -depth + min(distance to the nearest groove in x, in y), which the benchmark uses to check
that the coloured map is exact at its nodes while the drawn body is decimated.

"Opens" is `machinesim view PART.ply --html FILE`: read the PLY, measure the height map on the
exact mesh, decimate what is drawn, write the self-contained page. The browser figure is the
time from starting to load that page until its first frame is drawn.
"""

from __future__ import annotations

import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from machinesim.exceptions import MachineSimError
from machinesim.viewer import Browser, part_scene, read_ply, serve, write_html
from machinesim.viewer.maps import surface_map
from machinesim.workpiece import Part

COUNT = 612
PITCH = 50e-6
DEPTH = 30e-6
THICKNESS = 1e-3
REPEATS = 3


def pyramid_mesh(count: int = COUNT) -> tuple[np.ndarray, np.ndarray]:
    """Closed float64 mesh of the pyramid part: (vertices (n, 3) m, triangles (m, 3))."""
    size = count * PITCH
    k = np.arange(count + 1)
    gx, gy = np.meshgrid(k * PITCH, k * PITCH)  # groove crossings, row-major in y
    corners = np.column_stack([gx.ravel(), gy.ravel(), np.full(gx.size, -DEPTH)])
    c = (np.arange(count) + 0.5) * PITCH
    ax, ay = np.meshgrid(c, c)
    apexes = np.column_stack([ax.ravel(), ay.ravel(), np.full(ax.size, -DEPTH + PITCH / 2)])
    j, i = np.mgrid[0:count, 0:count]
    a = (j * (count + 1) + i).ravel()
    b, cc, d = a + 1, a + count + 2, a + count + 1
    apex = len(corners) + (j * count + i).ravel()
    top = np.concatenate([np.column_stack(t) for t in
                          ((a, b, apex), (b, cc, apex), (cc, d, apex), (d, a, apex))])
    # the rim of the top (all at z = -DEPTH), counter-clockwise seen from above
    n = count
    rim = np.concatenate([k[:-1], n + k[:-1] * (n + 1), (n + 1) * (n + 1) - 1 - k[:-1],
                          (n - k[:-1]) * (n + 1)])
    base = len(corners) + len(apexes)
    bottom = corners[rim] * [1.0, 1.0, 0.0] + [0.0, 0.0, -THICKNESS]
    r0, r1 = rim, np.roll(rim, -1)
    b0 = base + np.arange(len(rim))
    b1 = np.roll(b0, -1)
    walls = np.concatenate([np.column_stack([r1, r0, b0]), np.column_stack([r1, b0, b1])])
    # the floor: a fan from its centre (a fan from a corner would have zero-area triangles)
    centre = base + len(rim)
    floor = np.column_stack([np.full(len(rim), centre), b1, b0])
    middle = [[size / 2, size / 2, -THICKNESS]]
    vertices = np.vstack([corners, apexes, bottom, middle])
    return vertices, np.concatenate([top, walls, floor])


def analytic_heights(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    def to_groove(v):
        return np.abs(v - PITCH * np.round(v / PITCH))

    return -DEPTH + np.minimum(to_groove(x)[None, :], to_groove(y)[:, None])


def median_time(function, repeats: int = REPEATS) -> tuple[float, object]:
    times, result = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        result = function()
        times.append(time.perf_counter() - start)
    return statistics.median(times), result


def main() -> None:
    with tempfile.TemporaryDirectory(prefix="machinesim-viewer-bench-") as folder:
        run(Path(folder))


def run(folder: Path) -> None:
    start = time.perf_counter()
    part = Part.from_mesh(*pyramid_mesh())
    ply, html = folder / "pyramids.ply", folder / "pyramids.html"
    part.export_ply(ply)
    triangles = len(part.mesh()[1])
    print(f"pyramid part {COUNT} x {COUNT}, pitch {PITCH * 1e6:.0f} um: {triangles:,} "
          f"triangles, built and written in {time.perf_counter() - start:.1f} s "
          f"({ply.stat().st_size / 1e6:.0f} MB PLY)")

    read_s, mesh = median_time(lambda: read_ply(ply))
    map_s, smap = median_time(lambda: surface_map(mesh))
    scene_s, scene = median_time(lambda: part_scene(mesh))
    html_s, _ = median_time(lambda: write_html(scene, html))
    open_s, _ = median_time(lambda: write_html(part_scene(ply), html))
    exact = np.nanmax(np.abs(smap.heights - analytic_heights(smap.x, smap.y)))
    print(f"open in Python, PLY -> self-contained HTML (median of {REPEATS}): {open_s:.2f} s")
    print(f"  read_ply {read_s:.2f} s, height map {len(smap.x)} x {len(smap.y)} "
          f"{map_s:.2f} s, whole scene {scene_s:.2f} s, HTML {html_s:.2f} s "
          f"({html.stat().st_size / 1e6:.1f} MB)")
    print(f"  map nodes vs closed form: max |height - analytic| = {exact:.1e} m")

    try:
        with Browser() as browser:
            def load(url, ready="true"):
                browser.open(url)
                browser.wait_for(ready)
                return browser.screenshot()

            page_s, _ = median_time(lambda: load(html.as_uri()))
            with serve(scene) as live:
                ready = f"viewer.num_messages_received >= {live.messages}"
                live_s, _ = median_time(lambda: load(live.url, ready))
    except MachineSimError as exc:
        print(f"browser timings skipped: {exc}", file=sys.stderr)
        return
    print(f"headless Chromium (SwiftShader, no GPU), load to first frame (median of "
          f"{REPEATS}):")
    print(f"  exported page {page_s:.2f} s, live page {live_s:.2f} s")
    print(f"  total, PLY to pixels, exported: {open_s + page_s:.2f} s")


if __name__ == "__main__":
    main()
