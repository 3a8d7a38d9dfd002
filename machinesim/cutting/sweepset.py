"""The sweeps of a set of pose paths: which reach the stock, their exact clipped solids.

`machinesim.cutting.engine.remove` hands its paths to a `SweepSet`, which transforms the
tool for all poses at once, finds the sweeps that come below a plane just above the stock
(most rapids do not), and builds each of those as an exact solid (`machinesim.cutting.sweeps`),
clipped to that plane so tall tool bodies do not overlap their neighbours. It keeps where
the holder begins (`SweepSet.holder_face`), which `machinesim.cutting.holder` checks against
the stock.
"""

from __future__ import annotations

from collections.abc import Callable

import manifold3d
import numpy as np

from machinesim.cutting.sideways import dragged
from machinesim.cutting.sweeps import (
    DeferredSolid,
    RebuiltSolid,
    Solids,
    SolidSweep,
    UnitedSolid,
    clipped_bounds,
    clipped_prisms,
    convex_piece,
    hull_mesh,
    manifold_from,
    mesh_volume,
    polygon_triangles,
)
from machinesim.cutting.tilted_profiles import split_sweeps
from machinesim.cutting.tilted_solids import SolidSplitter
from machinesim.tolerances import SAME_ORIENTATION, TWIST_M

__all__ = ["PAIR_CLIP_MAX_VERTICES", "POINTS_PER_CHUNK", "PROGRESS_STEPS",
           "REBUILD_BALL_SWEEPS", "SweepSet", "dragged"]

#: A turning sweep whose vertices' heights change by no more than this (m) between its
#: poses is not trimmed at the clip plane after its hull (`SweepSet.hulls`): it reaches at
#: most that far above the plane, which lies above the stock, where it cuts nothing, and
#: the trim made a C groove under a C axis tilted by 10 urad 36 % slower (4.07 -> 5.54 s).
RAISED_UNTRIMMED_M = 1e-9

#: The bounds of a profile's turning sweep below the clip plane come from the all-pairs edge
#: search of both poses, when the tool has no more than this many vertices (`hulls`).
PAIR_CLIP_MAX_VERTICES = 64
#: Sides of the polygon a shank wider than the tool's body is drawn as in the holder check
#: (circumscribed about the shank: it errs towards a crash, by at most 0.5 % of its radius).
HOLDER_SHANK_SIDES = 32
#: Times at most that `SweepSet.hulls` tells its progress while it builds the sweeps.
PROGRESS_STEPS = 200
#: A ball end mill's sweeps are kept as `RebuiltSolid`s, made again when a tile reads them
#: (`SweepSet.ball_sweep`), not as solids: False holds every one from the start, as before
#: (`benchmarks/ball_sweeps.py` compares the two).
REBUILD_BALL_SWEEPS = True
#: Sweeps whose tool points are processed together: bounds the transient memory (k points
#: per pose, ~100 bytes each) to ~50 MB whatever the path length.
POINTS_PER_CHUNK = 1 << 19


class SweepSet:
    """The sweeps of all paths, built chunk by chunk into exact clipped solids (`sweeps`).

    Parameters
    ----------
    tool : VTool or RoundNoseTool or BallEndMill
    paths : list of ndarray, each shape (N_i, 4, 4)
        Checked poses; consecutive poses of a path form sweeps.
    clip_z : float
        Height of the clip plane, just above the stock (m).
    """

    def __init__(self, tool, paths: list[np.ndarray], clip_z: float) -> None:
        self.rotational = bool(tool.rotational)
        self.planar = bool(getattr(tool, "planar", False))
        self.vertices = np.asarray(tool.vertices(), dtype=np.float64)
        edges = np.asarray(tool.edges(), dtype=np.int64)
        self.clip_z = clip_z
        # Every sweep's faces carry this id, so the faces a cut leaves can be found.
        self.run_id = manifold3d.Manifold.reserve_ids(1)
        self.poses = np.concatenate(paths) if paths else np.zeros((0, 4, 4))
        # A sweep joins pose i to pose i + 1 of the same path, never across paths. A path of
        # no pose before any pose ends at -1: no pair (np.delete took it from the end, and
        # the last sweep of the cut was never cut).
        last = np.cumsum([len(poses) for poses in paths], dtype=np.int64) - 1
        self.pairs = np.delete(np.arange(max(len(self.poses) - 1, 0), dtype=np.int64),
                               last[(last >= 0) & (last < len(self.poses) - 1)])
        self.count = len(self.pairs)
        k = len(self.vertices)
        self.edges = edges
        # Candidate edges of a sweep's hull, T1 = points k.. 2k-1: for a translation the
        # edges of T0, of T1 and each vertex's own path; for a rotation any T0-T1 pair as
        # well. The hull of the candidates below the plane and of the crossings is exactly
        # the hull clipped, and their bounds are its bounds (a turning sweep itself is the
        # hull of its poses clipped first, inside these bounds: `hulls`).
        ends = np.stack([np.arange(k), np.arange(k) + k], axis=1)
        self.translation_segments = np.concatenate([edges, edges + k, ends])
        # A turning sweep's poses are clipped one by one (`hulls`): the edges of T0 and T1.
        self.pose_edges = np.concatenate([edges, edges + k])
        self.rotation_segments = None
        if k <= PAIR_CLIP_MAX_VERTICES:
            i, j = np.meshgrid(np.arange(k), np.arange(k) + k, indexing="ij")
            self.rotation_segments = np.concatenate(
                [edges, edges + k, np.stack([i.ravel(), j.ravel()], axis=1)]
            )
        # A rotating tool's body is a closed convex polyhedron: translated, its sweep is the
        # Minkowski sum with the segment, built from its faces without a hull search.
        self.solid_sweep = (SolidSweep(self.vertices, tool.triangles())
                            if self.rotational and hasattr(tool, "triangles") else None)
        # ... and where a turn tilts it across its sides, it is cut in pieces
        self.splitter = (SolidSplitter(self.vertices, np.asarray(tool.triangles()))
                         if self.solid_sweep is not None else None)
        top = self.vertices[:, 2]
        self.top = np.flatnonzero(top >= top.max())
        # Where the holder begins: the body's top face, or a shank wider than the body
        # (`shank_radius`), a 32-gon about the tool axis at the body's height.
        self.holder_face = self.vertices[self.top]
        shank = float(getattr(tool, "shank_radius", 0.0) or 0.0)
        if shank > float(np.max(np.hypot(*self.holder_face[:, :2].T))):
            phi = 2.0 * np.pi * np.arange(HOLDER_SHANK_SIDES) / HOLDER_SHANK_SIDES
            # circumscribed, so that the polygon holds the round shank
            r = shank / np.cos(np.pi / HOLDER_SHANK_SIDES)
            self.holder_face = np.stack([r * np.cos(phi), r * np.sin(phi),
                                         np.full(phi.size, top.max())], axis=1)
        # A flat end mill: vertex i + n straight above vertex i (its two rings, `tools`).
        from machinesim.tools import BallEndMill, FlatEndMill
        self.rings = int(tool.segments) if isinstance(tool, FlatEndMill) else 0
        # A ball end mill: its vertices the tip, then rings of latitude of `segments` each,
        # from the tip up (`BallEndMill.rings`); its shorter sweeps by how many are kept.
        self.ball = (tool.rings[1] if isinstance(tool, BallEndMill)
                     and self.solid_sweep is not None else 0)
        self._ball_sweeps: dict[int, SolidSweep] = {}
        self._world = self._lowest = None

    def lowest(self, index) -> np.ndarray:
        """Height of the tool's lowest point at poses ``index``, shape (n,), m."""
        if self._lowest is None:
            self._lowest = np.empty(len(self.poses))
            step = max(1, POINTS_PER_CHUNK // len(self.vertices))
            for begin in range(0, len(self.poses), step):
                poses = self.poses[begin:begin + step]
                self._lowest[begin:begin + step] = (
                    np.einsum("nj,kj->nk", poses[:, 2, :3], self.vertices).min(axis=1)
                    + poses[:, 2, 3])
        return self._lowest[index]

    def world(self, index, columns=None) -> np.ndarray:
        """The tool's vertices (those in ``columns``, default all) at poses ``index`` (a
        slice or index array), shape (n, k, 3), m.

        All poses are transformed once when they fit in `POINTS_PER_CHUNK` points (the
        usual case), and read from there by every pass."""
        if self._world is None and len(self.poses) * len(self.vertices) <= POINTS_PER_CHUNK:
            self._world = (self.vertices @ self.poses[:, :3, :3].transpose(0, 2, 1)
                           + self.poses[:, None, :3, 3])
        if self._world is not None:
            points = self._world[index]
            return points if columns is None else points[:, columns]
        poses = self.poses[index]
        vertices = self.vertices if columns is None else self.vertices[columns]
        return vertices @ poses[:, :3, :3].transpose(0, 2, 1) + poses[:, None, :3, 3]

    def _clip(self, points: np.ndarray, segments, plane=None):
        """Point sets whose hulls are the sweeps' hulls cut by z <= clip_z (or by z <=
        ``plane``, one height per sweep).

        ``points`` has shape (s, 2k, 3); ``segments`` include every edge of each hull (the
        translation or rotation candidates of `__init__`). Every candidate lies in the
        hull, and every vertex of the clipped hull is a point below the plane or a crossing
        of a hull edge, so the hull of the candidates is exactly the clipped sweep. None
        where the whole sweep lies above the plane.
        """
        plane = np.full(len(points), self.clip_z) if plane is None else plane
        below = points[:, :, 2] <= plane[:, None]
        a, b = points[:, segments[:, 0]], points[:, segments[:, 1]]
        crossing = below[:, segments[:, 0]] != below[:, segments[:, 1]]
        # Segments that do not cross may divide by zero; only crossing ones are read.
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (plane[:, None] - a[:, :, 2]) / (b[:, :, 2] - a[:, :, 2])
            cut = a + t[:, :, None] * (b - a)
        cut[:, :, 2] = plane[:, None]
        out = []
        for sweep, state in enumerate(below.sum(axis=1)):
            if state == below.shape[1]:
                out.append(points[sweep])
            elif state == 0:
                out.append(None)
            else:
                out.append(np.concatenate([points[sweep][below[sweep]],
                                           cut[sweep][crossing[sweep]]]))
        return out

    def _solid(self, vertices, triangles, trim: bool):
        """(manifold, volume) of an exact sweep mesh, trimmed to z <= clip_z; None if it has
        no volume, "above" if nothing of it lies below the plane."""
        solid = manifold_from(vertices, triangles, self.run_id)
        if solid is None:
            return None
        if trim:
            tolerance = solid.get_tolerance()
            # The trim's half-space would leave its own, far coarser tolerance on the sweep
            # (1e-12 m), which slows unions of many passes 25 times (`sweeps`).
            solid = solid.trim_by_plane((0.0, 0.0, -1.0), -self.clip_z).set_tolerance(tolerance)
            if solid.is_empty():
                return "above"
        volume = solid.volume()
        return (solid, volume) if volume > 0.0 else None

    def _prism(self, prism, start: np.ndarray, move: np.ndarray):
        """A profile (k, 3) translated by ``move``: the prism of the profile clipped at
        ``clip_z`` + |move_z| (``prism``, from `sweeps.clipped_prisms`), exact, built without
        a hull.

        A point of the sweep below the stock top lies on the path of a profile point at
        most |move_z| higher, so below that level: the prism of the clipped profile is the
        sweep wherever there is material. Its top is the swept top edge of the clipped
        profile (two triangles), not a cap of hundreds of vertices in a plane every sweep
        shares: the unions of parallel passes run as fast as with the old hulls (90 side
        passes of paper 002's crown: 2.8 s, the old engine 3.0 s; through Qhull and a trim
        plane 5-6 s).
        """
        if min(start[:, 2].min(), start[:, 2].min() + move[2]) > self.clip_z or prism is None:
            return "above"
        vertices, triangles, volume = prism
        if not volume > 0.0:
            return None
        solid = manifold_from(vertices, triangles, self.run_id)
        return None if solid is None else (solid, volume, vertices)

    def _translated(self, rotation, origin, move, points):
        """A rotating tool translated by ``move`` from (``rotation``, ``origin``): its exact
        Minkowski sum with the segment (`SolidSweep`), trimmed by the clip plane; "above"
        when no point of it comes below the plane."""
        if points[:, 2].min() + min(move[2], 0.0) > self.clip_z:
            return "above"
        if self.rings:
            # An upright flat end mill (its top ring straight above its bottom ring) cut at
            # a plane between them is the same prism with its top ring lowered to it. Every
            # point of the sweep below the clip plane lies on the path of a tool point at
            # most max(0, -move z) above it, so the sweep of the tool cut there is the sweep
            # wherever there is material, built without a trim (a boolean: 16 of 28 s of
            # building a helix's 9,600 sweeps). Its top, above the clip plane by at most
            # |move z|, is never part of the cut.
            level = self.clip_z + max(0.0, -float(move[2]))
            n = self.rings
            start = self.vertices @ rotation.T + origin
            bottom, top = start[:n], start[n:]
            if (top[:, 2].min() > level > bottom[:, 2].max()
                    and np.array_equal(top[:, :2], bottom[:, :2])):
                start[n:, 2] = level
                vertices, triangles = self.solid_sweep.mesh_from(start, rotation, move)
                floor = bottom[:, 2]
                if move[2] == 0.0 and floor.min() == floor.max():
                    # level, on a level floor: an upright prism (`footprints`), its solid
                    # made only if it is cut as one (`DeferredSolid`)
                    volume = mesh_volume(vertices, triangles)
                    if not volume > 0.0:
                        return None
                    corners = np.concatenate([bottom[:, :2], bottom[:, :2] + move[:2]])
                    return (DeferredSolid(vertices, triangles, self.run_id), volume, vertices,
                            (float(floor[0]), float(level), corners))
                solid = manifold_from(vertices, triangles, self.run_id)
                if solid is None:
                    return None
                volume = solid.volume()
                if not volume > 0.0:
                    return None
                return solid, volume
        if self.ball:
            built = self._ball_cut(rotation, origin, move)
            if built != "whole":
                return built
        vertices, triangles = self.solid_sweep.mesh(rotation, origin, move)
        return self._solid(vertices, triangles, vertices[:, 2].max() > self.clip_z)

    def _ball_cut(self, rotation, origin, move):
        """A ball end mill translated by ``move``: the sweep of the tool cut at its lowest
        ring of latitude that lies wholly above clip_z + max(0, -move z), untrimmed; "whole"
        when no ring does (the tool's whole sweep is then trimmed, `_translated`).

        Every point of the sweep below the clip plane lies on the path of a tool point at
        most max(0, -move z) above it, and the tool below such a ring is the hull of the
        tip and the rings under it (a stack of frusta), so the sweep of that hull is the
        sweep wherever there is material. Its top, above the clip plane by at most a ring's
        rise plus |move z| (for R0.5 mm, 44 um), cuts nothing there. Built so, a raster's
        3,819 sweeps took 5 s instead of 23 s: the whole tool's sweep, 10 mm tall, was
        imported and then trimmed by the plane (a boolean) for a tip 0.08 mm deep. The part
        is the trimmed sweeps' to round-off (heights within 3e-17 m on that raster,
        `tests/test_cutting_sweeps.py`).
        """
        n = self.ball
        start = self.vertices @ rotation.T + origin
        level = self.clip_z + max(0.0, -float(move[2]))
        # lowest height of each ring and of everything above it
        above = np.minimum.accumulate(start[:0:-1, 2])[::-1][::n]
        rings = np.flatnonzero(above >= level)
        if not len(rings) or rings[0] == len(above) - 1:
            return "whole"
        kept = int(rings[0]) + 1
        if kept not in self._ball_sweeps:
            count = 1 + kept * n
            triangles = self.solid_sweep.triangles
            top = count - n + polygon_triangles(n)  # counter-clockwise from above: outward
            self._ball_sweeps[kept] = SolidSweep(
                self.vertices[:count],
                np.concatenate([triangles[(triangles < count).all(axis=1)], top]))
        sweep = self._ball_sweeps[kept]
        vertices, triangles = sweep.mesh_from(start[:len(sweep.vertices)], rotation, move)
        solid = manifold_from(vertices, triangles, self.run_id)
        if solid is None:
            return None
        volume = solid.volume()
        return _BallSweep((solid, volume)) if volume > 0.0 else None

    def ball_sweep(self, index: int) -> manifold3d.Manifold:
        """The solid `_ball_cut` made of the sweep from pose ``index`` to the next, made
        again from the same poses, laid out as `hulls` hands them over (the same mesh, bit
        for bit: `RebuiltSolid`)."""
        origin = self.poses[index, :3, 3]
        return self._ball_cut(self.poses[index, :3, :3].copy(), origin,
                              self.poses[index + 1, :3, 3] - origin)[0]

    def ball_line(self, start: int, end: int) -> manifold3d.Manifold:
        """`ball_sweep` of the straight level move from pose ``start`` to pose ``end``, the
        chain of moves between them in line (`machinesim.cutting.collinear`)."""
        origin = self.poses[start, :3, 3]
        return self._ball_cut(self.poses[start, :3, :3].copy(), origin,
                              self.poses[end, :3, 3] - origin)[0]

    def _hull(self, points: np.ndarray, clipped: bool, piece: bool = False):
        """The convex hull of a sweep's points by Qhull (`sweeps.hull_mesh`): the clipped
        candidates, or all points (then trimmed by the clip plane where they cross it); with
        ``piece``, (solid, volume) has its `sweeps.ConvexPiece` third."""
        hull = hull_mesh(points, planes=piece)
        if hull is None:
            return None
        trim = not clipped and points[:, 2].max() > self.clip_z
        built = self._solid(hull[0], hull[1], trim)
        if not piece or not isinstance(built, tuple):
            return built
        return (*built, convex_piece(hull[0], hull[3], self.clip_z if trim else None))

    def _united(self, pieces, clipped: bool):
        """`_hull` of each piece of a split sweep (`tilted_profiles.halves`,
        `tilted_solids.SolidSplitter.pieces`), united, with the pieces' planes (the run
        check's: `_UnitedSweep`)."""
        built = [self._hull(points, clipped, piece=True) for points in pieces
                 if points is not None]
        solids = [b for b in built if isinstance(b, tuple)]
        if not solids:
            return "above" if all(b == "above" for b in built) else None
        if len(solids) == 1:
            return solids[0][:2]
        solid = solids[0][0]
        for other in solids[1:]:
            solid = solid + other[0]
        return _UnitedSweep(solid, solid.volume(), [b[2] for b in solids])

    def hulls(self, keep: Callable[[np.ndarray, np.ndarray], np.ndarray],
              progress: Callable[[int, int], None] | None = None):
        """Clipped sweeps whose point bounds pass ``keep``.

        ``progress(done, total)``, optional, is told how many of the `count` sweeps have
        been looked at, as they are built: building a ball end mill's thousands of sweeps
        takes tens of seconds (a raster of 3,819: 22 s) before anything is cut.

        Returns
        -------
        hulls : Solids
            Each sweep's manifold3d.Manifold, by index (a level pass's is made when first
            read: `DeferredSolid`).
        lower, upper : ndarray, shape (s, 3)
            Bounds of each clipped sweep, m.
        direction : ndarray, shape (s, 3)
            Displacement of the tool tip over each sweep, m.
        n_degenerate : int
        sideways : list of int
            Sweep indices (over all paths) that reach the stock region and drag a
            non-rotational tool sideways.
        swept_volume : float
            Total volume of the clipped sweeps, m^3.
        reached : list of int
            Sweep indices (over all paths) that reach the stock region, degenerate or not.
        footprints : list of Footprint or None
            For each of ``hulls`` that is an upright prism (a flat end mill moved level on
            a level floor), its floor, top and footprint's corners
            (`machinesim.cutting.footprints`); None for the others.
        owners : list of int
            The sweep index (over all paths) of each of ``hulls``, increasing.
        """
        hulls, lower, upper, direction, sideways, reached = Solids(), [], [], [], [], []
        owners, footprints = [], []
        n_degenerate, swept = 0, 0.0
        rotation, origin = self.poses[:, :3, :3], self.poses[:, :3, 3]
        k = len(self.vertices)
        nseg = 0 if self.rotation_segments is None else len(self.rotation_segments)
        step = max(1, POINTS_PER_CHUNK // (2 * k + nseg))
        told = 0
        if progress is not None:
            progress(0, self.count)
        # told about every 1/PROGRESS_STEPS-th of the sweeps: a bar 40 columns wide needs
        # no more, and a cut of 10,000 level passes would redraw it 10,000 times
        every = max(1, self.count // PROGRESS_STEPS)
        for begin in range(0, self.count, step):
            first = self.pairs[begin:begin + step]
            # Only sweeps that come below the clip plane can reach the stock: find them by
            # the tool's lowest point first (most rapids stay above), then transform those.
            lowest = np.minimum(self.lowest(first), self.lowest(first + 1))
            near = np.flatnonzero(lowest <= self.clip_z)
            first = first[near]
            r0, r1 = rotation[first], rotation[first + 1]
            move = origin[first + 1] - origin[first]
            p0, p1 = self.world(first), self.world(first + 1)
            same = np.abs(r1 - r0).reshape(-1, 9).max(axis=1) <= SAME_ORIENTATION
            # A tool turned by no more than `TWIST_M` at any vertex is cut as translated.
            turned = ~same & (np.abs(p1 - p0 - move[:, None, :]).max(axis=(1, 2)) <= TWIST_M)
            if turned.any():
                same = same | turned
                p1[turned] = p0[turned] + move[turned, None, :]
            low = np.minimum(p0.min(axis=1), p1.min(axis=1))
            high = np.maximum(p0.max(axis=1), p1.max(axis=1))
            if self.planar:
                # The bounds of the part below the plane: tall bodies beside a window or
                # a groove are not sweeps that reach it (and sweeps wholly above it, most
                # rapids, need no more work).
                below = low[:, 2] <= self.clip_z
                for rows, segments in ((same & below, self.translation_segments),
                                       (~same & below, self.rotation_segments)):
                    if rows.any() and segments is not None:
                        points = np.concatenate([p0[rows], p1[rows]], axis=1)
                        low[rows], high[rows] = clipped_bounds(points, segments, self.clip_z)
            chosen = np.flatnonzero(keep(low, high))
            if not self.rotational:
                drag = dragged(r0[chosen], move[chosen])
                sideways.extend((begin + near[chosen[drag]]).tolist())
            # Profiles translated are prisms (`_prism`); every other sweep is the hull of
            # its clipped candidates, or of all its points, trimmed, where there are too
            # many for the pair search.
            level = same & self.planar
            minkowski = same & (self.solid_sweep is not None)
            # A sweep that turns: each vertex's height changes by at most `rise` along
            # it (linearly, between the poses the hull joins), so what lies higher than
            # clip_z + rise at either pose never comes below the clip plane. Each pose is
            # clipped there first (its own edges' crossings), and the hull trimmed at the
            # plane. The hull of the whole body at both poses, clipped after, reached past
            # the ends of a rotary groove where a tall V's flanks cross the C axis (78 nm
            # for a v:90 0.1 mm deep, 0.3 mm off the axis; found by the exactness audit).
            rise = np.abs(p1[:, :, 2] - p0[:, :, 2]).max(axis=1)
            candidates, raised, split = {}, set(), {}
            rows = chosen[same[chosen] & ~level[chosen] & ~minkowski[chosen]]
            if len(rows):
                points = np.concatenate([p0[rows], p1[rows]], axis=1)
                candidates.update(zip(rows.tolist(),
                                      self._clip(points, self.translation_segments),
                                      strict=True))
            rows = chosen[~same[chosen]]
            if len(rows):
                points = np.concatenate([p0[rows], p1[rows]], axis=1)
                candidates.update(zip(rows.tolist(), self._clip(
                    points, self.pose_edges, self.clip_z + rise[rows]), strict=True))
                # the hull reaches at most rise above the clip plane, itself above the
                # stock: trimmed only where that is more than `RAISED_UNTRIMMED_M`
                raised.update(rows[rise[rows] > RAISED_UNTRIMMED_M].tolist())
                if self.planar:  # a profile tilted across itself: two halves' hulls
                    split = split_sweeps(self.vertices, rows, p0, p1, r0, r1, origin[first],
                                         origin[first + 1], self.clip_z + rise)
                elif self.splitter is not None:  # a solid tilted across its sides
                    ends = origin[first + 1]
                    for row in rows[self.splitter.crossing(rows, r0, r1, origin[first], ends,
                                                           self.clip_z + rise)].tolist():
                        pieces = self.splitter.pieces(r0[row], origin[first[row]], r1[row],
                                                      ends[row], self.clip_z + rise[row])
                        if pieces is not None:
                            split[row] = pieces
            prisms = {}
            rows = chosen[level[chosen]]
            if len(rows):
                prisms = dict(zip(rows.tolist(), clipped_prisms(
                    p0[rows], move[rows], self.clip_z + np.abs(move[rows, 2])), strict=True))
            for row in chosen.tolist():
                if progress is not None and begin + int(near[row]) >= told + every:
                    told = begin + int(near[row])
                    progress(told, self.count)
                if level[row]:
                    built = self._prism(prisms[row], p0[row], move[row])
                elif minkowski[row]:
                    built = self._translated(r0[row], origin[first[row]], move[row], p0[row])
                elif row in split:
                    built = self._united(split[row], clipped=row not in raised)
                else:
                    points = candidates[row]
                    built = ("above" if points is None
                             else self._hull(points, clipped=row not in raised))
                if built == "above":
                    continue
                if built is None:
                    n_degenerate += 1
                    reached.append(begin + int(near[row]))
                    continue
                solid, volume = built[:2]
                solid_tool = len(built) < 3 or built[2] is None or len(built) > 3
                if len(built) > 2 and built[2] is not None:  # a prism: its vertices' bounds
                    # (a footprint's top is the clip plane: its move is level)
                    box = np.concatenate([built[2].min(axis=0), built[2].max(axis=0)])
                else:
                    box = np.array(solid.bounding_box())
                    box[5] = min(box[5], self.clip_z)  # an untrimmed flat end mill's top
                if solid_tool and not keep(box[None, :3], box[None, 3:])[0]:
                    continue  # a solid tool's body only passed by its unclipped bounds
                reached.append(begin + int(near[row]))
                owners.append(begin + int(near[row]))
                # a ball's sweep is made again when a tile reads it: kept, all of them took
                # 23 GB for a 100,000-line program before the first tile was cut
                if REBUILD_BALL_SWEEPS and isinstance(built, _BallSweep):
                    hulls.append(RebuiltSolid(self.ball_sweep, int(first[row])))
                else:
                    hulls.append(UnitedSolid(solid, built.pieces)
                                 if isinstance(built, _UnitedSweep) else solid)
                footprints.append(built[3] if len(built) > 3 else None)
                lower.append(box[:3])
                upper.append(box[3:])
                direction.append(move[row])
                swept += volume
        if progress is not None:
            progress(self.count, self.count)
        shape = (-1, 3)
        return (hulls, np.array(lower).reshape(shape), np.array(upper).reshape(shape),
                np.array(direction).reshape(shape), n_degenerate, sideways, swept, reached,
                footprints, owners)

    def pose_bounds(self):
        """Bounds (N, 3) of the tool below the clip plane at every pose (+inf / -inf where
        it lies wholly above), m."""
        low = np.full((len(self.poses), 3), np.inf)
        high = np.full((len(self.poses), 3), -np.inf)
        step = max(1, POINTS_PER_CHUNK // (len(self.vertices) + len(self.edges)))
        reaching = np.flatnonzero(self.lowest(slice(None)) <= self.clip_z)
        for begin in range(0, len(reaching), step):
            rows = reaching[begin:begin + step]
            low[rows], high[rows] = clipped_bounds(self.world(rows), self.edges, self.clip_z)
        return low, high


class _BallSweep(tuple):
    """(solid, volume) of a ball end mill's sweep that `SweepSet.ball_sweep` makes again
    from its poses alone (`hulls` keeps it as a `RebuiltSolid`)."""


class _UnitedSweep(tuple):
    """(solid, volume) of a sweep `SweepSet._united` made of convex pieces, and the pieces
    (`sweeps.ConvexPiece`) as ``pieces`` (`hulls` keeps it as a `UnitedSolid`)."""

    def __new__(cls, solid, volume: float, pieces):
        built = super().__new__(cls, (solid, volume))
        built.pieces = pieces
        return built
