"""The exact Gaussian blur of a part's top surface, in closed form (`Spot` with ``exact``).

The top surface of a mesh is piecewise planar: each upward-facing triangle carries a plane
``z = z_c + g . (p - c)`` over its plan. Its Gaussian-weighted integral about a sample ``c``
(spot sigma ``s``) splits into the plane's height at ``c`` times the spot's weight on the
triangle, and the gradient times the first moment, which the divergence theorem
(``(p - c) G = -s^2 grad G``) turns into a sum over the triangle's edges of the Gaussian along
each edge: ``erf`` terms. The weight on a triangle is a signed sum, over its edges, of the
weight of the triangle the edge makes with ``c``; each is two right triangles with a vertex
at ``c``, whose weight is the wedge's ``angle / 2 pi`` less Owen's T function beyond the leg.
So a height jump (a wall: its vertical triangles carry no plan) and a kink (the bottom of a
V) are integrated exactly wherever they fall, not where a sub-grid's nodes cross them.

Where the part's upward faces overlap in plan (an overhang: paper 002's rough crown has
faces that run 0.1 um over a wall 0.015 deg off vertical), the z-buffer of
`machinesim.metrology.surface` keeps the highest and this would sum both: a sample whose
spot weighs more than one on the part (`OVERLAP`) is read instead on a fine grid of
z-buffer heights (`FINE`). Under an overhang at the edge of the part the weight may stay
below one: not caught.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.special import ndtr, owens_t

from machinesim.metrology.surface import grid_heights

__all__ = ["OVERLAP", "REACH", "gaussian_blur"]

#: Triangles farther than this many sigmas from a sample are left out of its blur, and a
#: sample this far inside a triangle sees that triangle alone: the weight beyond is below
#: 1e-9 (exp(-REACH^2 / 2) = 6.8e-10 off a disc; 4e-11 beyond one straight edge).
REACH = 6.5
#: An upward triangle narrower in plan than this many sigmas across its slope is a wall (a
#: boolean's vertical face, tilted by round-off): left out, as a wall is. Its weight is at
#: most its width over sigma sqrt(2 pi), 4e-8 of the spot; its plane, evaluated at a sample
#: up to REACH sigmas away, had grown past any height the part has (the slope is the
#: height over that width) and its two terms had cancelled only to round-off of that size.
WALL_WIDTH = 1e-7
#: A spot weighing more than 1 + OVERLAP on the part counts some of it twice: upward faces
#: overlap in plan (an overhang), and the reading is off by up to that excess times the
#: height between the overlapping faces, up to a wall's height: 1e-5 keeps it within 4 nm
#: at paper 002's rough crown, whose faces run 0.1 um over walls up to ~0.4 mm high (its
#: samples weigh up to 1 + 1.1e-4 there). A boolean's round-off leans a wall out by
#: ~1e-13 m, an overlap that weighs ~1e-7 of the spot, and is passed.
OVERLAP = 1e-5
#: The fine grid's step, in sigmas (1/40), over +-REACH, and its turn about the sample, rad
#: (the spot is round; machined walls lie along x, y and 45 deg, not along 57.3 deg): its
#: midpoint sum is within 1e-4 of a wall's height of the closed form (tests/test_spot_exact.py).
FINE = 1.0 / 40.0
FINE_TURN = 1.0
#: Samples blurred at once: their pairs with the triangles near them are the arrays.
POINT_BLOCK = 20_000
#: (triangle, sample) pairs evaluated at once (each ~40 float64 temporaries: ~50 MB).
PAIR_BLOCK = 150_000


def gaussian_blur(vertices, triangles, px, py, sigma: float) -> tuple[np.ndarray, np.ndarray]:
    """The spot's weighted integral of the top surface and its weight on the part.

    Parameters
    ----------
    vertices : ndarray, shape (n, 3)
        m.
    triangles : ndarray, shape (m, 3)
        int; upward faces counter-clockwise seen from above (as the z-buffer reads them).
    px, py : ndarray, shape (k,)
        The samples' centres, m.
    sigma : float
        The Gaussian's standard deviation, m (> 0).

    Returns
    -------
    total : ndarray, shape (k,)
        The integral of height times the spot's density over the part's top surface, m.
    weight : ndarray, shape (k,)
        The spot's weight on the part, 0 .. 1; ``total / weight`` is the blurred height.
    """
    vertices = np.asarray(vertices, dtype=np.float64)
    triangles = np.asarray(triangles)
    planes = _planes(vertices, triangles, sigma)
    px = np.asarray(px, dtype=np.float64)
    py = np.asarray(py, dtype=np.float64)
    total, weight = np.zeros(px.size), np.zeros(px.size)
    for b0 in range(0, px.size, POINT_BLOCK):
        part = slice(b0, b0 + POINT_BLOCK)
        total[part], weight[part] = _block(planes, px[part], py[part], sigma)
    for i in np.flatnonzero(weight > 1.0 + OVERLAP):  # an overhang: read on the fine grid
        total[i], weight[i] = _fine(vertices, triangles, px[i], py[i], sigma)
    return total, weight


def _planes(vertices: np.ndarray, triangles: np.ndarray, sigma: float) -> tuple:
    """The upward triangles that are not walls: their corners (x, y (m, 3)), their planes
    (height at the first corner, gradient) and their edges' inward normals and offsets."""
    x, y, z = (vertices[triangles, k] for k in range(3))
    area2 = (x[:, 1] - x[:, 0]) * (y[:, 2] - y[:, 0]) - (y[:, 1] - y[:, 0]) * (x[:, 2] - x[:, 0])
    up = area2 > 0.0
    x, y, z, area2 = x[up], y[up], z[up], area2[up]
    gx = ((z[:, 1] - z[:, 0]) * (y[:, 2] - y[:, 0])
          - (z[:, 2] - z[:, 0]) * (y[:, 1] - y[:, 0])) / area2
    gy = ((x[:, 1] - x[:, 0]) * (z[:, 2] - z[:, 0])
          - (x[:, 2] - x[:, 0]) * (z[:, 1] - z[:, 0])) / area2
    # plan width across the slope: the height span over the slope
    keep = np.ptp(z, axis=1) >= WALL_WIDTH * sigma * np.hypot(gx, gy)
    x, y, z, gx, gy = x[keep], y[keep], z[keep, 0], gx[keep], gy[keep]
    # each edge's inward unit normal and offset: a point's distance inside it, m
    ex, ey = np.roll(x, -1, axis=1) - x, np.roll(y, -1, axis=1) - y
    length = np.hypot(ex, ey)
    nx, ny = -ey / length, ex / length
    return x, y, z, gx, gy, (nx, ny, nx * x + ny * y)


def _block(planes: tuple, px: np.ndarray, py: np.ndarray, sigma: float):
    x, y, z0, gx, gy, (nx, ny, offset) = planes
    reach = REACH * sigma
    near = ((x.min(axis=1) <= px.max() + reach) & (x.max(axis=1) >= px.min() - reach)
            & (y.min(axis=1) <= py.max() + reach) & (y.max(axis=1) >= py.min() - reach))
    tri = np.flatnonzero(near)
    total, weight = np.zeros(px.size), np.zeros(px.size)
    if tri.size == 0:
        return total, weight
    k_all, p_all = _candidates(x[tri], y[tri], px, py, reach)
    k_all = tri[k_all]
    for b0 in range(0, k_all.size, PAIR_BLOCK):
        k, p = k_all[b0:b0 + PAIR_BLOCK], p_all[b0:b0 + PAIR_BLOCK]
        # how far each sample lies inside its triangle (< 0 outside), in sigmas
        inside = np.min(nx[k] * px[p, None] + ny[k] * py[p, None] - offset[k], axis=1) / sigma
        deep = inside >= REACH  # the whole spot on this triangle (to 1e-10): its plane
        kd, pd = k[deep], p[deep]
        total += np.bincount(pd, z0[kd] + gx[kd] * (px[pd] - x[kd, 0])
                             + gy[kd] * (py[pd] - y[kd, 0]), minlength=px.size)
        weight += np.bincount(pd, minlength=px.size)
        on = ~deep & (inside > -REACH)  # the rest but those off it by more than REACH
        k, p = k[on], p[on]
        value, mass = _pairs(x[k], y[k], z0[k], gx[k], gy[k], px[p], py[p], sigma)
        total += np.bincount(p, value, minlength=px.size)
        weight += np.bincount(p, mass, minlength=px.size)
    return total, weight


def _candidates(x, y, px, py, reach: float) -> tuple[np.ndarray, np.ndarray]:
    """(triangle, sample) pairs whose sample lies in the triangle's plan box widened by
    ``reach``: the samples sorted along the axis they spread most along, each box's run of
    them found by bisection, then kept by the other axis."""
    along, other = (px, py) if np.ptp(px) >= np.ptp(py) else (py, px)
    (a0, a1), (o0, o1) = ((x.min(axis=1), x.max(axis=1)), (y.min(axis=1), y.max(axis=1))) \
        if along is px else ((y.min(axis=1), y.max(axis=1)), (x.min(axis=1), x.max(axis=1)))
    order = np.argsort(along, kind="stable")
    key = along[order]
    first = np.searchsorted(key, a0 - reach, side="left")
    count = np.searchsorted(key, a1 + reach, side="right") - first
    k = np.repeat(np.arange(x.shape[0]), count)
    starts = np.cumsum(count) - count
    p = order[first[k] + np.arange(k.size) - starts[k]]
    keep = (other[p] >= o0[k] - reach) & (other[p] <= o1[k] + reach)
    return k[keep], p[keep]


def _pairs(x, y, z0, gx, gy, px, py, sigma):
    """Each pair's integral of height times density over its triangle, and its weight (the
    samples near the triangle: within REACH sigmas of an edge)."""
    ax = (x - px[:, None]) / sigma  # the corners about the sample, in sigmas
    ay = (y - py[:, None]) / sigma
    edges = []
    for i, j in ((0, 1), (1, 2), (2, 0)):
        ex, ey = ax[:, j] - ax[:, i], ay[:, j] - ay[:, i]
        length = np.hypot(ex, ey)
        ex, ey = ex / length, ey / length
        # signed distance of the sample from the edge's line, > 0 inside (counter-clockwise)
        d = (ax[:, i] * ay[:, j] - ay[:, i] * ax[:, j]) / length
        edges.append((ex, ey, d, ax[:, i] * ex + ay[:, i] * ey, ax[:, j] * ex + ay[:, j] * ey))
    zc = z0 + gx * (px - x[:, 0]) + gy * (py - y[:, 0])
    sx, sy, mass = np.zeros(px.size), np.zeros(px.size), np.zeros(px.size)
    for ex, ey, d, ta, tb in edges:
        h = np.abs(d)
        mass += np.sign(d) * (_right(h, tb) - _right(h, ta))
        line = np.exp(-0.5 * d * d) / math.sqrt(2.0 * math.pi) * (ndtr(tb) - ndtr(ta))
        sx -= ey * line  # the outward normal is (ey, -ex)
        sy += ex * line
    return zc * mass + sigma * (gx * sx + gy * sy), mass


def _right(h: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Standard normal weight of the right triangle (0, 0), (h, 0), (h, t) (h >= 0), signed
    as t: the wedge's angle over 2 pi less what lies beyond the leg x = h (Owen's T)."""
    out = np.zeros(t.shape)
    ok = h > 0.0
    out[ok] = np.arctan2(t[ok], h[ok]) / (2.0 * math.pi) - owens_t(h[ok], t[ok] / h[ok])
    return out


def _fine(vertices, triangles, px: float, py: float, sigma: float) -> tuple[float, float]:
    """One sample's blur as `gaussian_blur` gives it, summed on a grid of step `FINE` sigma
    turned by `FINE_TURN` about the sample (the spot is round): a wall along the grid's
    lines had been read in steps of a node row, up to 5e-3 of its height off."""
    n = int(math.ceil(REACH / FINE))
    offsets = (np.arange(-n, n + 1) + 0.5) * FINE * sigma
    g = np.exp(-0.5 * (offsets / sigma) ** 2)
    w = np.outer(g, g) / np.sum(g) ** 2
    x, y = vertices[triangles, 0], vertices[triangles, 1]
    reach = np.hypot(offsets[0], offsets[0])
    near = ((x.min(axis=1) <= px + reach) & (x.max(axis=1) >= px - reach)
            & (y.min(axis=1) <= py + reach) & (y.max(axis=1) >= py - reach))
    used = np.unique(triangles[near])
    c, s = math.cos(FINE_TURN), math.sin(FINE_TURN)
    dx, dy = vertices[used, 0] - px, vertices[used, 1] - py
    turned = np.column_stack([c * dx + s * dy, c * dy - s * dx, vertices[used, 2]])
    index = np.searchsorted(used, triangles[near])
    z = grid_heights((turned, index), offsets, offsets)
    seen = np.isfinite(z)
    return float(np.sum(np.where(seen, z, 0.0) * w)), float(np.sum(w[seen]))
