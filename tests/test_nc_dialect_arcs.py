"""The FANUC dialect's arcs (issue 12): points on the circle within the chord tolerance, centres
and sweeps by I J K or R, the right-hand rule, helices, an end off the circle, located
refusals, incremental arcs; and arcs as public CAM posts write them (inch output
increments, G91.1, XZ without G18). Expected values worked out by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from machinesim.exceptions import NCProgramError
from machinesim.nc import ARC_RADIUS_TOLERANCE_M, AXES, KIND_LINEAR, Program, parse_program

MM = 1e-3


#: Points of an arc are centre + r (cos, sin): float64 round-off ~1e-18 m at 10 mm; the
#: issue's bound for "on the circle".
ON_CIRCLE_M = 1e-12


def _column(letter: str) -> int:
    return AXES.index(letter)


def _arc_rows(program: Program, line: int) -> np.ndarray:
    """The targets of the moves of one block, preceded by the position before it."""
    rows = np.flatnonzero(program.lines == line)
    return program.targets[rows[0] - 1:rows[-1] + 1]


def _sagitta(points: np.ndarray, centre: np.ndarray, radius: float) -> float:
    """Largest distance between a chord and its arc: r minus the chord midpoint's radius."""
    mid = (points[1:] + points[:-1]) / 2.0
    return float(np.max(radius - np.linalg.norm(mid - centre, axis=1)))


# --- arcs


@pytest.mark.parametrize("tolerance", [1e-9, 1e-6])
def test_quarter_arc_points_on_circle_within_chord_tolerance(tolerance):
    program = parse_program("G17 G00 X10. Y0 Z0\nG03 X0 Y10. I-10. J0 F100.",
                            chord_tolerance=tolerance)
    pts = _arc_rows(program, 2)[:, :2]
    radius = 10 * MM
    r = np.linalg.norm(pts, axis=1)
    assert np.max(np.abs(r - radius)) <= ON_CIRCLE_M
    assert _sagitta(pts, np.zeros(2), radius) <= tolerance
    # fewest segments: one fewer would break the tolerance (sagitta = r (1 - cos(step / 2)))
    n = len(pts) - 1
    assert radius * (1 - math.cos(math.pi / 2 / (n - 1) / 2)) > tolerance
    assert pts[-1].tolist() == [0.0, 10 * MM]  # the programmed end, exactly
    angles = np.unwrap(np.arctan2(pts[:, 1], pts[:, 0]))
    assert np.all(np.diff(angles) > 0)  # G03 turns counter-clockwise about +Z
    assert angles[-1] - angles[0] == pytest.approx(math.pi / 2, abs=1e-12)
    assert np.all(program.kinds[1:] == KIND_LINEAR)
    assert program.feeds[1] == pytest.approx(100 * MM / 60, rel=1e-15)


@pytest.mark.parametrize(
    ("text", "centre_mm", "sweep_deg"),
    [
        ("G00 X0 Y10.\nG03 X-10. Y0 R10. F1", (0.0, 0.0), 90.0),  # R > 0: up to 180 deg
        ("G00 X-10. Y0\nG02 X0 Y-10. R-10. F1", (0.0, 0.0), -270.0),  # R < 0: over 180
        ("G00 X-10. Y0\nG02 X0 Y-10. R10. F1", (-10.0, -10.0), -90.0),
        ("G00 X-10. Y0\nG03 X0 Y-10. R10. F1", (0.0, 0.0), 90.0),
        ("G00 X10. Y0\nG03 I-10. F1", (0.0, 0.0), 360.0),  # full circle, no end words
        ("G00 X10. Y0\nG02 X10. Y0 I-10. J0 F1", (0.0, 0.0), -360.0),
    ],
)
def test_arc_centre_and_sweep(text, centre_mm, sweep_deg):
    program = parse_program(text)
    pts = _arc_rows(program, 2)[:, :2]
    centre = np.array(centre_mm) * MM
    assert np.max(np.abs(np.linalg.norm(pts - centre, axis=1) - 10 * MM)) <= ON_CIRCLE_M
    angles = np.unwrap(np.arctan2(pts[:, 1] - centre[1], pts[:, 0] - centre[0]))
    assert math.degrees(angles[-1] - angles[0]) == pytest.approx(sweep_deg, abs=1e-9)
    assert _sagitta(pts, centre, 10 * MM) <= 1e-9


@pytest.mark.parametrize(
    ("text", "centre_mm", "radius_mm"),
    [
        # an inch half circle: 3 x 0.0254 - 2 x 0.0254 is 8e-18 m short of 0.0254, and
        # sqrt(r^2 - half^2) made that a centre 0.33 nm off the chord
        ("G20 G00 X2. Y0.01\nG02 X3. Y0.01 R0.5 F1", (63.5, 0.254), 12.7),
        # far out in mm, where the round-off of the coordinates is larger: 1.2 nm off before
        ("G21 G00 X500.048 Y0.763\nG03 X526.468 Y0.763 R13.21 F1", (513.258, 0.763), 13.21),
        ("G21 G00 X500.002 Y0.511\nG03 X538.956 Y0.511 R19.477 F1", (519.479, 0.511), 19.477),
    ],
)
def test_a_half_circle_by_r_is_centred_on_its_chord(text, centre_mm, radius_mm):
    program = parse_program(text)
    pts = _arc_rows(program, 2)[:, :2]
    centre = np.array(centre_mm) * MM
    assert np.max(np.abs(np.linalg.norm(pts - centre, axis=1) - radius_mm * MM)) <= ON_CIRCLE_M


@pytest.mark.parametrize(
    ("plane", "start", "end", "centre_words", "normal"),
    [
        ("G17", "X10. Y0 Z0", "X0 Y10.", "I-10. J0", "Z"),
        ("G18", "X0 Y0 Z10.", "X10. Z0", "K-10. I0", "Y"),
        ("G19", "X0 Y10. Z0", "Y0 Z10.", "J-10. K0", "X"),
    ],
)
@pytest.mark.parametrize("code", ["G02", "G03"])
def test_arc_direction_follows_the_right_hand_rule(plane, start, end, centre_words, normal,
                                                   code):
    # G03 turns positively about the plane's normal (+Z, +Y, +X), G02 negatively: checked
    # with the cross product of successive radius vectors, independently of the reader's
    # (u, v) plane coordinates.
    program = parse_program(f"{plane} G00 {start}\n{code} {end} {centre_words} F1")
    pts = _arc_rows(program, 2)[:, :3]
    cross = np.cross(pts[:-1], pts[1:])[:, _column(normal)]
    assert np.all(cross > 0) if code == "G03" else np.all(cross < 0)
    sweep = 90.0 if code == "G03" else 270.0  # the same ends: a quarter one way round
    angle = np.sum(np.arccos(np.clip(np.sum(pts[:-1] * pts[1:], axis=1)
                                     / (10 * MM) ** 2, -1.0, 1.0)))
    assert math.degrees(angle) == pytest.approx(sweep, abs=1e-6)
    assert np.max(np.abs(np.linalg.norm(pts, axis=1) - 10 * MM)) <= ON_CIRCLE_M


def test_helix_moves_the_third_axis_with_the_angle():
    program = parse_program("G00 X10. Y0 Z0 A0\nG03 X10. Y0 Z-1. A90. I-10. F50")
    rows = _arc_rows(program, 2)
    angle = np.unwrap(np.arctan2(rows[:, 1], rows[:, 0]))
    fraction = (angle - angle[0]) / (2 * math.pi)
    assert np.max(np.abs(rows[:, 2] - (-1 * MM) * fraction)) <= 1e-17
    assert np.max(np.abs(rows[:, 3] - math.radians(90) * fraction)) <= 1e-15
    assert np.max(np.abs(np.linalg.norm(rows[:, :2], axis=1) - 10 * MM)) <= ON_CIRCLE_M
    # the helix chord error equals the planar sagitta (midpoint deviation), within 1 nm
    assert _sagitta(rows[:, :2], np.zeros(2), 10 * MM) <= 1e-9


def test_end_off_the_circle_within_the_tolerance_spirals_to_the_programmed_end():
    off = 0.002  # mm: 2 um, within the 3 um a 3-decimal post may leave
    program = parse_program(f"G00 X10. Y0\nG03 X0 Y{10 + off:.3f} I-10. F1")
    pts = _arc_rows(program, 2)[:, :2]
    assert pts[-1].tolist() == [0.0, (10 + off) * MM]
    r = np.linalg.norm(pts, axis=1)
    assert np.all(np.diff(r) >= -1e-15)  # the radius grows from 10 to 10.002 mm
    assert r[0] == pytest.approx(10 * MM, abs=1e-15)
    with pytest.raises(NCProgramError, match="end point is off the arc") as info:
        parse_program("G00 X10. Y0\nG03 X0 Y10.004 I-10. F1", "p.nc")
    assert (info.value.line, info.value.column, info.value.key) == (2, 16, "I-10.")
    assert ARC_RADIUS_TOLERANCE_M == 3e-6


def test_arc_refusals_are_located():
    cases = [
        ("G17 G00 X0 Y0\nG02 X1. K1.", "word K is only read with"),
        ("G00 X0 Y0\nG02 X1.", "needs the centre"),
        ("G00 X0 Y0\nG02 X1. I0 J0", "zero radius"),
        ("G00 X0\nG02 X1. I1.", "Y is not known yet"),
        ("G00 X0 Y0\nG02 X1. R0", "R0 is no arc"),
    ]
    for text, message in cases:
        with pytest.raises(NCProgramError, match=message) as info:
            parse_program(text, "p.nc")
        assert info.value.line == 2 and info.value.column is not None


def test_a_centre_word_of_another_plane_is_not_said_to_be_read_in_this_one():
    # K in a G17 arc had been told it is "only read with G02/G03 in G17 (centre words I J)"
    with pytest.raises(NCProgramError) as info:
        parse_program("G17 G00 X0 Y0\nG02 X1. K1.", "p.nc")
    message = str(info.value)
    assert "in G17 (centre words" not in message
    assert "G17: I J, G18: K I, G19: J K; this block is in G17" in message
    assert message.endswith("and with G73 and G81-G83 (repeats; with G73 and G83 beside I "
                            "and J, Haas's smallest peck; with G73's Q and a decimal point, "
                            "Haas's depth between returns to R)")
    with pytest.raises(NCProgramError) as info:
        parse_program("G18 G00 X0 Z0\nG02 X1. J1.", "p.nc")
    assert any(problem.key == "J1." and "this block is in G18" in str(problem)
               for problem in info.value.problems)


def test_l_in_a_canned_cycle_is_refused_naming_k():
    # Smid's "G99 G82 R2.5 Z-3.4 P200 F200.0 L0 (OR K0 ON SOME CONTROLS)": L had been
    # refused as an M98 word only, without the K that this reader takes for it
    with pytest.raises(NCProgramError, match="repeat count is K here") as info:
        parse_program("G21 G90 G00 X7. Y7. Z25.\nG99 G82 R2.5 Z-3.4 P200 F200. L0\nG80", "p.nc")
    assert (info.value.line, info.value.key) == (2, "L0")
    with pytest.raises(NCProgramError) as info:
        parse_program("G21 G90 G00 X0 Y0 Z25.\nG01 X5. F100. L3", "p.nc")
    assert "K" not in str(info.value).split("key 'L3': ")[1]


def test_arc_in_increments_and_incremental_end():
    # G91: the end is incremental; I J always are. Integer input: I-10000 = 10 um.
    program = parse_program("G00 X0.01 Y0\nG91 G03 X-10000 Y10000 I-10000 J0 F1",
                            integer_input="increment")
    pts = _arc_rows(program, 2)[:, :2]
    assert pts[-1] == pytest.approx([0.0, 10e-6], abs=1e-20)
    assert np.max(np.abs(np.linalg.norm(pts, axis=1) - 10e-6)) <= ON_CIRCLE_M


def _arc_off_by(offset_um: float, inch: bool) -> str:
    """A quarter arc of radius 10 mm about the origin from (10, 0) to (0, 10 + offset) mm, in
    the program's unit: its end off the circle by ``offset_um``."""
    unit = 25.4 if inch else 1.0
    end = (10.0 + offset_um * 1e-3) / unit
    return (f"{'G20' if inch else 'G21'} G90 G17\nG00 X{10.0 / unit:.6f} Y0.\n"
            f"G03 X0. Y{end:.6f} I{-10.0 / unit:.6f} J0. F10.\n")


def test_an_inch_arc_is_held_to_what_its_output_increment_allows():
    # 0.0001 in rounding leaves up to 4 x 0.5 x 2.54 um x sqrt(2) = 7.18 um of radius
    # difference: 5 um passes under G20 and is refused in mm (3 um there); 26 um (a digit
    # in the thousandths of an inch) is refused in both
    inch = parse_program(_arc_off_by(5.0, inch=True), "inch.nc")
    np.testing.assert_allclose(np.hypot(*inch.targets[-1, :2].T), 10.005e-3, rtol=1e-6)
    with pytest.raises(NCProgramError, match="expected at most 3 um"):
        parse_program(_arc_off_by(5.0, inch=False), "mm.nc")
    with pytest.raises(NCProgramError, match="expected at most 7.5 um"):
        parse_program(_arc_off_by(26.0, inch=True), "inch.nc")


def test_g91_1_is_the_arc_centre_form_read_and_g90_1_is_refused():
    text = "G90 G17 G91.1\nG00 X10. Y0.\nG03 X0. Y10. I-10. J0. F10.\n"
    program = parse_program(text, "a.nc")
    assert program.states["G91.1"] == 1
    assert program.targets[-1, :2].tolist() == [0.0, 10e-3]
    with pytest.raises(NCProgramError, match="absolute arc centres \\(G90.1\\) are not read"):
        parse_program(text.replace("G91.1", "G90.1"), "b.nc")


def test_an_arc_in_xz_without_g18_is_told_to_select_it():
    with pytest.raises(NCProgramError, match="needs G18 first"):
        parse_program("G90\nG00 X5. Z0.\nG03 X10. Z-2.5 R2.5 F10.\n", "lathe.nc")


@pytest.mark.parametrize("word, shown", [
    ("X1" + "1" * 1_000_000 + ".", "(1000003 characters)"),  # out of float64's range
    ("X1." + "1." * 500_000, "(1000003 characters)"),  # malformed
])
def test_a_word_a_million_characters_long_is_shown_by_its_ends(word, shown):
    # its message had held the word twice (key and value): 2 MB on one line of stderr
    with pytest.raises(NCProgramError) as info:
        parse_program(f"G00 X0. Y0. Z1.\nG01 F100.\n{word}\n", "long.nc")
    message = str(info.value)
    assert len(message) < 400 and shown in message and "line 3, column 1" in message


#: 1e299 and 1e300 mm written out (the reader takes no exponent)
_E299, _E300 = "1" + "0" * 299 + ".", "1" + "0" * 300 + "."


@pytest.mark.parametrize("words, radius", [
    (f"R{_E299}", "1e+299"), (f"R-{_E299}", "1e+299"),  # had crashed: ZeroDivisionError
    (f"I{_E300}", "1e+300"),  # had been refused as needing a 156-digit count of segments
    ("R2000000000.", "2e+09"), ("I-2000000000.", "2e+09"),  # 2,000 km
])
def test_an_arc_too_large_for_float64_to_place_within_the_chord_tolerance_is_refused(
        words, radius):
    # float64 places a point of a circle of radius r within about 4 ulp of r, r 2**-50:
    # 1 nm (the default tolerance) at r = 1e-9 * 2**50 m = 1.1259e9 mm
    with pytest.raises(NCProgramError) as caught:
        parse_program(f"G90 G21\nG00 X0 Y0 Z1.\nG02 X2. Y0 {words} F100.\nM30\n", "a.nc")
    error = caught.value
    assert (error.line, error.key) == (3, words)
    assert f"radius of {radius} mm is too large" in str(error)
    assert "beyond 1.1259e+09 mm" in str(error)


def test_a_flat_arc_within_the_bound_reads_as_its_chord():
    # R 1e9 mm (1,000 km) over a 2 mm chord: its sagitta, 1 mm^2 / (2 * 1e9 mm) = 5e-10 mm,
    # is within the 1 nm tolerance, so it is one move to its end, its arc the chord's length
    # (to 2 mm * (1 + (1 / 1e9)^2 / 6): the same float64)
    program = parse_program("G90 G21\nG00 X0 Y0 Z1.\nG02 X2. Y0 R1000000000. F100.\nM30\n")
    assert len(program) == 2
    assert program.targets[-1, :2].tolist() == [0.002, 0.0]
    assert program.arc_lengths[-1] == pytest.approx(0.002, rel=1e-15)


@pytest.mark.parametrize("word", [f"I1{'0' * 310}.", f"R1{'0' * 310}."])
def test_a_centre_or_radius_word_beyond_float64_is_named_once(word):
    # 1e310 mm written out: the word's own refusal had been wrapped by the arc's, 'a.nc,
    # line 3, column 12, key ...: a.nc, line 3, column 12, key ...: value of ...'
    with pytest.raises(NCProgramError) as caught:
        parse_program(f"G90 G21\nG00 X0 Y0 Z1.\nG02 X2. Y0 {word} F100.\nM30\n", "a.nc")
    assert (caught.value.line, caught.value.column) == (3, 12)
    assert str(caught.value).count("a.nc, line 3") == 1
    assert str(caught.value).endswith("is out of range (not finite in float64)")


def test_an_arc_past_the_moves_left_says_what_they_are_left_of(monkeypatch):
    """An arc that would take the program past its most moves (`MAX_MOVES`, lowered here
    to 4000) is refused naming the moves left: 4000 less the 2 before it. The message had
    said 'more than the 3998 left; raise the chord tolerance' only, where a subprogram's
    repeats had used the moves (`M98 P2 L9999` around a full circle)."""
    monkeypatch.setattr("machinesim.nc.arc_block.MAX_MOVES", 4000)
    text = "G21 G90 G17\nG00 X0 Y0 Z0\nG01 X0.1 F100.\nG02 X0.1 Y0 I5.\n"
    with pytest.raises(NCProgramError, match=r"the arc \(radius 5 mm, 360 deg\) needs 4968 "
                       "segments") as caught:
        parse_program(text, chord_tolerance=1e-9)
    assert "more than the 3998 moves left of the most a program may expand to; raise the " \
           "chord tolerance, or, where the moves before it are many" in str(caught.value)
