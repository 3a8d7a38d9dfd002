"""A G02/G03 block: its end, its centre (I J K) or radius (R), its chords as moves.

Internal to the reader: a block (`machinesim.nc.blocks.Block`) in G02/G03 with axis or centre
words reads here (`read_arc`); the arc's geometry, its chords within the reader's
``chord_tolerance``, comes from `machinesim.nc.arcs`.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from machinesim.exceptions import NCProgramError
from machinesim.nc.arcs import (
    ARC_RADIUS_TOLERANCE_INCH_M,
    ARC_RADIUS_TOLERANCE_M,
    FULL_CIRCLE_M,
    PLANES,
    NearCircle,
    arc_points,
)
from machinesim.nc.length import check_length_carried
from machinesim.nc.program import AXES, KIND_LINEAR, ROTARY_AXES
from machinesim.nc.rotary_feed import inch_feed_scale
from machinesim.nc.words import MAX_MOVES

if TYPE_CHECKING:
    from machinesim.nc.blocks import Block
    from machinesim.nc.lexer import Word

__all__ = ["read_arc"]


def read_arc(block: Block, axes: list[Word], block_number: int | None) -> None:
    """The G02/G03 ``block``: its end (``axes``) and centre or radius checked, its chords
    added to the reader's moves and its end made the modal target."""
    state, single, reader = block.state, block.single, block.reader
    reader.arc_blocks += 1
    (u, v, normal), centre_letters = PLANES[state.plane]
    word = next(iter(axes), None) or next(single[k] for k in "IJKR" if k in single)
    g_word = block.g_codes.get("motion", (None, word))[1]
    for letter in (u, v):
        if letter not in state.target:
            plane = ("" if state.plane != "G17" else
                     "; an arc in X and Z (a lathe's) needs G18 first, in Y and Z G19")
            raise block.fail(f"the arc starts where {letter} is not known yet; move "
                             f"{u} and {v} before {state.motion}{plane}", word)
    start = dict(state.target)
    end = dict(start)
    check_length_carried(block, single.get("Z"), axes)
    end.update({axis.letter: block.machine(axis) for axis in axes})
    given = [single[k] for k in centre_letters if k in single]
    if "R" in single and given:
        raise block.fail(f"an arc takes R or {' '.join(centre_letters)}, not both",
                         single["R"])
    if "R" not in single and not given:
        raise block.fail(f"{state.motion} needs the centre ({' '.join(centre_letters)}) or "
                         "the radius R", g_word)
    # the words' own refusals (not finite) name their place already: outside the try below
    if "R" in single:
        radius = block.real(single["R"]) * block.length_of(single["R"])
        centre = None
    else:
        offsets = [block.real(single[k]) * block.length_of(single[k]) if k in single
                   else 0.0 for k in centre_letters]
        centre = (start[u] + offsets[0], start[v] + offsets[1])
        radius = None
    tolerance = ARC_RADIUS_TOLERANCE_INCH_M if state.inch else ARC_RADIUS_TOLERANCE_M
    try:
        fractions, points, _, sweep = arc_points(
            (start[u], start[v]), (end[u], end[v]), clockwise=state.motion == "G02",
            centre=centre, radius=radius, chord_tolerance=reader.chord_tolerance,
            radius_tolerance=tolerance, max_segments=MAX_MOVES - reader.out.count)
    except NCProgramError as error:
        located = single.get("R") or (given[0] if given else word)
        raise block.fail(str(error), located) from None
    gap = math.hypot(end[u] - start[u], end[v] - start[v])
    if centre is not None and FULL_CIRCLE_M < gap <= tolerance and abs(sweep) < math.pi:
        # the end within the rounding a post leaves on an arc (the radius tolerance) of the
        # start, on the side that makes the arc short: a full circle most likely meant
        path = np.diff(np.vstack([[start[u], start[v]], points]), axis=0)
        reader.near_circles.setdefault(block.line, NearCircle(
            state.motion, float(np.hypot(path[:, 0], path[:, 1]).sum()), abs(sweep), gap,
            tolerance))
    n = fractions.size
    block.reserve(n, word)
    targets = np.empty((n, len(AXES)))
    for k, letter in enumerate(AXES):
        if letter == u:
            targets[:, k] = points[:, 0]
        elif letter == v:
            targets[:, k] = points[:, 1]
        elif letter in end:
            a, b = start.get(letter, end[letter]), end[letter]
            targets[:, k] = a + (b - a) * fractions
            targets[-1, k] = b
        else:
            targets[:, k] = math.nan
    block.check_feed(state.motion, g_word)
    feeds = np.full(n, state.feed)
    # a rotary word that keeps its axis where it stands (a post writing every axis on
    # every block) turns nothing: the chords keep the arc's feed rule
    turning = [w for w in axes if w.letter in ROTARY_AXES
               and not end[w.letter] == start.get(w.letter, math.nan)]
    if state.feed_inch and turning:  # a rotary axis's degrees count as inches in the feed
        starts = np.vstack([[start.get(a, math.nan) for a in AXES], targets[:-1]])
        scale, unknown = inch_feed_scale(starts, targets)
        if unknown.any():
            raise block.fail(f"{state.motion} under an F in inch/min turns {turning[0].letter}, "
                             "which had no position yet: its degrees count as inches in the "
                             f"feed (FANUC), so its time needs the distance; give "
                             f"{turning[0].letter} a position first (e.g. with G00)", turning[0])
        feeds *= scale
    state.target = end
    spindle = math.nan if state.spindle is None else state.spindle
    # the control holds F along the arc in its plane (FANUC; a helix's third axis follows):
    # each chord takes the time of its piece of arc, chord * (x / sin x) for the half
    # angle x it spans (exact for a circle); an arc that turns a rotary axis keeps the
    # feed rule of its chords (its degrees count in the feed length)
    lengths = np.full(n, math.nan)
    if not turning:
        plane = np.vstack([[start[u], start[v]], points])
        chords = np.hypot(*np.diff(plane, axis=0).T)
        half = np.abs(sweep) * np.diff(np.concatenate([[0.0], fractions])) / 2.0
        lengths = chords / np.sinc(half / np.pi)
    reader.out.add_arrays(targets, np.full(n, KIND_LINEAR, dtype=np.int8),
                          feeds, np.zeros(n), np.full(n, block.line, np.int64),
                          np.full(n, spindle),
                          np.full(n, -1 if block_number is None else block_number), lengths)
