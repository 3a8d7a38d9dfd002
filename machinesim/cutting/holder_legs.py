"""The holder check of an end mill that stands in several orientations along a program: a
tilted workpiece cut at several C positions, as `machinesim.cutting.cut_turned` judges it
(`machinesim.cutting.holder.check_holder`). Each leg of one orientation is walked in its
own tool frame, where the end mill's floors are level and coincide, and the one running
material is turned from leg to leg; in the workpiece frame each floor is tilted by its own
round-off and the walk's material broke into slivers.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from machinesim.cutting.containment import CONTAINED_REL
from machinesim.cutting.frame import flat_end, into_frame
from machinesim.cutting.holder import (
    HOLDER_MATERIAL_M3,
    _box,
    _descends,
    _meets_any,
    _reach,
    _region,
    _room,
    _Walk,
)
from machinesim.cutting.holder_allowance import turned_lent
from machinesim.cutting.sweepset import SweepSet
from machinesim.tolerances import CLIP_MARGIN_REL, SAME_ORIENTATION

if TYPE_CHECKING:
    from machinesim.workpiece import Part

__all__ = ["in_material_by_legs", "legs"]


def legs(paths: list[np.ndarray], tool) -> list[tuple[int, int, np.ndarray]] | None:
    """The runs of consecutive ``paths`` that share one orientation of a tilted flat-ended
    ``tool`` (first path, end path, orientation), when every path keeps one (within
    `SAME_ORIENTATION`) and they are not one: a program at several C positions on a tilted
    workpiece, as `machinesim.cutting.cut_turned` judges its holder. None otherwise (one
    orientation is `tool_frame`'s; an upright tool's floors coincide where it stands; a
    path that turns the tool has no frame)."""
    if not flat_end(tool):
        return None
    first = [np.asarray(poses)[0, :3, :3] for poses in paths]
    if not any(np.any(r[2, :2]) or np.any(r[:2, 2]) for r in first):
        return None  # upright throughout
    legs: list[tuple[int, int, np.ndarray]] = []
    for k, poses in enumerate(paths):
        rotation = np.asarray(poses)[:, :3, :3]
        if float(np.abs(rotation - rotation[0]).max()) > SAME_ORIENTATION:
            return None
        if legs and float(np.abs(rotation[0] - legs[-1][2]).max()) <= SAME_ORIENTATION:
            legs[-1] = (legs[-1][0], k + 1, legs[-1][2])
        else:
            legs.append((k, k + 1, rotation[0].copy()))
    return legs if len(legs) > 1 else None


def _between(into: np.ndarray, out_of: np.ndarray | None) -> np.ndarray:
    """The rotation taking coordinates in the tool frame ``out_of`` (the workpiece frame for
    None) to the frame ``into``. Where the two differ by a turn about the tool's axis alone
    (a C table's positions under a fixed tool: ``into.T @ out_of`` = Rz, the workpiece's
    tilt cancelling), that turn is made exact, its Z row and column (0, 0, 1): a level face
    stays at its height to the bit, so that a pass at one C coincides with an earlier one at
    the same C and depth as the engine's level passes do (`frame`), rather than 1e-19 m off
    it, where manifold3d breaks the two into slivers."""
    turn = into.T if out_of is None else into.T @ out_of
    if out_of is not None and max(float(np.abs(turn[2, :2]).max()),
                                  float(np.abs(turn[:2, 2]).max())) <= SAME_ORIENTATION:
        c, s = turn[0, 0], turn[1, 0]
        norm = float(np.hypot(c, s))
        turn = np.array([[c / norm, -s / norm, 0.0], [s / norm, c / norm, 0.0],
                         [0.0, 0.0, 1.0]])
    return turn


def _turned_box(box: np.ndarray, turn: np.ndarray) -> np.ndarray:
    """The box (6,) holding the box ``box`` (low, high) turned by ``turn`` (3, 3)."""
    corners = np.array([[box[3 * a], box[1 + 3 * b], box[2 + 3 * c]]
                        for a in (0, 1) for b in (0, 1) for c in (0, 1)])
    moved = corners @ turn.T
    return np.concatenate([moved.min(axis=0), moved.max(axis=0)])


def in_material_by_legs(stock: Part, tool, paths: list[np.ndarray], legs, candidates,
                         tolerance, lent=None) -> list[int]:
    """`holder_in_material` for paths whose tool stands in several orientations, one per leg
    (`legs`): each leg's sweeps and rooms are built in its own frame, where the end mill's
    floors are level and coincide, and the one running material is turned from leg to leg
    (`_between`) as the walk goes through the sweeps in the program's order. In the
    workpiece frame each sweep's floor is tilted with its own round-off and the walk's
    material broke into slivers (a contour in 3 levels 0.4 mm apart under a 0.5 mm body,
    with one pass at C = 90 deg: 235 s of CPU against 27 s without that pass).
    ``tolerance`` (m): one value, or one per sweep of all the legs in the program's order,
    and ``lent`` keyed by those sweeps, its boxes in the workpiece frame
    (`holder_in_material`'s): each leg's sweep i is the program's sweep offset + i."""
    reach, per_leg, inside, offset = _reach(stock), [], {}, 0
    tolerance = np.asarray(tolerance, dtype=np.float64)
    for begin, end, frame in legs:
        leg_stock, leg_paths = into_frame(stock, paths[begin:end], frame)
        scale = float(np.abs(leg_stock.bounds).max()) or 1.0
        sweeps = SweepSet(tool, leg_paths, leg_stock.bounds[1, 2] + CLIP_MARGIN_REL * scale)
        mine = sorted({int(i) - offset for i in candidates
                       if offset <= int(i) < offset + sweeps.count})
        # the lenders' boxes turned into this leg's frame, as its stock and paths are
        borrowed = turned_lent({i: lent[offset + i] for i in mine if offset + i in lent},
                               frame.T) if lent else {}
        rooms = {}
        for i in mine:
            room = _room(sweeps, i, reach, float(
                tolerance if tolerance.ndim == 0 else tolerance[offset + i]), borrowed.get(i))
            met = leg_stock.manifold ^ room
            if met.volume() > HOLDER_MATERIAL_M3:
                rooms[i] = room
                inside[offset + i] = _turned_box(np.asarray(met.bounding_box()), frame)
        per_leg.append((frame, leg_stock, sweeps, offset, rooms))
        offset += sweeps.count
    if not inside:
        return []
    boxes = np.array(list(inside.values()))
    material = stock.manifold ^ _box(boxes[:, :3].min(axis=0), boxes[:, 3:].max(axis=0))
    tol = CONTAINED_REL * (float(np.abs(stock.bounds).max()) or 1.0)
    last = max(k for k, leg in enumerate(per_leg) if leg[4])
    found, held = set(), None
    for k, (frame, leg_stock, sweeps, offset, rooms) in enumerate(per_leg[:last + 1]):
        turn = _between(frame, held)
        material, held = material.transform(np.hstack([turn, np.zeros((3, 1))])), frame
        near = np.array([_turned_box(box, frame.T) for box in boxes])
        whole = _region(leg_stock)

        def into_a_room(low, high, near=near, whole=whole):
            return whole(low, high) & _meets_any(low, high, near)

        hulls, lower, upper, *_, owners = sweeps.hulls(into_a_room)
        walk = _Walk(material, hulls, lower, upper, tol)
        owners = np.asarray(owners, dtype=np.int64)
        for i, room in rooms.items():
            side = "right" if _descends(sweeps, i) else "left"
            walk.cut(np.arange(walk.done, int(np.searchsorted(owners, i, side=side))))
            if walk.holds(room):
                found.add(offset + i)
        if k < last:  # what this leg leaves, for the legs after it
            walk.cut(np.arange(walk.done, len(owners)))
        material = walk.material
    return [int(i) for i in dict.fromkeys(int(i) for i in candidates) if int(i) in found]
