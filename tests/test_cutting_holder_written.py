"""The holder's allowance on a straight move is the rounding of the words as written
(`machinesim.cutting.program.written_rounding`, `Program.length_digit`): a plunge meant down a
tilted tool's axis, written to 3 decimals of mm or 4 of inch as CAM posts write it, is cut;
a straight pass whose holder enters a wall by more than that rounding is refused."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

from machinesim.cutting import cut, cut_turned
from machinesim.cutting.program import WRITTEN_ROUNDING_M, written_rounding
from machinesim.exceptions import HolderContactError, NCProgramError
from machinesim.nc import Move, Program, parse_program

B = np.radians(30.0)
#: robonano_a0ib's tool axis at B = 30 deg, in its Z-X plane (x, z), and the unit vector
#: across it in that plane
AXIS, ACROSS = np.array([np.sin(B), np.cos(B)]), np.array([np.cos(B), -np.sin(B)])
INCH_MM = 25.4
STOCK = "block:40x40x20@-20,-20,0"  # top at z = 0
TOOL = "ball:0.5:h=2"  # a 2 mm body: the holder follows it into the hole


def _plunge(start, end, decimals: int, inch: bool = False) -> str:
    """A plunge from ``start`` to ``end`` ((x, z), mm) at B30, both written to ``decimals``
    (of inch with ``inch``), and back."""
    scale = 1.0 / INCH_MM if inch else 1.0
    (xs, zs), (xe, ze) = (np.asarray(start) * scale, np.asarray(end) * scale)
    f = lambda v: f"{v:.{decimals}f}"  # noqa: E731
    return (f"G90 {'G20' if inch else 'G21'}\nG00 X{f(xs)} Y0. Z{f(zs)} B30.\n"
            f"G01 X{f(xe)} Z{f(ze)} F{f(100.0 * scale)}\nG00 X{f(xs)} Z{f(zs)}\nM30\n")


def _across(text: str) -> float:
    """How far the written plunge (lines 2 to 3) runs across the tool's axis, mm: the meant
    move runs along it, so its start-to-end vector's component across it."""
    program = parse_program(text)
    start, end = program.targets[0, [0, 2]], program.targets[1, [0, 2]]
    return float((end - start) @ ACROSS) * 1e3


#: (start, end) (x, z) mm of plunges meant down the axis: from a hand-written X0 Z5 17 mm
#: along it (the end computed), and from a start computed 17.06996 mm up the axis from an
#: end computed, both rounding against each other across the axis at 3 decimals of mm
FROM_WRITTEN = ((0.0, 5.0), (-17.0 * AXIS[0], 5.0 - 17.0 * AXIS[1]))
BOTH_COMPUTED = (tuple(np.array([-8.49449, -13.71951]) + 17.06996 * AXIS),
                 (-8.49449, -13.71951))
#: the same in inch, rounding against each other at 4 decimals of inch
BOTH_COMPUTED_INCH = (tuple((np.array([-0.334449, -0.540151]) + 0.667996 * AXIS) * INCH_MM),
                      tuple(np.array([-0.334449, -0.540151]) * INCH_MM))


@pytest.mark.parametrize("plunge, decimals, inch, across_um", [
    (FROM_WRITTEN, 6, False, 0.0), (FROM_WRITTEN, 3, False, -0.216),
    (BOTH_COMPUTED, 3, False, 1.339), (BOTH_COMPUTED_INCH, 4, True, 3.407)])
def test_a_tilted_plunge_written_as_posts_write_it_is_cut(plunge, decimals, inch, across_um):
    """The plunges at B30 with a 2 mm body (its holder in the hole from 2 mm above the end up
    to the stock's top, some 0.6 to 0.8 of the plunge), written to 6 and 3 decimals of mm and
    4 of inch: 0.216 um across the axis (an end computed from a written start, Z-9.722 for
    -9.7224319 mm: 0.432 um sin 30 deg), 1.339 um (both ends computed and rounded against
    each other), and 3.407 um in inch. The holder, following the body down the hole the body
    drilled along the written move, is beside it by that offset times the holder's height in
    the material over the move's length, below 1. Within 100 nm, the allowance of every
    straight move, all but the 6-decimal one were refused as a crash. The words' rounding,
    up to sqrt(2) digits across the axis (sqrt(2) um at 3 decimals of mm, 3.592 um at 4 of
    inch), holds them: cut, as --allow-holder-contact cuts them."""
    text = _plunge(*plunge, decimals, inch)
    part, report = cut(parse_program(text), "robonano_a0ib", tool=TOOL, stock=STOCK)
    allowed, _ = cut(parse_program(text), "robonano_a0ib", tool=TOOL, stock=STOCK,
                     allow_holder_contact=True)
    assert report.holder_contact == ()
    assert part.volume == pytest.approx(allowed.volume, rel=1e-12)
    assert _across(text) * 1e3 == pytest.approx(across_um, abs=1e-3)
    assert abs(_across(text)) * 1e-3 <= written_rounding(parse_program(text))


@pytest.mark.parametrize("integer_input", ["calculator", "increment", "is-b", "is-c"])
def test_a_zero_written_without_a_point_leaves_the_plunge_cut_under_any_integer_input(
        integer_input):
    """A post writes ``Y0`` for a zero: it reads 0 whatever the integer input (no entry in
    `Program.integer_words`), so it tells nothing of the decimals. Under ``increment`` it
    had counted as a digit of 1 nm, the allowance fell to the 100 nm floor, and the
    3-decimal plunge with both ends computed (1.339 um across the axis), cut when read as a
    calculator reads it, was refused as a crash with the same targets."""
    text = _plunge(*BOTH_COMPUTED, 3).replace("Y0.", "Y0")
    calculator = parse_program(text)
    program = parse_program(text, integer_input=integer_input)
    assert program.integer_words == {}
    assert np.array_equal(program.targets, calculator.targets, equal_nan=True)
    assert program.length_digit == pytest.approx(1e-6, rel=1e-14)  # 3 decimals of mm
    part, report = cut(program, "robonano_a0ib", tool=TOOL, stock=STOCK)
    assert report.holder_contact == ()
    assert part.volume == pytest.approx(cut(calculator, "robonano_a0ib", tool=TOOL,
                                            stock=STOCK)[0].volume, rel=1e-12)


@pytest.mark.parametrize("plunge", [FROM_WRITTEN, BOTH_COMPUTED])
def test_a_compensated_plunge_keeps_the_rounding_of_the_text_it_came_from(plunge):
    """`compensation.rewrite` with the program's own axis values (a compensation that
    corrects nothing) leaves every target written as it was, to the bit: the 3-decimal
    plunges are cut as the program read is. `Program.with_targets` had dropped
    `length_digit`, the allowance fell to 100 nm, and both were refused at line 3 with the
    same targets."""
    from machinesim.compensation import program_axes, rewrite
    from machinesim.machines import load_machine

    machine = load_machine("robonano_a0ib")
    program = parse_program(_plunge(*plunge, 3))
    motion = [i for i, move in enumerate(program.moves) if move.kind != "dwell"]
    compensated = rewrite(program, machine, program_axes(program, machine)[motion])
    written = ~np.isnan(program.targets)  # (rewrite gives every axis on every move)
    assert np.array_equal(compensated.targets[written], program.targets[written])
    assert written_rounding(compensated) == pytest.approx(np.sqrt(2.0) * 1e-6, rel=1e-14)
    part, report = cut(compensated, machine, tool=TOOL, stock=STOCK)
    assert report.holder_contact == ()
    assert part.volume == pytest.approx(cut(program, machine, tool=TOOL, stock=STOCK)[0].volume,
                                        rel=1e-12)


def test_half_the_rounding_refuses_a_plunge_whose_two_ends_were_rounded():
    """The allowance counts a whole digit on each axis, not half: the plunge whose start and
    end were both computed and rounded runs 1.339 um across the axis at 3 decimals of mm,
    beyond sqrt(2) x half a digit (0.707 um), and its holder enters the hole's wall by more
    than that: refused with it, cut with sqrt(2) digits (the test above)."""
    import machinesim.cutting.program as program_module

    text = _plunge(*BOTH_COMPUTED, 3)
    half = written_rounding(parse_program(text)) / 2
    assert half == pytest.approx(np.sqrt(2.0) * 0.5e-6, rel=1e-15)
    original = program_module.written_rounding
    try:
        program_module.written_rounding = lambda program: half
        with pytest.raises(HolderContactError, match=r"line 3 \(lines 3, 4\) takes the top"):
            cut(parse_program(text), "robonano_a0ib", tool=TOOL, stock=STOCK)
    finally:
        program_module.written_rounding = original


def _slot_then_step(x_word: str) -> str:
    """A slot along Y at x = 5 mm, 0.5 then 1 mm down, then a pass 1.5 mm down at
    ``x_word`` (line 12): flat:1.0:h=1 (1 mm in radius, its holder as wide, from 0.5 mm
    below the top up) enters the slot's wall at x = 6 mm by the pass's x - 5 mm."""
    return ("G21 G90\nG00 X5. Y-1. Z1.\nG01 Z-0.5 F100.\nY11.\nG00 Z1.\nG00 X5. Y-1.\n"
            f"G01 Z-1.0\nY11.\nG00 Z1.\nG00 {x_word} Y-1.\nG01 Z-1.5\nY11.\nG00 Z5.\nM30\n")


@pytest.mark.parametrize("f", [cut, cut_turned])
def test_a_straight_pass_into_a_wall_beyond_the_words_rounding_is_refused(f):
    """Written to 3 decimals of mm the straight moves' allowance is sqrt(2) um: a pass 1 um
    into the slot's wall is within it (one digit: the text cannot tell it from the wall),
    2 um and 50 um beyond it. A pass 0.1 mm into the wall written to 1 decimal, X5.1 (a
    digit of 0.1 mm, hand-written), is no rounding: the allowance is capped at 3 decimals
    of mm, and it is refused."""
    kwargs = {"tool": "flat:1.0:h=1", "stock": "block:10x10x3"}
    _, report = f(parse_program(_slot_then_step("X5.001")), "grooving_4axis", **kwargs)
    assert report.holder_contact == ()
    for x_word in ("X5.002", "X5.050", "X5.1"):
        with pytest.raises(HolderContactError, match=r"line 12 takes the top of the tool"):
            f(parse_program(_slot_then_step(x_word)), "grooving_4axis", **kwargs)


@pytest.mark.parametrize("text, digit, allowance", [
    ("G21\nG00 X1.234 Z-0.5\nM30\n", 1e-6, np.sqrt(2.0) * 1e-6),
    ("G20\nG00 X0.1234 Z-0.5\nM30\n", 2.54e-6, np.sqrt(2.0) * 2.54e-6),
    ("G21\nG00 X1.2345\nM30\n", 1e-7, np.sqrt(2.0) * 1e-7),
    ("G00 X1.23456\nM30\n", 1e-8, 1e-7),  # no unit word: mm; below the floor
    ("G21\nG00 X1.5 Y2.\nM30\n", 1e-4, np.sqrt(2.0) * 1e-6),  # capped at 3 decimals of mm
    ("G20\nG00 X1.5\nM30\n", 2.54e-3, np.sqrt(2.0) * 2.54e-6),  # at 4 of inch
    ("G21\nG00 X1.234 Y0.00001\nM30\n", 1e-8, 1e-7),  # the finest word counts
    # incremental, and an arc's centre word (a half circle)
    ("G21\nG00 X0. Y0.\nG91 X1. Y1.\nG02 X1. Y0. I0.5000 J0. F100.\nM30\n", 1e-7,
     np.sqrt(2.0) * 1e-7),
    ("G21\nG00 B30.12345 X1.\nM30\n", 1e-3, np.sqrt(2.0) * 1e-6),  # an angle is no length
])
def test_the_allowance_is_sqrt_2_digits_of_the_finest_length_word(text, digit, allowance):
    """By hand: the last digit of the finest length word (`Program.length_digit`: the unit
    over 10 to its decimals), and the straight moves' allowance sqrt(2) times that digit (a
    plunge down an axis in the Z-X plane changes two coordinates, each end off by up to half
    a digit in each), the digit taken at most 3 decimals of mm or 4 of inch, never below
    100 nm."""
    program = parse_program(text)
    assert program.length_digit == pytest.approx(digit, rel=1e-14)
    assert written_rounding(program) == pytest.approx(allowance, rel=1e-14)


def test_the_written_digit_is_pickled_and_none_for_targets_not_read():
    program = parse_program("G21\nG00 X1.234 Z-0.5\nM30\n")
    assert pickle.loads(pickle.dumps(program)).length_digit == program.length_digit
    # targets moved from the text's (compensated) keep its rounding
    moved = program.with_targets(program.targets + 1e-6)
    assert moved.length_digit == program.length_digit == pytest.approx(1e-6, rel=1e-14)
    built = Program.from_moves([Move("rapid", {"X": 0.001234})])
    assert built.length_digit is None and written_rounding(built) == WRITTEN_ROUNDING_M
    assert parse_program("G00 B30.\nM30\n").length_digit is None  # no length word
    bare = parse_program("G21\nG00 X1500 Y2.\nM30\n", integer_input="increment")
    assert bare.length_digit == pytest.approx(1e-9, rel=1e-14)  # X1500: 1500 nm
    for fast in (True, False):  # a zero without a point: no digit, on either path
        zeros = parse_program("G21\nG00 X0 Y0 Z-0\nM30\n", integer_input="increment",
                              fast=fast)
        assert zeros.length_digit is None
    function, arguments = program.__reduce__()
    with pytest.raises(NCProgramError, match=r"length_digit must be None or a length > 0 "
                                             r"\(m\).*got -1\.0"):
        function(*arguments[:-1], -1.0)


def test_a_word_of_hundreds_of_decimals_is_read_with_its_digit_bounded():
    """``X1.`` and 400 zeros is 1 mm: the last digit's 10 ** -400 mm is beyond float64 and
    had ended the read in an OverflowError. Counted to `MOST_DECIMALS` (30) decimals, the
    digit is 1e-30 mm and the allowance the floor."""
    from machinesim.nc.blocks import MOST_DECIMALS

    program = parse_program("G21 G90\nG01 X1." + "0" * 400 + " Y2. F100.\nM30\n")
    assert program.targets[-1, 0] == 1e-3
    assert program.length_digit == pytest.approx(1e-3 / 10.0 ** MOST_DECIMALS, rel=1e-14, abs=0.0)
    assert written_rounding(program) == WRITTEN_ROUNDING_M
