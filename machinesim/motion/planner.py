"""`plan`: a program's moves, as arrays, become a `Trajectory`, every step vectorised."""

from __future__ import annotations

import math
import os

import numpy as np

from machinesim.exceptions import InputError, NCProgramError
from machinesim.motion.chords import (
    MAX_SUBSTEPS,
    hold_corners,
    hold_raised,
    substeps,
)
from machinesim.motion.faces import ProfileEdges, face_substeps, profile_substeps
from machinesim.motion.following import StepRule, follow_plan
from machinesim.motion.steps import wrap_steps
from machinesim.motion.timing import (
    LONG_DWELL_S,
    M_PER_MM,
    NUMBER,
    SLOW_MOVE_S,
    check_total_time,
    move_duration,
    move_durations,
    slow_move_notes,
)
from machinesim.motion.tool_paths import ToolPaths
from machinesim.motion.trajectory import IdealServo, ServoModel, Trajectory
from machinesim.nc.moves import feed_problem
from machinesim.nc.program import AXES, KIND_DWELL, KIND_LINEAR, MOVE_KINDS
from machinesim.tolerances import CHORD_TOLERANCE_M, MAX_STEP_TURN_RAD


def _check_program(program) -> None:
    """Refuse, naming it, what is no program (a path, None): `_program_arrays` reads a
    `machinesim.nc.Program`'s arrays or any object's ``moves``."""
    arrays = getattr(program, "targets", None), getattr(program, "kinds", None)
    if not all(isinstance(a, np.ndarray) for a in arrays) and not hasattr(program, "moves"):
        shown = type(program).__name__ + (f" {program!r:.60}" if isinstance(program, str)
                                          else "")
        raise InputError(f"Expected program as a machinesim.nc.Program, got {shown}; read an "
                         "NC file with machinesim.nc.read_program(path) (text: "
                         "parse_program)", key="program")


def _start_values(start, axes: tuple[str, ...]) -> np.ndarray:
    """``start`` as float64 axis values: numbers only (``"home"``, ``["0", ...]``, booleans
    and None are refused, not converted or left to numpy's ValueError)."""
    try:
        values = np.asarray(start)
        flags = any(isinstance(v, bool | np.bool_)  # [True, 0, ...] is int64 to numpy
                    for v in np.asarray(start, dtype=object).flat)
    except (TypeError, ValueError):  # ragged
        values, flags = None, True
    if values is None or flags or values.dtype.kind not in "iuf":
        raise InputError(f"Expected start as axis values (m, rad), one per axis of "
                         f"{''.join(axes)}, got {start!r:.80}", key="start")
    return values.astype(np.float64)


def _program_arrays(program):
    """targets (N, 6) (columns `machinesim.nc.AXES`, NaN: no value yet), kinds (N,) int8
    (index into MOVE_KINDS), feeds (N,) m/s (NaN: none), dwells (N,) s, lines (N,) int64,
    and arc lengths (N,) m (NaN: no arc's chord; None for a program that keeps none).

    A `machinesim.nc.Program` holds these arrays; any other object with ``moves`` (each with
    ``kind``, ``target``, ``feed_m_per_s``, ``dwell_s``, ``line``, and optionally
    ``arc_length_m``, as `machinesim.nc.Move` has) is read move by move, so that its arc
    chords are timed as the program's were.
    """
    arrays = getattr(program, "targets", None), getattr(program, "kinds", None)
    if all(isinstance(a, np.ndarray) for a in arrays):
        return (program.targets, program.kinds, program.feeds, program.dwells,
                program.lines, _arc_lengths(program, len(program.kinds)))
    moves = tuple(program.moves)
    targets = np.full((len(moves), len(AXES)), np.nan)
    column = {a: i for i, a in enumerate(AXES)}
    for row, move in enumerate(moves):
        _check_move(move, _source(program))
        for letter, value in move.target.items():
            if letter not in column:
                raise NCProgramError(f"unknown axis {letter!r}; expected one of "
                                     f"{' '.join(AXES)}", source=_source(program),
                                     line=move.line, key=str(letter))
            targets[row, column[letter]] = value
    kinds = np.array([MOVE_KINDS.index(m.kind) for m in moves], dtype=np.int8)
    feeds = np.array([np.nan if m.feed_m_per_s is None else m.feed_m_per_s for m in moves])
    dwells = np.array([m.dwell_s for m in moves], dtype=np.float64)
    lines = np.array([m.line for m in moves], dtype=np.int64)
    arcs = [getattr(m, "arc_length_m", None) for m in moves]
    arcs = np.array([np.nan if a is None else a for a in arcs], dtype=np.float64)
    return targets, kinds, feeds, dwells, lines, arcs


def _arc_lengths(program, count: int) -> np.ndarray | None:
    """The length of arc (m) each move of ``program`` stands for, NaN where none
    (`machinesim.nc.Program.arc_lengths`); None for a program that keeps none."""
    lengths = getattr(program, "arc_lengths", None)
    if not isinstance(lengths, np.ndarray) or lengths.shape != (count,):
        return None
    return lengths


def _check_move(move, source: str) -> None:
    """Refuse, naming its line, a move (of a program read move by move) whose kind, axis
    values, feed or dwell `plan` would turn into no time or a wrong one: a `Move` checks
    these when made, any other object nothing (a feed of 0 m/s took inf s and NaN sample
    times, a negative one its axes' time at their velocity limit, a dwell of -1 s ran the
    clock back)."""
    kind, feed, dwell = move.kind, move.feed_m_per_s, move.dwell_s
    if kind not in MOVE_KINDS:
        raise NCProgramError(f"kind must be one of {', '.join(MOVE_KINDS)}, got {kind!r}",
                             source=source, line=move.line, key="kind")
    for letter, value in move.target.items():
        if not (isinstance(value, NUMBER)
                and not isinstance(value, bool | np.bool_) and math.isfinite(value)):
            raise NCProgramError(f"axis value {letter} must be a finite number (m, rad), "
                                 f"got {value!r}", source=source, line=move.line,
                                 key=str(letter))
    if feed is not None and not (isinstance(feed, NUMBER)
                                 and kind == "linear" and 0.0 < feed < math.inf):
        raise NCProgramError(feed_problem(kind, feed) + " (None: no feed given)",
                             source=source, line=move.line, key="feed_m_per_s")
    if not (isinstance(dwell, NUMBER)
            and 0.0 <= dwell < math.inf and (kind == "dwell" or dwell == 0.0)):
        raise NCProgramError(f"dwell_s must be >= 0 s for a dwell and 0.0 otherwise, got "
                             f"{dwell!r} for a {kind} move", source=source, line=move.line,
                             key="dwell_s")
    arc = getattr(move, "arc_length_m", None)
    if arc is not None and not (isinstance(arc, NUMBER) and not isinstance(arc, bool | np.bool_)
                                and 0.0 <= arc < math.inf):
        raise NCProgramError(f"arc_length_m must be None (no arc) or a length >= 0 m, got "
                             f"{arc!r}", source=source, line=move.line, key="arc_length_m")


def _block(program, move) -> int | None:
    """The N word of ``program``'s move ``move`` (`Program.block_numbers`), None when its
    block has none: a refusal names it beside the line ('line 12 (N120)'). A program that
    keeps no N words (an object with the arrays but neither ``block_numbers`` nor
    ``moves``, which `_program_arrays` reads) has none: its refusal names the line alone."""
    blocks = getattr(program, "block_numbers", None)
    if isinstance(blocks, np.ndarray) and blocks.ndim == 1 and move < blocks.size:
        number = blocks[move]
    elif hasattr(program, "moves"):
        number = getattr(tuple(program.moves)[move], "block_number", None)
    else:
        return None
    if not isinstance(number, int | np.integer) or isinstance(number, bool):
        return None
    return None if number < 0 else int(number)


def _source(program) -> str:
    return getattr(program, "source", "<program>")


def plan(program, machine, errors=None, *, start=None, tool_points=None,
         chord_tolerance: float = CHORD_TOLERANCE_M, servo: ServoModel | None = None,
         face_radius: float = 0.0, profile: ProfileEdges | None = None) -> Trajectory:
    """Sample ``program`` on ``machine`` into a `Trajectory`.

    Parameters
    ----------
    program : machinesim.nc.Program
    machine : machinesim.Machine or str
        A machine, or its name or URDF path (`machinesim.load_machine`), as `cut` takes it.
    errors : ErrorModel, optional
        The machine's errors: the chord check follows the real (erroneous) tool path.
    start : array_like, shape (n_axes,), optional
        Axis values before the first block (default zeros); axes the program never sets
        stay there.
    tool_points : ndarray, shape (k, 3), optional
        Points of the tool in the tool_tip frame (m) whose paths must stay within the chord
        tolerance; the edge (origin) is always included.
    face_radius : float
        Half-width (m) of the tool's widest flat face normal to its axis, a flat end mill's
        radius (`machinesim.tools.flat_face_radius`): a move that tilts the tool is split
        further, so that the hull of each sub-step's two poses leaves the face's true sweep
        by at most the chord tolerance (`machinesim.motion.faces`). 0: no flat face.
    profile : machinesim.motion.faces.ProfileEdges, optional
        A planar tool's straight edges (and the stock's top): a move that turns a rotary
        axis is split further, so that the hull of each sub-step's two poses leaves no
        edge's true sweep by more than the chord tolerance (`edge_substeps`: the first-order
        waist of a profile tilting while it moves). None: no such rule.
    chord_tolerance : float
        Largest allowed distance, m, between a sub-step's chord and the true path.
    servo : ServoModel, optional
        Follow-up model (default: ideal), applied to each run of consecutive feed moves as
        one continuous motion, and to each rapid and dwell alone (`follow_runs`). A run
        also ends at an exact stop (`Program.exact_stops`: G09, G61). Each motion ends in
        position: its last sample is the command's end, so the tool goes on from the last
        lagged sample to it (the time the axes take to settle is not added to the
        program's). `Trajectory.peak_lag` keeps each axis' largest lag. The followed
        samples keep the commanded sub-steps' rules (the chord tolerance, at most 45 deg a
        step): a motion is followed again on a finer sampling where they do not, and its
        settling step split (`machinesim.motion.following`).

    Raises
    ------
    NCProgramError
        At the first move (in program order) that sets an axis the machine lacks, feeds
        without a feed rate, or would need more than `MAX_SUBSTEPS` sub-steps; at a move
        whose followed path (``servo``) would, naming the servo model.
    """
    _check_program(program)
    if isinstance(machine, str | os.PathLike):
        from machinesim.machines import load_machine

        machine = load_machine(machine)
    axes = tuple(machine.axes)
    n_axes = len(axes)
    q0 = np.zeros(n_axes) if start is None else _start_values(start, axes)
    if q0.shape != (n_axes,):
        raise InputError(f"start must have shape ({n_axes},) for axes {''.join(axes)}, "
                         f"got {q0.shape}")
    if not np.all(np.isfinite(q0)):
        raise InputError(f"start must be finite axis values, got {q0.tolist()}")
    if not chord_tolerance > 0.0:
        raise InputError(f"chord_tolerance must be positive, got {chord_tolerance}")
    if not (isinstance(face_radius, int | float) and 0.0 <= face_radius < math.inf):
        raise InputError(f"face_radius must be a finite length >= 0 (m), got {face_radius!r}",
                         key="face_radius")
    if profile is not None and not isinstance(profile, ProfileEdges):
        raise InputError(f"profile must be a machinesim.motion.faces.ProfileEdges or None, "
                         f"got {type(profile).__name__}", key="profile")
    points = np.zeros((1, 3)) if tool_points is None else np.vstack(
        [np.zeros((1, 3)), np.asarray(tool_points, dtype=np.float64).reshape(-1, 3)])
    targets, kinds, feeds, dwells, lines, arcs = _program_arrays(program)
    source = _source(program)
    count = len(kinds)

    # where each move starts and ends: an axis the program has not set stays at start
    ends = np.empty((count, n_axes))
    for i, letter in enumerate(axes):
        if letter in AXES:
            column = targets[:, AXES.index(letter)]
            ends[:, i] = np.where(np.isnan(column), q0[i], column)
        else:
            ends[:, i] = q0[i]
    starts = np.empty_like(ends)
    if count:
        starts[0] = q0
        starts[1:] = ends[:-1]
    delta = ends - starts

    # errors the moves themselves show: the first in program order wins
    stop, error = count, None
    for c, letter in enumerate(AXES):
        if letter in axes:
            continue
        given = np.flatnonzero(~np.isnan(targets[:stop, c]))
        if given.size and given[0] < stop:
            stop = int(given[0])
            error = NCProgramError(f"axis {letter} is not on {machine.name} (axes "
                                   f"{''.join(axes)})", source=source,
                                   line=int(lines[stop]), block=_block(program, stop), key=letter)
    moved = np.zeros(stop, dtype=bool)
    for i in range(n_axes):
        moved |= delta[:stop, i] != 0.0
    unfed = np.flatnonzero((kinds[:stop] == KIND_LINEAR) & np.isnan(feeds[:stop]) & moved)
    if unfed.size:
        stop = int(unfed[0])
        error = NCProgramError("a feed move (G01, or an arc: G02/G03) with no feed rate F given "
                               "so far; expected an F word in its block or one before it",
                               source=source, line=int(lines[stop]),
                               block=_block(program, stop), key="F")

    # rotary moves, and moves of an axis whose errors vary along it (a straightness or
    # angular table bends a straight move): split to the chord tolerance (only those
    # before a located error)
    steps = np.ones(stop, dtype=np.int64)
    rotary = np.asarray(machine.rotary, dtype=bool)
    bending = rotary.copy()
    if errors is not None:
        for var in machine.binding(errors).varying:
            bending[var.axis] = True
    if bending.any():
        turns = np.zeros(stop, dtype=bool)
        for i in np.flatnonzero(bending).tolist():
            turns |= delta[:stop, i] != 0.0
        turning = np.flatnonzero(turns & (kinds[:stop] != KIND_DWELL))
        if turning.size:
            paths = ToolPaths(machine, errors, points)
            stepped = wrap_steps(paths, starts[turning], delta[turning], chord_tolerance)
            if stepped:
                move, axis, at, size, name = stepped[0]
                symbol = name.rpartition(".")[2]
                table = errors.component[axes[axis]][symbol]
                unit, per = ("urad", 1e-6) if symbol[1] in "ABC" else ("um", 1e-6)
                ends = [f"{v / per:.6g} {unit} at {math.degrees(x):g} deg" for x, v in
                        ((table.positions[0], table.values[0]),
                         (table.positions[-1], table.values[-1]))]
                raise NCProgramError(
                    f"{axes[axis]} passes {math.degrees(at):g} deg, where {name}, a table of a "
                    f"whole turn repeated each turn, wraps with values a turn apart that "
                    f"differ ({ends[0]}, {ends[1]}): the tool path steps {size * 1e9:.3g} nm "
                    f"there, more than the chord "
                    f"tolerance {chord_tolerance * 1e9:g} nm, and no chord follows a step; give "
                    "the table the same value a turn apart",
                    source=source, line=int(lines[turning[move]]),
                    block=_block(program, turning[move]))
            found, failed, stalls = substeps(paths, starts[turning], delta[turning],
                                             chord_tolerance)
            # a sub-step turns the tool by at most its rotary axes' turns added up; the
            # cutting engine takes a sweep for the hull of its two poses only up to
            # MAX_STEP_TURN_RAD (a quarter turn), which a chord tolerance as coarse as the
            # tool would pass (--chord-nm 1e9, a C180. in one step): half of it, the
            # machine's angular errors far inside the rest; the counts raised to it are
            # checked again (a turn of 720 deg is one point at its ends and middle)
            turn = np.abs(delta[turning][:, rotary]).sum(axis=1)
            least = np.ceil(turn / (MAX_STEP_TURN_RAD / 2.0))
            hold_raised(paths, starts[turning], delta[turning], chord_tolerance, found,
                        failed, stalls, least)
            unfollowed = (failed, stalls, paths, axes, rotary, starts, delta, turning, lines,
                          source, chord_tolerance, program)
            _refuse_failed(*unfollowed)
            bad = _first_beyond(least, turning)
            if bad is not None:
                turned = math.degrees(float(turn[np.argmax(least > MAX_SUBSTEPS)]))
                raise NCProgramError(
                    f"a rotary move of {turned:.6g} deg would need more than {MAX_SUBSTEPS} "
                    "sub-steps of at most "
                    f"{math.degrees(MAX_STEP_TURN_RAD / 2.0):g} deg (what a sweep's hull "
                    "stands for, with room for the machine's errors); split it into moves",
                    source=source, line=int(lines[bad]), block=_block(program, bad))
            held = np.maximum(found, least.astype(np.int64))
            found = face_substeps(machine, errors, starts[turning], delta[turning],
                                  np.maximum(held, 1), face_radius, chord_tolerance)
            found = profile_substeps(machine, errors, starts[turning], delta[turning], found,
                                     rotary, profile, chord_tolerance)
            bad = _first_beyond(found, turning)
            if bad is not None:
                what = (f"the tool's flat face ({face_radius * 1e3:g} mm across its axis)"
                        if face_radius > 0.0 else "the tool's profile while it moves")
                raise NCProgramError(
                    f"a move that tilts {what} would need more than {MAX_SUBSTEPS} "
                    f"sub-steps to keep the face within {chord_tolerance * 1e9:g} nm; raise "
                    "chord_tolerance (--chord-nm on the command line)",
                    source=source, line=int(lines[bad]), block=_block(program, bad))
            # counts the faces and profiles raised: a corner of an error table (or a
            # polynomial's bow) the old sub-steps held at a node can lie inside a new one
            raised = np.flatnonzero((found > held) & ~failed)
            if raised.size:
                found = np.array(found, dtype=np.int64)
                hold_corners(paths, starts[turning], delta[turning], chord_tolerance, found,
                             failed, stalls, raised)
                stalls.sort(key=lambda stall: stall.move)
                _refuse_failed(*unfollowed)
            steps[turning] = found
    if error is not None:
        raise error

    with np.errstate(over="ignore", invalid="ignore"):  # refused just below
        durations = move_durations(kinds, starts, ends, feeds, dwells, rotary,
                                   np.asarray(machine.rapid_rate, dtype=np.float64), arcs)
    check_total_time(durations, kinds, lines, program,
                     block_of=lambda move: _block(program, move))
    # times add up move after move from 0.0, as a running sum does (np.cumsum is sequential)
    clock = np.cumsum(np.concatenate([[0.0], durations]))
    cutting = float(np.cumsum(np.concatenate([[0.0], durations[kinds == KIND_LINEAR]]))[-1])
    peak_lag = None
    if servo is not None and type(servo) is not IdealServo:
        # the followed path held to the rules the commanded sub-steps keep (`following`)
        rule = StepRule(machine, errors, points, bending, chord_tolerance, face_radius,
                        profile)
        q, t, offsets, peak_lag = follow_plan(
            servo, lambda split: _samples(starts, delta, clock[:-1], durations, split),
            steps, kinds, getattr(program, "exact_stops", ()), rule, lines, source,
            lambda move: _block(program, move))
    else:
        q, t, offsets = _samples(starts, delta, clock[:-1], durations, steps)
    q.flags.writeable = False
    t.flags.writeable = False
    offsets.flags.writeable = False
    kinds_out = np.array(kinds, dtype=np.int8)
    lines_out = np.array(lines, dtype=np.int64)
    kinds_out.flags.writeable = False
    lines_out.flags.writeable = False
    notes = slow_move_notes(durations, kinds, lines, feeds, program)
    return Trajectory(axes, q, t, offsets, kinds_out, lines_out, float(clock[-1]), cutting,
                      notes=notes, peak_lag=peak_lag)


def _refuse_failed(failed, stalls, paths, axes, rotary, starts, delta, turning, lines, source,
                   tolerance, program) -> None:
    """Refuse, naming its line, the first move (of ``turning``) whose chords no count up to
    `MAX_SUBSTEPS` holds: its path steps (``stalls``: where, and the table that does it),
    or it needs more sub-steps than that."""
    if not failed.any():
        return
    first = int(np.argmax(failed))
    bad = int(turning[first])
    stall = next((s for s in stalls if s.move == first), None)
    if stall is not None:
        raise NCProgramError(
            _stall_message(stall, paths, axes, rotary, starts[bad], delta[bad], tolerance),
            source=source, line=int(lines[bad]), block=_block(program, bad))
    what = "a rotary move" if np.any(delta[bad, rotary] != 0.0) else "a move"
    raise NCProgramError(
        f"{what} would need more than {MAX_SUBSTEPS} sub-steps to keep the chord within "
        f"{tolerance * 1e9:g} nm; raise chord_tolerance (--chord-nm on the command line)",
        source=source, line=int(lines[bad]), block=_block(program, bad))


def _first_beyond(counts: np.ndarray, moves: np.ndarray) -> int | None:
    """The first of ``moves`` (indices of blocks) whose sub-step ``counts`` pass
    `MAX_SUBSTEPS`, for its line in a refusal; None when none does."""
    over = counts > MAX_SUBSTEPS
    return int(moves[int(np.argmax(over))]) if np.any(over) else None


def _stall_message(stall, paths, axes, rotary, start, delta, tolerance) -> str:
    """Why a move's chords do not converge (`steps.Stall`): where its path steps, by how
    much, and the error table that steps there if one does."""
    def value(i, x):
        return f"{math.degrees(x):.6g} deg" if rotary[i] else f"{x / M_PER_MM:.6g} mm"

    moving = np.flatnonzero(delta != 0.0).tolist()
    at = start + (stall.low + stall.high) / 2 * delta
    where = ", ".join(f"{axes[i]} = {value(i, at[i])}" for i in moving)
    span = ", ".join(f"{axes[i]} {value(i, abs(delta[i]) * (stall.high - stall.low))}"
                     for i in moving)
    (n0, d0), (n1, d1) = stall.tried
    cause = _stepping_table(stall, paths, axes, rotary, start, delta)
    return (
        f"a move whose path steps: its chords do not converge on it ({d0 * 1e9:.3g} nm off "
        f"at {n0} sub-steps, still {d1 * 1e9:.3g} nm at {n1}, where a smooth path's "
        f"deviation falls as 1/n**2); at {where} the path leaves the chord of a piece of "
        f"{span} (1/{round(1 / (stall.high - stall.low))} of the move, finer than "
        f"{MAX_SUBSTEPS} sub-steps split it) by {stall.deviation * 1e9:.3g} nm, more than "
        f"the chord tolerance {tolerance * 1e9:g} nm. "
        + (cause or "An error model whose value changes by about that over less than "
           "that span does this (a step, which no chord follows); smooth it there, or "
           "raise chord_tolerance above the step (--chord-nm on the command line)"))


def _stepping_table(stall, paths, axes, rotary, start, delta) -> str | None:
    """The steepest segment of an error table on a moving axis around the piece where the
    path steps, described, or None."""
    best = None
    for axis, table, name in paths.tables:
        if delta[axis] == 0.0:
            continue
        ends = sorted(start[axis] + f * delta[axis] for f in (stall.low, stall.high))
        pad = ends[1] - ends[0]
        lo, hi = ends[0] - pad, ends[1] + pad
        p, v = table.positions, table.values
        period = getattr(table, "period", None)
        centre = (lo + hi) / 2
        if period is not None and not p[0] <= centre <= p[-1]:
            # read a whole number of turns back into the table, as `each_turn` does
            shift = p[0] + float(np.mod(centre - p[0], period)) - centre
            lo, hi = lo + shift, hi + shift
        first = max(int(np.searchsorted(p, lo, side="right")) - 1, 0)
        last = min(int(np.searchsorted(p, hi, side="left")), len(p) - 1)
        for j in range(first, last):
            change = abs(float(v[j + 1] - v[j]))
            slope = change / float(p[j + 1] - p[j])
            if best is None or slope > best[0]:
                best = (slope, axis, name, j, p, v)
    if best is None:
        return None
    _, axis, name, j, p, v = best
    symbol = name.rpartition(".")[2]
    unit, per = ("urad", 1e-6) if symbol[1:2] in ("A", "B", "C") else ("um", 1e-6)

    def at(x):
        return f"{math.degrees(x):.9g} deg" if rotary[axis] else f"{x / M_PER_MM:.9g} mm"

    return (f"The error table {name} changes from {v[j] / per:.6g} to {v[j + 1] / per:.6g} "
            f"{unit} between {axes[axis]} = {at(p[j])} and {at(p[j + 1])} there, a step no "
            "chord follows: give the change a span the sub-steps can follow, or raise "
            "chord_tolerance above the step (--chord-nm on the command line)")


def _linspace_by_product(most: int = 4096) -> bool:
    """Whether ``np.linspace(0, 1, n + 1)`` is ``i * (1.0 / n)`` with its last value 1.0 (as
    numpy computes it), so that fractions can be formed for all samples at once."""
    for n in (*range(1, 300), 997, most):
        f = np.arange(n + 1) * (1.0 / n)
        f[-1] = 1.0
        if not np.array_equal(f, np.linspace(0.0, 1.0, n + 1)):
            return False
    return True


_BY_PRODUCT = _linspace_by_product()
#: Samples formed in one pass of `_samples`.
_SAMPLES_PER_CHUNK = 1 << 20


def _samples(starts, delta, t0, durations, steps):
    """Samples ``start + f * delta`` and times ``t0 + f * duration`` of every move,
    ``f = linspace(0, 1, steps + 1)``, end to end."""
    count, n_axes = starts.shape
    counts = steps + 1
    offsets = np.zeros(count + 1, dtype=np.int64)
    np.cumsum(counts, out=offsets[1:])
    total = int(offsets[-1])
    q = np.empty((total, n_axes))
    t = np.empty(total)
    if np.all(steps == 1):  # the common case: rows 2i and 2i + 1
        for k, f in enumerate((0.0, 1.0)):
            q[k::2] = starts + f * delta
            t[k::2] = t0 + f * durations
        return q, t, offsets
    # moves a chunk at a time, so that the per-sample work arrays stay small
    bounds = np.searchsorted(offsets, np.arange(0, total, _SAMPLES_PER_CHUNK), side="right") - 1
    for first, last in zip(bounds.tolist(), [*bounds[1:].tolist(), count], strict=True):
        if last > first:
            _sample_moves(first, last, starts, delta, t0, durations, steps, offsets, q, t)
    return q, t, offsets


def _sample_moves(first, last, starts, delta, t0, durations, steps, offsets, q, t) -> None:
    """Samples of moves ``first:last`` into their rows of ``q`` and ``t``."""
    a, b = int(offsets[first]), int(offsets[last])
    counts = steps[first:last] + 1
    move = np.repeat(np.arange(first, last, dtype=np.intp), counts)
    if _BY_PRODUCT:
        fraction = np.arange(a, b, dtype=np.float64)
        fraction -= offsets[move]
        fraction *= (1.0 / steps[first:last])[move - first]
        fraction[offsets[first + 1:last + 1] - 1 - a] = 1.0
    else:
        fraction = np.empty(b - a)
        for n in np.unique(counts - 1).tolist():
            at = offsets[first:last][counts - 1 == n] - a
            fraction[at[:, None] + np.arange(n + 1)] = np.linspace(0.0, 1.0, n + 1)
    for i in range(starts.shape[1]):
        column = delta[:, i][move]
        column *= fraction  # start + f * delta, as the reference forms it (+ and * commute)
        column += starts[:, i][move]
        q[a:b, i] = column
    column = durations[move]
    column *= fraction
    column += t0[move]
    t[a:b] = column


__all__ = ["LONG_DWELL_S", "MAX_SUBSTEPS", "SLOW_MOVE_S", "move_duration", "plan",
           "slow_move_notes"]
