"""The FANUC dialect of issue 12: arcs, G28/G53, tool length, states, canned cycles,
subprograms, integer input, and every refusal at once; expected values worked out by hand."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from machinesim.exceptions import MachineSimError, NCProgramError
from machinesim.motion import move_duration
from machinesim.nc import (
    ARC_RADIUS_TOLERANCE_M,
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
from machinesim.nc.cycles import CHIP_BREAK_RETRACT_M, PECK_CLEARANCE_M

MM = 1e-3
#: Targets are a decimal in mm times 1e-3 (plus offsets): float64 round-off is far below this,
#: and it is 10^6 x below 1 nm, so any misreading fails.
EXACT_M = 1e-15
#: Points of an arc are centre + r (cos, sin): float64 round-off ~1e-18 m at 10 mm; the
#: issue's bound for "on the circle".
ON_CIRCLE_M = 1e-12
TOOLS = {"tool": {"1": {"length_mm": 50.0, "radius_mm": 3.0},
                  "2": {"length_um": 2500.0, "radius_mm": 0.5, "name": "ball"}}}


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


# --- G28, G53, tool length, states


def test_g28_returns_to_the_reference_position_it_is_given():
    """With a reference position (the machine's home, machine coordinates), G28 goes there
    instead of machine zero: the CAM header's G28 G91 Z0 lifts Z to 100 mm, G28 X Y moves X
    through 20 mm to 30 mm (its reference) and Y to zero; a bad reference is refused."""
    text = "G91 G28 Z0\nG90 G00 X10. Y5. Z3.\nG28 X20. Y0\n"
    program = parse_program(text, reference={"Z": 0.1, "X": 30 * MM})
    t = program.targets
    assert t[0, 2] == 0.1
    assert t[-2, :2].tolist() == [20 * MM, 0.0]  # the intermediate point
    assert t[-1, :3].tolist() == [30 * MM, 0.0, 3 * MM]
    with pytest.raises(NCProgramError, match="unknown axis 'W'"):
        parse_program(text, reference={"W": 0.1})
    with pytest.raises(NCProgramError, match="reference must be a mapping"):
        parse_program(text, reference=0.1)


def test_g28_goes_through_the_intermediate_point_to_machine_zero():
    offsets = {"G54": {"X": 100 * MM, "Y": 50 * MM, "Z": -20 * MM}}
    text = "G91 G28 Z0\nG90 G00 X10. Y5. Z3.\nG28 X20. Y0\nG91 G28 Z1.\n"
    program = parse_program(text, work_offsets=offsets)
    assert program.targets[0, 2] == 0.0  # unknown Z, incremental 0: straight to zero
    assert len(program) == 6
    t = program.targets
    assert t[2, :2].tolist() == pytest.approx([120 * MM, 50 * MM], abs=EXACT_M)  # via point
    assert t[3, :3].tolist() == [0.0, 0.0, -17 * MM]  # X Y at machine zero, Z untouched
    assert t[4, 2] == pytest.approx(-16 * MM, abs=EXACT_M)  # incremental intermediate point
    assert t[5, 2] == 0.0
    assert np.all(program.kinds == KIND_RAPID)
    assert program.lines.tolist() == [1, 2, 3, 3, 4, 4]


def test_g53_moves_in_machine_coordinates_for_one_block():
    offsets = {"G54": {"X": 100 * MM, "Z": -20 * MM}}
    program = parse_program("G00 X1. Z1.\nG43 H1 Z2.\nG53 G00 X-1. Z-2.\nG00 X3.",
                            work_offsets=offsets, tools=TOOLS)
    t = program.targets
    assert t[1, 2] == pytest.approx((2 + 50 - 20) * MM, abs=EXACT_M)
    assert t[2, [0, 2]].tolist() == [-1 * MM, -2 * MM]  # no work offset, no tool length
    assert t[3, 0] == pytest.approx(103 * MM, abs=EXACT_M)  # the next block: G54 again


@pytest.mark.parametrize("tools", [TOOLS, "toml"])
def test_tool_length_offsets_z_words(tools, tmp_path):
    if tools == "toml":
        path = tmp_path / "tools.toml"
        path.write_text("[tool.1]\nlength_mm = 50.0\n[tool.2]\nlength_um = 2500.0\n")
        tools = path
    text = ("G00 X0 Z100.\nG43 H2 Z10.\nZ5.\nG91 Z-1.\nG90 G44 H1 Z10.\nG49 Z10.\n"
            "G43 X1. Z10.")  # X without Z after the change is refused (tests/test_nc_tape.py)
    program = parse_program(text, tools=tools)
    z = program.targets[:, 2] / MM
    assert z.tolist() == pytest.approx([100, 12.5, 7.5, 6.5, -40, 10, 60], abs=1e-12)


def test_an_incremental_z_after_a_tool_length_change_is_refused():
    """FANUC (TOS = 0) moves Z by a G43/G44/G49 change in its own block; LinuxCNC carries it
    with the next absolute Z. After G43 H2 (2.5 mm) from Z10, G91 Z-12 ends at machine
    Z 0.5 mm on the first and -2 mm on the second: refused, not read as either. An absolute
    Z, a G28 Z or a G53 Z carries the change, and the incremental moves after it agree."""
    for text, line, key in [
        ("G90 G00 X0 Z10.\nG91 G43 H2 Z0\n", 2, "Z0"),
        ("G90 G00 X0 Z10.\nG43 H2\nG91 G01 Z-12. F100.\n", 3, "Z-12."),
        ("G90 G00 X0 Y0 Z10.\nG43 H2\nG91 G02 X10. Z-1. I5. F100.\n", 3, "Z-1."),
        ("G90 G00 X0 Y0 Z10.\nG43 H2\nG91 G81 X1. R-5. Z-2. F100.\n", 3, "R-5."),
        ("G90 G00 X0 Z10.\nG43 H2 Z10.\nG49\nG91 Z-1.\n", 4, "Z-1."),
    ]:
        with pytest.raises(NCProgramError, match="tool length offset by [+-]2.5 mm, before "
                           "any absolute Z: controls differ") as info:
            parse_program(text, "tlo.nc", tools=TOOLS)
        assert (info.value.line, info.value.key) == (line, key)
    z = [parse_program(text, tools=TOOLS).targets[-1, 2] / MM for text in [
        "G90 G00 X0 Z10.\nG43 H2\nG01 Z10. F100.\nG91 Z-12.\n",  # absolute Z carries it
        "G90 G00 X0 Z10.\nG43 H2\nG91 G28 Z0\nZ-12.\n",  # at the reference (0)
        "G90 G00 X0 Z10.\nG43 H2\nG53 Z20.\nG91 Z-12.\n",  # a machine position
        "G90 G00 X0 Z10.\nG43 H2\nG49 X1.\nG91 Z-1.\n",  # changed back: nothing waits
    ]]
    assert z == pytest.approx([0.5, -12.0, 8.0, 9.0], abs=1e-12)


def test_tool_words_are_checked_against_the_table():
    with pytest.raises(NCProgramError, match="H7: tool 7|no length for tool 7") as info:
        parse_program("G00 Z0\nG43 H7 Z1.", tools=TOOLS)
    assert (info.value.line, info.value.key) == (2, "H7")
    with pytest.raises(NCProgramError, match="T9: tool 9 is not in the tool table"):
        parse_program("T9 M06", tools=TOOLS)
    with pytest.raises(NCProgramError, match="needs tool 1's length, and no tool table"):
        parse_program("G43 H1")
    program = parse_program("T9 M06\nD4\nG43 H0 G00 Z1.")  # no table: T D listed, H0 = 0
    assert dict(program.states) == {"T9": 1, "D4": 2}
    assert program.targets[-1, 2] == pytest.approx(1 * MM, abs=EXACT_M)


def test_tool_table_refusals(tmp_path):
    for data, message in [
        ({"tool": {"1": {"length": 5.0}}}, "unknown key 'length'"),
        ({"tool": {"1": {"length_in": 5.0}}}, "unknown length unit 'in'"),
        ({"tool": {"x": {"length_mm": 5.0}}}, "tool number must be an unsigned integer"),
        ({"tool": {"1": {"radius_mm": -1.0}}}, "must be >= 0"),
        ({"tool": {"1": {"length_mm": float("nan")}}}, "must be a finite number"),
        # TOML reads 10**400 exactly (1329 bits): it was an internal OverflowError
        ({"tool": {"1": {"length_mm": 10**400}}}, "integer of 1329 bits, beyond float64"),
        ({"tools": {}}, "only \\[tool.<number>\\]"),
        ({"tool": {"1": {"shape": 0.5}}}, "shape must be a tool spec string"),
        ({"tool": {"1": {"shape": "drill:3"}}}, "tool spec 'drill:3': expected"),
        ({"tool": {"1": {"shape": "ball:1e9"}}}, "tool spec 'ball:1e9'"),
    ]:
        with pytest.raises(NCProgramError, match=message):
            ToolTable.from_dict(data)
    bad = tmp_path / "bad.toml"
    bad.write_text("[tool.1\n")
    with pytest.raises(NCProgramError, match="not valid TOML"):
        ToolTable.from_toml(bad)
    with pytest.raises(MachineSimError, match="no such file"):
        ToolTable.from_toml(tmp_path / "missing.toml")


@pytest.mark.parametrize(("text", "line", "key", "message"), [
    ("# tools\n[tool.1]\nlength_mm = 0.0\n\n[tool.2]\nlength = 5.0\n", 6, "tool.2.length",
     "unknown key 'length'"),
    ("[tool.1]\nlength_mm = 0.0\nradius_in = 0.5\n", 3, "tool.1.radius_in",
     "unknown length unit 'in'"),
    ("\n[tool.two]\nlength_mm = 0.0\n", 2, "tool.two", "got 'two'"),
    ('[tool.1]\nlength_mm = 0.0\nshape = "ball:-1"\n', 3, "tool.1.shape",
     "tool spec 'ball:-1'"),
    ("[tool.1]\nlength_mm = 0.0\n[tool.01]\nlength_mm = 1.0\n", 3, "tool",
     "tool 1 is given twice, as [tool.1] and [tool.01]; expected each tool number once"),
    ("\n\n[tools.1]\nlength_mm = 0.0\n", 3, "tool", "got ['tools']"),
])
def test_a_tool_table_file_refusal_names_the_line(tmp_path, text, line, key, message):
    # a tool table's refusals named the file and key alone, an --errors file's the line too
    # (the line of the key or table as an editor counts it, here known by hand)
    table = tmp_path / "tools.toml"
    table.write_text(text)
    with pytest.raises(NCProgramError) as caught:
        ToolTable.from_toml(table)
    assert (caught.value.source, caught.value.line, caught.value.key) == (str(table), line, key)
    assert str(caught.value).startswith(f"{table}, line {line}, key '{key}': ")
    assert message in str(caught.value)


def test_tool_changes_follow_t_and_m06():
    # T preselects, M06 puts the last selected tool in (T2 is selected during T1's run and
    # changed at line 4; T3 is selected but never changed); the change starts at the move
    # after the M06 and carries the table's length and shape.
    table = {"tool": {"1": {"length_mm": 1.0, "shape": "ball:0.5"},
                      "2": {"length_um": 2500.0}, "3": {"length_mm": 0.0}}}
    text = "G00 X0\nT1 M06\nG01 X1. F100 T2\nM06\nX2.\nT3\nX3.\nM30"
    program = parse_program(text, tools=table)
    changes = [(c.number, c.line, c.length_m, c.shape) for c in program.tool_changes]
    assert changes == [(1, 2, 1 * MM, "ball:0.5"), (2, 4, 2.5 * MM, None)]
    moves = [c.move for c in program.tool_changes]
    assert program.lines[moves].tolist() == [3, 5]  # each tool's first move, after the M06
    # a turret (no M06): every T is a change, where it stands
    turret = parse_program("G00 X0\nT1\nX1.\nT2 X2.\nM30", tools=table)
    assert [(c.number, c.line) for c in turret.tool_changes] == [(1, 2), (2, 4)]
    assert parse_program(text).tool_changes == ()  # without a table T is a state only


def test_states_are_listed_with_their_first_line():
    text = ("G90 G94 G17 G49 G40 G80\nG05.1 Q1\nG08 P1\nG61\nG64\nT1 M06\nG05.1 Q0\n"
            "G05.1 Q1 R5\nG40\nG00 X0\nM30")
    program = parse_program(text)
    assert dict(program.states) == {"G40": 1, "G80": 1, "G05.1 Q1": 2, "G08 P1": 3, "G61": 4,
                                    "G64": 5, "T1": 6, "G05.1 Q0": 7, "G05.1 Q1 R5": 8}
    assert len(program) == 2  # the M06 dwell and the move: states move nothing


def test_g05_1_reads_a_q_with_a_decimal_point_as_its_value():
    # 'G05.1 Q1.', as programs and G-code lists write it, had been refused as if no Q1 were
    # there ('G05.1 needs Q1 (on) or Q0 (off)'): FANUC reads a Q given with a point as its
    # value, so Q1. (Q1.0) is on and Q0. (Q0.000) off, the same states as Q1 and Q0
    text = "G05.1 Q1.\nG05.1 Q0.\nG05.1 Q1.0 R5\nG05.1 Q0.000\nG00 X0\nM30"
    assert dict(parse_program(text).states) == {"G05.1 Q1": 1, "G05.1 Q0": 2,
                                                "G05.1 Q1 R5": 3}
    # any other number is still no setting, and the message says what came
    for q in ("Q2", "Q1.5", "Q10."):
        with pytest.raises(NCProgramError, match=rf"G05.1 needs Q1 \(on\) or Q0 \(off\), "
                                                 rf"got {re.escape(q)}$"):
            parse_program(f"G05.1 {q}\nG00 X0")
    # G08's P takes no point on a FANUC control (as G04's P): refused, saying so
    with pytest.raises(NCProgramError, match=r"G08 needs P1 \(on\) or P0 \(off\), got P1\.: "
                                             r"a FANUC control takes no decimal point in P "
                                             r"here \(write P1\)"):
        parse_program("G08 P1.\nG00 X0")


def test_haas_g103_look_ahead_limit_is_a_state_with_p0_to_p15():
    # a Haas post's G103 P1 (look-ahead limited to one block) had been refused as an unknown
    # G code, and with it the program; Haas's manual gives P the range 0-15, and G103 alone
    # (or P0) lifts the limit: states, moving nothing
    text = "G90 G21\nG103 P1\nG00 X0\nN40 G103 P15\nG103\nG103 P0\nX1.\nM30"
    program = parse_program(text)
    assert dict(program.states) == {"G103 P1": 2, "G103 P15": 4, "G103": 5, "G103 P0": 6}
    assert program.targets[:, 0].tolist() == [0.0, 1 * MM]
    for p, hint in (("P16", ""), ("P1.", r" \(write P1: a Haas takes a whole number here\)"),
                    ("P-1", "")):
        with pytest.raises(NCProgramError, match=rf"line 1, column 6, key '{re.escape(p)}': "
                                                 rf"G103's P is the most blocks the control "
                                                 rf"looks ahead \(0: no limit\), P0..P15, "
                                                 rf"got {re.escape(p)}{hint}$"):
            parse_program(f"G103 {p}\nG00 X0")
    with pytest.raises(NCProgramError, match=r"line 1 \(N5\), column 12, key 'X1\.': G103 "
                                             r"stands in a block of its own \(with P0..P15 "
                                             r"or nothing\), found X1\.$"):
        parse_program("N5 G103 P1 X1.")


def test_haas_g187_smoothness_and_corner_rounding_is_a_state_with_p1_to_p3_and_e():
    # a Haas post's G187 P3 E0.0004 (finish smoothness, 0.0004 in corner rounding) had been
    # refused as an unknown G code (and E as an unknown letter): P1..P3 rough, medium,
    # finish, E a distance >= 0, and G187 alone returns to the settings (Haas)
    text = ("G90 G20\nG187 P3 E0.0004\nG00 X0\nG187 P1 E+.01\nG187\nG187 P2\n"
            "G187 E0.\nX1.\nM30")
    program = parse_program(text)
    assert dict(program.states) == {"G187 P3 E0.0004": 2, "G187 P1 E.01": 4, "G187": 5,
                                    "G187 P2": 6, "G187 E0.": 7}
    assert program.targets[:, 0].tolist() == [0.0, 25.4 * MM]
    for p in ("P0", "P4", "P3.", "P-2"):
        with pytest.raises(NCProgramError, match=rf"G187's P is the smoothness level \(1 "
                                                 rf"rough, 2 medium, 3 finish\), P1..P3, got "
                                                 rf"{re.escape(p)}"):
            parse_program(f"G187 {p}\nG00 X0")
    with pytest.raises(NCProgramError, match=r"column 9, key 'E-0\.01': G187's E is the "
                                             r"maximum corner rounding, a distance >= 0, got "
                                             r"E-0\.01$"):
        parse_program("G187 P3 E-0.01\nG00 X0")
    # E in any other block is still an unknown letter (X1e5 is no number here), named once
    for text in ("G00 X1e5", "G103 P1 E1."):
        with pytest.raises(NCProgramError, match=r"unknown word letter 'E'; .* and E in a "
                                                 r"G187 block \(Haas's maximum corner "
                                                 r"rounding\)$"):
            parse_program(text)
    with pytest.raises(NCProgramError, match=r"G187 stands in a block of its own \(with "
                                             r"P1..P3, E or nothing\), found M08$"):
        parse_program("G187 P3 M08")


def test_a_safe_start_line_cancelling_what_is_refused_is_read_as_states():
    # Haas's safe-start line and a FANUC shop header: G50, G69 and G15 cancel scaling,
    # coordinate rotation and polar coordinates, whose codes (G51, G68, G16) are refused, so
    # they set the state the reader keeps. They had been refused as unknown G codes, and with
    # them the whole program.
    text = ("O1\nG00 G17 G40 G49 G50 G69 G80 G90\nG15 G21\nG00 X1. Y2. Z3.\n"
            "G01 X4. F100.\nM30")
    program = parse_program(text)
    assert dict(program.states) == {"G40": 2, "G50": 2, "G69": 2, "G80": 2, "G15": 3}
    assert np.array_equal(program.targets[:, :3], np.array([[1.0, 2.0, 3.0],
                                                            [4.0, 2.0, 3.0]]) * MM)
    assert program.kinds.tolist() == [0, 1]
    # the codes they cancel stay refused, each by name
    for code in ("G51", "G68", "G16"):
        with pytest.raises(NCProgramError, match=rf"\({code}\) is not supported"):
            parse_program(f"G00 X0\n{code}\nM30")


def test_g50_with_axis_words_is_a_lathe_coordinate_setting_and_refused():
    # on a FANUC lathe (G code system A) G50 X Z sets the coordinates, as G92 does on a
    # mill: read as the milling dialect's scaling cancel, its X Z words would move the tool
    with pytest.raises(NCProgramError) as info:
        parse_program("G00 X1. Z1.\nG50 X100. Z50.\nM30", "turn.nc")
    assert (info.value.line, info.value.column, info.value.key) == (2, 1, "G50")
    assert "G50 with axis words sets the coordinates" in str(info.value)


def test_every_refusal_is_listed_at_once():
    text = ("O1 (a CAM file with what machinesim refuses)\n"
            "G90 G95 G54.1 P1\n"
            "G00 X0 Y0 #5\n"
            "G41 D1 G01 X1. F100\n"
            "G01 X2. U3. E4.\n"
            "M99\n"
            "X1.2.3 Z--1\n"
            "M30\n")
    with pytest.raises(NCProgramError) as info:
        parse_program(text, "cam.nc")
    located = [(e.line, e.column, e.key) for e in info.value.problems]
    assert located == [(2, 5, "G95"), (2, 9, "G54.1"), (2, 15, "P1"), (3, 11, "#"),
                       (4, 1, "G41"), (5, 9, "U3."), (5, 13, "E4."), (6, 1, "M99"),
                       (7, 1, "X1.2.3"), (7, 8, "Z--1")]
    message = str(info.value)
    assert message.startswith("cam.nc, line 2, column 5, key 'G95': 10 problems")
    # a later problem may be a consequence of an earlier refused block: the message says so
    assert "a later problem may follow from an earlier one: mend them in order" in message
    for line, column, key in located:
        assert f"line {line}, column {column}, key '{key}'" in message


# --- canned cycles


def test_drilling_cycles_expand_to_fanuc_sequences():
    text = ("G00 X0 Y0 Z10.\n"
            "G98 G81 X5. Y5. Z-2. R1. F100.\n"
            "G99 G82 X6. Z-1.5 R0.5 P250\n"
            "G98 G83 X7. Z-3. R1. Q1.2\n"
            "G80 X8.\n")
    program = parse_program(text)
    moves = [(MOVE := ("rapid", "linear", "dwell")[k], *(t[[0, 2]] / MM), d)
             for k, t, d in zip(program.kinds, program.targets, program.dwells, strict=True)]
    del MOVE
    c = PECK_CLEARANCE_M / MM
    expected = [
        ("rapid", 0, 10, 0),
        ("rapid", 5, 10, 0), ("rapid", 5, 1, 0), ("linear", 5, -2, 0), ("rapid", 5, 10, 0),
        ("rapid", 6, 10, 0), ("rapid", 6, 0.5, 0), ("linear", 6, -1.5, 0),
        ("dwell", 6, -1.5, 0.25), ("rapid", 6, 0.5, 0),  # G99: back to R
        ("rapid", 7, 0.5, 0), ("rapid", 7, 1, 0),
        ("linear", 7, -0.2, 0), ("rapid", 7, 1, 0), ("rapid", 7, -0.2 + c, 0),
        ("linear", 7, -1.4, 0), ("rapid", 7, 1, 0), ("rapid", 7, -1.4 + c, 0),
        ("linear", 7, -2.6, 0), ("rapid", 7, 1, 0), ("rapid", 7, -2.6 + c, 0),
        ("linear", 7, -3, 0), ("rapid", 7, 10, 0),  # G98: the initial level of G81
        ("rapid", 8, 10, 0),  # after G80 a plain move
    ]
    assert len(moves) == len(expected)
    for got, want in zip(moves, expected, strict=True):
        assert got[0] == want[0]
        assert got[1:] == pytest.approx(want[1:], abs=1e-12)


def test_incremental_cycle_with_repeats_drills_a_row():
    # G91: R from the initial level, Z from R; K4 drills four holes 3 mm apart in X
    program = parse_program("G00 X0 Y0 Z5.\nG91 G99 G81 X3. Z-2. R-4. K4 F50")
    bottoms = program.targets[program.kinds == KIND_LINEAR]
    assert bottoms[:, 0].tolist() == pytest.approx([3 * MM, 6 * MM, 9 * MM, 12 * MM])
    assert np.all(bottoms[:, 2] == pytest.approx(-1 * MM, abs=EXACT_M))
    assert program.targets[-1, 2] == pytest.approx(1 * MM, abs=EXACT_M)  # G99: at R


def test_a_cycle_carried_into_g91_drills_with_r_and_z_restated_there():
    """G81 begun in G90 (R1, Z-2 from Z5) and repeated in G91 with R and Z given again:
    R-4 from the initial level is the same R plane at 1 mm, Z-3 from it the same bottom at
    -2 mm, one hole 2 mm further along X. (Left unstated, they are refused: controls differ
    on what the kept numbers mean in G91.)"""
    program = parse_program("G00 X2. Y2. Z5.\nG98 G81 X2. Y2. Z-2. R1. F50.\n"
                            "G91 X2. Z-3. R-4.")
    bottoms = program.targets[program.kinds == KIND_LINEAR]
    assert bottoms[:, 0].tolist() == pytest.approx([2 * MM, 4 * MM])
    assert bottoms[:, 2].tolist() == pytest.approx([-2 * MM, -2 * MM], abs=EXACT_M)


def test_p_in_a_g81_block_is_kept_for_the_cycle_and_moves_as_without_it():
    # 'G81 ... P100' had been refused ("word P is only read with G04, G82 ..."): FANUC keeps
    # P, as Z R Q, as the cycle's data until G80, and G81 does not dwell. The holes are those
    # of the block without P; a G82 later in the cycle dwells the kept 100 ms
    head = "G21 G90 G17\nG00 X0 Y0 Z5.\n"
    with_p = parse_program(head + "G98 G81 X1. Y1. Z-1. R1. P100 F100.\nX2.\nG80\n")
    without = parse_program(head + "G98 G81 X1. Y1. Z-1. R1. F100.\nX2.\nG80\n")
    for name in ("kinds", "targets", "dwells", "lines"):
        np.testing.assert_array_equal(getattr(with_p, name), getattr(without, name))
    assert not np.any(with_p.dwells)
    kept = parse_program(head + "G98 G81 X1. Y1. Z-1. R1. P100 F100.\nG82 X2.\nG80\n")
    assert kept.dwells.tolist().count(0.1) == 1
    assert kept.kinds[kept.dwells == 0.1].tolist() == [KIND_DWELL]
    assert kept.targets[kept.dwells == 0.1, 2] == pytest.approx(-1 * MM, abs=EXACT_M)


def test_a_motion_code_cancels_the_cycle():
    program = parse_program("G00 Z5.\nG81 X1. Z-1. R1. F10\nG00 X2.\nX3.")
    assert program.targets[-2:, 0].tolist() == [2 * MM, 3 * MM]
    assert program.targets[-1, 2] == pytest.approx(5 * MM, abs=EXACT_M)


# --- subprograms


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
    with pytest.raises(NCProgramError, match="nests deeper than 10 levels"):
        parse_program(chain)
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


# --- integer input, arrays, files


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


def test_high_speed_peck_drilling_breaks_the_chip_within_the_hole():
    # G73 (FANUC's high-speed peck, as Fusion 360's and Haas posts write chip breaking):
    # feed Q, rapid back up by d (parameter 5114; CHIP_BREAK_RETRACT_M), feed Q further from
    # the last depth, to Z; then G99's R. It had been refused, and with it every program
    # that drills so. From R1 in pecks of 0.8 to -1: 0.2, -0.6, -1
    program = parse_program("G00 X0 Y0 Z5.\nG99 G73 X1. Y2. Z-1. R1. Q0.8 F100.\nG80\n")
    rows = program.lines == 2
    kinds = [("rapid", "linear")[k] for k in program.kinds[rows]]
    z = program.targets[rows][:, 2] / MM
    d = CHIP_BREAK_RETRACT_M / MM
    assert kinds == ["rapid", "rapid", "linear", "rapid", "linear", "rapid", "linear", "rapid"]
    assert z == pytest.approx([5, 1, 0.2, 0.2 + d, -0.6, -0.6 + d, -1, 1], abs=1e-12)
    assert np.max(np.abs(program.targets[rows][:, :2] / MM - [1, 2])) <= 1e-12
    assert d == 0.1  # within the hole: every retract stays below R and above the bottom
    with pytest.raises(NCProgramError, match="G73 needs a peck depth Q > 0"):
        parse_program("G00 X0 Y0 Z5.\nG73 X1. Y2. Z-1. R1. F100.\n")


@pytest.mark.parametrize("code", ["G83", "G73"])
def test_haas_variable_peck_i_j_k_and_its_dwell_p_are_read(code):
    # Haas's G73/G83 I (first peck) J (reduction per peck) K (smallest peck) and P (dwell
    # after the last peck) had been refused ("word I is only read with G02/G03 ..."). From
    # R1 to Z-1 with I0.5 J0.1 K0.2: pecks 0.5, 0.4, 0.3, then 0.2 on, ending at
    # 0.5, 0.1, -0.2, -0.4, -0.6, -0.8, -1 mm; then 500 ms at the bottom. The next hole
    # (X2., no P) pecks and dwells alike: Haas keeps P until the cycle is cancelled
    program = parse_program(f"G00 X0 Y0 Z5.\nG98 {code} X1. Y1. Z-1. R1. I0.5 J0.1 K0.2 "
                            "P500 F100.\nX2.\nG80\n")
    for line in (2, 3):
        rows = program.lines == line
        linear = program.targets[rows & (program.kinds == KIND_LINEAR)]
        assert linear[:, 2] / MM == pytest.approx([0.5, 0.1, -0.2, -0.4, -0.6, -0.8, -1],
                                                  abs=1e-12)
        # the dwell follows the last peck, at the bottom, and the hole ends at the
        # initial level (G98)
        kinds, z = program.kinds[rows], program.targets[rows][:, 2] / MM
        assert kinds[-2] == KIND_DWELL and program.dwells[rows][-2] == 0.5
        assert z[-2:] == pytest.approx([-1, 5], abs=1e-12)
        assert np.count_nonzero(program.dwells[rows]) == 1
    # K is the smallest peck here, not a repeat count: one hole per block
    assert np.count_nonzero(program.kinds[program.lines == 2] == KIND_LINEAR) == 7
    # a P carried from G82 does not make a peck cycle dwell (FANUC's G73/G83 take no P)
    carried = parse_program(f"G00 X0 Y0 Z5.\nG82 X1. Z-1. R1. P500 F100.\n{code} X2. "
                            "I0.5 J0.1 K0.2\nG80\n")
    assert np.count_nonzero(carried.dwells[carried.lines == 3]) == 0


@pytest.mark.parametrize("block, seconds", [
    ("G83 X1. Z-1. R1. Q0.5 P5. F100.", 5.0),  # Haas's own example's P5.: five seconds
    ("G73 X1. Z-1. R1. Q0.5 P.25 F100.", 0.25),
    ("G83 X1. Z-1. R1. I0.5 J0.1 K0.2 P2.5 F100.", 2.5),
    ("G82 X1. Z-1. R1. P1.5 F100.", 1.5),
    ("G83 X1. Z-1. R1. Q0.5 P500 F100.", 0.5),  # without a point: ms, as before
])
def test_a_cycle_dwell_with_a_decimal_point_is_seconds_as_haas_reads_it(block, seconds):
    # Haas's G83 'P5.' (96-8000: "dwell for five seconds at the end") had been refused
    # ("dwell time must be an unsigned integer ..."); a FANUC control takes no point in P
    program = parse_program(f"G00 X0 Y0 Z5.\nG98 {block}\nX2.\nG80\n")
    for line in (2, 3):  # kept for the cycle's next hole
        rows = program.lines == line
        assert program.dwells[rows].tolist().count(seconds) == 1
        assert np.count_nonzero(program.dwells[rows]) == 1
        # at the bottom, after the last peck
        dwell = np.flatnonzero(program.kinds[rows] == KIND_DWELL)[0]
        assert program.targets[rows][dwell - 1, 2] / MM == pytest.approx(-1, abs=1e-12)
    with pytest.raises(NCProgramError) as info:
        parse_program("G00 X0 Y0 Z5.\nG83 X1. Z-1. R1. Q0.5 P-5. F100.\n")
    assert (info.value.line, info.value.key) == (2, "P-5.")
    assert "G83's dwell P-5. must be >= 0 (with a decimal point P is seconds" in str(info.value)


@pytest.mark.parametrize("rule", ["calculator", "increment", "is-b", "is-c"])
@pytest.mark.parametrize("units", ["G21", "G20"])
def test_g04_p_with_a_decimal_point_is_seconds_without_milliseconds_as_haas_reads_it(
        rule, units):
    # Haas 96-8000, G04: 'G04 P10.' is a dwell of 10 seconds, 'G04 P10' one of 10
    # milliseconds. 'G04 P10.' had been refused ("G04 P takes integer milliseconds, got
    # P10.; use G04 X<seconds>") while a cycle's P10. was read as 10 s. Neither the unit
    # nor the integer-input rule (which scales a bare X) changes a P; under G91 it is a time
    text = (f"{units} G00 X1.\nG04 P10.\nG04 P10\nG91 G04 P.25\nG04 P1.5\nG04 X1.5\n"
            "G90 G04 P0.\nM30\n")
    program = parse_program(text, integer_input=rule)
    assert program.dwells.tolist() == [0.0, 10.0, 0.010, 0.25, 1.5, 1.5, 0.0]
    assert program.kinds.tolist() == [KIND_RAPID] + [KIND_DWELL] * 6
    assert len(set(program.targets[:, 0].tolist())) == 1  # no dwell moves X
    # the same reading as a cycle's P10.: ten seconds at the bottom of G82
    cycle = parse_program(f"{units} G00 X0 Y0 Z5.\nG82 X1. Z-1. R1. P10. F100.\nG80\n",
                          integer_input=rule)
    assert cycle.dwells[cycle.kinds == KIND_DWELL].tolist() == [10.0]


def test_haas_g73_with_q_and_a_decimal_k_returns_to_r_after_pecks_adding_up_to_k():
    # Haas 96-8000, G73: with both K and Q "the tool is returned to the R plane after a
    # number of passes totals up to the K amount". 'K1.' had been refused as a repeat count
    # ("repeat count must be an unsigned integer ..., got K1."). From R1 to Z-3 in pecks of
    # 0.5 with K1.: back to R after the pecks ending at 0, -1 and -2 (each 1 mm below the
    # last return), then down to PECK_CLEARANCE_M above that depth; a chip break elsewhere
    program = parse_program("G00 X0 Y0 Z5.\nG98 G73 X1. Z-3. R1. Q0.5 K1. F100.\nX2.\n"
                            "G80\n")
    d, c = CHIP_BREAK_RETRACT_M / MM, PECK_CLEARANCE_M / MM
    expected = [(0, 5), (0, 1), (1, 0.5), (0, 0.5 + d), (1, 0)]
    for depth in (0, -1, -2):
        expected += [(0, 1), (0, depth + c), (1, depth - 0.5), (0, depth - 0.5 + d),
                     (1, depth - 1)]
    expected.append((0, 5))  # then up to G98's initial level
    for line in (2, 3):  # modal: the next hole alike, one hole each (K is no repeat here)
        rows = program.lines == line
        kinds = [int(k) for k in program.kinds[rows]]
        z = program.targets[rows][:, 2] / MM
        assert kinds == [KIND_RAPID if k == 0 else KIND_LINEAR for k, _ in expected]
        assert z == pytest.approx([v for _, v in expected], abs=1e-12)
    # a Q without K drills as plain G73 again; K with a point elsewhere is refused by name
    plain = parse_program("G00 X0 Y0 Z5.\nG73 X1. Z-3. R1. Q0.5 K1. F100.\nX2. Q0.5\n")
    up = [np.count_nonzero(plain.targets[plain.lines == line][:, 2] / MM > 0.9)
          for line in (2, 3)]
    assert up == [6, 3]  # positioning, R, 3 returns to R and the initial level; then none
    for block, key, message in [
            ("G83 X1. Z-3. R1. Q0.5 K1.", "K1.", "not in G83"),
            ("G81 X1. Z-3. R1. K2.", "K2.", "so it is no repeat count"),
            ("G73 X1. Z-3. R1. Q0.5 K0.", "K0.", "must be > 0, got K0.")]:
        with pytest.raises(NCProgramError) as info:
            parse_program(f"G00 X0 Y0 Z5.\n{block} F100.\n")
        assert (info.value.line, info.value.key) == (2, key)
        assert message in str(info.value)


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


@pytest.mark.parametrize("block, code", [
    ("G99 G85 X1. Y1. Z-1. R0.25 F100.", "G85"),  # a public program's boring cycle
    ("G98 G84 X1. Y1. Z-1. R1. P200 F100.", "G84"),
    ("G98 G76 X1. Y1. Z-1. R1. Q0.1 P500 F100.", "G76"),
    ("G98 G87 X1. Y1. Z-1. R-3. I0.1 J0. Q0.1 F100.", "G87"),
])
def test_a_refused_cycle_is_one_problem_not_one_more_for_each_of_its_words(block, code):
    # the cycle's R, P, Q, I, J had each been a further problem ("word R is only read with
    # G02/G03 (radius), G81-G83 (R plane)"), as if the block held more than one mistake
    with pytest.raises(NCProgramError) as info:
        parse_program(f"G00 X0 Y0 Z5.\n{block}\n")
    problems = getattr(info.value, "problems", None) or [info.value]
    assert [(p.line, p.key) for p in problems] == [(2, code)]
    assert f"canned cycle {code}" in str(info.value)


def test_a_peck_typed_in_the_wrong_unit_is_refused_before_it_makes_thousands_of_moves():
    # 1.5 mm from R to Z in pecks of 0.1 um: 15000 pecks, each a sweep to cut
    with pytest.raises(NCProgramError, match="makes 15000 pecks in one hole"):
        parse_program("G00 X2. Y2. Z2.\nG83 X2. Y2. Z-1. R0.5 Q0.0001 F30.\n")
    # 1000 pecks of 1.5 um are a micro drill's and are read
    program = parse_program("G00 X2. Y2. Z2.\nG83 X2. Y2. Z-1. R0.5 Q0.0015 F30.\n")
    assert int(np.sum(np.asarray(program.kinds) == KIND_LINEAR)) == 1000


@pytest.mark.parametrize("data, expected", [
    ("G00 X1. Y1. Z1.\n".encode("utf-16"), "UTF-16 text"),
    ("G00 X1. Y1. Z1.\n".encode("utf-16-le"), "UTF-16 text"),
    (bytes(range(256)) * 8, "not a text file"),
    # without a byte-order mark, big-endian: the zero before each character
    ("G00 X1. Y1. Z1.\n".encode("utf-16-be"), "UTF-16 text"),
    # a binary full of zeros on both sides of each byte pair (little-endian integers, as an
    # executable or a binary PLY holds) is no UTF-16, and was called so
    (np.arange(1024, dtype="<i4").tobytes(), "not a text file"),
])
def test_a_file_that_is_not_utf8_text_is_refused_in_one_line(tmp_path, data, expected):
    path = tmp_path / "prog.nc"
    path.write_bytes(data)
    with pytest.raises(NCProgramError, match=expected) as info:
        read_program(path)
    assert "\n" not in str(info.value)


def test_a_control_byte_in_a_program_is_named_escaped_never_raw(tmp_path):
    path = tmp_path / "esc.nc"
    path.write_bytes(b"G00 X1. Y1. Z1.\nG00 X1.\x1b[31m Y5.\n")
    with pytest.raises(NCProgramError) as info:
        read_program(path)
    assert "\x1b" not in str(info.value) and "key '\\x1b'" in str(info.value)


# ----------------------------------------------------------- what public CAM posts write


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


def test_a_bare_g43_takes_the_last_h_and_is_refused_before_any():
    tools = ToolTable.from_dict({"tool": {"1": {"length_mm": 2.5}}})
    with pytest.raises(NCProgramError, match="G43 without H, and no H given before it") as e:
        parse_program("G90\nT1 M06\nG00 G43 Z10.\n", "bare.nc", tools=tools)
    assert e.value.line == 3
    # after G43 H1 and G49, a bare G43 is H1 again (FANUC's modal H): Z lifted by 2.5 mm
    program = parse_program("G90\nG00 G43 H1 Z10.\nG49 Z20.\nG43 Z10.\n", "h.nc",
                            tools=tools)
    assert program.targets[:, 2].tolist() == pytest.approx([12.5e-3, 20e-3, 12.5e-3])


def test_g53_is_measured_from_the_reference_position():
    # a post's G53 G0 Z0. goes to machine zero, where G28 goes: with a reference at the top
    # of Z (the command line's home) it retracts there, not onto the workpiece's zero
    text = "G90 G00 X1. Y1. Z5.\nG53 G00 Z0.\nG53 Z-10.\n"
    assert parse_program(text, "a.nc", reference={"Z": 0.1}).targets[1:, 2].tolist() == \
        pytest.approx([0.1, 0.09])
    assert parse_program(text, "b.nc").targets[1:, 2].tolist() == pytest.approx([0.0, -0.01])


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
    assert MAX_LINE_ITEMS == 10_000 and not hasattr(info.value, "problems")
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


def test_a_length_offset_without_a_tool_table_says_what_table_to_write(tmp_path):
    # 'G43 H3 needs the tool length: give a tool table (..., CLI --tools)' left a new user
    # to find the file's format; the table the message gives, pasted, reads the program
    text = "G90 G21\nG00 Z0\nG43 H3 Z5.\nM30\n"
    with pytest.raises(NCProgramError) as info:
        parse_program(text)
    message = str(info.value)
    assert (info.value.line, info.value.key) == (3, "H3")
    pasted = re.findall(r"'(\[tool\.\d+\]|length_mm = [0-9.]+)'", message)
    assert pasted == ["[tool.3]", "length_mm = 0.0"]
    assert "--tools tools.toml" in message and "docs/nc.md, 'Tool table'" in message
    table = tmp_path / "tools.toml"
    table.write_text("\n".join(pasted) + "\n")
    program = parse_program(text, tools=str(table))
    assert program.targets[-1, 2] == pytest.approx(5 * MM, abs=EXACT_M)  # length 0
