"""NC programs: parsing against hand-computed SI values, refusals, write/read round trips."""

from __future__ import annotations

import dataclasses
import math
import os
import re
from decimal import ROUND_HALF_EVEN, Decimal

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from machinesim.exceptions import NCProgramError, brief
from machinesim.nc import (
    AXES,
    Move,
    Program,
    ProgramBuilder,
    format_program,
    parse_program,
    read_program,
    write_program,
)

DEG = math.pi / 180.0
#: Targets are a decimal in mm times 1e-3 plus an offset: float64 round-off at <= 0.1 m is
#: below 1e-17 m per operation; 1e-15 m leaves room for a few operations and is 1e6 x below
#: 1 nm, so any real misreading (a unit, an offset, a sign) fails.
EXACT_M = 1e-15
#: The same for angles in rad (values <= 2 pi).
EXACT_RAD = 1e-15

HAND_WRITTEN = """%
O0100 (hand-written test program)
(work offsets: G54 X 10 mm, Z 5 mm; G55 X -20 mm, C 90 deg)
N1 G90 G21 G94 G17 G54
N2 G00 X0 Y0. Z2. C0 S12000 M03
N3 g01 z.5 f60 ; plunge at 60 mm/min
N4 X12.5Y-3.25
N5 G91 X-0.5 C45.
N6 G04 P1500
N7 G4 X0.25 (seconds)
N8 G90 G55 G00 X0 C0
N9 G01 Y1. F10.
N10 M09
N11 G21 G91 Z -1 M05
N12 M30
(nothing after the end but comments)
%
"""
OFFSETS = {"G54": {"X": 0.010, "Z": 0.005}, "G55": {"X": -0.020, "C": math.pi / 2}}
MM_PER_MIN = 1e-3 / 60.0
INCH_PER_MIN = 0.0254 / 60.0


def test_hand_written_program_gives_hand_computed_si_values():
    program = parse_program(HAND_WRITTEN, "hand.nc", work_offsets=OFFSETS)
    # (kind, X, Y, Z, C, feed m/s, dwell s, line, N, M codes), worked out by hand:
    # G54 adds 10 mm to X and 5 mm to Z; G55 subtracts 20 mm from X and adds 90 deg to C.
    start = (0.010, 0.0, 0.007, 0.0)
    cut = (0.0225, -0.00325, 0.0055, 0.0)
    turned = (0.022, -0.00325, 0.0055, 45 * DEG)
    g55 = (-0.020, -0.00325, 0.0055, 90 * DEG)
    y1 = (-0.020, 0.001, 0.0055, 90 * DEG)
    expected = [
        ("rapid", start, None, 0.0, 5, 2, (3,)),
        ("linear", (0.010, 0.0, 0.0055, 0.0), 60 * MM_PER_MIN, 0.0, 6, 3, ()),
        ("linear", cut, 60 * MM_PER_MIN, 0.0, 7, 4, ()),
        ("linear", turned, 60 * MM_PER_MIN, 0.0, 8, 5, ()),
        ("dwell", turned, None, 1.5, 9, 6, ()),
        ("dwell", turned, None, 0.25, 10, 7, ()),
        ("rapid", g55, None, 0.0, 11, 8, ()),
        ("linear", y1, 10 * MM_PER_MIN, 0.0, 12, 9, ()),
        ("dwell", y1, None, 0.0, 13, 10, (9,)),  # G21 again after the moves: the same unit
        ("linear", (-0.020, 0.001, 0.0045, 90 * DEG), 10 * MM_PER_MIN, 0.0, 14, 11, (5,)),
    ]
    assert len(program) == len(expected)
    assert program.number == 100
    assert program.source == "hand.nc"
    assert program.axes == ("X", "Y", "Z", "C")
    for move, (kind, xyzc, feed, dwell, line, n, m_codes) in zip(program, expected, strict=True):
        assert (move.kind, move.line, move.block_number, move.m_codes) == (kind, line, n, m_codes)
        assert list(move.target) == ["X", "Y", "Z", "C"]
        np.testing.assert_allclose([move.target[a] for a in "XYZ"], xyzc[:3], rtol=0,
                                   atol=EXACT_M)
        assert move.target["C"] == pytest.approx(xyzc[3], rel=0, abs=EXACT_RAD)
        if feed is None:
            assert move.feed_m_per_s is None
        else:
            assert move.feed_m_per_s == pytest.approx(feed, rel=1e-15)
        assert move.dwell_s == dwell
        assert move.spindle_rpm == 12000.0


def test_integer_input_rules():
    text = "G00 X10 Z1. A5 C2.\nX12 Y.5\nG04 X500\nG04 X0.5\n"
    calculator = parse_program(text).moves
    increment = parse_program(text, integer_input="increment").moves
    inch = "G20\nG00 X10 Y.5\n"  # the units at the head: a switch after a move is refused
    # Calculator: X10 is 10 mm, A5 is 5 deg, X10 under G20 is 10 inch, G04 X500 is 500 s.
    assert calculator[0].target["X"] == pytest.approx(0.010, abs=EXACT_M)
    assert calculator[0].target["A"] == pytest.approx(5 * DEG, abs=EXACT_RAD)
    assert calculator[1].target["X"] == pytest.approx(0.012, abs=EXACT_M)
    assert parse_program(inch).moves[0].target["X"] == pytest.approx(0.254, abs=EXACT_M)
    assert calculator[2].dwell_s == 500.0
    # Increment: 10 x 1 nm, 5 x 0.00001 deg, 10 x 0.0000001 inch, 500 ms; words with a
    # decimal point read the same in both modes.
    assert increment[0].target["X"] == pytest.approx(10e-9, abs=1e-20)
    assert increment[0].target["A"] == pytest.approx(5e-5 * DEG, abs=1e-20)
    assert increment[1].target["X"] == pytest.approx(12e-9, abs=1e-20)
    inch_increment = parse_program(inch, integer_input="increment").moves[0].target
    assert inch_increment["X"] == pytest.approx(10 * 1e-7 * 0.0254, abs=1e-20)
    assert inch_increment["Y"] == pytest.approx(0.5 * 0.0254, abs=EXACT_M)
    assert increment[2].dwell_s == 0.5
    for a, b in zip(calculator, increment, strict=True):
        for axis in ("Z", "C", "Y"):
            assert a.target.get(axis) == b.target.get(axis)
    assert calculator[3].dwell_s == increment[3].dwell_s == 0.5


#: G04 X1500 (no point) in s by rule: 1 s a unit under calculator-type input, the rule's time
#: increment otherwise (`words.DWELL_INCREMENT_S`: 1 ms, 1 ms, 0.1 ms).
BARE_DWELL_S = {"calculator": 1500.0, "increment": 1.5, "is-b": 1.5, "is-c": 0.15}


@pytest.mark.parametrize("rule", sorted(BARE_DWELL_S))
@pytest.mark.parametrize("units", ["G21", "G20"])
def test_a_dwell_under_g91_moves_nothing_and_its_x_is_seconds(rule, units):
    # FANUC's G04 X<s> (decimal point allowed) or P<ms> (none): under G91 and under every
    # integer-input rule X is a time, not an axis move, in mm or inch alike; the dwell keeps
    # X where it was, so the incremental move after it counts from there (1 + 1 = 2 units).
    text = (f"{units} G00 X1. Y0 Z0\nG91 G04 X1.5\nG04 X1500\nG04 P1500\nG00 X1.\n"
            "G90 G04 X2.\nX3.\nM30\n")
    program = parse_program(text, "p.nc", integer_input=rule)
    unit_m = 25.4e-3 if units == "G20" else 1e-3
    assert program.kinds.tolist() == [0, 2, 2, 2, 0, 2, 0]
    assert program.targets[:, 0].tolist() == pytest.approx(
        [unit_m, unit_m, unit_m, unit_m, 2 * unit_m, 2 * unit_m, 3 * unit_m], rel=1e-15)
    assert program.dwells.tolist() == [0.0, 1.5, BARE_DWELL_S[rule], 1.5, 0.0, 2.0, 0.0]
    assert dict(program.integer_words) == {}  # a dwell's X is no length


def test_integer_input_in_fanuc_increment_systems_and_the_words_read_so():
    # IS-B: 0.001 mm, 0.0001 inch, 0.001 deg; IS-C: a tenth of each. The plain lines take the
    # vectorised path, the arc the block-by-block one: both apply the rule and keep the
    # letters written without a point, with their first lines (zero and pointed ones not).
    text = "G00 X0 Z1.\nG01 X10 Y0 A5 F100.\nG02 X0. Y0. R5\nG01 X10\nG04 X500\n"
    # G04 X500: 500 x 0.001 s under IS-B, 500 x 0.0001 s under IS-C (`words.DWELL_INCREMENT_S`)
    for rule, mm, deg, s in (("is-b", 1e-6, 1e-3, 1e-3), ("is-c", 1e-7, 1e-4, 1e-4)):
        program = parse_program(text, integer_input=rule)
        moves = program.moves
        assert moves[1].target["X"] == pytest.approx(10 * mm, rel=1e-15)
        assert moves[1].target["A"] == pytest.approx(5 * deg * DEG, rel=1e-15)
        assert moves[-2].target["X"] == pytest.approx(10 * mm, rel=1e-15)
        # the inch increment a tenth of the mm one in inches (G20 at the head: after a move
        # the switch is refused)
        inch = parse_program("G20\nG01 X10 F1.\n", integer_input=rule).moves[0]
        assert inch.target["X"] == pytest.approx(10 * mm * 0.1 * 25.4, rel=1e-15)
        assert moves[-1].dwell_s == pytest.approx(500 * s, rel=1e-15)
        assert program.integer_input == rule
        assert dict(program.integer_words) == {"X": 2, "A": 2, "R": 3}
        slow = parse_program(text, integer_input=rule, fast=False)
        assert dict(slow.integer_words) == dict(program.integer_words) and slow == program
    # an arc of R5 increments from X10 increments back to X0: a half circle of 5 um at IS-B
    arc = parse_program(text, integer_input="is-b", chord_tolerance=1e-10).moves
    middle = [m.target["Y"] for m in arc[2:-2]]
    assert max(np.abs(middle)) == pytest.approx(5e-6, rel=1e-3)
    assert dict(parse_program("G01 X1.5 Y0 F100.\n").integer_words) == {}


def test_read_program_names_the_file_and_accepts_crlf(tmp_path):
    path = tmp_path / "part.nc"
    path.write_bytes(b"%\r\nO7\r\nG00 X1. (\xc3\x98 5 tool)\r\nG01 X2. F100\r\n%\r\n")
    program = read_program(path)
    assert program.source == str(path)
    assert [m.line for m in program] == [3, 4]
    bad = tmp_path / "bad.nc"
    bad.write_text("G00 X0\nG00 X1 Q5\n")
    with pytest.raises(NCProgramError, match=r"bad\.nc, line 2, column 8, key 'Q5'"):
        read_program(bad)
    # a UTF-8 byte order mark (Windows editors) is no part of line 1: the same moves, and a
    # problem on line 1 at the column an editor shows
    marked = tmp_path / "marked.nc"
    marked.write_bytes(b"\xef\xbb\xbf" + path.read_bytes())
    assert read_program(marked).moves == program.moves
    marked.write_bytes(b"\xef\xbb\xbfG00 X1 Q5\n")
    with pytest.raises(NCProgramError, match=r"marked\.nc, line 1, column 8, key 'Q5'"):
        read_program(marked)
    # a Ctrl-Z after the last line (DOS editors, DNC senders) ends the file: the same moves
    # (it had been refused as "unexpected character '\x1a'"); elsewhere it is still refused
    dos = tmp_path / "dos.nc"
    for tail in (b"\x1a", b"\x1a\x1a\r\n"):
        dos.write_bytes(path.read_bytes() + tail)
        assert read_program(dos).moves == program.moves
    dos.write_bytes(b"G00 X1. (a longer line: the byte is one of many)\n\x1a\nG00 X2.\n")
    with pytest.raises(NCProgramError, match=r"dos\.nc, line 2, column 1, key '\\x1a'"):
        read_program(dos)


def test_lone_cr_is_refused_at_its_line_and_column(tmp_path):
    # Old Mac line ends after line 3: read as blanks they would join 'X11.', 'G00 Z1.' and
    # 'M30' into one block (a rapid to X 11 mm, Z 1 mm instead of the G01 cut). Line 4 is
    # "X11.\rG00 Z1.\rM30\r": its first CR follows the 4 characters 'X11.', column 5.
    path = tmp_path / "mac.nc"
    path.write_bytes(b"G90 G21\nG00 X-1. Y2. Z0.1\nG01 Z-0.02 F100.\nX11.\rG00 Z1.\rM30\r")
    for fast in (True, False):
        with pytest.raises(NCProgramError, match="line ends must be LF or CRLF") as info:
            read_program(path, fast=fast)
        error = info.value
        assert (error.source, error.line, error.column, error.key) == (str(path), 4, 5, "\\r")
        assert "lone CR" in str(error)
        assert str(error).startswith(f"{path}, line 4, column 5, key '\\r': ")


# (text, line, column of the first lone CR): in a run of point lines that the fast path
# reads, at the end of the text, before a CRLF, in a comment, after ';'.
_POINTS = [f"X{k}. Z-0.{k:03d}" for k in range(20)]  # lines 3..22
LONE_CRS = [
    ("G90 G21\nG01 X0 Z0 F10.\n" + "\n".join(_POINTS[:9] + ["X9.\rZ-0.009"] + _POINTS[10:]),
     12, 4),  # "X9." is 3 characters
    ("G90 G21\nG01 X0 Z0 F10.\n" + "\n".join(_POINTS) + "\r", 22, 13),  # "X19. Z-0.019"
    ("G00 X0\r\r\nM30\r\n", 1, 7),  # CR CR LF: the first CR is lone
    ("G00 X0 (part\rG00 X5.)\nM30\n", 1, 13),
    ("G00 X0 ; go\rG00 X5.\nM30\n", 1, 12),
]


@pytest.mark.parametrize(("text", "line", "column"), LONE_CRS)
def test_lone_cr_is_refused_on_both_paths(text, line, column):
    for fast in (True, False):
        with pytest.raises(NCProgramError) as info:
            parse_program(text, "prog.nc", fast=fast)
        problems = getattr(info.value, "problems", (info.value,))
        lone = [p for p in problems if p.key == "\\r"]
        assert [(p.line, p.column) for p in lone] == [(line, column)]
        assert "CR) not followed by a line feed (LF): line ends must be LF or CRLF" in str(
            lone[0])


def test_crlf_reads_exactly_as_lf():
    # Blocks, comments, a ';' comment, and a run of point lines long enough for the fast
    # path; CRLF must give the same program as LF, with and without a final line end.
    lf = ("%\nO12 (crlf)\nG90 G21 G94 G54 ; setup\nG00 X-1. Y2. Z0.1 S1000 M03\n"
          "G01 Z-0.02 F100.\n" + "\n".join(_POINTS) + "\nG04 P250\nG00 Z1.\nM30\n%\n")
    crlf = lf.replace("\n", "\r\n")
    reference = parse_program(lf, "p.nc", fast=False)
    assert len(reference) == 1 + 1 + 20 + 1 + 1  # rapid, plunge, points, dwell, rapid
    for text in (crlf, crlf.removesuffix("\r\n"), lf.removesuffix("\n")):
        for fast in (True, False):
            program = parse_program(text, "p.nc", fast=fast)
            assert np.array_equal(program.targets, reference.targets, equal_nan=True)
            assert np.array_equal(program.kinds, reference.kinds)
            assert np.array_equal(program.feeds, reference.feeds, equal_nan=True)
            assert np.array_equal(program.dwells, reference.dwells)
            assert np.array_equal(program.lines, reference.lines)
            assert program == reference


def test_words_after_semicolon_are_refused():
    # ';' as FANUC end of block with several blocks on one line: 'X11.; Y4.; X-1.;' would be
    # read as a comment. Line 3 is "G01 Z-0.02 F100.; X11.; Y4.; X-1.;": ';' at column 17,
    # 'X11.' at column 19.
    text = "G90 G21;\nG00 X-1. Y2. Z0.1;\nG01 Z-0.02 F100.; X11.; Y4.; X-1.;\nG00 Z1.;\nM30;\n"
    with pytest.raises(NCProgramError, match="';' ends a block in FANUC text") as info:
        parse_program(text, "prog.nc")
    error = info.value
    assert (error.line, error.column, error.key) == (3, 19, "X11.")
    assert str(error).startswith("prog.nc, line 3, column 19, key 'X11.': word 'X11.' after "
                                 "the ';' at column 17 would be lost")
    assert "put each block on its own line (or write the comment in parentheses" in str(error)


# (line, column, word): a word after ';' (blanks between letter and number allowed, either
# case, after more ';'), refused at its letter; 'G01 X1. F100.' is 13 characters.
SEMICOLON_WORDS = [
    ("G01 X1. F100. ; T1 tool", 17, "T1"),
    ("G01 X1. F100.;X2.", 15, "X2."),
    ("G01 X1. F100.;; z -.5", 17, "Z-.5"),
    ("G01 X1. F100.;\tG00", 16, "G00"),
    ("G01 X1. F100. ; a 5-axis part", 17, "A5"),
]


@pytest.mark.parametrize(("text", "column", "word"), SEMICOLON_WORDS)
def test_word_after_semicolon_is_refused_at_its_column(text, column, word):
    with pytest.raises(NCProgramError, match="would be lost") as info:
        parse_program(f"G00 X0\n{text}\n", "p.nc")
    assert (info.value.line, info.value.column, info.value.key) == (2, column, word)


@pytest.mark.parametrize("comment", [
    "; move to x1", ";", ";  ;; ", "; N.B. slow here", "; 3 passes", "; E5 is no word here",
    "; (T1) tool", "; G-code from CAM", "(a; X1.) ; cut",
])
def test_comment_after_semicolon_reads_as_without_it(comment):
    bare = "G90 G21\nG00 X-1. Y2. Z0.1\nG01 Z-0.02 F100.\nX11.\nG00 Z1.\nM30\n"
    lines = bare.split("\n")
    lines[3] = f"X11. {comment}"
    assert parse_program("\n".join(lines), "p.nc") == parse_program(bare, "p.nc")


# (text, line, column, word, message): each refusal the language describes.
REFUSALS = [
    ("G00 X0 Y0\nG02 X1. Y1.", 2, 1, "G02", "G02 needs the centre"),
    ("G03 X1 I1", 1, 5, "X1", "the arc starts where X is not known yet"),
    ("G00 X0\n\nG41 X0", 3, 1, "G41", r"cutter radius compensation \(G41\) is not supp"),
    ("G00 X0\nG42 D1 G01 X1. F100.", 2, 1, "G42", "compensation 'in wear' .* holds the "
     "tool-centre path already, its G42 adding only the wear .* without the G42 and D"),
    ("G54.1 X0", 1, 1, "G54.1", "unknown G code G54.1"),
    ("G95", 1, 1, "G95", r"feed per revolution \(G95\)"),
    ("G00 X0 U1", 1, 8, "U1", "unknown word letter 'U'"),
    ("G00 X0 I5", 1, 8, "I5", "word I is only read with G02/G03"),
    ("G00 X0\nM99", 2, 1, "M99", "M99 in the main program would jump back"),
    ("G00 Z0\nG43 H1 Z5.", 2, 5, "H1", "G43 H1 needs tool 1's length"),
    ("G00 X0\nG91 G53 X0", 2, 5, "G53", "machine coordinates, which are absolute"),
    # a bare G28 (26 in one public set of Haas-style programs) is read differently by
    # Haas (every axis home) and FANUC (none): the message had said neither
    ("G28", 1, 1, "G28", "G28 without axis words: a Haas control returns every axis to "
     "machine zero, a FANUC moves none; name the axes it moves, Z first"),
    ("G53", 1, 1, "G53", "G53 needs the axes it moves"),
    ("G05.1 Q2", 1, 1, "G05.1", r"G05.1 needs Q1 \(on\) or Q0 \(off\)"),
    ("G05.1 Q1 X0", 1, 10, "X0", "G05.1 stands in a block of its own"),
    ("G81 X0 Z-1 R1", 1, 1, "G81", "Z is not known yet"),
    ("G00 Z5\nG81 X0 Z3. R2.", 2, 8, "Z3.", "hole bottom Z .* is not below the R plane"),
    ("G00 X0 Y0\nG02 X10. Y0 R4. F100", 2, 13, "R4.", "more than the diameter"),
    ("G00 X0 Y0\nG02 X10. Y0 I5.01 F100", 2, 13, "I5.01", "end point is off the arc"),
    ("G00 X0 Y0\nG02 X10. I5. R5.", 2, 14, "R5.", "an arc takes R or I J, not both"),
    ("G00 X0 Y0\nG03 X0 Y0 R5.", 2, 11, "R5.", "cannot be a full circle"),
    # an M98 problem points at the word at fault, P or L (it had pointed at M98)
    ("O1\nM98 P2\nM30", 2, 5, "P2", "M98 calls O0002, which is not in this file"),
    ("O1\nM98 P2\nM30\nO2\nM98 P2\nM99", 5, 5, "P2", "O0002 calls itself"),
    ("O1\nM30\nO2\nG04 P1\nM99\nG04 P2", 6, 1, "G04", "block after M99 on line 5"),
    ("O1\nM30\nO2\nM30\nM99", 4, 1, "M30", "M30 in subprogram O0002"),
    ("M98 P00002", 1, 5, "P00002", "asks for 0 repeats"),
    ("M98", 1, 1, "M98", r"M98 needs P<program number> \(an unsigned integer\)$"),
    ("M98 P1.5", 1, 5, "P1.5", r"M98 needs P<program number> \(an unsigned integer\), got P1.5"),
    ("O1\nM98 P2 L1.5\nM30\nO2\nM99", 2, 8, "L1.5", "M98 L takes an unsigned integer"),
    ("O1\nM98 P2 L99999999\nM30\nO2\nM98 P3 L9999\nM99\nO3\nG04 P0\nM99", 2, 8, "L99999999",
     "more than 50000000 blocks"),
    ("G00 X1e5", 1, 7, "E5", "unknown word letter 'E'"),
    ("G00 X1.2.3", 1, 5, "X1.2.3", "malformed number"),
    ("G00 X--1", 1, 5, "X--1", "malformed number .* e.g. X-12.5$"),
    ("G00 X2. Y2. Z5.\nG83 X2. Y2. Z-2. R1. Q.5 F50.\nG91 X2. K3", 3, 1, "G91",
     r"G83 repeated in G91 with R \(line 2\) and Z \(line 2\) given in G90: .* restate R "
     "and Z after changing G90/G91"),
    ("G00 X2. Y2. Z5.\nG83 X2. Y2. Z-2. R1. Q.5 F50.\nG91 X2. R-4. K3", 3, 1, "G91",
     r"with Z \(line 2\) given in G90: .* restate Z after"),
    ("G01 X1 F--5", 1, 8, "F--5", "malformed number .* e.g. F12.5$"),  # F-12.5 is refused
    ("G1.2.3", 1, 1, "G1.2.3", "malformed number .* e.g. G12$"),
    ("G00 Y", 1, 5, "Y", "malformed number"),
    ("G00 Xnan", 1, 5, "Xnan", "Xnan is not a finite number"),
    ("G00 X0\nG01 Z-inf F100.", 2, 5, "Z-inf", "Z-inf is not a finite number"),
    ("G00 X0\nG01 YInfinity F100.", 2, 5, "YInfinity", "YInfinity is not a finite number"),
    ("G00 X1 X2", 1, 8, "X2", "axis word X appears twice in one block"),
    ("G01 X1 F10 F20", 1, 12, "F20", "word F appears twice"),
    ("G00 G01 X1", 1, 5, "G01", "two motion G-codes in one block: G00 and G01"),
    ("G00 X0\nG04 G01 X1", 2, 5, "G01", "two motion G-codes in one block: G04 and G01"),
    ("G90 G91", 1, 5, "G91", "two distance G-codes in one block"),
    # P with a decimal point is seconds (Haas): the messages had said P is milliseconds
    ("G04", 1, 1, "G04", r"dwell without time: G04 needs P<milliseconds> \(with a decimal "
     r"point, P<seconds>, as Haas reads it\) or X<seconds>$"),
    ("G04 P-1.5", 1, 5, "P-1.5", "G04's dwell P-1.5 must be >= 0 .with a decimal point P is "
     "seconds"),
    ("G04 P-1500", 1, 5, "P-1500", "dwell time must be an unsigned integer"),
    ("G04 P100 X1.", 1, 10, "X1.", "got both P and X"),
    ("G04 X-1.", 1, 5, "X-1.", "dwell time must be >= 0"),
    ("G04 Y1", 1, 5, "Y1", r"axis word Y in a dwell block; G04 takes only "
     r"P<milliseconds> \(with a decimal point, P<seconds>, as Haas reads it\) or X<seconds>$"),
    ("G00 X0 P100", 1, 8, "P100", "P is only read with G04"),
    ("X1", 1, 1, "X1", "without a motion mode"),
    ("G91 G00 X1", 1, 9, "X1", "incremental .G91. move on axis X before its position"),
    ("G00 X0\nM30\nG00 X1", 3, 1, "G00", "block after the program end M30 on line 2"),
    ("G00 X0 (unclosed", 1, 8, "(", "comment '\\(' is not closed"),
    ("G00 X0 )", 1, 8, ")", "without an opening"),
    ("G00 X0 (a (b) c)", 1, 11, "(", "comments do not nest: .* opened at column 8"),
    ("O1\nM98 P1\nM30", 2, 5, "P1", "M98 calls O0001, the main program itself"),
    ("G00 X0 / Y1", 1, 8, "/", "block delete '/' is not read: a FANUC control skips"),
    ("G00 X12,5 Y0", 1, 8, ",", "decimal comma in 'X12,5': NC numbers take a decimal point"),
    ("G00 X0 Z1.\nG93 G01 X1. F10.", 2, 1, "G93", "inverse time feed \\(G93"),
    ("G00 X0 Y0 Z5.\nG74 X1. Y1. Z-1. R1. F100.", 2, 1, "G74",
     "canned cycle G74 \\(left-hand tapping\\) is not supported: machinesim expands G73, G81"),
    ("G00 X0 Y0 Z5.\nG98 G84 X1. Y1. Z-1. R1. F100.", 2, 5, "G84",
     "canned cycle G84 \\(tapping\\) is not supported"),
    ("G00 X0 Y0 Z5.\nG43.4 H1", 2, 1, "G43.4",
     "tool centre point control \\(G43.4\\) is not supported: the axis words"),
    ("G92 X0 Y0 Z50.", 1, 1, "G92", "setting the work coordinates at the current position "
     "\\(G92\\) is not supported: it would move every later axis word"),
    ("G00 X0\n/G01 X1. F10.", 2, 1, "/", "block delete '/' is not read"),
    ("G00 X0\n/2 G01 X1. F10.", 2, 1, "/2", "block delete '/2' is not read"),
    ("G00 #1", 1, 5, "#", "macro variable '#1': macro variables and expressions"),
    ("#101=[#1*2.] (CUSTOM MACRO B)", 1, 1, "#", "are not read: post the program with"),
    # one problem for the whole expression: it had been ten, one for each letter of 'sqrt'
    ("G00 X0 Y0\nG02 X600. I[300 + [100 * [0.00099 * sqrt[2]]]]", 2, 11,
     "I[300 + [100 * [0.00099 * sqrt[2]]]]", "^[^\n]*is a macro expression: macro"),
    ("G01 X#146/2+#148 F100.", 1, 5, "X#146/2+#148", r"X#146/2\+#148 is a macro expression"),
    ("G00 10", 1, 5, "10", "without an address letter"),
    ("G01 X0 F0", 1, 8, "F0", "feed must be > 0"),
    ("G01 X0 F-5", 1, 8, "F-5", "feed must be > 0"),
    ("G01 X0 F0." + "0" * 30 + "1", 1, 8, "F0." + "0" * 30 + "1", "below 1 nm a minute"),
    ("G00 X0\nG01 X1. F0.0000009", 2, 9, "F0.0000009", "below 1 nm a minute"),
    ("S-100", 1, 1, "S-100", "spindle speed must be >= 0"),
    ("M3.5", 1, 1, "M3.5", "M code must be an unsigned integer"),
    ("N1234567890", 1, 1, "N1234567890", "at most 9 digits"),
    ("G-1", 1, 1, "G-1", "has a sign"),
    ("G00 X0\nO1", 2, 1, "O1", "must be the first block"),
    ("O1\nM30\nO2\nM99\nO2\nM99", 5, 1, "O2", "subprogram O0002 is defined twice"),
    ("O1 G00", 1, 4, "G00", "must stand alone"),
    ("G00 X0\n% G00", 2, 3, "G00", "must stand alone on its line"),
    # one problem for the text, not one for each of its letters (MPCNC posts write such
    # lines as comments): 'vfd enable' had been nine problems
    ("G00 X0\n% vfd enable (MPCNC)", 2, 3, "vfd enable",
     "^[^\n]*found 'vfd enable' after it: past the opening one, a '%' ends the program"),
    ("G00 X0 %", 1, 8, "%", "found it after words"),
    ("G00 X" + "9" * 400, 1, 5, "X" + "9" * 400, "out of range"),
    ("G00 X1.\nG04 X" + "9" * 400 + ".", 2, 5, "X" + "9" * 400 + ".", "out of range"),
]


#: What a word is, in the refusal of text outside parentheses.
_TEXT_WANTED = ("a word is one letter and a number (X1., M98 P1000); expected a comment in "
                "parentheses")
_MACRO_WANTED = ("(custom macro B: IF, GOTO, WHILE/DO/END, DPRNT) is not read: machinesim reads "
                 "no branches, loops or macro output; post the program with them resolved into "
                 "plain blocks")


@pytest.mark.parametrize(("text", "line", "column", "key", "message"), [
    # prose outside parentheses: one problem for the text (to the line's end, or a comment),
    # not one 'malformed number' for each of its letters (14 for ROUGH THE POCKET)
    ("ROUGH THE POCKET\nG00 X0", 1, 1, "ROUGH THE POCKET",
     f"text 'ROUGH THE POCKET' outside a comment: {_TEXT_WANTED}, e.g. '(ROUGH THE POCKET)'"),
    ("G00 X0\nG01 X1. FEED SLOWLY (NOTE)", 2, 9, "FEED SLOWLY",
     f"text 'FEED SLOWLY' outside a comment: {_TEXT_WANTED}, e.g. '(FEED SLOWLY)'"),
    ("G00 X0 Y0\nA POCKET", 2, 1, "A POCKET",
     f"text 'A POCKET' outside a comment: {_TEXT_WANTED}, e.g. '(A POCKET)'"),
    ("G00 X1.5MM", 1, 9, "MM", f"text 'MM' outside a comment: {_TEXT_WANTED}, e.g. '(MM)'"),
    ("G00 X0\nEND OF PROGRAM", 2, 1, "END OF PROGRAM",
     f"text 'END OF PROGRAM' outside a comment: {_TEXT_WANTED}, e.g. '(END OF PROGRAM)'"),
    # custom macro B statements, refused as macros: each had been one problem per letter
    ("IF [#1 GT 2] GOTO 10", 1, 1, "IF [#1 GT 2] GOTO 10",
     f"macro statement 'IF [#1 GT 2] GOTO 10' {_MACRO_WANTED}"),
    ("G00 X0\nWHILE [#1 LT 3] DO1 (LOOP)", 2, 1, "WHILE [#1 LT 3] DO1",
     f"macro statement 'WHILE [#1 LT 3] DO1' {_MACRO_WANTED}"),
    ("GOTO 10", 1, 1, "GOTO 10", f"macro statement 'GOTO 10' {_MACRO_WANTED}"),
    ("G00 X0\nEND1", 2, 1, "END1", f"macro statement 'END1' {_MACRO_WANTED}"),
    # a lone letter before a word is still a missing number, not text
    ("G00 X Y1.", 1, 5, "X",
     "malformed number '' after 'X'; expected digits with an optional sign and decimal "
     "point, e.g. X-12.5"),
])
def test_text_outside_a_comment_is_one_problem(text, line, column, key, message):
    with pytest.raises(NCProgramError) as info:
        parse_program(text, "prog.nc")
    error = info.value
    assert (error.line, error.column, error.key) == (line, column, key)
    assert str(error) == f"prog.nc, line {line}, column {column}, key '{key}': {message}"


def test_words_packed_without_blanks_are_no_text():
    program = parse_program("g90g21\nG01X1.Y2.F100.\nM98P1000\nM30\nO1000\nx3.y-4.\nM99\n")
    assert program.targets[:, :2].tolist() == [[1e-3, 2e-3], [3e-3, -4e-3]]


@pytest.mark.parametrize(("text", "line", "column", "word", "message"), REFUSALS)
def test_refusals_name_line_column_and_word(text, line, column, word, message):
    with pytest.raises(NCProgramError, match=message) as info:
        parse_program(text, "prog.nc")
    error = info.value
    assert (error.source, error.line, error.column, error.key) == ("prog.nc", line, column, word)
    # the key stays whole; the message shows a long one by its ends (`brief`)
    assert str(error).startswith(f"prog.nc, line {line}, column {column}, key '{brief(word)}': ")


def test_refused_arguments():
    with pytest.raises(NCProgramError, match="integer_input must be one of"):
        parse_program("G00 X0", integer_input="decimal")
    with pytest.raises(NCProgramError, match="unknown work offset 'G60'"):
        parse_program("G00 X0", work_offsets={"G60": {"X": 0.0}})
    with pytest.raises(NCProgramError, match="unknown axis 'U'"):
        parse_program("G00 X0", work_offsets={"G54": {"U": 0.0}})
    with pytest.raises(NCProgramError, match="must be str"):
        parse_program(b"G00 X0")


@pytest.mark.parametrize("code", ["G55", "G56", "G57", "G58", "G59"])
def test_a_work_offset_the_given_offsets_lack_is_refused_naming_its_line(code):
    # G54 X 10 mm given, the program selects another system: it had read as zero (machine
    # zero), the part cut 10 mm from where G54's would be, without a word
    text = f"G90 G21\nG00 X0 Y0 Z1.\nN20 {code}\nG00 X1.\nM30\n"
    with pytest.raises(NCProgramError) as info:
        parse_program(text, "prog.nc", work_offsets={"G54": {"X": 10e-3}})
    error = info.value
    assert (error.line, error.column, error.key) == (3, 5, code)
    assert f"{code} selects a work offset that work_offsets does not give (it gives G54)" in str(
        error)
    # given (an empty system is machine zero), the same text reads: X1. is 1 mm + its offset
    for system, x_mm in (({"X": -20e-3}, -19.0), ({}, 1.0)):
        program = parse_program(text, work_offsets={"G54": {"X": 10e-3}, code: system})
        assert program.targets[:, 0].tolist() == pytest.approx([10e-3, x_mm * 1e-3],
                                                               abs=EXACT_M)
    # without any offsets every system is zero, as documented, and listed with its line
    program = parse_program(text)
    assert program.targets[-1, 0] == pytest.approx(1e-3, abs=EXACT_M)
    assert program.states[code] == 3


def test_g54_left_out_of_the_given_offsets_is_machine_zero():
    # G54 is the system a program runs in without a G54..G59 word; left out it is zero, as
    # the writer and `to_resolution` read it
    text = "G90 G21 G54\nG00 X1.\nG55 X1.\nM30\n"
    program = parse_program(text, work_offsets={"G55": {"X": 5e-3}})
    assert program.targets[:, 0].tolist() == pytest.approx([1e-3, 6e-3], abs=EXACT_M)


@pytest.mark.parametrize("distance", ["G90", "G91"])
def test_target_beyond_float64_is_refused(distance):
    # An offset near the float64 maximum (1.798e308) plus 1e305 m overflows: absolute values
    # add the offset, incremental ones the previous target (which holds the offset).
    huge = "1" + "0" * 308 + "."  # 1e308 mm = 1e305 m
    with pytest.raises(NCProgramError, match="out of range") as info:
        parse_program(f"G00 X0\n{distance} X{huge}", work_offsets={"G54": {"X": 1.797e308}})
    assert (info.value.line, info.value.column, info.value.key) == (2, 5, "X" + huge)


def test_builder_matches_the_equivalent_nc_text():
    built = (
        ProgramBuilder(number=1)
        .spindle(8000)
        .rapid(X=0.0, Z=1e-3, m_codes=(3,))
        .linear(X=0.01, feed_mm_per_min=100.0)
        .linear(Z=0.0)
        .dwell(0.5)
        .dwell(0.0, m_codes=(8,))
        .build()
    )
    text = "O1\nG00 X0 Z1. S8000 M03\nG01 X10. F100.\nZ0\nG04 P500\nM08\n"
    parsed = parse_program(text)
    assert len(built) == len(parsed) == 5
    for b, p in zip(built, parsed, strict=True):
        assert dataclasses.replace(b, line=p.line) == p
    assert built.moves[2].target == {"X": 0.01, "Z": 0.0}
    assert built.moves[2].feed_m_per_s == pytest.approx(100 * MM_PER_MIN, rel=1e-15)


def test_moves_and_programs_are_immutable_and_hashable():
    program = ProgramBuilder().rapid(X=0.0).linear(Y=1e-3, feed_m_per_s=1e-3).build()
    move = program.moves[1]
    with pytest.raises(TypeError):
        move.target["X"] = 1.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        move.kind = "rapid"
    with pytest.raises(TypeError):
        program.work_offsets["G54"] = {"X": 1.0}
    assert hash(move) == hash(Move("linear", {"Y": 1e-3, "X": 0.0}, 1e-3, line=2))
    assert list(move.target) == ["X", "Y"]


@pytest.mark.parametrize(
    ("moves", "message"),
    [
        ([Move("rapid", {"X": 0.0, "Y": 0.0}), Move("rapid", {"X": 1.0})], "drops axis Y"),
        ([Move("rapid", {"X": 0.0}), Move("dwell", {"X": 1.0}, dwell_s=1.0)], "is a dwell but"),
        ([Move("linear", {"X": 0.0}, 1e-3), Move("linear", {"X": 1.0})], "without feed after"),
        ([Move("rapid", {"X": 0.0}, m_codes=(30,)), Move("rapid", {"X": 1.0})], "ends the prog"),
        ([Move("rapid", {"X": 0.0}, spindle_rpm=1.0), Move("rapid", {"X": 1.0})], "S is modal"),
    ],
)
def test_from_moves_refuses_what_nc_cannot_say(moves, message):
    with pytest.raises(NCProgramError, match=message):
        Program.from_moves(moves)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"kind": "arc", "target": {"X": 0.0}}, "kind must be one of"),
        ({"kind": "rapid", "target": {}}, "needs at least one axis"),
        ({"kind": "rapid", "target": {"X": 0.0}, "feed_m_per_s": 1.0}, "feed must be None"),
        ({"kind": "linear", "target": {"X": math.nan}}, "must be finite"),
        ({"kind": "linear", "target": {"X": 0.0}, "dwell_s": 1.0}, "dwell_s must be"),
        ({"kind": "dwell", "target": {}, "m_codes": (-1,)}, "m_codes must be"),
    ],
)
def test_move_refuses_bad_fields(kwargs, message):
    with pytest.raises(NCProgramError, match=message):
        Move(**kwargs)


@pytest.mark.parametrize(("kind", "feed", "message"), [
    ("linear", -1e-3, "feed must be > 0 for a linear move, got -0.001 m/s"),
    ("linear", 0.0, "feed must be > 0 for a linear move, got 0.0 m/s"),
    ("rapid", 1e-3, "feed must be None for a rapid move (only a linear move has one), got "
                    "0.001"),
])
def test_a_bad_feed_is_named_for_what_is_wrong_with_it(kind, feed, message):
    # the message had read "feed must be None for a linear move and > 0 for a linear move"
    # for a linear move's negative feed; the same from a Move and from Program.from_arrays
    with pytest.raises(NCProgramError) as error:
        Move(kind, {"X": 0.0}, feed)
    assert message in str(error.value)
    code = {"rapid": 0, "linear": 1}[kind]
    with pytest.raises(NCProgramError) as error:
        Program.from_arrays(np.array([[0.0] + [np.nan] * 5]), np.array([code], np.uint8),
                            np.array([feed]), np.zeros(1), np.ones(1, np.int64))
    assert message in str(error.value)


@pytest.mark.parametrize(("feed", "message"), [
    ({"feed_mm_per_min": -100.0}, "feed_mm_per_min must be > 0, got -100.0"),
    ({"feed_mm_per_min": 0.0}, "feed_mm_per_min must be > 0, got 0.0"),
    ({"feed_m_per_s": -1e-3}, "feed_m_per_s must be > 0, got -0.001"),
    ({"feed_m_per_s": "fast"}, "feed must be a real number, got 'fast'"),
])
def test_the_builder_names_a_bad_feed_as_it_was_given(feed, message):
    # a builder's feed_mm_per_min=-100 was refused by the move, as key 'feed_m_per_s' of
    # '<move>' in m/s: neither the argument the caller wrote nor its unit
    builder = ProgramBuilder().rapid(X=0.0)
    with pytest.raises(NCProgramError) as error:
        builder.linear(X=1e-3, **feed)
    assert message in str(error.value)
    assert error.value.source == "<builder>"
    assert error.value.key == next(iter(feed))
    assert error.value.line == 2


def test_the_builder_refuses_a_linear_move_before_any_feed_naming_the_argument():
    # it built, and the planner refused it later as 'a feed move (G01) with no feed rate F
    # given so far', at the move's line: an F the builder's caller never writes
    builder = ProgramBuilder().rapid(X=0.0).rapid(Z=1e-3)
    with pytest.raises(NCProgramError) as error:
        builder.linear(X=1e-3)
    assert str(error.value).startswith(
        "<builder>, line 3, key 'feed_mm_per_min': a linear move needs a feed and none was "
        "given before it: give feed_mm_per_min (or feed_m_per_s) on the first linear move")
    assert len(builder.build().moves) == 2  # nothing appended
    # the feed is modal: given once, the next linear moves keep it (100 mm/min in m/s)
    program = builder.linear(X=1e-3, feed_mm_per_min=100.0).linear(Y=1e-3).build()
    assert [m.feed_m_per_s for m in program.moves[2:]] == [100.0 * 1e-3 / 60.0] * 2


def _rounded(value: float, decimals: int) -> float:
    """Round-half-even of the exact binary value with Decimal: a second method to f-strings."""
    quantum = Decimal(1).scaleb(-decimals)
    return float(Decimal(value).quantize(quantum, rounding=ROUND_HALF_EVEN))


def _random_program(rng: np.random.Generator) -> Program:
    offsets = {"G54": {"X": rng.uniform(-0.05, 0.05), "Z": rng.uniform(-0.05, 0.05),
                       "C": rng.uniform(-1.0, 1.0)}}
    builder = ProgramBuilder(number=int(rng.integers(0, 10000)), work_offsets=offsets)
    axes = list(rng.choice(AXES, size=int(rng.integers(1, 7)), replace=False))
    last: dict[str, float] = {}
    fed = False
    n_moves = 40
    for index in range(n_moves):
        if rng.random() < 0.1:
            builder.spindle(float(rng.choice([0.0, 12000.0, rng.uniform(0.0, 20000.0)])))
        number = int(rng.integers(0, 100000)) if rng.random() < 0.3 else None
        m_codes = tuple(int(c) for c in rng.choice([0, 1, 3, 5, 8, 9, 97],
                                                   size=int(rng.integers(0, 3))))
        if index == n_moves - 1 and rng.random() < 0.5:
            m_codes += (30,)
        kind = rng.choice(["rapid", "linear", "linear", "dwell", "m"])
        if kind in ("rapid", "linear"):
            chosen = rng.choice(axes, size=int(rng.integers(1, len(axes) + 1)), replace=False)
            values = {
                str(a): (last[a] if a in last and rng.random() < 0.2  # zero-length moves too
                         else rng.uniform(-2 * math.pi, 2 * math.pi) if a in "ABC"
                         else rng.uniform(-0.5, 0.5))
                for a in chosen
            }
            last.update(values)
            if kind == "rapid":
                builder.rapid(block_number=number, m_codes=m_codes, **values)
            else:
                feed = rng.uniform(0.1, 2000.0) if rng.random() < 0.3 else None
                if feed is None and not fed:  # the first linear move has one
                    feed = rng.uniform(0.1, 2000.0)
                fed = True
                builder.linear(feed_mm_per_min=feed, block_number=number, m_codes=m_codes,
                               **values)
        elif kind == "dwell":
            seconds = float(rng.choice([0.0, int(rng.integers(0, 100000)) / 1000.0,
                                        rng.uniform(0.0, 10.0)]))
            builder.dwell(seconds, block_number=number, m_codes=m_codes)
        else:
            builder.dwell(0.0, block_number=number, m_codes=m_codes or (8,))
    return builder.build()


@pytest.mark.parametrize("seed", range(20))
def test_write_read_round_trip_at_the_resolution(seed, tmp_path):
    program = _random_program(np.random.default_rng(seed))
    path = tmp_path / "out.nc"
    write_program(program, path)
    text = path.read_text()
    assert text == format_program(program)
    back = read_program(path, work_offsets=program.work_offsets)
    assert format_program(back) == text  # the format is stable
    offset = program.work_offsets["G54"]
    assert len(back) == len(program)
    assert back.number == program.number
    for before, after in zip(program, back, strict=True):
        assert (after.kind, after.block_number, after.m_codes, after.spindle_rpm) == (
            before.kind, before.block_number, before.m_codes, before.spindle_rpm)
        assert after.dwell_s == before.dwell_s  # dwell is written exactly
        assert list(after.target) == list(before.target)
        for axis, value in before.target.items():
            off = offset.get(axis, 0.0)
            if axis in "ABC":
                # Within half the 0.00001 deg resolution (+ round-off), and exactly the
                # Decimal-rounded value read back.
                assert abs(after.target[axis] - value) <= 0.5e-5 * DEG + EXACT_RAD
                expected = _rounded((value - off) / DEG, 5) * DEG + off
            else:
                # Within half the 1 nm resolution (+ round-off), and exactly the rounded value.
                assert abs(after.target[axis] - value) <= 0.5e-9 + EXACT_M
                expected = _rounded((value - off) / 1e-3, 6) * 1e-3 + off
            assert after.target[axis] == expected
        if before.feed_m_per_s is None:
            assert after.feed_m_per_s is None
        else:
            expected = _rounded(before.feed_m_per_s * 60.0 / 1e-3, 6) * 1e-3 / 60.0
            assert after.feed_m_per_s == expected


def test_written_text_looks_as_documented():
    offsets = {"G54": {"Z": 0.001}}
    program = (ProgramBuilder(number=12, work_offsets=offsets)
               .rapid(X=1e-3, Z=1.0000004e-3, A=math.pi)
               .linear(X=2e-3, feed_mm_per_min=50.0, block_number=7)
               .linear(X=2e-3)
               .dwell(0.1234)
               .dwell(0.123456789)
               .dwell(0.0)
               .dwell(0.0, m_codes=(9,))
               .dwell(0.0, m_codes=(30,))
               .build())
    text = format_program(program)
    assert text == (
        "%\nO0012\nG90 G21 G94 G54\n"
        "G00 X1. Z0. A180.\n"   # Z: 1.0000004 mm - 1 mm offset rounds to 0 at 1 nm
        "N7 G01 X2. F50.\n"
        "X2.\n"                 # a move that changes nothing still gets a block
        "G04 X0.1234\n"         # 0.1234 s is not whole milliseconds
        "G04 X0.123456789\n"
        "G04 P0\n"
        "M09\n"                 # M codes without motion: a 0 s dwell
        "G04 P0 M30\n"          # a lone M30 would make no move; no second M30
        "%\n"
    )
    back = parse_program(text, work_offsets=offsets)
    assert [(m.kind, m.dwell_s, m.m_codes) for m in back.moves[-3:]] == [
        ("dwell", 0.0, ()), ("dwell", 0.0, (9,)), ("dwell", 0.0, (30,))]
    assert len(back) == len(program)


def test_writing_what_is_not_a_program_says_what_came(tmp_path):
    # write_program(model_based(...), path), the result for its .program, ended in
    # "AttributeError: 'Compensated' object has no attribute 'work_offsets'"; a path that
    # is not one in "TypeError: expected str, bytes or os.PathLike object, not int"
    from machinesim.compensation import model_based

    program = ProgramBuilder(1).rapid(X=1e-3, Y=2e-3, Z=1e-3).build()
    result = model_based(program, "grooving_4axis", {"tool": {"offset_um": [4.0, -2.0, 0.0]}})
    path = tmp_path / "c.nc"
    for wrong, message in [
        (result, "expected a machinesim.nc.Program, got Compensated; write its .program, the "
                 "rewritten Program (Compensated.program)"),
        ("part.nc", "expected a machinesim.nc.Program, got str; read an NC file with "
                    "machinesim.nc.read_program(path)"),
        (None, "expected a machinesim.nc.Program, got NoneType")]:
        with pytest.raises(NCProgramError) as info:
            write_program(wrong, path)
        assert (info.value.key, str(info.value)) == ("program", f"key 'program': {message}")
        with pytest.raises(NCProgramError) as info:
            format_program(wrong)
        assert info.value.key == "program"
    with pytest.raises(NCProgramError, match="key 'path': expected the path to write the "
                                             "program to as a str or Path, got int"):
        write_program(program, 3)
    assert not path.exists()
    write_program(result.program, path)
    assert read_program(path).targets[0, :2].tolist() == pytest.approx([0.996e-3, 2.002e-3],
                                                                        abs=1e-15)


def test_write_is_whole_or_nothing(tmp_path, monkeypatch):
    path = tmp_path / "p.nc"
    good = ProgramBuilder().rapid(X=0.0).build()
    write_program(good, path)
    before = path.read_text()
    too_slow = ProgramBuilder().linear(X=0.0, feed_m_per_s=1e-15).build()
    with pytest.raises(NCProgramError, match=r"line 1, key .F.: feed 1e-15 m/s rounds to F0"):
        write_program(too_slow, path)

    def failing_replace(src, dst):
        raise OSError("disk full")

    monkeypatch.setattr(os, "replace", failing_replace)
    with pytest.raises(OSError, match="disk full"):
        write_program(ProgramBuilder().rapid(X=1.0).build(), path)
    assert path.read_text() == before
    assert os.listdir(tmp_path) == ["p.nc"]


NC_CHARACTERS = "GXYZABCMNFSPOIJKTgxz0123456789.+-  ()%;\n\t/#"
_number = st.one_of(
    st.integers(-10**12, 10**12).map(str),
    st.floats(allow_nan=False, allow_infinity=False, width=64).map(lambda v: f"{v:f}"),
    st.text("0123456789.+-", max_size=6),
)
_any_word = st.tuples(st.sampled_from("GGGMNFSPOXYZABCxyzIT"), _number).map("".join)
# Mostly well-formed words, so that many programs parse and reach the writer too.
_good_word = st.one_of(
    st.sampled_from(["G0", "G00", "G1", "g01", "G04", "G90", "G91", "G20", "G21", "G18",
                     "G55", "G94", "M3", "M08", "M30", "S1000", "F100", "P250"]),
    st.tuples(st.sampled_from("XYZABCxz"), _number).map("".join),
)
_word = st.one_of(_good_word, _good_word, _good_word, _any_word)
_block = st.lists(_word, max_size=6).map(" ".join)
_words_text = st.tuples(
    st.sampled_from(["", "G00 X0 Y0 Z0 A0 B0 C0\n", "G01 X0 F100\n"]),
    st.lists(_block, max_size=12).map("\n".join),
).map("".join)


def _parse_only_nc_errors(text: str, integer_input: str) -> None:
    try:
        program = parse_program(text, "fuzz.nc", integer_input=integer_input)
    except NCProgramError as error:
        assert error.line is not None
        assert 1 <= error.line <= text.count("\n") + 1
        # the line, and the block's N word when it has one: 'line 1,' or 'line 1 (N0),'
        assert re.search(rf"line {error.line}( \(N[0-9]+\))?,", str(error))
        return
    try:
        written = format_program(program)
    except NCProgramError:
        return
    parse_program(written)


@settings(max_examples=300, deadline=None)
@given(st.text(NC_CHARACTERS, max_size=200), st.sampled_from(["calculator", "increment"]))
def test_fuzz_nc_characters_raise_only_nc_errors(text, integer_input):
    _parse_only_nc_errors(text, integer_input)


@settings(max_examples=300, deadline=None)
@given(_words_text, st.sampled_from(["calculator", "increment"]))
def test_fuzz_word_sequences_raise_only_nc_errors(text, integer_input):
    _parse_only_nc_errors(text, integer_input)


def test_blanks_between_a_sign_and_its_digits_are_not_read_but_inside_the_digits_refused():
    # blanks in a block are not read: 'Z - 0.1' is Z-0.1, as 'X 1.' is X1.
    spaced = parse_program("G01 Z - 0.1 F100\nX + 2.5\nY -\t.25\n", "a.nc")
    plain = parse_program("G01 Z-0.1 F100\nX+2.5\nY-.25\n", "b.nc")
    np.testing.assert_array_equal(spaced.targets, plain.targets)
    assert spaced.targets[-1, :3].tolist() == [2.5e-3, -0.25e-3, -0.1e-3]
    # a blank inside the digits would make two numbers of one (X1 0. is not X10.)
    with pytest.raises(NCProgramError, match="without an address letter") as error:
        parse_program("G01 X1 0. F100\n", "c.nc")
    assert error.value.line == 1


@pytest.mark.parametrize(("build", "message"), [
    (lambda b: b.rapid(X="0.001"), r"axis X must be a real number, got '0.001'"),
    (lambda b: b.rapid(X=True), r"axis X must be a real number, got True"),
    (lambda b: b.rapid(Z=np.bool_(True)), r"axis Z must be a real number, got "),
    (lambda b: b.linear(X=1e-3, feed_m_per_s="0.1"), r"feed must be a real number, got '0.1'"),
    (lambda b: b.linear(X=1e-3, feed_mm_per_min="100"),
     r"feed must be a real number, got '100'"),
    (lambda b: b.dwell("2"), r"dwell time must be a real number, got '2'"),
    (lambda b: b.spindle("1000").rapid(X=0.0), r"spindle speed must be a real number, got "
                                               r"'1000'"),
])
def test_the_builder_takes_numbers_not_text_or_flags(build, message):
    # ProgramBuilder().rapid(X="0.001") built X = 1 mm from the text and X=True X = 1 m;
    # a dwell("2"), spindle("1000") and feed_m_per_s="0.1" were converted alike, where
    # every instrument refuses a number spelt as text (docs/metrology.md)
    with pytest.raises(NCProgramError, match=message):
        build(ProgramBuilder(1)).build()
    exact = ProgramBuilder(1).rapid(X=np.float64(1e-3), Y=2).dwell(np.int64(2)).build()
    assert exact.targets[0, :2].tolist() == [1e-3, 2.0] and exact.dwells[1] == 2.0


def test_a_refusal_names_the_blocks_n_word_beside_its_line():
    # an error names the file's line (an editor's) and, where the block has an N word, that
    # block number (the control's): 'line 4 (N20)'; a block without one reads as before
    text = "%\nO1000\nN10 G21 G90\nN0020 G01 X1. F100. G99.3\nG01 X2. G99.4\nM30\n%\n"
    with pytest.raises(NCProgramError) as info:
        parse_program(text, "p.nc")
    error = info.value
    assert (error.line, error.block) == (4, 20)
    assert str(error).startswith("p.nc, line 4 (N20), column 21, key 'G99.3': 2 problems in "
                                 "the program (the first at line 4 (N20); ")
    assert [str(e).split(": ")[0] for e in error.problems] == [
        "p.nc, line 4 (N20), column 21, key 'G99.3'", "p.nc, line 5, column 9, key 'G99.4'"]
    # a malformed word of the lexer's, and one refused by a single block
    for bad, where in (("N30 G01 X", "p.nc, line 3 (N30), column 9, key 'X'"),
                       ("G01 X", "p.nc, line 3, column 5, key 'X'")):
        with pytest.raises(NCProgramError) as info:
            parse_program(f"%\nG21\n{bad}\nM30\n%\n", "p.nc")
        assert str(info.value).startswith(where + ": malformed number ''"), str(info.value)
