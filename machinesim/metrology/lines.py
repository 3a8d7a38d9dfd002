"""Straight lines in the xy plane: groove centre lines and their crossing, parallel edges.

A groove's centre line is fitted (total least squares) to its centres measured in several
profiles across it; two such lines give the point where the grooves cross (seed 002, Fig. 7;
seed 003). An edge of a face is found where profiles cross a height level between the face
and its surroundings; two parallel edges give a distance across the face (seed 002, Fig. 12a).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from machinesim.exceptions import InputError
from machinesim.metrology._arrays import (
    as_floats,
    as_number,
    frozen,
    map_arrays,
    profile_arrays,
    shown,
)
from machinesim.metrology._mesh import as_vector

__all__ = [
    "GrooveCrossing",
    "Line2D",
    "ParallelEdges",
    "edge_distance",
    "fit_line",
    "fit_parallel_edges",
    "fit_parallel_lines",
    "groove_crossing",
    "intersect_lines",
    "profile_points",
    "step_positions",
]

#: Two lines whose directions' cross product (the sine of their angle) is below this are
#: parallel: their intersection would move by more than 1e12 times any error in the lines.
PARALLEL_SINE = 1e-12


@dataclass(frozen=True, eq=False)
class Line2D:
    """A straight line in the xy plane (m).

    Attributes
    ----------
    point : ndarray, shape (2,)
        A point on the line (the centroid of the points it was fitted to).
    direction : ndarray, shape (2,)
        Unit direction, pointing from the first fitted point towards the last.
    residual_rms : float
        RMS perpendicular distance of the fitted points from the line (m).
    """

    point: np.ndarray
    direction: np.ndarray
    residual_rms: float


@dataclass(frozen=True, eq=False)
class GrooveCrossing:
    """Intersection of two groove centre lines.

    Attributes
    ----------
    point : ndarray, shape (2,)
        (x, y) of the intersection, m.
    angle : float
        Angle between the two lines, rad, in [0, pi/2].
    first, second : Line2D
        The fitted centre lines.
    """

    point: np.ndarray
    angle: float
    first: Line2D
    second: Line2D


@dataclass(frozen=True, eq=False)
class ParallelEdges:
    """Two parallel edges fitted to the step positions of a height map (m).

    Attributes
    ----------
    distance : float
        Distance between the two lines of the common direction.
    first, second : Line2D
        The edges with their common direction; ``first`` is the one met first along each
        scanned row (or column).
    parallelism : float
        Angle between the two edges fitted separately (rad): how far from parallel they are.
    """

    distance: float
    first: Line2D
    second: Line2D
    parallelism: float


def profile_points(start, end, s) -> np.ndarray:
    """(x, y) of positions s along a profile from ``start`` to ``end`` (as `profile` samples).

    Parameters
    ----------
    start, end : array-like, shape (2,)
        End points of the profile line, m.
    s : array-like, shape (k,)
        Distances from ``start``, m.

    Returns
    -------
    ndarray, shape (k, 2)
    """
    start = as_vector(start, 2, "start")
    direction = as_vector(end, 2, "end") - start
    length = float(np.hypot(*direction))
    if length == 0.0:
        raise InputError(f"Expected a profile of non-zero length, got start = end = {start}")
    s = as_floats(s, "s").reshape(-1)
    return start + s[:, None] * (direction / length)


def fit_line(points) -> Line2D:
    """Total-least-squares line through points in the plane.

    Parameters
    ----------
    points : array-like, shape (k, 2)
        Points, m, k >= 2, not all equal.
    """
    points = _points(points, "points")
    centroid = points.mean(axis=0)
    centred = points - centroid
    _, singular, vt = np.linalg.svd(centred, full_matrices=False)
    if singular[0] == 0.0:
        raise InputError("Expected points that span a line, got all points equal")
    direction = vt[0]
    if direction @ (points[-1] - points[0]) < 0.0:
        direction = -direction
    rms = float(singular[1] / math.sqrt(points.shape[0])) if singular.size > 1 else 0.0
    return Line2D(frozen(centroid), frozen(direction), rms)


def intersect_lines(first: Line2D, second: Line2D) -> np.ndarray:
    """Intersection (x, y) of two lines in the plane, m; InputError when they are parallel."""
    for name, line in (("first", first), ("second", second)):
        if not isinstance(line, Line2D):
            raise InputError(f"Expected {name} as a Line2D (from fit_line), got "
                             f"{shown(line)}", key=name)
    d1, d2 = first.direction, second.direction
    cross = d1[0] * d2[1] - d1[1] * d2[0]
    if abs(cross) < PARALLEL_SINE:
        raise InputError(f"Expected two crossing lines, got directions {d1} and {d2} "
                         f"(sine of their angle {cross:.3g})")
    gap = second.point - first.point
    t = (gap[0] * d2[1] - gap[1] * d2[0]) / cross
    return frozen(first.point + t * d1)


def groove_crossing(centres_first, centres_second) -> GrooveCrossing:
    """Where two grooves cross, from centres measured in several profiles along each.

    Parameters
    ----------
    centres_first, centres_second : array-like, shape (k, 2)
        (x, y) of each groove's centre in k >= 2 profiles across it, m (from a groove's
        ``centre`` through `profile_points`).
    """
    first = fit_line(centres_first)
    second = fit_line(centres_second)
    point = intersect_lines(first, second)
    return GrooveCrossing(point, _angle(first.direction, second.direction), first, second)


def step_positions(s, z, level: float | None = None) -> np.ndarray:
    """Where a profile crosses a height level (linear interpolation between samples).

    A step's position is taken where the profile crosses the level between its two heights
    (default: halfway between the lowest and the highest sample). On a sloped wall sampled
    on both sides this is exact; a vertical wall lies between two samples, so its position is
    known to a sample spacing, and to a few percent of it when the wall sits midway.

    A crossing passes from below the level to above it or back. Samples exactly at the level
    take no side: the profile crosses where it goes from a sample below to the next one
    above (or back) with only samples at the level between, at the middle of those (at the
    one such sample; between the two samples, interpolated, when there is none). A profile
    that touches the level and turns back, a peak from below or a valley from above (or a
    flat at the level's height), does not cross it, nor does one that starts or ends at it:
    both count no crossing, the same read upside down or backwards.

    Parameters
    ----------
    s : array-like, shape (k,)
        Positions, m, strictly increasing.
    z : array-like, shape (k,)
        Heights, m; NaN samples are left out.
    level : float, optional
        The height (m) whose crossings are the steps.

    Returns
    -------
    ndarray, shape (c,), read-only
        The crossings in order of s.
    """
    s, z = profile_arrays(s, z, 2)
    if level is None:
        level = 0.5 * (float(z.min()) + float(z.max()))
    else:
        level = as_number(level, "level")
    d = z - level
    off = np.flatnonzero(d != 0.0)  # the samples on a side
    i, j = off[:-1], off[1:]
    change = np.sign(d[i]) != np.sign(d[j])
    i, j = i[change], j[change]
    # next neighbours: the interpolated crossing; else the middle of the samples at the level
    fraction = d[i] / (d[i] - d[j])
    next_to = j == i + 1
    return frozen(np.where(next_to, s[i] + fraction * (s[j] - s[i]),
                           0.5 * (s[np.minimum(i + 1, j)] + s[np.maximum(j - 1, i)])))


def edge_distance(s, z, level: float | None = None) -> float:
    """Distance (m) between the two steps of a profile across a plateau or a slot."""
    steps = step_positions(s, z, level)
    if steps.size != 2:
        raise InputError(f"Expected a profile crossing the level twice, got {steps.size} "
                         f"crossings at {steps.tolist()} m")
    return float(steps[1] - steps[0])


def fit_parallel_edges(x, y, z, *, level: float | None = None, along: str = "x") -> ParallelEdges:
    """Two parallel edges of a height map and their distance (seed 002, Fig. 12a).

    Each row (``along="x"``) or column (``along="y"``) that crosses ``level`` must cross it
    exactly twice: crop the map to the stretch of the two edges. The first crossings of all
    rows make one edge, the second ones the other; the two lines are fitted with one common
    direction (least squares on both centred point sets) and their distance is measured
    across it.

    Parameters
    ----------
    x : array-like, shape (nx,)
    y : array-like, shape (ny,)
    z : array-like, shape (ny, nx)
        The height map, m, NaN where not seen.
    level : float, optional
        Step height (m); default halfway between the map's lowest and highest sample.
    along : {"x", "y"}
        Direction of the scanned lines; choose the one that crosses the edges more steeply.
    """
    x, y, z = map_arrays(x, y, z)
    if along not in ("x", "y"):
        raise InputError(f"Expected along 'x' or 'y', got {along!r}", key="along")
    if not np.isfinite(z).any():  # nanmin would warn and the level be NaN
        raise InputError(f"Expected a map with measured heights, got all {z.size} samples "
                         "NaN (off the part)", key="z")
    if level is None:
        level = 0.5 * (float(np.nanmin(z)) + float(np.nanmax(z)))
    else:
        level = as_number(level, "level")
    scan, across, heights = (x, y, z) if along == "x" else (y, x, z.T)
    pairs = []
    for position, row in zip(across, heights, strict=True):
        if np.count_nonzero(~np.isnan(row)) < 2:
            continue
        steps = step_positions(scan, row, level)
        if steps.size == 2:
            pairs.append((steps[0], steps[1], position))
        elif steps.size:
            raise InputError(f"Expected two crossings of level {level:.9g} m in the line at "
                             f"{'y' if along == 'x' else 'x'} = {position:.9g} m, got "
                             f"{steps.size}: crop the map to the two edges")
    if len(pairs) < 2:
        raise InputError(f"Expected at least two lines crossing both edges, got {len(pairs)}")
    pairs = np.array(pairs)
    first, second = (pairs[:, [0, 2]], pairs[:, [1, 2]]) if along == "x" else (
        pairs[:, [2, 0]], pairs[:, [2, 1]])
    one, two = fit_parallel_lines(first, second)
    normal = np.array([-one.direction[1], one.direction[0]])
    return ParallelEdges(
        distance=abs(float(normal @ (two.point - one.point))), first=one, second=two,
        parallelism=_angle(fit_line(first).direction, fit_line(second).direction))


def fit_parallel_lines(first, second) -> tuple[Line2D, Line2D]:
    """Two lines of one common direction fitted to two sets of points (m).

    The common direction is the principal axis of both sets, each centred on its centroid
    (total least squares); each line passes through its set's centroid. Their distance and
    the offset between them are then free of any turn or shift of the frame the points were
    read in.

    Parameters
    ----------
    first, second : array_like, shape (k, 2)
        At least two points each.

    Returns
    -------
    (Line2D, Line2D)
        Both with the common direction, pointing from ``first``'s first point towards its
        last; ``residual_rms`` is that of both sets about their lines.
    """
    sets = [_points(points, name) for points, name in ((first, "first"), (second, "second"))]
    centroids = [points.mean(axis=0) for points in sets]
    stacked = np.vstack([points - c for points, c in zip(sets, centroids, strict=True)])
    _, singular, vt = np.linalg.svd(stacked, full_matrices=False)
    direction = vt[0] if vt[0] @ (sets[0][-1] - sets[0][0]) >= 0.0 else -vt[0]
    if singular[0] == 0.0:
        raise InputError("Expected points that span two lines, got each set's points equal")
    rms = float(singular[1] / math.sqrt(len(stacked)))
    return tuple(Line2D(frozen(c), frozen(direction), rms) for c in centroids)


def _points(points, what: str) -> np.ndarray:
    """``points`` as a finite (k, 2) float64 array, k >= 2."""
    points = as_floats(points, what)
    if points.ndim != 2 or points.shape[1] != 2 or points.shape[0] < 2:
        raise InputError(f"Expected {what} with shape (k, 2), k >= 2, got {points.shape}",
                         key=what)
    if not np.isfinite(points).all():
        raise InputError(f"Expected finite {what}, got NaN or infinity", key=what)
    return points


def _angle(first: np.ndarray, second: np.ndarray) -> float:
    """Angle between two unit directions taken as undirected lines, rad, in [0, pi/2]."""
    sine = abs(float(first[0] * second[1] - first[1] * second[0]))
    return math.atan2(sine, abs(float(first @ second)))
