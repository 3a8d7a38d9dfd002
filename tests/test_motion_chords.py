"""Motion: rotary moves and moves bent by the errors split to the chord tolerance; linear moves
kept whole."""

from __future__ import annotations

import math

import numpy as np
import pytest

from machinesim import ErrorModel, ToolSetting, load_machine
from machinesim.exceptions import NCProgramError
from machinesim.motion import plan
from machinesim.nc import Move, Program, ProgramBuilder, parse_program


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
