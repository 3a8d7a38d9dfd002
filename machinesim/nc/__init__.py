"""NC programs: read and write FANUC-style G-code as ultraprecision machines and CAM posts
write it.

The first arrow of the data flow: NC text (mm, inch, deg) -> `Program` (moves with absolute
machine axis targets in SI: m for X Y Z, rad for A B C, s, m/s). `format_program` writes a
`Program` back as NC text; `ProgramBuilder` makes one in Python. The full table of words
(supported, accepted as a state, refused), the tool table, subprograms, arcs and their
tolerances are in docs/nc.md; the rules in short:

The language read by `parse_program` / `read_program`
-----------------------------------------------------
Lines and blocks
    One block per line (lines split at ``\\n``; tab counts as a blank). Line ends are LF or
    CRLF: a CR not followed by LF (a lone CR, as old Mac files end lines) is refused at its
    line and column. Lines that are blank, only comments, or a lone ``%`` are skipped.
    Comments: ``(...)`` closed on the same line (no nesting), and everything after ``;``.
    Text after ``;`` that starts like a word (a letter read here, blanks allowed, a number:
    ``; X11.``, ``; T1 tool``) is refused, for ``;`` ends a block in FANUC text and that
    block would be lost (at a line's start, a whole-line comment in LinuxCNC and grbl, that
    text would run as the next block: write it in parentheses); ``; move to x1`` or a ``;``
    with nothing after it is a comment.
Words
    A letter (either case) and a number: optional sign, digits, optional decimal point
    (``X-.5``, ``X10.``, ``x+3``); blanks between words optional, between a letter and its
    number allowed, inside a number not. Letters read: N O G M S F P X Y Z A B C (axes and
    the rest as before) and I J K R Q L H T D where a G or M code reads them (arcs, cycles,
    subprograms, tools), E in a G187 block. Any other letter, ``/``, ``#``, ``=``, a
    number without letter, a malformed number is refused; so is text outside parentheses
    (a letter after a letter: ``ROUGH THE POCKET``, one problem for the text) and a macro
    statement (``IF``, ``GOTO``, ``WHILE``). Integer words N O G M P L H T D take at most 9 unsigned
    digits. Each letter other than G and M at most once a block; G codes one per modal group.
    Within a block: modal G codes, then F S T D H, then the motion, then M codes.
G codes
    Motion (modal, no default): G00 rapid, G01 linear, G02/G03 arcs (expanded at read time
    into linear moves within ``chord_tolerance``, default 1 nm; centre I J K from the start
    or radius R, R < 0 over 180 deg; full circle with I J K and end = start; helical with
    the plane's third axis, other axes move with the angle; an end off the circle by more
    than `ARC_RADIUS_TOLERANCE_M` is refused; an end within it of the start but not on it,
    read as a short arc, is warned about: a full circle was most likely meant). G04 dwell
    (P ms, P with a decimal point s as Haas reads it, or X s). G17/G18/G19 plane. G20/G21
    inch/mm. G90/G91. G54..G59 work offsets. G94. G28 (rapid through the intermediate
    point to the reference position of the named axes, ``reference`` or machine zero;
    ``G28 G91 Z0`` before Z is known goes straight to zero), G53 (one block in machine
    coordinates measured from the reference position: no work offset, no tool length;
    absolute only). G43/G44 H (tool
    length from the tool table added to / taken from absolute Z words; a bare G43 takes the
    last H, refused before any; G49 cancels; like a work offset change it moves nothing by
    itself; an incremental Z before an absolute Z has carried a change is refused, since
    controls differ there). G81/G82/G83/G73 canned cycles along Z in G17 with R, Z, Q, P, K and
    G98/G99 (G73/G83 also Haas's variable peck I J K), expanded into moves; G80 or a motion
    code cancels. G09 (this block) and G61 (every
    block until G64) end a block in an exact stop: `Program.exact_stops`, where the servo
    loops' lag does not carry into the next block; listed as states too. Accepted as
    states, no geometric effect, listed in `Program.states` with their first line: G40,
    G80, G91.1, G15 G50 G69 (the cancels of polar coordinates, scaling and rotation, as
    safe-start lines write them; G50 with an axis word, a lathe's coordinate setting, is
    refused),
    G05 P10000/P0, G05.1 Q1/Q0 (R level), G08 P1/P0, Haas's G103 P0..P15 (look-ahead limit) and G187
    P1..P3 E (smoothness, corner rounding), T and D words, and G55..G59 selected when no
    ``work_offsets`` were given (G54's zero); with offsets given, a G55..G59 they lack is
    refused. Refused: G41/G42 (cutter radius
    compensation), G93, G95, the canned cycles G74 G76 G84..G89, tool centre point
    and tilted planes (G43.4 G43.5 G68.2 G53.1), coordinate changes (G92 G52 G68 G51 G51.1
    G16), each by name, and every G code not named here.
Subprograms
    The main program is the file's first program (its O number in the first block, if any);
    after its M02/M30, ``O<n>`` blocks start subprograms, each ending in M99. ``M98 P<n>
    L<count>`` (n of at most 4 digits) or ``M98 P<count><nnnn>`` (at most 8 digits, no L)
    calls one; calls nest up to 10 deep; recursion,
    calls to missing programs, M99 in the main program (FANUC loops forever), M02/M30 in a
    subprogram, blocks after a subprogram's M99, and programs that would run more than
    `parser.MAX_BLOCK_RUNS` blocks are refused before anything runs.
Axis values
    The machine target of an absolute axis word is the programmed value plus the active work
    offset (`work_offsets`, SI; absent axes and G54 = 0, an absent G55..G59 refused when
    any offsets are given, 0 when none are), plus the tool length offset for Z; an
    incremental word adds to the axis's current machine target. Targets are modal.
Integer input (a number without decimal point in a length or angle: X Y Z A B C I J K R Q)
    ``integer_input="calculator"`` (the default): X10 is 10 mm (10 inch under G20), A10
    10 deg. ``"increment"`` (FANUC without calculator-type input): X10 is 10 least input
    increments: 1 nm (0.0000001 inch under G20) for lengths, 0.00001 deg for A B C;
    ``G04 X`` counts milliseconds. `Program.integer_input` says which rule was used.
F, S, M
    F: feed (mm/min, inch/min under G20), > 0, modal; linear moves carry it (m/s; a move
    that turns a rotary axis counts its degrees as mm, under G20 as inches: FANUC's rule,
    `machinesim.nc.rotary_feed`). S:
    spindle speed, passed through. M: passed through on the block's last move (M98/M99 are
    consumed); a block with M codes and no move makes a 0 s dwell carrying them, unless all
    are program ends. Blocks after M02/M30 (outside subprograms) are refused.
Errors
    Every refusal is an `NCProgramError` naming source, line, column and word. All refusals
    of a program are collected: one error lists them all (``error.problems`` holds each).

Reading speed
    Runs of plain modal motion lines (``X.. Z.. C..``: words N G0/G1 X Y Z A B C F only) are
    read by numpy over the whole text (`machinesim.nc.fastscan`), bit-identical to the
    word-by-word path; ``fast=False`` forces the latter.

Arrays
    A `Program` holds its moves as read-only arrays (`Program.targets` (N, 6) with NaN for
    axes without a value yet, `kinds`, `feeds`, `dwells`, `lines`, ...); `Program.moves` makes
    `Move` values on demand. `Program.from_arrays` builds one from arrays, checked.

The writer
----------
`format_program` emits ``%``, ``O<number>``, ``G90 G21 G94 G54``, one block per move with
only the words that changed (values relative to the program's G54 offset, rounded to 1 nm
and 0.00001 deg; F in mm/min to 6 decimals; dwell as ``G04 P<ms>`` when whole milliseconds,
else ``G04 X<s>`` exact), ``M30`` and ``%``. Reading that text back with the same work
offsets gives the moves at that resolution, and formatting them again gives the same text.
"""

from __future__ import annotations

from machinesim._submodules import submodule
from machinesim.nc.arcs import ARC_CHORD_M, ARC_RADIUS_TOLERANCE_M
from machinesim.nc.builder import ProgramBuilder
from machinesim.nc.parser import (
    INCREMENT_INCH_M,
    INCREMENT_M,
    INCREMENT_RAD,
    parse_program,
    read_program,
)
from machinesim.nc.program import (
    AXES,
    KIND_DWELL,
    KIND_LINEAR,
    KIND_RAPID,
    MOVE_KINDS,
    FrozenMapping,
    Move,
    Program,
)
from machinesim.nc.tooltable import Tool, ToolTable
from machinesim.nc.writer import (
    LINEAR_DECIMALS,
    ROTARY_DECIMALS,
    format_program,
    write_program,
)

__all__ = [
    "ARC_CHORD_M",
    "ARC_RADIUS_TOLERANCE_M",
    "AXES",
    "INCREMENT_INCH_M",
    "INCREMENT_M",
    "INCREMENT_RAD",
    "KIND_DWELL",
    "KIND_LINEAR",
    "KIND_RAPID",
    "LINEAR_DECIMALS",
    "MOVE_KINDS",
    "ROTARY_DECIMALS",
    "Tool",
    "ToolTable",
    "FrozenMapping",
    "Move",
    "Program",
    "ProgramBuilder",
    "format_program",
    "parse_program",
    "read_program",
    "write_program",
]


def __getattr__(name: str):
    # machinesim.nc.<module> without its own import (`machinesim._submodules`)
    return submodule(__name__, name)
