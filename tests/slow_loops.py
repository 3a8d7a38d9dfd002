"""Servos as the tests of followed paths want them (mill and lathe import them; not part of
the package): Table 6 "after"'s C loop with its gains scaled to lag as slowly as a test
wants, and a model whose C output jumps, which no sampling follows."""

from __future__ import annotations

import math

import numpy as np

from machinesim.servo import AxisServo, PIDServo, table6_axis


def slow_c(machine, scale: float) -> PIDServo:
    """Table 6 "after"'s C loop with its gains times ``scale`` (lagging tens of degrees at
    1e-4), the other axes exact."""
    c = table6_axis("after", "c")
    slow = AxisServo(kp=c.kp * scale, ki=c.ki * scale, kd=c.kd * scale, mass=c.mass,
                     damping=c.damping, name="c")
    return PIDServo(tuple(slow if a == "C" else None for a in machine.axes))


class Jump:
    """A servo model whose C (column ``c_column`` of the axis values) jumps by a quarter
    turn halfway through each motion, the other axes exact: no sampling follows that."""

    def __init__(self, c_column: int) -> None:
        self.c_column = c_column

    def follow(self, t, q):
        out = np.array(q, dtype=np.float64)
        out[t > (t[0] + t[-1]) / 2.0, self.c_column] += math.pi / 2.0
        return out
