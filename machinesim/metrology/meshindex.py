"""A part's triangles in a bounding-volume tree, for queries along a ball's path.

The triangles are put in Morton (z-curve) order of their box centres and grouped FANOUT at a time,
level over level: an implicit tree with no pointers, whose every level is a few numpy arrays,
so a query walks it for many balls at once with whole-array operations.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from machinesim.exceptions import InputError
from machinesim.metrology._mesh import mesh_arrays

__all__ = ["MeshIndex"]

#: Children per node of the box tree: the query tests whole groups at once, so wide and
#: shallow beats a binary tree in numpy.
FANOUT = 16
#: Bits per axis of the Morton code that orders the triangles (3 x 21 = 63 bits of a uint64).
_MORTON_BITS = 21


@dataclass(frozen=True, eq=False)
class MeshIndex:
    """A part's mesh with a box tree over its triangles, built once, read by every touch.

    Attributes
    ----------
    vertices : ndarray, shape (n, 3), float64, read-only
        Vertex positions in the workpiece frame, m.
    triangles : ndarray, shape (m, 3), int64, read-only
        Vertex indices, in tree (Morton) order.
    levels : tuple of (ndarray (6, k), ndarray (4, k))
        Per tree level, from the root level (at most FANOUT nodes) down to the triangles:
        boxes as rows (x_lo, y_lo, z_lo, -x_hi, -y_hi, -z_hi) and enclosing spheres as rows
        (centre x, y, z, radius), m. Node i of a level holds nodes FANOUT * i ...
        FANOUT * i + FANOUT - 1 of the next. The upper corner is stored negated so that
        "boxes meet" is one comparison, box <= query, on all six rows. A triangle's sphere is
        centred on its centroid, a node's on its box centre.
    """

    vertices: np.ndarray
    triangles: np.ndarray
    levels: tuple

    @classmethod
    def from_surface(cls, surface) -> MeshIndex:
        """Index a Part, or a ``(vertices (n, 3) float64 m, triangles (m, 3) int)`` pair."""
        if isinstance(surface, MeshIndex):
            return surface
        vertices, triangles = mesh_arrays(surface)
        vertices = vertices.copy()  # frozen below: never freeze the caller's array
        if triangles.size == 0:
            raise InputError("Expected a mesh with at least one triangle, got none")
        columns = np.ascontiguousarray(vertices.T)
        a, b, c = (columns[:, triangles[:, k]] for k in range(3))
        lo = np.minimum(np.minimum(a, b), c)
        hi = np.maximum(np.maximum(a, b), c)
        order = np.argsort(_morton(lo + hi), kind="stable")
        boxes = [np.concatenate([lo[:, order], -hi[:, order]])]
        while boxes[-1].shape[1] > FANOUT:
            groups = np.arange(0, boxes[-1].shape[1], FANOUT)
            boxes.append(np.minimum.reduceat(boxes[-1], groups, axis=1))
        triangles = triangles[order]
        a, b, c = a[:, order], b[:, order], c[:, order]
        centroid = (a + b + c) / 3.0
        reach = np.sqrt(np.maximum(np.maximum(_dot3(a - centroid, a - centroid),
                                              _dot3(b - centroid, b - centroid)),
                                   _dot3(c - centroid, c - centroid)))
        spheres = [np.vstack([centroid, reach])]
        for box in boxes[1:]:
            half = (-box[3:] - box[:3]) / 2.0
            spheres.append(np.vstack([box[:3] + half, np.sqrt(_dot3(half, half))]))
        levels = tuple(zip(reversed(boxes), reversed(spheres), strict=True))
        for array in (vertices, triangles, *boxes, *spheres):
            array.setflags(write=False)
        return cls(vertices, triangles, levels)

    def mesh(self) -> tuple[np.ndarray, np.ndarray]:
        """Vertices, shape (n, 3) float64 in m, and triangles, shape (m, 3) int64."""
        return self.vertices, self.triangles


def _morton(points: np.ndarray) -> np.ndarray:
    """Morton (z-order) codes of points (3, m) over their bounding box, shape (m,) uint64."""
    lo, hi = points.min(axis=1, keepdims=True), points.max(axis=1, keepdims=True)
    span = np.where(hi > lo, hi - lo, 1.0)
    cells = ((points - lo) / span * (2**_MORTON_BITS - 1)).astype(np.uint64)
    code = np.zeros(points.shape[1], dtype=np.uint64)
    for axis in range(3):
        v = cells[axis]
        for shift, mask in ((32, 0x1F00000000FFFF), (16, 0x1F0000FF0000FF),
                            (8, 0x100F00F00F00F00F), (4, 0x10C30C30C30C30C3),
                            (2, 0x1249249249249249)):
            v = (v | (v << np.uint64(shift))) & np.uint64(mask)
        code |= v << np.uint64(axis)
    return code


def candidates(index: MeshIndex, query, c, d, travel, reach) -> tuple[np.ndarray, np.ndarray]:
    """(ball, triangle) pairs where the triangle may come within reach of the ball's path.

    Two conservative tests per tree node: its box meets the box swept by the ball, and its
    sphere comes within ``reach`` (ball radius plus padding) of the segment the centre sweeps.

    Parameters
    ----------
    index : MeshIndex
        The part.
    query : ndarray, shape (6, K)
        Swept boxes as rows (x_hi, y_hi, z_hi, -x_lo, -y_lo, -z_lo), m: a tree box, stored
        as (lo, -hi), meets one when box <= query on every row.
    c, d : ndarray, shape (3, K)
        Start centres and unit directions.
    travel, reach : ndarray, shape (K,)
        Segment lengths and reach, m.

    Returns
    -------
    ball, triangle : ndarray, shape (N,), int64
        The pairs, in ball order; ``triangle`` indexes ``index.triangles``.
    """
    levels = index.levels
    roots = levels[0][0].shape[1]
    probe = np.repeat(np.arange(query.shape[1]), roots)
    node = np.tile(np.arange(roots), query.shape[1])
    for depth, (boxes, spheres) in enumerate(levels):
        if depth:
            probe = np.repeat(probe, FANOUT)
            node = (node[:, None] * FANOUT + np.arange(FANOUT)).ravel()
            real = node < boxes.shape[1]
            probe, node = probe[real], node[real]
        meets = np.all(boxes[:, node] <= query[:, probe], axis=0)
        probe, node = probe[meets], node[meets]
        sphere = spheres[:, node]
        dk = d[:, probe]
        w = sphere[:3] - c[:, probe]
        off = w - np.clip(_dot3(w, dk), 0.0, travel[probe]) * dk
        near = _dot3(off, off) <= (reach[probe] + sphere[3]) ** 2
        probe, node = probe[near], node[near]
    return probe, node


def _dot3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise dot product of (3, N) arrays."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
