"""The edge path the axes really follow: a spiral tool path run through a servo model.

The STS program turns C at a constant spindle speed while X and Z follow the cutting points;
the axes' servo loops (`machinesim.servo`, or any `ServoModel`) lag behind. Here the whole
path is one continuous motion, as on the machine, in `Lab.turn` and in the motion planner
(which follows each run of consecutive feed moves as one motion).
"""

from __future__ import annotations

import math

import numpy as np

from machinesim.cam.spiral import SPINDLE_RPM, ToolPath, _check_increasing, _positive
from machinesim.cutting.turning import EdgePath
from machinesim.exceptions import InputError


def path_times(path: ToolPath, spindle_rpm: float = SPINDLE_RPM) -> np.ndarray:
    """Time of each point of ``path`` (s) at a constant spindle speed, from 0; its C
    increases strictly (as `machinesim.cam.spiral.interpolate` takes it)."""
    # a str or None was a TypeError from '>', True taken as 1 rpm
    spindle_rpm = _positive(spindle_rpm, "spindle_rpm")
    _check_increasing(path.c, "path.c")  # times running backwards: a servo lags nothing
    return (path.c - path.c[0]) / (2.0 * math.pi * spindle_rpm / 60.0)


def followed_path(path: ToolPath, servo, spindle_rpm: float = SPINDLE_RPM) -> ToolPath:
    """The (C, X, Z) the axes reach when ``servo`` (``follow(t, q)``, q columns X, Z, C)
    follows ``path`` at ``spindle_rpm``, entering it settled at its first step's speed (as
    `machinesim.cutting.lathe.followed`, which `Lab.turn` uses), sampled by the rule
    `Lab.turn` samples its runs by (`machinesim.cutting.lathe_following.follow_held`):
    where the straight join of two followed points strays more than 1 nm
    (`machinesim.tolerances.CHORD_TOLERANCE_M`) from the servo's own motion at mid-step, or
    C turns more than a quarter turn, that step of the path is sampled finer (the added
    points on the path's straight step) and the path followed again. The turning engine
    joins the points straight; on the Case 4 path (Constant Angle 2 deg, 45,001 points)
    Table 6 "before" had been joined up to 519 nm off that motion. A servo whose output
    jumps is refused (`InputError`, key ``servo``, naming the path's step)."""
    from machinesim.cutting.lathe_following import follow_held

    def refuse(step: int, why: str) -> InputError:
        return InputError(f"path step {step} (points {step} to {step + 1}): {why}", key="servo")

    t = path_times(path, spindle_rpm)
    q = np.column_stack([path.x, path.z, path.c])
    _, _, reached = follow_held(servo, t, q, ("X", "Z", "C"), (False, False, True), refuse)
    return ToolPath(reached[:, 2], reached[:, 0], reached[:, 1])


def followed_edge_path(path: ToolPath, servo, spindle_rpm: float = SPINDLE_RPM, *,
                       dx: float = 0.0, dy: float = 0.0) -> EdgePath:
    """`EdgePath` of the followed path, the tool set off by ``dx`` (radial) and ``dy``
    (centre height), m."""
    reached = followed_path(path, servo, spindle_rpm)
    return EdgePath(reached.c, reached.x + dx, dy, reached.z)


__all__ = ["followed_edge_path", "followed_path", "path_times"]
