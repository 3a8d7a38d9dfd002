"""The servo's path: a program's samples as the axes follow them, sampled as finely as the
planner samples a commanded move.

`follow_runs` applies a `ServoModel` to each motion (a run of feed moves, a rapid, a dwell).
The followed samples are where the axes are at the command's sample times; the cutting
engine sweeps the tool from each to the next as from one pose to another, as it sweeps a
commanded sub-step. A commanded move is split until each sub-step's chord stays within the
chord tolerance and turns the tool by at most half of `MAX_STEP_TURN_RAD` (`plan`); the
lagging axes do not keep to those sub-steps: slow loops fall behind and catch up, so one
followed step turned C by 78.7 deg where the command's turned 45 (and past 90 deg the
engine refused the cut, naming poses). `follow_plan` holds the followed steps to the same
rules (`StepRule`):

* a step within a motion is the servo's own path: the motion is followed again on a finer
  sampling of the same command (each step that breaks the rules split into the pieces it
  needs, the others kept: the loops are simulated at their own period and read back at the
  samples, so the new ones lie on the followed path), until every step keeps the rules;
* the last step of a motion, from the axes' lag when the command ends to the command's end
  where they settle (`plan` puts each motion's end in position), goes straight in axis
  space, as documented for `plan`: it is split as a commanded move is, its sub-steps
  spread over that step's time.

A motion whose followed path does not come within the rules (a servo model whose output
jumps, or more than `MAX_SUBSTEPS` sub-steps of one move) is refused, naming the program's
line and the servo model.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from machinesim.exceptions import InputError, NCProgramError
from machinesim.motion.chords import (
    MAX_SUBSTEPS,
    hold_corners,
    hold_raised,
    substeps,
)
from machinesim.motion.faces import face_substeps, profile_substeps
from machinesim.motion.tool_paths import ToolPaths
from machinesim.nc.program import KIND_LINEAR
from machinesim.tolerances import MAX_STEP_TURN_RAD

#: Rounds of following a motion again on a finer sampling: each splits every followed step
#: that breaks the rules into the pieces it needs, so a smooth followed path holds after one
#: or two (a step the path makes at one instant, which no sampling follows, is refused after
#: these).
FOLLOW_ROUNDS = 8


class StepRule:
    """The rules a commanded move's sub-steps keep, for straight steps in axis space: the
    chord tolerance for every tool point (`machinesim.motion.chords.substeps`), at most half
    of `MAX_STEP_TURN_RAD` of the rotary axes' turns added up, and a flat face's tilt
    (`machinesim.motion.faces.face_substeps`) and, for a step that turns a rotary axis, a
    planar profile's edges (`profile_substeps`). Steps that change no bending axis (rotary, or
    one whose errors vary along it) move the tool straight and need one sub-step."""

    def __init__(self, machine, errors, points: np.ndarray, bending: np.ndarray,
                 tolerance: float, face_radius: float, profile=None) -> None:
        self.machine, self.errors = machine, errors
        self.points = points
        self.bending = np.asarray(bending, dtype=bool)
        self.rotary = np.asarray(machine.rotary, dtype=bool)
        self.tolerance, self.face_radius = tolerance, face_radius
        self.profile = profile
        self._paths = None

    def counts(self, starts: np.ndarray, delta: np.ndarray) -> np.ndarray:
        """Sub-steps each straight step (``starts``, ``delta``: (n, n_axes)) needs; 0 where
        more than `MAX_SUBSTEPS` would do (or its path steps)."""
        need = np.ones(len(starts), dtype=np.int64)
        bends = np.flatnonzero(np.any(delta[:, self.bending] != 0.0, axis=1))
        if not bends.size:
            return need
        if self._paths is None:
            self._paths = ToolPaths(self.machine, self.errors, self.points)
        found, failed, stalls = substeps(self._paths, starts[bends], delta[bends],
                                         self.tolerance)
        turn = np.abs(delta[bends][:, self.rotary]).sum(axis=1)
        least = np.ceil(turn / (MAX_STEP_TURN_RAD / 2.0))
        hold_raised(self._paths, starts[bends], delta[bends], self.tolerance, found, failed,
                    stalls, least)
        held = np.maximum(found, np.minimum(least, MAX_SUBSTEPS + 1).astype(np.int64))
        found = face_substeps(self.machine, self.errors, starts[bends], delta[bends],
                              np.maximum(held, 1), self.face_radius, self.tolerance)
        found = profile_substeps(self.machine, self.errors, starts[bends], delta[bends],
                                 found, self.rotary, self.profile, self.tolerance)
        # counts the faces and profiles raised: their corners checked again, as `plan` does
        raised = np.flatnonzero((found > held) & (found <= MAX_SUBSTEPS) & ~failed)
        if raised.size:
            found = np.array(found, dtype=np.int64)
            hold_corners(self._paths, starts[bends], delta[bends], self.tolerance, found,
                         failed, stalls, raised)
        found[failed | (found > MAX_SUBSTEPS)] = 0
        need[bends] = found
        return need


def follow_runs(servo, q: np.ndarray, t: np.ndarray, offsets: np.ndarray,
                kinds: np.ndarray, exact_stops=()) -> np.ndarray:
    """Apply ``servo.follow`` to the program's motions, in place; the last row of each motion.

    A run of consecutive feed moves is one continuous motion: the control passes from block
    to block without stopping (FANUC's cutting mode, G64), so the loops carry their lag
    across the blocks, as around the chords of an arc (a circle's radius is then off by
    ``r (|G(jw)| - 1)``, the loops' closed-loop response at its frequency). A run ends after
    a move that ends in an exact stop (``exact_stops``, move indices: G09, G61), where the
    control waits for the axes to be in position. The run is followed in one call, entered
    from rest on its first point; each sample shared by two of its moves (one's end, the
    next one's start) is given once and reached once. A rapid and a dwell are each followed
    alone, from rest (a rapid ends in position, and the axes settle in a dwell).

    Returns the row of ``q`` that ends each motion, where the followed value is the lag the
    axes still have when the command arrives: `plan` puts the axes in position there.
    """
    bounds = offsets.tolist()
    count = len(kinds)
    feed = np.asarray(kinds) == KIND_LINEAR
    stops = np.zeros(count, dtype=bool)
    stops[np.asarray(exact_stops, dtype=np.int64)] = True
    ends = []
    first = 0
    while first < count:
        last = first + 1
        if feed[first]:
            while last < count and feed[last] and not stops[last - 1]:
                last += 1
        a, b = bounds[first], bounds[last]
        # the rows of the motion, each shared boundary once (a move's start row is the
        # previous move's end row)
        shared = np.asarray(bounds[first + 1:last], dtype=np.int64)
        rows = np.setdiff1d(np.arange(a, b), shared, assume_unique=True)
        followed = np.asarray(servo.follow(t[rows].copy(), q[rows].copy()), dtype=np.float64)
        if followed.shape != (len(rows), q.shape[1]):
            raise InputError(f"servo.follow must return axis values of shape "
                             f"({len(rows)}, {q.shape[1]}), got {followed.shape}")
        if not np.all(np.isfinite(followed)):
            bad = int(np.argmax(~np.all(np.isfinite(followed), axis=1)))
            raise InputError(f"servo.follow returned axis values that are not finite (NaN or "
                             f"inf) at t = {t[rows][bad]:.6g} s of the program (the servo "
                             f"model {type(servo).__name__}): nothing is cut with them",
                             key="servo")
        q[rows] = followed
        q[shared] = q[shared - 1]
        if b > a:
            ends.append(b - 1)
        first = last
    return np.asarray(ends, dtype=np.int64)


def follow_plan(servo, sample, steps: np.ndarray, kinds: np.ndarray, exact_stops,
                rule: StepRule, lines: np.ndarray, source: str,
                block_of: Callable[[int], int | None]):
    """The followed samples of a program: ``(q, t, offsets, peak_lag)``.

    ``sample(steps)`` gives the commanded samples ``(q, t, offsets)`` of the moves split
    into ``steps``; the motions are followed (`follow_runs`), sampled again more finely
    where a followed step breaks ``rule``, and each motion's last step, to the command's
    end, split by ``rule`` (module docstring). ``peak_lag`` is each axis' largest
    |command - reached|, the lag at each motion's end included. Where nothing breaks the
    rule the samples are those of the command's sub-steps, followed.
    A refusal names the move's line (``lines``) and its block's N word (``block_of(move)``,
    None when it has none), ``line 12 (N120)``.
    """
    commanded, t, offsets = sample(np.asarray(steps, dtype=np.int64))
    for _ in range(FOLLOW_ROUNDS):
        q = commanded.copy()
        settled = follow_runs(servo, q, t, offsets, kinds, exact_stops)
        move_of = np.repeat(np.arange(len(kinds)), np.diff(offsets))
        # the steps within a move, but for a motion's last (its settling, split below)
        inner = np.ones(len(q), dtype=bool)
        inner[offsets[1:] - 1] = False
        inner[settled - 1] = False
        rows = np.flatnonzero(inner)
        need = rule.counts(q[rows], q[rows + 1] - q[rows])
        if np.all(need == 1):
            break
        # only the steps that break the rule are split: the command between two samples is
        # straight in axis space and in time, so its new samples are the command's own
        need = np.where(need == 0, MAX_SUBSTEPS + 1, need)
        total = np.diff(offsets) - 1
        np.add.at(total, move_of[rows], need - 1)
        if np.any(total > MAX_SUBSTEPS):
            bad = int(np.argmax(total > MAX_SUBSTEPS))
            raise NCProgramError(_refusal(servo, rule, f"would need more than {MAX_SUBSTEPS} "
                                          "sub-steps"), source=source, line=int(lines[bad]),
                                 block=block_of(bad))
        commanded, t, offsets = _split_steps(commanded, t, offsets, rows + 1, need, move_of)
    else:
        bad = int(move_of[rows[np.argmax(need != 1)]])
        raise NCProgramError(_refusal(servo, rule, f"still breaks them after {FOLLOW_ROUNDS} "
                                      "rounds of finer sampling (its path jumps)"),
                             source=source, line=int(lines[bad]), block=block_of(bad))
    lag = np.abs(commanded - q)
    peak_lag = lag.max(axis=0) if len(lag) else np.zeros(q.shape[1])
    # each motion ends in position (a rapid or a dwell follows, or an exact stop): the axes
    # settle onto the command's end, the tool moving on from the lagged point
    q[settled] = commanded[settled]
    if len(settled):
        last = settled - 1
        need = rule.counts(q[last], q[settled] - q[last])
        if np.any(need == 0):
            bad = int(move_of[settled[np.argmax(need == 0)]])
            raise NCProgramError(_refusal(servo, rule, f"settles from its lag at the end by a "
                                          f"step that would need more than {MAX_SUBSTEPS} "
                                          "sub-steps"), source=source, line=int(lines[bad]),
                                 block=block_of(bad))
        if np.any(need > 1):
            q, t, offsets = _split_steps(q, t, offsets, settled, need, move_of)
    peak_lag.flags.writeable = False
    return q, t, offsets, peak_lag


def _refusal(servo, rule: StepRule, what: str) -> str:
    return (f"the axes' path as the servo model {type(servo).__name__} follows this move "
            f"does not keep the rules of a commanded move's sub-steps (chords within "
            f"{rule.tolerance * 1e9:g} nm, at most "
            f"{math.degrees(MAX_STEP_TURN_RAD / 2.0):g} deg a sub-step): it {what}; check "
            "the servo loops' gains, or raise chord_tolerance (--chord-nm on the command "
            "line)")


def _split_steps(q, t, offsets, ends, need, move_of):
    """``q``, ``t``, ``offsets`` with the step into each row of ``ends`` (a row after the
    first of its move) split into ``need`` equal steps (straight in axis space and in
    time)."""
    extra = need - 1
    where = ends[extra > 0]
    counts = extra[extra > 0]
    total = int(counts.sum())
    piece = np.repeat(np.arange(len(where)), counts)
    k = np.arange(total) - np.repeat(np.cumsum(counts) - counts, counts) + 1.0
    f = k / np.repeat(counts + 1, counts)
    a, b = where[piece] - 1, where[piece]
    new_q = q[a] + f[:, None] * (q[b] - q[a])
    new_t = t[a] + f * (t[b] - t[a])
    at = np.repeat(where, counts)  # inserted before the step's end row
    q = np.insert(q, at, new_q, axis=0)
    t = np.insert(t, at, new_t)
    added = np.zeros(len(offsets) - 1, dtype=np.int64)
    np.add.at(added, move_of[where], counts)
    offsets = offsets.copy()
    offsets[1:] += np.cumsum(added)
    return q, t, offsets


__all__ = ["FOLLOW_ROUNDS", "StepRule", "follow_plan", "follow_runs"]
