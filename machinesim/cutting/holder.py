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

from machinesim.cutting.sweeps import hull_mesh, manifold_from
from machinesim.cutting.sweepset import POINTS_PER_CHUNK

if TYPE_CHECKING:
    from machinesim.cutting.sweepset import SweepSet

__all__ = ["HOLDER_MATERIAL_M3", "holder_contact", "holder_in_material", "holder_room"]

#: Material inside the holder's room over a sweep (m^3) above which the holder meets the part:
#: 1 um x 1 um x 1 nm. A body cut flush to its top leaves round-off slivers (1e-19 m thick
#: over a few mm^2: ~1e-25 m^3) far below it; any real contact is far above.
HOLDER_MATERIAL_M3 = 1e-21


def holder_contact(sweeps: SweepSet, below: float, keep) -> list[int]:
    """The sweeps of ``sweeps`` (indices over all paths) in which the top of the tool's
    body, where the holder begins, comes below ``below`` (the stock top) where ``keep``
    finds stock."""
    found = []
    face = sweeps.holder_face
    step = max(1, POINTS_PER_CHUNK // (2 * len(face)))
    for begin in range(0, sweeps.count, step):
        first = sweeps.pairs[begin:begin + step]
        t0, t1 = (face @ sweeps.poses[k, :3, :3].transpose(0, 2, 1)
                  + sweeps.poses[k, None, :3, 3] for k in (first, first + 1))
        low = np.minimum(t0.min(axis=1), t1.min(axis=1))
        high = np.maximum(t0.max(axis=1), t1.max(axis=1))
        hit = (low[:, 2] < below) & keep(low, high)
        found.extend((begin + np.flatnonzero(hit)).tolist())
    return found


def holder_in_material(sweeps: SweepSet, candidates, solid: manifold3d.Manifold,
                       reach: float, keep=None) -> list[int]:
    """Those of the sweeps ``candidates`` whose holder meets ``solid`` as this tool has cut
    it by then: more than `HOLDER_MATERIAL_M3` of it inside the holder's room over the sweep
    (`holder_room`). The bounding-box test of `holder_contact` finds the candidates;
    this one reads the material, so that a short profile running down a face (air over
    its top) is not a crash.

    With ``keep`` (the stock's region, as `hulls` takes it), the material a sweep's
    holder meets is what the earlier sweeps of these paths left of ``solid``: a slot
    cut in steps down is open to the holder when the steps reach below the body's
    height. Only the earlier sweeps that reach into a room with material are built.
    """
    inside = {}
    for i in (int(i) for i in candidates):
        met = solid ^ holder_room(sweeps, i, reach)
        if met.volume() > HOLDER_MATERIAL_M3:
            inside[i] = met
    if not inside or keep is None:
        return list(inside)
    boxes = np.array([met.bounding_box() for met in inside.values()]).reshape(-1, 6)

    def into_a_room(low: np.ndarray, high: np.ndarray) -> np.ndarray:
        meets = ((low[:, None, :] <= boxes[None, :, 3:])
                 & (high[:, None, :] >= boxes[None, :, :3])).all(axis=2).any(axis=1)
        return keep(low, high) & meets

    hulls, lower, upper, *_, owners = sweeps.hulls(into_a_room)
    owners = np.asarray(owners, dtype=np.int64)
    found = []
    for (i, met), box in zip(inside.items(), boxes, strict=True):
        earlier = np.flatnonzero((owners < i) & (lower <= box[3:]).all(axis=1)
                                 & (upper >= box[:3]).all(axis=1))
        # One earlier sweep at a time until nothing is left, those whose boxes share
        # most of the room's material box first: the passes right over it (a contour's
        # levels above, along the same chords) clear it, where in program order the
        # first level's every neighbouring chord came first (a contour in 5 levels, 3
        # below the body: more than 10 minutes). One union of all of them (a pocket's
        # every level, stacked) took minutes and GB. Subtraction commutes: the order
        # changes only when the loop stops.
        shared = np.prod(np.clip(np.minimum(upper[earlier], box[3:])
                                 - np.maximum(lower[earlier], box[:3]), 0.0, None), axis=1)
        earlier = earlier[np.argsort(-shared, kind="stable")]
        left = met.volume()
        for j in earlier:
            if left <= HOLDER_MATERIAL_M3:
                break
            met = met - hulls[j]
            left = met.volume()
        if left > HOLDER_MATERIAL_M3:
            found.append(i)
    return found


def holder_room(sweeps: SweepSet, sweep: int, reach: float) -> manifold3d.Manifold:
    """The room the holder takes over sweep ``sweep``: the hull of the body's top face
    at both poses and of the same face lifted ``reach`` along the tool axis. A top of
    zero width (a V's or a nose's: a segment) is widened along the tool's X to its own
    length, as the bar that carries the tool is.

    The hull is Qhull's (`sweeps.hull_mesh`), exact to float64 round-off, as the sweeps'
    are: manifold3d's QuickHull drops points within about 1e-7 of the largest coordinate of a
    plane, so the room of a tool a few nm wide, ~30 mm tall over a 10 mm block, came out
    empty, and a 2 nm ball 2 nm high cut 20 um deep with no holder contact.
    """
    face = sweeps.holder_face
    width = float(np.ptp(face[:, 0]))
    if width <= 0.0:
        half = 0.5 * max(float(np.ptp(face[:, 1])), float(np.ptp(face[:, 2])))
        face = np.concatenate([face + [half, 0.0, 0.0], face - [half, 0.0, 0.0]])
    local = np.concatenate([face, face + [0.0, 0.0, reach]])
    first = sweeps.pairs[sweep]
    poses = sweeps.poses[[first, first + 1]]
    points = (local @ poses[:, :3, :3].transpose(0, 2, 1) + poses[:, None, :3, 3])
    hull = hull_mesh(points.reshape(-1, 3))
    room = None if hull is None else manifold_from(hull[0], hull[1], _ROOM_ID)
    return manifold3d.Manifold() if room is None else room


#: The run id of the holder's rooms: they are only intersected with the part, never kept.
_ROOM_ID = manifold3d.Manifold.reserve_ids(1)
