"""Turning through the lab: the program's spiral through the servo and the machine's errors
(tool setting, nose radius) to the turning engine, read by the white-light interferometer;
the control's encoders; the operator's tool adjustment; the nose radius in the error model."""

import math

import numpy as np
import pytest

import machinesim
import machinesim.cam.spiral as sp
from machinesim.cutting.lathe import turn, turning_runs
from machinesim.cutting.tool_form_error import alignment_error_x
from machinesim.cutting.turning import EdgePath, turned_heights
from machinesim.exceptions import ErrorModelError, InputError
from machinesim.metrology import WhiteLightInterferometer
from machinesim.metrology.fits import roughness_sa
from machinesim.metrology.imperfections import Spot
from machinesim.nc import parse_program
from machinesim.procedures.sts_plans import profile_error
from machinesim.realism import TOOL_ADJUSTER_RESOLUTION_M
from machinesim.servo import AxisServo, PIDServo

RS, FEED, RADIUS, R, RPM = 0.5e-3, 2e-6, 0.17e-3, 0.2e-3, 600.0
DESIGN = sp.sphere(RS)
TOOL = "nose:0.2:90"


@pytest.fixture(scope="module")
def tool_path():
    spiral = sp.Spiral(RADIUS, FEED)
    return sp.tool_path(sp.cutting_points(DESIGN, spiral, sp.constant_angle(spiral, 0.01)), R)


@pytest.fixture(scope="module")
def program(tool_path):
    return sp.spiral_program(tool_path, spindle_rpm=RPM)


def _points():
    x = np.linspace(0.02e-3, 0.15e-3, 40) + 3e-9
    return x, np.full_like(x, 1e-9)


def test_lab_turn_is_the_engine_along_the_erroneous_path(tool_path, program):
    # a second route: the engine on the edge path written by hand, tool set off by (dx, dy)
    # and a nose dR larger (eqs 12-20's conventions), against the lab's program -> kinematics
    dx, dy, dr = 0.7e-6, -1.2e-6, 3e-6
    errors = {"tool": {"offset_um": [dx * 1e6, dy * 1e6, 0.0]},
              "tool_geometry": {"nose_radius_um": dr * 1e6}}
    lab = machinesim.Lab("sts_lathe", errors, noise=False)
    part, report = lab.turn(program, TOOL, top=1e-6)
    px, py = _points()
    expected = turned_heights(EdgePath(tool_path.c, tool_path.x + dx, dy, tool_path.z),
                              R + dr, px, py, top=1e-6)
    np.testing.assert_allclose(part.heights_at(px, py), expected, rtol=0, atol=1e-15)
    with pytest.raises(InputError, match=r"two arrays of one length, got \d+ and 0 values"):
        part.heights_at(np.column_stack([px, py]), [])  # an (n, 2) array is two arrays
    assert report.runs == 1 and report.points == len(tool_path)
    turns = (tool_path.c[-1] - tool_path.c[0]) / (2 * np.pi)
    assert report.revolutions == pytest.approx(turns, rel=1e-12)
    assert report.machining_time_s == pytest.approx(turns / RPM * 60.0, rel=1e-6)
    # the interferometer reads the height field at its samples (noise off: 0.1 nm rounding)
    profile = lab.white_light_interferometer().profile(part, (0.02e-3, 1e-9), (0.15e-3, 1e-9),
                                                        1e-6)
    exact = part.heights_at(profile.xy[:, 0], profile.xy[:, 1])
    assert np.abs(profile.z - exact).max() <= 0.05e-9 + 1e-18


def test_servo_lag_in_the_lab_cuts_the_cone_of_a_radial_offset(tool_path, program):
    # compensated X on a sphere is a ramp of speed v (1 + R / Rs); a PD loop lags it by
    # speed c / kp (final-value theorem), from the first point on since the axes enter the
    # run already moving: the cut is the sphere with the exact form error of that dx
    kp, kd, c, mass = 2e5, 2e3, 1e4, 4.0
    servo = PIDServo((AxisServo(kp=kp, ki=0.0, kd=kd, mass=mass, damping=c), None, None))
    lab = machinesim.Lab("sts_lathe", noise=False, servo=servo)
    part, report = lab.turn(program, TOOL, top=1e-6)
    speed = FEED * RPM / 60.0 * (1 + R / RS)
    lag = speed * c / kp
    assert report.peak_following_error["X"] == pytest.approx(lag, rel=2e-3)
    px, py = _points()
    error = part.heights_at(px, py) - DESIGN(px, py)
    expected = alignment_error_x(DESIGN, np.hypot(px, py), 0.0, lag)
    scallop = (FEED * (1 + R / RS)) ** 2 / (8 * R)
    assert (error - expected).min() > -1e-11
    assert (error - expected).max() < scallop
    assert np.abs(expected).max() > 50 * scallop
    # the control's encoders record that lag (noise off: rounding to the 1 nm resolution);
    # X runs inwards, so the axis stays behind at larger X: command - position = -lag
    reading = lab.encoders().record_turning(program)
    np.testing.assert_array_equal(reading.commanded[:, 0], tool_path.x)
    assert np.abs(reading.following_error[:, 0] + lag).max() < 0.6e-9 + 2e-3 * lag


def test_adjusting_the_tool_moves_the_cut_and_keeps_the_injected_errors(program):
    injected = {"tool": {"offset_um": [2.0, 0.0, 0.0]}}
    lab = machinesim.Lab("sts_lathe", injected, noise=False)
    lab.adjust_tool((-2e-6, 0.0, 0.0))
    reference = machinesim.Lab("sts_lathe", noise=False)
    px, py = _points()
    np.testing.assert_allclose(lab.turn(program, TOOL)[0].heights_at(px, py),
                               reference.turn(program, TOOL)[0].heights_at(px, py), atol=1e-15)
    assert lab.reveal().tool.offset[0] == 2e-6
    np.testing.assert_array_equal(lab.reveal_adjustments(), [-2e-6, 0.0, 0.0])
    # with noise the adjuster lands within half its resolution of the command
    noisy = machinesim.Lab("sts_lathe", injected, seed=3)
    noisy.adjust_tool((-2e-6, 1e-6, 0.0))
    made = noisy.reveal_adjustments() - np.array([-2e-6, 1e-6, 0.0])
    assert np.abs(made).max() <= TOOL_ADJUSTER_RESOLUTION_M / 2
    assert np.abs(made).max() > 0.0


def test_nose_radius_error_in_the_error_model():
    model = machinesim.ErrorModel.from_dict({"tool_geometry": {"nose_radius_um": 12.5}})
    assert model.tool_geometry.nose_radius == pytest.approx(12.5e-6, rel=1e-15)
    assert model.parameters()["tool_geometry.nose_radius"] == model.tool_geometry.nose_radius
    assert machinesim.ErrorModel.from_dict(model.to_dict()) == model
    assert model.with_parameters({"tool_geometry.nose_radius": 0.0}) == machinesim.ErrorModel()
    assert "tool_geometry.nose_radius" in machinesim.load_machine("sts_lathe").parameter_names()
    with pytest.raises(ErrorModelError, match="nose_radius"):
        machinesim.ErrorModel.from_dict({"tool_geometry": {"nose_radius_um": "big"}})
    with pytest.raises(ErrorModelError, match="tool_geometry.radius_um"):
        machinesim.ErrorModel.from_dict({"tool_geometry": {"radius_um": 1.0}})


def test_mesh_cut_applies_the_nose_radius_error():
    # second method: the same groove cut with a ball 10 um larger and no error
    program = parse_program("G90 G21\nG00 X0 Y0 Z0.1\nG01 Z-0.01 F100\nG01 X1\n")
    errors = machinesim.ErrorModel.from_dict({"tool_geometry": {"nose_radius_um": 10.0}})
    with_error, _ = machinesim.cut(program, "grooving_4axis", "ball:0.5", "block:3x3x1", errors)
    larger, _ = machinesim.cut(program, "grooving_4axis", "ball:0.51", "block:3x3x1")
    assert with_error.volume == pytest.approx(larger.volume, rel=1e-12)
    with pytest.raises(InputError, match="no nose radius"):
        machinesim.cut(program, "grooving_4axis", "v:90", "block:3x3x1", errors)


def test_turning_refuses_what_it_cannot_cut(program):
    lab = machinesim.Lab("sts_lathe", noise=False)
    with pytest.raises(InputError, match="no feed move turns C"):
        lab.turn(parse_program("G90 G21\nG00 X1 Z0 C0\nG01 X0 F10\n"))
    with pytest.raises(InputError, match="round-nose"):
        lab.turn(program, "v:90")
    with pytest.raises(InputError, match="Expected a lathe.*planer_4axis .*no C axis"):
        turn(program, "planer_4axis")
    part, _ = lab.turn(program, TOOL)
    with pytest.raises(InputError, match="spot"):
        WhiteLightInterferometer(
            noise=False, spot=Spot(0.8e-6, "gaussian")).profile(part, (0, 0), (1e-4, 0))


def test_encoders_record_no_turning_on_a_mill():
    # a mill's C table (grooving_4axis: X, Y, Z, C) ran this spiral as a lathe's and was
    # recorded (9 samples); lab.turn refuses the machine, and so does the recording now
    text = "G01 X0 Y0 Z0 C0 F100.\nG01 X0.1 C360.\nG01 X0.05 C720.\n"
    for name, found in (("grooving_4axis", "its C travels .* axis Y"),
                        ("robonano_a0ib", "its C travels .* axes Y, B")):
        lab = machinesim.Lab(name, noise=False)
        ax = " ".join(f"{a}0" for a in lab.machine.axes)
        program = parse_program(text.replace("X0 Y0 Z0 C0", ax))
        with pytest.raises(InputError, match=f"Expected a lathe.*{name} .*{found}"):
            lab.encoders().record_turning(program)
        with pytest.raises(InputError, match=f"Expected a lathe.*{name}"):
            lab.turn(program)
    lathe = machinesim.Lab("sts_lathe", noise=False)
    reading = lathe.encoders().record_turning(parse_program(text.replace(" Y0", "")))
    # 3 points of a run of 2 moves, each turn split into quarter turns: 1 + 4 + 4 rows
    assert reading.commanded.shape == (9, 3)


def test_profile_error_removes_piston_and_tilt():
    r = np.linspace(0.0, 1e-4, 201)
    wave = 2e-9 * np.sin(2 * np.pi * r / 1e-4)
    found = profile_error(r, wave + 3e-9 + 5e-6 * r, np.zeros_like(r))
    # the least-squares line through one period of a sine is not zero: compare with lstsq
    fitted = np.polyval(np.polyfit(r, wave, 1), r)
    np.testing.assert_allclose(found.residual, wave - fitted, atol=1e-21)
    assert found.pv == pytest.approx(np.ptp(wave - fitted), rel=1e-12)


def test_l_filtered_sa_keeps_the_feed_marks_and_drops_the_form():
    x = np.arange(0.0, 100e-6, 0.5e-6)
    gx, _ = np.meshgrid(x, x)
    marks = 1e-9 * np.sin(2 * np.pi * gx / 2e-6 + 0.3)
    form = 20e-9 * np.sin(2 * np.pi * gx / 100e-6)
    sa = roughness_sa(x, x, marks + form, l_cutoff=8e-6)
    assert sa == pytest.approx(np.mean(np.abs(marks)), rel=0.02)
    assert roughness_sa(x, x, marks + form) > 10 * sa


def test_the_tool_test_reads_dy_with_its_sign_and_the_alignment_cancels_it():
    # a turned sphere shows only |dy| (the uncut core); the tilted plane's twist about the
    # centre, slope dy y / rho, shows its sign: moved by -dx, -dy the tool is then on centre
    from machinesim.procedures.sts_turning import STSTurning

    procedure = STSTurning()
    for dy in (2e-6, -2e-6):
        lab = machinesim.Lab("sts_lathe", {"tool": {"offset_um": [0.3, dy * 1e6, 0.0]}},
                             noise=False)
        identified = procedure.identify(procedure.measure(lab))
        assert identified.parameters["tool.y"][0] == pytest.approx(dy, rel=0.05)
        assert identified.parameters["tool.x"][0] == pytest.approx(0.3e-6, abs=10e-9)
        residual, report = procedure.align(lab, identified.detail)
        assert abs(residual.dy) < 0.1e-6 and abs(residual.dx) < 10e-9
        # what the adjuster made (exact with the noise off) against the injected offset
        assert abs(lab.reveal().tool.offset[1] + lab.reveal_adjustments()[1]) < 0.1e-6
        assert report["dy_after_alignment_um"] == pytest.approx(residual.dy / 1e-6)


def test_the_tool_test_refuses_tool_errors_beyond_what_its_sphere_identifies():
    # +10 um of dx: the tip stays 10 um outside the spindle axis and the nose, not the tip,
    # cuts the middle of the sphere, which the exact form does not describe: the fit's dR
    # comes out 8 % off (92 um for 100). The misfit (1.7 nm against 0.6) refuses it; +5 um,
    # inside the range, is read to 0.6 % (docs/procedures/sts_turning.md)
    from machinesim.procedures.sts_turning import STSTurning

    procedure = STSTurning()
    errors = {"tool": {"offset_um": [10.0, -3.5, 0.0]},
              "tool_geometry": {"nose_radius_um": 100.0}}
    with pytest.raises(InputError, match=r"does not fit the tool-error model: residual RMS "
                       r"1\.\d\d nm .* dR 92\.\d\d um"):
        procedure.measure(machinesim.Lab("sts_lathe", errors, noise=False))
    errors["tool"]["offset_um"][0] = 5.0
    found = procedure.measure(machinesim.Lab("sts_lathe", errors, noise=False))["tool_test"]
    assert found.d_radius == pytest.approx(100e-6, rel=0.01)
    assert found.dx == pytest.approx(5e-6, abs=0.05e-6)


def test_a_facing_cut_of_many_turns_in_one_block_turns_as_the_same_cut_in_small_blocks():
    # G01 X0 C18000 faces the part in 50 turns in one block. The control interpolates it
    # linearly in X and C, so the same cut written as 2000 blocks along that line is the
    # same path; before, the angle read back from the poses of the block's two ends, which
    # know C only modulo a turn, saw no turn at all and left the face uncut.
    head = "G21 G90 G94\nG00 X5.5 Z1. C0.\nG01 Z-0.01 F100.\n"
    one = parse_program(head + "G01 X0. C18000. F20.\nG00 Z1.\nM30\n")
    many = parse_program(head + "".join(
        f"G01 X{5.5 * (1 - k / 2000):.6f} C{18000 * k / 2000:.4f} F20.\n"
        for k in range(1, 2001)) + "G00 Z1.\nM30\n")
    rho = np.linspace(0.5e-3, 5e-3, 37)
    theta = np.linspace(0.1, 6.0, 37)
    x, y = rho * np.cos(theta), rho * np.sin(theta)
    (face, report), (reference, _) = (turn(p, "sts_lathe", "nose:0.5:90") for p in (one, many))
    assert report.revolutions == pytest.approx(50.0, rel=1e-12)
    assert np.abs(face.heights_at(x, y) - reference.heights_at(x, y)).max() < 1e-15
    # a face 10 um deep with the scallops of a 0.11 mm feed per turn on a 0.5 mm nose:
    # at most (f/2)^2 / (2 R) = 3.0 um above the tip
    heights = face.heights_at(x, y)
    assert heights.max() <= -1e-5 + (0.11e-3 / 2) ** 2 / (2 * 0.5e-3) + 1e-12
    assert heights.min() >= -1e-5 - 1e-12


def test_a_turning_move_of_more_than_a_day_is_noted():
    # the facing cut above at F0.0001 for F20.: sqrt(5.5**2 + 18000**2) mm-or-deg over
    # 0.0001 mm/min is 1.08e10 s, by hand; it was reported without a word
    head = "G21 G90 G94\nG00 X5.5 Z1. C0.\nG01 Z-0.01 F100.\n"
    slow, fast = (turn(parse_program(head + f"G01 X0. C18000. F{f}\nG00 Z1.\nM30\n"),
                       "sts_lathe", "nose:0.5:90")[1] for f in ("0.0001", "20."))
    assert slow.machining_time_s == pytest.approx(
        np.hypot(5.5, 18000.0) / 0.0001 * 60.0, rel=1e-12)
    (note,) = [n for n in slow.notes if "takes" in n]
    assert "line 4" in note and "1.08e+10 s" in note and "F0.0001" in note
    assert not [n for n in fast.notes if "takes" in n]


def test_a_plunge_of_more_than_a_day_is_noted_though_it_turns_no_c():
    # the facing cut above plunging its 1.01 mm at F0.000001 (a week and more): 1.01 mm over
    # 1e-6 mm/min is 6.06e7 s, by hand; the lathe noted slow moves inside turning runs only,
    # and the plunge is none, so it passed without a word (plan notes it)
    program = parse_program("G21 G90 G94\nG00 X5.5 Z1. C0.\nG01 Z-0.01 F0.000001\n"
                            "G01 X0. C18000. F20.\nG00 Z1.\nM30\n")
    report = turn(program, "sts_lathe", "nose:0.5:90")[1]
    assert report.notes == (
        f"the feed move of line 3 takes {1.01 / 1e-6 * 60:.3g} s (1.68e+04 h) at F1e-06 "
        "(mm/min or deg/min), more than the 24 h one move of a program takes: is F in the "
        "program's unit (G94: per minute)?",)
    # it is not cut, so not in the turning time: the facing run's alone
    assert report.machining_time_s == pytest.approx(np.hypot(5.5, 18000.0) / 20.0 * 60.0,
                                                    rel=1e-12)


def test_an_arc_plunge_is_timed_by_its_arc_as_plan_times_it():
    # a G18 half circle of R0.505 mm down to the face (pi r = 1.5865 mm), read as 8 chords
    # (10 um tolerance), at the F that takes each chord's piece of arc 1.003 days: noted, as
    # plan notes it; the chords are 0.66 % (tol / (3 r)) shorter than their arcs, 0.9964
    # days each, and the lathe timed them so: no word
    feed = round(math.pi * 0.505 / (8 * 86400 * 1.003) * 60.0, 10)  # mm/min
    program = parse_program(f"G21 G90 G94\nG00 X5.5 Z1. C0.\nG18 G03 X5.5 Z-0.01 R0.505 "
                            f"F{feed:.10f}\nG01 X0. C18000. F20.\nG00 Z1.\nM30\n",
                            chord_tolerance=1e-5)
    assert (program.lines == 3).sum() == 8
    report = turn(program, "sts_lathe", "nose:0.5:90")[1]
    piece_s = math.pi * 0.505 / 8 / feed * 60.0
    assert report.notes == (
        f"the feed move of line 3 takes {piece_s:.3g} s ({piece_s / 3600:.3g} h) at "
        f"F{feed:.6g} (mm/min or deg/min), more than the 24 h one move of a program takes: "
        "is F in the program's unit (G94: per minute)?",)
    assert report.notes == machinesim.motion.plan(program,
                                                  machinesim.load_machine("sts_lathe")).notes


def test_a_turning_programs_dwells_are_timed_and_a_dwell_of_more_than_an_hour_is_noted():
    # the facing cut above at F20. split by a dwell: its time is sqrt(2.75**2 + 9000**2) mm-
    # or-deg twice at 20 mm/min plus the dwell, by hand; the dwell was left out of the time
    # (the same 54000.0 s with a 2 s or a 31-year dwell) and never noted, as plan notes it
    half = np.hypot(2.75, 9000.0) / 20.0 * 60.0
    for dwell, seconds in (("G04 X2.", 2.0), ("G04 P1000000000.", 1e9), ("G04 P3600000", 3600.0)):
        program = parse_program("G21 G90 G94\nG00 X5.5 Z1. C0.\nG01 Z-0.01 F100.\n"
                                f"G01 X2.75 C9000. F20.\n{dwell}\nG01 X0. C18000.\nG00 Z1.\nM30\n")
        report = turn(program, "sts_lathe", "nose:0.5:90")[1]
        assert report.machining_time_s == pytest.approx(2 * half + seconds, rel=1e-12)
        noted = [n for n in report.notes if "dwell" in n]
        assert noted == ([] if seconds <= 3600.0 else [
            "the dwell of line 5 (P1000000000.) waits 1e+09 s (2.78e+05 h), more than the 1 h "
            "a dwell of a program waits: is its time in the unit meant (P counts milliseconds "
            "without a decimal point, seconds with one; X seconds)?"]), dwell
    # a dwell before the cut (the spindle run up) is the program's time too
    program = parse_program("G21 G90 G94\nG00 X5.5 Z1. C0.\nG04 X5000\nG01 Z-0.01 F100.\n"
                            "G01 X0. C18000. F20.\nG00 Z1.\nM30\n")
    report = turn(program, "sts_lathe", "nose:0.5:90")[1]
    assert report.machining_time_s == pytest.approx(2 * half + 5000.0, rel=1e-12)
    assert [n[:45] for n in report.notes] == ["the dwell of line 3 (X5000) waits 5000 s (1.3"]


def test_a_feed_faster_than_an_axis_can_go_is_clamped_at_its_limit_as_the_planner_does():
    # the facing cut above at F1000000. would turn C at 1e6 / 60 deg/s (291 rad/s): sts_lathe's
    # C goes 150 rad/s at most (its rapid rate), so its 18000 deg take pi * 100 / 150 s, by
    # hand, as motion.plan times the move; the lathe took length / F, 1.08 s, a spindle of
    # 2778 rpm the machine cannot turn. At F20. nothing is clamped (the time as before).
    lathe = machinesim.load_machine("sts_lathe")
    c_limit = lathe.rapid_rate[lathe.axes.index("C")]
    assert c_limit == 150.0
    head = "G21 G90 G94\nG00 X5.5 Z1. C0.\nG01 Z-0.01 F100.\n"
    fast, slow = (turn(parse_program(head + f"G01 X0. C18000. F{f}\nG00 Z1.\nM30\n"),
                       "sts_lathe", "nose:0.5:90")[1] for f in ("1000000.", "20."))
    assert fast.machining_time_s == pytest.approx(100.0 * np.pi / c_limit, rel=1e-12)
    assert slow.machining_time_s == pytest.approx(np.hypot(5.5, 18000.0) / 20.0 * 60.0,
                                                  rel=1e-12)
    # the commanded motion the servo follows runs C at its limit, not beyond
    (t, points), = turning_runs(
        parse_program(head + "G01 X0. C18000. F1000000.\nG00 Z1.\nM30\n"), lathe)
    speed = np.abs(np.diff(points[:, lathe.axes.index("C")])) / np.diff(t)
    assert speed.max() == pytest.approx(c_limit, rel=1e-12)


def test_a_turning_move_of_more_than_a_day_under_g20_is_noted_with_its_f_in_inch():
    # X 0.2 inch and C 1 deg at F0.00001 inch/min (a degree counts as an inch): sqrt(0.04 +
    # 1) / 1e-5 min; it was noted as 'F5.07695e-05 (mm/min or deg/min)', the planner's
    # equivalent 1e-5 * sqrt(5.08**2 + 1) / sqrt(0.04 + 1). The first move sets Z alone, so
    # the lathe's runs start a move later than the program's moves: the note reads the
    # slow move, not the F4. plunge before it.
    program = parse_program("G20 G90 G94\nG00 Z0.04\nG00 X0.2 C0.\nG01 Z-0.0004 F4.\n"
                            "G01 X0. C1. F0.00001\nG00 Z0.04\nM30\n")
    report = turn(program, "sts_lathe", "nose:0.5:90")[1]
    (note,) = [n for n in report.notes if "takes" in n]
    seconds = 1.04 ** 0.5 / 1e-5 * 60
    assert f"the feed move of line 5 takes {seconds:.3g} s" in note
    equivalent = 1e-5 * (5.08 ** 2 + 1) ** 0.5 / 1.04 ** 0.5
    assert f"at F1e-05 (inch/min under G20; {equivalent:.6g} mm/min or deg/min)," in note


def test_a_nose_radius_the_tool_cannot_take_names_its_file_in_a_lab_with_background(
        tmp_path, program):
    # the lab adds its background to the injected errors: the sum kept neither the file nor
    # the key as written, so the refusal named neither (the scenario's --errors, default lab).
    # The lab's refusal is read by the procedure that turns: it names the tool as commanded
    # and the key, not the file or the value (tests/test_lab_texts.py); turn() given the
    # errors names all three
    path = tmp_path / "errors.toml"
    path.write_text("[tool_geometry]\nnose_radius_um = -1000\n", encoding="utf-8")
    lab = machinesim.Lab("sts_lathe", machinesim.ErrorModel.from_toml(path),
                         realism=machinesim.Realism.lab())
    with pytest.raises(InputError) as refused:
        lab.turn(program, TOOL, top=1e-6)
    assert str(refused.value) == (
        "key 'tool': the RoundNoseTool of radius 0.2 mm as commanded does not fit the lab's "
        "tool: with its nose radius error (tool_geometry.nose_radius of the errors it was made "
        "with) the radius would not be positive; expected a tool of a larger radius")
    with pytest.raises(InputError) as refused:
        turn(program, "sts_lathe", TOOL, machinesim.ErrorModel.from_toml(path))
    assert str(refused.value) == (
        f"{path}, line 2, key 'tool_geometry.nose_radius_um': the error model's "
        "tool_geometry.nose_radius_um = -1000 does not fit the RoundNoseTool (nose_radius must "
        "be a positive finite number, got -0.8 mm (-0.0008 m))")


def test_a_turned_part_says_what_it_is_with_units():
    """Its repr had been the dataclass dump: each EdgePath's four arrays (angle, along,
    offset, z) in bare SI, then the tool's fields, hundreds of lines for a facing cut. Now
    the runs, the path points, the turns cut, the nose radius in mm and the top in m. Hand
    values: a facing cut from X = 5 mm to 0 over C = 18000 deg is 50 turns; a tool offset
    of 0.5 um along Z leaves the face 0.5 um higher (-1 um deep: -0.5 um)."""
    program = parse_program("%\nO1\nG90 G21 G94\nG00 X5. Z0.1 C0.\nG01 Z-0.001 F10.\n"
                            "G01 X0. C18000. F36000.\nG00 Z0.1\n%\n")
    deepest = []
    for errors in (None, {"tool": {"offset_um": [0.0, 0.0, 0.5]}}):
        lab = machinesim.Lab("sts_lathe", errors, noise=False)
        part, _ = lab.turn(program, "nose:1.0:90")
        assert repr(part) == ("TurnedFace(1 run, 201 path points over 50 turns, nose radius "
                              "1 mm as commanded, top 0 m)")
        assert repr(turn(program, "sts_lathe", "nose:1.0:90", errors)[0]) == (
            "TurnedPart(1 run, 201 path points over 50 turns, nose radius 1 mm, top 0 m)")
        deepest.append(part.heights_at(np.linspace(-4e-3, 4e-3, 8001), np.zeros(8001)).min())
    assert deepest == pytest.approx([-1e-6, -0.5e-6], abs=1e-12)


def test_a_grid_cut_with_the_tool_set_high_reads_its_uncut_crests():
    # The sine grid is cut 0.9 to 1 um below the stock's top; a tool tip set 0.95 um high
    # cuts the same surface 0.95 um higher, and where that passes the top (crests) the
    # stock stays. The share of the measured line that reads the top is then the share of
    # the grid cut as programmed (tool.z = 0) that lies above top - 0.95 um - UNCUT_BAND:
    # a second cut, shifted by hand. Bracketed analytically too: the grid along the line is
    # A sin(k r) + A over two whole wavelengths, cut within -4.1 .. +0.25 nm of it (the
    # as-found program's interpolation), so the share lies between P(sin > -0.205) = 0.566
    # (design above 39.75 nm) and P(sin > -0.118) = 0.538 (above 44.1 nm), by
    # P(sin > a) = 1/2 - asin(a) / pi over whole wavelengths.
    import machinesim.cam.spiral as sp
    from machinesim.procedures.sts_cases import GRID_TOP, UNCUT_BAND, uncut_share
    from machinesim.procedures.sts_plans import MEASURE_LINE, PLANS
    from machinesim.procedures.sts_turning import STSTurning

    procedure = STSTurning()
    program = sp.spiral_program(PLANS["before"].path(sp.sine_grid(), procedure.nose_radius))
    high = 0.95e-6
    read = {}
    for z in (0.0, high):
        lab = machinesim.Lab("sts_lathe", {"tool": {"offset_um": [0.0, 0.0, z * 1e6]}},
                             noise=False)
        part, _ = lab.turn(program, procedure.tool, top=GRID_TOP)
        read[z] = lab.white_light_interferometer(label="grid").profile(part, *MEASURE_LINE).z
    assert uncut_share(read[0.0]) == 0.0
    share = uncut_share(read[high])
    shifted = np.asarray(read[0.0]) + high
    assert share == pytest.approx(float(np.mean(shifted > GRID_TOP - UNCUT_BAND)),
                                  abs=1.0 / len(shifted))
    assert 0.5 - math.asin(-0.118) / math.pi - 1e-3 < share < 0.5 - math.asin(-0.205) / math.pi


def test_a_case_partly_uncut_says_so_in_its_figures():
    from machinesim.procedures.sts_cases import CASES, CaseResult
    from machinesim.procedures.sts_prediction import Prediction
    from machinesim.procedures.sts_turning import STSTurning

    def case(name, line, window):
        prediction = Prediction(6e-9, 1e-9, 1e-9, 5e-9, np.zeros(3))
        return CaseResult(name, prediction, 31e-9, np.zeros(3), np.zeros(3), 0.4e-9, 10, 1.0,
                          (), uncut_line=line, uncut_window=window)

    cases = {name: case(name, 0.0, 0.0) for name in CASES}
    cases["case_4"] = case("case_4", 0.32, 0.5)
    notes = {f.name: f.note for f in STSTurning().figures(cases)}
    said = ("case_4: 32% of the measured line and 50% of the Sa window read the stock's "
            "top, uncut")
    for name in ("form_error_pv", "sa", "form_error_pv_case_4"):
        assert said in notes[name]
    assert "uncut" not in notes["form_error_pv_case_1"] + notes["form_error_pv_predicted"]
