"""Which rapids (G00) cut: those whose sweep met material still there when they ran.

`machinesim.cutting.cut` cuts every move, rapids included, and asks `rapids_that_cut` which
rapids met material: the stock less every earlier sweep that could have taken it away,
found by box, tried latest first, and past `RAPID_EARLIER_UNION` of them by meeting solids
(docs/cutting.md, "Rapids that cut are cut").
"""

from __future__ import annotations

from collections import OrderedDict
from typing import TYPE_CHECKING

import manifold3d
import numpy as np

from machinesim.cutting.boxgrid import BoxGrid
from machinesim.cutting.containment import CONTAINED_REL, vertices_and_planes
from machinesim.cutting.frame import into_frame, tool_frame
from machinesim.cutting.sweeps import (
    SolidSweep,
    hull_mesh,
    manifold_from,
    mesh_volume,
    prism_triangles,
)
from machinesim.cutting.sweepset import POINTS_PER_CHUNK
from machinesim.tolerances import (
    RAPID_CUT_VOLUME_M3,
    RAPID_EDGE_HALF_THICKNESS_M,
    SAME_ORIENTATION,
    SHEET_M,
)
from machinesim.workpiece import Part

if TYPE_CHECKING:
    from machinesim.cutting.tool_runs import _Moves

__all__ = ["rapids_that_cut"]

#: A rapid that reaches the stock is checked against the sweeps before it that could have
#: taken away what it meets: those whose boxes overlap it, and past this many (a rapid
#: across a field of grooves, a V tool whose box is far wider than its tip) those whose
#: solids meet it.
RAPID_EARLIER_UNION = 64
#: The sweeps just before a rapid are taken away from what it meets first, alone: when they
#: leave nothing (a retract at the end of a cut), no union of the earlier ones is needed.
RAPID_RECENT_SWEEPS = 8
#: Before any boolean, up to this many earlier sweeps whose boxes hold the box of what a
#: rapid met are asked, latest first, whether one holds it whole (`_Earlier.held`): a rapid
#: down a hole an earlier move cut, a retract up its own plunge. Each sweep is convex, so
#: that is a test of vertices against face planes, where subtracting the recent sweeps'
#: union took 60 ms a rapid (a star of 180 spokes, each begun by a rapid down into the hub
#: the spokes before had cut: 34 of its 38 s).
RAPID_HOLDERS = 16
#: The solids (and face planes) of this many sweeps last built are kept: a rapid's own
#: sweep, built to meet the stock, is the first the next rapid asks whether it holds what it
#: met (a rapid down to a hole, then back up), and the holders are the latest sweeps.
RAPID_KEPT_SOLIDS = 2 * RAPID_HOLDERS


def rapids_that_cut(stock: Part, tool, poses: np.ndarray, moves: _Moves,
                    reached: np.ndarray, roi=None) -> tuple[int, ...]:
    """Lines of rapids whose sweep met material still there when they ran.

    A zero-thickness edge plunging into material sweeps no volume, so the check thickens a
    profile by `RAPID_EDGE_HALF_THICKNESS_M` along the tool's X (here only). Candidates are
    the rapid sweeps the engine found reaching the stock (``reached``); each is intersected
    with the stock (inside the ``roi`` windows when given: the part is cut there alone), less
    the earlier sweeps that reached the stock and could have taken some of it away (`_Earlier`):
    first the last `RAPID_RECENT_SWEEPS` of them alone (a retract at the end of a cut is then
    done), then the rest (past `RAPID_EARLIER_UNION` of them, those whose solids meet what
    is left), each taken away in turn (`_Earlier.subtract`): exact, and free for rapids that
    stay clear.
    """
    candidates = reached[moves.sweep_rapid[reached]]
    if not len(candidates):
        return ()
    from machinesim.cutting.windows import clip_to  # windows builds on cutting.program

    frame = tool_frame(poses, tool)
    if frame is not None:
        # A tilted tool: judged where it stands upright, as the engine cuts it
        # (`cutting.frame`): in the workpiece frame a retract's faces meet the last pass's
        # only to round-off, and the booleans took a retract for a cut.
        windows = None if roi is None else np.reshape(roi, (-1, 4)).tolist()
        stock, (poses,) = into_frame(stock, [poses], frame, windows)
        roi = None
    shape = _Thick(tool)
    material = (stock.manifold if roi is None
                else clip_to(stock, np.reshape(roi, (-1, 4))).manifold)
    sweeps = _Earlier(shape, poses, moves, reached)
    # a vertex of what a rapid met may stand this far outside a sweep that holds it (the
    # engine's tolerance for a sweep inside another, `containment`)
    tol = CONTAINED_REL * (float(np.abs(np.array(material.bounding_box())).max()) or 1.0)
    found = []
    for sweep in np.sort(candidates):
        swept = sweeps.solid(sweep)
        if swept is None:
            continue
        hit = material ^ swept
        if hit.volume() <= RAPID_CUT_VOLUME_M3 or sweeps.held(sweep, hit, tol):
            continue
        earlier = sweeps.overlapping(sweep, hit)
        hit = sweeps.subtract(hit, earlier[-RAPID_RECENT_SWEEPS:])
        if hit.volume() <= RAPID_CUT_VOLUME_M3:
            continue
        earlier = earlier[:-RAPID_RECENT_SWEEPS]
        if len(earlier) > RAPID_EARLIER_UNION:
            earlier = sweeps.meeting(earlier, hit)
        hit = sweeps.subtract(hit, earlier)
        if _material_left(hit):
            found.append(int(moves.sweep_line[sweep]))
    return tuple(dict.fromkeys(found))


def _material_left(solid) -> bool:
    """Whether ``solid`` (what a rapid met, less what earlier sweeps took) holds material,
    not round-off: more than `RAPID_CUT_VOLUME_M3`, in a piece thicker on average (twice its
    volume over its surface) than `tolerances.SHEET_M`. Faces that coincide in exact
    arithmetic meet to round-off, which grows with the coordinates: a retract straight up
    its own plunge at x = y = -75 mm left a film 2.5e-18 m thick and 6.6e-24 m^3, above the
    volume alone, and was listed as a rapid that cut."""
    if solid.volume() <= RAPID_CUT_VOLUME_M3:
        return False
    return any(piece.volume() > RAPID_CUT_VOLUME_M3
               and 2.0 * piece.volume() > SHEET_M * piece.surface_area()
               for piece in solid.decompose())


class _Earlier:
    """The sweeps a rapid is judged against: those that reached the stock, as thickened
    solids (each built once), found by box (through a `BoxGrid` of their boxes: comparing
    every earlier box for each rapid grew as the square of the rapids) and, where many boxes
    overlap, by meeting."""

    def __init__(self, shape, poses: np.ndarray, moves: _Moves, reached: np.ndarray) -> None:
        self.shape, self.poses, self.moves = shape, poses, moves
        self.reached = np.sort(reached)
        self.low, self.high = shape.bounds(poses, moves.sweep_start[self.reached])
        self.grid = BoxGrid(self.low, self.high)
        self._solids: dict[int, object] = {}
        self._recent: OrderedDict[int, object] = OrderedDict()
        self._planes: OrderedDict[int, tuple] = OrderedDict()

    def solid(self, sweep: int, keep: bool = False):
        """The thickened tool's solid of ``sweep``, or None when it sweeps no volume; kept
        for the next rapid when ``keep`` (those tested for meeting, which the next rapid
        across the same grooves tests again), else among the last `RAPID_KEPT_SOLIDS`
        built (memory)."""
        if sweep in self._solids:
            return self._solids[sweep]
        if sweep in self._recent:
            self._recent.move_to_end(sweep)
            return self._recent[sweep]
        a = self.moves.sweep_start[sweep]
        solid = self.shape.solid(self.poses[a], self.poses[a + 1])
        if keep:
            self._solids[sweep] = solid
        else:
            _keep_recent(self._recent, sweep, solid)
        return solid

    def planes(self, sweep: int, solid) -> tuple:
        """The unit normals and offsets of ``solid``'s (``sweep``'s) faces, the last
        `RAPID_KEPT_SOLIDS` kept."""
        if sweep in self._planes:
            self._planes.move_to_end(sweep)
            return self._planes[sweep]
        planes = vertices_and_planes(solid)[1:]
        _keep_recent(self._planes, sweep, planes)
        return planes

    def _before(self, sweep: int, low: np.ndarray, high: np.ndarray) -> np.ndarray:
        """Positions (in ``reached``, ascending) of the reached sweeps before ``sweep`` whose
        boxes may overlap the box ``low``, ``high``: every one that does, and a few more."""
        return self.grid.candidates(low, high, int(np.searchsorted(self.reached, sweep)))

    def overlapping(self, sweep: int, hit) -> np.ndarray:
        """Reached sweeps before ``sweep`` whose boxes overlap ``hit``'s, in program order."""
        low, high = np.array(hit.bounding_box()).reshape(2, 3)
        near = self._before(sweep, low, high)
        inside = (np.all(self.high[near] >= low, axis=1)
                  & np.all(self.low[near] <= high, axis=1))
        return self.reached[near[inside]]

    def _holding(self, sweep: int, low: np.ndarray, high: np.ndarray) -> np.ndarray:
        """Positions (in ``reached``) of the last `RAPID_HOLDERS` reached sweeps before
        ``sweep`` whose boxes reach below ``low`` and above ``high`` on every axis, latest
        first. When ``low`` <= ``high``, such a box holds the point midway, so it is listed
        in that point's cell of the grid or among its wide boxes; the cell's are tried back
        from the latest, in runs that double, until enough hold (retracts and plunges are
        held by the moves just before them). Otherwise (a box thinner than twice the
        tolerance) it overlaps the box between them, and those that may are tried."""
        k = int(np.searchsorted(self.reached, sweep))
        if np.all(low <= high):
            listed, wide = self.grid.at(0.5 * (low + high), k)
        else:
            listed = self.grid.candidates(np.minimum(low, high), np.maximum(low, high), k)
            wide = listed[:0]

        def holding(positions):
            return positions[np.all(self.low[positions] <= low, axis=1)
                             & np.all(self.high[positions] >= high, axis=1)][::-1]

        found, end, size = [holding(wide)], len(listed), RAPID_HOLDERS
        while end > 0 and sum(len(f) for f in found[1:]) < RAPID_HOLDERS:
            begin = max(0, end - size)
            found.append(holding(listed[begin:end]))
            end, size = begin, 2 * size
        return np.sort(np.concatenate(found))[::-1][:RAPID_HOLDERS]

    def held(self, sweep: int, hit, tol: float) -> bool:
        """Whether one of the last `RAPID_HOLDERS` reached sweeps before ``sweep`` whose boxes
        hold ``hit``'s box holds ``hit`` whole: every vertex of it within ``tol`` inside
        every face plane of that sweep's solid (convex: a tool's convex body or thickened
        profile swept along a segment, or a hull)."""
        low, high = np.array(hit.bounding_box()).reshape(2, 3)
        candidates = self.reached[self._holding(sweep, low + tol, high - tol)]
        if not len(candidates):
            return False
        vertices = vertices_and_planes(hit)[0]
        for k in candidates.tolist():
            solid = self.solid(k)
            if solid is None:
                continue
            normal, offset = self.planes(k, solid)
            if float((vertices @ normal.T - offset).max()) <= tol:
                return True
        return False

    def meeting(self, sweeps: np.ndarray, hit) -> np.ndarray:
        """Those of ``sweeps`` whose solids share volume with ``hit``: a tall tool's box
        (a V 10 mm high is 20 mm wide at its top) overlaps far more than its tip cuts."""
        return np.array([k for k in sweeps
                         if (solid := self.solid(k, keep=True)) is not None
                         and (solid ^ hit).volume() > 0.0], dtype=np.int64)

    def subtract(self, hit, sweeps: np.ndarray):
        """``hit`` less the union of ``sweeps``' solids, each taken away in turn (those whose
        boxes share the most of ``hit``'s first) until no more than `RAPID_CUT_VOLUME_M3` is
        left, which the rest can only make less. Uniting them first cost more than all the
        differences: in a field of plunges 0.1 mm apart with a flat:0.2, each rapid down
        into the cut met some 100 sweeps whose flat ends and walls coincide, and their union
        took 0.6 s a rapid (benchmarks/rapids.py --case plunge)."""
        low, high = np.array(hit.bounding_box()).reshape(2, 3)
        at = np.searchsorted(self.reached, sweeps)
        shared = np.prod(np.clip(np.minimum(self.high[at], high)
                                 - np.maximum(self.low[at], low), 0.0, None), axis=1)
        for k in sweeps[np.argsort(-shared, kind="stable")].tolist():
            solid = self.solid(k)
            if solid is None:
                continue
            hit = hit - solid
            if hit.volume() <= RAPID_CUT_VOLUME_M3:
                break
        return hit

    def union(self, sweeps: np.ndarray):
        """The union of ``sweeps``' solids, or an empty solid (`benchmarks/rapids.py` times
        `subtract` against taking it away)."""
        solids = [s for s in (self.solid(k) for k in sweeps) if s is not None]
        if not solids:
            return manifold3d.Manifold()
        return manifold3d.Manifold.batch_boolean(solids, manifold3d.OpType.Add)


def _keep_recent(kept: OrderedDict, key: int, value) -> None:
    """Keep ``value`` under ``key``, dropping the least recently used past
    `RAPID_KEPT_SOLIDS`."""
    kept[key] = value
    if len(kept) > RAPID_KEPT_SOLIDS:
        kept.popitem(last=False)


class _Thick:
    """The tool as a solid for the rapid check: a profile thickened along its X."""

    def __init__(self, tool) -> None:
        vertices = np.asarray(tool.vertices(), dtype=np.float64)
        if getattr(tool, "planar", False):
            shift = np.array([RAPID_EDGE_HALF_THICKNESS_M, 0.0, 0.0])
            self.vertices = np.concatenate([vertices - shift, vertices + shift])
            triangles = prism_triangles(len(vertices)).astype(np.int64)
            volume = mesh_volume(self.vertices, triangles)
            self.triangles = triangles if volume > 0.0 else triangles[:, ::-1]
        else:
            self.vertices, self.triangles = vertices, np.asarray(tool.triangles())
        self.sweep = SolidSweep(self.vertices, self.triangles)
        self.run_id = manifold3d.Manifold.reserve_ids(1)

    def bounds(self, poses: np.ndarray, starts: np.ndarray):
        """Bounds (s, 3) of the sweeps starting at poses ``starts`` (the points of both
        poses, which contain the hull), m."""
        low, high = np.empty((len(starts), 3)), np.empty((len(starts), 3))
        step = max(1, POINTS_PER_CHUNK // (2 * len(self.vertices)))
        for begin in range(0, len(starts), step):
            a = starts[begin:begin + step]
            points = np.concatenate(
                [np.einsum("nij,kj->nki", poses[i][:, :3, :3], self.vertices)
                 + poses[i][:, None, :3, 3] for i in (a, a + 1)], axis=1)
            low[begin:begin + step] = points.min(axis=1)
            high[begin:begin + step] = points.max(axis=1)
        return low, high

    def solid(self, start: np.ndarray, end: np.ndarray) -> manifold3d.Manifold | None:
        """The thickened tool swept from pose ``start`` to ``end`` (4, 4), or None."""
        rotation = start[:3, :3]
        if np.abs(end[:3, :3] - rotation).max() <= SAME_ORIENTATION:
            vertices, triangles = self.sweep.mesh(rotation, start[:3, 3],
                                                  end[:3, 3] - start[:3, 3])
        else:
            points = np.concatenate([self.vertices @ m[:3, :3].T + m[:3, 3]
                                     for m in (start, end)])
            hull = hull_mesh(points)
            if hull is None:
                return None
            vertices, triangles = hull[0], hull[1]
        return manifold_from(vertices, triangles, self.run_id)
