"""The vectorised planner gives the line-by-line planner's trajectory, number for number,
except where its faster chord rule picks another sub-step count, which is then checked on
its own against the tolerance.

`motion_reference` (next to this file) is the planner as it was before it was vectorised,
kept verbatim. Every segment is compared exactly: the same samples, times, kinds and lines,
the same durations, machining and cutting time and notes. Exact equality holds because the
vectorised planner forms every number by the same float64 operations in the same order
(see `machinesim.motion.chords`); only the sign of a zero may differ, which ``==`` does not
see and which no later number depends on.

The sub-step count of a rotary move is predicted from one chord (`chords.substeps`) instead
of the reference's bisection from 8 sub-steps, and raised where an error table's breakpoint
puts a corner in the path between midpoints; the two agree on most moves. Where they
differ, the segment must still run from the same start to the same end in the same time,
and its chords must hold the tolerance: checked here by evaluating `Machine.tool_pose`
densely along every sub-step (distance from the chord's line), independently of the
planner's own checks.
"""

from __future__ import annotations

import math

import motion_reference as reference
import numpy as np
import pytest
from motion_helpers import assert_same, chord_deviation, random_program

import machinesim
from machinesim import load_machine
from machinesim.exceptions import NCProgramError
from machinesim.motion import plan
from machinesim.motion.chords import ToolPaths, deviations
from machinesim.nc import Move, Program, ProgramBuilder, parse_program
from machinesim.sampling import random_errors
from machinesim.tool_specs import tool_from_spec

MACHINES = ("robonano_a0ib", "planer_4axis", "grooving_4axis", "robonano_ui", "sts_lathe")


@pytest.fixture(scope="module")
def machines():
    return {name: load_machine(name) for name in MACHINES}


@pytest.mark.parametrize("name", MACHINES)
@pytest.mark.parametrize("seed", [0, 1])
def test_random_programs_nominal_and_with_errors(machines, name, seed):
    machine = machines[name]
    rng = np.random.default_rng(seed * 101 + MACHINES.index(name))
    program = random_program(machine, rng, 40)
    for errors in (None, random_errors(machine, rng)):
        for tolerance in (1e-9, 1e-7):
            new = plan(program, machine, errors, chord_tolerance=tolerance)
            old = reference.plan(program, machine, errors, chord_tolerance=tolerance)
            assert_same(new, old, check=(machine, errors, np.zeros((1, 3)), tolerance))


@pytest.mark.parametrize("spec", ["v:90", "nose:2.0:90"])
@pytest.mark.parametrize("name", ["planer_4axis", "robonano_a0ib", "sts_lathe"])
def test_tool_points_and_start(machines, name, spec):
    machine = machines[name]
    rng = np.random.default_rng(len(spec) + MACHINES.index(name))
    program = random_program(machine, rng, 12, big_turns=False)
    points = tool_from_spec(spec).vertices()
    if len(points) > 40:
        points = points[:: len(points) // 40]
    start = (machine.lower + machine.upper) / 2 * 0.0 + rng.normal(0, 1e-3, len(machine.axes))
    errors = random_errors(machine, rng)
    new = plan(program, machine, errors, start=start, tool_points=points, chord_tolerance=5e-9)
    old = reference.plan(program, machine, errors, start=start, tool_points=points,
                         chord_tolerance=5e-9)
    assert_same(new, old, check=(machine, errors, points, 5e-9))


class LagServo:
    """A first-order lag over each motion it is given (state starts at the first sample)."""

    def __init__(self, tau: float) -> None:
        self.tau = tau

    def follow(self, t, q):
        out = q.copy()
        for i in range(1, len(q)):
            a = 1.0 - math.exp(-(t[i] - t[i - 1]) / self.tau) if self.tau else 1.0
            out[i] = out[i - 1] + a * (q[i] - out[i - 1])
        return out


def test_a_servo_model_follows_feed_runs_as_one_motion(machines):
    machine = machines["grooving_4axis"]
    program = random_program(machine, np.random.default_rng(7), 25)
    servo = LagServo(0.05)
    # at 1 um the followed steps keep the chord rule (at 1 nm the lag's catch-up after a
    # rapid breaks it, and the planner follows those runs again on a finer sampling, which
    # the reference, move by move, does not: tests/test_servo_following.py); the three
    # motions whose settling step (the lag at their end) the planner splits still start and
    # end on the command
    assert_same(plan(program, machine, servo=servo, chord_tolerance=1e-6),
                reference.plan(program, machine, servo=servo, chord_tolerance=1e-6))


def test_exact_stops_end_the_servo_s_feed_runs_as_the_reference_does(machines):
    machine = machines["grooving_4axis"]
    program = random_program(machine, np.random.default_rng(11), 40)
    stops = np.flatnonzero(np.random.default_rng(3).random(len(program)) < 0.3)
    stopped = Program.from_arrays(program.targets, program.kinds, program.feeds,
                                  program.dwells, program.lines, exact_stops=stops)
    servo = LagServo(0.05)
    new = plan(stopped, machine, servo=servo)
    assert_same(new, reference.plan(stopped, machine, servo=servo))
    # the stops change the motion: the run no longer carries the lag across them
    assert not np.array_equal(new.q, plan(program, machine, servo=servo).q)


def test_an_sts_point_list_from_nc_text(machines):
    """The slow-tool-servo style: G01 X Z C point after point on a spiral, read from text."""
    machine = machines["sts_lathe"]
    k = np.arange(300)
    x = 10.0 * (1.0 - k / 300)
    c = k * 2.7  # deg, 2.7 deg a point: 1 to 8 sub-steps depending on the radius
    z = 0.01 * np.sin(np.radians(c) * 3.0)
    text = "G90 G21 G94\nG00 X10. Z1. C0.\nG01 Z0. F20.\n" + "".join(
        f"X{a:.6f} Z{b:.6f} C{d:.5f}\n" for a, b, d in zip(x, z, c, strict=True)) + "M30\n"
    program = parse_program(text)
    new = plan(program, machine)
    old = reference.plan(program, machine)
    assert_same(new, old)
    assert len({len(s.q) for s in new.segments}) > 3  # various sub-step counts were chosen
    # near-circular sub-steps: within tolerance everywhere along them, not only at midpoints
    edge = np.zeros((1, 3))
    worst = max(chord_deviation(machine, None, edge, s.q) for s in new.segments[2:])
    assert worst <= 1.001 * 1e-9


def test_a_corner_of_an_error_table_is_held_to_the_tolerance(machines):
    """An error table turns the path where its axis crosses a breakpoint. With the edge on
    the C axis (X = 0) only EXC and EYC move it: 2 um along X while C turns to 5.85 deg,
    then 2 um along Y until 14 deg, an L with its corner off the sub-step midpoints (the
    midpoint rule alone left it 1.30 nm from its chord); the chords still hold 1 nm."""
    machine = machines["sts_lathe"]
    errors = machinesim.ErrorModel.from_dict({"component": {"C": {
        "position_deg": [0.0, 5.85, 14.0, 30.0], "EXC_um": [0.0, 2.0, 2.0, 2.0],
        "EYC_um": [0.0, 0.0, 2.0, 2.0]}}})
    program = ProgramBuilder(source="corner").rapid(X=0.0, Z=0.0, C=0.0).linear(
        C=math.radians(14.0), feed_mm_per_min=100.0).build()
    tolerance = 1e-9
    new = plan(program, machine, errors, chord_tolerance=tolerance)
    turn = next(s for s in new.segments if s.q[-1, 2] != s.q[0, 2])
    assert chord_deviation(machine, errors, np.zeros((1, 3)), turn.q) <= tolerance


def test_a_corner_of_a_table_of_a_whole_turn_is_held_each_turn(machines):
    """The same L in a table of a whole turn (back to 0 at 360 deg), turned a turn later, C
    from 360 to 374 deg: the table repeats each turn, and so does its corner at 5.85 deg
    (365.85 deg here). Only the table's own breakpoints were checked, so the midpoints alone
    left this chord 1.30 nm from the corner, and the rapid from 0 to -720 deg, whose one
    chord has the table's 0 at its ends and its midpoint, 2.83 um; they hold 1 nm now."""
    machine = machines["sts_lathe"]
    errors = machinesim.ErrorModel.from_dict({"component": {"C": {
        "position_deg": [0.0, 5.85, 14.0, 30.0, 360.0], "EXC_um": [0.0, 2.0, 2.0, 2.0, 0.0],
        "EYC_um": [0.0, 0.0, 2.0, 2.0, 0.0]}}})
    tolerance = 1e-9
    for first in (0.0, 360.0, -720.0):
        program = ProgramBuilder(source="corner").rapid(
            X=0.0, Z=0.0, C=math.radians(first)).linear(
            C=math.radians(first + 14.0), feed_mm_per_min=100.0).build()
        new = plan(program, machine, errors, chord_tolerance=tolerance)
        for turn in (s for s in new.segments if s.q[-1, 2] != s.q[0, 2]):
            worst = chord_deviation(machine, errors, np.zeros((1, 3)), turn.q)
            assert worst <= tolerance, (first, turn.q[[0, -1], 2], worst)


def test_a_corner_is_held_again_when_the_45_deg_rule_raises_the_count(machines):
    """C turns 260 deg with the edge on the axis; EXC 0.64 um and EYC 0.2 um at 60 deg, 0
    at 0 and 260 deg: a corner at 60 deg. The chord rule holds 160 nm with 5 sub-steps
    (the corner off 52 deg's node by 8 deg); the 45 deg rule raises them to 6, whose
    midpoints hold, but not the corner: left 184 nm (1.15 tolerances) off its chord's line,
    as 64 points a sub-step show, since the corners were not checked again."""
    machine = machines["sts_lathe"]
    errors = machinesim.ErrorModel.from_dict({"component": {"C": {
        "position_deg": [0.0, 60.0, 260.0], "EXC_um": [0.0, 0.64, 0.0],
        "EYC_um": [0.0, 0.2, 0.0]}}})
    program = ProgramBuilder(source="corner").rapid(X=0.0, Z=0.0, C=0.0).linear(
        C=math.radians(260.0), feed_mm_per_min=100.0).build()
    tolerance = 160e-9
    turn = plan(program, machine, errors, chord_tolerance=tolerance).segments[1]
    assert len(turn.q) - 1 >= 6  # at most 45 deg a sub-step
    assert chord_deviation(machine, errors, np.zeros((1, 3)), turn.q, 64) <= tolerance


def test_a_corner_is_held_again_when_a_flat_face_raises_the_count(machines):
    """A turns 0.7 deg on planer_4axis with a flat face 0.5 mm across (face_radius), EYA and
    EZA tables with corners at 0.26, 0.28 and 0.48 deg, 13 nm: the chord rule holds them
    with 70 sub-steps, the face rule raises them to 238, which left a corner 13.9 nm (1.07
    tolerances) off its chord's line (64 points a sub-step): the raised counts' corners were
    not checked again."""
    machine = machines["planer_4axis"]
    errors = machinesim.ErrorModel.from_dict({"component": {"A": {
        "position_deg": [-45.0, 0.26, 0.28, 0.48, 45.0], "EYA_um": [0.0, 0.0, 0.4, 0.8, 0.0],
        "EZA_um": [0.0, -0.6, -0.2, -0.2, 0.0]}}})
    program = ProgramBuilder(source="face").rapid(X=0.0, Y=0.0, Z=0.0, A=0.0).linear(
        A=math.radians(0.7), feed_mm_per_min=100.0).build()
    tolerance = 13e-9
    plain = plan(program, machine, errors, chord_tolerance=tolerance).segments[1]
    turn = plan(program, machine, errors, chord_tolerance=tolerance,
                face_radius=0.5e-3).segments[1]
    assert len(turn.q) > len(plain.q)  # the face rule raised the count
    assert chord_deviation(machine, errors, np.zeros((1, 3)), turn.q, 64) <= tolerance
    # the servo's followed steps are held to the same rule (`following.StepRule`)
    from machinesim.motion.following import StepRule

    bending = np.array([False, False, False, True])
    rule = StepRule(machine, errors, np.zeros((1, 3)), bending, tolerance, 0.5e-3)
    start = turn.q[:1]
    n = int(rule.counts(start, turn.q[-1:] - start)[0])
    q = start + np.linspace(0.0, 1.0, n + 1)[:, None] * (turn.q[-1:] - start)
    assert chord_deviation(machine, errors, np.zeros((1, 3)), q, 64) <= tolerance


def test_a_table_of_a_whole_turn_that_steps_where_it_wraps_is_refused_at_once(machines):
    """ECC 1 arcsec at -180 deg and -1 at 180 (the README's example before): repeated each
    turn, C's error steps 2 arcsec where C passes 180 deg, so the edge 10 mm off the C axis
    jumps r * 2 sin(dECC / 2) = 96.96 nm, and no chord follows it (the planner raised the
    sub-steps by 10 % a round towards a million, for more than 15 minutes on the grooves).
    Refused naming the line and the step; a move that only reaches 180 deg has no step, and
    the table with its ends equal is planned."""
    machine = machines["sts_lathe"]
    arcsec = math.pi / 648000

    def errors(last):
        return machinesim.ErrorModel.from_dict({"component": {"C": {
            "position_deg": [-180.0, 0.0, 180.0], "ECC_arcsec": [1.0, 0.0, last]}}})

    def program(*turns):
        b = ProgramBuilder(source="wrap").rapid(X=0.01, Z=0.0, C=0.0)
        for c in turns:
            b.linear(C=math.radians(c), feed_mm_per_min=100.0)
        return b.build()

    step = 0.01 * 2 * math.sin(2 * arcsec / 2)
    assert f"{step * 1e9:.3g}" == "97"
    for turns, line in (((200.0,), 2), ((180.0, 250.0), 3), ((-90.0, -190.0), 3),
                        ((100.0, 900.0), 3)):
        with pytest.raises(NCProgramError, match=(
                r"C passes -?\d+ deg, where component\.C\.ECC, a table of a whole turn "
                r"repeated each turn, wraps .*\(4\.84814 urad at -180 deg, -4\.84814 urad "
                r"at 180 deg\): the tool path steps 97 nm there")) as info:
            plan(program(*turns), machine, errors(-1.0), chord_tolerance=1e-9)
        assert info.value.line == line, turns
    reached = plan(program(180.0), machine, errors(-1.0), chord_tolerance=1e-9)
    closed = plan(program(200.0, 900.0), machine, errors(1.0), chord_tolerance=1e-9)
    for trajectory, model in ((reached, errors(-1.0)), (closed, errors(1.0))):
        for turn in (s for s in trajectory.segments if s.q[-1, 2] != s.q[0, 2]):
            assert chord_deviation(machine, model, np.zeros((1, 3)), turn.q) <= 1e-9


def test_a_path_that_steps_inside_a_table_is_refused_at_the_first_raise(machines, monkeypatch):
    """EYX steps 1 um between X = 0 and 1 pm: the chord of any sub-step across it sits at
    half the step, so the move's deviation is 500 nm at every count. From 8 sub-steps the
    rule raises to ceil(8 sqrt(500 nm / 1 nm)) = 179, where a smooth path's deviation would
    have fallen 500-fold; the move is refused there, naming the step's place and table. The
    rule went on raising by 10 % a round towards a million (93 rounds, 2.9 s for the edge
    alone; with a nose tool's 397 points not done in 10 min) and then blamed the tolerance."""
    from machinesim.motion import chords

    machine = machines["grooving_4axis"]
    errors = machinesim.ErrorModel.from_dict({"component": {"X": {
        "position_mm": [-100.0, 0.0, 1e-9, 100.0], "EYX_um": [0.0, 0.0, 1.0, 1.0]}}})
    program = ProgramBuilder(source="step").rapid(X=-0.01, Y=0.0, Z=0.0).linear(
        X=0.0123, feed_mm_per_min=500.0).build()
    counts = []
    evaluate = chords.deviations

    def spy(paths, start, delta, ns, index=None):
        counts.extend(ns.tolist())
        return evaluate(paths, start, delta, ns, index)

    monkeypatch.setattr(chords, "deviations", spy)
    assert math.ceil(8 * math.sqrt(500.0)) == 179
    with pytest.raises(NCProgramError) as info:
        plan(program, machine, errors, chord_tolerance=1e-9)
    assert info.value.line == 2
    message = info.value.message
    assert message.startswith(
        "a move whose path steps: its chords do not converge on it (500 nm off at 8 "
        "sub-steps, still 500 nm at 179, where a smooth path's deviation falls as 1/n**2); "
        "at X = ")
    # the piece found: 1/(179 * 64**3) of the 22.3 mm move, about X = 0 (the step), off
    # its chord by half the step
    piece = 22.3 / (179 * 64**3)
    at = float(message.split("at X = ")[1].split(" mm")[0])
    assert abs(at) <= piece
    assert (f"a piece of X {piece:.6g} mm (1/{179 * 64**3} of the move, finer than "
            "1000000 sub-steps split it) by 500 nm, more than the chord tolerance 1 nm. "
            "The error table component.X.EYX changes from 0 to 1 um between X = 0 mm and "
            "1e-09 mm there, a step no chord follows") in message
    assert max(counts) == 179


def test_a_dense_table_s_stalled_deviation_is_looked_into_and_the_counts_kept(
        machines, monkeypatch):
    """A table every 10 um with 50 nm of noise: the deviation hardly falls while the
    sub-steps are longer than the table's spacing, which starts the look for a step; none
    is there (its finest pieces are within 1e-12 m of their chords), so the counts are those
    of the rule with no look at all, and the chords hold the tolerance."""
    from machinesim.motion import steps

    machine = machines["grooving_4axis"]
    knots = np.linspace(-1.0, 1.0, 201)
    noise = np.random.default_rng(0).normal(0.0, 50.0, knots.size)
    errors = machinesim.ErrorModel.from_dict({"component": {"X": {
        "position_mm": knots.tolist(), "EYX_nm": noise.tolist()}}})
    program = ProgramBuilder(source="dense").rapid(X=-0.0011, Y=0.0, Z=0.0).linear(
        X=0.00113, feed_mm_per_min=500.0).build()
    looked = []
    zoom = steps._zoom

    def spy(*args):
        looked.append(zoom(*args))
        return looked[-1]

    monkeypatch.setattr(steps, "_zoom", spy)
    found = plan(program, machine, errors, chord_tolerance=1e-9)
    assert looked and max(deviation for _, _, deviation in looked) < 1e-12
    monkeypatch.setattr(steps, "_zoom", lambda *args: (0.0, 1.0, 0.0))
    unlooked = plan(program, machine, errors, chord_tolerance=1e-9)
    assert [len(s.q) for s in found.segments] == [len(s.q) for s in unlooked.segments]
    for segment, other in zip(found.segments, unlooked.segments, strict=True):
        assert np.array_equal(segment.q, other.q)
        assert chord_deviation(machine, errors, np.zeros((1, 3)), segment.q) <= 1e-9


def test_a_straight_move_follows_a_straightness_table(machines):
    """X travelling 300 mm on a machine whose EYX table bends at -100, 0 and +100 mm: the
    tool's path is the table, not the chord between the ends, so the move is split like a
    rotary one and its chords hold the tolerance; at the breakpoints the path's Y is
    EYX there (a table on the knots, read back by kinematics)."""
    machine = machines["grooving_4axis"]
    knots = [-200.0, -100.0, 0.0, 100.0, 200.0]
    eyx = [0.0, 1.5, -0.5, 2.0, 0.0]
    errors = machinesim.ErrorModel.from_dict({"component": {"X": {
        "position_mm": knots, "EYX_um": eyx}}})
    program = ProgramBuilder(source="line").rapid(X=-0.15, Y=0.0, Z=0.0).linear(
        X=0.15, feed_mm_per_min=500.0).build()
    tolerance = 1e-9
    new = plan(program, machine, errors, chord_tolerance=tolerance)
    move = new.segments[-1]
    assert len(move.q) > 2
    assert chord_deviation(machine, errors, np.zeros((1, 3)), move.q) <= tolerance
    nominal = chord_deviation(machine, None, np.zeros((1, 3)), move.q[[0, -1]])
    assert nominal == 0.0  # the same move on the nominal machine is one straight sweep
    bent = machine.tool_pose(np.array([[x * 1e-3, 0, 0, 0] for x in (-100.0, 0.0, 100.0)]),
                             errors)[:, 1, 3] - machine.tool_pose(
        np.array([[x * 1e-3, 0, 0, 0] for x in (-100.0, 0.0, 100.0)]))[:, 1, 3]
    assert np.abs(np.abs(bent) - np.array([1.5, 0.5, 2.0]) * 1e-6).max() < 1e-12
    assert len(plan(program, machine, None, chord_tolerance=tolerance).segments[-1].q) == 2


def test_a_pure_turn_takes_the_fewest_sub_steps(machines):
    """C turning a point at radius r: a chord of angle h deviates by r (1 - cos(h / 2)), so
    the fewest sub-steps are ceil(theta / (2 acos(1 - tol / r)))."""
    machine = machines["sts_lathe"]
    tolerance = 1e-9
    for radius_mm, turn_deg in ((10.0, 3.0), (1.0, 7.5), (0.3, 40.0), (5.0, 0.5)):
        program = ProgramBuilder().rapid(X=radius_mm * 1e-3, Z=0.0, C=0.0).linear(
            C=math.radians(turn_deg), feed_mm_per_min=100.0).build()
        segment = plan(program, machine, chord_tolerance=tolerance).segments[-1]
        r = np.hypot(*machine.tool_pose(segment.q[:1])[0, :2, 3])
        fewest = math.ceil(math.radians(turn_deg) / (2 * math.acos(1 - tolerance / r)))
        assert len(segment.q) - 1 == fewest, (radius_mm, turn_deg)


def test_moves_large_enough_for_several_kinematic_blocks(machines):
    """A move split into more than 8192 sub-steps is evaluated in blocks by tool_pose: the
    series/cos choice is made per block, here too."""
    machine = machines["grooving_4axis"]
    program = ProgramBuilder().rapid(X=0.05, Y=0.0, Z=0.0, C=-0.001).linear(
        C=0.03, feed_mm_per_min=100.0).linear(C=0.5).linear(C=0.501).linear(C=-0.001).linear(
        C=0.03).build()
    # the last turn repeats the first: the same n, yet each is a batch of its own when cut
    # in blocks (at 5e-14, n ~ 12,000); at 1e-14 the first block of these turns is in series
    # range (|C| < 0.01 rad) and their next blocks are not
    for tolerance in (1e-12, 5e-14, 1e-14):
        new = plan(program, machine, chord_tolerance=tolerance)
        old = reference.plan(program, machine, chord_tolerance=tolerance)
        assert_same(new, old)
    assert max(len(s.q) for s in new.segments) > 8193


def test_an_empty_program_and_dwells_only(machines):
    machine = machines["planer_4axis"]
    for program in (ProgramBuilder().build(), ProgramBuilder().dwell(1.0).dwell(-0.0).build()):
        assert_same(plan(program, machine), reference.plan(program, machine))


def errors_of(call):
    try:
        call()
    except NCProgramError as error:
        return str(error), error.line, error.key
    return None


@pytest.mark.parametrize("text", [
    "G01 X1. F100.\nG01 A10.\nG01 C10.\n",          # A is not on the machine: line 2
    # no feed: line 2 (the reader refuses 'G00 X1.\nG01 X2.\nG01 C20. F10.'; built from moves)
    Program.from_moves([Move("rapid", {"X": 1e-3}), Move("linear", {"X": 2e-3}, line=2),
                        Move("linear", {"X": 2e-3, "C": math.radians(20.0)},
                             feed_m_per_s=10e-3 / 60.0, line=3)]),
    "G01 C180. F100.\nG01 A1.\n",                      # the rotary move fails first: line 1
    "G00 X1.\nG01 Y1. F10\nG01 C359.\nG01 A1.\n",     # the rotary move fails first: line 3
])
def test_errors_name_the_same_move(machines, text):
    machine = machines["grooving_4axis"]
    program = parse_program(text) if isinstance(text, str) else text
    new = errors_of(lambda: plan(program, machine, chord_tolerance=1e-17))
    old = errors_of(lambda: reference.plan(program, machine, chord_tolerance=1e-17))
    assert new is not None and new == old


def test_batched_deviations_equal_one_move_at_a_time(machines):
    """The batch evaluator against the reference's deviation, move by move and n by n."""
    machine = machines["robonano_ui"]
    rng = np.random.default_rng(5)
    errors = random_errors(machine, rng)
    points = np.vstack([np.zeros((1, 3)), rng.normal(0, 1e-3, (4, 3))])
    paths = ToolPaths(machine, errors, points)
    start = rng.normal(0, 0.2, (30, 6)) * [0.1, 0.1, 0.1, 1, 1, 1]
    delta = rng.normal(0, 0.05, (30, 6))
    ns = rng.integers(1, 40, 30)
    batch = deviations(paths, start, delta, ns)
    for i in range(30):
        f = np.linspace(0.0, 1.0, ns[i] + 1)
        mid = (f[:-1] + f[1:]) / 2
        nodes = machine.tool_pose(start[i] + f[:, None] * delta[i], errors)
        middle = machine.tool_pose(start[i] + mid[:, None] * delta[i], errors)
        p_nodes = nodes[:, :3, :3] @ points.T + nodes[:, :3, 3:4]
        p_mid = middle[:, :3, :3] @ points.T + middle[:, :3, 3:4]
        one = float(np.max(np.linalg.norm(p_mid - (p_nodes[:-1] + p_nodes[1:]) / 2, axis=1)))
        assert batch[i] == one, i
