"""A rotary axis's component errors as the axis moves through them: they repeat each turn.

A table that spans a whole turn or more (a spindle's, a table's over 360 deg) is read at a
position beyond it a whole number of turns back into it; a shorter one holds its end values,
as on a linear axis; a polynomial in the angle does not repeat, so on an axis that turns more
than a turn each way it is refused. `machinesim.kinematics` binds every component error of a
rotary axis through `each_turn`, and `machinesim.Machine.error_jacobian` differentiates it so.
"""

from __future__ import annotations

import math

import numpy as np

from machinesim.exceptions import ErrorModelError
from machinesim.units import angle_text

__all__ = ["TURN", "each_turn", "table_each_turn"]

#: One turn, rad.
TURN = 2.0 * math.pi


def each_turn(component, axis, name: str, source=None):
    """``component`` as a rotary ``axis`` moves through it: its errors repeat each turn.

    A table that spans a whole turn or more (a spindle's, a table's over 360 deg) is read
    at a position beyond it shifted by whole turns into it: the same place of the axis, the
    same error (its values a turn apart should agree: where they differ the tool path steps
    as the axis wraps, and no chord follows a step). A shorter table holds its end values,
    as on a linear axis. A polynomial in the angle does not repeat, so on an axis
    that turns more than a turn each way it is refused. Linear axes: ``component`` itself.
    """
    if not axis.rotary:
        return component
    if component.kind == "poly":
        if axis.lower < -TURN or axis.upper > TURN:
            raise ErrorModelError(
                f"a polynomial in the angle does not repeat each turn, and {axis.letter} "
                f"turns {angle_text(axis.lower)} .. {angle_text(axis.upper)}; give a table "
                "over one turn "
                "(position_deg from 0 to 360, the same value at both ends)",
                source=source, key=name)
        return component
    return table_each_turn(component)


def table_each_turn(component):
    """A rotary axis's table as the axis moves through it (`each_turn`): one of a whole
    turn or more read beyond it a whole number of turns back into it; a shorter table, or
    a polynomial, ``component`` itself."""
    if component.kind != "table":
        return component
    span = component.positions[-1] - component.positions[0]
    return _EachTurn(component) if span >= TURN * (1.0 - 1e-12) else component


class _EachTurn:
    """A rotary axis's table of a turn or more, read at positions beyond it shifted by
    whole turns into it (`each_turn`)."""

    #: The errors repeat with this period (rad): the table's breakpoints recur each turn.
    period = TURN

    def __init__(self, component) -> None:
        self.component = component
        self.kind, self.positions, self.values = "table", component.positions, component.values

    def into(self, x) -> np.ndarray:
        """Positions ``x`` (rad) beyond the table shifted by whole turns into it."""
        x = np.asarray(x, dtype=np.float64)
        first, last = self.positions[0], self.positions[-1]
        return np.where((x < first) | (x > last), first + np.mod(x - first, TURN), x)

    def evaluate(self, x) -> np.ndarray:
        return self.component.evaluate(self.into(x))

    def basis(self, x) -> np.ndarray:
        return self.component.basis(self.into(x))

    def largest(self, lower: float, upper: float):
        return self.component.largest(lower, upper)
