"""Join cut tiles that share walls into one solid without a boolean union.

Tiles partition a cell with axis-aligned walls, so the two tiles on either side of a wall
both carry the same cross-section of the part on it: the same polygon, with vertices that
agree to a few ulp (each tile's boolean computed them separately). Dropping the wall
triangles of both sides and merging the wall vertices that coincide gives the closed surface
of the union at the cost of one mesh import, where a boolean union of the tiles would
re-intersect every tile.

The two sides need not carry the same vertices along a section edge: a face cut in several
runs (a pocket's floor, where each run's bottom coincides with the floor the runs before
left) keeps vertices from its history where its old edges met the wall, and the two tiles
have different histories. Such a vertex, on one side only, lies on an edge of the other
side's section (a T-junction); that edge's triangle is split there, so both sides meet in
the same vertices. Any other mismatch (a vertex on one side only and on no edge of the
other, a part face lying in a wall) leaves an open or non-manifold mesh, which manifold3d
rejects: the caller then falls back to a boolean union, exact either way.

A tile's wall vertices lie on the wall's plane only to the round-off of the boolean that
made them (measured: up to 1.6e-18 m off on a 5 mm part). Both the merge and the fallback
union (`snapped_union`) first move them onto the plane exactly: a boolean union of tiles
whose walls are off by 1e-18 m does not fuse them everywhere: it keeps both walls where they
face each other as a closed crack of no width (found on a round pocket in levels, 10 mm
square, in 4 tiles: 3.2 mm^2 of crack, 101 triangles; re-importing that part's own mesh,
manifold3d's clean-up folded the crack and changed the volume by 3.8 mm^3).
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


def _wall_sides(grid: np.ndarray, filled: np.ndarray, box, outer) -> list[int]:
    """Sides of ``box`` (0..3: xmin, xmax, ymin, ymax) that are walls to a filled tile."""
    return [side for side, value in enumerate(box)
            if value != outer[side] and _neighbour_filled(grid, filled, box, side)]


def _snapped_mesh(piece: manifold3d.Manifold, box, sides, tol: float):
    """The piece's vertices (a copy) with those within ``tol`` of a wall in ``sides`` put on
    its plane exactly, its triangles, and per side the mask of the vertices on that wall."""
    mesh = piece.to_mesh64()
    vertices = np.array(mesh.vert_properties[:, :3], dtype=np.float64)
    triangles = np.asarray(mesh.tri_verts, dtype=np.int64)
    masks = []
    for side in sides:
        axis, value = side // 2, box[side]
        near = np.abs(vertices[:, axis] - value) <= tol
        vertices[near, axis] = value
        masks.append(near)
    return vertices, triangles, masks


def snapped_union(pieces, boxes, outer, scale: float) -> manifold3d.Manifold:
    """Boolean union of the tiles, each with its wall vertices put on its walls' planes.

    The fallback where `stitch` returns None: unsnapped, the tiles' walls lie up to a few
    1e-18 m off their planes and the union keeps both walls inside the part, a crack of no
    width. Arguments as `stitch`.
    """
    tol = WALL_TOL_REL * scale
    filled = np.array([not piece.is_empty() for piece in pieces])
    grid = np.array(boxes, dtype=np.float64).reshape(-1, 4)
    snapped = []
    for piece, box, full in zip(pieces, boxes, filled, strict=True):
        if not full:
            continue
        vertices, triangles, _ = _snapped_mesh(piece, box, _wall_sides(grid, filled, box, outer),
                                               tol)
        snapped.append(manifold3d.Manifold(manifold3d.Mesh64(
            vert_properties=vertices, tri_verts=np.ascontiguousarray(triangles, dtype=np.uint64))))
    return manifold3d.Manifold.batch_boolean(snapped, manifold3d.OpType.Add)


#: Passes of T-junction splitting: each splits at most one edge of a triangle.
T_JUNCTION_PASSES = 4


def split_t_junctions(vertices: np.ndarray, triangles: np.ndarray, tol: float,
                      on_wall: np.ndarray | None = None) -> np.ndarray:
    """Triangles with every open edge split at the open-edge vertices lying on it.

    An edge used in one direction only (its reverse missing) whose interior passes within
    ``tol`` (m) of vertices of other open edges is the long side of a T-junction: its
    triangle (a, b, c) becomes the fan (a, r1, c), (r1, r2, c), ..., (rk, b, c), the same
    orientation and, to ``tol``, the same surface. With ``on_wall`` (a mask of the
    vertices), only edges between two such vertices are taken as open: ``triangles`` may
    then be only those that hold such edges.
    """
    for _ in range(T_JUNCTION_PASSES):
        edges = triangles[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
        count = len(vertices)
        reverse = np.isin(edges[:, 0] * count + edges[:, 1], edges[:, 1] * count + edges[:, 0])
        if on_wall is not None:
            reverse |= ~(on_wall[edges[:, 0]] & on_wall[edges[:, 1]])
        open_edges = np.flatnonzero(~reverse)
        if not len(open_edges):
            break
        ends = np.unique(edges[open_edges])
        start, end = vertices[edges[open_edges, 0]], vertices[edges[open_edges, 1]]
        length = np.linalg.norm(end - start, axis=1)
        near = cKDTree(vertices[ends]).query_ball_point((start + end) / 2.0,
                                                        length / 2.0 + tol)
        splits = {}
        for k, found in enumerate(near):
            triangle, corner = divmod(int(open_edges[k]), 3)
            if triangle in splits or length[k] <= 2.0 * tol:
                continue
            others = ends[found]
            others = others[(others != edges[open_edges[k], 0])
                            & (others != edges[open_edges[k], 1])]
            if not len(others):
                continue
            along = (end[k] - start[k]) / length[k]
            offset = vertices[others] - start[k]
            s = offset @ along
            off_line = np.linalg.norm(offset - s[:, None] * along, axis=1)
            on = (off_line <= tol) & (s > tol) & (s < length[k] - tol)
            if on.any():
                splits[triangle] = (corner, others[on][np.argsort(s[on])])
        if not splits:
            break
        keep = np.ones(len(triangles), dtype=bool)
        fans = []
        for triangle, (corner, points) in splits.items():
            a, b, c = (triangles[triangle, (corner + i) % 3] for i in range(3))
            chain = [a, *points.tolist(), b]
            fans.extend((p, q, c) for p, q in zip(chain[:-1], chain[1:], strict=True))
            keep[triangle] = False
        triangles = np.vstack([triangles[keep], np.array(fans, dtype=np.int64)])
    return triangles


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
        vertices, triangles, walls = _snapped_mesh(
            piece, box, _wall_sides(grid, filled, box, outer), tol)
        expected_volume += piece.volume()
        wall_vertex = np.zeros(len(vertices), dtype=bool)
        wall_triangle = np.zeros(len(triangles), dtype=bool)
        for near in walls:
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
    # Open edges join two wall vertices: look for T-junctions only among the triangles that
    # hold such edges (each of them holds both triangles of such an edge).
    wall = np.zeros(len(vertices), dtype=bool)
    wall[parent[candidates]] = True
    near_wall = wall[triangles].sum(axis=1) >= 2
    split = split_t_junctions(vertices, triangles[near_wall], tol, wall)
    if len(split) != np.count_nonzero(near_wall):
        triangles = np.concatenate([triangles[~near_wall], split])
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
