"""Touch-probe contact: a ball swept along a straight line against a part's triangles, exactly.

A triangle is the union of its face, its three edges and its three vertices, so the ball of
radius r first touches it when its centre, moving along c + t d, first reaches distance r from
one of them: the face's plane offset by r (the contact point inside the face), an edge's
capsule (an infinite cylinder of radius r about the edge line, the contact foot within the
edge) or a vertex's sphere. Each is solved in closed form in float64 (a linear equation or a
quadratic taken by its cancellation-free root) for every candidate triangle; the first
contact is the least travel over all of them. No rays, no iteration.

Candidate triangles come from the part's `MeshIndex` (build it once per part and pass it to
every call). A cheap lower bound on each candidate's travel then lets most of them go
unsolved: the most promising triangle of each ball is solved first, and only those that
could be touched before that contact are solved after it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from machinesim.exceptions import InputError
from machinesim.metrology._mesh import as_positive, as_vector
from machinesim.metrology.meshindex import MeshIndex, candidates
from machinesim.tolerances import SWEEP_PAD

__all__ = ["Contact", "Contacts", "touch", "touch_many"]

#: Probes queried together: bounds the (probe, box) pair arrays of one pass.
PROBE_BLOCK = 256
#: Below this many (ball, triangle) pairs in a block, all are solved in one pass: a second
#: pass costs more numpy call overhead (~0.3 ms) than the pairs it would skip.
ONE_PASS_PAIRS = 256


@dataclass(frozen=True, eq=False)
class Contact:
    """First contact of a swept ball with a part.

    Attributes
    ----------
    travel : float
        Distance the ball centre moved along the direction until contact, m.
    point : ndarray, shape (3,)
        Contact point on the part's surface, m.
    centre : ndarray, shape (3,)
        Ball centre at contact, m.
    normal : ndarray, shape (3,)
        Unit vector from the contact point to the ball centre (the surface normal the ball
        sees there).
    """

    travel: float
    point: np.ndarray
    centre: np.ndarray
    normal: np.ndarray


@dataclass(frozen=True, eq=False)
class Contacts:
    """First contacts of K swept balls; NaN rows where a ball touched nothing.

    Attributes
    ----------
    travel : ndarray, shape (K,)
        Distance moved until contact, m; NaN when nothing is touched within the travel.
    point, centre, normal : ndarray, shape (K, 3)
        As in `Contact`, NaN where nothing is touched.
    """

    travel: np.ndarray
    point: np.ndarray
    centre: np.ndarray
    normal: np.ndarray

    @property
    def touched(self) -> np.ndarray:
        """Shape (K,) bool: which balls touched the part within their travel."""
        return ~np.isnan(self.travel)


def touch(surface, centre, direction, radius: float, max_travel: float) -> Contact | None:
    """Move a ball from ``centre`` along ``direction`` until it first touches the part.

    Parameters
    ----------
    surface : MeshIndex or Part or tuple of (array-like, array-like)
        The part. Pass a `MeshIndex` when touching the same part more than once: building
        the index is most of the cost of a single touch.
    centre : array-like, shape (3,)
        Ball centre at the start, workpiece frame, m. The ball must not overlap the part.
    direction : array-like, shape (3,)
        Direction of motion (normalised here; must be non-zero).
    radius : float
        Ball radius, m, > 0.
    max_travel : float
        Longest travel to search, m, > 0.

    Returns
    -------
    Contact or None
        The first contact, or None when the ball touches nothing within ``max_travel``.

    Raises
    ------
    InputError
        For bad arguments, or a ball that already overlaps the part at ``centre``.
    """
    contacts = touch_many(
        surface,
        as_vector(centre, 3, "centre")[None],
        as_vector(direction, 3, "direction")[None],
        radius,
        max_travel,
    )
    if not contacts.touched[0]:
        return None
    return Contact(
        float(contacts.travel[0]), contacts.point[0], contacts.centre[0], contacts.normal[0]
    )


def touch_many(surface, centres, directions, radius: float, max_travel) -> Contacts:
    """`touch` for K balls of one radius at once.

    Parameters
    ----------
    surface : MeshIndex or Part or tuple of (array-like, array-like)
        The part.
    centres : array-like, shape (K, 3)
        Ball centres at the start, m.
    directions : array-like, shape (K, 3)
        Directions of motion, each non-zero (normalised here).
    radius : float
        Ball radius, m, > 0.
    max_travel : float or array-like, shape (K,)
        Longest travel to search per ball, m, > 0.

    Returns
    -------
    Contacts
        First contact per ball, NaN rows for balls that touch nothing.

    Raises
    ------
    InputError
        For bad arguments, or balls that already overlap the part at their start (the
        message lists them).
    """
    index = MeshIndex.from_surface(surface)
    centres = _rows(centres, "centres")
    directions = _rows(directions, "directions")
    if directions.shape != centres.shape:
        raise InputError(
            f"Expected directions with the shape of centres {centres.shape}, "
            f"got {directions.shape}", key="directions")
    norms = np.linalg.norm(directions, axis=1)
    if np.any(norms == 0.0):
        raise InputError(f"Expected non-zero directions, got zero in rows "
                         f"{np.flatnonzero(norms == 0.0).tolist()}", key="directions")
    directions = directions / norms[:, None]
    radius = as_positive(radius, "radius")
    travel = np.broadcast_to(np.asarray(max_travel, dtype=np.float64), (len(centres),))
    if not np.all(np.isfinite(travel) & (travel > 0.0)):
        raise InputError(f"Expected max_travel > 0 (m), got {max_travel}", key="max_travel")

    k = len(centres)
    result = np.full((k, 10), np.nan)
    for begin in range(0, k, PROBE_BLOCK):
        block = slice(begin, begin + PROBE_BLOCK)
        result[block] = _touch_block(index, centres[block], directions[block], radius,
                                     travel[block], begin)
    result.setflags(write=False)
    return Contacts(result[:, 0], result[:, 1:4], result[:, 4:7], result[:, 7:10])


def _rows(values, name: str) -> np.ndarray:
    try:
        array = np.array(values, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise InputError(f"Expected {name} as numbers, got {values!r}", key=name) from error
    if array.ndim != 2 or array.shape[1] != 3:
        raise InputError(f"Expected {name} with shape (K, 3), got {array.shape}", key=name)
    if not np.isfinite(array).all():
        raise InputError(f"Expected finite {name}, got NaN or infinity", key=name)
    return array


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise dot product of (3, N) arrays."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Column-wise cross product of (3, N) arrays."""
    return np.stack([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


def _first_root(half_b: np.ndarray, c: np.ndarray, disc: np.ndarray) -> np.ndarray:
    """Smaller root of a t^2 + 2 half_b t + c = 0 (disc = half_b^2 - a c), cancellation-free.

    Valid where half_b < 0 (approaching), disc >= 0 and c >= 0 (outside at t = 0); elsewhere
    the result is meaningless and is masked by the caller.
    """
    with np.errstate(invalid="ignore", divide="ignore"):
        return c / (np.sqrt(np.maximum(disc, 0.0)) - half_b)


def _touch_block(index, centres, directions, radius, travel, first_probe) -> np.ndarray:
    """Rows (travel, point, centre, normal) for one block of probes, NaN where no contact."""
    ends = centres + travel[:, None] * directions
    pad = SWEEP_PAD * (np.abs(centres).max(axis=1) + travel + radius)
    grow = (radius + pad)[:, None]
    query = np.concatenate([np.maximum(centres, ends) + grow, grow - np.minimum(centres, ends)],
                           axis=1).T
    probe, tri = candidates(index, query, centres.T, directions.T, travel, radius + pad)
    out = np.full((len(centres), 10), np.nan)
    c, d = centres.T[:, probe], directions.T[:, probe]
    boxes, spheres = index.levels[-1]
    bound, across = _lower_bound(boxes[:, tri], spheres[:, tri], c, d, radius)
    bound -= pad[probe]
    # Two passes: the most promising triangles of each ball first (least bound, centre
    # nearest the line of motion), whose contact bounds the rest; a triangle that cannot be
    # reached before that contact is never solved. A ball overlapping a triangle at its start
    # has a bound <= 0 there, so such a triangle is never skipped.
    if probe.size <= ONE_PASS_PAIRS:
        first = bound < np.inf
    else:
        least = np.full(len(centres), np.inf)
        np.minimum.at(least, probe, bound)
        nearest = np.full(len(centres), np.inf)
        np.minimum.at(nearest, probe, across)
        first = np.zeros(probe.size, dtype=bool)
        for pick in (bound == least[probe], across == nearest[probe]):
            pick = np.flatnonzero(pick & (bound < np.inf))
            first[pick[np.unique(probe[pick], return_index=True)[1]]] = True  # one per ball
    best, point, overlap = _sweep(c[:, first], d[:, first], radius,
                                  _corners(index, tri[first]))
    limit = travel.copy()
    np.minimum.at(limit, probe[first], best)
    rest = ~first & (bound <= limit[probe])
    if rest.any():
        more = _sweep(c[:, rest], d[:, rest], radius, _corners(index, tri[rest]))
        best = np.concatenate([best, more[0]])
        point = np.concatenate([point, more[1]], axis=1)
        overlap = np.concatenate([overlap, more[2]])
    probe = np.concatenate([probe[first], probe[rest]])
    if overlap.any():
        bad = np.unique(probe[overlap]) + first_probe
        raise InputError(
            f"Expected each ball to start clear of the part, got balls {bad.tolist()[:10]} "
            f"overlapping it at their start centre (radius {radius} m)", key="centres")
    within = np.flatnonzero(best <= travel[probe])
    order = within[np.lexsort((best[within], probe[within]))]
    win = order[np.unique(probe[order], return_index=True)[1]]
    k = probe[win]
    centre = centres[k] + best[win, None] * directions[k]
    out[k, 0] = best[win]
    out[k, 1:4] = point[:, win].T
    out[k, 4:7] = centre
    out[k, 7:10] = (centre - point[:, win].T) / radius
    return out


def _corners(index: MeshIndex, tri: np.ndarray) -> np.ndarray:
    """Vertices of triangles ``tri`` as (vertex, axis, triangle), shape (3, 3, N), m."""
    return np.ascontiguousarray(index.vertices[index.triangles[tri]].transpose(1, 2, 0))


def _lower_bound(boxes, spheres, c, d, r) -> tuple[np.ndarray, np.ndarray]:
    """Travel before which a ball cannot touch a triangle, from its box and its sphere.

    The ball meets a point q no sooner than along(q) - sqrt(r^2 - across(q)^2), with along and
    across the distances of q from c along d and from the line of motion. For q in the
    triangle's sphere (centre m, radius rho), along(q) >= along(m) - rho and across(q) >=
    across(m) - rho; for q in its box, along(q) >= the least along over the box corners.

    Returns
    -------
    bound : ndarray, shape (N,)
        The lower bound, m; inf where the sphere stays farther than r from the line.
    across : ndarray, shape (N,)
        Distance of the sphere's centre from the line of motion, m.
    """
    rho = spheres[3]
    w = spheres[:3] - c
    along = _dot(w, d)
    w_across = w - along * d
    centre_across = np.sqrt(_dot(w_across, w_across))
    across = np.maximum(centre_across - rho, 0.0)
    box_along = np.minimum(boxes[:3] * d, boxes[3:] * -d).sum(axis=0) - _dot(c, d)
    with np.errstate(invalid="ignore"):
        bound = np.maximum(along - rho - np.sqrt(r * r - across * across), box_along - r)
    return np.where(across <= r, bound, np.inf), centre_across


def _sweep(c, d, r, corners):
    """First touch of balls (centre c + t d, radius r) on triangles, per pair.

    Parameters
    ----------
    c, d : ndarray, shape (3, N)
        Start centres and unit directions, m.
    r : float
        Ball radius, m.
    corners : ndarray, shape (3, 3, N)
        Triangle vertices (vertex, axis, pair), m.

    Returns
    -------
    travel : ndarray, shape (N,)
        Least t >= 0 at which the ball touches the triangle, inf if never.
    point : ndarray, shape (3, N)
        The touched point of the triangle.
    overlap : ndarray, shape (N,) bool
        The ball already overlaps the triangle at t = 0 (closer than r).
    """
    n = c.shape[1]
    # Edges and vertices are solved three at a time: start vertex p = corners[i], end
    # corners[i + 1], laid side by side in (3, 3N) arrays, vertex 0 of every pair first.
    p = np.concatenate(corners, axis=1)
    e = np.concatenate(corners[[1, 2, 0]], axis=1) - p
    c3, d3 = np.tile(c, 3), np.tile(d, 3)

    a = corners[0]
    normal = _cross(e[:, :n], -e[:, 2 * n:])
    length = np.sqrt(_dot(normal, normal))
    with np.errstate(invalid="ignore", divide="ignore"):
        normal = normal / length
        gap = _dot(c - a, normal)
        closing = _dot(d, normal)
        side = np.where(gap >= 0.0, 1.0, -1.0)
        t_face = (np.abs(gap) - r) / (-side * closing)
        foot = c + t_face * d - side * r * normal
        valid = (length > 0.0) & (side * closing < 0.0) & (np.abs(gap) >= r)
        t_face[~(valid & _inside(p, e, normal, foot))] = np.inf
        overlap = (length > 0.0) & (np.abs(gap) < r) & _inside(p, e, normal, c - gap * normal)

    ee = _dot(e, e)
    w = c3 - p
    with np.errstate(invalid="ignore", divide="ignore"):
        u0 = _dot(w, e) / ee
        w_across = w - u0 * e
        d_across = d3 - (_dot(d3, e) / ee) * e
        aa = _dot(d_across, d_across)
        half_b = _dot(w_across, d_across)
        cc = _dot(w_across, w_across) - r * r
        disc = half_b * half_b - aa * cc
        t_edge = _first_root(half_b, cc, disc)
        u = _dot(w + t_edge * d3, e) / ee
    valid = (ee > 0.0) & (half_b < 0.0) & (disc >= 0.0) & (cc >= 0.0) & (u >= 0.0) & (u <= 1.0)
    t_edge[~valid] = np.inf
    overlap |= ((ee > 0.0) & (cc < 0.0) & (u0 >= 0.0) & (u0 <= 1.0)).reshape(3, n).any(axis=0)

    half_b = _dot(w, d3)
    cc = _dot(w, w) - r * r
    disc = half_b * half_b - cc
    t_vertex = _first_root(half_b, cc, disc)
    t_vertex[~((half_b < 0.0) & (disc >= 0.0) & (cc >= 0.0))] = np.inf
    overlap |= (cc < 0.0).reshape(3, n).any(axis=0)

    travel = np.concatenate([t_face, t_edge, t_vertex]).reshape(7, n)
    points = np.concatenate([foot, p + u * e, p], axis=1).reshape(3, 7, n)
    feature = np.argmin(travel, axis=0)
    pair = np.arange(n)
    return travel[feature, pair], points[:, feature, pair], overlap


def _inside(p: np.ndarray, e: np.ndarray, normal: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Whether points q (3, N) in the triangles' planes lie in the closed triangles.

    ``p`` and ``e`` (3, 3N) are the edges' start points and vectors as `_sweep` lays them out.
    """
    n = q.shape[1]
    inner = _dot(_cross(e, np.tile(q, 3) - p), np.tile(normal, 3))
    return (inner >= 0.0).reshape(3, n).all(axis=0)
