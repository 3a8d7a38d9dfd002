"""Write a `Program` as FANUC-style NC text: absolute, metric, at the machine resolution."""

from __future__ import annotations

import math
import os
from decimal import Decimal

from machinesim._io import write_atomic
from machinesim.exceptions import NCProgramError
from machinesim.nc.parser import MAX_INTEGER_DIGITS
from machinesim.nc.program import PROGRAM_END, ROTARY_AXES, Move, Program
from machinesim.units import M_PER_MM, RAD_PER_DEG

#: Decimals of linear axis words in mm: 1 nm, the resolution of the seeds' machines.
LINEAR_DECIMALS = 6
#: Decimals of rotary axis words in deg: 0.00001 deg, the same machines' rotary resolution.
ROTARY_DECIMALS = 5
#: Decimals of F in mm/min: 1e-6 mm/min is 1e-8 of the slowest practical feed (0.1 mm/min)
#: apart, so rounding F never changes a cut, and F stays short enough for a control.
FEED_DECIMALS = 6
#: Modal state set by the header: absolute, metric, feed per minute, work offset G54.
HEADER = "G90 G21 G94 G54"


def format_program(program: Program) -> str:
    """The program as NC text.

    Emits ``%``, the O number (if any), ``G90 G21 G94 G54``, one block per move with only the
    words that changed, ``M30`` (unless the last move already ends the program) and ``%``.
    Axis words are relative to the program's G54 work offset, rounded to 1 nm (6 decimals in
    mm) and 0.00001 deg (5 decimals in deg); F in mm/min; a dwell as ``G04 P<ms>`` when the
    time is a whole number of milliseconds, else as ``G04 X<s>`` with the exact float.
    Reading the text back (with the same work offsets) gives the moves rounded to that
    resolution, and formatting those gives the same text.

    Parameters
    ----------
    program : Program

    Returns
    -------
    str
        The NC text, lines ending in ``\\n``.

    Raises
    ------
    NCProgramError
        When a value cannot be written: a feed that rounds to F0, a coordinate that is not
        finite relative to G54.
    """
    offset = program.work_offsets.get("G54", {})
    lines = ["%"]
    if program.number is not None:
        lines.append(f"O{program.number:04d}")
    lines.append(HEADER)
    written: dict[str, str] = {}
    mode = feed = spindle = None
    for move in program.moves:
        words = [] if move.block_number is None else [f"N{move.block_number}"]
        if move.kind == "dwell":
            if move.dwell_s != 0.0 or all(c in PROGRAM_END for c in move.m_codes):
                words += ["G04", _dwell_word(move.dwell_s)]
        else:
            code = "G00" if move.kind == "rapid" else "G01"
            if code != mode:
                words.append(code)
                mode = code
            axis_words = []
            for axis, value in move.target.items():
                text = _axis_text(axis, value - offset.get(axis, 0.0), program, move)
                if written.get(axis) != text:
                    axis_words.append(axis + text)
                    written[axis] = text
            if not axis_words:
                # A move that changes nothing at this resolution still has to be a block.
                axis = next(iter(move.target))
                axis_words.append(axis + written[axis])
            words += axis_words
            if move.feed_m_per_s is not None:
                text = _feed_text(move.feed_m_per_s, program, move)
                if text != feed:
                    words.append("F" + text)
                    feed = text
        if move.spindle_rpm is not None:
            text = _spindle_text(move.spindle_rpm)
            if text != spindle:
                words.append("S" + text)
                spindle = text
        words += [f"M{code:02d}" for code in move.m_codes]
        lines.append(" ".join(words))
    if not (program.moves and any(c in PROGRAM_END for c in program.moves[-1].m_codes)):
        lines.append("M30")
    lines.append("%")
    return "\n".join(lines) + "\n"


def write_program(program: Program, path: str | os.PathLike) -> None:
    """Write the program to ``path`` whole or not at all (`machinesim._io.write_atomic`)."""
    text = format_program(program)
    write_atomic(path, text, encoding="ascii")


def _fixed(value: float, decimals: int) -> str:
    """``value`` rounded to ``decimals``, with a decimal point and no trailing zeros."""
    text = f"{value:.{decimals}f}".rstrip("0")
    return "0." if text == "-0." else text


def _exact(value: float) -> str:
    """The shortest decimal that reads back as exactly ``value``, without exponent."""
    text = format(Decimal(repr(value)), "f")
    return text if "." in text else text + "."


def _axis_text(axis: str, value: float, program: Program, move: Move) -> str:
    if not math.isfinite(value):
        raise NCProgramError(f"axis {axis} relative to G54 is not finite ({value!r})",
                             source=program.source, line=move.line, key=axis)
    if axis in ROTARY_AXES:
        return _fixed(value / RAD_PER_DEG, ROTARY_DECIMALS)
    return _fixed(value / M_PER_MM, LINEAR_DECIMALS)


def _feed_text(feed_m_per_s: float, program: Program, move: Move) -> str:
    text = _fixed(feed_m_per_s * 60.0 / M_PER_MM, FEED_DECIMALS)
    if float(text) <= 0.0:
        raise NCProgramError(
            f"feed {feed_m_per_s!r} m/s rounds to F0 at {FEED_DECIMALS} decimals in mm/min",
            source=program.source,
            line=move.line,
            key="F",
        )
    return text


def _spindle_text(rpm: float) -> str:
    return str(int(rpm)) if rpm.is_integer() else _exact(rpm)


def _dwell_word(dwell_s: float) -> str:
    if dwell_s * 1000.0 < 10**MAX_INTEGER_DIGITS:
        ms = round(dwell_s * 1000.0)
        if ms / 1000.0 == dwell_s:
            return f"P{ms}"
    return "X" + _exact(dwell_s)
