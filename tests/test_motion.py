"""Motion: machining time by the FANUC feed rule, rotary moves split to the chord tolerance."""

from __future__ import annotations

import math

import numpy as np
import pytest

from machinesim import ErrorModel, ToolSetting, load_machine
from machinesim.exceptions import InputError, NCProgramError
from machinesim.motion import plan
from machinesim.nc import Move, Program, ProgramBuilder, parse_program


def test_times_follow_the_feed_rule_by_hand():
    machine = load_machine("robonano_a0ib")
    program = parse_program(
        "G90 G21\nG00 X1. Y2.\nG01 X4. Y6. F300.\nG01 C90. F600.\nG04 P1500\nG01 X5. C100.\nM30\n")
    tr = plan(program, machine)
    rapid = max(1e-3 / 0.025, 2e-3 / 0.025)  # each axis at 25 mm/s, the slowest sets the time
    feed1 = 5.0 / 300.0 * 60.0  # 5 mm at 300 mm/min
    turn = 90.0 / 600.0 * 60.0  # 90 deg at 600 deg/min
    mixed = math.hypot(1.0, 10.0) / 600.0 * 60.0  # 1 mm and 10 deg count as a 1:10 vector
    expected = [rapid, feed1, turn, 1.5, mixed]
    np.testing.assert_allclose([s.duration for s in tr.segments], expected, rtol=1e-14)
    assert tr.duration == pytest.approx(sum(expected), rel=1e-14)
    assert tr.cutting_time == pytest.approx(feed1 + turn + mixed, rel=1e-14)
    np.testing.assert_allclose(tr.segments[-1].q[-1], [5e-3, 6e-3, 0.0, 0.0, math.radians(100)],
                               rtol=0, atol=1e-18)


@pytest.mark.parametrize(("kind", "feed", "dwell", "key"), [
    ("arc", 1e-3, 0.0, "kind"),            # timed as a feed move: 1.0 s
    ("linear", None, 0.0, "feed_m_per_s"),  # TypeError of None / 1e-3
    ("linear", 0.0, 0.0, "feed_m_per_s"),   # ZeroDivisionError
    ("linear", -1e-3, 0.0, "feed_m_per_s"),  # the axis' limit: 0.04 s, silently
    ("dwell", None, -2.0, "dwell_s"),       # -2.0 s
    ("dwell", None, None, "dwell_s"),
    ("linear", True, 0.0, "feed_m_per_s"),  # 1 m/s: 0.001 s (a Move refuses it)
    ("dwell", None, True, "dwell_s"),       # 1 s
])
def test_move_duration_refuses_a_move_it_cannot_time(kind, feed, dwell, key):
    from machinesim.motion import move_duration

    with pytest.raises(InputError) as caught:
        move_duration(kind, np.zeros(1), np.full(1, 1e-3), np.array([False]),
                      np.array([0.025]), feed, dwell)
    assert caught.value.key == key
    # 1 mm at 60 mm/min is 1 s, a dwell its time
    assert move_duration("linear", np.zeros(1), np.full(1, 1e-3), np.array([False]),
                         np.array([0.025]), 1e-3, 0.0) == pytest.approx(1.0, rel=1e-15)
    assert move_duration("dwell", np.zeros(1), np.zeros(1), np.array([False]),
                         np.array([0.025]), None, 0.5) == 0.5


def test_a_feed_beyond_an_axis_velocity_limit_is_clamped_there():
    """No axis outruns its velocity limit (25 mm/s for X and Y, 2 rad/s for C on the
    alpha-0iB): F 1e8 mm/min over 12 mm in X takes 12 / 25 s, not 7.2 us; over 3 mm X and
    4 mm Y the slower axis, Y, sets it (4 / 25 s); a feed below the limit keeps its time."""
    machine = load_machine("robonano_a0ib")
    program = parse_program("G90 G21\nG00 X0 Y0 Z0 C0\nG01 X12. F100000000.\n"
                            "G01 X15. Y4.\nG01 X3. F300.\nG01 C180. F100000000.\nM30\n")
    tr = plan(program, machine)
    expected = [12.0 / 25.0, 4.0 / 25.0, 12.0 / 300.0 * 60.0, math.pi / 2.0]
    np.testing.assert_allclose([s.duration for s in tr.segments][1:], expected, rtol=1e-14)
    assert tr.cutting_time == pytest.approx(sum(expected), rel=1e-14)


@pytest.mark.parametrize("tolerance", [1e-9, 1e-8])
def test_a_tool_rotation_is_split_so_the_chord_stays_within_tolerance(tolerance):
    """The planer's edge turns on an arm of r = 120.5 mm: an arc, whose chord over a step
    dtheta deviates by the sagitta r (1 - cos(dtheta / 2)); the fewest steps over 20 deg is
    ceil(theta / (2 acos(1 - tol / r)))."""
    machine = load_machine("planer_4axis")
    theta, r = math.radians(20.0), 0.1205
    program = ProgramBuilder().rapid(X=0.0, Y=0.0, Z=0.0, A=0.0).linear(
        A=theta, feed_mm_per_min=100.0).build()
    steps = len(plan(program, machine, chord_tolerance=tolerance).segments[1].q) - 1
    fewest = math.ceil(theta / (2 * math.acos(1 - tolerance / r)))
    assert fewest <= steps <= fewest + 1
    dtheta = theta / steps
    assert r * (1 - math.cos(dtheta / 2)) <= tolerance


@pytest.mark.parametrize("turn_deg", [720.0, 1440.0, 2880.0])
def test_a_turn_of_whole_double_turns_is_split_by_the_sagitta_not_by_its_aliased_midpoint(
        turn_deg):
    """C turns 720 deg (or 1440, 2880) with the edge 5 mm from the axis: one chord's ends
    and midpoint are one point, so the chord rule's first look saw no deviation; the old
    planner took 1 sub-step, raised to the 45 deg sub-steps (16 for 720 deg), whose
    sagitta r (1 - cos(22.5 deg)) is 0.38 mm. The fewest that hold are
    ceil(theta / (2 acos(1 - tol / r))) (9935 for 720 deg), the planned and the followed
    (servo) counts alike."""
    from machinesim.motion.following import StepRule

    machine = load_machine("grooving_4axis")
    theta, r, tolerance = math.radians(turn_deg), 5e-3, 1e-8
    program = parse_program(f"G90 G21 G94\nG00 X5. Y0. Z0. C0.\nG01 C{turn_deg} F36000.\n"
                            "M30\n")
    segment = plan(program, machine, chord_tolerance=tolerance).segments[1]
    steps = len(segment.q) - 1
    fewest = math.ceil(theta / (2 * math.acos(1 - tolerance / r)))
    assert steps >= fewest
    assert r * (1 - math.cos(theta / steps / 2)) <= tolerance
    rule = StepRule(machine, None, np.zeros((1, 3)), np.asarray(machine.rotary), tolerance,
                    0.0)
    start = segment.q[:1]
    followed = int(rule.counts(start, segment.q[-1:] - start)[0])
    assert followed >= fewest


def test_a_quintic_with_zeros_at_the_quarters_is_split_to_the_tolerance(tmp_path):
    """EYX = k x (x - a/2)(x + a/2)(x - a)(x + a), a = 250 mm: zeros at -250, -125, 0, 125
    and 250 mm, 1 um at its outer peaks, X over the whole travel. One chord's checks (its
    midpoint and quarters) and two sub-steps' midpoints all lie at its zeros: the old
    planner took one sub-step, 1 um off the path. The path, sampled 64 times a sub-step,
    stays within 1 nm of the planned chords."""
    a = 250.0
    roots = np.array([-a, -a / 2, 0.0, a / 2, a])
    coefficients = np.polynomial.polynomial.polyfromroots(roots)
    # the peaks: where the derivative vanishes
    extrema = np.polynomial.polynomial.polyroots(np.polynomial.polynomial.polyder(coefficients))
    coefficients /= np.abs(np.polynomial.polynomial.polyval(extrema.real, coefficients)).max()
    (tmp_path / "q.toml").write_text("[component.X]\nEYX_poly_um_mm = ["
                                     + ", ".join(repr(float(c)) for c in coefficients) + "]\n")
    errors = ErrorModel.from_toml(tmp_path / "q.toml")
    machine = load_machine("grooving_4axis")
    program = ProgramBuilder().rapid(X=-0.25, Y=0.0, Z=0.0, C=0.0).linear(
        X=0.25, feed_mm_per_min=100.0).build()
    q = plan(program, machine, errors, chord_tolerance=1e-9).segments[1].q
    f = np.linspace(0.0, 1.0, 65)
    dense = (q[:-1, None, :] + f[None, :, None] * (q[1:] - q[:-1])[:, None, :]).reshape(-1, 4)
    y = machine.tool_pose(dense, errors)[:, 1, 3]
    nodes = machine.tool_pose(q, errors)[:, 1, 3]
    peaks = np.zeros((4, 4))
    peaks[:, 0] = np.sort(extrema.real) * 1e-3
    # the bow the chords must follow
    assert np.abs(machine.tool_pose(peaks, errors)[:, 1, 3]).max() == pytest.approx(1e-6,
                                                                                  rel=1e-9)
    assert np.abs(y - np.interp(dense[:, 0], q[:, 0], nodes)).max() <= 1e-9


def test_a_straightness_s_that_passes_its_moves_middle_is_split_to_the_tolerance(tmp_path):
    """EYX = k x (x - 5)(x - 10) (x in mm, 1 um at its peaks, x = 2.11 and 7.89 mm) on X
    from 0 to 10 mm: the path is on its chord at both ends and at the middle, where one
    chord's check looks, and 1 um off it between; the old planner took one sub-step. The
    path, sampled at 2001 points, stays within 1 nm of the planned chords."""
    k = 1.0 / (2.1132487 * 2.8867513 * 7.8867513)  # 1 um at the peaks
    (tmp_path / "s.toml").write_text(
        f"[component.X]\nEYX_poly_um_mm = [0.0, {50 * k!r}, {-15 * k!r}, {k!r}]\n")
    errors = ErrorModel.from_toml(tmp_path / "s.toml")
    machine = load_machine("grooving_4axis")
    program = ProgramBuilder().rapid(X=0.0, Y=0.0, Z=0.0, C=0.0).linear(
        X=10e-3, feed_mm_per_min=100.0).build()
    q = plan(program, machine, errors, chord_tolerance=1e-9).segments[1].q
    assert len(q) > 2
    dense = np.linspace(0.0, 10e-3, 2001)
    y = np.array([machine.tool_pose([x, 0.0, 0.0, 0.0], errors)[1, 3] for x in dense])
    nodes = np.array([machine.tool_pose(row, errors)[1, 3] for row in q])
    assert np.abs(y).max() == pytest.approx(1e-6, rel=1e-6)  # the bow the chords must follow
    assert np.abs(y - np.interp(dense, q[:, 0], nodes)).max() <= 1e-9


def test_the_chord_follows_the_real_path_with_errors_and_the_tool_extent():
    """A longer arm (tool set 5 mm low) and a tool point 1 mm above the edge: the farthest
    point from the A axis sets the step count."""
    machine = load_machine("planer_4axis")
    errors = ErrorModel(tool=ToolSetting([0.0, 0.0, -5e-3], [0.0, 0.0, 0.0]))
    theta = math.radians(5.0)
    program = ProgramBuilder().rapid(X=0.0, Y=0.0, Z=0.0, A=0.0).linear(
        A=theta, feed_mm_per_min=100.0).build()
    steps = len(plan(program, machine, errors, tool_points=[[0.0, 0.0, 1e-3]],
                     chord_tolerance=1e-9).segments[1].q) - 1
    r = 0.1205 + 5e-3  # the edge, farther from A than the point 1 mm above it
    fewest = math.ceil(theta / (2 * math.acos(1 - 1e-9 / r)))
    assert fewest <= steps <= fewest + 1


def test_linear_moves_are_not_split_and_bad_programs_are_refused():
    machine = load_machine("grooving_4axis")
    tr = plan(parse_program("G01 X10. Y5. F100.\nM30\n"), machine)
    assert [len(s.q) for s in tr.segments] == [2]
    with pytest.raises(NCProgramError, match="axis A is not on grooving_4axis"):
        plan(parse_program("G01 A10. F100.\n"), machine)
    # a feed move without a feed: the reader refuses it (test_nc_feed.py); a program built
    # from moves may still hold one, and the planner refuses it there
    with pytest.raises(NCProgramError, match="line 1.*no feed rate F"):
        plan(Program.from_moves([Move("linear", {"X": 1e-3})]), machine)


def test_an_arc_without_a_feed_is_not_called_a_g01():
    # 'G02 X1. Y0. R0.5' with no F so far was refused as 'a feed move (G01) with no feed
    # rate F given so far', naming a G01 the program does not hold; the reader now refuses
    # it at its line, naming the G02 (test_nc_feed.py), before the planner sees it
    with pytest.raises(NCProgramError) as caught:
        parse_program("G90 G21 G17\nG00 X0. Y0. Z1.\nG02 X1. Y0. R0.5\nM30\n")
    assert (caught.value.line, caught.value.key) == (3, "G02")
    assert caught.value.message.startswith("G02 feeds with no F in force")


def test_plan_takes_a_machine_by_name_and_refuses_a_path_for_the_program(tmp_path):
    # plan(program, "grooving_4axis"), as cut() takes a machine, and plan("grooves.nc", ...)
    # had ended in AttributeError ('str' object has no attribute 'axes' / 'moves')
    program = parse_program("G90 G21\nG00 X1.\nG01 X11. F600.\nM30\n")
    by_name = plan(program, "grooving_4axis")
    assert by_name.duration == plan(program, load_machine("grooving_4axis")).duration
    assert by_name.segments[-1].t[-1] - by_name.segments[-1].t[0] == pytest.approx(1.0)
    path = tmp_path / "p.nc"
    path.write_text("G00 X1.\nM30\n")
    for wrong in (path, str(path), [1, 2]):
        with pytest.raises(InputError) as info:
            plan(wrong, "grooving_4axis")
        assert info.value.key == "program"
        assert str(info.value).startswith("key 'program': Expected program as a "
                                          "machinesim.nc.Program, got ")
        assert "read an NC file with machinesim.nc.read_program(path)" in str(info.value)


def test_a_move_of_more_than_a_day_is_noted_with_its_line_and_feed():
    # 10 mm at F0.0001 mm/min: 1e5 min = 6e6 s, by hand; it had been planned without a word
    machine = load_machine("grooving_4axis")
    slow = plan(parse_program("G90 G21\nG01 X1. F100.\nG01 X11. F0.0001\nM30\n"), machine)
    assert slow.duration == pytest.approx(0.6 + 6e6, rel=1e-12)
    (note,) = slow.notes
    assert "line 3" in note and "6e+06 s" in note and "F0.0001" in note
    # an hour-long finishing pass is a plan, not a slip: 100 mm at F1 mm/min
    assert plan(parse_program("G90 G21\nG01 X100. F1.\nM30\n"), machine).notes == ()


@pytest.mark.parametrize("text, duration, feed", [
    # 0.4 inch at F0.0001 inch/min: 4000 min; it was noted as 'F0.00254 (mm/min or deg/min)'
    ("G90 G20\nG01 X0.1 F10.\nG01 X0.5 F0.0001\nM30\n", 0.1 / 10 * 60 + 4000 * 60,
     "F0.0001 (inch/min under G20; 0.00254 mm/min or deg/min)"),
    # C alone: F in deg/min under G20 too (FANUC), 90 deg at F0.001: 90,000 min
    ("G90 G20\nG00 X0. C0.\nG01 C90. F0.001\nM30\n", 90000 * 60,
     "F0.001 (deg/min under G20; 0.001 mm/min or deg/min)"),
    # X and C: a degree counts as an inch, sqrt(1 + 10**2) / 0.001 min; the planner's
    # equivalent counts it as a mm: 0.001 * sqrt(25.4**2 + 10**2) / sqrt(1 + 10**2)
    ("G90 G20\nG00 X0. C0.\nG01 X1. C10. F0.001\nM30\n", 101 ** 0.5 / 0.001 * 60,
     f"F0.001 (inch/min under G20; {0.001 * 745.16 ** 0.5 / 101 ** 0.5:.6g} mm/min or "
     "deg/min)"),
    # G21 and G20 both before the move: the last before the first motion is in force (a
    # switch after it is refused), 1.5 inch = 38.1 mm at F0.0001 inch/min = 0.00254 mm/min;
    # each had been noted with both readings, 'F0.00254 (mm/min or deg/min), or F0.0001
    # (inch/min) if written under G20', Program.unit_words keeping first lines only
    ("G90 G21\nG20\nG01 X1.5 F0.0001\nM30\n", 38.1 / 0.00254 * 60,
     "F0.0001 (inch/min under G20; 0.00254 mm/min or deg/min)"),
    ("G20\nG21\nG20\nG01 X1.5 F0.0001\nM30\n", 38.1 / 0.00254 * 60,
     "F0.0001 (inch/min under G20; 0.00254 mm/min or deg/min)"),
    ("G90 G20\nG21\nG01 X38.1 F0.00254\nM30\n", 38.1 / 0.00254 * 60,
     "F0.00254 (mm/min or deg/min)"),
    ("G21\nG20\nG21\nG01 X38.1 F0.00254\nM30\n", 38.1 / 0.00254 * 60,
     "F0.00254 (mm/min or deg/min)"),
])
def test_a_slow_move_under_g20_is_noted_with_its_f_as_the_program_wrote_it(text, duration,
                                                                           feed):
    import pickle

    program = parse_program(text)
    slow = plan(program, load_machine("grooving_4axis"))
    assert slow.duration == pytest.approx(duration, rel=1e-12)
    (note,) = slow.notes
    in_force = "G20" if "under G20" in feed else "G21"
    assert program.unit_in_force == pickle.loads(pickle.dumps(program)).unit_in_force == in_force
    line = text.count("\n") - 1
    assert note == (f"the feed move of line {line} takes {duration:.3g} s "
                    f"({duration / 3600:.3g} h) at {feed}, more than the 24 h one move of a "
                    "program takes: is F in the program's unit (G94: per minute)?")


@pytest.mark.parametrize("dwell, word, seconds", [
    # a billion seconds (31 years) with no word: P with a decimal point counts seconds
    ("G04 P1000000000.", " (P1000000000.)", 1e9),
    ("G04 X5000", " (X5000)", 5000.0),  # X counts seconds: 5000 ms meant?
    ("G82 X2. Z-0.1 R1. P4000000. F10.", " (P4000000.)", 4e6),  # a cycle's dwell
])
def test_a_dwell_longer_than_an_hour_is_noted_with_its_word_and_seconds(dwell, word,
                                                                        seconds):
    import pickle

    text = f"G90 G21\nG00 X1. Z1.\n{dwell}\nG80\nM30\n"
    program = parse_program(text)
    trajectory = plan(program, load_machine("grooving_4axis"))
    (note,) = trajectory.notes
    assert note == (f"the dwell of line 3{word} waits {seconds:.6g} s ({seconds / 3600:.3g} "
                    "h), more than the 1 h a dwell of a program waits: is its time in the unit "
                    "meant (P counts milliseconds without a decimal point, seconds with one; X "
                    "seconds)?")
    assert pickle.loads(pickle.dumps(program)).dwell_words == {3: word[2:-1]}


#: A note on the dwell of line {line}, {word} as the note names it, of {seconds} s.
DWELL_NOTE = ("the dwell of line {line} ({word}) waits {seconds:.6g} s ({hours:.3g} h), more "
              "than the 1 h a dwell of a program waits: is its time in the unit meant (P "
              "counts milliseconds without a decimal point, seconds with one; X seconds)?")


@pytest.mark.parametrize("holes, line, word, seconds", [
    # G81 keeps its P for a G82: line 4 writes no P, and the note had named no word at all
    ("G81 X1. Z-0.1 R1. P5000000 F10.\nG82 X2.\n", 4, "P5000000 of line 3", 5000.0),
    # a G83's P kept by the G82 after it (Haas's peck dwell of line 3 waits it too: 5000 s)
    ("G83 X1. Z-0.1 R1. Q0.05 P7000000 F10.\nG82 X2.\n", 3, "P7000000", 7000.0),
    # a G82 repeated with the P written: its first hole, the P's own line, as before
    ("G82 X1. Z-0.1 R1. P100 F10.\nX2. P7000000\nX3.\n", 4, "P7000000", 7000.0),
    # a P given to a G81 (no dwell) between two G82s: the hole after it dwells it
    ("G82 X1. Z-0.1 R1. P100 F10.\nG81 X2. P6000000\nG82 X3.\n", 5,
     "P6000000 of line 4", 6000.0),
])
def test_a_long_dwell_of_a_kept_cycle_p_names_the_p_and_the_line_it_was_written_on(
        holes, line, word, seconds):
    text = f"G90 G21\nG00 X1. Z1.\n{holes}G80\nM30\n"
    notes = plan(parse_program(text), load_machine("grooving_4axis")).notes
    assert notes == (DWELL_NOTE.format(line=line, word=word, seconds=seconds,
                                       hours=seconds / 3600),)


def test_a_subprograms_hole_under_two_kept_ps_names_the_p_of_its_longest_dwell():
    # O100's line 10 drills under the P of line 4 (5000 s), then under that of line 6 (2 s):
    # its note names P5000000 of line 4, the dwell it is about, not the last P kept
    text = ("O1\nG90 G21\nG00 X1. Z1.\nG81 X1. Z-0.1 R1. P5000000 F10.\nM98 P100\n"
            "G81 X1. P2000\nM98 P100\nG80\nM30\nO100\nG82 X2.\nM99\n")
    program = parse_program(text)
    assert [float(d) for d in program.dwells if d > 0] == [5000.0, 2.0]
    assert program.dwell_words[11] == "P5000000 of line 4"
    assert plan(program, load_machine("grooving_4axis")).notes == (
        DWELL_NOTE.format(line=11, word="P5000000 of line 4", seconds=5000.0,
                          hours=5000 / 3600),)


def test_a_dwell_of_an_hour_is_not_noted_and_a_built_one_is_noted_without_a_word():
    machine = load_machine("grooving_4axis")
    # 3,600,000 ms is the hour itself: a long settling, not a slip
    assert plan(parse_program("G00 X1. Z1.\nG04 P3600000\nM30\n"), machine).notes == ()
    built = ProgramBuilder(1).rapid(X=1e-3, Z=1e-3).dwell(1e9).build()
    assert built.dwell_words == {}
    assert plan(built, machine).notes == (
        "the dwell of line 2 waits 1e+09 s (2.78e+05 h), more than the 1 h a dwell of a "
        "program waits: is its time in the unit meant (P counts milliseconds without a "
        "decimal point, seconds with one; X seconds)?",)


def test_a_start_or_program_of_the_wrong_kind_is_refused_naming_it():
    # a new user's start="home" (or ["0", ...]) ended in numpy's ValueError inside plan, from
    # Lab.cut, machinesim.cut and the encoders alike; encoders.record(None) or record of a
    # path in AttributeError: 'NoneType' object has no attribute 'moves'
    import machinesim
    from machinesim.exceptions import InputError

    machine = load_machine("robonano_a0ib")
    program = ProgramBuilder(1).rapid(X=1e-3, Z=1e-3).build()
    for start in ("home", ["0"] * 5, [True, 0, 0, 0, 0], [None] * 5, {"X": 0.0}):
        with pytest.raises(InputError, match=r"start as axis values \(m, rad\), one per axis "
                                             r"of XYZBC") as info:
            plan(program, machine, start=start)
        assert info.value.key == "start"
    lab = machinesim.Lab(machine, noise=False)
    with pytest.raises(InputError, match="start as axis values"):
        lab.cut(program, "v:90", "block:10x10x2", start="home")
    for wrong, shown in ((None, "NoneType"), ("part.nc", "str 'part.nc'")):
        with pytest.raises(InputError, match=rf"program as a machinesim.nc.Program, got "
                                             rf"{shown}; read an NC file with "
                                             r"machinesim.nc.read_program\(path\)") as info:
            lab.encoders().record(wrong)
        assert info.value.key == "program"
    # numbers of any kind pass, as before: ints, numpy floats, a tuple
    start = (1, np.float64(2e-3), 0, 0, 0)
    assert plan(program, machine, start=start).segments[0].q[0].tolist() == [1, 2e-3, 0, 0, 0]


@pytest.mark.parametrize("tolerance", [1e-9, 1e-5])
def test_an_arc_takes_its_length_over_f_not_its_chords(tolerance):
    """G03 half circle of radius 10 mm at F600 mm/min: pi r / F = 3.14159... s. Each chord
    carried F, so the arc took its chords' length over F: 3.3e-8 of it fast at 1 nm chords
    and 3.2e-4 at 10 um (tol / (3 r)). The control holds F along the arc (FANUC), and so
    does a helix's plane (its Z follows); an arc that turns a rotary axis keeps its chords'
    feed rule (degrees count in the feed length). Pickling and new targets keep the arcs'
    lengths."""
    import pickle

    machine = load_machine("grooving_4axis")
    r, feed = 10.0, 600.0  # mm, mm/min
    text = ("G90 G21 G94 G17\nG00 X10. Y0. Z0. C0.\nG01 X10. F600.\nG03 X-10. Y0. I-10. J0.\n"
            "G03 X10. Y0. Z-1. I10. J0.\nG03 X-10. Y0. I-10. J0. C90.\nM30\n")
    program = parse_program(text, chord_tolerance=tolerance)
    trajectory = plan(program, machine)
    lines = np.array([s.line for s in trajectory.segments])
    time = {line: sum(s.duration for s in trajectory.segments if s.line == line)
            for line in (4, 5, 6)}
    assert time[4] == pytest.approx(math.pi * r / feed * 60.0, rel=1e-12)
    assert time[5] == pytest.approx(math.pi * r / feed * 60.0, rel=1e-12)  # helix
    # the arc that turns C: its chords, each sqrt(chord_mm**2 + dC_deg**2) over F
    chords = [s for s in trajectory.segments if s.line == 6]
    by_chords = sum(math.hypot(math.hypot(*(s.q[-1, :2] - s.q[0, :2])) * 1e3,
                               math.degrees(s.q[-1, 3] - s.q[0, 3])) for s in chords)
    assert time[6] == pytest.approx(by_chords / feed * 60.0, rel=1e-12)
    assert (lines == 4).sum() > 1
    assert np.isnan(program.arc_lengths[~np.isin(program.lines, (4, 5))]).all()
    again = pickle.loads(pickle.dumps(program))
    assert again == program
    np.testing.assert_array_equal(again.arc_lengths, program.arc_lengths)
    moved = program.with_targets(program.targets)
    np.testing.assert_array_equal(moved.arc_lengths, program.arc_lengths)
    with pytest.raises(NCProgramError, match="arc_lengths must be lengths >= 0"):
        Program.from_arrays(program.targets, program.kinds, program.feeds,
                            arc_lengths=-program.arc_lengths)


@pytest.mark.parametrize("units, feed", [("G21", "F600."), ("G20", "F23.62204724")])
def test_an_arc_whose_rotary_word_keeps_its_axis_takes_its_length_over_f(units, feed):
    """A post that writes every axis on every block writes C0. in an arc where C stands at
    0: nothing turns, and the control holds F along the arc (pi r / F for the half circle
    of R10 mm, here read at 10 um chords). The reader took any rotary word for a turn and
    kept the chords' own lengths: 3.2e-4 fast (tol / (3 r)). Under G20 the same (F in
    inch/min, 600 mm/min); a C that does turn keeps its chords' rule (the test above)."""
    machine = load_machine("grooving_4axis")
    scale = 25.4 if units == "G20" else 1.0
    text = (f"G90 {units} G17\nG00 X{10 / scale:.10f} Y0. Z0. C0.\n"
            f"G01 X{10 / scale:.10f} {feed}\n"
            f"G03 X{-10 / scale:.10f} Y0. I{-10 / scale:.10f} J0. C0.\nM30\n")
    program = parse_program(text, chord_tolerance=1e-5)
    assert not np.isnan(program.arc_lengths[program.lines == 4]).any()
    time = sum(s.duration for s in plan(program, machine).segments if s.line == 4)
    assert time == pytest.approx(math.pi * 10.0 / 600.0 * 60.0, rel=1e-9)


def test_an_arcs_chords_keep_their_arc_length_as_moves():
    """The half circle of R10 mm at F600 read at 10 um chords takes pi r / F (3.14159 s)
    however it reaches plan: the Program, its moves, a slice of them (the arc alone, from
    the feed move's end) and Program.from_moves of them. Moves had been plain chords
    (Move kept no arc length): 3.2e-4 fast (tol / (3 r)). A Move without an arc length
    equals and pickles as before; a bad one is refused naming its key."""
    import pickle
    from types import SimpleNamespace

    machine = load_machine("grooving_4axis")
    program = parse_program("G90 G21 G17\nG00 X10. Y0. Z0. C0.\nG01 X10. F600.\n"
                            "G03 X-10. Y0. I-10. J0.\nM30\n", chord_tolerance=1e-5)
    arc = np.flatnonzero(program.lines == 4)
    half = math.pi * 10.0 / 600.0 * 60.0  # s
    moves = program.moves
    assert all(m.arc_length_m == program.arc_lengths[i] for i, m in enumerate(moves)
               if i in arc)
    assert moves[0].arc_length_m is None
    again = Program.from_moves(moves, source=program.source)
    np.testing.assert_array_equal(again.arc_lengths, program.arc_lengths)
    assert tuple(again.moves) == tuple(moves)
    start = np.zeros(len(machine.axes))
    start[0] = 10e-3
    for planned in (program, SimpleNamespace(moves=moves), again,
                    SimpleNamespace(moves=tuple(moves)[arc[0] - 1:]),
                    SimpleNamespace(moves=moves[arc[0]:arc[-1] + 1])):
        trajectory = plan(planned, machine, start=start)
        assert trajectory.cutting_time == pytest.approx(half, rel=1e-12)
    # a Move without an arc length: equal to one made before, and pickled round
    plain = Move("linear", {"X": 1e-3}, 0.01)
    assert plain == Move("linear", {"X": 1e-3}, 0.01, arc_length_m=None)
    assert pickle.loads(pickle.dumps(plain)) == plain
    old = object.__new__(Move)  # pickled before Move kept arc lengths: no such entry
    old.__dict__.update({k: v for k, v in vars(plain).items() if k != "arc_length_m"})
    assert pickle.loads(pickle.dumps(old)) == plain
    assert pickle.loads(pickle.dumps(moves[arc[0]])) == moves[arc[0]]
    for bad in (-1e-3, math.nan, math.inf, True, "1"):
        with pytest.raises(NCProgramError) as caught:
            Move("linear", {"X": 1e-3}, 0.01, arc_length_m=bad)
        assert caught.value.key == "arc_length_m"
    odd = SimpleNamespace(kind="linear", target={"X": 1e-3}, feed_m_per_s=0.01, dwell_s=0.0,
                          line=3, arc_length_m=True)
    with pytest.raises(NCProgramError) as caught:
        plan(SimpleNamespace(moves=(odd,)), machine)
    assert caught.value.key == "arc_length_m"


def test_an_arc_length_is_taken_only_by_a_chord_of_that_arc():
    """A Move keeps its chord's arc length, so a program cut from the middle of an arc, or
    given new targets, carries arc lengths of moves it no longer makes. The half circle of
    R10 mm at F600 read at 10 um chords (5 deg each, 0.8727 mm of arc): cut at its fifth
    chord and planned from zero, the first move goes from (0, 0) to that chord's end,
    10 mm (1 s at F600), and was timed as 0.8727 mm (0.087 s, clamped at X's velocity
    limit: 0.363 s). Such a move takes its own length; a chord of its arc still its piece
    of arc (the slice planned from the chord's start, the whole program: pi r / F)."""
    from machinesim.motion.timing import move_duration

    machine = load_machine("grooving_4axis")
    program = parse_program("G90 G21 G17\nG00 X10. Y0. Z0. C0.\nG01 X10. F600.\n"
                            "G03 X-10. Y0. I-10. J0.\nM30\n", chord_tolerance=1e-5)
    arc = np.flatnonzero(program.lines == 4)
    k = int(arc[4])
    cut = Program.from_moves(program.moves[k:], source=program.source)
    start = np.zeros(len(machine.axes))
    first = plan(cut, machine, start=start).segments[0]
    end = program.targets[k, :2]
    assert first.duration == pytest.approx(math.hypot(*end) / 0.01, rel=1e-12)  # 10 mm/s
    assert first.duration == pytest.approx(1.0, rel=1e-9)
    # planned from the chord's start it is that chord: its piece of arc over F
    start[:3] = program.targets[k - 1, :3]
    resumed = plan(cut, machine, start=start)
    assert resumed.segments[0].duration == pytest.approx(
        program.arc_lengths[k] / 0.01, rel=1e-12)
    assert plan(program, machine).cutting_time == pytest.approx(math.pi, rel=1e-12)
    # one move: a chord's arc length taken, another move's not
    rotary = np.array(machine.rotary)
    rate = np.asarray(machine.rapid_rate, dtype=np.float64)
    a, b = np.zeros(4), np.zeros(4)
    b[:2] = program.targets[k, :2] - program.targets[k - 1, :2]
    assert move_duration("linear", a, b, rotary, rate, 0.01, 0.0,
                         arc_length_m=program.arc_lengths[k]) == pytest.approx(
        program.arc_lengths[k] / 0.01, rel=1e-12)
    b[:2] = program.targets[k, :2]
    assert move_duration("linear", a, b, rotary, rate, 0.01, 0.0,
                         arc_length_m=program.arc_lengths[k]) == pytest.approx(1.0, rel=1e-9)


def test_a_planner_refusal_names_the_blocks_n_word_beside_its_line():
    # as the reader's refusals: 'line 2 (N40)' where the block has an N word, the line
    # alone where it has none; from a Program's arrays and from a plain list of Moves
    machine = load_machine("grooving_4axis")
    for text, where in (("G21 G90\nN40 G00 A1.\nM30\n", "p.nc, line 2 (N40), key 'A'"),
                        ("G21 G90\nG00 A1.\nM30\n", "p.nc, line 2, key 'A'")):
        program = parse_program(text, "p.nc")
        with pytest.raises(NCProgramError) as info:
            plan(program, machine)
        assert str(info.value) == f"{where}: axis A is not on grooving_4axis (axes XYZC)"

    class Moves:  # any object with moves (planner._program_arrays)
        source = "m.nc"
        moves = (Move("rapid", {"X": 0.0}, line=1, block_number=7),
                 Move("rapid", {"B": 0.1}, line=2, block_number=8))

    with pytest.raises(NCProgramError, match=r"^m.nc, line 2 \(N8\), key 'B': axis B is not"):
        plan(Moves(), machine)


@pytest.mark.parametrize("tolerance", [1e-9, 1e-5])
def test_move_duration_of_an_arc_chord_takes_its_piece_of_arc(tolerance):
    """`move_duration` (one move) times a chord given its ``arc_length_m`` as
    `move_durations` does: the half circle of R10 mm at F600 sums to pi r / F (3.14159 s),
    where its chords' own lengths ran fast by tol / (3 r) (3.2e-4 at 10 um); each move the
    same float as the planner's, and a chord given no arc length keeps its own."""
    from machinesim.motion import move_duration
    from machinesim.motion.timing import move_durations

    program = parse_program("G90 G21 G17\nG00 X10. Y0.\nG01 X10. F600.\n"
                            "G03 X-10. Y0. I-10. J0.\nM30\n", chord_tolerance=tolerance)
    targets, rotary = np.nan_to_num(program.targets), np.zeros(len(program.targets[0]), bool)
    rates = np.full(rotary.size, 1.0)
    arc = np.flatnonzero(program.lines == 4)
    one = [move_duration("linear", targets[i - 1], targets[i], rotary, rates,
                         program.feeds[i], 0.0, arc_length_m=program.arc_lengths[i])
           for i in arc]
    assert math.fsum(one) == pytest.approx(math.pi * 10.0 / 600.0 * 60.0, rel=1e-12)
    every = move_durations(program.kinds[arc], targets[arc - 1], targets[arc],
                           program.feeds[arc], program.dwells[arc], rotary, rates,
                           program.arc_lengths[arc])
    assert one == every.tolist()
    chords = [move_duration("linear", targets[i - 1], targets[i], rotary, rates,
                            program.feeds[i], 0.0) for i in arc]
    assert math.fsum(chords) < math.fsum(one) * (1.0 - tolerance / 10e-3 / 3.0 * 0.9)
    with pytest.raises(InputError) as caught:
        move_duration("linear", targets[arc[0] - 1], targets[arc[0]], rotary, rates,
                      program.feeds[arc[0]], 0.0, arc_length_m=-1e-3)
    assert caught.value.key == "arc_length_m"
    with pytest.raises(InputError) as caught:  # True is no length (it had timed 1 m)
        move_duration("linear", targets[arc[0] - 1], targets[arc[0]], rotary, rates,
                      program.feeds[arc[0]], 0.0, arc_length_m=True)
    assert caught.value.key == "arc_length_m"


def test_a_written_arc_program_keeps_chords_timed_by_the_chord_rule():
    """As format_program says: the writer writes an arc's chords as G01 blocks, so the text
    read back keeps no arc lengths and its chords take their own length over F (the half
    circle of R10 mm at F600 read at 10 um: 3.14060 s, not pi r / F = 3.14159 s)."""
    from machinesim.nc import format_program

    machine = load_machine("grooving_4axis")
    program = parse_program("G90 G21 G17\nG00 X10. Y0. Z0. C0.\nG01 X10. F600.\n"
                            "G03 X-10. Y0. I-10. J0.\nM30\n", chord_tolerance=1e-5)
    text = format_program(program)
    assert "G02" not in text and "G03" not in text
    again = parse_program(text)
    assert np.isnan(again.arc_lengths).all()
    arc = program.lines == 4
    chords_mm = np.hypot(*np.diff(program.targets[:, :2], axis=0)[arc[1:]].T).sum() * 1e3
    time = plan(again, machine).cutting_time
    assert time == pytest.approx(chords_mm / 600.0 * 60.0, rel=1e-7)  # 1 nm rounding
    assert plan(program, machine).cutting_time == pytest.approx(math.pi, rel=1e-12)
    assert math.pi * (1.0 - 1e-5 / 10e-3 / 3.0) < time < math.pi  # the sagitta <= tol


def test_a_planner_refusal_of_a_program_without_n_words_names_its_line():
    # _program_arrays reads any object with the arrays; one without block_numbers or moves
    # keeps no N words: its refusal names the line alone (it had raised AttributeError:
    # no attribute 'moves', looking for a Move's block_number)
    targets = np.full((2, 6), np.nan)
    targets[0, :2] = 0.0
    targets[1, :2] = (1e-3, 0.0)

    class Arrays:
        source = "a.nc"
        kinds = np.array([0, 1], dtype=np.int8)  # a rapid, then a feed move with no F
        feeds = np.array([np.nan, np.nan])
        dwells = np.zeros(2)
        lines = np.array([2, 3], dtype=np.int64)

    Arrays.targets = targets
    with pytest.raises(NCProgramError, match=r"^a.nc, line 3, key 'F': a feed move \(G01"):
        plan(Arrays(), load_machine("robonano_a0ib"))


def test_move_and_segment_indices_are_read_as_a_tuple_reads_them():
    # a float index ended in "AttributeError: 'float' object has no attribute '__index__'"
    # (program.moves, trajectory.segments) or numpy's IndexError (trajectory.segment); a
    # tuple of the same moves refuses it with TypeError and takes a NumPy integer or a bool
    program = parse_program("G90 G21\nG01 X1. F100.\nG01 X2.\nM30\n")
    tr = plan(program, "robonano_ui")
    as_tuple = tuple(program.moves)
    for index in (1.0, "1", None):
        with pytest.raises(TypeError, match="move indices must be integers or slices, not"):
            program.moves[index]
        with pytest.raises(TypeError, match="move indices must be integers or slices, not"):
            tr.segments[index]
        with pytest.raises(TypeError, match="move indices must be integers or slices, not"):
            tr.segment(index)
        with pytest.raises(TypeError):
            as_tuple[index]
    assert program.moves[np.int64(1)] == program.moves[True] == as_tuple[1]
    assert program.moves[-1] == as_tuple[-1]
    assert tr.segments[np.int64(-1)].line == tr.segments[len(tr) - 1].line
    with pytest.raises(IndexError, match="move index 2 out of range for 2 moves"):
        program.moves[2]
    with pytest.raises(IndexError, match=f"move index {len(tr)} out of range"):
        tr.segment(len(tr))
