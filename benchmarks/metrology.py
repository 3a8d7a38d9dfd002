"""Height-map samples per second, their exactness, and touch-probe contacts per second.

Run: ``.venv/bin/python benchmarks/metrology.py`` (prints medians of several runs; the part
takes ~40 s to build).

First, profiles and a height map on a plate of a few large facets (a V groove in a block,
as papers 000 and 001 read it at sub-micrometre pitch), each large triangle evaluated on its
own block of samples (`surface.BOX_RUN`, the default) against the batched pass alone.

The part is the 500 x 500 pyramid field of crossing 90-degree V grooves at 50 um pitch, cut
30 um deep into a 25 x 25 mm block (a box minus two combs of V prisms, one manifold3d
batch_boolean; ~1.1M triangles). Its top is known in closed form:
z = -depth + min(distance to the nearest groove in x, in y). For comparison the script also
times manifold3d's own per-ray ``ray_cast`` on the same part.
"""

from __future__ import annotations

import statistics
import time

import manifold3d
import numpy as np

from machinesim.metrology import MeshIndex, height_map, touch, touch_many
from machinesim.workpiece import Part

COUNT = 500
PITCH = 50e-6
DEPTH = 30e-6
SIZE = COUNT * PITCH
GRID = 1000
REPEATS = 3
RADIUS = 0.25e-3  # ruby ball of the alpha-0iB probe


def comb(along: str) -> manifold3d.Manifold:
    """The V prisms of one groove direction as one solid: a sawtooth-bottomed bar.

    Grooves (lowest edges at multiples of PITCH, depth DEPTH, flanks at 45 degrees) run along
    ``along`` over the whole part and beyond; neighbouring prisms overlap above the ridges, so
    their union is the bar above the sawtooth, built directly as an exact float64 mesh.
    """
    margin, above = 2 * PITCH, 10e-6
    k = np.arange(-2, COUNT + 3)
    u = np.empty(2 * k.size - 1)
    w = np.empty_like(u)
    u[0::2], w[0::2] = k * PITCH, -DEPTH
    u[1::2], w[1::2] = (k[:-1] + 0.5) * PITCH, -DEPTH + PITCH / 2
    n = u.size
    ends = np.array([-margin, SIZE + margin])
    uu = np.tile(np.repeat(u, 2), 2)
    ww = np.tile(np.column_stack([w, np.full(n, above)]).ravel(), 2)
    ee = np.repeat(ends, 2 * n)

    def vid(end, i, level):
        return end * 2 * n + 2 * i + level

    i = np.arange(n - 1)
    quads = np.concatenate([
        np.column_stack([vid(0, i, 0), vid(1, i, 0), vid(1, i + 1, 0), vid(0, i + 1, 0)]),
        np.column_stack([vid(0, i, 1), vid(0, i + 1, 1), vid(1, i + 1, 1), vid(1, i, 1)]),
        np.column_stack([vid(0, i, 0), vid(0, i + 1, 0), vid(0, i + 1, 1), vid(0, i, 1)]),
        np.column_stack([vid(1, i, 0), vid(1, i, 1), vid(1, i + 1, 1), vid(1, i + 1, 0)]),
        [[vid(0, 0, 0), vid(0, 0, 1), vid(1, 0, 1), vid(1, 0, 0)]],
        [[vid(0, n - 1, 0), vid(1, n - 1, 0), vid(1, n - 1, 1), vid(0, n - 1, 1)]],
    ])
    triangles = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    if along == "y":
        vertices = np.column_stack([uu, ee, ww])
    else:  # swapping x and y mirrors the bar: reverse the winding to keep it outward
        vertices = np.column_stack([ee, uu, ww])
        triangles = triangles[:, ::-1]
    return manifold3d.Manifold(manifold3d.Mesh64(np.ascontiguousarray(vertices),
                                                 np.ascontiguousarray(triangles, np.uint64)))


def pyramid_part() -> Part:
    stock = manifold3d.Manifold.cube([SIZE, SIZE, 1e-3]).translate([0.0, 0.0, -1e-3])
    return Part(manifold3d.Manifold.batch_boolean([stock, comb("y"), comb("x")],
                                                  manifold3d.OpType.Subtract))


def analytic_heights(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    def to_groove(v):
        return np.abs(v - PITCH * np.round(v / PITCH))

    return -DEPTH + np.minimum(to_groove(x)[None, :], to_groove(y)[:, None])


def median_time(function, repeats: int = REPEATS) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def report_box_runs() -> None:
    """Profiles at 0.1 um pitch over a 6 mm plate with one V groove (24 triangles), along x
    and at 30 deg, and a 1200 x 1200 map of it: per-triangle blocks against the batched pass,
    and their heights compared."""
    from machinesim.metrology import profile, surface

    plate = manifold3d.Manifold.cube([6e-3, 6e-3, 1e-3]).translate([0.0, 0.0, -1e-3])
    prism = (manifold3d.Manifold.cube([1e-3, 8e-3, 1e-3], center=True).rotate([0.0, 45.0, 0.0])
             .translate([3e-3, 3e-3, -10e-6 + 1e-3 / np.sqrt(2)]))
    mesh = Part(plate - prism).mesh()
    grid = np.linspace(0.0, 6e-3, 1200)
    reads = {"profile along x": lambda: profile(mesh, (0.0, 2e-3), (6e-3, 2e-3), 1e-7)[1],
             "profile at 30 deg": lambda: profile(
                 mesh, (0.5e-3, 1e-3), (0.5e-3 + 5e-3 * np.cos(np.pi / 6),
                                        1e-3 + 5e-3 * np.sin(np.pi / 6)), 1e-7)[1],
             "map 1200 x 1200": lambda: height_map(mesh, grid, grid)}
    print(f"a plate with one V groove ({len(mesh[1])} triangles), median of {REPEATS}:")
    default = surface.BOX_RUN
    try:
        for name, read in reads.items():
            times, z = {}, {}
            for label, run in (("blocks", default), ("batched", 10**12)):
                surface.BOX_RUN = run
                z[label] = read()
                times[label] = median_time(read)
            print(f"  {name:18s} {z['blocks'].size:8d} samples: per-triangle blocks "
                  f"{times['blocks'] * 1e3:6.1f} ms, batched {times['batched'] * 1e3:6.1f} ms "
                  f"({times['batched'] / times['blocks']:.1f}x); identical heights: "
                  f"{np.array_equal(z['blocks'], z['batched'], equal_nan=True)}")
    finally:
        surface.BOX_RUN = default


def main() -> None:
    report_box_runs()
    start = time.perf_counter()
    part = pyramid_part()
    mesh = part.mesh()  # manifold3d evaluates booleans lazily: this runs them
    build = time.perf_counter() - start
    print(f"pyramid part {COUNT} x {COUNT}, pitch {PITCH * 1e6:.0f} um: "
          f"{len(mesh[1]):,} triangles, built in {build:.1f} s")

    x = np.linspace(0.0, SIZE, GRID)
    y = np.linspace(0.0, SIZE, GRID)
    heights = height_map(part, x, y)
    deviation = np.nanmax(np.abs(heights - analytic_heights(x, y)))
    from_part = median_time(lambda: height_map(part, x, y))
    from_mesh = median_time(lambda: height_map(mesh, x, y))
    n = GRID * GRID
    print(f"height_map {GRID} x {GRID} (median of {REPEATS}):")
    print(f"  from the Part (incl. to_mesh64): {from_part * 1e3:7.1f} ms  "
          f"{n / from_part / 1e6:5.2f} M samples/s")
    print(f"  from the mesh arrays:            {from_mesh * 1e3:7.1f} ms  "
          f"{n / from_mesh / 1e6:5.2f} M samples/s")
    print(f"  max |height - analytic| = {deviation:.1e} m, "
          f"NaN samples: {int(np.isnan(heights).sum())}")

    report_turned(part, x, y)

    rng = np.random.default_rng(0)
    rays = rng.uniform(0.0, SIZE, (2000, 2))
    ray_time = median_time(lambda: [part.manifold.ray_cast([px, py, 1e-3], [px, py, -2e-3])
                                    for px, py in rays])
    print(f"  manifold3d ray_cast for comparison: {len(rays) / ray_time / 1e3:6.1f} k rays/s")

    report_touch("pyramid part", part, rng, plunge=True)
    sphere = Part(manifold3d.Manifold.sphere(5e-3, 448))
    report_touch("sphere R5 mm, 448 segments", sphere, rng, plunge=False)


def report_turned(part: Part, x, y) -> None:
    """The field turned 45 deg about Z: its long groove faces then cross the grid diagonally,
    their boxes holding many times the samples they cover. Row spans against whole boxes."""
    from machinesim.metrology import surface

    turned = Part(part.manifold.rotate((0.0, 0.0, 45.0)).translate((SIZE / 2, -SIZE / 5, 0.0)))
    mesh = turned.mesh()
    inside = (x[GRID // 4:3 * GRID // 4], y[GRID // 4:3 * GRID // 4])
    times, maps = {}, {}
    try:
        for spans in (True, False):
            surface.ROW_SPANS = spans
            maps[spans] = height_map(mesh, *inside)
            times[spans] = median_time(lambda: height_map(mesh, *inside))
    finally:
        surface.ROW_SPANS = True
    n = inside[0].size * inside[1].size
    print(f"height_map {inside[0].size} x {inside[1].size} of the field turned 45 deg "
          f"(median of {REPEATS}):")
    for spans, label in ((True, "row spans (default)"), (False, "whole boxes")):
        print(f"  {label:20s} {times[spans] * 1e3:8.1f} ms  {n / times[spans] / 1e6:5.2f} M "
              "samples/s")
    print(f"  identical maps: {np.array_equal(maps[True], maps[False], equal_nan=True)}")


def report_touch(name: str, part: Part, rng, plunge: bool) -> None:
    """Contacts per second, batched and one by one, with a prebuilt MeshIndex."""
    start = time.perf_counter()
    index = MeshIndex.from_surface(part)
    build = time.perf_counter() - start
    k = 2000
    if plunge:  # straight down onto the pyramids from 0.5 mm above their base level
        centres = np.column_stack([rng.uniform(0.0, SIZE, (k, 2)), np.full(k, 0.5e-3)])
        directions = np.tile([0.0, 0.0, -1.0], (k, 1))
        travel = 1e-3
    else:  # from 8 mm out, aimed roughly at the centre
        u = rng.normal(size=(k, 3))
        u /= np.linalg.norm(u, axis=1)[:, None]
        centres = 8e-3 * u
        directions = -u + 0.1 * rng.normal(size=(k, 3))
        travel = 5e-3
    batched = median_time(lambda: touch_many(index, centres, directions, RADIUS, travel))
    touched = touch_many(index, centres, directions, RADIUS, travel).touched.mean()
    m = 300
    single = median_time(lambda: [touch(index, centres[i], directions[i], RADIUS, travel)
                                  for i in range(m)])
    print(f"touch, {name} ({len(index.triangles):,} triangles, index built in "
          f"{build * 1e3:.0f} ms), R{RADIUS * 1e3:.2f} mm ball, {touched:.0%} touched "
          f"(median of {REPEATS}):")
    print(f"  touch_many ({k} balls): {k / batched:8.0f} contacts/s")
    print(f"  touch, one at a time:   {m / single:8.0f} contacts/s")


if __name__ == "__main__":
    main()
