"""Sweeps that lie inside another sweep of the same cut (`contained_sweeps`): they remove
nothing more, and the boolean engine (`machinesim.cutting.engine`) drops them before it
unites and subtracts the rest.
"""

from __future__ import annotations

import manifold3d
import numpy as np

__all__ = ["CONTAINED_REL", "contained_sweeps", "vertices_and_planes"]

#: A sweep lies inside another when none of its vertices is farther than this fraction of
#: the stock's scale outside any face plane of the other (`contained_sweeps`): 1e-15 m on a
#: 0.1 m part, 100 times below manifold3d's own tolerance for a sweep (`sweeps`,
#: SOLID_TOLERANCE_REL 1e-12) and far above the round-off of a vertex that lies on the
#: other's face (measured: at most 6e-17 m for the repeated passes of a helix or a pocket).
CONTAINED_REL = 1e-14
#: Tile members compared pairwise at once by their boxes in `contained_sweeps`.
CONTAINED_BLOCK = 512
#: Most sweeps a sweep is tested against for containment, among those whose boxes hold its
#: box: half the largest (the deepest of passes repeated down, which are kept), half those
#: of the tightest boxes (a long move's box holds the boxes of many short moves it does not
#: contain: testing them all would cost the square of their count).
CONTAINED_CANDIDATES = 8
#: Vertices of a sweep tested first against a candidate's planes, spread along its vertex
#: list: one outside rejects the candidate without testing them all.
CONTAINED_PROBE = 32


def vertices_and_planes(solid: manifold3d.Manifold):
    """A convex solid's vertices (n, 3) and its faces' unit normals (t, 3) and offsets (t,)."""
    mesh = solid.to_mesh64()
    vertices = np.asarray(mesh.vert_properties)[:, :3]
    triangles = np.asarray(mesh.tri_verts, dtype=np.int64)
    a, b, c = (vertices[triangles[:, i]] for i in range(3))
    normal = np.cross(b - a, c - a)
    length = np.linalg.norm(normal, axis=1)
    flat = length > 0.0
    normal = normal[flat] / length[flat, None]
    return vertices, normal, np.einsum("ij,ij->i", normal, a[flat])


def contained_sweeps(hulls, lower: np.ndarray, upper: np.ndarray, tiles,
                     tol: float) -> np.ndarray:
    """Which sweeps lie inside another sweep that is cut: they remove nothing more.

    Passes repeated over the same path at increasing depth are the common case: a helix's
    every turn but the last, a pocket's or a contour's every level but the deepest. A sweep
    of a vertical tool reaches up through the clip plane, so the deeper pass's sweep holds
    the shallower one whole, with faces in the same planes; uniting or subtracting such
    coincident faces is the slowest work manifold3d does (a helix's turns stacked in one
    union took 107 ms a run, 2/3 of a 200 s cut). Subtraction commutes and A - B - C equals
    A - C when B lies in C, so dropping them leaves the same solid (to round-off: a dropped
    sweep pokes out of its keeper by at most ``tol``).

    Sweeps are visited by decreasing box volume; one is dropped when all its vertices lie within
    ``tol`` of the inside of every face plane of an earlier kept sweep whose box holds its
    box (each sweep is convex). Only sweeps that share a tile are compared: a box that holds
    another's reaches every tile the other does.

    Returns
    -------
    ndarray of bool, shape (len(hulls),)
    """
    count = len(hulls)
    dropped = np.zeros(count, dtype=bool)
    if count < 2:
        return dropped
    # A box that holds another's is at least as large: ordering by box volume puts every
    # holder first without evaluating a solid's volume (equal boxes go by index).
    box_volume = np.prod(upper - lower, axis=1)
    order = np.argsort(-box_volume, kind="stable")
    rank = np.empty(count, dtype=np.int64)
    rank[order] = np.arange(count)
    holders: dict[int, np.ndarray] = {}
    seen = np.zeros(count, dtype=bool)
    for _, members in tiles:
        fresh = members[~seen[members]]
        seen[members] = True
        for begin in range(0, len(fresh), CONTAINED_BLOCK):
            inner = fresh[begin:begin + CONTAINED_BLOCK]
            # a holder's box holds the sweep's box, and it comes first (larger box)
            holds = (np.all(lower[None, members] <= lower[inner, None] + tol, axis=2)
                     & np.all(upper[None, members] >= upper[inner, None] - tol, axis=2)
                     & (rank[members][None, :] < rank[inner][:, None]))
            rows = np.flatnonzero(holds.any(axis=1))
            if not len(rows):
                continue
            take = min(CONTAINED_CANDIDATES // 2, len(members))
            # the largest sweeps first (the deepest of repeated passes: kept), then the
            # tightest boxes
            best = [np.argpartition(np.where(holds[rows], key[members][None, :], np.inf),
                                    take - 1, axis=1)[:, :take]
                    for key in (rank.astype(np.float64), box_volume)]
            for row, first, tight in zip(rows.tolist(), *best, strict=True):
                columns = np.concatenate([first[np.argsort(rank[members[first]])], tight])
                columns = columns[holds[row, columns]]
                holders[int(inner[row])] = members[columns[np.sort(
                    np.unique(columns, return_index=True)[1])]]
    if not holders:
        return dropped
    planes: dict[int, tuple] = {}  # of the kept sweeps that hold another's box
    for index in order.tolist():
        candidates = [j for j in holders[index].tolist() if not dropped[j]] \
            if index in holders else []
        vertices = vertices_and_planes(hulls[index])[0] if candidates else None
        probe = vertices[::max(1, len(vertices) // CONTAINED_PROBE)] if candidates else None
        for j in candidates:
            if j not in planes:
                planes[j] = vertices_and_planes(hulls[j])[1:]
            normal, offset = planes[j]
            # most candidates fail: a few vertices outside tell so at a fraction of the cost
            if float((probe @ normal.T - offset).max()) > tol:
                continue
            if float((vertices @ normal.T - offset).max()) <= tol:
                dropped[index] = True
                break
    return dropped
