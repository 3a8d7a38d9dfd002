"""Consecutive level ball sweeps along one straight line, cut as one sweep of the whole line.

A ball end mill's sweep is the Minkowski sum of its (convex, faceted) body with the move's
segment, P + [a, b] (`sweeps.SolidSweep`). When b lies on the segment [a, c], P + [a, b]
united with P + [b, c] is P + [a, c]: one sweep of the joined move is exactly the union of
the two, at the cost of one. A CAM program written as a point list repeats its direction
wherever its points fall on a line: a `ball:0.5` spiral of 100,000 moves, its points
rounded to 0.1 um, has 10,437 pairs of consecutive moves exactly in line (0 of 1,000 moves,
436 of 10,000; `benchmarks/ball_spiral_window.py`).

Only exact cases are joined: the tool's rotation the same to the bit at every pose, every
move level (its Z travel 0, so that each is cut at the same ring, `SweepSet._ball_cut`), and
the cross product of consecutive moves exactly 0 in float64 with a positive dot product
(the middle point within round-off of the line, ~1e-16 of the move). A polyline that turns
by any angle is not one sweep, and its moves stay apart.
"""

from __future__ import annotations

import numpy as np

from machinesim.cutting.sweeps import RebuiltSolid, Solids


def joined_ball_sweeps(sweeps, hulls: Solids, owners) -> tuple[np.ndarray | None, Solids]:
    """Each cut sweep's head (the first sweep of its straight chain, itself if it has none)
    and the solids by index, a head's being the sweep of its whole chain; (None, ``hulls``)
    when no two sweeps join.

    Parameters
    ----------
    sweeps : SweepSet
        The set `hulls` came from (its poses, pairs and `SweepSet.ball_line`).
    hulls : Solids
        The cut sweeps' solids (`SweepSet.hulls`); only `RebuiltSolid`s (ball sweeps) join.
    owners : list of int
        The sweep index (over all paths) of each of ``hulls``.
    """
    count = len(hulls)
    if count < 2:
        return None, hulls
    items = [list.__getitem__(hulls, i) for i in range(count)]
    first = sweeps.pairs[np.asarray(owners, dtype=np.int64)]  # pose at each sweep's start
    ball = np.array([isinstance(item, RebuiltSolid) for item in items])
    position = sweeps.poses[:, :3, 3]
    rotation = sweeps.poses[:, :3, :3].reshape(-1, 9)
    move = position[first + 1] - position[first]
    # sweep h joins sweep h + 1: the next pose pair of the same path, both ball sweeps,
    # level, the same rotation at the three poses, the moves in line and the same way
    joins = ((first[1:] == first[:-1] + 1) & ball[1:] & ball[:-1]
             & (move[1:, 2] == 0.0) & (move[:-1, 2] == 0.0)
             & (rotation[first[:-1]] == rotation[first[:-1] + 1]).all(axis=1)
             & (rotation[first[:-1]] == rotation[first[1:] + 1]).all(axis=1)
             & (np.cross(move[:-1], move[1:]) == 0.0).all(axis=1)
             & (np.einsum("ij,ij->i", move[:-1], move[1:]) > 0.0))
    if not joins.any():
        return None, hulls
    head, solids = np.arange(count), Solids(items)
    # chains: a new one starts at every sweep that does not join its predecessor
    starts = np.flatnonzero(np.concatenate([[True], ~joins]))
    ends = np.concatenate([starts[1:], [count]])
    for start, end in zip(starts.tolist(), ends.tolist(), strict=True):
        if end - start > 1:
            head[start:end] = start
            list.__setitem__(solids, start, RebuiltSolid(sweeps.ball_line, int(first[start]),
                                                         int(first[end - 1]) + 1))
    return head, solids
