"""The notes on an errors file that a cut's report carries (`CutReport.notes`).

`machinesim.cutting.cut` and ``cut_turned`` add them to their report, where a Python user
reads a cut's notes; ``machinesim cut`` prints and writes that report's, and ``machinesim
view`` prints the same list. A `Lab`'s cut carries none: its errors are the truth a
procedure must not read (docs/lab.md).
"""

from __future__ import annotations

import numpy as np

from machinesim.errors.idle import idle_location_notes
from machinesim.errors.model import ErrorModel
from machinesim.errors.unit_slips import unit_slip_notes

__all__ = ["error_file_notes"]


def error_file_notes(model: ErrorModel, machine, program=None, start=None, *,
                     done: str | None = "cut") -> list[str]:
    """A file that sets no error (``done``: what was done on the machine as built; None
    leaves the note to the caller), `unit_slip_notes` of ``model`` on ``machine`` (values
    perhaps written in other units than their keys ask), then, given a ``program``,
    `idle_location_notes` (location errors of an axis the program keeps at zero move nothing)
    from ``start``: axis values in ``machine.axes`` order, default zeros, as
    `machinesim.cutting.cut` starts.

    The first had been the command line's alone: ``cut(..., errors="empty.toml")`` cut on
    the nominal machine with no note, a file meant to hold errors taken silently."""
    notes = []
    source = model.source
    if done is not None and source and not source.startswith("<") and not model.written:
        notes.append(f"{source} sets no error (no key in any section): {done} on the machine "
                     "as built, every error zero")
    notes += unit_slip_notes(model, machine)
    if program is not None:
        start = np.zeros(len(machine.axes)) if start is None else np.asarray(start, float)
        notes += idle_location_notes(model, machine, program, start)
    return notes
