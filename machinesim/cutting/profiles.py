"""Groove profiles and their lower envelopes, the 1-D half of the height-field cutter.

A tool translated in a straight line across a block removes an extrusion of its profile: the
lower boundary of its shadow on the plane across the travel, which for a convex tool is the
lower convex hull of its vertices projected along the travel (`lower_hull`). Grooves that
share a direction leave the lower envelope of their profiles (`envelope`), a piecewise linear
function of the coordinate across them, computed exactly: every breakpoint is a profile
corner or the crossing of two segments. `machinesim.cutting.relief` builds these;
`machinesim.cutting.relief_mesh` meshes the surface they leave.
"""

from __future__ import annotations

import numpy as np


def lower_hull(u: np.ndarray, z: np.ndarray) -> np.ndarray:
    """Lower convex hull of points (u, z), shape (h, 2), by increasing u (monotone chain).

    Points on a vertical end edge reduce to the lowest one; collinear points are dropped.
    """
    order = np.lexsort((z, u))
    hull: list[tuple[float, float]] = []
    for k in order:
        p = (float(u[k]), float(z[k]))
        if hull and hull[-1][0] == p[0]:
            continue  # same u, higher (sorted by z): not on the lower hull
        while len(hull) >= 2:
            (ax, az), (bx, bz) = hull[-2], hull[-1]
            if (bx - ax) * (p[1] - az) - (bz - az) * (p[0] - ax) <= 0.0:
                hull.pop()
            else:
                break
        hull.append(p)
    return np.array(hull, dtype=np.float64).reshape(-1, 2)


def clip_to_top(u0, z0, u1, z1, top):
    """Segments cut to their part at or below ``top`` (those wholly at or above it dropped)."""
    keep = (z0 < top) | (z1 < top)
    u0, z0, u1, z1 = u0[keep], z0[keep], u1[keep], z1[keep]
    with np.errstate(divide="ignore", invalid="ignore"):
        cross = u0 + (top - z0) / (z1 - z0) * (u1 - u0)
    high0, high1 = z0 > top, z1 > top
    u0, z0 = np.where(high0, cross, u0), np.where(high0, top, z0)
    u1, z1 = np.where(high1, cross, u1), np.where(high1, top, z1)
    return u0, z0, u1, z1


#: Most entries of the table of segment pairs `envelope` compares at once (per interval
#: between segment ends, every pair of the segments over it): 4e6 float64 (32 MB) per array.
#: Beyond it the segments are split between whole chains and the two halves' envelopes
#: merged, so that a raster of thousands of overlapping passes (each point under hundreds
#: of profiles: 31 GB in one table for 25,000 passes of a 1 mm ball at 0.4 um) costs
#: N log N, not N times the overlap squared.
MOST_PAIRS = 4_000_000


def envelope(u0, z0, u1, z1, lo: float, hi: float, top: float, *, split: bool = True):
    """Lower envelope of segments and the line z = top over [lo, hi], exactly.

    The segments must form chains, listed one after the other, that start and end at or
    above ``top`` (groove profiles, or an earlier envelope): their minimum is then
    continuous, and every corner of it is a segment end or the crossing of two segments
    within one interval between ends.

    Parameters
    ----------
    u0, z0, u1, z1 : ndarray
        Segments from (u0, z0) to (u1, z1), u0 < u1 (m).
    lo, hi : float
        The domain (m).
    top : float
        The uncut height (m).
    split : bool
        Split the segments between chains when their table of pairs would pass
        `MOST_PAIRS` (default); False builds the one table whatever its size.

    Returns
    -------
    u, z : ndarray
        Breakpoints, strictly increasing u from lo to hi, and the envelope there; a point
        is kept only where the envelope changes line.
    """
    u0, z0, u1, z1 = (np.asarray(a, dtype=np.float64) for a in (u0, z0, u1, z1))
    u0, z0, u1, z1 = clip_to_top(u0, z0, u1, z1, top)
    keep = (u1 > lo) & (u0 < hi) & (u1 > u0)
    u0, z0, u1, z1 = u0[keep], z0[keep], u1[keep], z1[keep]
    ends = np.concatenate([u0, u1])
    xs = np.unique(np.concatenate([[lo, hi], ends[(ends > lo) & (ends < hi)]]))
    n = len(xs) - 1
    if len(u0) == 0:
        return np.array([lo, hi]), np.array([top, top])
    first = np.clip(np.searchsorted(xs, u0, side="right") - 1, 0, n - 1)
    last = np.clip(np.searchsorted(xs, u1, side="left"), 1, n)
    over = np.cumsum(np.bincount(first, minlength=n + 1) - np.bincount(last, minlength=n + 1))
    width = int(over[:n].max()) + 1
    if split and n * width * (width - 1) // 2 > MOST_PAIRS:
        middle = _chain_break_near_middle(u0, z0, u1, z1, lo, hi, top)
        if middle is not None:
            halves = [envelope(u0[part], z0[part], u1[part], z1[part], lo, hi, top)
                      for part in (slice(None, middle), slice(middle, None))]
            pieces = [segments_of(u, z) for u, z in halves]
            # two functions of u: at most two segments and the top over any interval
            return envelope(*(np.concatenate([p[i] for p in pieces]) for i in range(4)),
                            lo, hi, top, split=False)
    return _envelope(u0, z0, u1, z1, xs, first, last, width, top)


def _chain_break_near_middle(u0, z0, u1, z1, lo, hi, top) -> int | None:
    """The index nearest the middle where one chain of segments ends and the next begins:
    a segment that does not start where the one before it ended, the one before ending at
    the top (or past the domain) and this one starting there. The chains on either side
    then have continuous envelopes of their own. None when there is no such index (one
    chain, or chains not listed one after the other)."""
    breaks = np.flatnonzero(((u0[1:] != u1[:-1]) | (z0[1:] != z1[:-1]))
                            & ((z1[:-1] >= top) | (u1[:-1] >= hi))
                            & ((z0[1:] >= top) | (u0[1:] <= lo))) + 1
    if not len(breaks):
        return None
    return int(breaks[np.argmin(np.abs(breaks - len(u0) / 2))])


def _envelope(u0, z0, u1, z1, xs, first, last, width: int, top: float):
    """`envelope` in one table: every pair of segments over each interval of ``xs``."""
    n = len(xs) - 1
    lo, hi = xs[0], xs[-1]
    slope = (z1 - z0) / (u1 - u0)
    count = last - first
    segment = np.repeat(np.arange(len(u0)), count)
    offsets = np.cumsum(count) - count
    interval = first[segment] + np.arange(len(segment)) - offsets[segment]
    order = np.argsort(interval, kind="stable")
    interval, segment = interval[order], segment[order]
    per = np.bincount(interval, minlength=n)
    slot = np.arange(len(interval)) - (np.cumsum(per) - per)[interval]
    # Column `width - 1` stays -1: the top, last so that a segment at the top wins ties.
    table = np.full((n, width), -1, dtype=np.int64)
    table[interval, slot] = segment

    def values(at: np.ndarray, rows: np.ndarray) -> np.ndarray:
        ids = table[rows]
        valid = ids >= 0
        safe = np.where(valid, ids, 0)
        line = z0[safe] + slope[safe] * (at[:, None] - u0[safe])
        line = np.where(valid, line, np.inf)
        line[:, -1] = top
        return line

    rows = np.arange(n)
    va, vb = values(xs[:-1], rows), values(xs[1:], rows)
    found = [xs]
    p, q = np.triu_indices(width, k=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        da, db = va[:, p] - va[:, q], vb[:, p] - vb[:, q]
        crossing = ((da < 0.0) & (db > 0.0)) | ((da > 0.0) & (db < 0.0))
        where = np.nonzero(crossing)
        a, b = xs[:-1][where[0]], xs[1:][where[0]]
        found.append(a + (b - a) * (da[where] / (da[where] - db[where])))
    points = np.unique(np.concatenate(found))
    points = points[(points >= lo) & (points <= hi)]
    home = np.clip(np.searchsorted(xs, points, side="right") - 1, 0, n - 1)
    z = values(points, home).min(axis=1)
    middle = (points[:-1] + points[1:]) / 2.0
    in_mid = np.clip(np.searchsorted(xs, middle, side="right") - 1, 0, n - 1)
    column = values(middle, in_mid).argmin(axis=1)
    line = table[in_mid, column]
    keep = np.ones(len(points), dtype=bool)
    keep[1:-1] = line[:-1] != line[1:]
    return points[keep], z[keep]


def segments_of(relief_u: np.ndarray, relief_z: np.ndarray):
    """The segments (u0, z0, u1, z1) between consecutive breakpoints of an envelope."""
    return relief_u[:-1], relief_z[:-1], relief_u[1:], relief_z[1:]


__all__ = ["clip_to_top", "envelope", "lower_hull", "segments_of"]
