"""The FANUC dialect's positions, tool length and states (issue 12): G28 through its
intermediate point, G53 in machine coordinates, tool length offsets from a table (a bare
G43, an offset without a table), tool words and changes, tool table refusals, the states a
program selects (G05.1, Haas G103 and G187, a safe-start line), G50 refused and every
refusal listed at once. Expected values worked out by hand."""

from __future__ import annotations

import re

import numpy as np
import pytest

from machinesim.exceptions import MachineSimError, NCProgramError
from machinesim.nc import KIND_RAPID, ToolTable, parse_program

MM = 1e-3
#: Targets are a decimal in mm times 1e-3 (plus offsets): float64 round-off is far below this,
#: and it is 10^6 x below 1 nm, so any misreading fails.
EXACT_M = 1e-15


TOOLS = {"tool": {"1": {"length_mm": 50.0, "radius_mm": 3.0},
                  "2": {"length_um": 2500.0, "radius_mm": 0.5, "name": "ball"}}}


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
    Z carries the change, and the incremental moves after it agree (a G28 Z or a G53 Z
    cancels the offset on Z instead: the next test)."""
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
        "G90 G00 X0 Z10.\nG43 H2\nG49 X1.\nG91 Z-1.\n",  # changed back: nothing waits
    ]]
    assert z == pytest.approx([0.5, 9.0], abs=1e-12)


def test_a_g49_after_g28_z_or_g53_z_changes_no_length():
    """G28 Z and G53 Z cancel the tool length offset vector on Z, G43 staying modal (FANUC
    Series 0i-MB B-63844EN/02, 14.1.2), so the G49 a Fusion 360 FANUC post writes after its
    G28 G91 Z0. changes nothing, and the next tool's G00 X Y runs at the reference on a FANUC
    as here. It had been refused as a change of the whole length (-2.5 mm), every program
    of such a post with a tool table whose lengths are not 0."""
    for retract, z in (("G28 G91 Z0.\nG90", 0.0), ("G53 Z20.", 20.0)):
        text = (f"G90 G00 X0 Y0\nT2 M06\nG43 Z10. H2\n{retract}\nG49\nT1 M06\n"
                "G00 X10. Y15.\nG43 Z15. H1\nM30\n")
        program = parse_program(text, tools=TOOLS)
        assert program.targets[-2:, :3].ravel().tolist() == pytest.approx(
            [10 * MM, 15 * MM, z * MM, 10 * MM, 15 * MM, 65 * MM], abs=EXACT_M)
    # there a G43 H2 changes the length from 0: FANUC lifts Z 2.5 mm in its block
    with pytest.raises(NCProgramError, match=r"X10\. moves without Z after G43 H2 at line 4, "
                                             r"which changed the tool length offset by "
                                             r"\+2.5 mm"):
        parse_program("G90 G00 X0 Y0\nG43 Z10. H1\nG28 G91 Z0.\nG90 G43 H2\nG00 X10.\n",
                      tools=TOOLS)


@pytest.mark.parametrize("retract", ["G28 G91 Z0.", "G91 G28 Z0", "G53 Z20."])
def test_an_incremental_z_after_g28_z_or_g53_z_with_a_length_offset_modal_is_refused(retract):
    """After G28 Z or G53 Z the offset vector on Z is cancelled, G43 H2 staying modal
    (FANUC B-63844EN/02, 14.1.2); a FANUC restores it with the next Z move, so an
    incremental Z there ends H2's 2.5 mm apart from a control that kept the offset. It had
    run (G28 G91 Z0. then G01 Z-5.: 95 mm, the reference less 5, with G43 H1)."""
    text = f"G90 G00 X0 Y0\nG43 Z10. H2\n{retract}\nG91 G01 Z-5. F100.\n"
    with pytest.raises(NCProgramError, match=r"incremental Z-5\. after the G28 Z or G53 Z at "
                                             r"line 3, which cancelled the tool length offset "
                                             r"on Z while G43 H2 \(2\.5 mm\) stayed "
                                             r"modal") as info:
        parse_program(text, tools=TOOLS, reference={"Z": 0.1})
    assert (info.value.line, info.value.key) == (4, "Z-5.")
    # an absolute Z restores it on every control; incremental moves after it are read
    program = parse_program(text.replace("G91 G01 Z-5.", "G90 G00 Z20.\nG91 G01 Z-5."),
                            tools=TOOLS, reference={"Z": 0.1})
    assert program.targets[-1, 2] == pytest.approx(17.5 * MM, abs=EXACT_M)
    # with G49 in force nothing was cancelled that a move could restore
    parse_program(text.replace(retract, f"{retract}\nG49"), tools=TOOLS,
                  reference={"Z": 0.1})


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
        # digits other than ASCII's, which str.isdigit() passed: '²' was an internal
        # ValueError of int(), '١' (Arabic-Indic) and '１' (full width) read as tool 1
        ({"tool": {"\u00b2": {"length_mm": 5.0}}}, "unsigned integer up to 99999999, got '²'"),
        ({"tool": {"\u0661": {"length_mm": 5.0}}}, "unsigned integer up to 99999999, got '١'"),
        ({"tool": {"\uff11": {"length_mm": 5.0}}}, "unsigned integer up to 99999999, got '１'"),
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
    # an M06 before any T had been passed over, the cut going on with --tool unsaid: which
    # tool it puts in is the control's, refused at its line (without a table, a state)
    with pytest.raises(NCProgramError, match="M06 with no tool selected before it") as info:
        parse_program("G21 G90\nM06\nG00 X0 Y0 Z0\nT1 M06\nM30", "m06.nc", tools=table)
    assert (info.value.source, info.value.line, info.value.key) == ("m06.nc", 2, "M06")
    assert parse_program("G21 G90\nM06\nG00 X0 Y0 Z0\nM30").tool_changes == ()


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


def test_fanuc_g05_p10000_high_precision_contour_control_is_a_state():
    # 'G05 P10000' / 'G05 P0', as posts for 16i/18i-class controls write it (Mastercam's
    # FANUC post, Makino), had been refused as an unknown G code: it smooths the control's
    # path as G05.1 Q1 does, and the programmed path cut here is the same without it
    text = "G90 G21\nG05 P10000\nG00 X1. Y0 Z1.\nG5 P00000\nX2.\nM30"
    program = parse_program(text)
    assert dict(program.states) == {"G05 P10000": 2, "G05 P0": 4}
    assert program.targets[:, 0].tolist() == [1 * MM, 2 * MM]
    # its other P numbers are high-speed cycle (P1) and binary (P3) operation, whose path is
    # data stored in the control: refused, as a P with a point (FANUC's P takes none)
    for block, column, key in (("G05 P1", 5, "P1"), ("G05 P3", 5, "P3"), ("G05", 1, "G05"),
                               ("G05 P10000.", 5, "P10000.")):
        with pytest.raises(NCProgramError, match="G05 is read as FANUC's high-precision "
                                                 r"contour control, P10000 \(on\) or P0 "
                                                 r"\(off\), got .*: its other P numbers run "
                                                 "high-speed cycle") as info:
            parse_program(f"{block}\nG00 X0")
        assert (info.value.line, info.value.column, info.value.key) == (1, column, key)
    with pytest.raises(NCProgramError, match=r"G05 stands in a block of its own \(with "
                                             r"P10000 or P0\), found X1\.$"):
        parse_program("G05 P10000 X1.")


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


def test_g97_spindle_speed_in_rpm_is_read_as_the_program_without_it():
    # posts write `G97 S1000 M03` (S in rpm, as every S is read here): it had been refused
    # as an unknown G code, and with it the whole program
    body = "G00 X1. Y2. Z3.\nG01 X4. F100.\nM30"
    with_g97 = parse_program(f"G21 G90\nG97 S1000 M03\n{body}")
    without = parse_program(f"G21 G90\nS1000 M03\n{body}")
    assert np.array_equal(with_g97.targets, without.targets, equal_nan=True)
    assert np.array_equal(with_g97.feeds, without.feeds, equal_nan=True)
    assert with_g97.kinds.tolist() == without.kinds.tolist()
    assert np.array_equal(with_g97.spindles, without.spindles, equal_nan=True)
    assert dict(with_g97.m_codes) == dict(without.m_codes)


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
    # G54.1's P1 is its own word, not refused again (`words.OWN_WORDS`)
    assert located == [(2, 5, "G95"), (2, 9, "G54.1"), (3, 11, "#"),
                       (4, 1, "G41"), (5, 9, "U3."), (5, 13, "E4."), (6, 1, "M99"),
                       (7, 1, "X1.2.3"), (7, 8, "Z--1")]
    message = str(info.value)
    assert message.startswith("cam.nc, line 2, column 5, key 'G95': 9 problems")
    # a later problem may be a consequence of an earlier refused block: the message says so
    assert "a later problem may follow from an earlier one: mend them in order" in message
    for line, column, key in located:
        assert f"line {line}, column {column}, key '{key}'" in message


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
