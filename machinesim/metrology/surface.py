"""Exact top-surface heights of a part: a float64 z-buffer over its mesh.

A height is the plane of the triangle above the sample, evaluated in float64 at the sample
point: no interpolation, no ray, no rounding of the geometry. The mesh is rasterised onto the
samples: each upward-facing triangle is binned to the samples inside its xy bounding box (on
a grid, a thin one row by row to the span each row crosses, so that a long thin triangle
across the grid's diagonal does not visit its whole box), an edge-function test keeps those
inside the triangle, and each sample keeps the highest plane value that covers it.

Why no sample falls through a crack: each edge function is evaluated from the edge's
canonical anchor (its endpoint lower in (y, x)), with the direction taken as the difference of
the two endpoints. IEEE subtraction and multiplication are symmetric under negation, so the two
triangles that share an edge get exactly opposite values at any sample. A triangle is closed
(a sample on its edge is inside), so a sample on a shared edge is inside both, and one exactly
on a vertex gets exact zeros from every edge through it. Where several triangles cover a sample
the highest wins: a sample exactly on a vertical step reads the top of the step, as
"the highest surface point above (x, y)" asks.
"""

from __future__ import annotations

import numpy as np

from machinesim.exceptions import InputError
from machinesim.metrology._arrays import as_floats
from machinesim.metrology._mesh import as_positive, as_vector, mesh_arrays
from machinesim.tolerances import END_SLACK, INDEX_SLACK, LINE_MARGIN, UNIFORM_GRID

__all__ = ["MAX_SAMPLES", "check_read", "grid_heights", "height_map", "profile"]

#: Most samples one reading (a profile, a height map) may hold; a profile read through a spot
#: counts each of the spot's ``samples**2`` sub-samples, which it reads at once. Beyond it the
#: reading is refused before anything is allocated. Measured peak memory per sample: 33 bytes
#: for a map (49 with a spot, read in blocks, or lateral noise), 42 for a profile, 106 for a
#: profile with lateral noise, 36 per sub-sample for a profile through a spot. So a reading at
#: the cap takes at most ~11 GB, under half of a 24 GB machine: a map of 10^4 x 10^4 samples
#: is a 3 mm square at the microscope's 0.3 um pitch.
MAX_SAMPLES = 100_000_000

#: Triangles read per pass: small enough that a pass's arrays stay in the CPU cache
#: (measured: 8192 is ~1.5x faster than 131072 on the pyramid benchmark).
TRIANGLE_CHUNK = 8192
#: Triangle-sample candidates evaluated per pass, for the same reason; also bounds memory when
#: one triangle covers millions of samples.
CANDIDATE_BLOCK = 32768

#: Bin a grid's triangles row by row to the spans they cross (`_row_spans`), not to their
#: whole boxes: the same heights bit for bit; benchmarks/metrology.py switches it off to
#: compare (the pyramid field turned 45 deg, and paper 002's crown, read 10-30 times faster).
ROW_SPANS = True
#: A triangle that covers less than this share of its xy box (over more than one row) is
#: binned by row spans: a long thin triangle across the diagonal covers a few percent, one
#: along the axes half (a right triangle), where whole boxes are cheaper to bin.
THIN_FILL = 0.125

#: A box (a triangle's, or one row's span of it) that holds at least this many samples is
#: evaluated on its own, over its block of samples (a run of a line, a rectangle of a grid)
#: with the triangle's parameters as scalars: the same arithmetic as the batched pass, so
#: the same heights bit for bit, without gathering the table per sample. Lines and maps over
#: a few large facets (the plates of papers 000 and 001 read at sub-micrometre pitch, the
#: crown's faces) are where the batched pass spent most of its time.
BOX_RUN = 256
#: Samples evaluated at once on such a box (bounds the temporaries to a few MB).
BOX_BLOCK = 65536

# Rows of the per-triangle parameter table used by the rasteriser.
_X0, _Y0, _Z0, _GX, _GY, _ZLO, _ZHI, _EDGES = range(8)


def height_map(surface, x, y) -> np.ndarray:
    """Heights of the top surface over a grid of sample points.

    Parameters
    ----------
    surface : Part or MeshIndex or tuple of (array-like, array-like)
        The measured solid, or its ``(vertices (n, 3) float64 m, triangles (m, 3) int)``.
    x : array-like, shape (nx,)
        Sample x coordinates in the workpiece frame, m, strictly increasing.
    y : array-like, shape (ny,)
        Sample y coordinates, m, strictly increasing.

    Returns
    -------
    heights : ndarray, shape (ny, nx), float64, read-only
        ``heights[j, i]`` is the highest surface point above ``(x[i], y[j])``, m; NaN where no
        surface lies below: the sample is off the part and read nothing (a missing point, as
        an x3p file marks it invalid). The fits leave such samples out.

    Raises
    ------
    InputError
        For a malformed mesh, sample axes that are not 1-D, finite and strictly increasing,
        or a grid of which no sample lies over the part (`check_read`).
    """
    vertices, triangles = mesh_arrays(surface)
    x, y = _axis(x, "x"), _axis(y, "y")
    heights = _grid_heights(vertices, triangles, x, y)
    check_read(heights, vertices, f"the height map over x {x[0]:g} .. {x[-1]:g} m, y "
                                  f"{y[0]:g} .. {y[-1]:g} m", "x")
    return heights


def grid_heights(surface, x, y) -> np.ndarray:
    """`height_map` without its refusal of a grid wholly off the part: for a reading put
    together from blocks (`machinesim.metrology.imperfections.spot_heights`), one of which
    may lie off the part while the whole does not."""
    vertices, triangles = mesh_arrays(surface)
    return _grid_heights(vertices, triangles, _axis(x, "x"), _axis(y, "y"))


def _grid_heights(vertices, triangles, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    check_samples(float(x.size) * y.size, None, f"x {x[0]:g} .. {x[-1]:g} m, y {y[0]:g} .. "
                  f"{y[-1]:g} m")
    grid = _Grid(x, y)
    return _finish(_zbuffer(vertices, triangles, grid).reshape(grid.shape))


def check_read(heights: np.ndarray, vertices: np.ndarray, what: str, key: str) -> None:
    """Refuse a reading (``what``: a profile from ... to ..., a map over ...) of which every
    sample read nothing: no surface of the part (``vertices``, m) lies below any of them.

    A real profilometer off the part reads no point, and a trace that reads none is no
    measurement: its heights would all be NaN, and a fit of them fails later naming none of
    this ("Expected at least 5 finite samples, got 0"), or a mean of them is NaN. A trace
    partly off the part keeps its on-part samples; the rest are NaN (missing).
    """
    if heights.size == 0 or not np.isnan(heights).all():
        return
    if len(vertices) == 0:
        spans = "the part has no surface at all (an empty mesh)"
    else:
        lo, hi = vertices[:, :2].min(axis=0), vertices[:, :2].max(axis=0)
        spans = (f"the part spans x {lo[0]:.6g} .. {hi[0]:.6g} m, y {lo[1]:.6g} .. "
                 f"{hi[1]:.6g} m")
    raise InputError(f"{what} reads no surface: all {heights.size} of its samples lie off "
                     f"the part (no surface below them); {spans}. Expected a trace over "
                     "the part, in m (SI: 5 mm is 0.005)", key=key)


def profile(surface, start, end, spacing: float, *, refuse: bool = True
            ) -> tuple[np.ndarray, np.ndarray]:
    """Heights of the top surface along a straight line in xy.

    Parameters
    ----------
    surface : Part or MeshIndex or tuple of (array-like, array-like)
        The measured solid, or its ``(vertices, triangles)``.
    start, end : array-like, shape (2,)
        End points (x, y) of the line in the workpiece frame, m.
    spacing : float
        Distance between samples along the line, m. The first sample is at ``start``; the
        last is the last whole spacing not beyond ``end`` (``end`` itself when the length is a
        whole number of spacings).
    refuse : bool
        False: leave a line wholly off the part to the caller, who names it (an optical
        instrument names the line as asked, not where its stage put it: `check_read`).

    Returns
    -------
    s : ndarray, shape (k,), float64, read-only
        Distance of each sample from ``start`` along the line, m.
    z : ndarray, shape (k,), float64, read-only
        Height of the top surface at each sample, m; NaN where no surface lies below: the
        sample is off the part and read nothing (missing). The fits leave such samples out.

    Raises
    ------
    InputError
        For a malformed mesh, a zero-length line, a spacing that is not > 0, or (``refuse``)
        a line of which no sample lies over the part (`check_read`).
    """
    vertices, triangles = mesh_arrays(surface)
    start = as_vector(start, 2, "start")
    end = as_vector(end, 2, "end")
    spacing = as_positive(spacing, "spacing")
    length = float(np.hypot(*(end - start)))
    if length == 0.0:
        raise InputError(f"Expected a profile of non-zero length, got start = end = {start}")
    count = line_count(length, spacing)
    if count < 2.0:  # spacing=0.3 (um meant) over a 2 mm line read the start alone
        raise InputError(f"Expected a spacing shorter than the line, got spacing {spacing:g} m "
                         f"over a {length:g} m line: it would read one sample, at start "
                         "(spacing is in m: 0.3 um is 3e-07)", key="spacing")
    check_samples(count, spacing, f"a {length:g} m line")
    s = np.arange(int(count)) * spacing
    if abs(s[-1] - length) <= END_SLACK * spacing:
        s[-1] = length
    line = _Line(start, end, length, s, vertices)
    z = _finish(_zbuffer(vertices, triangles, line))
    s.setflags(write=False)
    if refuse:
        check_read(z, vertices, f"the profile from ({start[0]:g}, {start[1]:g}) to "
                                f"({end[0]:g}, {end[1]:g}) m", "start")
    return s, z


def line_count(length: float, spacing: float) -> float:
    """Samples from 0 to the last whole ``spacing`` not beyond ``length`` (m, both > 0), as a
    float: a whole number, possibly far too large to allocate (see `check_samples`)."""
    return float(np.floor(length / spacing + END_SLACK)) + 1.0


def check_samples(count: float, spacing: float | None, window: str,
                  per_sample: int = 1) -> None:
    """Refuse a reading of ``count`` samples (``per_sample`` points read for each) over
    ``window`` beyond `MAX_SAMPLES`, naming the count, the spacing and the window."""
    if count * per_sample > MAX_SAMPLES:
        each = f" x {per_sample} spot sub-samples" if per_sample > 1 else ""
        at = "" if spacing is None else f" at spacing {spacing:g} m"
        fix = "fewer x or y samples" if spacing is None else "a larger spacing or a smaller window"
        raise InputError(f"Expected at most {MAX_SAMPLES:.0e} samples in one reading "
                         f"(MAX_SAMPLES), got {count:.4g}{each}{at} over {window}: "
                         f"take {fix}", key=None if spacing is None else "spacing")


def _axis(values, name: str) -> np.ndarray:
    """A sample axis as a finite, strictly increasing float64 1-D copy."""
    axis = as_floats(values, name)
    if axis.ndim != 1 or axis.size == 0:
        raise InputError(f"Expected {name} with shape (n,), n >= 1, got {axis.shape}", key=name)
    if not np.isfinite(axis).all():
        raise InputError(f"Expected finite {name}, got NaN or infinity", key=name)
    if np.any(np.diff(axis) <= 0.0):
        raise InputError(f"Expected strictly increasing {name}", key=name)
    return axis


def _finish(top: np.ndarray) -> np.ndarray:
    top[top == -np.inf] = np.nan
    top.setflags(write=False)
    return top


class _AxisBins:
    """Index range of the samples of one sorted axis that lie in [lo, hi]."""

    def __init__(self, axis: np.ndarray) -> None:
        self.axis = axis
        n = axis.size
        self.uniform = False
        if n >= 2:
            self.step = (axis[-1] - axis[0]) / (n - 1)
            deviation = np.max(np.abs(axis - (axis[0] + np.arange(n) * self.step))) / self.step
            if deviation < UNIFORM_GRID:
                self.uniform = True
                # Round-off, in spacings, of the deviation itself and of the bin arithmetic.
                round_off = 8 * np.finfo(np.float64).eps * (np.abs(axis).max() / self.step + n)
                self.slack = deviation + round_off + INDEX_SLACK

    def __call__(self, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """First index with axis >= lo and the count of indices with lo <= axis <= hi."""
        n = self.axis.size
        if self.uniform:
            first = np.ceil((lo - self.axis[0]) / self.step - self.slack)
            stop = np.floor((hi - self.axis[0]) / self.step + self.slack) + 1.0
            np.clip(first, 0, n, out=first)
            np.clip(stop, 0, n, out=stop)
            first = first.astype(np.int64)
            stop = stop.astype(np.int64)
        else:
            first = np.searchsorted(self.axis, lo, side="left")
            stop = np.searchsorted(self.axis, hi, side="right")
        return first, np.maximum(stop - first, 0)


class _Grid:
    """Samples on the grid x[i], y[j], stored row by row (index j * nx + i)."""

    def __init__(self, x: np.ndarray, y: np.ndarray) -> None:
        self.x, self.y = x, y
        self.shape = (y.size, x.size)
        self.size = x.size * y.size
        self.bins_x, self.bins_y = _AxisBins(x), _AxisBins(y)

    def ranges(self, xmin, xmax, ymin, ymax):
        first_x, count_x = self.bins_x(xmin, xmax)
        first_y, count_y = self.bins_y(ymin, ymax)
        return first_x, count_x, first_y, count_y

    def coordinates(self, i, j):
        return self.x[i], self.y[j]

    def flat(self, i, j):
        return j * self.x.size + i


class _Line:
    """Samples start + s[i] * direction along a line; a degenerate grid of one row."""

    def __init__(self, start, end, length, s, vertices) -> None:
        self.start = start
        self.direction = direction = (end - start) / length
        self.px = start[0] + s * direction[0]
        self.py = start[1] + s * direction[1]
        if s[-1] == length:
            # The end is sampled: take it exactly, not one rounding away from it.
            self.px[-1], self.py[-1] = end
        self.size = s.size
        scale = max(np.abs(vertices).max(initial=0.0), np.abs(start).max(),
                    np.abs(self.px[-1]), np.abs(self.py[-1]))
        self.margin = LINE_MARGIN * scale
        # Along the axis the line runs most along, the sample coordinate is monotonic in i (the
        # rounding of start + s * u is monotonic in s), so a box maps to one index range.
        self.axis = 0 if abs(direction[0]) >= abs(direction[1]) else 1
        self.sign = 1.0 if direction[self.axis] > 0 else -1.0
        self.key = self.sign * (self.px if self.axis == 0 else self.py)

    def ranges(self, xmin, xmax, ymin, ymax):
        ux, uy = self.direction
        # Signed distance (times |u| = 1) of the box corners from the line: a box the line
        # misses has all four on one side.
        across_x = np.stack([(xmin - self.start[0]) * uy, (xmax - self.start[0]) * uy])
        across_y = np.stack([(ymin - self.start[1]) * -ux, (ymax - self.start[1]) * -ux])
        low = across_x.min(axis=0) + across_y.min(axis=0)
        high = across_x.max(axis=0) + across_y.max(axis=0)
        near = np.flatnonzero((low <= self.margin) & (high >= -self.margin))
        lo, hi = (xmin[near], xmax[near]) if self.axis == 0 else (ymin[near], ymax[near])
        if self.sign < 0:
            lo, hi = -hi, -lo
        first = np.zeros(xmin.size, dtype=np.int64)
        count = np.zeros(xmin.size, dtype=np.int64)
        first[near] = np.searchsorted(self.key, lo, side="left")
        count[near] = np.searchsorted(self.key, hi, side="right") - first[near]
        return first, count, np.zeros_like(first), np.ones_like(count)

    def coordinates(self, i, j):
        return self.px[i], self.py[i]

    def flat(self, i, j):
        return i


def _zbuffer(vertices: np.ndarray, triangles: np.ndarray, samples) -> np.ndarray:
    """Highest plane value over each sample, flat, -inf where no triangle covers it."""
    vx, vy, vz = (np.ascontiguousarray(vertices[:, k]) for k in range(3))
    top = np.full(samples.size, -np.inf)
    margin = LINE_MARGIN * max(float(np.abs(vertices[:, :2]).max(initial=0.0)), 1e-300)
    for begin in range(0, len(triangles), TRIANGLE_CHUNK):
        chunk = triangles[begin:begin + TRIANGLE_CHUNK]
        i0, i1, i2 = chunk[:, 0], chunk[:, 1], chunk[:, 2]
        x = (vx[i0], vx[i1], vx[i2])
        y = (vy[i0], vy[i1], vy[i2])
        # Twice the projected area, > 0 for a triangle counter-clockwise seen from above, i.e.
        # facing up. Vertical (0) and downward faces never carry the top surface of a solid.
        area2 = (x[1] - x[0]) * (y[2] - y[0]) - (y[1] - y[0]) * (x[2] - x[0])
        box = (np.minimum(np.minimum(x[0], x[1]), x[2]), np.maximum(np.maximum(x[0], x[1]), x[2]),
               np.minimum(np.minimum(y[0], y[1]), y[2]), np.maximum(np.maximum(y[0], y[1]), y[2]))
        first_x, count_x, first_y, count_y = samples.ranges(*box)
        keep = np.flatnonzero((area2 > 0.0) & (count_x > 0) & (count_y > 0))
        if keep.size == 0:
            continue
        x = tuple(c[keep] for c in x)
        y = tuple(c[keep] for c in y)
        z = (vz[i0[keep]], vz[i1[keep]], vz[i2[keep]])
        table = _triangle_table(x, y, z, area2[keep])
        first_x, count_x, first_y, count_y = (a[keep] for a in (first_x, count_x, first_y,
                                                                  count_y))
        owner = None
        if ROW_SPANS and isinstance(samples, _Grid):
            # thin: the triangle covers under THIN_FILL of its box, over more than one row
            box_area = (box[1] - box[0])[keep] * (box[3] - box[2])[keep]
            is_thin = (count_y > 1) & (area2[keep] < 2.0 * THIN_FILL * box_area)
            if is_thin.any():
                thin, whole = np.flatnonzero(is_thin), np.flatnonzero(~is_thin)
                spans = _row_spans(tuple(c[thin] for c in x), tuple(c[thin] for c in y),
                                   first_y[thin], count_y[thin], samples, margin)
                owner = np.concatenate([whole, thin[spans[0]]])
                first_x = np.concatenate([first_x[whole], spans[1]])
                count_x = np.concatenate([count_x[whole], spans[2]])
                first_y = np.concatenate([first_y[whole], spans[3]])
                count_y = np.concatenate([count_y[whole], np.ones_like(spans[2])])
        _rasterise(table, first_x, count_x, first_y, count_y, samples, top, owner)
    return top


def _row_spans(x, y, first_y, count_y, samples: _Grid, margin: float):
    """Each triangle's rows of the grid and, on each, the samples of the span it crosses.

    Returns (owner, first, count, row): one entry per (triangle, row) pair, the triangle's
    index, the first sample of the span and their count, and the row. The span runs between
    the edges' crossings of the row, widened by ``margin`` (and the rows by as much beyond the
    triangle's y range), so it holds every sample the exact edge test can keep: round-off
    puts those within ~1e-16 relative of the triangle.
    """
    owner = np.repeat(np.arange(first_y.size), count_y)
    ends = np.cumsum(count_y)
    row = first_y[owner] + (np.arange(owner.size) - (ends - count_y)[owner])
    yj = samples.y[row]
    lo = np.full(owner.size, np.inf)
    hi = np.full(owner.size, -np.inf)
    for a, b in ((0, 1), (1, 2), (2, 0)):
        xa, ya, xb, yb = x[a][owner], y[a][owner], x[b][owner], y[b][owner]
        on = (yj >= np.minimum(ya, yb) - margin) & (yj <= np.maximum(ya, yb) + margin)
        dy = yb - ya
        level = dy == 0.0
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.clip((yj - ya) / np.where(level, 1.0, dy), 0.0, 1.0)
        cross = xa + t * (xb - xa)
        # a level edge on the row crosses it all along: both of its ends bound the span
        left = np.where(level, np.minimum(xa, xb), cross)
        right = np.where(level, np.maximum(xa, xb), cross)
        lo = np.where(on, np.minimum(lo, left), lo)
        hi = np.where(on, np.maximum(hi, right), hi)
    first, count = samples.bins_x(lo - margin, hi + margin)
    return owner, first, count, row


def _triangle_table(x, y, z, area2) -> np.ndarray:
    """Per-triangle plane and edge functions, shape (19, m): rows named by the _ constants."""
    ax, ay, az = x[1] - x[0], y[1] - y[0], z[1] - z[0]
    bx, by, bz = x[2] - x[0], y[2] - y[0], z[2] - z[0]
    rows = [
        x[0], y[0], z[0],
        (az * by - ay * bz) / area2,
        (ax * bz - az * bx) / area2,
        # The plane evaluated inside a triangle lies between its lowest and highest vertex;
        # clamping to that only bites on near-vertical slivers, where round-off of the tiny
        # projected area would otherwise throw a height far off.
        np.minimum(np.minimum(z[0], z[1]), z[2]),
        np.maximum(np.maximum(z[0], z[1]), z[2]),
    ]
    for i, j in ((0, 1), (1, 2), (2, 0)):
        swap = (y[i] > y[j]) | ((y[i] == y[j]) & (x[i] > x[j]))
        rows += [np.where(swap, x[j], x[i]), np.where(swap, y[j], y[i]), x[j] - x[i], y[j] - y[i]]
    return np.stack(rows)


def _rasterise(table, first_x, count_x, first_y, count_y, samples, top, owner=None) -> None:
    """Evaluate every (triangle, sample-in-its-box) pair and keep the maximum per sample.

    With ``owner``, box k (a triangle's whole box, or one row's span of it, `_row_spans`)
    belongs to column ``owner[k]`` of ``table``."""
    counts = count_x * count_y
    run = counts >= BOX_RUN
    if run.any():
        for k in np.flatnonzero(run):
            _rasterise_box(table[:, k if owner is None else owner[k]], int(first_x[k]),
                           int(count_x[k]), int(first_y[k]), int(count_y[k]), samples, top)
        rest = np.flatnonzero(~run)
        if rest.size == 0:
            return
        if owner is None:
            table = table[:, rest]
        else:
            owner = owner[rest]
        first_x, count_x, first_y, count_y, counts = (
            a[rest] for a in (first_x, count_x, first_y, count_y, counts))
    ends = np.cumsum(counts)
    starts = ends - counts
    total = int(ends[-1])
    for k0 in range(0, total, CANDIDATE_BLOCK):
        k1 = min(k0 + CANDIDATE_BLOCK, total)
        t0 = int(np.searchsorted(ends, k0, side="right"))
        t1 = int(np.searchsorted(ends, k1 - 1, side="right")) + 1
        share = np.minimum(ends[t0:t1], k1) - np.maximum(starts[t0:t1], k0)
        tri = np.repeat(np.arange(t0, t1), share)
        offset = np.arange(k0, k1) - starts[tri]
        width = count_x[tri]
        row = offset // width
        i = first_x[tri] + (offset - row * width)
        j = first_y[tri] + row
        px, py = samples.coordinates(i, j)
        p = table[:, tri if owner is None else owner[tri]]
        inside = None
        for e in range(_EDGES, _EDGES + 12, 4):
            ax, ay, dx, dy = p[e], p[e + 1], p[e + 2], p[e + 3]
            ok = dx * (py - ay) - dy * (px - ax) >= 0.0
            inside = ok if inside is None else inside & ok
        hit = np.flatnonzero(inside)
        if hit.size == 0:
            continue
        p = p[:_EDGES, hit]
        px, py = px[hit], py[hit]
        z = p[_Z0] + p[_GX] * (px - p[_X0]) + p[_GY] * (py - p[_Y0])
        np.clip(z, p[_ZLO], p[_ZHI], out=z)
        np.maximum.at(top, samples.flat(i[hit], j[hit]), z)


def _rasterise_box(p, i0: int, ni: int, j0: int, nj: int, samples, top) -> None:
    """`_rasterise` for one triangle (its table column ``p``) over the samples ``i0 .. i0 +
    ni`` (of a line), or the grid's columns ``i0 .. i0 + ni`` of rows ``j0 .. j0 + nj``: the
    same edge tests and plane, in the same order, on a view of ``top``, in blocks of at most
    `BOX_BLOCK` samples (memory stays bounded however large the triangle)."""
    width = min(ni, BOX_BLOCK)
    rows = max(1, BOX_BLOCK // width)
    for i in range(i0, i0 + ni, width):
        i1 = min(i + width, i0 + ni)
        if not isinstance(samples, _Grid):
            _evaluate_block(p, samples.px[i:i1], samples.py[i:i1], top[i:i1])
            continue
        grid = top.reshape(samples.shape)
        for j in range(j0, j0 + nj, rows):
            j1 = min(j + rows, j0 + nj)
            _evaluate_block(p, samples.x[i:i1][None, :], samples.y[j:j1][:, None],
                            grid[j:j1, i:i1])


def _evaluate_block(p, px, py, seen) -> None:
    """Raise ``seen`` (a view of the z-buffer) to triangle ``p``'s plane where the samples
    ``px``, ``py`` (broadcast to ``seen``'s shape) pass its three edge tests."""
    inside = None
    for e in range(_EDGES, _EDGES + 12, 4):
        ax, ay, dx, dy = p[e], p[e + 1], p[e + 2], p[e + 3]
        ok = dx * (py - ay) - dy * (px - ax) >= 0.0
        inside = ok if inside is None else inside & ok
    z = p[_Z0] + p[_GX] * (px - p[_X0]) + p[_GY] * (py - p[_Y0])
    np.clip(z, p[_ZLO], p[_ZHI], out=z)
    np.maximum(seen, z, out=seen, where=inside)
