"""The FANUC dialect's subprograms (issue 12): M98/M99 with repeats and nesting, a packed P
of 5 to 8 digits, programs numbered above 9999, depth and recursion, layout refusals, and
G20/G21 switched in a subprogram or after a motion. Expected values worked out by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from machinesim.exceptions import NCProgramError
from machinesim.nc import parse_program

MM = 1e-3
#: Targets are a decimal in mm times 1e-3 (plus offsets): float64 round-off is far below this,
#: and it is 10^6 x below 1 nm, so any misreading fails.
EXACT_M = 1e-15


SUBPROGRAMS = """O100
G00 X0 Y0 Z0
M98 P200 L3
M98 P20300
M30
O200
G91 G01 X1. F10
G90
M99
O300
M98 P200
G00 Y1.
M99
"""


def test_subprograms_with_repeats_and_nesting():
    program = parse_program(SUBPROGRAMS)
    assert program.number == 100
    # O200 three times, then O300 twice (each O200 once and a move)
    assert program.targets[:, 0].tolist() == pytest.approx(
        [0, 1 * MM, 2 * MM, 3 * MM, 4 * MM, 4 * MM, 5 * MM, 5 * MM])
    assert program.lines.tolist() == [2, 7, 7, 7, 7, 12, 7, 12]


#: O0100 steps X by 1 mm at line 6 and Y by 2 mm at line 7: each run of it adds 1 to X.
PACKED_CALL = "O1\nG00 X0 Y0\nM98 P{p}\nM30\nO100\nG91 G00 X1.\nG01 Y2. F100.\nG90\nM99\n"


def test_a_p_of_5_to_8_digits_is_repeats_then_program_number():
    # P30100: O0100 three times (FANUC's P<repeats><4-digit program number>)
    program = parse_program(PACKED_CALL.format(p="30100"))
    assert program.lines.tolist() == [2] + [6, 7] * 3
    assert program.targets[:, 0].tolist() == pytest.approx(
        [0, 1 * MM, 1 * MM, 2 * MM, 2 * MM, 3 * MM, 3 * MM], abs=EXACT_M)
    assert program.targets[-1, 1] == pytest.approx(6 * MM, abs=EXACT_M)
    # 8 digits: 12 repeats (leading zeros) of O0100; P100 alone: once
    assert len(parse_program(PACKED_CALL.format(p="00120100"))) == 1 + 2 * 12
    assert len(parse_program(PACKED_CALL.format(p="100"))) == 1 + 2


# (P and L words, column and key of the word at fault, message): each points at the word
# it is about, P (column 5, after "M98 ") or L (after "M98 P30100 ": column 12), as other
# problems do; they had all pointed at M98, column 1
@pytest.mark.parametrize(("p", "column", "key", "message"), [
    # 9 digits had been read as 12345 repeats of O6789
    ("123450100", 5, "P123450100",
     "M98 P123450100 has 9 digits; FANUC's P takes at most 8: a repeat count of up to 4 "
     "digits, then the 4-digit program number (M98 P30100: O0100 three times)"),
    # 10 digits had been 'M98 needs P<program number> (an unsigned integer)'
    ("1234560100", 5, "P1234560100",
     "M98 P1234560100 has 10 digits; FANUC's P takes at most 8: a repeat count of up to 4 "
     "digits, then the 4-digit program number (M98 P30100: O0100 three times)"),
    # L beside a P that holds its repeats had called O30100 (not in the file) twice
    ("30100 L2", 12, "L2",
     "M98 P30100 L2: a P of more than 4 digits holds its own repeat count (3 x O0100), so L "
     "cannot be given beside it; write M98 P100 L2 or M98 P20100"),
    ("12340100 L2", 15, "L2",
     "M98 P12340100 L2: a P of more than 4 digits holds its own repeat count (1234 x O0100), "
     "so L cannot be given beside it; write M98 P100 L2 or M98 P20100"),
])
def test_a_p_of_more_than_8_digits_or_with_l_beside_its_repeats_is_refused(p, column, key,
                                                                          message):
    with pytest.raises(NCProgramError) as info:
        parse_program(PACKED_CALL.format(p=p), "prog.nc")
    assert str(info.value) == f"prog.nc, line 3, column {column}, key '{key}': {message}"


#: O12345 (line 8) is above the 4-digit program numbers M98 P calls; O2345 (line 5) is the
#: number a packed P12345 reads as (1 x O2345). {call} is line 3.
HIGH_NUMBER = "O1\nG00 X0 Y0\n{call}\nM30\nO2345\nG00 X1.\nM99\nO12345\nG00 X5.\nM99\n"


def test_a_subprogram_numbered_above_9999_is_read_when_never_called():
    # A definition alone changes nothing that runs (a control with 5-digit program numbers,
    # as Haas's, holds it): the program reads as the same one without O12345.
    program = parse_program(HIGH_NUMBER.format(call="G00 X2."), "prog.nc")
    assert program.targets[:, 0].tolist() == [0.0, 2 * MM]
    without = "O1\nG00 X0 Y0\nG00 X2.\nM30\nO2345\nG00 X1.\nM99\n"
    assert program == parse_program(without, "prog.nc")


@pytest.mark.parametrize(("call", "key", "reading"), [
    # had silently run O2345 (X1.), not the O12345 (X5.) its author meant
    ("M98 P12345", "M98 P12345", " (P12345: 1 x O2345)"),
    ("M98 P00012345", "M98 P00012345", " (P00012345: 1 x O2345)"),
    # had said to write M98 P2345 L2: a call of the wrong program
    ("M98 P12345 L2", "M98 P12345 L2", ""),
])
def test_a_call_of_a_subprogram_numbered_above_9999_is_refused_at_its_p(call, key, reading):
    with pytest.raises(NCProgramError) as info:
        parse_program(HIGH_NUMBER.format(call=call), "prog.nc")
    p = key.split()[1]
    assert str(info.value) == (
        f"prog.nc, line 3, column 5, key '{p}': {key}: O12345, defined on line 8, cannot be "
        "called: M98 calls programs O1..O9999 (Series 0i-MC Operator's Manual B-64124EN/01, "
        "12.3), a P of 5 to 8 digits being a repeat count then the 4-digit program "
        f"number{reading}; a control with longer program numbers (Haas: 5 digits) reads it "
        "as O12345. Renumber O12345 to at most 4 digits and call it so")


def test_a_packed_p_calling_a_missing_program_says_how_it_was_read():
    # O12345 in another file, say: the message had named only O2345, whose digits the
    # user never wrote as a program number
    with pytest.raises(NCProgramError) as info:
        parse_program("O1\nM98 P12345\nM30\n", "prog.nc")
    assert str(info.value) == (
        "prog.nc, line 2, column 5, key 'P12345': M98 P12345 calls O2345 (1 x: FANUC's "
        "P<repeats><4-digit program number>), which is not in this file (subprograms: none)")


def test_subprogram_depth_and_recursion_are_refused_before_running():
    chain = "O1\nM98 P2\nM30\n" + "".join(f"O{k}\nM98 P{k + 1}\nM99\n" for k in range(2, 13))
    chain += "O13\nG00 X0\nM99\n"
    with pytest.raises(NCProgramError, match="nests deeper than 10 levels") as info:
        parse_program(chain)
    # 11 levels end: too deep, not endless (it had said 'the program would never end')
    assert str(info.value).endswith(
        "-> O0011 -> O0012); FANUC controls nest 4 to 10 levels; call the deepest ones from a "
        "shallower level")
    assert (info.value.line, info.value.key) == (32, "P12")
    # 10 levels read, and run the deepest one's move once
    ten = chain.replace("O11\nM98 P12\n", "O11\nG00 X1.\n")
    assert np.asarray(parse_program(ten).targets)[:, 0].tolist() == [0.001]
    mutual = "O1\nM98 P2\nM30\nO2\nM98 P3\nM99\nO3\nM98 P2\nM99\n"
    with pytest.raises(NCProgramError, match=r"calls itself \(main -> O0002 -> O0003 -> O0002"):
        parse_program(mutual)
    runaway = "O1\nM98 P2 L99999999\nM30\nO2\nM98 P3 L9999\nM99\nO3\nG04 P0\nM99\n"
    with pytest.raises(NCProgramError, match="more than 50000000 blocks"):
        parse_program(runaway)


#: O0100 selects {code}, then moves X by 1 unit; the main program moves X by 1 after M99.
UNITS_CALL = ("O1\n{main}G90 G00 X0 Y0\nM98 P100\nG01 X2. F100.\nM30\n"
              "O100\n{code}\nG91 G01 X1. F10.\nG90\nM99\n")


@pytest.mark.parametrize(("main", "code", "was", "now"), [
    ("G21\n", "G20", "mm", "inch"),
    ("", "G20", "mm", "inch"),  # no units selected: mm, the reader's default
    ("G20\n", "G21", "inch", "mm"),
])
def test_a_subprogram_switching_g20_g21_is_refused_naming_its_line(main, code, was, now):
    # the switch had been taken: the main program's X2. after the M99 read as 2 inch
    # (50.8 mm), in the subprogram's units; FANUC forbids switching within a program
    text = UNITS_CALL.format(main=main, code=code)
    line = text.splitlines().index(code) + 1
    with pytest.raises(NCProgramError) as info:
        parse_program(text, "prog.nc")
    assert str(info.value) == (
        f"prog.nc, line {line}, column 1, key '{code}': {code} in a subprogram switches the "
        f"units from {was} to {now}: FANUC forbids switching G20/G21 within a program, and "
        f"the blocks after the M99 would be read in {now}; select the units once, at the "
        "head of the main program")


@pytest.mark.parametrize(("main", "code", "unit"), [("G21\n", "G21", MM), ("", "G21", MM),
                                                    ("G20\n", "G20", 25.4 * MM)])
def test_a_subprogram_restating_the_units_in_force_is_read(main, code, unit):
    program = parse_program(UNITS_CALL.format(main=main, code=code))
    assert program.targets[:, 0].tolist() == pytest.approx([0.0, unit, 2 * unit],
                                                           abs=EXACT_M)


#: The main program's unit switches after its first motion, each with its line, column, the
#: line of that motion and the units from and to.
SWITCHES_AFTER_MOTION = [
    ("G21\nG01 X1. F100.\nG20\nG01 X1.\nM30\n", 3, 1, 2, "G20", "mm", "inch"),
    ("G20\nG00 X1.\nG21 G01 X2. F10.\nM30\n", 3, 1, 2, "G21", "inch", "mm"),
    ("G04 P100\nG00 X1.\nG20\nM30\n", 3, 1, 2, "G20", "mm", "inch"),  # a dwell no motion
    # the first motion in a subprogram the main program called
    ("O1\nM98 P100\nG20\nM30\nO100\nG00 X1.\nM99\n", 3, 1, 6, "G20", "mm", "inch"),
    # the first motions on the vectorised path (a run of simple lines): X0 of lines 1 and 2
    # is the work zero in either unit, X1. of line 3 is the first motion
    ("G00 X0\n" + "".join(f"G01 X{k}. F100.\n" for k in range(20)) + "N5 G20\n",
     "22 (N5)", 4, 3, "G20", "mm", "inch"),  # its N word named beside the line
    # a reference return of zeros is none (the test below), one with a length word is
    ("G91 G28 Z0.\nG90 G28 X1.\nG20\nM30\n", 3, 1, 2, "G20", "mm", "inch"),
    ("G53 Z0.\nG53 Z-1.\nG20\nM30\n", 3, 1, 2, "G20", "mm", "inch"),
    # a G00 or G01 of zeros is none either (the test below), one with a length word is
    ("G20\nG91 G28 Z0.\nG90 G00 X0\nG01 Y0.001 F1.\nG21\nM30\n", 5, 1, 4, "G21", "inch",
     "mm"),
    ("G90 G00 X0 Y0 Z0\nG91 G00 X0\nX1.\nG20\nM30\n", 4, 1, 3, "G20", "mm", "inch"),
]


@pytest.mark.parametrize(("text", "line", "column", "moved", "code", "was", "now"),
                         SWITCHES_AFTER_MOTION)
def test_a_main_program_switching_g20_g21_after_a_motion_is_refused_naming_its_line(
        text, line, column, moved, code, was, now):
    # the switch had been taken: the moves before it read in one unit, those after in the
    # other (G21 X1. then G20 X1.: 1 mm, then 25.4 mm); FANUC wants the units at the head
    with pytest.raises(NCProgramError) as info:
        parse_program(text, "prog.nc")
    assert str(info.value) == (
        f"prog.nc, line {line}, column {column}, key '{code}': {code} switches the units from "
        f"{was} to {now} after the first motion (line {moved}), whose moves were read in "
        f"{was}: FANUC forbids switching G20/G21 within a program; select the units once, at "
        "the head of the program, before any motion")


@pytest.mark.parametrize(("text", "expected_mm"), [
    # a post's header: Z to the reference (0.1 m), then the units and an inch move (G54's X
    # offset is 10 mm: X1. is 25.4 mm + 10 mm)
    ("G91 G28 Z0.\nG90\nG20\nG00 X1.\nM30\n",
     [[math.nan, 100.0], [35.4, 100.0]]),
    # G53 of zeros at the reference; the angle is in degrees in either unit
    ("G53 Z0. C90.\nG20\nG00 X1. Z-1.\nM30\n",
     [[math.nan, 100.0], [35.4, -25.4]]),
    # G90: through the work zero (G54's X), then the reference, then 25.4 mm + 10 mm
    ("G90 G28 X0 Y0\nG20\nG00 X1.\nM30\n",
     [[10.0, math.nan], [0.0, math.nan], [35.4, math.nan]]),
    # the other way: inch, back to mm before the first move with a length
    ("G20\nG91 G28 Z0.\nG28 X0. Y0.\nG90 G21 G00 X1.\nM30\n",
     [[math.nan, 100.0], [0.0, 100.0], [11.0, 100.0]]),
    # G00/G01 of zeros: G90's are the work zero (G54's X, 10 mm, and Z's reference under
    # it), G91's where the axes stand (reached by zeros); then the units and an inch move
    ("G90 G00 X0 Z0\nG91 G01 X0 Z0. F100.\nG90\nG20\nG00 X1.\nM30\n",
     [[10.0, 0.0], [10.0, 0.0], [35.4, 0.0]]),
    ("G20\nG00 G90 X0. C45.\nG21\nG00 X1.\nM30\n",  # an angle: degrees in either
     [[10.0, math.nan], [11.0, math.nan]]),
    # a run of zeros on the vectorised path (16 lines or more), then the switch
    ("G90 G00 X0 Z0\n" + "G01 X0 F100.\n" * 20 + "G20\nG00 X1.\nM30\n",
     [[10.0, 0.0]] * 21 + [[35.4, 0.0]]),
])
def test_a_move_of_zero_lengths_is_no_first_motion_for_the_units(text, expected_mm):
    # its target is the same read in mm or inch, so the units after it are read, and the
    # moves after the switch in the new unit: X1. is 25.4 mm under G20, 1 mm under G21
    for fast in (True, False):
        program = parse_program(text, reference={"Z": 0.1}, fast=fast,
                                work_offsets={"G54": {"X": 10 * MM}})
        got = program.targets[:, [0, 2]] / MM
        np.testing.assert_allclose(got, expected_mm, rtol=0.0, atol=1e-12)  # NaN: unset
    if "C90." in text:
        assert program.targets[:, 5].tolist() == pytest.approx([math.pi / 2] * 2, abs=1e-15)


def test_units_selected_before_any_motion_or_restated_after_it_are_read():
    # switched and repeated before the first motion (after a dwell), restated after it
    text = "G21\nG04 P100\nG20\nG20\nG01 X1. F10.\nG20 X2.\nM30\n"
    program = parse_program(text)
    assert program.targets[1:, 0].tolist() == pytest.approx([25.4 * MM, 50.8 * MM],
                                                            abs=EXACT_M)
    assert dict(program.unit_words) == {"G21": 1, "G20": 3}


def test_subprogram_layout_refusals():
    with pytest.raises(NCProgramError, match="has no M99"):
        parse_program("O1\nM30\nO2\nG00 X0\n")
    with pytest.raises(NCProgramError, match="must be the first block"):
        parse_program("O1\nG00 X0\nO2\nM99\n")
