"""Feed moves with no F in force: refused where the reader meets them, in both of its paths.

A G01, G02/G03 or canned-cycle block read before any F had read without a refusal (its feed
moves kept no feed, NaN); the planner refused the moving ones later as 'a feed move (G01)'
whatever the block was, and a G01 to where the tool already stood took 0 s. A FANUC control
stops there with alarm PS0011 (feed zero: "the feedrate was not commanded to a cutting
feed"), as Beckhoff's TwinCAT CNC does (ID 20008: "the first motion command with
interpolation (G01, G02, G03) requires a feed value").
"""

from __future__ import annotations

import math

import pytest

from machinesim.exceptions import NCProgramError
from machinesim.nc import KIND_LINEAR, parse_program

START = "G90 G94 G21 G17\nG00 X0 Y0 Z5.\n"
#: The message's text after the code.
NO_F = ("feeds with no F in force: no feed rate has been given yet (a FANUC control stops "
        "with alarm PS0011, feed zero); give F in this block or before it (mm/min; inch/min "
        "under G20)")


def _refusal(text: str, **options) -> NCProgramError:
    with pytest.raises(NCProgramError) as error:
        parse_program(text, **options)
    return error.value


@pytest.mark.parametrize(("block", "code", "column"), [
    ("G01 X1.", "G01", 1),
    ("G01 X0", "G01", 1),  # to where it stands: the planner had given it 0 s
    ("G02 X2. Y0 R1.", "G02", 1),
    ("G03 X2. Y0 I1. J0", "G03", 1),
    ("G81 X1. Z-1. R1.", "G81", 1),
    ("G82 X1. Z-1. R1. P10.", "G82", 1),
    ("G73 X1. Z-1. R1. Q0.5", "G73", 1),
    ("G83 X1. Z-1. R1. Q0.5", "G83", 1),
    ("G98 G83 X1. Z-1. R1. I0.5 J0.1 K0.2", "G83", 5),
    ("G21 G82 X1. Z-1. R1. P10", "G82", 5),
])
def test_a_feed_move_with_no_f_in_force_is_refused_naming_line_and_code(block, code, column):
    error = _refusal(START + block + "\nM30\n")
    assert str(error) == f"<string>, line 3, column {column}, key '{code}': {code} {NO_F}"
    assert (error.line, error.key) == (3, code)


def test_a_hole_of_a_cycle_without_f_is_refused_in_each_block_that_drills():
    # the cycle's later holes, blocks without its G code, are located at their first word
    error = _refusal(START + "G82 X1. Z-1. R1. P10.\nX2.\nY3.\nG80\nM30\n")
    assert [(p.line, p.key) for p in error.problems] == [(3, "G82"), (4, "X2."), (5, "Y3.")]
    assert all(str(p).endswith(f"G82 {NO_F}") for p in error.problems)


def test_an_f_given_before_or_in_the_block_is_in_force():
    # F is modal from any block (a rapid's too); in a cycle block it feeds that hole
    for text in ("G00 X0 Y0 Z5. F150.\nG82 X1. Z-1. R1. P10.\n",
                 "G00 X0 Y0 Z5.\nG82 X1. Z-1. R1. P10. F150.\n",
                 "G00 X0 Y0 Z5.\nF150.\nG01 X1.\nG02 X3. R1.\n"):
        program = parse_program(text)
        linear = program.kinds == KIND_LINEAR
        assert linear.any()
        assert program.feeds[linear].tolist() == [150e-3 / 60.0] * int(linear.sum())


def test_the_feed_move_after_the_block_that_gives_f_reads():
    # lines before the F are refused, the ones from it on are not
    error = _refusal(START + "G01 X1.\nG01 X2. F100.\nG01 X3.\n")
    assert [(p.line, p.key) for p in getattr(error, "problems", (error,))] == [(3, "G01")]


def test_a_switch_of_feed_mode_reads_no_earlier_f_in_another_unit():
    # FANUC clears F on a change between G93/G94/G95 (Series 30i spec A-91417, PS0011):
    # G93 and G95 are refused by name, so no F of theirs runs a later G94 move
    for mode, name in (("G93", "inverse time feed"), ("G95", "feed per revolution")):
        error = _refusal(f"G00 X0 Z1.\n{mode} G01 X1. F10.\nG94 G01 X2.\nM30\n")
        assert (error.line, error.key) == (2, mode)
        assert name in str(error)


@pytest.mark.parametrize("f_line", [None, 5, 30])
def test_the_fast_and_the_word_by_word_paths_refuse_alike(f_line):
    # 40 plain G01 lines, one run of the vectorised path; F on none, the 5th or the 30th
    lines = [f"G01 X{k}." if k != f_line else f"G01 X{k}. F100." for k in range(1, 41)]
    text = "G00 X0 Y0 Z5.\n" + "\n".join(lines) + "\nM30\n"
    fast, slow = _refusal(text), _refusal(text, fast=False)
    assert str(fast) == str(slow)
    problems = [(p.line, p.key, str(p)) for p in fast.problems]
    assert problems == [(p.line, p.key, str(p)) for p in slow.problems]
    refused = 40 if f_line is None else f_line - 1
    assert [line for line, _, _ in problems] == list(range(2, 2 + refused))
    assert all(message.endswith(f"G01 {NO_F}") for _, _, message in problems)


def test_a_long_run_after_its_f_reads_alike_in_both_paths():
    # the run's F on its first line: both paths read the same program, every feed 100 mm/min
    text = "G00 X0 Y0 Z5.\nG01 X1. F100.\n" + "".join(f"X{k}.\n" for k in range(2, 41))
    fast, slow = parse_program(text), parse_program(text, fast=False)
    assert fast == slow
    assert all(math.isclose(f, 100e-3 / 60.0, rel_tol=0.0) for f in fast.feeds[1:])


def test_a_cycle_block_with_k0_drills_nothing_so_needs_no_f():
    # FANUC's K0 keeps the hole data and drills no hole: the block has no feed move, so no
    # F need be in force there (it had been refused as 'G81 feeds with no F in force'); the
    # next block, which drills, is where F is needed
    program = parse_program(START + "G81 X1. Z-1. R1. K0\nX2. F100.\nG80\nM30\n")
    linear = program.kinds == KIND_LINEAR
    assert program.lines[linear].tolist() == [4]  # the one feed move: line 4's hole
    assert program.feeds[linear][0] == pytest.approx(100.0 / 60e3, rel=1e-15)
    assert not (program.lines == 3).any()  # K0's block added no move
    error = _refusal(START + "G81 X1. Z-1. R1. K0\nX2.\nG80\nM30\n")
    assert (error.line, error.key) == (4, "X2.")


# --- an F given before the G20/G21 that switched the units

#: The message of a feed move under the F of line 1, given before the switch on line 2.
F_BEFORE = ("{code} feeds at the F of line 1 ({number} {was}/min), given before {switch} on "
            "line 2 switched the units to {now}, and no F since: whether a control keeps that "
            "F in {was}/min or reads its number in {now}/min is not documented for FANUC "
            "(B-63944EN/02 8.2 wants G20/G21 alone at the head of the program, before any F); "
            "give F again after the {switch}")


@pytest.mark.parametrize(("head", "block", "code", "line"), [
    ("G21 F100.\nG20\n", "G00 X0 Y0 Z0.1\nG01 X1.", "G01", 4),
    ("G21 F100.\nG20\n", "G00 X0 Y0\nG02 X2. Y0 I1. J0", "G02", 4),
    ("G21 F100.\nG20\n", "G00 X0 Y0 Z1.\nG81 X1. Z-1. R0.5", "G81", 4),
    # the same on the vectorised path (a run of plain lines)
    ("G21 F100.\nG20\n", "G00 X0 Y0 Z0\n" + "G01 X0.1\n" * 20, "G01", 4),
    ("G20 F4.\nG21\n", "G00 X0 Y0 Z0\nG01 X1.", "G01", 4),
])
def test_a_feed_under_an_f_from_before_a_unit_switch_is_refused_naming_both_lines(
        head, block, code, line):
    # G21 F100. / G20 / G01 X1.: the F had kept its reading, 100 mm/min, in an inch program
    for fast in (True, False):
        error = _refusal(head + block + "\nM30\n", source="prog.nc", fast=fast)
        switch = head.split("\n")[1]
        was, now, number = (("mm", "inch", "100") if switch == "G20" else ("inch", "mm", "4"))
        assert (error.line, error.column, error.key) == (line, 1, code)
        assert str(error).endswith(F_BEFORE.format(code=code, number=number, was=was,
                                                   now=now, switch=switch))


@pytest.mark.parametrize(("text", "feed_mm_per_min"), [
    ("G21 F100.\nG20\nG01 X1. F4.\nM30\n", 4 * 25.4),  # F again after the switch
    ("G21 F100.\nG20\nG00 X1.\nG01 X2. F4.\nM30\n", 4 * 25.4),  # a rapid needs none
    ("G20 F4.\nG21\nG20\nG01 X1.\nM30\n", 4 * 25.4),  # back in the F's own unit
    ("G21 F100.\nG21\nG01 X1.\nM30\n", 100.0),  # restated, not switched
])
def test_an_f_read_in_the_units_in_force_feeds(text, feed_mm_per_min):
    program = parse_program(text)
    feeds = program.feeds[program.kinds == KIND_LINEAR]
    assert feeds.tolist() == pytest.approx([feed_mm_per_min * 1e-3 / 60.0], rel=1e-15)


def test_the_f_read_on_the_vectorised_path_is_named_with_its_line():
    # moves of zeros (no first motion for the units rule), each with its F, then the switch
    text = "G90 G00 X0 Y0 Z0\n" + "G01 X0 F100.\n" * 20 + "G20\nG01 X1.\nM30\n"
    for fast in (True, False):
        error = _refusal(text, fast=fast)
        assert error.line == 23
        assert "the F of line 21 (100 mm/min), given before G20 on line 22" in str(error)


@pytest.mark.parametrize("move", [f"X1. A1{'0' * 300}.", f"X1{'0' * 200}. A1."])
def test_a_g20_move_of_linear_and_rotary_axes_too_long_to_square_keeps_its_feed(move):
    # F10. under G20 counts a degree as an inch. With A 1e300 deg beside X 1 inch the move is
    # all but rotary: F10 deg/min, 10 mm/min in the metric equivalent; with X 1e200 inch all
    # but linear: 10 inch/min = 254 mm/min. Its squared lengths overflowed to inf, the feed
    # was inf / inf = NaN, and the planner refused it as 'a feed move ... with no feed rate F'
    program = parse_program(f"G90 G20\nG00 X0 A0\nG01 {move} F10.\nM30\n")
    expected = 10.0 if "A1000" in move else 254.0
    assert program.feeds[-1] * 60e3 == pytest.approx(expected, rel=1e-12)
