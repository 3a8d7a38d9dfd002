"""Exact convex sweeps of a tool between two poses, built from the tool's own faces.

The volume a convex tool sweeps over one sub-step is the convex hull of the tool at its two
poses. manifold3d's `Manifold.hull_points` (QuickHull) is not used for it: it treats points
within about 1e-7 of the largest coordinate of a plane as lying on it and drops them.
Measured: the hull of a V profile moved 0.1 nm out of its own plane at mm coordinates keeps
two thirds of the true prism, a round-nose profile moved 1 um out of its plane loses 5e-5 of
it. Such near-flat sweeps are everyday ones (a plunge or retract a few urad off the profile
plane, from a workpiece setting error), and subtracting the wrong solids made the part
depend on how the sweeps were batched (issue 12: up to 3e4 um^3 on paper 002's grooves).

Here the sweep's mesh is written down from the tool's faces, exactly:

- a translation of a profile (a planar convex polygon P by d): the prism P + [0, d], its
  two caps and one parallelogram per edge (`prism_mesh`);
- a translation of a solid: the faces that face backwards (n . d < 0) stay at the start, the
  others move to the end, and each edge between the two sets sweeps a parallelogram: the
  Minkowski sum of a convex polytope and a segment (`SolidSweep`);
- any other convex point set (a move that also rotates, a clipped solid sweep): its convex
  hull by Qhull (`hull_mesh`, scipy), whose precision is float64 round-off, relative to the
  points' spread, with each face Qhull fanned re-triangulated evenly.

Every mesh is imported with one run id (`manifold_from`), so the faces a cut leaves on the
part can be told from the stock's (`machinesim.cutting.engine` integrates the removed
volume over them).
"""

from __future__ import annotations

import functools
from collections import OrderedDict
from typing import NamedTuple

import manifold3d
import numpy as np
from scipy.spatial import ConvexHull, QhullError

#: manifold3d's tolerance for a sweep, relative to its largest coordinate: what manifold3d
#: gives the solids it builds or imports itself. It must stay that fine: a trim by a plane
#: leaves 1e-12 m (its half-space's), and unions of many overlapping passes with that
#: tolerance ran 25 times slower (measured: 90 round-nose passes of paper 002's crown, 48 s
#: against 2 s) and kept 3.7 times the triangles.
SOLID_TOLERANCE_REL = 1e-12

__all__ = ["REBUILT_KEPT", "ConvexPiece", "DeferredSolid", "RebuiltSolid", "SolidSweep",
           "Solids", "UnitedSolid", "clip_polygon", "clipped_bounds", "clipped_prisms",
           "convex_piece", "hull_mesh", "manifold_from", "mesh_volume", "polygon_triangles",
           "prism_mesh", "prism_triangles", "vector_area"]


def manifold_from(vertices: np.ndarray, triangles: np.ndarray,
                  run_id: int) -> manifold3d.Manifold | None:
    """A closed oriented mesh as a manifold whose triangles carry ``run_id``; None if the
    mesh has no volume (manifold3d collapses degenerate triangles on import)."""
    # Fresh writable copies: the bindings refuse read-only arrays.
    vertices = np.array(vertices, dtype=np.float64, order="C")
    mesh = manifold3d.Mesh64(
        vert_properties=vertices,
        tri_verts=np.array(triangles, dtype=np.uint64, order="C"),
        run_index=np.array([0, 3 * len(triangles)], dtype=np.uint64),
        run_original_id=np.array([run_id], dtype=np.uint32),
        tolerance=SOLID_TOLERANCE_REL * float(np.abs(vertices).max(initial=0.0)),
    )
    solid = manifold3d.Manifold(mesh)
    if solid.status() != manifold3d.Error.NoError or solid.is_empty():
        return None
    return solid


def mesh_volume(vertices: np.ndarray, triangles: np.ndarray) -> float:
    """Volume of a closed outward mesh (m^3): the tetrahedra of its triangles and its first
    vertex (not the origin: a sweep far from zero would lose its digits)."""
    corner = vertices[np.asarray(triangles, dtype=np.int64)] - vertices[0]
    return float(np.einsum("ij,ij->i", corner[:, 0],
                           np.cross(corner[:, 1], corner[:, 2])).sum()) / 6.0


class DeferredSolid:
    """A sweep's closed mesh, made a manifold only when it is read (`Solids`): a level pass
    united with its floor's others by their footprints (`machinesim.cutting.footprints`)
    is never cut as a solid of its own, and building it took a third of such a cut."""

    __slots__ = ("run_id", "triangles", "vertices")

    def __init__(self, vertices: np.ndarray, triangles: np.ndarray, run_id: int) -> None:
        self.vertices, self.triangles, self.run_id = vertices, triangles, run_id

    def solid(self) -> manifold3d.Manifold:
        """The manifold (empty where manifold3d takes the mesh for no volume)."""
        solid = manifold_from(self.vertices, self.triangles, self.run_id)
        return manifold3d.Manifold() if solid is None else solid


class RebuiltSolid:
    """A sweep's solid that is made again each time it is read and not kept (`Solids`):
    ``build(*arguments)`` gives the same manifold each time (the same mesh, made from the
    same poses). A ball end mill's sweep is ~230 kB as a manifold (`ball:0.5`); holding all
    of a 100,000-line program's before cutting took 23 GB, where making each again as a
    tile reads it costs what building it did (4 ms on a loaded machine: a tenth of a
    1,000-sweep spiral's 46 s)."""

    __slots__ = ("arguments", "build")

    def __init__(self, build, *arguments) -> None:
        self.build, self.arguments = build, arguments

    def solid(self) -> manifold3d.Manifold:
        """The manifold."""
        return self.build(*self.arguments)


class ConvexPiece(NamedTuple):
    """One convex piece of a `UnitedSolid`."""

    #: Its outward planes (p, 4), Qhull's: unit normal n and offset c, n . x + c <= 0
    #: inside, sorted.
    equations: np.ndarray
    #: Its bounds (3,), m.
    lower: np.ndarray
    upper: np.ndarray


class UnitedSolid:
    """A sweep cut as the union of convex pieces (`SweepSet._united`: a tool tilted across
    itself), which is not convex: its manifold, and its pieces' planes and bounds
    (`ConvexPiece`), which the check of a run's subtraction tests the faces it made against
    (`machinesim.cutting.run_check`; the union's own hull holds material outside it). The
    planes take less room than the manifold they come with (``SweepSet.hulls`` keeps both)."""

    __slots__ = ("pieces", "solid")

    def __init__(self, solid: manifold3d.Manifold, pieces: list[ConvexPiece]) -> None:
        self.solid, self.pieces = solid, tuple(pieces)


def convex_piece(vertices: np.ndarray, equations: np.ndarray,
                 top: float | None = None) -> ConvexPiece:
    """The `ConvexPiece` of the hull of ``vertices`` (n, 3) whose faces lie in the planes
    ``equations`` (f, 4, `hull_mesh`'s), cut to z <= ``top`` (m) when it is given."""
    lower, upper = vertices.min(axis=0), vertices.max(axis=0)
    if top is not None:
        equations = np.unique(np.concatenate([equations, [[0.0, 0.0, 1.0, -top]]]), axis=0)
        upper[2] = min(upper[2], top)
    return ConvexPiece(equations, lower, upper)


#: `RebuiltSolid`s a `Solids` keeps made, the least recently read dropped first: the
#: sweeps of a tile (`tiling.SWEEPS_PER_TILE`) and of its neighbour in the grid, which
#: share those that cross their wall (~120 MB of `ball:0.5` sweeps at most).
REBUILT_KEPT = 512


class Solids(list):
    """Sweeps' solids by index: a `DeferredSolid` becomes its manifold the first time it is
    read (by index or by iterating), and stays so; a `RebuiltSolid` is made when read and
    kept among the last `REBUILT_KEPT` read, so that memory does not grow with the sweeps;
    a `UnitedSolid` reads as its manifold, its convex pieces by `pieces`."""

    def __init__(self, *items) -> None:
        super().__init__(*items)
        self._made: OrderedDict[int, manifold3d.Manifold] = OrderedDict()

    def __getitem__(self, index):
        item = list.__getitem__(self, index)
        if isinstance(item, DeferredSolid):
            item = item.solid()
            list.__setitem__(self, index, item)
        elif isinstance(item, RebuiltSolid):
            key = int(index) if index >= 0 else int(index) + len(self)
            made = self._made.get(key)
            if made is None:
                made = self._made[key] = item.solid()
                while len(self._made) > REBUILT_KEPT:
                    self._made.popitem(last=False)
            else:
                self._made.move_to_end(key)
            item = made
        elif isinstance(item, UnitedSolid):
            item = item.solid
        return item

    def __iter__(self):
        return (self[i] for i in range(len(self)))

    def deferred(self, index: int) -> bool:
        """Whether the solid at ``index`` has not been made yet."""
        return isinstance(list.__getitem__(self, index), DeferredSolid)

    def pieces(self, index: int) -> tuple[ConvexPiece, ...] | None:
        """The convex pieces of the sweep at ``index`` when it is their union (`UnitedSolid`),
        None when it is convex itself."""
        item = list.__getitem__(self, index)
        return item.pieces if isinstance(item, UnitedSolid) else None


def vector_area(polygon: np.ndarray) -> np.ndarray:
    """Vector area of closed polygons (..., k, 3): half the sum of v_i x v_(i+1), m^2.

    Its direction is the polygon's normal by the right-hand rule, its length the area; the
    volume of the prism P + [0, d] is |area . d|.
    """
    return 0.5 * np.cross(polygon, np.roll(polygon, -1, axis=-2)).sum(axis=-2)


@functools.lru_cache(maxsize=64)
def polygon_triangles(count: int) -> np.ndarray:
    """Triangles (count - 2, 3) of a convex ``count``-gon, in its own turning order.

    Balanced (the triangle lo, mid, hi, then each half), not a fan: a fan from one vertex of
    a long arc polygon is all slivers, and manifold3d's booleans with such caps were twice
    as slow (measured: union of 90 round-nose passes 3.4 s, 1.5 s balanced).
    """
    triangles, stack = [], [(0, count - 1)]
    while stack:
        low, high = stack.pop()
        if high - low >= 2:
            middle = (low + high) // 2
            triangles.append((low, middle, high))
            stack += [(low, middle), (middle, high)]
    return np.array(triangles, dtype=np.int64).reshape(-1, 3)


@functools.lru_cache(maxsize=64)
def prism_triangles(count: int) -> np.ndarray:
    """Triangles of the prism over a convex ``count``-gon (start copy 0..count-1, end copy
    count..2 count-1), outward when the polygon turns counter-clockwise about the move."""
    cap = polygon_triangles(count)
    end_cap = cap + count
    start_cap = cap[:, ::-1]
    a = np.arange(count)
    b = (a + 1) % count
    sides = np.concatenate([np.stack([a, b, b + count], axis=1),
                            np.stack([a, b + count, a + count], axis=1)])
    return np.concatenate([end_cap, start_cap, sides]).astype(np.uint64)


#: A move within this sine of a polygon's plane sweeps no prism (volume 0): the sliver is at
#: most 1e-9 of the move thick (0.1 pm for 0.1 mm), and its rounding, of either orientation,
#: corrupted the union of the sweeps it joined (a planar tool's plunges along its own plane:
#: paper 002's crown cut 22 um too deep at a point, docs/procedures/workpiece_setting.md).
PLANE_MOVE_SINE = 1e-9


def _in_plane(area: np.ndarray, move: np.ndarray, turn) -> np.ndarray:
    """Where ``turn`` = area . move is within `PLANE_MOVE_SINE` of |area| |move|."""
    return np.abs(turn) <= PLANE_MOVE_SINE * np.linalg.norm(area, axis=-1) \
        * np.linalg.norm(move, axis=-1)


def prism_mesh(polygon: np.ndarray, move: np.ndarray):
    """The prism swept by a convex polygon (k, 3) translated by ``move`` (3,), m.

    Returns
    -------
    vertices : ndarray, shape (2k, 3)
    triangles : ndarray, shape (4k - 4, 3), uint64, outward
    volume : float
        |area . move|, m^3; 0 for a move within the polygon's plane (`PLANE_MOVE_SINE`: no
        mesh worth making).
    """
    area = vector_area(polygon)
    turn = float(area @ move)
    vertices = np.concatenate([polygon, polygon + move])
    triangles = prism_triangles(len(polygon))
    if turn < 0.0:
        triangles = triangles[:, ::-1]
    return vertices, triangles, 0.0 if _in_plane(area, move, turn) else abs(turn)


def clip_polygon(polygon: np.ndarray, level: float) -> np.ndarray:
    """The part of a convex polygon (k, 3) at z <= ``level`` (Sutherland-Hodgman), in order.

    Repeated points (a vertex on the plane) are dropped; fewer than 3 points left means the
    polygon at most touches the region.
    """
    z = polygon[:, 2]
    inside = z <= level
    if inside.all():
        return polygon
    following = np.roll(polygon, -1, axis=0)
    crossing = inside != np.roll(inside, -1)
    # Edges that do not cross may divide by zero; only crossing ones are read.
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (level - z) / (following[:, 2] - z)
        cut = polygon + t[:, None] * (following - polygon)
    cut[:, 2] = level
    points = np.stack([polygon, cut], axis=1).reshape(-1, 3)
    points = points[np.stack([inside, crossing], axis=1).ravel()]
    if len(points) > 1:
        points = points[np.any(points != np.roll(points, 1, axis=0), axis=1)]
    return points


def clipped_prisms(polygons: np.ndarray, moves: np.ndarray, levels: np.ndarray):
    """`prism_mesh` of many convex polygons each clipped at its level, at once.

    Parameters
    ----------
    polygons : ndarray, shape (s, k, 3)
        Convex polygons, m.
    moves : ndarray, shape (s, 3)
        Each polygon's translation, m.
    levels : ndarray, shape (s,)
        Each polygon is cut to z <= its level first (`clip_polygon`), m.

    Returns
    -------
    list of (vertices, triangles, volume) or None
        One per polygon; None where fewer than 3 points lie at or below the level.
    """
    s, k = polygons.shape[:2]
    z = polygons[:, :, 2]
    inside = z <= levels[:, None]
    following = np.roll(polygons, -1, axis=1)
    crossing = inside != np.roll(inside, -1, axis=1)
    # Edges that do not cross may divide by zero; only crossing ones are read.
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (levels[:, None] - z) / (following[:, :, 2] - z)
        cut = polygons + t[:, :, None] * (following - polygons)
    cut[:, :, 2] = np.broadcast_to(levels[:, None], cut.shape[:2])
    points = np.stack([polygons, cut], axis=2).reshape(s, 2 * k, 3)
    keep = np.stack([inside, crossing], axis=2).reshape(s, 2 * k)
    count = keep.sum(axis=1)
    order = np.argsort(~keep, axis=1, kind="stable")
    packed = np.take_along_axis(points, order[:, :, None], axis=1)
    out = [None] * s
    for size in np.unique(count[count >= 3]).tolist():
        rows = np.flatnonzero(count == size)
        clipped = packed[rows, :size]
        repeated = np.all(clipped == np.roll(clipped, 1, axis=1), axis=2).any(axis=1)
        area = vector_area(clipped)
        turn = np.einsum("ij,ij->i", area, moves[rows])
        turn[_in_plane(area, moves[rows], turn)] = 0.0
        template = prism_triangles(size)
        vertices = np.concatenate([clipped, clipped + moves[rows, None, :]], axis=1)
        for row, polygon, points_of, sign, again in zip(rows.tolist(), clipped, vertices,
                                                         turn.tolist(), repeated.tolist(),
                                                         strict=True):
            if again:  # a vertex on the plane: drop the repeat, one polygon at a time
                polygon = polygon[np.any(polygon != np.roll(polygon, 1, axis=0), axis=1)]
                out[row] = prism_mesh(polygon, moves[row]) if len(polygon) >= 3 else None
            else:
                out[row] = (points_of, template if sign >= 0.0 else template[:, ::-1],
                            abs(sign))
    return out


class SolidSweep:
    """Sweeps of one convex polyhedron (the tool) translated along segments.

    Parameters
    ----------
    vertices : ndarray, shape (k, 3)
        The tool's vertices in its frame, m.
    triangles : ndarray, shape (t, 3)
        Its outward triangles (a closed convex polyhedron).
    """

    def __init__(self, vertices: np.ndarray, triangles: np.ndarray) -> None:
        self.vertices = np.asarray(vertices, dtype=np.float64)
        self.triangles = np.asarray(triangles, dtype=np.int64)
        corner = self.vertices[self.triangles]
        self.normals = np.cross(corner[:, 1] - corner[:, 0], corner[:, 2] - corner[:, 0])
        # Half-edges a -> b of triangle i, and the triangle across each (its b -> a).
        a = self.triangles.ravel()
        b = self.triangles[:, [1, 2, 0]].ravel()
        k = len(self.vertices)
        key = a * k + b
        order = np.argsort(key)
        twin = order[np.searchsorted(key[order], b * k + a)]
        self.half_a, self.half_b = a, b
        self.owner = np.repeat(np.arange(len(self.triangles)), 3)
        self.across = self.owner[twin]

    def mesh(self, rotation: np.ndarray, origin: np.ndarray, move: np.ndarray):
        """Vertices (n, 3) and outward triangles (m, 3) of the tool at (rotation, origin)
        swept by ``move`` (3,), m."""
        return self.mesh_from(self.vertices @ rotation.T + origin, rotation, move)

    def mesh_from(self, start: np.ndarray, rotation: np.ndarray, move: np.ndarray):
        """`mesh` of the tool's vertices placed at ``start`` (k, 3) (the tool at rotation,
        or a shape with the same faces and face normals), swept by ``move``."""
        k = len(self.vertices)
        back = (self.normals @ rotation.T) @ move < 0.0
        triangles = np.where(back[:, None], self.triangles, self.triangles + k)
        edge = back[self.owner] & ~back[self.across]
        a, b = self.half_a[edge], self.half_b[edge]
        quads = np.concatenate([np.stack([b, a, a + k], axis=1),
                                np.stack([b, a + k, b + k], axis=1)])
        triangles = np.concatenate([triangles, quads])
        used, inverse = np.unique(triangles, return_inverse=True)
        vertices = np.concatenate([start, start + move])[used]
        return vertices, inverse.reshape(-1, 3).astype(np.uint64)


def hull_mesh(points: np.ndarray, planes: bool = False):
    """Convex hull of points (n, 3) by Qhull: vertices, outward triangles (uint64), volume,
    and with ``planes`` its faces' outward equations (f, 4), Qhull's, each once, sorted.

    Each face of the hull that Qhull triangulated as a fan (a profile's end face, the top
    of a clipped sweep: polygons of hundreds of vertices) is triangulated again by
    `polygon_triangles`: manifold3d's booleans with fans of slivers were 2-5 times slower.
    None when the points are flat within Qhull's float64 precision (no volume to remove).
    """
    try:
        hull = ConvexHull(points)
    except QhullError:
        return None
    simplices = hull.simplices.copy()
    corner = points[simplices]
    normal = np.cross(corner[:, 1] - corner[:, 0], corner[:, 2] - corner[:, 0])
    flip = np.einsum("ij,ij->i", normal, hull.equations[:, :3]) < 0.0
    simplices[flip] = simplices[flip][:, ::-1]
    # Qhull gives the triangles of one face that face's own plane: group them by it.
    equations, face, count = np.unique(hull.equations, axis=0, return_inverse=True,
                                       return_counts=True)
    face = face.reshape(-1)
    large = np.flatnonzero(count >= 3)
    if len(large):
        kept = [simplices[~np.isin(face, large)]]
        for group in large:
            loop = _boundary_loop(simplices[face == group])
            kept.append(loop[polygon_triangles(len(loop))] if loop is not None
                        else simplices[face == group])
        simplices = np.concatenate(kept)
    used, inverse = np.unique(simplices, return_inverse=True)
    mesh = points[used], inverse.reshape(-1, 3).astype(np.uint64), float(hull.volume)
    return (*mesh, equations) if planes else mesh


def _boundary_loop(triangles: np.ndarray) -> np.ndarray | None:
    """The boundary of a triangulated convex polygon, in the triangles' turning order, or
    None when it is not one simple loop."""
    start = triangles.ravel()
    end = triangles[:, [1, 2, 0]].ravel()
    edge = start * (int(max(start.max(), end.max())) + 1) + end
    reverse = end * (int(max(start.max(), end.max())) + 1) + start
    outer = ~np.isin(edge, reverse)
    following = dict(zip(start[outer].tolist(), end[outer].tolist(), strict=True))
    if len(following) != int(outer.sum()):
        return None
    loop = [next(iter(following))]
    for _ in range(len(following) - 1):
        loop.append(following[loop[-1]])
    if following.get(loop[-1]) != loop[0] or len(set(loop)) != len(loop):
        return None
    return np.array(loop, dtype=np.int64)


def clipped_bounds(points: np.ndarray, segments: np.ndarray, level: float):
    """Bounds of the convex hulls of point sets cut by the half-space z <= ``level``.

    Parameters
    ----------
    points : ndarray, shape (n, m, 3)
        n point sets, m.
    segments : ndarray, shape (e, 2)
        Index pairs into the m points that include every edge of each hull: every vertex
        of a cut hull is then a point below the plane or a crossing of one of them.
    level : float
        m.

    Returns
    -------
    low, high : ndarray, shape (n, 3)
        +inf and -inf where nothing lies below the plane.
    """
    below = points[:, :, 2] <= level
    first, second = segments[:, 0], segments[:, 1]
    # Only the segments that cross the plane are cut (a few of the thousands of a profile's
    # sweep): each crossing is the same float operations as over every segment at once,
    # and a min or max does not depend on the order it reads its values in.
    sets, crossing = np.nonzero(below[:, first] != below[:, second])
    a, b = points[sets, first[crossing]], points[sets, second[crossing]]
    t = (level - a[:, 2]) / (b[:, 2] - a[:, 2])
    cut = a + t[:, None] * (b - a)
    cut[:, 2] = level
    low = np.where(below[:, :, None], points, np.inf).min(axis=1)
    high = np.where(below[:, :, None], points, -np.inf).max(axis=1)
    np.minimum.at(low, sets, cut)
    np.maximum.at(high, sets, cut)
    return low, high
