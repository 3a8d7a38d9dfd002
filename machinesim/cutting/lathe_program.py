"""A turning program's moves on a lathe: the axis values, the runs of feed moves that turn C,
and their times, as `machinesim.cutting.lathe`'s turn reads a program (its steps 1 and 2).

A slow-tool-servo (STS) or facing program on a lathe (``sts_lathe``: X carries the work
spindle C, the tool rides Z) is a list of feed moves that turn C while X and Z follow:

1. **Axis values.** Every move's target (modal: an axis not named keeps its value), from
   the first move that sets every axis of the machine.
2. **Runs.** Each run of consecutive feed moves that turn C is one continuous motion, its
   points a quarter turn of C apart at most (points added on the moves where needed). A
   program whose C stands still throughout is refused, as is a rapid inside a run.
3. **Times.** The control runs each feed move in length / F, the length with rotary axes in
   degrees counted as millimetres (FANUC, as `machinesim.motion` plans it), and no axis
   faster than its velocity limit (the machine's rapid rate): a feed beyond it is clamped
   there, as the planner clamps it; a dwell waits its time (`_untimed_moves`, noted beyond
   an hour, not cut).

The moves that do not turn C (the plunge, the retract) and the rapids are not cut: the
rapids with the tip below the stock's top are noted (`_rapids_below_top`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from types import SimpleNamespace

import numpy as np

from machinesim.exceptions import InputError, line_of
from machinesim.motion.timing import check_total_time, on_chord, slow_move_notes
from machinesim.nc.moves import AXES, KIND_DWELL, KIND_LINEAR, KIND_RAPID, ROTARY_AXES
from machinesim.nc.program import modal_values

__all__ = ["MOST_C_STEP_RAD", "STILL_C_RAD", "turning_runs"]

#: Relative change of the spindle angle below which a move counts as not turning, rad.
STILL_C_RAD = 1e-12
#: Largest turn of C between two points of a run (rad): a quarter turn, well inside the half
#: turn beyond which an angle read from poses is ambiguous.
MOST_C_STEP_RAD = 0.5 * math.pi


def _rapids_below_top(program, machine, top: float) -> tuple[str, ...]:
    """The note on the rapids the program runs with the tip below the stock's top (as
    commanded, on the nominal machine): the turning engine cuts the turning runs alone, and
    on a machine such a rapid is a crash."""
    source = getattr(program, "source", "<program>")
    q, kinds, _, lines = _axis_values(program, machine, source)
    z = machine.tool_pose(q)[:, 2, 3]
    # ending below the top, or starting there and moving across (a retract straight out of
    # the cut along Z is none)
    across = np.any(np.diff(np.delete(q, machine.axes.index("Z"), axis=1), axis=0,
                            prepend=np.nan) != 0.0, axis=1)
    below = np.flatnonzero((kinds == KIND_RAPID)
                           & ((z < top) | ((np.roll(z, 1) < top) & across)))
    below = below[below > 0]  # the first point is the start, not a move
    if not below.size:
        return ()
    line_text = _line_text(program)
    shown = ", ".join(line_text(lines[k]) for k in below[:10])
    more = f" and {below.size - 10} more" if below.size > 10 else ""
    return (f"rapids with the tip below the stock's top (z = {top * 1e6:.6g} um) at "
            f"{shown}{more}: the turning engine cuts only the runs of feeds that turn C, so "
            "they are not in the part; on a machine a rapid there is a crash",)


def _untimed_moves(program, machine) -> tuple[float, tuple[str, ...]]:
    """The time ``program``'s dwells wait (s), and the notes on its moves whose time is
    hardly what it meant (`machinesim.motion.timing.slow_move_notes`, as `plan` notes
    them): the longest feed move when it takes more than a day, turning or not (a plunge
    at F0.000001), and the longest dwell beyond an hour. Neither a plunge nor a dwell is
    in a turning run, which `_timed_runs` times. A chord of an arc (a G02/G03 plunge) takes
    its piece of arc over F (`machinesim.nc.Program.arc_lengths`) when it is a chord of it
    (`machinesim.motion.timing.on_chord`), as `plan` times it; a move that only kept an arc
    length (a program cut from an arc's middle) its own length. Dwells and feed moves that
    take more than `machinesim.nc.words.MAX_PROGRAM_TIME_S` in all are refused
    (`machinesim.motion.timing.check_total_time`), as `plan` refuses them."""
    kinds = np.asarray(program.kinds)
    feeds = np.asarray(program.feeds, dtype=np.float64)
    durations = np.where(kinds == KIND_DWELL, np.asarray(program.dwells, dtype=np.float64),
                         0.0)
    source = getattr(program, "source", "<program>")
    q, moved, _, _ = _axis_values(program, machine, source)
    first = len(kinds) - len(moved)  # a move from a point of known axis values: later ones
    linear = np.flatnonzero(kinds[first + 1:] == KIND_LINEAR) + first + 1
    lengths = _lengths(q[linear - first - 1], q[linear - first], machine.axes)
    arcs = getattr(program, "arc_lengths", None)  # none in a program pickled before them
    if isinstance(arcs, np.ndarray) and arcs.shape == kinds.shape:
        on_arc = np.flatnonzero(~np.isnan(arcs[linear]))
        ends = q[linear[on_arc] - first] - q[linear[on_arc] - first - 1]
        on_arc = on_arc[on_chord(arcs[linear[on_arc]], ends, machine.rotary)]
        lengths[on_arc] = arcs[linear[on_arc]]
    with np.errstate(divide="ignore", invalid="ignore"):  # F none or 0: no time, no note
        times = np.maximum(lengths / feeds[linear],
                           _at_limits(q[linear - first - 1], q[linear - first],
                                      machine.rapid_rate))
    durations[linear] = np.where(np.isfinite(times), times, 0.0)
    check_total_time(durations, kinds, np.asarray(program.lines), program,
                     block_of=lambda move: _block_number(program, move))
    return float(durations[kinds == KIND_DWELL].sum()), slow_move_notes(
        durations, kinds, np.asarray(program.lines), feeds, program)


def _block_number(program, move: int) -> int | None:
    """The N word of ``program``'s move ``move`` (None: none), for a refusal's line."""
    blocks = getattr(program, "block_numbers", None)
    if not isinstance(blocks, np.ndarray) or not 0 <= move < blocks.size or blocks[move] < 0:
        return None
    return int(blocks[move])


def _program_moves(program, machine) -> SimpleNamespace:
    """``program``'s axis values per move (modal; NaN before an axis is first set) and
    source lines, as `machinesim.cutting.program`'s travel check reads a cut's moves. The
    moves are straight in axis space, so their ends bound them."""
    targets = np.asarray(program.targets, dtype=np.float64)
    q = modal_values(targets[:, [AXES.index(a) for a in machine.axes]])
    return SimpleNamespace(q=q, line=np.asarray(program.lines))


def turning_runs(program, machine) -> list[tuple[np.ndarray, np.ndarray]]:
    """The commanded motion of each turning run of ``program`` on ``machine``: times from
    the run's start (s, shape (n,)) and axis values (SI, shape (n, n_axes), the machine's
    axis order), one row per point, the run's start point first (module docstring)."""
    return _timed_runs(program, machine)


def _timed_runs(program, machine, *, with_lines: bool = False) -> list[tuple]:
    """`turning_runs`' runs (``(t, points)``), with points added within quarter turns; with
    ``with_lines``, each step's program line too (``(t, points, lines)``)."""
    source = getattr(program, "source", "<program>")
    q, kinds, feeds, lines = _axis_values(program, machine, source)
    out = []
    c_column = machine.axes.index("C")
    line_text = _line_text(program)
    for first, last in _turning_runs(q, kinds, c_column, lines, source, line_text,
                                     _spindle_hint(program)):
        points = q[first - 1:last + 1]  # moves first..last: points first-1..last
        moves = slice(first, last + 1)
        durations = _durations(points, feeds[moves], machine.axes, lines[moves], source,
                               line_text, machine.rapid_rate)
        t = np.concatenate([[0.0], np.cumsum(durations)])
        t, points, rows = _within_quarter_turns(t, points, _c_steps(points[:, c_column]))
        out.append((t, points, lines[moves][rows]) if with_lines else (t, points))
    return out


def _c_steps(c: np.ndarray) -> np.ndarray:
    """Pieces each step of ``c`` (rad) takes to turn at most `MOST_C_STEP_RAD` a piece."""
    return np.ceil(np.abs(np.diff(c)) / MOST_C_STEP_RAD).astype(np.int64)


def _within_quarter_turns(t: np.ndarray, points: np.ndarray, steps: np.ndarray):
    """``(t, points, rows)``: points added on each step (linearly in time and axis values, as
    the control interpolates a move) to split it into ``steps`` pieces (`_c_steps`: none
    turns C by more than `MOST_C_STEP_RAD`), and the step each piece lies on.

    The edge path's angle is read back from the tool's poses (`edge_path_from_poses`),
    which know C only modulo a turn: a move of 50 turns in one block (a facing cut) would
    read as no turn at all. Added points lie on the move, so the path is the same."""
    if (steps <= 1).all():
        return t, points, np.arange(len(steps))
    steps = np.maximum(steps, 1)
    rows = np.repeat(np.arange(len(steps)), steps)
    fraction = (np.arange(steps.sum()) - np.repeat(np.cumsum(steps) - steps, steps) + 1.0
                ) / np.repeat(steps, steps)
    dense = points[rows] + fraction[:, None] * (points[rows + 1] - points[rows])
    times = t[rows] + fraction * (t[rows + 1] - t[rows])
    return np.concatenate([t[:1], times]), np.concatenate([points[:1], dense]), rows


def _axis_values(program, machine, source: str):
    """Per move of ``program``: the machine's axis values (modal), kinds, feeds, lines; from
    the first move at which every machine axis has a value."""
    targets = np.asarray(program.targets, dtype=np.float64)
    columns = [AXES.index(a) for a in machine.axes]
    extra = [a for a in AXES if a not in machine.axes
             and not np.all(np.isnan(targets[:, AXES.index(a)]))]
    if extra:
        raise InputError(f"{source}: the program moves {', '.join(extra)}, which "
                         f"{machine.name} does not have (axes {', '.join(machine.axes)})",
                         key="program")
    q = modal_values(targets[:, columns])
    known = np.flatnonzero(~np.isnan(q).any(axis=1))
    if known.size == 0:
        raise InputError(f"{source}: no move sets every axis of {machine.name} "
                         f"({', '.join(machine.axes)}); the turn has no start", key="program")
    start = int(known[0])
    kinds = np.asarray(program.kinds)
    lines = np.asarray(program.lines)
    for k in range(start):
        if kinds[k] == KIND_LINEAR:
            raise InputError(f"{source}, {_line_text(program)(lines[k])}: a feed move before "
                             f"every axis of {machine.name} has a value", key="program")
    feeds = np.asarray(program.feeds, dtype=np.float64)
    return q[start:], kinds[start:], feeds[start:], lines[start:]


def _line_text(program) -> Callable[[int], str]:
    """How a refusal names a line of ``program``: ``line 12 (N120)`` where its block has an
    N word (`machinesim.nc.Program.line_text`), ``line 12`` for a program that keeps none."""
    text = getattr(program, "line_text", None)
    if callable(text):
        return lambda line: text(int(line))
    return lambda line: line_of(int(line))


def _spindle_hint(program) -> str:
    """What a refusal of a program without C turning adds when the program runs the spindle
    by M03/M04 instead (as a conventional lathe program does): that is not simulated."""
    codes = getattr(program, "m_codes", {})
    runs = [k for k, m in sorted(codes.items()) if 3 in m or 4 in m]
    if not runs:
        return ""
    code = 3 if 3 in codes[runs[0]] else 4
    return (f" (M0{code} at {_line_text(program)(program.lines[runs[0]])} runs the spindle at "
            "S rpm, which is not simulated: program C as an axis, as a slow-tool-servo program "
            "does, e.g. G01 X0 C18000 F7200 for 50 turns)")


def _turning_runs(q, kinds, c_column: int, lines, source: str,
                  line_text: Callable[[int], str], hint: str = "") -> list[tuple[int, int]]:
    """(first, last) move index of each run of consecutive feed moves that turn C; a rapid
    inside one is refused, naming its line by ``line_text`` (`_line_text`)."""
    c = q[:, c_column]
    dc = np.abs(np.diff(c, prepend=c[0]))
    turning = (kinds == KIND_LINEAR) & (dc > STILL_C_RAD * np.maximum(1.0, np.abs(c)))
    turning[0] = False  # the first point is a start, not a move from a known point
    runs, k = [], 0
    while k < turning.size:
        if turning[k]:
            first = k
            while k + 1 < turning.size and turning[k + 1]:
                k += 1
            runs.append((first, k))
        k += 1
    if not runs:
        raise InputError(f"{source}: no feed move turns C: nothing to turn{hint}",
                         key="program")
    rapid = np.flatnonzero(kinds == KIND_RAPID)
    for first, last in runs:
        inside = rapid[(rapid >= first) & (rapid <= last)]
        if inside.size:
            raise InputError(f"{source}, {line_text(lines[inside[0]])}: a rapid inside a "
                             f"turning run", key="program")
    return runs


def _durations(points: np.ndarray, feeds: np.ndarray, axes: tuple, lines: np.ndarray,
               source: str, line_text: Callable[[int], str], rapid_rate) -> np.ndarray:
    """Time of each move between consecutive ``points`` at ``feeds`` (m/s), s: the length in
    mm with rotary axes in degrees, over F in mm/s (FANUC), or the time its slowest axis
    takes at its velocity limit ``rapid_rate`` (per axis, SI) where that is longer (a feed
    beyond it is clamped, `machinesim.motion.timing.move_duration`); a move without a
    positive feed is refused naming its ``lines`` in ``source`` (by ``line_text``).

    Every move here turns C, so none is the chord of an arc that keeps its arc's length
    (`machinesim.nc.Program.arc_lengths`): an arc block leaves C where it was unless it
    names C, and an arc that turns a rotary axis keeps its chords' feed rule (its degrees
    count in the feed length), as `move_durations` times it. The chord rule here is that
    rule, not an approximation of it."""
    length = _lengths(points[:-1], points[1:], axes)
    bad = ~(np.isfinite(feeds) & (feeds > 0.0))
    if bad.any():
        first = int(np.flatnonzero(bad)[0])
        value = float(feeds[first])
        got = "none" if math.isnan(value) else f"F{value * 6e4:g} (mm/min)"
        raise InputError(f"{source}, {line_text(lines[first])}: expected a positive feed on "
                         f"every turning move, got {got}", key="F")
    return np.maximum(length / feeds, _at_limits(points[:-1], points[1:], rapid_rate))


def _at_limits(starts: np.ndarray, ends: np.ndarray, rapid_rate) -> np.ndarray:
    """The time (s) of each move from ``starts`` to ``ends`` (rows, SI) with its slowest
    axis at its velocity limit (``rapid_rate``, per axis, SI): no feed runs it faster."""
    return (np.abs(ends - starts) / np.asarray(rapid_rate, dtype=np.float64)).max(axis=1)


def _lengths(starts: np.ndarray, ends: np.ndarray, axes: tuple) -> np.ndarray:
    """The length of each move from ``starts`` to ``ends`` (rows, SI) as F measures it, in
    mm with rotary axes in degrees (FANUC)."""
    scale = np.array([math.degrees(1.0) * 1e-3 if a in ROTARY_AXES else 1.0 for a in axes])
    return np.sqrt(np.sum(((ends - starts) * scale) ** 2, axis=1))
