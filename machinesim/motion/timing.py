"""The time of a program's moves by FANUC's feed rule, and notes on times hardly meant:
`move_duration` of one move, `durations` of every move at once (the same operations), and
`slow_move_notes`."""

from __future__ import annotations

import math

import numpy as np

from machinesim.exceptions import InputError, ProgramTimeError, brief, line_of
from machinesim.nc.arcs import MAX_STEP_RAD
from machinesim.nc.program import KIND_DWELL, KIND_LINEAR, KIND_RAPID, MOVE_KINDS
from machinesim.nc.rotary_feed import inch_feed_as_written
from machinesim.nc.words import MAX_PROGRAM_TIME_S

M_PER_MM = 1e-3
#: A feed move longer than this is noted (`slow_move_notes`): a day for one move is a feed
#: written in the wrong unit (F0.0001 mm/min for 0.1 mm/min), not a machining plan.
SLOW_MOVE_S = 24 * 3600.0
#: A dwell longer than this is noted (`slow_move_notes`). A dwell in a part program waits
#: seconds (a spindle coming up to speed, a chip clearing, a spark-out); a time in the wrong
#: unit is 1000 times what was meant (P counts milliseconds without a decimal point and
#: seconds with one, X seconds: ``G04 X5000`` for 5 s, ``P5000.`` for 5000 ms), so a dwell
#: of more than a few seconds becomes more than an hour, which no machining step waits.
LONG_DWELL_S = 3600.0
_RAD_PER_DEG = np.pi / 180.0
NUMBER = int | float | np.integer | np.floating
#: The most the piece of arc a chord stands for exceeds the chord: x / sin x at the half
#: angle of the reader's longest step (`machinesim.nc.arcs.MAX_STEP_RAD`), 1.1107.
ARC_OVER_CHORD = (MAX_STEP_RAD / 2.0) / math.sin(MAX_STEP_RAD / 2.0)
#: Slack (relative, and absolute in m) of `on_chord`'s test: a compensated program's chords
#: (`Program.with_targets`) end micrometres from the read ones, rounded to the resolution.
ARC_CHORD_SLACK = 1e-2
ARC_CHORD_SLACK_M = 1e-8


def _real(value) -> bool:
    """A number `move_duration` times (`NUMBER`), a bool not: ``True`` is no feed, dwell or
    length (a `Move` refuses it), where Python's int would take it for 1."""
    return isinstance(value, NUMBER) and not isinstance(value, bool)


def on_chord(arc_lengths: np.ndarray, deltas: np.ndarray, rotary: np.ndarray) -> np.ndarray:
    """Whether each move of axis motion ``deltas`` (n, n_axes; m, rad) is a chord of the
    piece of arc ``arc_lengths`` (n,) m gives it: in one plane of two linear axes its chord c
    has c <= arc <= `ARC_OVER_CHORD` c (with `ARC_CHORD_SLACK`), as every chord the reader
    makes of an arc has in its plane. An arc length kept by a move that is no such chord
    (the first move of a program cut from the middle of an arc, planned from elsewhere;
    moves put together out of order; new targets) describes another move: the move takes
    its own length, as any feed move."""
    linear = np.flatnonzero(~np.asarray(rotary, dtype=bool))
    d = np.abs(np.asarray(deltas, dtype=np.float64)[:, linear])
    if len(linear) >= 2:
        chords = np.stack([np.hypot(d[:, i], d[:, j]) for i in range(len(linear))
                           for j in range(i + 1, len(linear))], axis=1)
    else:
        chords = d  # one linear axis (or none): its motion is the chord
    arcs = np.asarray(arc_lengths, dtype=np.float64)[:, None]
    low = chords * (1.0 - ARC_CHORD_SLACK) - ARC_CHORD_SLACK_M
    high = chords * (ARC_OVER_CHORD * (1.0 + ARC_CHORD_SLACK)) + ARC_CHORD_SLACK_M
    return np.any((low <= arcs) & (arcs <= high), axis=1)


def move_duration(kind: str, start: np.ndarray, end: np.ndarray, rotary: np.ndarray,
                  rapid_rate: np.ndarray, feed_m_per_s: float | None, dwell_s: float,
                  *, arc_length_m: float | None = None) -> float:
    """Time of one move by the rules of `machinesim.motion` (FANUC's feed rule, clamped at
    the axes' velocity limits ``rapid_rate``; a rapid at its slowest axis), s.

    ``kind`` is one of ``"rapid"``, ``"linear"``, ``"dwell"``; a linear move that moves
    needs a feed > 0 (m/s, its degrees counting as mm), a dwell a time >= 0: anything
    else is refused (InputError), as a `Move` refuses it, not timed.

    ``arc_length_m``: for a linear move that is the chord of an arc, the length of the
    piece of arc it stands for (m; its entry of `machinesim.nc.Program.arc_lengths`; None
    or NaN: none), which it takes over F as `move_durations` does (the control holds F
    along the arc), still clamped at the velocity limits, when the move is a chord of it
    (`on_chord`; else the move takes its own length). Without it a chord takes its own
    length, which runs an arc fast by tol / (3 r)."""
    if kind not in MOVE_KINDS:
        raise InputError(f"kind must be one of {', '.join(MOVE_KINDS)}, got {kind!r}",
                         key="kind")
    if kind == "dwell":
        if not (_real(dwell_s) and 0.0 <= dwell_s < math.inf):
            raise InputError(f"dwell_s must be a time >= 0 s, got {dwell_s!r}", key="dwell_s")
        return float(dwell_s)
    delta = np.abs(end - start)
    if kind == "rapid":
        return float(np.max(delta / rapid_rate)) if delta.size else 0.0
    # FANUC: degrees count as millimetres in the feed length
    scaled = np.where(rotary, delta / _RAD_PER_DEG, delta / M_PER_MM)
    length_mm = float(np.sqrt(np.sum(scaled**2)))
    if arc_length_m is not None and not (_real(arc_length_m)
                                         and (math.isnan(arc_length_m)
                                              or 0.0 <= arc_length_m < math.inf)):
        raise InputError(f"arc_length_m must be a length >= 0 (m), NaN or None (no arc), "
                         f"got {arc_length_m!r}", key="arc_length_m")
    if (arc_length_m is not None and not math.isnan(arc_length_m)
            and on_chord(np.array([arc_length_m]), delta[None], rotary)[0]):
        length_mm = float(arc_length_m) / M_PER_MM
    if length_mm == 0.0:
        return 0.0
    if not (_real(feed_m_per_s) and 0.0 < feed_m_per_s < math.inf):
        raise InputError(f"a linear move that moves needs a feed > 0 (m/s), got "
                         f"{feed_m_per_s!r}", key="feed_m_per_s")
    feed_mm_per_s = feed_m_per_s / M_PER_MM
    # no axis runs faster than its velocity limit: a feed beyond it is clamped there
    return max(length_mm / feed_mm_per_s, float(np.max(delta / rapid_rate)))


def slow_move_notes(durations, kinds, lines, feeds, program=None,
                    first: int = 0) -> tuple[str, ...]:
    """Notes on the moves whose time is hardly what the program meant: the longest feed
    move when it takes more than `SLOW_MOVE_S`, and the longest dwell when it waits more
    than `LONG_DWELL_S`, each with its line, time and the word that set it.

    The feed is the F as ``program`` (these moves from its move ``first`` on) wrote it: in
    inch/min where G20 is in force (`Program.unit_in_force`: the last G20/G21 before the
    first motion), with the mm/min the planner used beside it; both readings for a program
    unpickled from before that was kept that selected G20. The dwell's P or X is the word
    its line wrote (`Program.dwell_words`: a canned cycle's P kept from an earlier block with
    that block's line; none for a program built from moves)."""
    kinds = np.asarray(kinds)
    notes = []
    linear = np.flatnonzero(kinds == KIND_LINEAR)
    i = int(linear[np.argmax(durations[linear])]) if linear.size else None
    if i is not None and durations[i] > SLOW_MOVE_S:
        feed = _feed_text(feeds[i], program, first + i)
        notes.append(f"the feed move of {_line_text(program, int(lines[i]))} takes "
                     f"{durations[i]:.3g} s ({durations[i] / 3600.0:.3g} h) at {feed}, "
                     f"more than the {SLOW_MOVE_S / 3600.0:g} h one move of a program takes: "
                     "is F in the program's unit (G94: per minute)?")
    dwell = np.flatnonzero(kinds == KIND_DWELL)
    i = int(dwell[np.argmax(durations[dwell])]) if dwell.size else None
    if i is not None and durations[i] > LONG_DWELL_S:
        line = int(lines[i])
        word = getattr(program, "dwell_words", {}).get(line)
        said = f" ({brief(word)})" if word else ""  # a word of 300 zeros, shown by its ends
        notes.append(f"the dwell of {_line_text(program, line)}{said} waits "
                     f"{durations[i]:.6g} s ({durations[i] / 3600.0:.3g} h), more than the "
                     f"{LONG_DWELL_S / 3600.0:g} h a dwell of a program waits: is its time "
                     "in the unit meant (P counts milliseconds without a decimal point, "
                     "seconds with one; X seconds)?")
    return tuple(notes)


def check_total_time(durations, kinds, lines, program=None, *, block_of=None) -> None:
    """Refuse (`ProgramTimeError`) moves and dwells that take more than `MAX_PROGRAM_TIME_S`
    in all, or one whose time is no finite number (a move of 1e304 m at the slowest feed):
    the program's clock, their float64 running sum, keeps 0.1 ms only up to there, and
    beyond it overflows to inf. The error names the line at which the sum passes the bound
    and the longest move or dwell, with its line and word (`Program.dwell_words`).
    ``block_of(move)``: the N word of a move's block (None: none), for the line's name."""
    durations = np.asarray(durations, dtype=np.float64)
    with np.errstate(over="ignore", invalid="ignore"):
        clock = np.cumsum(durations)
    beyond = np.flatnonzero(~(clock <= MAX_PROGRAM_TIME_S))
    if not beyond.size:
        return
    at = int(beyond[0])
    unknown = np.isnan(durations)
    longest = int(np.argmax(unknown)) if unknown.any() else int(np.argmax(durations))
    kinds = np.asarray(kinds)
    line = int(lines[longest])
    if kinds[longest] == KIND_DWELL:
        word = getattr(program, "dwell_words", {}).get(line)
        what = "dwell" + (f" ({brief(word)})" if word else "")
    else:
        what = "rapid" if kinds[longest] == KIND_RAPID else "feed move"
    taken = (f"{durations[longest]:.3g} s" if math.isfinite(durations[longest])
             else "a time beyond float64 (its length over its feed overflowed)")
    block = None if block_of is None else block_of(at)
    raise ProgramTimeError(
        f"the program's moves and dwells take more than {MAX_PROGRAM_TIME_S:.6g} s (2**39 s, "
        f"about 17,400 years) by this line, the longest the {what} of "
        f"{_line_text(program, line)}, {taken}: a program's clock, a float64 sum of "
        "seconds, keeps 0.1 ms only up to there (and overflows to inf beyond 1.8e308 s); is "
        "a time, feed or length in the unit meant?",
        source=getattr(program, "source", "<program>"), line=int(lines[at]), block=block)


def _line_text(program, line: int) -> str:
    """``line 12 (N120)`` where ``program``'s block at ``line`` has an N word
    (`machinesim.nc.Program.line_text`), else ``line 12`` (`line_of`)."""
    text = getattr(program, "line_text", None)
    return text(line) if callable(text) else line_of(line)


def _feed_text(feed: float, program, move: int) -> str:
    """The feed (m/s; of `slow_move_notes`' move) as its program wrote it."""
    metric = f"F{feed * 60e3:.6g} (mm/min or deg/min)"
    inch = None if program is None else inch_feed_as_written(program, move)
    if inch is None:
        return metric
    in_force = getattr(program, "unit_in_force", None)
    if in_force == "G20":
        return f"F{inch[0]:.6g} ({inch[1]} under G20; {feed * 60e3:.6g} mm/min or deg/min)"
    if in_force == "G21":
        return metric
    return f"{metric}, or F{inch[0]:.6g} ({inch[1]}) if written under G20"


def move_durations(kinds, starts, ends, feeds, dwells, rotary, rapid_rate,
                   arc_lengths=None) -> np.ndarray:
    """`move_duration` of every move, by the same operations (axis by axis: the largest
    ratio, and the squares summed in numpy's order, first axis first, for up to 7 axes).

    ``arc_lengths`` (m, NaN: none; `machinesim.nc.Program.arc_lengths`): a feed move that
    is the chord of an arc takes its piece of arc over F, as the control holds F along the
    arc, not the chord's length (which ran an arc fast by tol / (3 r) of its time for
    chords within tol of a radius r: 3.3e-7 at 1 nm on 1 mm, 0.33 % at 10 um), still
    clamped at the axes' velocity limits; an arc length whose move is no chord of it
    (`on_chord`) is not taken."""
    out = np.zeros(len(kinds))
    dwell = kinds == KIND_DWELL
    out[dwell] = dwells[dwell]
    n_axes = starts.shape[1]
    if not n_axes:
        return out
    def slowest_axis(moves):  # s: every axis at its velocity limit
        slowest = None
        for i in range(n_axes):
            ratio = np.abs(ends[moves, i] - starts[moves, i]) / rapid_rate[i]
            slowest = ratio if slowest is None else np.maximum(slowest, ratio)
        return slowest

    rapid = np.flatnonzero(kinds == KIND_RAPID)
    if rapid.size:
        out[rapid] = slowest_axis(rapid)
    linear = np.flatnonzero(kinds == KIND_LINEAR)
    if linear.size:
        if n_axes <= 7:
            total = None
            for i in range(n_axes):
                scaled = np.abs(ends[linear, i] - starts[linear, i]) / (
                    _RAD_PER_DEG if rotary[i] else M_PER_MM)
                scaled *= scaled
                total = scaled if total is None else total + scaled
        else:
            delta = np.abs(ends[linear] - starts[linear])
            total = np.sum(np.where(rotary, delta / _RAD_PER_DEG, delta / M_PER_MM)**2, axis=1)
        length_mm = np.sqrt(total)
        if arc_lengths is not None:
            arc = arc_lengths[linear]
            on_arc = np.flatnonzero(~np.isnan(arc))
            on_arc = on_arc[on_chord(arc[on_arc], ends[linear[on_arc]] - starts[linear[on_arc]],
                                     rotary)]
            length_mm[on_arc] = arc[on_arc] / M_PER_MM
        moving = length_mm != 0.0
        out[linear[moving]] = np.maximum(
            length_mm[moving] / (feeds[linear[moving]] / M_PER_MM),
            slowest_axis(linear[moving]))
    return out


__all__ = ["ARC_OVER_CHORD", "LONG_DWELL_S", "MAX_PROGRAM_TIME_S", "M_PER_MM", "NUMBER",
           "SLOW_MOVE_S", "check_total_time", "move_duration", "move_durations", "on_chord",
           "slow_move_notes"]
