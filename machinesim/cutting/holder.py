"""Whether the tool's holder meets the part: the top of the tool's body, where the holder
begins, against the stock's box (`holder_contact`), then against the material the tool has
left (`holder_in_material`, in the room the holder takes over a sweep, `holder_room`).

`machinesim.cutting.engine.remove` asks these of its `SweepSet` before it cuts; a program
whose holder would enter the stock is refused (`HolderContactError`, docs/cutting.md).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import manifold3d
import numpy as np
from scipy.spatial import ConvexHull, HalfspaceIntersection, QhullError

from machinesim.cutting.containment import (
    CONTAINED_CANDIDATES,
    CONTAINED_REL,
    contained_sweeps,
    vertices_and_planes,
)
from machinesim.cutting.frame import into_frame, tool_frame
from machinesim.cutting.holder_allowance import turned_lent
from machinesim.cutting.sweeps import hull_mesh, manifold_from
from machinesim.cutting.sweepset import POINTS_PER_CHUNK, SweepSet
from machinesim.exceptions import InputError
from machinesim.tolerances import CLIP_MARGIN_REL, SAME_ORIENTATION

if TYPE_CHECKING:
    from machinesim.workpiece import Part

__all__ = ["HOLDER_MATERIAL_M3", "check_holder", "holder_contact", "holder_in_material",
           "holder_reach", "holder_room", "judge_holder"]

#: Material inside the holder's room over a sweep (m^3) above which the holder meets the part:
#: 1 um x 1 um x 1 nm. A body cut flush to its top leaves round-off slivers (1e-19 m thick
#: over a few mm^2: ~1e-25 m^3) far below it; any real contact is far above.
HOLDER_MATERIAL_M3 = 1e-21


def judge_holder(sweeps: SweepSet, stock: Part, on_holder_contact=None,
                 tolerance=0.0, lent=None) -> tuple[int, ...]:
    """The sweeps of ``sweeps`` whose holder meets ``stock``, anywhere over it: those whose
    body top comes below the stock's top within its box (`holder_contact`), and, with
    ``on_holder_contact`` (a refusal), of those only the ones whose room holds material the
    earlier sweeps left (`holder_in_material`, within ``tolerance``, m, one value or one per
    sweep: a chord, `holder_allowance`; a borrowed one only where ``lent`` says),
    ``on_holder_contact`` called with them.

    The whole stock, never a window of it: the holder meeting the part outside the windows
    a cut is read in is a crash all the same (a holder crash at x = 8 mm was cut, exit 0,
    with --roi 0,3,0,10, and refused without it).
    """
    holder = _box_step(sweeps, stock)
    if holder and on_holder_contact is not None:
        # the stock's box says it may; before refusing, the material says whether it does
        holder = tuple(holder_in_material(sweeps, holder, stock.manifold, _reach(stock),
                                          _region(stock), tolerance, lent))
        if holder:
            on_holder_contact(holder)
    return holder


def _box_step(sweeps: SweepSet, stock: Part) -> tuple[int, ...]:
    """`judge_holder`'s first step: the sweeps whose body top comes below the stock's top
    within its box (`holder_contact`), the box met as the engine's cell over the whole
    stock meets it: a margin more across (the cell's own, and the one it is met with)."""
    bounds = stock.bounds
    margin = CLIP_MARGIN_REL * (float(np.abs(bounds).max()) or 1.0)
    low, high = bounds[0] - margin, bounds[1] + margin
    wide = np.array([margin, margin, 0.0])
    return tuple(holder_contact(
        sweeps, bounds[1, 2],
        lambda lo, hi: (lo <= high + wide).all(axis=1) & (hi >= low - wide).all(axis=1)))


def _reach(stock: Part) -> float:
    """How far a holder's room is lifted (m): past the stock whatever its tilt."""
    bounds = stock.bounds
    scale = float(np.abs(bounds).max()) or 1.0
    return 2.0 * float(np.linalg.norm(bounds[1] - bounds[0])) + scale


def _region(stock: Part):
    """The stock's region, as `SweepSet.hulls` takes it: boxes meeting its box (with the
    clip margin)."""
    bounds = stock.bounds
    margin = CLIP_MARGIN_REL * (float(np.abs(bounds).max()) or 1.0)
    low, high = bounds[0] - margin, bounds[1] + margin

    def whole(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
        return (lo <= high).all(axis=1) & (hi >= low).all(axis=1)

    return whole


def check_holder(stock: Part, tool, paths: list[np.ndarray], on_holder_contact=None,
                 tolerance=0.0, lent=None) -> tuple[int, ...]:
    """`judge_holder` for ``tool`` along ``paths`` (workpiece frame, in program order)
    over ``stock``, without cutting: for a caller that cuts the sweeps in another order
    (`machinesim.cutting.cut_turned`, by turn groups), since the material a holder meets
    is what the sweeps before it, in the program's order, left. A tilted end mill that does
    not turn is judged in its own frame, as `machinesim.cutting.remove` judges it; one that
    stands in several orientations (a tilted workpiece at several C), leg by leg in each
    leg's frame (`machinesim.cutting.holder_legs`)."""
    paths = _one_sweep_each(paths)
    if not paths:
        return ()
    scale = float(np.abs(stock.bounds).max()) or 1.0
    z_high = stock.bounds[1, 2] + CLIP_MARGIN_REL * scale
    sweeps = SweepSet(tool, paths, z_high)
    frame = tool_frame(sweeps.poses, tool) if sweeps.count else None
    if frame is not None:
        stock, paths = into_frame(stock, paths, frame)
        z_high = stock.bounds[1, 2] + CLIP_MARGIN_REL * scale
        sweeps = SweepSet(tool, paths, z_high)
        lent = turned_lent(lent, frame.T)
    elif on_holder_contact is not None and sweeps.count:
        from machinesim.cutting.holder_legs import in_material_by_legs
        from machinesim.cutting.holder_legs import legs as tool_legs

        legs = tool_legs(paths, tool)
        if legs is not None:
            holder = _box_step(sweeps, stock)
            if holder:
                holder = tuple(in_material_by_legs(stock, tool, paths, legs, holder,
                                                    tolerance, lent))
            if holder:
                on_holder_contact(holder)
            return holder
    return judge_holder(sweeps, stock, on_holder_contact, tolerance, lent)


def holder_reach(stock: Part, tool, paths: list[np.ndarray]):
    """The box (xmin, xmax, ymin, ymax), m, over which the holders of ``tool`` along
    ``paths`` may meet ``stock``: the rooms' (`holder_room`) of the sweeps `holder_contact`
    finds over the stock's whole box, or None when it finds none. `machinesim.cutting.cut`
    reads what earlier tools left there when it cuts within windows."""
    paths = _one_sweep_each(paths)
    if not paths:
        return None
    bounds = stock.bounds
    scale = float(np.abs(bounds).max()) or 1.0
    low, high = bounds[0] - CLIP_MARGIN_REL * scale, bounds[1] + CLIP_MARGIN_REL * scale
    sweeps = SweepSet(tool, paths, high[2])
    found = holder_contact(sweeps, bounds[1, 2],
                           lambda lo, hi: (lo <= high).all(axis=1) & (hi >= low).all(axis=1))
    if not found:
        return None
    reach = 2.0 * float(np.linalg.norm(bounds[1] - bounds[0])) + scale
    face = _holder_top(sweeps.holder_face)
    local = np.concatenate([face, face + [0.0, 0.0, reach]])
    first = sweeps.pairs[np.asarray(found)]
    poses = sweeps.poses[np.concatenate([first, first + 1])]
    points = (local @ poses[:, :3, :3].transpose(0, 2, 1) + poses[:, None, :3, 3])
    points = points.reshape(-1, 3)
    least, most = points.min(axis=0), points.max(axis=0)
    return (float(least[0]), float(most[0]), float(least[1]), float(most[1]))


def _one_sweep_each(paths) -> list[np.ndarray]:
    """``paths`` with a path of one pose given twice: the tool standing there is one sweep,
    as `machinesim.cutting.remove` takes it."""
    return [np.concatenate([poses, poses]) if len(poses) == 1 else np.asarray(poses)
            for poses in paths if len(poses)]


def holder_contact(sweeps: SweepSet, below: float, keep) -> list[int]:
    """The sweeps of ``sweeps`` (indices over all paths) in which the top of the tool's
    body, where the holder begins, comes below ``below`` (the stock top) where ``keep``
    finds stock. The holder rises from that face through ``below``, so its box, not the
    face's, is what ``keep`` tests: a body taken wholly below the stock (a tool longer than
    the program's, without its G43) has its holder through the stock, not clear of it."""
    found = []
    face = sweeps.holder_face
    step = max(1, POINTS_PER_CHUNK // (2 * len(face)))
    for begin in range(0, sweeps.count, step):
        first = sweeps.pairs[begin:begin + step]
        t0, t1 = (face @ sweeps.poses[k, :3, :3].transpose(0, 2, 1)
                  + sweeps.poses[k, None, :3, 3] for k in (first, first + 1))
        low = np.minimum(t0.min(axis=1), t1.min(axis=1))
        high = np.maximum(t0.max(axis=1), t1.max(axis=1))
        high[:, 2] = np.maximum(high[:, 2], below)  # the holder, up through the top
        hit = (low[:, 2] < below) & keep(low, high)
        found.extend((begin + np.flatnonzero(hit)).tolist())
    return found


def holder_in_material(sweeps: SweepSet, candidates, solid: manifold3d.Manifold,
                       reach: float, keep=None, tolerance=0.0, lent=None) -> list[int]:
    """Those of the sweeps ``candidates`` whose holder meets ``solid`` as this tool has cut
    it by then: more than `HOLDER_MATERIAL_M3` of it inside the holder's room over the sweep
    (`holder_room`), in the order given. The bounding-box test of `holder_contact` finds
    the candidates; this one reads the material, so that a short profile running down a
    face (air over its top) is not a crash.

    With ``keep`` (the stock's region, as `hulls` takes it), the material a sweep's
    holder meets is what the earlier sweeps of these paths left of ``solid``: a slot
    cut in steps down is open to the holder when the steps reach below the body's
    height. Only the earlier sweeps that reach into a room with material are built.

    The material candidate i meets, (solid & room_i) - (hull_0 + ... + hull_(i-1)), is
    (solid - (hull_0 + ... + hull_(i-1))) & room_i: one running material, the solid
    within the rooms' box, is cut by the sweeps in program order, each subtracted once,
    and read in each candidate's room as the walk reaches it (`_Walk`). Before, each
    candidate's material was cut by the earlier sweeps until none was left: candidates x
    earlier sweeps booleans where slivers stay (a helical bore's bottom circle, its chords
    not those of the half turns, 5 min 11 s before its refusal).

    ``tolerance`` (m; one value, or one per sweep of ``sweeps``): how far the holder may
    enter the material, the rooms' faces taken in by as much (`holder_room`'s ``inset``):
    one chord (`machinesim.cutting.holder_allowance`).
    Arcs cut as chords put the holder into walls the body cut by up to one chord where its
    own chords and the body's do not line up (a helical bore's bottom circle under its half
    turns, refused as a crash): each chord lies inside its arc by at most the tolerance, the
    holder at a chord's end reaches the arc's wall, and the body along another's middle cut
    the wall that much short of it.

    ``lent`` ({sweep: (own allowance, m; boxes)}, `holder_allowance.Lent`): a sweep whose
    ``tolerance`` it borrowed from the chorded sweeps that cut next to its holder may enter
    the material by it only inside their boxes, elsewhere by its own: its room is the one
    taken in by ``tolerance``, and outside the boxes the one taken in by its own.
    """
    order = list(dict.fromkeys(int(i) for i in candidates))
    each = np.broadcast_to(np.asarray(tolerance, dtype=np.float64), (sweeps.count,))
    rooms = {i: _room(sweeps, i, reach, float(each[i]), lent.get(i) if lent else None)
             for i in order}
    inside = {}
    for i in sorted(order):
        met = solid ^ rooms[i]
        if met.volume() > HOLDER_MATERIAL_M3:
            inside[i] = met.bounding_box()
    if not inside or keep is None:
        return [i for i in order if i in inside]
    boxes = np.array(list(inside.values())).reshape(-1, 6)

    def into_a_room(low: np.ndarray, high: np.ndarray) -> np.ndarray:
        return keep(low, high) & _meets_any(low, high, boxes)

    hulls, lower, upper, *_, owners = sweeps.hulls(into_a_room)
    low, high = boxes[:, :3].min(axis=0), boxes[:, 3:].max(axis=0)
    material = solid ^ _box(low, high)
    bounds = np.asarray(solid.bounding_box())
    tol = CONTAINED_REL * (float(np.abs(bounds).max()) or 1.0)
    walk = _Walk(material, hulls, lower, upper, tol)
    owners = np.asarray(owners, dtype=np.int64)
    found = set()
    for i in inside:
        # a sweep that takes the tool down its own axis has cut what its room holds of its
        # own body's sweep before the holder came there (`_descends`): counted as earlier
        side = "right" if _descends(sweeps, i) else "left"
        walk.cut(np.arange(walk.done, int(np.searchsorted(owners, i, side=side))))
        if walk.holds(rooms[i]):
            found.add(i)
    return [i for i in order if i in found]


def _descends(sweeps: SweepSet, sweep: int) -> bool:
    """Whether sweep ``sweep`` moves the tool down its own axis without turning (a plunge,
    a ramp), so that its body has cut what its holder meets of the body's own sweep before
    the holder came there: a point the holder covers at time t lies at least the body's
    height H above the tip along the axis a, a point the body covers at t' at most H, so
    a . tip(t') >= a . tip(t), and a . tip falls along the move: t' <= t. A plunge deeper
    than the body had been refused as a crash, its own hole never counted as cut; a move
    back up the axis (the holder there first) or one that turns is not such a sweep."""
    first = sweeps.pairs[sweep]
    start, end = sweeps.poses[first], sweeps.poses[first + 1]
    if np.abs(end[:3, :3] - start[:3, :3]).max() > SAME_ORIENTATION:
        return False
    return float(start[:3, 2] @ (end[:3, 3] - start[:3, 3])) < 0.0


class _Walk:
    """What is left of the material as the walk of `holder_in_material` goes through the
    sweeps in program order: each hull is subtracted once, when the walk first passes it.

    A hull is skipped where it takes nothing more: when its box misses what is left, and
    when the part of it within that box lies inside a hull already subtracted, or inside one
    of the same batch (`contained_sweeps`; within ``tol``, as the engine drops them). The
    rest are subtracted one at a time: a helix's neighbouring sweeps overlap almost wholly,
    and their union cost more (569 sweeps of a bore 1.5 mm deep into a small block: 0.64 s
    one at a time, 13.4 s in the engine's runs, `tiling.union_runs`, 38 s in one
    batch_boolean; measured on a loaded machine). Passes repeated down the same path (a
    helix's turns, a pocket's levels) are the hulls skipped: over the material, the rooms
    above the body, each turn's sweep is the turn's before it, and subtracting it again
    puts faces onto faces, the slowest work manifold3d does (a helical bore 12.8 mm deep:
    the material grew to 190,000 triangles by its 1,800th sweep of 3,834).
    """

    def __init__(self, material: manifold3d.Manifold, hulls, lower: np.ndarray,
                 upper: np.ndarray, tol: float) -> None:
        self.material, self.hulls, self.lower, self.upper = material, hulls, lower, upper
        self.tol = tol
        self.done = 0
        self.box = np.asarray(material.bounding_box())
        self.kept: list[int] = []
        self.kept_boxes = np.zeros((0, 6))
        self.planes: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    def cut(self, batch: np.ndarray) -> None:
        """Subtract the hulls ``batch`` (consecutive indices from `done`)."""
        if len(batch):
            self.done = int(batch[-1]) + 1
        if not len(batch) or self.material.is_empty():
            return
        batch = batch[self._meet(batch)]
        if len(batch) > 1:  # compared within windows: the pairs grow as their square
            windows = [(None, batch[begin:begin + _CONTAINED_WINDOW])
                       for begin in range(0, len(batch), _CONTAINED_WINDOW)]
            batch = batch[~contained_sweeps(self.hulls, self.lower, self.upper, windows,
                                            self.tol)[batch]]
        for j in batch.tolist():
            if not self._meet(np.array([j]))[0]:
                continue
            clipped = self.hulls[j] ^ _box(self.box[:3], self.box[3:])
            if clipped.is_empty():
                continue
            points = vertices_and_planes(clipped)[0]
            if self._inside_kept(points):
                continue
            self.material = self.material - self.hulls[j]
            self.box = np.asarray(self.material.bounding_box())  # evaluated: one at a time
            self.kept.append(j)
            self.kept_boxes = np.concatenate([self.kept_boxes,
                                              np.concatenate([self.lower[j], self.upper[j]])[None]])
            if self.material.is_empty():
                return

    def holds(self, room: manifold3d.Manifold) -> bool:
        """Whether more than `HOLDER_MATERIAL_M3` of what is left lies in ``room``."""
        if self.material.is_empty():
            return False
        room_box = np.asarray(room.bounding_box())
        if ((room_box[:3] > self.box[3:]) | (room_box[3:] < self.box[:3])).any():
            return False
        return (self.material ^ room).volume() > HOLDER_MATERIAL_M3

    def _meet(self, batch: np.ndarray) -> np.ndarray:
        return ((self.lower[batch] <= self.box[3:]).all(axis=1)
                & (self.upper[batch] >= self.box[:3]).all(axis=1))

    def _inside_kept(self, points: np.ndarray) -> bool:
        """Whether ``points`` lie within `tol` inside one of the latest kept hulls whose box
        holds theirs (at most `CONTAINED_CANDIDATES` of them tested)."""
        if not self.kept:
            return False
        low, high = points.min(axis=0), points.max(axis=0)
        holds = np.flatnonzero((self.kept_boxes[:, :3] <= low + self.tol).all(axis=1)
                               & (self.kept_boxes[:, 3:] >= high - self.tol).all(axis=1))
        for k in holds[::-1][:CONTAINED_CANDIDATES].tolist():
            j = self.kept[k]
            if j not in self.planes:
                self.planes[j] = vertices_and_planes(self.hulls[j])[1:]
            normal, offset = self.planes[j]
            if float((points @ normal.T - offset).max()) <= self.tol:
                return True
        return False


def _room(sweeps: SweepSet, sweep: int, reach: float, inset: float,
          lent=None) -> manifold3d.Manifold:
    """The holder's room over sweep ``sweep`` taken in by ``inset`` (`holder_room`), but by
    a borrowed ``inset`` only inside the lenders' boxes: ``lent`` (its own allowance, m; the
    boxes, in the frame of ``sweeps``: `holder_allowance.Lent`'s entry), outside them the
    room taken in by its own. None: ``inset`` throughout."""
    room = holder_room(sweeps, sweep, reach, inset)
    if lent is None:
        return room
    own, boxes = lent
    return room + (holder_room(sweeps, sweep, reach, own) - boxes)


def _box(low, high) -> manifold3d.Manifold:
    """The box from corner ``low`` to corner ``high``."""
    low = np.asarray(low, dtype=np.float64)
    return manifold3d.Manifold.cube(tuple(np.asarray(high) - low)).translate(tuple(low))


def holder_room(sweeps: SweepSet, sweep: int, reach: float,
                inset: float = 0.0) -> manifold3d.Manifold:
    """The room the holder takes over sweep ``sweep``: the hull of the body's top face
    at both poses and of the same face lifted ``reach`` along the tool axis. A top that
    is a segment (a V's or a nose's, along Y) is widened across it (along the tool's X) to
    its own length, as the bar that carries the tool is (`_holder_top`); a top of no
    width (a point) is refused, InputError, not taken for an empty room.

    The hull is Qhull's (`sweeps.hull_mesh`), exact to float64 round-off, as the sweeps'
    are: manifold3d's QuickHull drops points within about 1e-7 of the largest coordinate of a
    plane, so the room of a tool a few nm wide, ~30 mm tall over a 10 mm block, came out
    empty, and a 2 nm ball 2 nm high cut 20 um deep with no holder contact.

    ``inset`` (m, >= 0): the face is taken that much in from its edges first (`_inset`), the
    holder's tolerance, one chord of the paths (`holder_in_material`).
    """
    face = _inset(_holder_top(sweeps.holder_face), inset)
    local = np.concatenate([face, face + [0.0, 0.0, reach]])
    first = sweeps.pairs[sweep]
    poses = sweeps.poses[[first, first + 1]]
    points = (local @ poses[:, :3, :3].transpose(0, 2, 1) + poses[:, None, :3, 3])
    hull = hull_mesh(points.reshape(-1, 3))
    room = None if hull is None else manifold_from(hull[0], hull[1], _ROOM_ID)
    if room is None:  # a face of width (`_holder_top`) lifted by reach > 0 is no flat set
        raise InputError(f"the holder's room over sweep {sweep} is flat (its face "
                         f"{np.ptp(face, axis=0).tolist()} m wide, lifted {reach:g} m): "
                         "the tool's body has no top for a holder to begin on, and the "
                         "holder check would pass any cut", key="tool")
    return room


def _holder_top(face: np.ndarray) -> np.ndarray:
    """The holder's face from the body's top ``face`` (k, 3), widened where it is a segment:
    along X (a V's or a nose's top, in the YZ plane), or across it for a segment lying
    elsewhere in XY, to its own length. A segment's room (the face lifted, at two poses) is
    flat for any move in the segment's plane: Qhull finds no hull, and the room was empty."""
    if float(np.ptp(face[:, 0])) <= 0.0:
        half = 0.5 * max(float(np.ptp(face[:, 1])), float(np.ptp(face[:, 2])))
        return np.concatenate([face + [half, 0.0, 0.0], face - [half, 0.0, 0.0]])
    xy = face[:, :2] - face[:, :2].mean(axis=0)
    spread = np.linalg.svd(xy, compute_uv=False) if len(face) > 1 else np.zeros(2)
    if spread.size > 1 and spread[1] > _SEGMENT_REL * spread[0]:
        return face
    along = np.linalg.svd(xy)[2][0]
    across = np.array([-along[1], along[0], 0.0])
    half = 0.5 * float(np.ptp(xy @ along))
    return np.concatenate([face + half * across, face - half * across])


def _inset(face: np.ndarray, inset: float) -> np.ndarray:
    """The face ``face`` (k, 3), flat at one height in the tool's frame, taken ``inset`` (m)
    in from each of its edges (a polygon's offset: each edge's line moved in by ``inset``),
    at most half way to its centre, so that a face narrower than the tolerance keeps a
    holder. ``face`` itself for ``inset`` 0 or a face of no area."""
    if inset <= 0.0:
        return face
    xy = face[:, :2]
    try:
        hull = ConvexHull(xy)
    except QhullError:
        return face
    normals, offsets = hull.equations[:, :2], hull.equations[:, 2]  # n . x + d <= 0 inside
    centre = xy[hull.vertices].mean(axis=0)
    room = float(-(normals @ centre + offsets).min())  # the centre's distance to an edge
    step = min(inset, 0.5 * room)
    if not step > 0.0:
        return face
    inner = HalfspaceIntersection(np.column_stack([normals, offsets + step]), centre)
    points = inner.intersections
    return np.column_stack([points, np.full(len(points), face[0, 2])])


#: Material boxes tested at once against a chunk of sweeps' boxes (`holder_in_material`):
#: bounds the transient (sweeps x boxes x 3) arrays.
_BOXES_PER_TEST = 64


def _meets_any(low: np.ndarray, high: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """Whether each box (``low``, ``high``: (n, 3) each) meets any of ``boxes`` ((k, 6): low,
    high), compared `_BOXES_PER_TEST` at a time."""
    meets = np.zeros(len(low), dtype=bool)
    for begin in range(0, len(boxes), _BOXES_PER_TEST):
        part = boxes[begin:begin + _BOXES_PER_TEST]
        meets |= ((low[:, None, :] <= part[None, :, 3:])
                  & (high[:, None, :] >= part[None, :, :3])).all(axis=2).any(axis=1)
    return meets


#: Consecutive sweeps of one batch of `_Walk.cut` compared with each other for containment
#: (`contained_sweeps`): a bore 12.8 mm deep has 2,840 sweeps before its first candidate.
_CONTAINED_WINDOW = 4096

#: A top face thinner across than this fraction of its length is a segment (`_holder_top`).
_SEGMENT_REL = 1e-9

#: The run id of the holder's rooms: they are only intersected with the part, never kept.
_ROOM_ID = manifold3d.Manifold.reserve_ids(1)
