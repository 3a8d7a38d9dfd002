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

__all__ = ["TURN", "each_turn"]

#: One turn, rad.
TURN = 2.0 * math.pi


def each_turn(component, axis, name: str, source=None):
    """``component`` as a rotary ``axis`` moves through it: its errors repeat each turn.

    A table that spans a whole turn or more (a spindle's, a table's over 360 deg) is read
    at a position beyond it shifted by whole turns into it: the same place of the axis, the
    same error; its values a turn apart must agree (within `CLOSING_TOLERANCE`), or it is
    refused (the path would jump where the axis wraps). A shorter table holds its end
    values, as on a linear axis. A polynomial in the angle does not repeat, so on an axis
    that turns more than a turn each way it is refused. Linear axes: ``component`` itself.
    """
    if not axis.rotary:
        return component
    if component.kind == "poly":
        if axis.lower < -TURN or axis.upper > TURN:
            raise ErrorModelError(
                f"a polynomial in the angle does not repeat each turn, and {axis.letter} "
                f"turns {axis.lower:g} .. {axis.upper:g} rad; give a table over one turn "
                "(position_deg from 0 to 360, the same value at both ends)",
                source=source, key=name)
        return component
    span = component.positions[-1] - component.positions[0]
    if span < TURN * (1.0 - 1e-12):
        return component
    _check_closes(component, name, source)
    return _EachTurn(component)


#: Values of a repeating table a turn apart that differ by more than this (m or rad) are
#: refused (`each_turn`): a picometre at a metre's lever, far below any chord tolerance, and
#: far above the round-off of one value converted from its unit twice.
CLOSING_TOLERANCE = 1e-12


def _check_closes(component, name: str, source) -> None:
    """Refuse a table of a turn or more whose values a turn apart differ: read each turn, it
    would jump there (a tool path with a step, which no chord follows: the planner's sub-steps
    grew towards a million on the README's example table, 1 arcsec at -180 deg, -1 at 180)."""
    first, last = component.positions[0], component.positions[-1]
    pairs = ((first, component.values[0], first + TURN), (last, component.values[-1],
                                                           last - TURN))
    for at, value, other in pairs:
        there = float(component.evaluate(np.array([other]))[0])
        if abs(there - value) > CLOSING_TOLERANCE:
            angle = name.rpartition(".")[2][1:2] in "ABC"
            unit, factor = ("arcsec", math.pi / 648000) if angle else ("um", 1e-6)
            raise ErrorModelError(
                f"a table of a whole turn repeats each turn, but its values a turn apart "
                f"differ: {value / factor:.6g} {unit} at {math.degrees(at):g} deg, "
                f"{there / factor:.6g} {unit} at {math.degrees(other):g} deg (the same place "
                "of the axis); the tool path would jump there, and no chord follows a jump. "
                "Give the same value a turn apart (e.g. at -180 and 180 deg)",
                source=source, key=name)


class _EachTurn:
    """A rotary axis's table of a turn or more, read at positions beyond it shifted by
    whole turns into it (`each_turn`)."""

    def __init__(self, component) -> None:
        self.component = component
        self.kind, self.positions, self.values = "table", component.positions, component.values

    def _into(self, x) -> np.ndarray:
        x = np.asarray(x, dtype=np.float64)
        first, last = self.positions[0], self.positions[-1]
        return np.where((x < first) | (x > last), first + np.mod(x - first, TURN), x)

    def evaluate(self, x) -> np.ndarray:
        return self.component.evaluate(self._into(x))

    def basis(self, x) -> np.ndarray:
        return self.component.basis(self._into(x))

    def largest(self, lower: float, upper: float):
        return self.component.largest(lower, upper)
