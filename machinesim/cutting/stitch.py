"""Join cut tiles that share walls into one solid without a boolean union.

Tiles partition a cell with axis-aligned walls, so the two tiles on either side of a wall
both carry the same cross-section of the part on it: the same polygon, with vertices that
agree to a few ulp (each tile's boolean computed them separately). Dropping the wall
triangles of both sides and merging the wall vertices that coincide gives the closed surface
of the union at the cost of one mesh import, where a boolean union of the tiles would
re-intersect every tile. Any mismatch (a vertex on one side only, a part face lying in a
wall) leaves an open or non-manifold mesh, which manifold3d rejects: the caller then falls
back to the boolean union, so the result is exact either way.
"""

from __future__ import annotations

import manifold3d
import numpy as np
from scipy.spatial import cKDTree

from machinesim.tolerances import WALL_TOL_REL


def exact_box(xmin: float, xmax: float, ymin: float, ymax: float, zmin: float,
              zmax: float) -> manifold3d.Manifold:
    """Box whose corner coordinates are exactly the given floats (m)."""
    x, y, z = (xmin, xmax), (ymin, ymax), (zmin, zmax)
    vertices = np.array([[x[i & 1], y[(i >> 1) & 1], z[i >> 2]] for i in range(8)])
    triangles = np.array(
        [[0, 2, 1], [1, 2, 3], [4, 5, 6], [5, 7, 6], [0, 1, 4], [1, 5, 4],
         [2, 6, 3], [3, 6, 7], [0, 4, 2], [2, 4, 6], [1, 3, 5], [3, 7, 5]],
        dtype=np.uint64,
    )
    return manifold3d.Manifold(manifold3d.Mesh64(vert_properties=vertices, tri_verts=triangles))


def _roots(parent: np.ndarray) -> np.ndarray:
    while True:
        grand = parent[parent]
        if np.array_equal(grand, parent):
            return parent
        parent = grand


def _neighbour_filled(grid: np.ndarray, filled: np.ndarray, box, side: int) -> bool:
    """True when the tile across ``side`` of ``box`` exists and holds material."""
    other = 1 - side // 2
    facing = side ^ 1
    match = ((grid[:, facing] == box[side]) & (grid[:, 2 * other] == box[2 * other])
             & (grid[:, 2 * other + 1] == box[2 * other + 1]))
    return bool(np.any(match & filled))


def stitch(pieces, boxes, outer, scale: float) -> manifold3d.Manifold | None:
    """One solid from tiles cut separately, or None when they do not stitch cleanly.

    Parameters
    ----------
    pieces : list of manifold3d.Manifold
        The cut tiles. An empty tile (no material left) has no wall: its neighbours keep
        their faces on the wall they share with it.
    boxes : list of (xmin, xmax, ymin, ymax)
        Each tile's box (m). They must form a grid: each wall is shared whole by the two
        tiles beside it, with exactly equal coordinates.
    outer : (xmin, xmax, ymin, ymax)
        The cell the tiles partition; its sides are not walls.
    scale : float
        Largest coordinate magnitude of the part (m), for `WALL_TOL_REL`.
    """
    tol = WALL_TOL_REL * scale
    filled = np.array([not piece.is_empty() for piece in pieces])
    grid = np.array(boxes, dtype=np.float64).reshape(-1, 4)
    all_vertices, all_triangles, on_wall = [], [], []
    offset = 0
    expected_volume = 0.0
    for piece, box, full in zip(pieces, boxes, filled, strict=True):
        if not full:
            continue
        mesh = piece.to_mesh64()
        vertices = np.asarray(mesh.vert_properties[:, :3], dtype=np.float64)
        triangles = np.asarray(mesh.tri_verts, dtype=np.int64)
        expected_volume += piece.volume()
        wall_vertex = np.zeros(len(vertices), dtype=bool)
        wall_triangle = np.zeros(len(triangles), dtype=bool)
        for side, value in enumerate(box):
            axis = side // 2
            if value == outer[side] or not _neighbour_filled(grid, filled, box, side):
                continue
            near = np.abs(vertices[:, axis] - value) <= tol
            wall_vertex |= near
            wall_triangle |= near[triangles].all(axis=1)
        all_vertices.append(vertices)
        all_triangles.append(triangles[~wall_triangle] + offset)
        on_wall.append(wall_vertex)
        offset += len(vertices)
    vertices = np.concatenate(all_vertices)
    triangles = np.concatenate(all_triangles)
    candidates = np.flatnonzero(np.concatenate(on_wall))
    parent = np.arange(len(vertices))
    if len(candidates):
        pairs = cKDTree(vertices[candidates]).query_pairs(tol, output_type="ndarray")
        if len(pairs):
            a, b = candidates[pairs[:, 0]], candidates[pairs[:, 1]]
            low, high = np.minimum(a, b), np.maximum(a, b)
            # Relax edges to the smallest index until stable: union-find without recursion.
            while True:
                roots = _roots(parent)
                moved = roots[high] != roots[low]
                if not moved.any():
                    break
                target = np.minimum(roots[high], roots[low])
                np.minimum.at(parent, roots[high], target)
                np.minimum.at(parent, roots[low], target)
            parent = _roots(parent)
    triangles = parent[triangles]
    used, triangles = np.unique(triangles, return_inverse=True)
    triangles = triangles.reshape(-1, 3)
    mesh = manifold3d.Mesh64(
        vert_properties=np.ascontiguousarray(vertices[used]),
        tri_verts=np.ascontiguousarray(triangles, dtype=np.uint64),
    )
    result = manifold3d.Manifold(mesh)
    if result.status() != manifold3d.Error.NoError or result.is_empty():
        return None
    if abs(result.volume() - expected_volume) > 1e-12 * abs(expected_volume):
        return None
    return result
