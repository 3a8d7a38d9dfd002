"""Write a `Program` as FANUC-style NC text: absolute, metric, at the machine resolution."""

from __future__ import annotations

import os
from decimal import Decimal

import numpy as np

from machinesim._io import write_atomic
from machinesim.exceptions import NCProgramError
from machinesim.nc.blocks import TOOL_CHANGE
from machinesim.nc.moves import AXES, KIND_DWELL, KIND_RAPID
from machinesim.nc.parser import MAX_INTEGER_DIGITS
from machinesim.nc.program import PROGRAM_END, ROTARY_AXES, Program
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
    mm) and 0.00001 deg (5 decimals in deg); F in mm/min; ``G09`` in the block of each move
    that ends in an exact stop (`Program.exact_stops`; G61 is written as a G09 in every
    block); a dwell as ``G04 P<ms>`` when the time is a whole number of milliseconds, else
    as ``G04 X<s>`` with the exact float.
    Reading the text back (with the same work offsets) gives the moves rounded to that
    resolution, and formatting those gives the same text.

    An arc's chords (a program read with G02/G03) are written as the ``G01`` blocks they
    are: a `Program` keeps its moves, not its arcs, so the text read back keeps no
    `Program.arc_lengths` and its chords are timed by their own length over F, fast by
    chord_tolerance / (3 r) of the arc's time (3.2e-4 at 10 um chords on R10 mm, 3.3e-8
    at the reader's 1 nm). Writing the arcs back would mean fitting G02/G03 blocks to the
    chords and a text that no longer reads back to the same moves; scaling each chord's F
    by chord / arc would keep the time but write feeds the program never gave.

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
    program = _as_program(program)
    offset = program.work_offsets.get("G54", {})
    lines = ["%"]
    if program.number is not None:
        lines.append(f"O{program.number:04d}")
    lines.append(HEADER)
    # every word's text at once, column by column; None where the move leaves it unset
    axis_texts = [(axis, _axis_texts(program, column, offset.get(axis, 0.0)))
                  for column, axis in enumerate(AXES)
                  if not np.all(np.isnan(program.targets[:, column]))]
    feed_texts = _feed_texts(program)
    kinds, dwells = program.kinds.tolist(), program.dwells.tolist()
    blocks, spindles = program.block_numbers.tolist(), program.spindles.tolist()
    m_codes = dict(program.m_codes)
    tool_words = _tool_words(program, m_codes)
    stops = np.zeros(len(program), dtype=bool)
    stops[program.exact_stops] = True
    stops = stops.tolist()
    written: dict[str, str] = {}
    mode = feed = spindle = None
    for i, kind in enumerate(kinds):
        codes = m_codes.get(i, ())
        words = [] if blocks[i] < 0 else [f"N{blocks[i]}"]
        if stops[i]:
            words.append("G09")  # this block ends in position (`Program.exact_stops`)
        if kind == KIND_DWELL:
            if dwells[i] != 0.0 or all(c in PROGRAM_END for c in codes):
                words += ["G04", _dwell_word(dwells[i])]
        else:
            code = "G00" if kind == KIND_RAPID else "G01"
            if code != mode:
                words.append(code)
                mode = code
            axis_words = []
            first = None
            for axis, texts in axis_texts:
                text = texts[i]
                if text is None:
                    continue
                first = first or axis
                if written.get(axis) != text:
                    axis_words.append(axis + text)
                    written[axis] = text
            if not axis_words:
                # A move that changes nothing at this resolution still has to be a block.
                axis_words.append(first + written[first])
            words += axis_words
            text = feed_texts[i]
            if text is not None and text != feed:
                words.append("F" + text)
                feed = text
        if spindles[i] == spindles[i]:
            text = _spindle_text(spindles[i])
            if text != spindle:
                words.append("S" + text)
                spindle = text
        words += tool_words.get(i, [])
        words += [f"M{code:02d}" for code in codes]
        lines.append(" ".join(words))
    last = program.m_codes.get(len(kinds) - 1, ())
    if not (kinds and any(c in PROGRAM_END for c in last)):
        lines.append("M30")
    lines.append("%")
    return "\n".join(lines) + "\n"


def _tool_words(program: Program, m_codes) -> dict[int, list[str]]:
    """Block index -> the T word of each tool change (`Program.tool_changes`), placed so the
    reader, given the same tool table, finds the change at the same move: in the M06 block
    just before the tool's first move, or (a program without M06) in that move's block."""
    words: dict[int, list[str]] = {}
    for change in program.tool_changes:
        block = change.move - 1 if TOOL_CHANGE in m_codes.get(change.move - 1, ()) \
            else change.move
        words.setdefault(block, []).append(f"T{change.number}")
    return words


def write_program(program: Program, path: str | os.PathLike) -> None:
    """Write the program to ``path`` whole or not at all (`machinesim._io.write_atomic`)."""
    if not isinstance(path, str | os.PathLike):
        raise NCProgramError(f"expected the path to write the program to as a str or Path, "
                             f"got {type(path).__name__}", key="path")
    text = format_program(program)
    write_atomic(path, text, encoding="ascii")


def _as_program(program) -> Program:
    """``program`` when it is a `Program`; else a refusal naming what came, and for a
    result that holds one (`compensation.model_based`'s `Compensated`) where it is: such a
    result given to `write_program` had ended in "AttributeError: 'Compensated' object has
    no attribute 'work_offsets'"."""
    if isinstance(program, Program):
        return program
    name = type(program).__name__
    hint = (f"; write its .program, the rewritten Program ({name}.program)"
            if isinstance(getattr(program, "program", None), Program) else
            "; read an NC file with machinesim.nc.read_program(path)"
            if isinstance(program, str | os.PathLike) else "")
    raise NCProgramError(f"expected a machinesim.nc.Program, got {name}{hint}", key="program")


def _fixed(value: float, decimals: int) -> str:
    """``value`` rounded to ``decimals``, with a decimal point and no trailing zeros."""
    text = f"{value:.{decimals}f}".rstrip("0")
    return "0." if text == "-0." else text


def _exact(value: float) -> str:
    """The shortest decimal that reads back as exactly ``value``, without exponent."""
    text = format(Decimal(repr(value)), "f")
    return text if "." in text else text + "."


def _axis_texts(program: Program, column: int, offset: float) -> list[str | None]:
    """The words' texts of one axis column, relative to G54 (None where unset)."""
    axis = AXES[column]
    values = program.targets[:, column]
    rows = np.flatnonzero(~np.isnan(values))
    relative = values[rows] - offset
    bad = ~np.isfinite(relative)
    if np.any(bad):
        k = int(np.argmax(bad))
        raise NCProgramError(f"axis {axis} relative to G54 is not finite ({relative[k]!r})",
                             source=program.source, line=int(program.lines[rows[k]]), key=axis,
                             block=program.block_at(int(program.lines[rows[k]])))
    if axis in ROTARY_AXES:
        scaled, decimals = relative / RAD_PER_DEG, ROTARY_DECIMALS
    else:
        scaled, decimals = relative / M_PER_MM, LINEAR_DECIMALS
    texts: list[str | None] = [None] * len(values)
    for row, value in zip(rows.tolist(), scaled.tolist(), strict=True):
        texts[row] = _fixed(value, decimals)
    return texts


def _feed_texts(program: Program) -> list[str | None]:
    """F texts in mm/min of the moves that set a feed (None elsewhere)."""
    feeds = program.feeds
    rows = np.flatnonzero(~np.isnan(feeds))
    values, which = np.unique(feeds[rows], return_inverse=True)  # a program has few feeds
    distinct = [_fixed(value * 60.0 / M_PER_MM, FEED_DECIMALS) for value in values.tolist()]
    for k, text in enumerate(distinct):
        if float(text) <= 0.0:
            row = rows[np.argmax(which == k)]
            raise NCProgramError(
                f"feed {float(values[k])!r} m/s rounds to F0 at {FEED_DECIMALS} decimals in mm/min",
                source=program.source, line=int(program.lines[row]), key="F",
                block=program.block_at(int(program.lines[row])))
    texts: list[str | None] = [None] * len(feeds)
    for row, k in zip(rows.tolist(), which.reshape(-1).tolist(), strict=True):
        texts[row] = distinct[k]
    return texts


def _spindle_text(rpm: float) -> str:
    return str(int(rpm)) if rpm.is_integer() else _exact(rpm)


def _dwell_word(dwell_s: float) -> str:
    if dwell_s * 1000.0 < 10**MAX_INTEGER_DIGITS:
        ms = round(dwell_s * 1000.0)
        if ms / 1000.0 == dwell_s:
            return f"P{ms}"
    return "X" + _exact(dwell_s)
