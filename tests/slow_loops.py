"""A servo whose C loop lags as slowly as a test wants: Table 6 "after"'s C loop with its
gains scaled. Not part of the package: the tests of followed paths (mill and lathe) import it."""

from __future__ import annotations

from machinesim.servo import AxisServo, PIDServo, table6_axis


def slow_c(machine, scale: float) -> PIDServo:
    """Table 6 "after"'s C loop with its gains times ``scale`` (lagging tens of degrees at
    1e-4), the other axes exact."""
    c = table6_axis("after", "c")
    slow = AxisServo(kp=c.kp * scale, ki=c.ki * scale, kd=c.kd * scale, mass=c.mass,
                     damping=c.damping, name="c")
    return PIDServo(tuple(slow if a == "C" else None for a in machine.axes))
