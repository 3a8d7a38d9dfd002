"""Location errors a program never shows: notes in a cut's report (`machinesim.errors.notes`,
which `machinesim cut --errors` prints).

A location error moves and tilts an axis's line without moving what the axis carries at
zero (docs/machines.md, "How errors enter": ``E_i J_i(q) E_i^-1`` is the identity where
``J_i`` is): a C table's offsets EX0C, EY0C and tilts EA0C, EB0C show only as C turns, a
linear axis's squareness and parallelism only as it moves. So on a program that keeps the
axis at zero from its start to its end, they leave the part exactly as the machine without
them cuts it, which is right (to second order where the axis also has a component error at
zero: a tilt turns that error's vector, 15 urad of 1 um by 15 fm), and which a user who
injected one error to see it move reads as the error ignored. A rotary axis's zero offset
(EC0C for C) turns what it carries at zero too, and is never noted.
"""

from __future__ import annotations

import numpy as np

from machinesim.errors.model import ErrorModel
from machinesim.errors.unit_slips import _noted_at
from machinesim.nc.moves import AXES as PROGRAM_AXES

__all__ = ["idle_location_notes"]


def idle_location_notes(model: ErrorModel, machine, program, start) -> list[str]:
    """One line per axis whose location errors (its zero offset apart) move nothing in
    `program`: the axis stands at zero at `start` (axis values, `machine.axes` order) and in
    every target of the program. Each line begins with the file and the line of the first
    such error (``F.toml, line 2: location.C EX0C, EB0C move nothing ...``)."""
    notes = []
    for letter, symbols in model.location.items():
        axis = machine.axis(letter)
        column = program.targets[:, PROGRAM_AXES.index(letter)]
        values = np.append(column[~np.isnan(column)], start[machine.axes.index(letter)])
        if np.any(values != 0.0):
            continue
        zero_offset = f"E{'ABC'[axis.direction]}0{letter}" if axis.rotary else None
        idle = [symbol for symbol, value in symbols.items()
                if symbol != zero_offset and value != 0.0]
        if not idle:
            continue
        where = _noted_at(model, f"location.{letter}.{idle[0]}")
        shows = ("the offsets and tilts of its line show only as it turns" if axis.rotary
                 else "its squareness and parallelism show only as it moves")
        them, move = ("them", "move") if len(idle) > 1 else ("it", "moves")
        notes.append(f"{where}location.{letter} {', '.join(idle)} {move} nothing in this "
                     f"program: {letter} stays at 0 from its start to its end, and {shows}; "
                     f"the part is the one the machine without {them} cuts")
    return notes
