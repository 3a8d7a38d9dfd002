"""`lathe.turn` against what a new user throws at it: points on the spindle axis, programs
beyond the axes' travel, errors that lift the tool off the part, errors as a dict or a TOML
file, an errors file with a bad value."""

import re

import numpy as np
import pytest

import machinesim
import machinesim.cam.spiral as sp
from machinesim.cutting.lathe import turn
from machinesim.errors import ErrorModel
from machinesim.exceptions import AxisLimitError, InputError

RS, R, FEED, TOP = 2e-3, 1e-3, 1e-6, 1e-6


@pytest.fixture(scope="module")
def tool_path():
    spiral = sp.Spiral(0.12e-3, FEED)
    return sp.tool_path(sp.cutting_points(sp.sphere(RS), spiral,
                                          sp.constant_angle(spiral, 0.02)), R)


@pytest.fixture(scope="module")
def program(tool_path):
    return sp.spiral_program(tool_path)


def test_a_nominal_tool_cuts_the_points_on_the_spindle_axis(program):
    # the poses of a tool on the centre height carry ~1e-17 m of round-off in the edge
    # plane's offset; taken as a centre-height error it left an uncut core that wide, and a
    # point at r = 0 or 1e-18 m read the stock's top (1 um) instead of the cut surface
    part, _ = turn(program, "sts_lathe", "nose:1.0:90", top=TOP)
    scallop = (FEED * (1 + R / RS)) ** 2 / (8 * R)  # nose centres f (1 + R/Rs) apart
    near = part.heights_at([1e-9], [1e-9])[0]
    assert abs(near) < scallop  # the sphere's top, z = 0, plus at most a scallop
    for r in (0.0, 1e-18, 1e-16):
        assert abs(part.heights_at([r], [r])[0] - near) <= scallop, r


def test_a_facing_cut_of_many_turns_from_far_out_cuts_the_axis_too():
    # 500 turns from X = 1 mm to the axis: the poses' round-off in the offset grows with the
    # angle and the radius (2.2e-15 m here, beyond the absolute 1e-15 m), was read as a
    # varying centre height, and the axis and the last crossing along the end angle kept the
    # stock's top (0 nm on the axis for -1000 nm; 15 nm high at r = 3.4 um with dx = 10 um)
    from machinesim.nc import parse_program

    program = parse_program("G90 G21\nG00 X1.0 Z0.01 C0\nG01 Z-0.001 F10\n"
                            "G01 X0 C180000 F36000\nG01 Z0.01\n")
    part, _ = machinesim.Lab("sts_lathe", noise=False).turn(program, "nose:1.0:90")
    scallop = 1e-6 ** 2 / (8 * R)  # 1 um a turn under a 1 mm nose: 0.5 nm
    for r in (0.0, 1e-18, 1e-16, 1e-9):
        assert -1e-6 <= part.heights_at([r], [0.0])[0] <= -1e-6 + scallop, r
    # with the tool 10 um past the centre (dx), the lowest point of the nose passes r = 10 um
    # at the end angle theta = 0: the groove's floor there is the nose circle about it
    lab = machinesim.Lab("sts_lathe", {"tool": {"offset_um": [10.0, 0.0, 0.0]}}, noise=False)
    part, _ = lab.turn(program, "nose:1.0:90")
    r = np.array([3.4e-6, 5e-6])
    hand = -1e-6 + (R - np.sqrt(R ** 2 - (10e-6 - r) ** 2))
    np.testing.assert_allclose(part.heights_at(r, np.zeros(2)), hand, rtol=0, atol=1e-12)


def test_a_rapid_below_the_stocks_top_is_noted_a_retract_is_not():
    # the turning engine cuts the runs of feeds that turn C: a rapid across at cutting depth
    # left no trace and no word (z(0.3 mm) = -246 nm, two runs, notes empty)
    from machinesim.nc import parse_program

    lab = machinesim.Lab("sts_lathe", noise=False)
    head = "G90 G21\nG00 X1.0 Z0.01 C0\nG01 Z-0.001 F10\n"
    across = parse_program(head + "G01 X0.5 C1800 F36000\nG00 X0.4 C1900\nG01 X0 C3600\n"
                           "G00 Z0.01\n")
    _, report = lab.turn(across, "nose:1.0:90")
    (note,) = report.notes
    assert note.startswith("rapids with the tip below the stock's top (z = 0 um) at line 5:")
    plunge = parse_program("G90 G21\nG00 X1.0 Z0.01 C0\nG00 Z-0.001\nG01 X0 C3600 F36000\n")
    assert "at line 3:" in lab.turn(plunge, "nose:1.0:90")[1].notes[0]
    out = parse_program(head + "G01 X0 C3600 F36000\nG00 Z0.01\nG00 X2.\n")
    assert lab.turn(out, "nose:1.0:90")[1].notes == ()  # straight up out of the cut, then over


def test_a_nominal_tool_test_reads_no_uncut_core():
    # the interferometer's maps are symmetric about the origin and have a pixel on the axis:
    # it read the stock's top, and |dy| came out as one pixel, sqrt(pitch^2 / pi) = 0.28 um
    from machinesim.procedures.sts_plans import TEST_SPHERE
    from machinesim.procedures.sts_turning import STSTurning

    found = STSTurning().measure(machinesim.Lab("sts_lathe", noise=False))["tool_test"]
    assert found.dy_abs < 0.01 * TEST_SPHERE.pixel
    assert abs(found.dx) < 1e-9 and abs(found.dy) < 1e-9


def _line_of_extreme(program, axis: str, largest: bool) -> int:
    """The program line at which ``axis`` takes its largest (or least) value."""
    column = program.targets[:, "XYZABC".index(axis)]
    index = np.nanargmax(column) if largest else np.nanargmin(column)
    return int(program.lines[index])


@pytest.mark.parametrize("start_c", [99990.0, -1e6])
def test_turn_refuses_a_spindle_angle_beyond_its_travel_naming_the_line(tool_path, start_c):
    # sts_lathe's C travels +-1e5 rad (5729577.95131 deg); the spiral turns 120 times from
    # start_c: 99990 + 754 rad ends beyond it, -1e6 starts beyond it
    program = sp.spiral_program(tool_path, start_c=start_c)
    worst = _line_of_extreme(program, "C", largest=start_c > 0)
    value = np.degrees(program.targets[:, 5][program.lines == worst][0])
    with pytest.raises(AxisLimitError, match=(
            rf"axis C = {value:.5f} deg at line {worst} outside its travel "
            r"-5729577\.95131 deg \.\. 5729577\.95131 deg .*nothing was cut")):
        turn(program, "sts_lathe")


def test_turn_refuses_a_radius_beyond_the_x_travel_unless_allowed():
    # a facing spiral of 150 mm radius on X's +-100 mm travel: refused at its first line
    # (the rapid to X 150 mm); allowed, it is turned and listed, as `cut` lists it
    spiral = sp.Spiral(0.15, 1e-3)
    path = sp.tool_path(sp.cutting_points(sp.tilted_plane(0.0), spiral,
                                          sp.constant_angle(spiral, 0.5)), R)
    program = sp.spiral_program(path)
    first = int(program.lines[0])
    with pytest.raises(AxisLimitError, match=rf"axis X = 150\.000000 mm at line {first} "
                                             r"outside its travel -100\.000000 mm \.\. "
                                             r"100\.000000 mm"):
        turn(program, "sts_lathe")
    _, report = turn(program, "sts_lathe", allow_overtravel=True)
    assert len(report.limit_violations) == 1
    assert report.limit_violations[0].startswith(f"axis X = 150.000000 mm at line {first}")
    # through a lab too
    import machinesim

    lab = machinesim.Lab("sts_lathe", noise=False)
    with pytest.raises(AxisLimitError, match="axis X = 150"):
        lab.turn(program)
    _, by_lab = lab.turn(program, allow_overtravel=True)
    assert by_lab.limit_violations == report.limit_violations


@pytest.mark.parametrize("lift", [{"tool.z": 0.5}, {"workpiece.z": -1.0}])
def test_a_turn_that_never_reaches_the_stock_reports_an_empty_cut(program, tool_path, lift):
    # the tool set 0.5 m up, or the workpiece 1 m down: the tip's lowest point is the
    # program's lowest Z plus that, far above the stock's top; nothing is cut
    # (a lab's note does not say how far: that is its errors, tests/test_lab_texts.py)
    errors = ErrorModel().with_parameters(lift)
    above = (tool_path.z.min() + abs(next(iter(lift.values()))) - TOP) * 1e6
    for (part, report), how_far in (
            (turn(program, "sts_lathe", "nose:1.0:90", errors, top=TOP),
             f"{above:.6g} um or more above"),
            (machinesim.Lab("sts_lathe", errors, noise=False).turn(program, top=TOP),
             "above")):
        assert report.empty_cut
        assert report.notes == (
            f"nothing was cut: the tool's tip stays {how_far} the stock's "
            f"top (z = {TOP * 1e6:.6g} um) throughout; does the program reach the stock, and "
            "do the errors set the tool too high or the workpiece too low (tool.z, "
            "workpiece.z)?",)
        assert (part.heights([-1e-4, 0.0, 5e-5], [0.0, 3e-5]) == TOP).all()
    _, nominal = turn(program, "sts_lathe", "nose:1.0:90", top=TOP)
    assert not nominal.empty_cut and nominal.notes == () and nominal.limit_violations == ()


def test_turn_takes_errors_as_a_model_a_dict_or_a_toml_file(program, tmp_path):
    table = {"tool": {"offset_um": [0.7, -1.2, 0.0]}, "tool_geometry": {"nose_radius_um": 3.0}}
    path = tmp_path / "errors.toml"
    path.write_text("[tool]\noffset_um = [0.7, -1.2, 0.0]\n\n"
                    "[tool_geometry]\nnose_radius_um = 3.0\n")
    x = np.linspace(2e-5, 1e-4, 9)
    y = np.full_like(x, 3e-6)
    model, _ = turn(program, "sts_lathe", "nose:1.0:90", ErrorModel.from_dict(table), top=TOP)
    expected = model.heights_at(x, y)
    assert model.tool.nose_radius == pytest.approx(R + 3e-6, abs=1e-18)
    for errors in (table, path, str(path)):
        part, _ = turn(program, "sts_lathe", "nose:1.0:90", errors, top=TOP)
        np.testing.assert_array_equal(part.heights_at(x, y), expected)


def test_a_bad_nose_radius_in_an_errors_file_names_the_file(program, tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text("[tool_geometry]\nnose_radius_mm = -1.0\n")
    with pytest.raises(InputError, match=(
            rf"^{path}, line 2, key 'tool_geometry\.nose_radius_mm': the error model's "
            r"tool_geometry\.nose_radius_mm = -1 does not fit the RoundNoseTool")):
        turn(program, "sts_lathe", "nose:1.0:90", path)
    with pytest.raises(InputError, match=r"^key 'tool_geometry\.nose_radius': the error "
                                         r"model's tool_geometry\.nose_radius = -0\.001 m"):
        turn(program, "sts_lathe", "nose:1.0:90",
             ErrorModel().with_parameters({"tool_geometry.nose_radius": -1e-3}))


def test_turn_refuses_a_program_that_is_not_one():
    with pytest.raises(InputError, match="Expected program as a machinesim.nc.Program or an "
                                         "NC file's path, got int"):
        turn(3, "sts_lathe")
    # the program's text where its path belongs: the whole text came back as a missing file
    with pytest.raises(InputError, match=r"expected the NC program's path, got text of 3 "
                                         r"lines \('G90 G21' \.\.\.\): read text with "
                                         r"machinesim.nc.parse_program\(text\)"):
        turn("G90 G21\nG00 X1.0 Z0.01 C0\n", "sts_lathe")


def test_turn_and_heights_refuse_what_is_not_a_number(program):
    # top=None ended in float()'s TypeError, top="0" was read as 0; text as px in numpy's
    # ValueError
    for top in (None, "0", [0.0]):
        with pytest.raises(InputError, match=r"key 'top': Expected top as a number \(m\)"):
            turn(program, "sts_lathe", "nose:1.0:90", top=top)
    part, _ = turn(program, "sts_lathe", "nose:1.0:90", top=TOP)
    with pytest.raises(InputError, match=r"key 'px': Expected px as numbers \(m\), got \['a'\]"):
        part.heights_at(["a"], [0.0])
    assert part.heights_at([1e-9], [0.0])[0] == pytest.approx(0.0, abs=1e-9)
    # heights on a grid: text ended in numpy's "could not convert string to float", True
    # was read as 1 m
    with pytest.raises(InputError, match=r"key 'y': Expected y as numbers \(m\), got 'abc'"):
        part.heights([0.0, 1e-4], "abc")
    with pytest.raises(InputError, match=r"key 'x': Expected x as numbers \(m\), got \[True"):
        part.heights([True, False], [0.0])
    np.testing.assert_array_equal(part.heights([1e-9, 2e-4], [0.0]),
                                  part.heights_at([1e-9, 2e-4], [0.0, 0.0])[None])


def test_turn_refuses_a_top_not_finite_or_a_metre_away(program):
    # top=1e300 was turned without a word: every point the edge never reached read a stock
    # 1e300 m high; a top in um given as m (5 for 5e-6) likewise
    for top in (1e300, -1e300, 5.0, -1.5, float("inf"), float("nan")):
        with pytest.raises(InputError, match=r"key 'top': Expected (a finite top|top within "
                                             r"\+-1 m .*was it given in mm or um\?\), got)"):
            turn(program, "sts_lathe", "nose:1.0:90", top=top)
    lab = machinesim.Lab("sts_lathe", noise=False)
    with pytest.raises(InputError, match=r"key 'top': Expected top within \+-1 m"):
        lab.turn(program, top=1e300)
    # a metre is still a top (the bound itself), a part the tool never reaches: empty
    _, report = turn(program, "sts_lathe", "nose:1.0:90", top=-1.0)
    assert report.empty_cut


def test_a_spindle_angle_just_past_its_travel_prints_apart_from_the_travel():
    # C 1e5 rad is 5729577.95131 deg to five decimals: value and travel printed alike
    from machinesim.nc import parse_program

    program = parse_program("G90 G21\nG00 X1.0 Z0.01 C0\nG01 Z-0.001 F10\n"
                            "G01 X0 C5729577.95131 F36000\n")
    with pytest.raises(AxisLimitError, match=r"axis C = 5729577\.951310 deg at line 4 outside "
                                             r"its travel -5729577\.951308 deg \.\. "
                                             r"5729577\.951308 deg"):
        turn(program, "sts_lathe", "nose:1.0:90")


def test_a_program_that_runs_the_spindle_by_m03_says_that_is_not_simulated(tmp_path):
    # a conventional lathe program (M03 S500, then X and Z feeds) was refused as "no feed
    # move turns C: nothing to turn", with no word on why its spindle did not count
    conventional = tmp_path / "conventional.nc"
    conventional.write_text("G90 G21\nM03 S500\nG00 X0.5 Z0.1 C0\nG01 Z-0.005 F10\n"
                            "G01 X0 F10\nG00 Z1\nM30\n")
    with pytest.raises(InputError, match=r"no feed move turns C: nothing to turn \(M03 at "
                       r"line 2 runs the spindle at S rpm, which is not simulated: program "
                       r"C as an axis"):
        turn(conventional, "sts_lathe", "nose:0.5:90")
    still = tmp_path / "still.nc"  # no M03: the refusal as before, without the hint
    still.write_text("G90 G21\nG00 X0.5 Z0.1 C0\nG01 Z-0.005 F10\nG01 X0 F10\nM30\n")
    with pytest.raises(InputError, match=r"nothing to turn$"):
        turn(still, "sts_lathe", "nose:0.5:90")


def test_a_turning_move_without_a_feed_is_refused_naming_its_line():
    """A program built from arrays (`Program.from_arrays`, feeds NaN by default) whose
    turning move (the facing, line 4) has no feed: refused naming the program and the
    line, as the reader names an F0 (the message named neither)."""
    from machinesim.nc import parse_program
    from machinesim.nc.program import Program

    read = parse_program("G90 G21\nG00 X1.0 Z0.01 C0\nG01 Z-0.001 F10\nG01 X0 C720 F360\n"
                         "G01 Z0.01\n", "facing.nc")
    # no feeds at all (a linear move without one after one with one is refused on building)
    built = Program.from_arrays(read.targets, read.kinds, lines=read.lines, source="built.nc")
    with pytest.raises(InputError, match=r"built.nc, line 4: expected a positive feed on "
                                         r"every turning move, got none"):
        turn(built, "sts_lathe", "nose:1.0:90")


def test_the_lathe_s_own_refusals_name_the_block_s_n_word_beside_its_line(tmp_path):
    # the refusals of turn() that name a line (no feed on a turning move, a feed move before
    # every axis is known, the M03 hint) name its block's N word too, 'line 4 (N40)', as the
    # reader's refusals do; they had named the line alone
    from machinesim.nc import parse_program
    from machinesim.nc.program import Program

    read = parse_program("N10 G90 G21\nN20 G00 X1.0 Z0.01 C0\nN30 G01 Z-0.001 F10\n"
                         "N40 G01 X0 C720 F360\nN50 G01 Z0.01\n", "facing.nc")
    built = Program.from_arrays(read.targets, read.kinds, lines=read.lines,
                                block_numbers=read.block_numbers, source="built.nc")
    with pytest.raises(InputError, match=r"built.nc, line 4 \(N40\): expected a positive "
                                         r"feed on every turning move, got none"):
        turn(built, "sts_lathe", "nose:1.0:90")
    early = tmp_path / "early.nc"  # X and C known, Z not yet: a feed move before it
    early.write_text("N10 G90 G21\nN20 G00 X0.5 C0\nN30 G01 X0.4 F10\nN40 G00 Z0.1\n"
                     "N50 G01 X0 C720 F360\nM30\n")
    with pytest.raises(InputError, match=r"early.nc, line 3 \(N30\): a feed move before "
                                         r"every axis of sts_lathe has a value"):
        turn(early, "sts_lathe", "nose:0.5:90")
    conventional = tmp_path / "conventional.nc"
    conventional.write_text("G90 G21\nN20 M03 S500\nG00 X0.5 Z0.1 C0\nG01 Z-0.005 F10\n"
                            "G01 X0 F10\nG00 Z1\nM30\n")
    with pytest.raises(InputError, match=r"nothing to turn \(M03 at line 2 \(N20\) runs "
                                         r"the spindle at S rpm"):
        turn(conventional, "sts_lathe", "nose:0.5:90")


def test_a_turning_feed_far_too_slow_is_refused_at_once_not_followed_for_days(tmp_path):
    # F0.0001 deg/min on a 9000 deg move: 9e7 min = 5.4e9 s, 5.4e13 periods of a 10 kHz
    # loop, which the servo loops were simulated through without a word (hours per axis)
    from machinesim.servo import table6_servo

    path = tmp_path / "slow.nc"
    path.write_text("G90 G21\nG00 X0.05 Z0.01 C0\nG01 Z-0.001 F10\nG01 X0 C9000 F0.0001\nM30\n")
    _, report = turn(path, "sts_lathe", "nose:1.0:90")  # no servo: a time, not a simulation
    # the turning move alone, C in degrees as mm (FANUC), at 0.0001 mm/min
    assert report.machining_time_s == pytest.approx(np.hypot(9000.0, 0.05) / 0.0001 * 60.0,
                                                    rel=1e-12)
    with pytest.raises(InputError, match=r"servo loop of axis x: a motion of 5\.4e\+09 s is "
                                         r"5\.4e\+13 loop periods of 0\.0001 s, more than the "
                                         r"1e\+09 .*27\.8 h.*feed far too slow"):
        turn(path, "sts_lathe", "nose:1.0:90", servo=table6_servo("before"))


ONE_TURN = "G01 Z-0.001 F10\nG01 X0.5 C360. F36000\nG00 Z0.01\n"


@pytest.mark.parametrize(("machine", "start", "named"), [
    ("grooving_4axis", "X1.0 Y0 Z0.01 C0", ["C travels -360 .. 360 deg", "axis Y, "]),
    ("robonano_ui", "X1.0 Y0 Z0.01 A0 B0 C0", ["C travels -360 .. 360 deg", "axes Y, A, B, "]),
    ("robonano_a0ib", "X1.0 Y0 Z0.01 B0 C0", ["C travels -360 .. 360 deg", "axes Y, B, "]),
    ("planer_4axis", "X1.0 Y0 Z0.01 A0", ["no C axis", "axes Y, A, "]),
])
def test_turn_refuses_a_machine_that_is_not_a_lathe(machine, start, named):
    # a turn of C facing from X 1 mm to 0.5 mm: grooving_4axis, robonano_ui and
    # robonano_a0ib turned it (their table C goes one turn either way; two turns were
    # refused only as beyond C's travel), with Y, A, B beside X, Z and C
    program = machinesim.nc.parse_program(f"G90 G21\nG00 {start}\n{ONE_TURN}")
    with pytest.raises(InputError, match="Expected a lathe") as refused:
        turn(program, machine, allow_overtravel=True)
    assert refused.value.key == "machine"
    for words in [f"{machine} (axes ", *named]:
        assert words in str(refused.value)
    if machine != "planer_4axis":  # a lab's turn is the same turn
        with pytest.raises(InputError, match="Expected a lathe"):
            machinesim.Lab(machine, noise=False).turn(program)


@pytest.mark.parametrize(("old", "new", "named"), [
    ('lower="-100000.0" upper="100000.0"',
     'lower="-6.283185307179586" upper="6.283185307179586"',
     r"its C travels -360 \.\. 360 deg: a table's travel, not a work spindle's"),
    ('<axis xyz="0.0 0.0 -1.0"/>\n    <limit lower="-100000.0"',
     '<axis xyz="0.0 -1.0 0.0"/>\n    <limit lower="-100000.0"', "its C turns about Y, not Z"),
])
def test_turn_refuses_a_lathe_whose_c_is_no_work_spindle_about_z(tmp_path, old, new, named):
    # sts_lathe with its C cut to one turn either way (X, Z, C as a lathe's, but no spindle,
    # which is what `cut` tells turning by, `Axis.spindle`), or turning about Y (the URDF
    # loads it): both were turned; the same file as shipped turns
    from machinesim.machines import models_dir

    text = (models_dir() / "sts_lathe.urdf").read_text()
    other = text.replace(old, new)
    assert other != text
    (tmp_path / "other.urdf").write_text(other)
    (tmp_path / "lathe.urdf").write_text(text)
    program = machinesim.nc.parse_program(f"G90 G21\nG00 X1.0 Z0.01 C0\n{ONE_TURN}")
    with pytest.raises(InputError, match=rf"\(axes X, Z, C\): {named}"):
        turn(program, machinesim.load_machine(tmp_path / "other.urdf"))
    _, report = turn(program, machinesim.load_machine(tmp_path / "lathe.urdf"))
    assert report.runs == 1 and report.revolutions == pytest.approx(1.0)


@pytest.mark.parametrize("far_mm", [1e12, 1e9, 1000010.0])
def test_turn_refuses_a_move_beyond_a_km_even_with_overtravel_allowed(far_mm):
    # as `cut` refuses it (machinesim.cutting.engine.FARTHEST_M): a facing run out to
    # X = 1e9 m (a length in the wrong unit) was turned with allow_overtravel, 81 points,
    # and listed only as overtravel; the tip there is X from the spindle axis, 1 um deep
    program = machinesim.nc.parse_program(
        f"G90 G21\nG00 X1.0 Z0.01 C0\nG01 Z-0.001 F10\nG01 X{far_mm:.1f} C3600. F36000\n"
        "G01 X0.0 C7200.\nG00 Z0.01\n")
    distance = np.hypot(far_mm, 0.001) * 1e-3
    far = re.escape(f"the move takes the tool {distance:.3g} m from the workpiece origin")
    with pytest.raises(InputError, match=rf"line 4: {far}; expected within 1000 m"):
        turn(program, "sts_lathe", allow_overtravel=True)
    with pytest.raises(InputError, match=far):
        machinesim.Lab("sts_lathe", noise=False).turn(program, allow_overtravel=True)


def test_a_move_too_far_to_square_is_refused_with_its_distance():
    # 1e200 mm written out (1e197 m): its distance by np.linalg.norm squared to inf, and the
    # refusal said 'the move takes the tool inf m ... (its spacing there is nan m)'
    program = machinesim.nc.parse_program(
        f"G90 G21\nG00 X1.0 Z0.01 C0\nG01 Z-0.001 F10\nG01 X1{'0' * 200}. C3600. F36000\n"
        "G01 X0.0 C7200.\nG00 Z0.01\n")
    with pytest.raises(InputError) as caught:
        turn(program, "sts_lathe", allow_overtravel=True)
    assert caught.value.line == 4
    assert "the move takes the tool 1e+197 m from the workpiece origin" in str(caught.value)
    assert "its spacing there is 1.7e+181 m" in str(caught.value)


def test_a_move_within_a_km_is_turned_and_one_before_the_start_is_refused_too():
    # 999.99 m is within FARTHEST_M: turned with allow_overtravel, X listed beyond its travel
    near = machinesim.nc.parse_program(
        "G90 G21\nG00 X1.0 Z0.01 C0\nG01 Z-0.001 F10\nG01 X999990.0 C3600. F36000\n"
        "G01 X0.0 C7200.\nG00 Z0.01\n")
    _, report = turn(near, "sts_lathe", allow_overtravel=True)
    assert report.runs == 1 and report.limit_violations[0].startswith("axis X = 999990.0")
    # a rapid 1e9 m out before every axis has a value (the machine is at its home, Z at the
    # top of its travel, until the program names an axis), which nothing turns
    early = machinesim.nc.parse_program(f"G90 G21\nG00 X1000000000000.0\nG00 X1.0 Z0.01 C0\n"
                                        f"{ONE_TURN}")
    with pytest.raises(InputError, match=r"line 2: the move takes the tool 1e\+09 m"):
        turn(early, "sts_lathe", allow_overtravel=True)


def test_the_lathes_notes_name_a_line_with_its_block_number_as_refusals_do():
    # the turn's notes named bare lines ("at lines 5", "the feed move of line 3", "the dwell
    # of line 4") where its refusals and the cut name "line 5 (N50)" (Program.line_text)
    from machinesim.nc import parse_program

    lab = machinesim.Lab("sts_lathe", noise=False)
    program = parse_program("G90 G21\nN20 G00 X1.0 Z0.01 C0\nN30 G01 Z-0.001 F0.000001\n"
                            "N40 G04 P3700.\nN50 G01 X0.5 C1800 F36000\nN60 G00 X0.4 C1900\n"
                            "N70 G01 X0 C3600\nN80 G00 Z0.01\n")
    notes = lab.turn(program, "nose:1.0:90")[1].notes
    assert [n[:n.index(" takes") if "takes" in n else n.index(" waits") if "waits" in n
              else n.index(":")] for n in notes] == [
        "rapids with the tip below the stock's top (z = 0 um) at line 6 (N60)",
        "the feed move of line 3 (N30)", "the dwell of line 4 (N40) (P3700.)"]
    # plan names them as the lathe does
    plan_notes = machinesim.motion.plan(program, lab.machine).notes
    assert [n for n in plan_notes if "feed move" in n or "dwell" in n] == list(notes[1:])


def test_a_move_that_only_kept_an_arc_length_is_noted_by_its_own_length_as_plan_times_it():
    # a G02 plunge (R10 mm in XZ at F0.001, 10 um chords of 0.8727 mm of arc: 52,360 s
    # each, under a day) cut at its fifth chord after the move to X10 Z0: that move goes
    # hypot(10 - 5.7738, 0.9369) = 4.329 mm, 259,728 s (72.1 h) by plan, but the lathe's
    # note took the 0.8727 mm of arc it kept (52,360 s) and said nothing
    from machinesim.motion import plan
    from machinesim.nc import Program, parse_program

    arc = parse_program("G90 G21 G18\nG00 X10. Z0. C0.\nG01 X10. F0.001\n"
                        "G02 X10. Z-20. R10.\nM30\n", chord_tolerance=1e-5)
    k = int(np.flatnonzero(arc.lines == 4)[4])
    face = parse_program("G90 G21\nG01 X9. Z-20. C360. F10.\nM30\n")
    program = Program.from_moves(arc.moves[:2] + arc.moves[k:] + tuple(face.moves),
                                 source="cut.nc")
    by_hand = np.hypot(*(arc.targets[k, [0, 2]] - [0.01, 0.0])) / (0.001e-3 / 60.0)
    assert by_hand == pytest.approx(2.597e5, rel=1e-3)
    assert plan(program, "sts_lathe").segments[2].duration == pytest.approx(by_hand, rel=1e-9)
    _, report = turn(program, "sts_lathe")
    assert any(note.startswith("the feed move of line 4 takes 2.6e+05 s (72.1 h) at F0.001")
               for note in report.notes)
    # the whole arc, each chord a chord of it: no note (52,360 s a chord), as before
    whole = Program.from_moves(arc.moves[:] + tuple(face.moves), source="arc.nc")
    _, report = turn(whole, "sts_lathe")
    assert not any("feed move" in note for note in report.notes)
