"""The lathe's followed path held to the quarter turn its command keeps
(`machinesim.cutting.lathe`).

The turning engine joins consecutive points of a run straight (linear in C and the slides)
and reads C back from the tool's poses modulo a turn, so the command's points are split
into quarter turns (`machinesim.cutting.lathe.MOST_C_STEP_RAD`). The servo's samples were
not: a slow loop lags and catches up, turning C by more than the command between two
samples (Table 6 "after" C gains x 1e-4 on ten turns in one block: 166.6 deg where the
command turns 90; past half a turn the angle would be read the wrong way round).
`follow_run` samples it finely enough, as `machinesim.motion.following` does the mill's.
"""

from __future__ import annotations

import math

import numpy as np

from machinesim.exceptions import NCProgramError
from machinesim.motion.chords import MAX_SUBSTEPS
from machinesim.motion.following import FOLLOW_ROUNDS

#: Relative excess over a quarter turn (`machinesim.cutting.lathe.MOST_C_STEP_RAD`) a
#: followed step may have: a loop settled on a quarter-turn step leads it by ~1e-10 of it
#: (Table 6 "after": 90.00000002 deg), no step to split.
FOLLOWED_SLACK = 1e-6


def follow_run(servo, t, points, lines, machine, source: str):
    """``(t, points, reached)``: the run (``t``, ``points``; ``lines``: each step's program
    line) followed by ``servo`` (None: exact), no followed step turning C by more than a
    quarter turn (`FOLLOWED_SLACK` aside), as no commanded step does.

    Where a followed step turns more, its step of the command is split into the pieces the
    followed turn needs and the run is followed again: the loops are simulated at their
    own period and read back at the samples, so the new samples lie on the servo's own
    motion. Up to `FOLLOW_ROUNDS` rounds; a run that still breaks it (a servo whose output
    jumps) is refused naming the line and the servo model. A run that keeps it is followed
    once, as before."""
    from machinesim.cutting.lathe import MOST_C_STEP_RAD, _c_steps, _within_quarter_turns, followed

    reached = followed(None if servo is None else servo.follow, t, points)
    if servo is None:
        return t, points, reached
    c_column = machine.axes.index("C")
    for round_ in range(FOLLOW_ROUNDS + 1):
        turns = np.abs(np.diff(reached[:, c_column]))
        steps = np.where(turns > MOST_C_STEP_RAD * (1.0 + FOLLOWED_SLACK),
                         _c_steps(reached[:, c_column]), 1)
        bad = int(np.argmax(steps))
        if steps[bad] <= 1:
            return t, points, reached
        if round_ == FOLLOW_ROUNDS or steps[bad] > MAX_SUBSTEPS:
            break
        t, points, rows = _within_quarter_turns(t, points, steps)
        lines = lines[rows]
        reached = followed(servo.follow, t, points)
    why = (f"and would take more than {MAX_SUBSTEPS} pieces" if steps[bad] > MAX_SUBSTEPS else
           f"still after {FOLLOW_ROUNDS} rounds of sampling the move finer")
    raise NCProgramError(
        f"the spindle C as the servo model {type(servo).__name__} follows this move turns "
        f"{math.degrees(float(turns[bad])):.6g} deg between two samples (at {t[bad]:.6g} s "
        f"into the turning run), more than the {math.degrees(MOST_C_STEP_RAD):g} deg a step "
        f"the turning engine takes, {why}: its output jumps; check the servo loops' gains",
        source=source, line=int(lines[bad]))


__all__ = ["FOLLOWED_SLACK", "follow_run"]
