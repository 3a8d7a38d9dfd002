"""A planar profile tilted between a sweep's poses, split where it tilts across itself.

A turning sweep is cut as the convex hull of the tool at its two poses (`SweepSet.hulls`).
For a point, that hull's chord stays within the chord tolerance of the point's arc, second
order in the turn (`machinesim.motion.chords`). A planar profile (V, round nose) whose plane
tilts about a line across it is worse: the points on one side of that line move one way
along the plane's normal, those on the other side the other way, and the hull joins the one
side at the first pose to the other at the second, filling the waist of the bow-tie the
profile truly sweeps. Across the line, with f the displacement along the mean normal of
the two poses (affine over the profile, zero on the line) reaching -A d on one side and
B d on the other for a tilt d, the hull's chord passes ``A B / (A + B) * d`` beyond the
line's true sweep, up to ``W d / 4`` for a profile W across the tilt: first order in d.
Measured before this: a v:90 spun 90 deg about its own axis on robonano_ui (A), 50 um deep,
at the default 1 nm chord (1,933 sweeps, each d = 0.047 deg), cut 28.8 nm into the wedges
the blade never swept, whose edge is the tool's axis: w sin(d / 2) / sin 45 deg = 28.7 nm
by hand, w = 50 um the blade's half-width at the top of the stock.

Each half of the profile, on one side of the line, moves to one side only: the hull of a
half at the two poses is its true sweep to second order (its chords, as a point's). So where
the line crosses the part of the profile below the clip plane and the hull would leave the
sweep by more than `SPLIT_M`, the sweep is cut as the union of its two halves' hulls
(`halves`); a profile whose tilt does not cross it (a B swing about the tool's edge point,
every shipped cut) keeps its one hull.
"""

from __future__ import annotations

import numpy as np

from machinesim.tolerances import TWIST_M

__all__ = ["SPLIT_M", "clip_halfspace", "crossing", "halves", "split_sweeps"]

#: A turning profile sweep is split when its hull would leave the true sweep by more than
#: this at the line its tilt crosses (m): `TWIST_M`, 1/100 of the finest chord tolerance,
#: which already stands for a tool turning continuously (`machinesim.tolerances`).
SPLIT_M = TWIST_M


def clip_halfspace(polygon: np.ndarray, normal: np.ndarray, offset: float) -> np.ndarray:
    """The part of a convex polygon (k, 3) where ``normal . p <= offset``, in order
    (Sutherland-Hodgman); fewer than 3 points where it at most touches the half-space."""
    side = polygon @ normal - offset
    inside = side <= 0.0
    if inside.all():
        return polygon
    if not inside.any():
        return polygon[:0]
    following = np.roll(polygon, -1, axis=0)
    after = np.roll(side, -1)
    crossing = inside != np.roll(inside, -1)
    with np.errstate(divide="ignore", invalid="ignore"):  # only crossing edges are read
        t = side / (side - after)
        cut = polygon + t[:, None] * (following - polygon)
    points = np.stack([polygon, cut], axis=1).reshape(-1, 3)
    return points[np.stack([inside, crossing], axis=1).ravel()]


def crossing(p0: np.ndarray, p1: np.ndarray, x0: np.ndarray, x1: np.ndarray) -> np.ndarray:
    """Whether the tilt of each sweep may cross its profile: the displacement of the
    profile's vertices along the mean of the profile normals ``x0``, ``x1`` (n, 3) between
    the poses ``p0``, ``p1`` (n, k, 3) takes both signs beyond `SPLIT_M` (a quick test:
    `halves` decides on the part below the clip plane)."""
    f = np.einsum("nki,ni->nk", p1 - p0, x0 + x1)
    return (f.min(axis=1) < -SPLIT_M) & (f.max(axis=1) > SPLIT_M)


def halves(profile: np.ndarray, r0: np.ndarray, o0: np.ndarray, r1: np.ndarray,
           o1: np.ndarray, level: float) -> list[np.ndarray | None] | None:
    """The point sets whose hulls are the sweep of a planar ``profile`` (k, 3) (tool frame,
    in the plane x = 0, in order round it) from pose (``r0``, ``o0``) to (``r1``, ``o1``)
    (rotations (3, 3), origins (3,)), split across the line where its tilt crosses it, each
    pose's part cut to z <= ``level`` first; None when the hull of the whole profile leaves
    that line's sweep by no more than `SPLIT_M` there (no split). A half wholly above
    ``level`` is None in the list."""
    normal = r0[:, 0] + r1[:, 0]
    # displacement along the mean normal, affine in the tool frame: f(p) = g . p + c
    g = (r1 - r0).T @ normal
    c = float(normal @ (o1 - o0))
    scale = 1.0 / np.linalg.norm(normal)
    below = [(r0[2], level - o0[2]), (r1[2], level - o1[2])]
    f = np.concatenate([clip_halfspace(profile, a, b) @ g for a, b in below]) + c
    low, high = float(f.min(initial=0.0)) * scale, float(f.max(initial=0.0)) * scale
    if not (low < 0.0 < high and -low * high / (high - low) > SPLIT_M):
        return None
    out = []
    for sign in (1.0, -1.0):
        half = clip_halfspace(profile, sign * g, -sign * c)
        parts = [clip_halfspace(half, a, b) for a, b in below]
        points = [part @ r.T + o for part, r, o in zip(parts, (r0, r1), (o0, o1), strict=True)
                  if len(part)]
        out.append(np.concatenate(points) if points else None)
    return out


def split_sweeps(profile: np.ndarray, rows: np.ndarray, p0: np.ndarray, p1: np.ndarray,
                 r0: np.ndarray, r1: np.ndarray, o0: np.ndarray, o1: np.ndarray,
                 levels: np.ndarray) -> dict[int, list[np.ndarray | None]]:
    """`halves` of the turning sweeps ``rows`` whose tilt crosses their profile, by row.

    ``p0``, ``p1`` (n, k, 3): the profile's vertices at each sweep's poses; ``r0``, ``r1``
    (n, 3, 3) and ``o0``, ``o1`` (n, 3): the poses; ``levels`` (n,): each sweep's clip
    height (m). Rows index all of these."""
    tilted = rows[crossing(p0[rows], p1[rows], r0[rows, :, 0], r1[rows, :, 0])]
    out = {}
    for row in tilted.tolist():
        pieces = halves(profile, r0[row], o0[row], r1[row], o1[row], float(levels[row]))
        if pieces is not None:
            out[row] = pieces
    return out
