"""The FANUC dialect's input (issue 12): integer input, a program's arrays and move views,
pickling and copying, the units it selects, F under G20 with rotary axes, files that are
not UTF-8 text or hold control bytes, and lines of huge or many words. Expected values
worked out by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from machinesim.exceptions import MachineSimError, NCProgramError
from machinesim.motion import move_duration
from machinesim.nc import (
    AXES,
    KIND_DWELL,
    KIND_LINEAR,
    KIND_RAPID,
    Move,
    Program,
    ToolTable,
    parse_program,
    read_program,
)

MM = 1e-3


def test_integer_input_is_reported_and_reads_lengths_and_angles():
    text = "G00 X10 Y0 A5 Z1.\nG03 X0 Y10000 I-10 J0 F1\n"
    calc = parse_program("G00 X10 Y0 A5 Z1.")
    assert calc.integer_input == "calculator"
    assert calc.targets[0, [0, 3]].tolist() == pytest.approx([10 * MM, math.radians(5)])
    inc = parse_program("G00 X10 Y0 A5 Z1.", integer_input="increment")
    assert inc.integer_input == "increment"
    assert inc.targets[0, [0, 2, 3]].tolist() == pytest.approx(
        [10e-9, 1 * MM, math.radians(5e-5)], abs=1e-20)
    with pytest.raises(NCProgramError, match="end point is off the arc"):
        parse_program(text, integer_input="increment")  # I-10 is 10 nm, the end 10 um away


def test_program_arrays_and_move_views_agree():
    program = parse_program("G00 X1. Z2. S100 M03\nG01 Y3. F60\nG04 P500\nM08\nM30")
    assert program.targets.shape == (4, 6)
    assert np.isnan(program.targets[0, 1])  # Y not given yet
    assert program.kinds.tolist() == [KIND_RAPID, KIND_LINEAR, KIND_DWELL, KIND_DWELL]
    assert program.m_codes == {0: (3,), 3: (8,)}
    assert not program.targets.flags.writeable
    rebuilt = Program(tuple(program.moves), program.number, program.source,
                      program.work_offsets, states=program.states,
                      integer_input=program.integer_input)
    assert rebuilt == program
    arrays = Program.from_arrays(program.targets, program.kinds, program.feeds,
                                 program.dwells, program.lines, spindles=program.spindles,
                                 block_numbers=program.block_numbers, m_codes=program.m_codes,
                                 source=program.source, integer_input="calculator")
    assert arrays == program
    assert list(arrays.moves) == list(program.moves)
    assert program.moves[1] == Move("linear", {"X": 1e-3, "Y": 3e-3, "Z": 2e-3}, 1e-3,
                                    line=2, spindle_rpm=100.0)
    with pytest.raises(NCProgramError, match="drops axis Y"):
        Program.from_arrays([[0.0, 0.0] + [np.nan] * 4, [0.0] + [np.nan] * 5], [0, 0])
    with pytest.raises(NCProgramError, match="a subprogram call or return"):
        Program.from_arrays([[0.0] + [np.nan] * 5], [0], m_codes={0: (99,)})


def test_programs_pickle_and_copy():
    import copy
    import pickle

    program = parse_program("G00 X1. C5.\nG01 Y2. F10 M08\nG05.1 Q1", work_offsets={
        "G54": {"X": 1e-3}})
    for back in (pickle.loads(pickle.dumps(program)), copy.deepcopy(program)):
        assert back == program
        assert not back.targets.flags.writeable
        assert back.moves[1] == program.moves[1]
    # the tool changes and the arcs read come back too: a copy cuts with the same tools
    tools = ToolTable.from_dict({"tool": {"2": {"length_mm": 2.5, "shape": "ball:0.5"}}})
    changed = parse_program("G00 X0 Y0\nT2 M06\nG01 X1. F10\nG02 X3. R1.\nG03 X1. R1.\n",
                            tools=tools)
    assert changed.arc_blocks == 2 and changed.tool_changes[0].length_m == 2.5e-3
    for back in (pickle.loads(pickle.dumps(changed)), copy.deepcopy(changed)):
        assert back.tool_changes == changed.tool_changes and back.arc_blocks == 2


def test_the_units_a_program_selects_are_kept_with_their_first_lines():
    import pickle

    # before the first motion (a switch after it is refused: the test above)
    both = parse_program("G90\nG21\nG20\nG20 G0 X1.\nG20 X3.\n")
    assert dict(both.unit_words) == {"G21": 2, "G20": 3}
    assert both.targets[:, 0].tolist() == pytest.approx([25.4e-3, 76.2e-3], rel=1e-15)
    assert dict(parse_program("G0 X1.\nX2.\n").unit_words) == {}  # read in mm
    back = pickle.loads(pickle.dumps(both))
    assert back == both and dict(back.unit_words) == {"G21": 2, "G20": 3}
    # the same moves with and without G21 are different texts of one part
    assert parse_program("G21\nG0 X1.\n") != parse_program("\nG0 X1.\n")


def test_read_program_file_errors_name_the_path(tmp_path):
    for path, message in [(tmp_path / "missing.nc", "no such file"),
                          (tmp_path, "is a folder")]:
        with pytest.raises(MachineSimError, match=message) as info:
            read_program(path)
        assert str(path) in str(info.value)


def _feed_minutes(program: Program) -> list[float]:
    """Each feed move's time by the planner's rule (`move_duration`, no axis limit), min."""
    rotary = np.array([a in "ABC" for a in AXES])
    targets = np.nan_to_num(program.targets)  # every axis is set before the first feed
    return [move_duration("linear", targets[i - 1], targets[i], rotary,
                          np.full(len(AXES), 1e9), program.feeds[i], 0.0) / 60.0
            for i in np.flatnonzero(program.kinds == KIND_LINEAR)]


def test_under_g20_a_rotary_axis_degrees_count_as_inches_in_the_feed():
    # FANUC: F of a move of linear and rotary axes is along the path, degrees counted in the
    # unit of F (B-63174EN/03 4.2: G91 G01 X20. C40. F300. takes sqrt(20^2 + 40^2) / 300
    # min); a rotary-only move is fed in deg/min. Under G20 every F had been converted by
    # inch, so a degree counted as a mm of an F 25.4 times larger: X1. A10. F10. took
    # sqrt(25.4^2 + 10^2) / 254 min (6.45 s) and A90. F10. 21.26 s, where by hand they take
    # sqrt(1 + 10^2) / 10 min and 9 min
    head = "G00 X0 Y0 Z0 A0 B0\n"
    blocks = "G01 X1. A10. F10.\nA100.\nX3. Y1. B20. F5.\nG02 X4. Y1. I0.5 A190. F10.\nG01 X5.\n"
    inch = parse_program("G20 " + head + blocks, chord_tolerance=1e-9)
    arc = math.hypot(math.pi * 0.5, 90.0) / 10.0  # a half circle of 0.5 in with A 90 deg
    expected = [math.sqrt(101) / 10, 9.0, math.sqrt(4 + 1 + 400) / 5, arc, 0.1]
    minutes = _feed_minutes(inch)
    lines = inch.lines[inch.kinds == KIND_LINEAR]
    by_line = [sum(m for m, n in zip(minutes, lines, strict=True) if n == line)
               for line in range(2, 7)]
    assert by_line == pytest.approx(expected, rel=1e-9)
    # the same numbers in mm under G21 take the same minutes (a degree counts as a mm)
    metric = parse_program("G21 " + head + blocks, chord_tolerance=1e-9)
    assert _feed_minutes(metric)[:3] == pytest.approx(expected[:3], rel=1e-12)
    # a move without rotary motion keeps F converted by inch, to the bit
    assert inch.feeds[-1] == 10.0 * 25.4e-3 / 60.0
    # the vectorised path (runs of 16 plain lines and more) keeps the same feeds
    run = "G20 G00 X0 Y0 Z0 A0\nG01 F10.\n" + "".join(
        f"X{k * 0.5:.1f} A{k * 3}.\n" for k in range(1, 21))
    fast, slow = parse_program(run), parse_program(run, fast=False)
    assert np.array_equal(fast.feeds, slow.feeds, equal_nan=True) and fast == slow
    assert _feed_minutes(fast) == pytest.approx([math.sqrt(0.25 + 9) / 10] * 20, rel=1e-12)
    # from where A has no position yet the distance is not known: refused, naming A
    for text in ("G20 G00 X0 Y0 Z0\nG01 X1. A10. F10.\n",
                 "G20 G00 X0 Y0 Z0\nG02 X1. Y0 I0.5 A10. F10.\n"):
        with pytest.raises(NCProgramError) as info:
            parse_program(text)
        assert (info.value.line, info.value.key) == (2, "A10.")
        assert "its degrees count as inches in the feed" in str(info.value)


@pytest.mark.parametrize("words, key, message", [
    ("I0.5", "I0.5", "G83's variable peck takes I (first peck), J (reduction per peck) and K "
     "(smallest peck) together (Haas); J and K missing"),
    ("J0.1 K0.2", "J0.1", "I missing"),
    ("I0.5 J0 K0.2", "J0", "G83's J must be > 0 (a length: Haas's I J K are always "
     "positive), got J0"),
    ("I-0.5 J0.1 K0.2", "I-0.5", "G83's I must be > 0"),
    ("I0.1 J0.1 K0.5", "K0.5", "G83's smallest peck K (K0.5) is larger than its first peck I "
     "(I0.1); expected K <= I"),
    ("I0.5 J0.1 K0.2 Q0.1", "Q0.1", "G83 takes a peck Q or I J K (Haas's variable peck), "
     "not both"),
])
def test_a_haas_variable_peck_is_checked(words, key, message):
    with pytest.raises(NCProgramError) as info:
        parse_program(f"G00 X0 Y0 Z5.\nG83 X1. Y1. Z-1. R1. {words} F100.\n")
    assert (info.value.line, info.value.key) == (2, key)
    assert message in str(info.value)
    # I and J stay refused with G81 and G82, which have no pecks
    with pytest.raises(NCProgramError, match="word I is only read with"):
        parse_program("G00 X0 Y0 Z5.\nG81 X1. Y1. Z-1. R1. I0.5 F100.\n")


def test_a_control_byte_in_a_program_is_named_escaped_never_raw(tmp_path):
    path = tmp_path / "esc.nc"
    path.write_bytes(b"G00 X1. Y1. Z1.\nG00 X1.\x1b[31m Y5.\n")
    with pytest.raises(NCProgramError) as info:
        read_program(path)
    assert "\x1b" not in str(info.value) and "key '\\x1b'" in str(info.value)


def test_one_line_of_repeated_words_is_one_problem_read_to_its_cap():
    # 2 million 'X1.' on one line (8 MB) made 1,999,999 problems, 2.4 GB and 23 s for one
    # mistake; reading then kept MAX_PROBLEMS (10,000), but still read every word of the
    # line and built a problem for each (one million: 65 s; a 48 MB line of 'G01 X1.': 256 s
    # and 3.6 GB). A line is now read for MAX_LINE_ITEMS words and problems: beyond them it
    # is one problem at the first character not read, and the line's words are not run
    from machinesim.nc.lexer import MAX_LINE_ITEMS

    line = "G01 F100. " + "X1. " * 30_000
    with pytest.raises(NCProgramError) as info:
        parse_program("G00 X0. Y0. Z1.\n" + line + "\n", "long.nc")
    assert MAX_LINE_ITEMS == 10_000 and info.value.problems == (info.value,)
    # G01 and F100. are two words, so the cap falls on the 9,999th 'X1.' (0-based 9,998),
    # which starts at column 11 + 4 x 9,998
    assert info.value.line == 2 and info.value.column == 11 + 4 * 9_998 == 40_003
    assert info.value.key == "X1. X1. X1. X1. X1. "
    assert f"({len(line) - 40_002} characters not read)" in str(info.value)
    # 20,000 M codes in one block had been read as one block passing them all through
    with pytest.raises(NCProgramError, match="more than 10000 words and problems"):
        parse_program("G00 X0. Y0. Z1.\n" + "M08 " * 20_000 + "\nM30\n", "long.nc")


def test_a_line_of_as_many_words_as_the_cap_and_a_comment_is_read_whole():
    # 501e290's cap was checked before a comment was: 10,000 words (not more) and a
    # '(comment)' or ';comment' were refused as "more than 10000 words and problems" at
    # the comment; a comment adds no word, so only a word or problem beyond the cap stops it
    from machinesim.nc.lexer import MAX_LINE_ITEMS, tokenize

    line = "X1. " * MAX_LINE_ITEMS
    for tail in ("(end)", ";end", "(a) (b)", ""):
        words, problems = tokenize(line + tail, "long.nc", 1)
        assert (len(words), problems) == (MAX_LINE_ITEMS, []), tail
    words, problems = tokenize(line + "(end) Y2.", "long.nc", 1)
    assert len(words) == MAX_LINE_ITEMS and len(problems) == 1
    assert problems[0].column == 4 * MAX_LINE_ITEMS + 7 and problems[0].key == "Y2."
    assert "more than 10000 words and problems" in problems[0].message


def test_a_latin1_byte_outside_comments_is_named_as_not_utf8(tmp_path):
    # a no-break space saved as Latin-1 (0xA0) between two words: it had been called an
    # "unexpected character '\ufffd'", the replacement the reader decoded it to
    path = tmp_path / "latin1.nc"
    path.write_bytes(b"G00 X1.\xa0Y1. Z1.\n" + b"G01 X2. Y1. Z0. F100.\n" * 10)
    with pytest.raises(NCProgramError, match="a byte that is not UTF-8") as info:
        read_program(path)
    assert (info.value.line, info.value.column) == (1, 8)


@pytest.mark.parametrize("end", [b"", b"\x1a"])
def test_a_short_program_with_a_latin1_comment_reads_as_without_it(tmp_path, end):
    # 4 Latin-1 bytes in 70 (5.7 %) had refused the file whole as 'not a text file'; a
    # comment's bytes are read as in a longer file, and the moves are those of the program
    # without the comment (a DOS end-of-file mark after it is skipped, as elsewhere)
    program = "%\nO1000\nG90 G21\nG00 X0 Y0 Z1.\n{}G01 X1. F100.\nM30\n%\n"
    path = tmp_path / "latin1.nc"
    path.write_bytes(program.format("(Schruppen: \xe4\xf6\xfc \xb0C)\n").encode("latin-1") + end)
    plain = parse_program(program.format("(Schruppen)\n"))
    read = read_program(path)
    assert np.array_equal(read.targets, plain.targets, equal_nan=True)
    assert read.lines.tolist() == [4, 6]
    # outside a comment such a byte is refused where it stands, naming it
    path.write_bytes(b"G90 G21\nG01 X1. F100. \xb0\nM30\n")
    with pytest.raises(NCProgramError, match="a byte that is not UTF-8") as info:
        read_program(path)
    assert (info.value.line, info.value.column) == (2, 15)


def test_a_short_program_with_control_bytes_in_a_comment_reads_as_without_them(tmp_path):
    # a terminal colour code and a NUL in a comment (2 of 39 characters, 5.1 %) had refused
    # the file whole as 'not a text file'; a comment holds any character, and one outside a
    # comment is named where it stands
    path = tmp_path / "esc.nc"
    path.write_bytes(b"G21 G90 (\x1b[31mred\x00)\nG00 X1. Y0 Z1.\nM30\n")
    plain = parse_program("G21 G90 (red)\nG00 X1. Y0 Z1.\nM30\n")
    assert np.array_equal(read_program(path).targets, plain.targets, equal_nan=True)
    path.write_bytes(b"G21 G90\nG00 X1.\x1b Y0 Z1.\nM30\n")
    with pytest.raises(NCProgramError, match="unexpected character") as info:
        read_program(path)
    assert (info.value.line, info.value.column) == (2, 8)


@pytest.mark.parametrize("data", [b"\xff" * 5000, b"\xe4\xf6\n" * 2000, b"\x00" * 5000,
                                  b"G01 X1.\x00\x01\x02\x03\x04\x05\n" * 10])
def test_bytes_mostly_not_utf8_or_with_control_bytes_are_still_no_text(tmp_path, data):
    path = tmp_path / "prog.nc"
    path.write_bytes(data)
    with pytest.raises(NCProgramError, match="not a text file") as info:
        read_program(path)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("encoding", ["utf-32", "utf-32-le", "utf-32-be"])
def test_a_utf32_file_is_named_utf32(tmp_path, encoding):
    # with its byte-order mark it had been called UTF-16, without it 'not a text file'
    path = tmp_path / "prog.nc"
    path.write_bytes("%\nG90 G21\nG00 X1. Y1. Z1.\nM30\n%\n".encode(encoding))
    with pytest.raises(NCProgramError) as info:
        read_program(path)
    assert str(info.value) == (f"{path}: the file is UTF-32 text (a byte-order mark, or three "
                               "zero bytes beside each character); expected ASCII or UTF-8: "
                               "save it as UTF-8")


@pytest.mark.parametrize("data", [np.arange(200, dtype="<i4").tobytes(),
                                  np.arange(200, dtype=">i4").tobytes(), b"\x00" * 400])
def test_small_binary_integers_are_no_utf32(tmp_path, data):
    # three zero bytes of four, but the fourth no text: a binary, refused as such
    path = tmp_path / "prog.nc"
    path.write_bytes(data)
    with pytest.raises(NCProgramError, match="not a text file"):
        read_program(path)
