"""How far the holder may enter the material, sweep by sweep (`holder.holder_in_material`'s
``tolerance``): one chord of its own move, or of a chorded move that cut the material next
to it before.

A sweep's own allowance is its move's (`machinesim.cutting.program.holder_tolerance`): the
rounding of the program's words on a straight move (`program.written_rounding`, from the
decimals the text wrote), the tolerance its chords were made within on a chord of an arc
or of a move the planner split. The holder also meets walls
other sweeps cut: a straight pass along a pocket whose wall an arc cut as chords finds the
wall up to one of those chords' sag short of the arc, and its holder, true to the arc,
enters it by that much. So a sweep's allowance is the largest of its own and of those of the
chorded sweeps before it (in the program's order, earlier tools' too) whose body's box,
widened by their own allowance, meets the box of its holder's room below the stock's top
(`sweep_allowances`). A chorded move elsewhere (an arc in air, a rotary move across the
part) lends a straight pass nothing: a holder 0.2 mm into a straight wall is refused
whatever the program's arcs were read within, or ``--chord-nm``. Nor does a chorded move
whose box meets a long pass's room somewhere: the larger allowance holds only inside the
boxes of the chorded sweeps that lend it (`Lent`); outside them the holder is judged by its
own.
"""

from __future__ import annotations

import manifold3d
import numpy as np

from machinesim.cutting.sweepset import POINTS_PER_CHUNK, SweepSet

__all__ = ["Chorded", "Lent", "sweep_allowances", "turned_lent"]

#: (lower (k, 3), upper (k, 3), allowance (k,)): the boxes of the bodies of chorded sweeps
#: cut so far, widened by their allowance (m), in the workpiece frame.
Chorded = tuple[np.ndarray, np.ndarray, np.ndarray]

#: {sweep: (its own allowance, m; the union of the widened boxes of the chorded sweeps that
#: lend it a larger one)}, for the sweeps whose allowance is borrowed: their holder may enter
#: the material by the larger allowance inside that union, by their own outside it
#: (`holder.holder_in_material`'s ``lent``). A straight pass 0.2 mm into a straight slot's
#: wall over 10 mm had been cut, exit 0, because an arc read within 1 mm cut 0.1 mm deep at
#: the slot's far end, its box meeting the pass's room there.
Lent = dict[int, tuple[float, manifold3d.Manifold]]

#: Box pairs compared at once (`_widened`): bounds the transient (n x k x 3) arrays.
_PAIRS_PER_TEST = 1 << 20


def no_chords() -> Chorded:
    """The empty `Chorded`: no chorded sweep cut yet."""
    return np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0)


def turned_lent(lent: Lent | None, rotation: np.ndarray) -> Lent | None:
    """``lent`` with its boxes turned by ``rotation`` (3 x 3), into the frame the sweeps and
    the stock are turned into (`machinesim.cutting.frame.into_frame`)."""
    if not lent:
        return lent
    matrix = np.hstack([np.asarray(rotation, dtype=np.float64), np.zeros((3, 1))])
    return {i: (own, boxes.transform(matrix)) for i, (own, boxes) in lent.items()}


def sweep_allowances(tool, paths: list[np.ndarray], own, top: float, floor: float,
                     before: Chorded | None = None, carry: bool = False
                     ) -> tuple[np.ndarray, Chorded, Lent]:
    """Each sweep's allowance (m) for ``tool`` along ``paths`` (workpiece frame, program
    order; consecutive poses of a path form sweeps, a path of one pose is one sweep), the
    chorded sweeps cut so far, ``before`` with these added, and where each sweep whose
    allowance is borrowed may use it (`Lent`: inside the lenders' widened boxes).

    ``own`` (per sweep, m): its move's allowance. A sweep is chorded where ``own`` exceeds
    ``floor`` (the written rounding a straight move gets). A sweep whose holder's face comes
    below ``top`` (the stock's top, where `holder.holder_contact` looks) gets the largest of
    its own and of the allowances of the chorded sweeps before it (``before``, and earlier
    sweeps of ``paths``) whose widened box meets its holder's room's box below ``top``.
    The chorded sweeps are returned for a later tool's (``carry``), else only where a
    sweep's own allowance is below another's (else ``before`` as it was).
    """
    paths = [np.concatenate([poses, poses]) if len(poses) == 1 else np.asarray(poses)
             for poses in paths if len(poses)]
    before = no_chords() if before is None else before
    own = np.asarray(own, dtype=np.float64)
    if not paths:
        return own, before, {}
    sweeps = SweepSet(tool, paths, top)
    if own.shape != (sweeps.count,):
        return own, before, {}  # the engine refuses the mismatch, naming holder_tolerance
    chorded = np.flatnonzero(own > floor)
    candidates = _below(sweeps, top)
    most = max(float(before[2].max(initial=0.0)), float(own[chorded].max(initial=0.0)))
    candidates = candidates[own[candidates] < most]
    if not carry and not len(candidates):
        return own, before, {}  # no sweep's holder below the top may borrow a larger chord
    low, high = _body_boxes(sweeps, chorded)
    reaches = low[:, 2] <= top  # a chorded sweep wholly above the stock cut nothing
    chorded, low, high = chorded[reaches], low[reaches], high[reaches]
    widen = own[chorded][:, None]
    after = (np.concatenate([before[0], low - widen]), np.concatenate([before[1], high + widen]),
             np.concatenate([before[2], own[chorded]]))
    allowance, lent = own.copy(), {}
    if len(candidates) and len(after[2]):
        room_low, room_high = _room_boxes(sweeps, candidates, top)
        # the run's own chorded sweeps count only before the candidate; earlier runs' all
        order = np.concatenate([np.full(len(before[2]), -1), chorded])
        lent = _widened(room_low, room_high, candidates, own[candidates], after, order)
        for i, (_, most) in lent.items():
            allowance[i] = most
        lent = {i: (float(own[i]), boxes) for i, (boxes, _) in lent.items()}
    return allowance, after, lent


def _below(sweeps: SweepSet, top: float) -> np.ndarray:
    """The sweeps whose holder's face comes below ``top`` at either pose."""
    face = sweeps.holder_face
    lowest = np.empty(len(sweeps.poses))
    step = max(1, POINTS_PER_CHUNK // len(face))
    for begin in range(0, len(sweeps.poses), step):
        poses = sweeps.poses[begin:begin + step]
        lowest[begin:begin + step] = (np.einsum("nj,kj->nk", poses[:, 2, :3], face).min(axis=1)
                                      + poses[:, 2, 3])
    first = sweeps.pairs
    return np.flatnonzero(np.minimum(lowest[first], lowest[first + 1]) < top)


def _body_boxes(sweeps: SweepSet, which: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Boxes (lower, upper; (n, 3) each) holding the tool's body at both poses of the
    sweeps ``which``: those of the corners of its box in its own frame (a ball's 1,369
    vertices are 8 corners; the box holds the body's)."""
    low, high = sweeps.vertices.min(axis=0), sweeps.vertices.max(axis=0)
    corners = np.array([[(low, high)[k >> b & 1][b] for b in range(3)] for k in range(8)])
    out_low, out_high = np.zeros((len(which), 3)), np.zeros((len(which), 3))
    step = max(1, POINTS_PER_CHUNK // 16)
    for begin in range(0, len(which), step):
        first = sweeps.pairs[which[begin:begin + step]]
        poses = np.concatenate([sweeps.poses[first], sweeps.poses[first + 1]], axis=0)
        points = (corners @ poses[:, :3, :3].transpose(0, 2, 1) + poses[:, None, :3, 3])
        points = points.reshape(2, len(first), 8, 3)
        out_low[begin:begin + step] = points.min(axis=(0, 2))
        out_high[begin:begin + step] = points.max(axis=(0, 2))
    return out_low, out_high


def _room_boxes(sweeps: SweepSet, which: np.ndarray, top: float):
    """The boxes (lower, upper) of the holder's rooms over the sweeps ``which`` below
    ``top``: the face at both poses and lifted along the tool's axis until it is above
    ``top`` (the room below ``top`` lies in the hull of those), cut at ``top``."""
    from machinesim.cutting.holder import _holder_top

    face = _holder_top(sweeps.holder_face)
    low, high = np.zeros((len(which), 3)), np.zeros((len(which), 3))
    step = max(1, POINTS_PER_CHUNK // (4 * len(face)))
    span = float(np.abs(sweeps.poses[:, :3, 3]).max()) + abs(top) + float(np.ptp(face)) + 1.0
    for begin in range(0, len(which), step):
        first = sweeps.pairs[which[begin:begin + step]]
        boxes = []
        for poses in (sweeps.poses[first], sweeps.poses[first + 1]):
            points = face @ poses[:, :3, :3].transpose(0, 2, 1) + poses[:, None, :3, 3]
            axis = poses[:, :3, 2]
            rise = np.maximum(top - points[:, :, 2].min(axis=1), 0.0)
            # up the axis until the whole face is above the top: rise / a_z (a level or
            # downward axis: far past everything)
            up = np.where(axis[:, 2] > 0.0, rise / np.maximum(axis[:, 2], 1e-300), span)
            lifted = points + (np.minimum(up, span)[:, None] * axis)[:, None, :]
            boxes += [points, lifted]
        stacked = np.concatenate(boxes, axis=1)
        low[begin:begin + step] = stacked.min(axis=1)
        high[begin:begin + step] = stacked.max(axis=1)
    high[:, 2] = np.minimum(high[:, 2], top)
    return low, high


def _widened(room_low, room_high, candidates, own, chorded: Chorded, order
             ) -> dict[int, tuple[manifold3d.Manifold, float]]:
    """For each candidate that borrows, {its index: (the union of the chorded boxes meeting
    its room's box whose ``order`` (sweep index; -1 for earlier runs) is below its own and
    whose allowance exceeds its own ``own``, the largest of those allowances)}."""
    low, high, allowance = chorded
    out = {}
    step = max(1, _PAIRS_PER_TEST // max(len(allowance), 1))
    for begin in range(0, len(candidates), step):
        rows = slice(begin, begin + step)
        meets = ((room_low[rows, None, :] <= high[None]).all(axis=2)
                 & (room_high[rows, None, :] >= low[None]).all(axis=2)
                 & (order[None, :] < candidates[rows, None])
                 & (allowance[None, :] > own[rows, None]))
        for row in np.flatnonzero(meets.any(axis=1)):
            lenders = np.flatnonzero(meets[row])
            boxes = [manifold3d.Manifold.cube(tuple(high[k] - low[k])).translate(
                tuple(low[k])) for k in lenders]
            union = boxes[0] if len(boxes) == 1 else manifold3d.Manifold.batch_boolean(
                boxes, manifold3d.OpType.Add)
            out[int(candidates[begin + row])] = (union, float(allowance[lenders].max()))
    return out
