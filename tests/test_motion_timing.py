"""Motion: machining time by the FANUC feed rule, clamped at an axis' velocity limit, and an
arc's time as its length over F."""

from __future__ import annotations

import math

import numpy as np
import pytest

from machinesim import load_machine
from machinesim.exceptions import InputError, NCProgramError
from machinesim.motion import plan
from machinesim.nc import Move, Program, parse_program


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
