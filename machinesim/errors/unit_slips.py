"""What an error file's values suggest about the units they were written in: notes, not
refusals, for the command line and the scenarios (`machinesim cut --errors`,
`machinesim.scenario_runs.errors_file`). A value below anything a machine shows
(`below_any_machine`: SI where the key asks um or urad), one beyond the errors of any
machine (`beyond_any_machine`: um or urad where the key asks mm or deg), and an error table
over a sliver of its axis's travel (`short_tables`: positions in um where mm were meant),
a polynomial beyond the errors of any machine within its axis's travel (`far_polynomials`);
and, no unit slip but as silent, a rotary axis's table of a turn whose values a turn apart
differ where the axis turns past it (`turn_steps`: the error steps there). Each note
begins with the file and the key's line (`ErrorModel.line_of`, from
`machinesim.errors.toml.key_lines`). Moved out of `machinesim.errors.toml`, which reads
and writes the files; every name is still importable from there.
"""

from __future__ import annotations

import numpy as np

from machinesim.errors._checks import _shown
from machinesim.errors.model import ErrorModel
from machinesim.errors.turns import TURN
from machinesim.units import FACTORS, is_length

__all__ = ["LARGEST_LIKELY_ERROR_M", "LARGEST_LIKELY_ERROR_RAD", "SHORTEST_TABLE_SHARE",
           "SMALLEST_WRITTEN_ERROR_SI", "below_any_machine", "beyond_any_machine",
           "far_polynomials", "short_tables", "turn_steps", "unit_slip_notes"]


#: Below this (m or rad) an error value written in a file is no error any machine shows (a
#: hundredth of the machines' 1 nm resolution): written in SI where its key asks um or urad,
#: more likely (`EX0C_um = 4e-6` is 4 pm).
SMALLEST_WRITTEN_ERROR_SI = 1e-11


def _noted_at(model: ErrorModel, field: str) -> str:
    """Where a note of ``field`` (``tool.offset``) begins, as refusals name it: the file and
    the key's line (`key_lines`, kept in ``model.lines``), ``F.toml, line 3: ``; nothing for a
    model not read from a file."""
    where = [model.source] if model.source is not None else []
    line = model.line_of(field)
    if line is not None:
        where.append(f"line {line}")
    return f"{', '.join(where)}: " if where else ""


def below_any_machine(model: ErrorModel) -> list[str]:
    """Lines naming each value the file wrote (``model.written``) that is not zero and yet
    below `SMALLEST_WRITTEN_ERROR_SI` in SI, all its entries: perhaps SI in a key in um or
    urad, or, in a key in m or rad, a value converted to SI twice. A table's positions are
    left out. Each line begins with the file and the key's line
    (``F.toml, line 3: location.C.EX0C_um = 4e-06 is at most ...``)."""
    lines = []
    for field, (key, value) in model.written.items():
        unit = key.rsplit("_", 1)[-1]
        if field.endswith(".position") or unit not in FACTORS:
            continue
        try:
            size = np.abs(np.asarray(value, dtype=np.float64)) * FACTORS[unit]
        except (TypeError, ValueError):  # a polynomial's table, a string: checked elsewhere
            continue
        if size.size and size.max() > 0.0 and size.max() < SMALLEST_WRITTEN_ERROR_SI:
            si = "m" if is_length(unit) else "rad"
            shown = np.asarray(value, dtype=np.float64).tolist()
            largest = float(size.max())  # in the key's unit, SI beside (mm or deg first for SI)
            if unit == si:  # no smaller-unit slip for a key in SI: a value scaled twice?
                small = "um" if si == "m" else "urad"
                reach = _shown(largest, si)
                guess = (f": was it converted to {si} twice? (the key takes 1 {small} as "
                         "1e-06)")
            else:
                reach = f"{_shown(largest, unit)} ({largest:g} {si})"
                guess = f": was it written in {si}, where the key asks {unit}?"
            lines.append(f"{_noted_at(model, field)}{key} = {shown!r} is at most {reach}, "
                         f"below anything a machine shows{guess}")
    return lines


#: At or above these an error value written in a file is no error of any machine's setting
#: or geometry (10 mm, 10 deg: the papers' largest are 0.85 mm and 0.5 deg), and more likely
#: written in a smaller unit than its key asks: `offset_mm = [0.0, -178.0, 0.0]` for the
#: README's 178 um sets the tool 178 mm off, which misses its part. A note, as
#: `below_any_machine`'s: `LARGEST_ERROR` (1 m, 180 deg) still bounds what is read.
LARGEST_LIKELY_ERROR_M = 10e-3
LARGEST_LIKELY_ERROR_RAD = np.radians(10.0)


def beyond_any_machine(model: ErrorModel) -> list[str]:
    """Lines naming each value the file wrote (``model.written``) that reaches
    `LARGEST_LIKELY_ERROR_M` (a length) or `LARGEST_LIKELY_ERROR_RAD` (an angle) in SI, all
    its entries: perhaps um or urad in a key in mm or deg. A table's positions and a
    polynomial's coefficients (whose size depends on the travel) are left out. Each line
    begins with the file and the key's line, as `below_any_machine`'s."""
    lines = []
    for field, (key, value) in model.written.items():
        unit = key.rsplit("_", 1)[-1]
        if field.endswith(".position") or "_poly_" in key or unit not in FACTORS:
            continue
        try:
            size = np.abs(np.asarray(value, dtype=np.float64)) * FACTORS[unit]
        except (TypeError, ValueError):  # a string: checked elsewhere
            continue
        length = is_length(unit)
        if not size.size or size.max() < (LARGEST_LIKELY_ERROR_M if length
                                          else LARGEST_LIKELY_ERROR_RAD):
            continue
        shown = np.asarray(value, dtype=np.float64).tolist()
        reach = (f"{size.max() * 1e3:.4g} mm" if length
                 else f"{np.degrees(size.max()):.4g} deg")
        what = ("a tool or workpiece set that far off misses its part" if length else
                "a part or an axis turned that far is another setting")
        lines.append(f"{_noted_at(model, field)}{key} = {shown!r} reaches {reach}, beyond "
                     "the errors of any machine "
                     f"({what}): was it written in {_SMALLER.get(unit, 'a smaller unit')}, "
                     f"where the key asks {unit}?")
    return lines


#: Below this share of its axis's travel (a whole turn for a rotary axis that turns
#: further) a table's positions are noted: `position_um = [-250.0, 0.0, 250.0]` for
#: grooving_4axis's X, written beside `EXX_um` where `position_mm` was meant, spans 0.5 mm of
#: its 500 mm, and the table, held at its end values beyond them, put a step of 7.6 um
#: within 0.5 mm of X = 0 and a constant 4.1 um everywhere else, with exit 0.
SHORTEST_TABLE_SHARE = 0.01


def short_tables(model: ErrorModel, machine) -> list[str]:
    """Lines naming each axis whose error tables' positions (as the file wrote them) span
    less than `SHORTEST_TABLE_SHARE` of the axis's travel on ``machine``: perhaps written
    in a smaller unit than meant (um for mm). Each says what the tables do beyond their
    positions: hold their end values. Axes the machine lacks are left to the fit check. Each
    line begins with the file and the key's line, as `below_any_machine`'s."""
    lines = []
    for field, (key, value) in model.written.items():
        if not field.endswith(".position"):
            continue
        axis = field.split(".")[1]
        if axis not in machine.axes:
            continue
        i = machine.axes.index(axis)
        travel = float(machine.upper[i] - machine.lower[i])
        if machine.rotary[i]:
            travel = min(travel, 2.0 * np.pi)
        tables = [error for error in model.component.get(axis, {}).values()
                  if error.kind == "table"]
        if not tables:
            continue
        positions = tables[0].positions
        span = float(positions[-1] - positions[0])
        if not travel > 0.0 or span >= SHORTEST_TABLE_SHARE * travel:
            continue
        unit = key.rsplit("_", 1)[-1]
        linear = not machine.rotary[i]
        show = (lambda v: f"{v * 1e3:.4g} mm") if linear else (
            lambda v: f"{np.degrees(v):.4g} deg")
        shown = np.asarray(value, dtype=np.float64).tolist()
        larger = {"um": "mm", "nm": "um or mm", "mm": "m"} if linear else {
            "urad": "mrad or deg", "mrad": "deg", "arcsec": "deg"}
        guess = (f": was it written in {larger[unit]}, where the key asks {unit}?"
                 if unit in larger else "")
        lines.append(f"{_noted_at(model, field)}{key} = {shown!r} spans {show(span)} of "
                     f"{axis}'s {show(travel)} "
                     f"travel, and its tables hold their end values beyond "
                     f"{show(positions[0])} .. {show(positions[-1])}{guess}")
    return lines


def far_polynomials(model: ErrorModel, machine) -> list[str]:
    """Lines naming each polynomial the file wrote that reaches `LARGEST_LIKELY_ERROR_M` (a
    length) or `LARGEST_LIKELY_ERROR_RAD` (an angle) over its axis's travel on ``machine``:
    `beyond_any_machine` leaves polynomials out, their size being the travel's, and
    `ErrorModel.check_travel` refuses only what passes `LARGEST_ERROR` (1 m, 180 deg), so
    ``EXX_poly_um_mm = [0.0, 0.0, 1.0]`` (c_2 in um/mm**2, perhaps meant per m**2) put the
    tool 62.5 mm off at X = 250 mm on grooving_4axis with exit 0 and no note. Axes the
    machine lacks are left to the fit check. Each line begins with the file and the key's
    line, as `below_any_machine`'s."""
    lines = []
    for axis, errors in model.component.items():
        if axis not in machine.axes:
            continue
        i = machine.axes.index(axis)
        lower, upper = float(machine.lower[i]), float(machine.upper[i])
        if machine.rotary[i] and (lower < -TURN or upper > TURN):
            continue  # a polynomial there is refused (`each_turn`): no note before that
        for symbol, error in errors.items():
            if error.kind != "poly":
                continue
            value, where = error.largest(lower, upper)
            length = symbol[1] in "XYZ"  # EXX .. EZC: a length; EAX .. ECC: an angle
            if abs(value) < (LARGEST_LIKELY_ERROR_M if length else LARGEST_LIKELY_ERROR_RAD):
                continue
            field = f"component.{axis}.{symbol}"
            key = model.key_as_written(field) or field
            reach = (f"{value * 1e3:.4g} mm" if length else f"{np.degrees(value):.4g} deg")
            at = (f"{np.degrees(where):.4g} deg" if machine.rotary[i]
                  else f"{where * 1e3:.4g} mm")
            written = model.written.get(field, (key, error.values))[1]
            shown = np.asarray(written, dtype=np.float64).tolist()
            lines.append(f"{_noted_at(model, field)}{key} = {shown!r} reaches {reach} at "
                         f"{axis} = {at} within {axis}'s travel, beyond the errors of any "
                         "machine: were its coefficients written for other units than its key "
                         "asks?")
    return lines


def turn_steps(model: ErrorModel, machine) -> list[str]:
    """Lines naming each table of a rotary axis that spans a whole turn or more, whose
    values a turn apart differ by `SMALLEST_WRITTEN_ERROR_SI` or more, where ``machine``'s
    travel of the axis reaches beyond the table: it repeats each turn there
    (`machinesim.errors.turns.each_turn`), so the error steps as the axis passes the
    table's end, and no chord follows a step. ``ECC_arcsec = [1.0, 0.0, 2.0]`` at
    ``position_deg = [-180.0, 0.0, 180.0]`` on grooving_4axis's C (-360 .. 360 deg) moved
    the tool 0.048 um at X = 10 mm as C passed 180 deg, without a word. Each line begins
    with the file and the key's line, as `below_any_machine`'s."""
    from machinesim.errors.turns import table_each_turn

    lines = []
    for axis, errors in model.component.items():
        if axis not in machine.axes or not machine.rotary[machine.axes.index(axis)]:
            continue
        i = machine.axes.index(axis)
        for symbol, error in errors.items():
            if table_each_turn(error) is error:  # a polynomial, or less than a turn
                continue
            first, last = float(error.positions[0]), float(error.positions[-1])
            pairs = ([(first, first + TURN)] if machine.lower[i] < first else []) + (
                [(last - TURN, last)] if machine.upper[i] > last else [])
            steps = [(abs(float(np.diff(error.evaluate(np.array(pair)))[0])), pair)
                     for pair in pairs]
            if not steps or max(steps)[0] < SMALLEST_WRITTEN_ERROR_SI:
                continue
            step, (a, b) = max(steps)
            field = f"component.{axis}.{symbol}"
            key = model.key_as_written(field) or field
            unit = key.rsplit("_", 1)[-1]
            if unit not in FACTORS:
                unit = "m" if symbol[1] in "XYZ" else "rad"
            va, vb = (float(v) / FACTORS[unit] for v in error.evaluate(np.array([a, b])))
            lines.append(
                f"{_noted_at(model, field)}{key} is {va:g} {unit} at {axis} = "
                f"{np.degrees(a):g} deg and {vb:g} {unit} at {np.degrees(b):g} deg, a turn "
                f"apart: the table repeats each turn beyond {np.degrees(first):g} .. "
                f"{np.degrees(last):g} deg, within {axis}'s travel, so the error steps by "
                f"{step / FACTORS[unit]:g} {unit} there, which no chord follows: give the "
                "same value a turn apart")
    return lines


def unit_slip_notes(model: ErrorModel, machine) -> list[str]:
    """Every note of this module on ``model`` against ``machine`` (a
    `machinesim.machines.Machine`), in one order: `below_any_machine`, `beyond_any_machine`,
    `short_tables`, `far_polynomials`, `turn_steps`. What `machinesim.cutting.cut` adds to
    its report's notes (`machinesim.errors.notes`, which ``machinesim cut --errors`` prints)
    and a scenario's ``--errors`` prints (`scenario_runs.errors_file`): one list, so a new
    check reaches both."""
    return [*below_any_machine(model), *beyond_any_machine(model),
            *short_tables(model, machine), *far_polynomials(model, machine),
            *turn_steps(model, machine)]


#: The units an error value is more likely written in, for a key in each unit.
_SMALLER = {"m": "mm or um", "mm": "um", "um": "nm", "rad": "mrad or urad", "mrad": "urad",
            "deg": "urad or arcsec"}
