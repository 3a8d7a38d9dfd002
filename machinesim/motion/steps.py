"""Where a tool path steps: no number of sub-steps makes its chords follow it.

A chord follows a smooth path ever closer as its sub-steps shorten (an arc's sagitta falls
as their square); a step in the path, where an error table's value changes by more than the
chord tolerance over a span finer than a sub-step, stays at half the step however many.
`machinesim.motion.chords.substeps` would raise the count towards `MAX_SUBSTEPS` on such a
move; these find the step and say where it is:

* `wrap_steps`, before the rule: where a rotary axis passes the place a table of a whole
  turn wraps with values a turn apart that differ (`ToolPaths.wraps`);
* `_zoom` and `Stall`, inside the rule (`chords._raise_until_within`): a move whose
  deviation has not halved while its count grew fourfold is looked into down to pieces of
  1 / `MAX_SUBSTEPS` of the move, and refused if its path still leaves such a piece's chord.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from machinesim.motion.chords import MAX_SUBSTEPS, _blocks, _columns
from machinesim.motion.tool_paths import ToolPaths

#: Pieces each level of `_zoom` splits the worst piece into.
_ZOOM = 64


def wrap_steps(paths: ToolPaths, start: np.ndarray, delta: np.ndarray,
               tolerance: float) -> list[tuple[int, int, float, float, str]]:
    """Moves on which the path steps by more than ``tolerance``: where a rotary axis passes
    (or leaves) the place a table of a whole turn wraps with values a turn apart that
    differ (`machinesim.errors.turns.each_turn` repeats it each turn). No chord follows a
    step, so no number of sub-steps holds such a move (the README's example, ECC 1 arcsec at
    -180 deg and -1 at 180, stepped the grooves' path 53 nm at C = 180 deg; the sub-steps
    were raised by 10 % a round from 1842 towards a million, silent for more than 15 min).

    Returns (move, axis, axis value, step in m, table name) of each, in move order. The step
    is the largest distance over the tool points between the path just before and just
    after the place (1e-10 of the angle apart), within the move.
    """
    found = []
    slack = 1e-12
    for axis, at, side, period, name in paths.wraps:
        d = delta[:, axis]
        live = np.flatnonzero(d != 0.0)
        if not live.size:
            continue
        begin, end = start[live, axis], start[live, axis] + d[live]
        low, high = np.minimum(begin, end), np.maximum(begin, end)
        first = np.ceil((low - at) / period - slack)
        last = np.floor((high - at) / period + slack)
        # only the turns beyond the table's end: inside it the table is read as it is
        if side < 0:
            last = np.minimum(last, 0.0)
        else:
            first = np.maximum(first, 0.0)
        count = np.maximum(last - first + 1, 0)
        count = count.astype(np.int64)
        which = np.repeat(np.arange(live.size), count)
        if not which.size:
            continue
        turn = np.arange(which.size) - np.repeat(np.cumsum(count) - count, count)
        x = at + (first[which] + turn) * period
        step = 1e-10 * np.maximum(1.0, np.abs(x))
        move = live[which]
        sides = [np.clip(x + sign * step, low[which], high[which]) for sign in (-1.0, 1.0)]
        f = np.concatenate([(side - start[move, axis]) / d[move] for side in sides])
        rows = len(move)
        q = [np.concatenate([start[move, i], start[move, i]]) + f * np.concatenate(
            [delta[move, i], delta[move, i]]) for i in range(start.shape[1])]
        pos = paths.positions(q, _blocks(2 * rows))
        gap = sum((p[:rows] - p[rows:]) ** 2 for p in pos[:3])
        if np.ndim(gap) == 2:
            gap = gap.max(axis=1)
        gap = np.sqrt(gap)
        for r in np.flatnonzero(gap > tolerance).tolist():
            found.append((int(move[r]), axis, float(x[r]), float(gap[r]), name))
    return sorted(found)


@dataclass(frozen=True)
class Stall:
    """A move whose chords do not converge on its path: it leaves the chord of a piece of
    at most 1 / `MAX_SUBSTEPS` of the move by more than the tolerance (a step).

    Attributes
    ----------
    move : int
        The move, an index into the moves given to `substeps`.
    low, high : float
        The piece, as fractions of the move.
    deviation : float, m
        The piece's deviation from its chord (the largest over the tool points).
    tried : tuple of (int, float)
        (sub-steps, the move's deviation in m) where the deviation was found not to shrink:
        the earlier count and the later.
    """

    move: int
    low: float
    high: float
    deviation: float
    tried: tuple[tuple[int, float], tuple[int, float]]


def _zoom(paths, start, delta, n: int) -> tuple[float, float, float]:
    """The piece of one move where its path leaves the chord most, found down to pieces of
    at most 1 / `MAX_SUBSTEPS` of the move: its fractions (low, high) and its deviation, m.

    The move's ``n`` sub-steps, then the worst one split into `_ZOOM` pieces, the worst of
    those split again, and so on: a smooth path's deviation falls as the square of the
    piece, so only a step in the path (narrower than the piece) keeps it above the
    tolerance there.
    """
    start, delta = start[None, :], delta[None, :]
    low, width, pieces = 0.0, 1.0, n
    while True:
        f = low + width * np.linspace(0.0, 1.0, pieces + 1)
        nodes = paths.positions(_columns(start, delta, f), _blocks(len(f)))
        mids = paths.positions(_columns(start, delta, (f[:-1] + f[1:]) / 2),
                               _blocks(pieces))
        square = sum((mids[c] - (nodes[c][:-1] + nodes[c][1:]) / 2) ** 2 for c in range(3))
        if np.ndim(square) == 2:
            square = square.max(axis=1)
        j = int(np.argmax(square))
        low, width = float(f[j]), float(f[j + 1] - f[j])
        if width * MAX_SUBSTEPS <= 1.0:
            return low, low + width, float(np.sqrt(square[j]))
        pieces = _ZOOM
