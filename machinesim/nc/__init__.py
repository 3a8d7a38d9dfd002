"""NC programs: read and write FANUC-style G-code as ultraprecision machines run it.

The first arrow of the data flow: NC text (mm, inch, deg) -> `Program` (moves with absolute
machine axis targets in SI: m for X Y Z, rad for A B C, s, m/s). `format_program` writes a
`Program` back as NC text; `ProgramBuilder` makes one in Python.

The language read by `parse_program`
------------------------------------
Lines and blocks
    One block per line (lines split at ``\\n``; ``\\r`` and tab count as blanks). Lines that
    are blank, only comments, or a lone ``%`` (tape start/end marker, comments aside) are
    skipped. Comments: ``(...)`` closed on the same line, anywhere between words (no
    nesting), and everything after ``;``.
Words
    A letter (upper or lower case) and a number: optional sign, digits, optional decimal
    point (``X-.5``, ``X10.``, ``x+3``). Blanks between words are optional; blanks between a
    letter and its number are allowed, inside the number not (``Z - 1`` is refused); words
    come in any order. Letters read:
    N O G M S F P X Y Z A B C. Any other letter (I J K R of arcs, T, D, H, E, ...) is
    refused, as is any other character (``/`` block delete, ``#`` macros, ``=``, ...), a
    number without a letter, or a malformed number (``X1.2.3``, ``X--1``, ``X``).
    Integer words N O G M P take at most 9 unsigned digits. A value that is not finite in
    float64 is refused.
Once per block
    Each of N O S F P X Y Z A B C at most once (an axis word twice is refused); several M
    words are passed through in order; several G codes are allowed if each belongs to a
    different modal group (two motion codes, or G90 and G91, in one block are refused).
    Within a block the G codes act first, then F and S, then the axis words.
Program number
    ``O<n>`` must stand alone in the first block (before it only ``%``, comments and blank
    lines). It becomes `Program.number`.
G codes (anything else, e.g. G28, G41, G54.1, is refused as unknown)
    G00 rapid, G01 linear: modal motion mode (no default: an axis word before the first
    G00/G01 is refused). G04 dwell: one-shot, leaves the motion mode; ``G04 P<ms>`` with
    integer milliseconds as FANUC (a decimal point in P is refused) or ``G04 X<s>``
    seconds; exactly one of P and X, >= 0; a dwell without time, or with another axis word,
    is refused; P without G04 is refused. G02/G03 (circular interpolation) are refused.
    G90/G91 absolute/incremental (default G90). An incremental value on an axis that has
    no value yet is refused (the start position is unknown). G20/G21 inch/mm (default G21):
    X Y Z and F in inch and inch/min under G20; A B C are always degrees; switching
    mid-program is allowed and affects the words that follow. G17/G18/G19 plane selection
    (default G17): carried as state, no effect without arcs. G54..G59 work offsets
    (default G54). G94 feed per minute (the default and only mode; G95 is refused).
Axis values
    The machine target of an absolute axis word is the programmed value plus the active
    work offset (`work_offsets`, SI, absent = 0); an incremental word adds to the axis's
    current machine target (work offset changes do not move axes). Targets are modal: each
    move's target holds every axis given a value so far.
Integer input (a number without decimal point in X Y Z A B C)
    ``integer_input="calculator"`` (the default): X10 is 10 mm (10 inch under G20),
    A10 10 deg, like X10. . ``integer_input="increment"`` (FANUC's default without
    calculator-type input): X10 is 10 least input increments: 1 nm (0.0000001 inch under
    G20) for X Y Z, 0.00001 deg for A B C; ``G04 X`` without decimal point counts
    milliseconds. Words with a decimal point read the same in both modes. F, S, P, N, M,
    O and G are never affected.
F, S, M
    F: feed (mm/min, inch/min under G20), > 0, modal, stored in m/s (kept across G20/G21);
    linear moves carry it, rapid and dwell moves carry None, a linear move before any F
    carries None. S: spindle speed (rev/min) >= 0, modal, passed through. M: unsigned
    integers, any code passed through in `Move.m_codes`.
Which blocks make a `Move`
    A block with axis words makes a rapid or linear move (even if nothing changes); a G04
    block makes a dwell. A block with M words but neither makes a dwell of 0 s at the
    current position carrying them, so they keep their place, unless all its M words are
    program ends. Blocks with only modal words (G, F, S, N) make no move.
Program end
    M02 or M30 ends the program. Blocks after it are refused (NCProgramError); blank, comment
    and ``%`` lines after it are fine. A program without M02/M30 is accepted.
Errors
    Every refusal is an `NCProgramError` whose message names the source, line, column and
    word (``prog.nc, line 7, column 5, key 'G02': circular interpolation ...``), with the
    same as attributes.

The writer
----------
`format_program` emits ``%``, ``O<number>``, ``G90 G21 G94 G54``, one block per move with
only the words that changed (values relative to the program's G54 offset, rounded to 1 nm
and 0.00001 deg; F in mm/min to 6 decimals; dwell as ``G04 P<ms>`` when whole milliseconds,
else ``G04 X<s>`` exact), ``M30`` and ``%``. Reading that text back with the same work
offsets gives the moves at that resolution, and formatting them again gives the same text.
"""

from __future__ import annotations

from machinesim.nc.parser import (
    INCREMENT_INCH_M,
    INCREMENT_M,
    INCREMENT_RAD,
    parse_program,
    read_program,
)
from machinesim.nc.program import AXES, FrozenMapping, Move, Program, ProgramBuilder
from machinesim.nc.writer import (
    LINEAR_DECIMALS,
    ROTARY_DECIMALS,
    format_program,
    write_program,
)

__all__ = [
    "AXES",
    "INCREMENT_INCH_M",
    "INCREMENT_M",
    "INCREMENT_RAD",
    "LINEAR_DECIMALS",
    "ROTARY_DECIMALS",
    "FrozenMapping",
    "Move",
    "Program",
    "ProgramBuilder",
    "format_program",
    "parse_program",
    "read_program",
    "write_program",
]
