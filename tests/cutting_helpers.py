"""What the cutting test files (tests/test_cutting.py, test_cutting_holder.py) share (not
collected: no test_ prefix): a slot cut in steps deeper than a short tool's body."""

from __future__ import annotations

from machinesim.nc import ProgramBuilder

MM = 1e-3


def _slot_in_steps(steps, last_y=0.0):
    """A slot along X cut 1 mm deeper each pass, the last pass at ``last_y`` (m)."""
    b = ProgramBuilder(1)
    for k in range(1, steps + 1):
        y = last_y if k == steps else 0.0
        b.rapid(X=-3 * MM, Y=y, Z=1 * MM).linear(Z=-k * MM, feed_mm_per_min=300.0)
        b.linear(X=3 * MM).rapid(Z=1 * MM)
    return b.build()
