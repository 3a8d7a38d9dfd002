"""NC programs read against hand-computed SI values: a hand-written program, integer input
rules and FANUC's increment systems, dwells, files with CRLF or a lone CR, words and
comments after ';', and blanks between a sign and its digits."""

from __future__ import annotations

import math

import numpy as np
import pytest

from machinesim.exceptions import NCProgramError
from machinesim.nc import parse_program, read_program

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


@pytest.mark.parametrize(("line", "column", "word", "comment"), [
    ("; G61 exact path mode was requested", 3, "G61", "'(G61 exact path mode was requested)'"),
    ("  ;T3 Diameter: 0.70mm", 4, "T3", "'(T3 Diameter: 0.70mm)'"),
    (";G42", 2, "G42", "'(G42)'"),
    ("; T1 (6 mm) tool", 3, "T1", "e.g. '(T1 tool)'"),
])
def test_a_word_after_a_semicolon_that_starts_the_line_names_no_lost_block(
        line, column, word, comment):
    """A line starting with ';' (a drill post's '; T3 Diameter: 0.70mm', LinuxCNC's ';G42'
    left out) has no block before the ';' to lose: the refusal says that the line is a
    comment in LinuxCNC and grbl and a block on FANUC, and gives the comment in
    parentheses; it had said the block 'would be lost' and to put each block on its own
    line, which it already is."""
    with pytest.raises(NCProgramError) as info:
        parse_program(f"G90 G21\n{line}\nG00 X1.\n", "p.nc")
    error = info.value
    assert (error.line, error.column, error.key) == (2, column, word)
    assert f"word '{word}' after the ';' that starts the line" in str(error)
    assert "would be lost" not in str(error) and "on its own line" not in str(error)
    assert f"write the comment in parentheses ({comment})" in str(error)
    # written as the message says, the line is a comment: the program reads as without it
    if comment.startswith("'("):
        fixed = parse_program(f"G90 G21\n{comment[1:-1]}\nG00 X1.\n", "p.nc")
        assert fixed == parse_program("G90 G21\n\nG00 X1.\n", "p.nc")


@pytest.mark.parametrize("comment", [
    "; move to x1", ";", ";  ;; ", "; N.B. slow here", "; 3 passes", "; E5 is no word here",
    "; (T1) tool", "; G-code from CAM", "(a; X1.) ; cut",
])
def test_comment_after_semicolon_reads_as_without_it(comment):
    bare = "G90 G21\nG00 X-1. Y2. Z0.1\nG01 Z-0.02 F100.\nX11.\nG00 Z1.\nM30\n"
    lines = bare.split("\n")
    lines[3] = f"X11. {comment}"
    assert parse_program("\n".join(lines), "p.nc") == parse_program(bare, "p.nc")


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
