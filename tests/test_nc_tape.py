"""What a FANUC control reads of a file and how: the closing %, ISO ':' program numbers,
G04 X without a decimal point per increment system, a tool length change without Z."""

from __future__ import annotations

import pytest

from machinesim._program_options import after_end_note
from machinesim.exceptions import NCProgramError
from machinesim.nc import parse_program

TOOLS = {"tool": {"1": {"length_mm": 10.0}}}


@pytest.mark.parametrize("text, after", [
    # opened by %: the next % ends it, and the program after it is not read
    ("%\nG90 G21\nG01 X1. F100.\n%\n\nG01 X5. F100.\n%\n", 6),
    # not opened by %: the first % ends it
    ("G90 G21\nG01 X1. F100.\n%\nX5.\n", 4),
    # only white space after it: nothing to say
    ("%\nG90 G21\nG01 X1. F100.\n%\n  \n\n", None),
])
def test_reading_stops_at_the_percent_that_ends_the_program(text, after):
    program = parse_program(text)
    assert len(program) == 1 and program.targets[0, 0] == pytest.approx(1e-3)
    assert program.after_end == after
    note = after_end_note(program)
    assert (note is None) == (after is None)
    if after is not None:
        assert f"line {after}" in note and "not read" in note


@pytest.mark.parametrize("text, moves, after", [
    # a second program after the first's closing % (had been refused as an M30 in a
    # subprogram), and a block after it (had been refused as a block after M02)
    ("%\nO1000\nG00 X0\nM30\n%\n%\nO2000\nG00 X1.\nM30\n%", 1, 6),
    ("G00 X0 M02 (end)\n%\nN5", 1, 3),
    # CRLF line ends: the % line keeps its whole line end
    ("%\r\nG90 G21\r\nG01 X1. F100.\r\n%\r\nX5.\r\n", 1, 5),
])
def test_what_follows_the_closing_percent_is_not_read(text, moves, after):
    program = parse_program(text)
    assert len(program) == moves and program.targets[-1, 0] < 2e-3
    assert program.after_end == after


BODY = ("O1234\nG90 G21 G17\nG00 X0 Y0 Z1.\nG01 Z-0.1 F100.\nG02 X2. Y0 I1. J0\n"
        "G00 Z1.\nM30\n%\n")


@pytest.mark.parametrize("leader", [
    "% TITLE", "%O1234 (PART)", "%   lens mould, rev B: 50% feed ;", "%\tG01 X99. #1=2 /",
])
@pytest.mark.parametrize("eol", ["\n", "\r\n"])
def test_the_leader_section_after_the_opening_percent_is_not_read(leader, eol):
    # B-64014EN/03, 2.5: from the opening % to the first end of block is the leader section,
    # which a FANUC ignores; it had been refused as words beside the %
    program = parse_program((leader + "\n" + BODY).replace("\n", eol), "titled.nc")
    plain = parse_program(("%\n" + BODY).replace("\n", eol), "titled.nc")
    assert program == plain
    assert program.lines.tolist() == plain.lines.tolist()
    assert program.lines[0] == 4 and program.lines[-1] == 7
    assert program.number == 1234
    assert program.targets[1, 2] == pytest.approx(-1e-4, abs=1e-15)
    assert program.targets[-2, 0] == pytest.approx(2e-3, abs=1e-15)


def test_after_a_leader_section_problems_keep_their_line_and_column():
    with pytest.raises(NCProgramError) as error:
        parse_program("\n%O1 (TITLE)\nG90 G21\nG00 X0 Q#5\n%\n", "titled.nc")
    assert (error.value.line, error.value.column) == (4, 8)
    # only the opening % has a leader: the text beside a later % is still refused
    with pytest.raises(NCProgramError, match="must stand alone") as error:
        parse_program("G90 G21\nG00 X0\n% G00\n")
    assert (error.value.line, error.value.column) == (3, 3)
    # so does a ';': a program written on the % line after one is refused, not dropped
    with pytest.raises(NCProgramError, match="would be lost") as error:
        parse_program("% TITLE;G21 G90;G00 X1.;M30;")
    assert (error.value.line, error.value.column, error.value.key) == (1, 9, "G21")
    assert parse_program("% LENS MOULD; REV B\nG00 X1.\n%\n").targets[0, 0] == 1e-3
    # a lone CR ends the leader too, and is refused, not taken as part of the title
    with pytest.raises(NCProgramError, match="carriage return") as error:
        parse_program("% TITLE\rG90 G21\rG00 X1.\r%")
    assert (error.value.line, error.value.column) == (1, 8)


def test_an_iso_colon_program_number_reads_as_an_o_number():
    program = parse_program(":1234\nG90 G21\nM98 P2000\nM30\n:2000\nG01 X1. F100.\nM99\n")
    assert program.number == 1234
    assert len(program) == 1 and program.targets[0, 0] == pytest.approx(1e-3)
    assert program == parse_program(
        "O1234\nG90 G21\nM98 P2000\nM30\nO2000\nG01 X1. F100.\nM99\n")


def test_an_iso_colon_number_in_the_program_is_named_as_written():
    # NX's sample FANUC output numbers its tool change block ':0030'; the refusal had named
    # a key 'O0030', which the file does not hold
    text = "%\nN0010 G40 G17 G90 G21\nN0020 G91 G28 Z0.0\n:0030 T00 M06\nN0040 G0 G90 X1.\nM02\n%\n"
    with pytest.raises(NCProgramError) as error:
        parse_program(text, "nx.nc")
    assert (error.value.line, error.value.column, error.value.key) == (4, 1, ":0030")
    assert str(error.value).startswith(
        "nx.nc, line 4, column 1, key ':0030': ':0030' is a program number (':' is the "
        "ISO-code address of O: O0030): the O number must be the first block")
    assert str(error.value).endswith("write N0030")


@pytest.mark.parametrize("text, key, fix", [
    (":O1001", ":O1001", "write ':1001' or 'O1001', not both"),
    (": o 12 (PART)", ": o 12", "write ':12' or 'O12', not both"),
    (":G01", ":G01", "write the program number's digits after it"),
])
def test_an_iso_colon_before_a_letter_is_refused_naming_the_colon(text, key, fix):
    # ':O1001' (':' and O, the same address twice) had been "malformed number '' after
    # 'O'" at column 1, where the file holds a ':' and no empty O
    with pytest.raises(NCProgramError) as error:
        parse_program(f"{text}\nG90 G21\nM30\n")
    assert (error.value.line, error.value.column, error.value.key) == (1, 1, key)
    assert str(error.value).endswith(
        "':' is the ISO-code address of a program number, as O is, and takes its digits "
        f"(':1001' reads as O1001); found {key!r}: {fix}")


@pytest.mark.parametrize("rule, seconds", [
    ("calculator", 10.0),  # X10 is 10 s
    ("increment", 0.010),  # milliseconds, as before
    ("is-b", 0.010),  # 10 x 0.001 s
    ("is-c", 0.001),  # 10 x 0.0001 s: not 10 ms
])
def test_g04_x_without_a_point_counts_the_increment_systems_time_unit(rule, seconds):
    program = parse_program("G90 G21\nG04 X10\nG04 X10.\nG04 P10\n", integer_input=rule)
    assert program.dwells.tolist() == pytest.approx([seconds, 10.0, 0.010], rel=1e-15)


def test_a_move_without_z_after_a_length_change_without_z_is_refused():
    text = "G90 G21\nG00 Z50.\nG43 H1\nG00 X10. Y5.\nZ2.\nM30\n"
    with pytest.raises(NCProgramError) as error:
        parse_program(text, tools=TOOLS)
    message = str(error.value)
    assert "line 4" in message and "X10." in message and "G43 H1 at line 3" in message
    assert "+10 mm" in message and "10 mm higher" in message and "5006#6" in message
    # with Z in the block of the change, it moves there: XY at 50 mm + 10 mm of tool
    program = parse_program(text.replace("G43 H1\n", "G43 H1 Z50.\n"), tools=TOOLS)
    assert program.targets[2, 2] == pytest.approx(0.060)
    # before Z is known there is no height to be off: read as before
    assert len(parse_program("G90 G21\nG43 H1\nG00 X10. Y5.\nZ2.\nM30\n", tools=TOOLS)) == 2


@pytest.mark.parametrize("text, end, at", [
    # the subprogram after the main program's closing % (had been 'not in this file')
    ("O0001\nG90 G21\nM98 P1000\nM30\n%\nO1000\nG0 X1.\nM99\n%\n", 5, 6),
    # each program between its own pair of %: the second pair is not read either
    ("%\nO0001\nG90 G21\nM98 P1000\nM30\n%\n%\n:1000\nG0 X1.\nM99\n%\n", 6, 8),
])
def test_a_subprogram_after_the_closing_percent_is_named_there(text, end, at):
    with pytest.raises(NCProgramError) as caught:
        parse_program(text, "two.nc")
    message = str(caught.value)
    assert caught.value.line == (4 if text.startswith("%") else 3)
    assert f"O1000, which is at line {at}, after the '%' on line {end}" in message
    assert "not in this file" not in message
    # with the % between them removed both programs are read, and the call runs O1000
    lines = text.splitlines()
    joined = "\n".join(lines[:end - 1] + [x for x in lines[end - 1:-1] if x != "%"] + ["%"])
    program = parse_program(joined, "one.nc")
    assert len(program) == 1 and program.targets[0, 0] == pytest.approx(1e-3)
