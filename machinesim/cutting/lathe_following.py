"""The lathe's followed path held to the rules its command keeps (`machinesim.cutting.lathe`).

The turning engine joins consecutive points of a run straight (linear in C and the slides)
and reads C back from the poses modulo a turn; the command's points are split into quarter
turns, and a commanded move is straight, so its join is exact. The servo's path is neither:
a slow loop lags and catches up, turning C by more than the command between two samples
and not linearly in time while the slides move on. `follow_held` samples it finely enough,
as `machinesim.motion.following` does the mill's: for `Lab.turn`'s runs (`follow_run`) and
for a CAM tool path run through a servo (`machinesim.cutting.servo_path`).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from machinesim.exceptions import NCProgramError, line_of
from machinesim.motion.chords import MAX_SUBSTEPS
from machinesim.motion.following import FOLLOW_ROUNDS
from machinesim.tolerances import CHORD_TOLERANCE_M

#: Relative excess over a quarter turn (`machinesim.cutting.lathe.MOST_C_STEP_RAD`) a
#: followed step may have: a loop settled on a quarter-turn step leads it by ~1e-10 of it
#: (Table 6 "after": 90.00000002 deg), no step to split.
FOLLOWED_SLACK = 1e-6


def _no_block(line: int) -> None:
    """No block has an N word: a run's lines named alone (``line 12``)."""
    return None


def follow_run(servo, t, points, lines, machine, source: str, *,
               block_at: Callable[[int], int | None] = _no_block):
    """``(t, points, reached)``: the run followed by ``servo`` (None: exact), its followed
    steps held to the rules the command's keep (`follow_held`); a run that still breaks
    them (a servo whose output jumps) is an `NCProgramError` naming the line (and its
    block's N word, ``block_at(line)``: `machinesim.nc.Program.block_at`) and the servo
    model. A run that keeps them is followed as before, bit for bit."""
    if servo is None:
        return t, points, points

    def refuse(step: int, why: str) -> NCProgramError:
        line = int(lines[step])
        return NCProgramError(why, source=source, line=line, block=block_at(line))

    return follow_held(servo, t, points, machine.axes, machine.rotary, refuse)


def follow_held(servo, t, points, axes, rotary, refuse):
    """``(t, points, reached)``: ``points`` (a run at times ``t``, one column per name in
    ``axes``, among them X and C; ``rotary`` marks the rotary columns) followed by ``servo``,
    its followed steps held to the rules the command's keep: C turns at most a quarter turn a
    step (`machinesim.cutting.lathe.MOST_C_STEP_RAD`), and the engine's straight join of two
    samples (linear in C and the slides) stays within `CHORD_TOLERANCE_M` of the servo's own
    motion (a commanded move is straight, its join exact). A slow loop lags and catches up,
    turning C by more than the command between samples (Table 6 "after" C gains x 1e-4: 166.6
    deg where the command turns 90) and not linearly in time, while the slides move on: joined
    straight, the edge was 1.46 um off its own path mid-step (at the same C). Where a step
    breaks a rule, its step of the command is split into the pieces it needs (a chord's error
    falls with the square of the step) and the run is followed again (the loops are simulated at
    their own period and read back at the samples, so the new samples lie on the servo's own
    motion), up to `FOLLOW_ROUNDS` rounds; a run that still breaks them (a servo whose output
    jumps) is refused: ``refuse(step, why)`` gives the error to raise, ``step`` the given run's
    step, ``why`` the words. A run that keeps them is followed once, its samples unchanged: the
    check follows a second sampling, with the mid-points, and only reads it."""
    from machinesim.cutting.lathe import followed
    from machinesim.cutting.lathe_program import MOST_C_STEP_RAD, _c_steps, _within_quarter_turns

    reached = followed(servo.follow, t, points)
    c_column = axes.index("C")
    rows = np.arange(len(t) - 1)
    for round_ in range(FOLLOW_ROUNDS + 1):
        turns = np.abs(np.diff(reached[:, c_column]))
        steps = np.where(turns > MOST_C_STEP_RAD * (1.0 + FOLLOWED_SLACK), _c_steps(
            reached[:, c_column]), 1)
        chord = chord_errors(servo, t, points, reached, axes, rotary)
        steps = np.maximum(steps, np.ceil(np.sqrt(np.minimum(
            chord / CHORD_TOLERANCE_M, 4.0 * float(MAX_SUBSTEPS) ** 2)))).astype(np.int64)
        bad = int(np.argmax(steps))
        if steps[bad] <= 1:
            return t, points, reached
        if round_ == FOLLOW_ROUNDS or steps[bad] > MAX_SUBSTEPS:
            break
        t, points, pieces = _within_quarter_turns(t, points, steps)
        rows = rows[pieces]
        reached = followed(servo.follow, t, points)
    why = (f"and would take more than {MAX_SUBSTEPS} pieces" if steps[bad] > MAX_SUBSTEPS else
           f"still after {FOLLOW_ROUNDS} rounds of sampling the move finer")
    turned = math.degrees(abs(float(reached[bad + 1, c_column] - reached[bad, c_column])))
    raise refuse(int(rows[bad]), (
        f"the axes as the servo model {type(servo).__name__} follows this move (C turns "
        f"{turned:.6g} deg between two samples, at {t[bad]:.6g} s into the turning run) "
        f"break the rules of a commanded step (at most {math.degrees(MOST_C_STEP_RAD):g} deg "
        f"of C, the straight join within {CHORD_TOLERANCE_M * 1e9:g} nm of the path) {why}: "
        "its output jumps; check the servo loops' gains"))


def chord_errors(servo, t, points, reached, axes, rotary) -> np.ndarray:
    """Per step of ``reached``: how far (m) the servo's motion at the step's mid-time lies
    from the straight join of its ends at the same C (the slides' offsets, and the C
    overshoot times the radius where C leaves the step's span); ``axes`` and ``rotary`` as
    `follow_held` takes them."""
    from machinesim.cutting.lathe import followed

    mid_t = np.empty(2 * len(t) - 1)
    mid_t[0::2], mid_t[1::2] = t, 0.5 * (t[1:] + t[:-1])
    mid_q = np.empty((len(mid_t), points.shape[1]))
    mid_q[0::2], mid_q[1::2] = points, 0.5 * (points[1:] + points[:-1])
    mid = followed(servo.follow, mid_t, mid_q)[1::2]
    c_column = axes.index("C")
    start, delta = reached[:-1], np.diff(reached, axis=0)
    dc = delta[:, c_column]
    turning = dc != 0.0
    s = np.full(len(dc), 0.5)
    s[turning] = np.clip((mid[turning, c_column] - start[turning, c_column]) / dc[turning],
                         0.0, 1.0)
    off = mid - (start + s[:, None] * delta)
    off[:, c_column] *= np.abs(mid[:, axes.index("X")])  # the radius
    keep = ~np.asarray(rotary, dtype=bool)
    keep[c_column] = True
    return np.sqrt(np.sum(off[:, keep] ** 2, axis=1))


def followed_beyond(machine, command_t, lines, t, reached, commanded_beyond=(), *,
                    block_at: Callable[[int], int | None] = _no_block
                    ) -> dict[str, tuple[float, str]]:
    """Where the servo's followed run ``reached`` (samples at times ``t``; the command's steps
    at times ``command_t``, their program ``lines``) takes an axis beyond its travel: per
    axis letter, by how much (m or rad) and its description (the value, the line, by how
    much, the travel), at the run's worst sample. Axes in ``commanded_beyond`` are skipped
    (`followed_overtravel`)."""
    from machinesim.cutting.program import _format
    from machinesim.tolerances import LIMIT_SLACK

    found = {}
    for i, letter in enumerate(machine.axes):
        if letter in commanded_beyond:
            continue
        low, high = float(machine.lower[i]), float(machine.upper[i])
        beyond = np.maximum(low - reached[:, i], reached[:, i] - high)
        worst = int(np.argmax(beyond))
        if not beyond[worst] > LIMIT_SLACK:
            continue
        step = int(np.clip(np.searchsorted(command_t, t[worst], side="right") - 1, 0,
                           len(lines) - 1))
        value = float(reached[worst, i])
        unit = _format(bool(machine.rotary[i]), value, (low, high))
        line = int(lines[step])
        found[letter] = (float(beyond[worst]), (
            f"axis {letter} = {unit(value)} at {line_of(line, block_at(line))} as "
            f"the servo follows it, {unit(float(beyond[worst]))} beyond its travel "
            f"{unit(low)} .. {unit(high)}, which the command keeps (the loop overshoots)"))
    return found


def worst_beyond(machine, *founds: dict[str, tuple[float, str]]) -> tuple[str, ...]:
    """The descriptions of `followed_beyond`'s ``founds`` (one per run), one per axis in the
    machine's axis order: the run that takes it farthest (the first of equals)."""
    worst: dict[str, tuple[float, str]] = {}
    for found in founds:
        for letter, (by, text) in found.items():
            if letter not in worst or by > worst[letter][0]:
                worst[letter] = (by, text)
    return tuple(worst[letter][1] for letter in machine.axes if letter in worst)


def followed_overtravel(machine, command_t, lines, t, reached, source, allow: bool,
                        commanded_beyond=(), *,
                        block_at: Callable[[int], int | None] = _no_block) -> tuple[str, ...]:
    """Where the servo's followed run ``reached`` (samples at times ``t``; the command's steps
    at times ``command_t``, their program ``lines``) takes an axis beyond its travel, one
    description an axis: the value, the line, by how much, the travel (`followed_beyond`;
    a turn of several runs lists each axis once, at its worst run: `worst_beyond`). A loop
    that overshoots carries an axis past a travel the command keeps (the command's own
    values are checked before anything is turned, `machinesim.cutting.program._overtravel`;
    axes in ``commanded_beyond`` are listed there and skipped here); a line is named with
    its block's N word (``block_at``, as `follow_run`). Raises `AxisLimitError` unless
    ``allow``."""
    found = worst_beyond(machine, followed_beyond(machine, command_t, lines, t, reached,
                                                  commanded_beyond, block_at=block_at))
    refuse_followed(found, source, allow)
    return found


def refuse_followed(found: tuple[str, ...], source, allow: bool) -> None:
    """Raise `AxisLimitError` on `followed_overtravel`'s descriptions ``found`` unless
    ``allow`` (or none were found)."""
    from machinesim.exceptions import AxisLimitError

    if found and not allow:
        where = f"{source}: " if source else ""
        raise AxisLimitError(f"{where}{'; '.join(found)}; nothing was turned "
                             "(allow_overtravel=True turns it anyway and lists it)")


__all__ = ["FOLLOWED_SLACK", "chord_errors", "follow_held", "follow_run", "followed_beyond",
           "followed_overtravel", "refuse_followed", "worst_beyond"]
