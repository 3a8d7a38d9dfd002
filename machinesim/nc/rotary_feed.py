"""The feed of a move that turns a rotary axis under G20: its degrees count as inches.

FANUC's F of a feed move of linear and rotary axes together is the feed along the path in the
space of all of them, a rotary axis's degrees counted in the unit of the linear ones: "G91
G01 X20.0 C40.0 F300.0 ... changes the unit of the C axis from 40.0 deg to 40mm with metric
input", so the move takes sqrt(20^2 + 40^2) / 300 = 0.14907 min; a rotary-only move is fed in
deg/min, and rotary axes take no inch/metric switching (Power Mate i-D/H operator's manual
B-63174EN/03 §4.2; Series 15i-MA B-63324EN §4.3). Under G20 (inch input) the same rule
counts a degree as an inch, the unit of F there: ``G20 G01 X1. A10. F10.`` takes
sqrt(1 + 100) / 10 min, ``G20 G01 A90. F10.`` 9 min.

A `Program` keeps one feed per move, m/s, and the planner
(`machinesim.motion.timing.move_duration`) counts a degree as a millimetre, the metric rule.
So the reader keeps, for a move under an F read in inch/min that turns a rotary axis, the feed
that takes the same time by the planner's rule: F converted by inch, times
``length_mm * M_PER_MM / (length_inch * M_PER_INCH)``, where ``length_mm`` counts degrees as
millimetres and ``length_inch`` as inches. A move without rotary motion keeps its feed as it
is (its factor would be 1 but for rounding).

Internal to the reader (`machinesim.nc.blocks`, `machinesim.nc.arc_block` and the vectorised
path in `machinesim.nc.reader`), which all use `inch_feed_scale`, so the three agree to the
bit; `inch_feed_as_written` undoes it for the planner's note on a slow move
(`machinesim.motion.timing.slow_move_notes`), which names the F as the program wrote it.
"""

from __future__ import annotations

import numpy as np

from machinesim.nc.program import AXES, ROTARY_AXES
from machinesim.nc.words import M_PER_INCH
from machinesim.units import M_PER_MM, RAD_PER_DEG

__all__ = ["inch_feed_as_written", "inch_feed_scale"]

#: Factor of a rotary-only move: F inch/min read as F deg/min, which the planner's rule takes
#: as F mm/min.
ROTARY_ONLY_SCALE = M_PER_MM / M_PER_INCH


def inch_feed_scale(starts: np.ndarray, ends: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The factor on the feed of each move from ``starts`` to ``ends`` (each (n, 6), m and
    rad in `AXES` order, NaN: no value yet) whose F was read in inch/min; and which moves'
    factor is not known.

    Returns
    -------
    scale : ndarray, shape (n,)
        1 where no rotary axis turns, `ROTARY_ONLY_SCALE` where only rotary axes do, else
        ``length_mm * M_PER_MM / (length_inch * M_PER_INCH)``.
    unknown : ndarray of bool, shape (n,)
        Moves that turn a rotary axis and move a linear one (or may) where an axis's start is
        not known yet (it gets its first value here): the planner moves it from its start,
        which the program does not say, so the ratio is not known.
    """
    n = ends.shape[0]
    length_mm, length_inch = np.zeros(n), np.zeros(n)
    linear, rotary = np.zeros(n, dtype=bool), np.zeros(n, dtype=bool)  # moves or may
    unknown = np.zeros(n, dtype=bool)
    parts_mm, parts_inch = [], []  # each axis's motion in mm (deg) and in inches (deg)
    for k, letter in enumerate(AXES):
        first = np.isnan(starts[:, k]) & ~np.isnan(ends[:, k])
        delta = np.abs(ends[:, k] - starts[:, k])
        delta[np.isnan(delta)] = 0.0
        unknown |= first
        moving = (delta > 0.0) | first
        with np.errstate(over="ignore"):  # squares beyond float64: summed again below
            if letter in ROTARY_AXES:
                rotary |= moving
                parts_mm.append(delta / RAD_PER_DEG)
                parts_inch.append(parts_mm[-1])
                turned = parts_mm[-1] * parts_mm[-1]
                length_mm += turned
                length_inch += turned
            else:
                linear |= moving
                parts_mm.append(delta / M_PER_MM)
                parts_inch.append(delta / M_PER_INCH)
                length_mm += parts_mm[-1] ** 2
                length_inch += parts_inch[-1] ** 2
    scale = np.ones(n)
    scale[rotary & ~linear] = ROTARY_ONLY_SCALE
    mixed = rotary & linear
    known = mixed & ~unknown
    with np.errstate(invalid="ignore"):  # inf / inf: taken again just below
        scale[known] = (np.sqrt(length_mm[known]) * M_PER_MM
                        / (np.sqrt(length_inch[known]) * M_PER_INCH))
    # a move of more than 1e154 mm or deg squares to inf, and its factor had been inf / inf,
    # a NaN feed that the planner took for no F at all: its lengths are taken again, each
    # axis's part over the largest first (as hypot does)
    over = np.flatnonzero(known & ~(np.isfinite(length_mm) & np.isfinite(length_inch)))
    if over.size:
        scale[over] = (_length(np.stack(parts_mm, axis=1)[over]) * M_PER_MM
                       / (_length(np.stack(parts_inch, axis=1)[over]) * M_PER_INCH))
    return scale, mixed & unknown


def _length(parts: np.ndarray) -> np.ndarray:
    """The length of each row of ``parts`` (finite, >= 0, each row's largest > 0), its
    squares summed over the largest part so that none overflows."""
    largest = parts.max(axis=1)
    return np.sqrt(np.sum((parts / largest[:, None]) ** 2, axis=1)) * largest


def inch_feed_as_written(program, move: int) -> tuple[float, str] | None:
    """The F that a program under G20 writes for the feed of its move ``move``, and its
    unit: ``"deg/min"`` for a move of rotary axes alone, else ``"inch/min"`` (a rotary
    axis's degrees counted as inches): the inverse of the reader's rule, so a move read
    from ``G20 G01 X1. A10. F10.`` gives (10.0, "inch/min") back. None where the program
    selected no G20 (`Program.unit_words`), has no feed there, or the rule's factor is not
    known (an axis without a start)."""
    if "G20" not in getattr(program, "unit_words", {}):
        return None
    targets = program.targets
    end = targets[move]
    start = targets[move - 1] if move > 0 else np.full(len(AXES), np.nan)
    scale, unknown = inch_feed_scale(start[np.newaxis], end[np.newaxis])
    feed = float(program.feeds[move])
    if unknown[0] or not np.isfinite(feed):
        return None
    moving = ~np.isnan(end) & (np.isnan(start) | (start != end))
    linear = any(moving[k] for k, a in enumerate(AXES) if a not in ROTARY_AXES)
    return feed / float(scale[0]) * 60.0 / M_PER_INCH, "inch/min" if linear else "deg/min"
