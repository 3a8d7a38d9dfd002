"""The followed (servo) path is cut as finely as a commanded one: its steps keep the chord
tolerance and the 45 deg sub-step, its samples lying on the servo's own motion
(`machinesim.motion.following`)."""

import math
import re

import numpy as np
import pytest
from slow_loops import Jump, slow_c

from machinesim import load_machine
from machinesim.cutting import cut
from machinesim.exceptions import NCProgramError
from machinesim.motion import plan
from machinesim.nc import parse_program

# a half turn of C at X 3 mm, 50 um deep, in one feed run with the plunge before it
HALF_TURN = ("G90 G21\nG00 X3. Y0. Z0.5 C0.\nG01 Z-0.05 F100.\nG01 C180. F36000.\n"
             "G00 Z1.\nM30\n")



def test_a_followed_half_turn_steps_at_most_45_deg_on_the_servo_s_own_motion():
    machine = load_machine("grooving_4axis")
    program = parse_program(HALF_TURN)
    servo = slow_c(machine, 1e-4)
    # chord 1 m: the 45 deg sub-step alone splits the move (4 commanded steps)
    lagged = plan(program, machine, servo=servo, chord_tolerance=1.0)
    c = machine.axes.index("C")
    # the old planner followed the command's 4 samples: one followed step turned C by
    # 78.7 deg (20.2 -> 98.9), cut as one sweep's hull
    assert np.degrees(np.abs(np.diff(lagged.q[:, c]))).max() <= 45.0
    # the reference: the run (the plunge and the half turn) followed on a fine sampling of
    # the same command, its times holding the plan's
    ideal = plan(program, machine, chord_tolerance=1.0)
    run = lagged.rows(("linear",))
    t = lagged.t[run]
    end = t[-1]
    fine_t = np.union1d(np.linspace(t[0], end, 4001), t)
    ideal_run = ideal.rows(("linear",))
    fine_q = np.column_stack([np.interp(fine_t, ideal.t[ideal_run], ideal.q[ideal_run, k])
                              for k in range(len(machine.axes))])
    reference = servo.follow(fine_t, fine_q)
    moving = t < end  # up to the command's end; then the axes settle onto it
    got = np.interp(t[moving], fine_t, reference[:, c])
    assert np.max(np.abs(lagged.q[run][moving, c] - got)) < 1e-9
    lag_at_end = math.pi - float(reference[-1, c])
    assert math.degrees(lag_at_end) > 10.0  # a settling step of its own
    assert lagged.peak_lag[c] >= lag_at_end
    assert lagged.q[run][-1, c] == math.pi


def test_only_the_followed_steps_that_turn_past_45_deg_are_split():
    # The old planner split every step of a move as finely as its worst followed step
    # needed: a V-tool spiral through docs/cli.md's loops (13632 sweeps where the command
    # took 6816) cut in 134 s against 38 s. Here the hand rule picks the steps: the servo's
    # own motion (a fine reference, as above) at the command's samples; a step within the
    # half turn that turns C past 45 deg is split into ceil(turn / 45 deg) equal pieces of
    # time, the others kept; the settling step to C180 (24 deg) is not split.
    machine = load_machine("grooving_4axis")
    program = parse_program(HALF_TURN)
    servo = slow_c(machine, 1e-4)
    lagged = plan(program, machine, servo=servo, chord_tolerance=1.0)
    ideal = plan(program, machine, chord_tolerance=1.0)
    c = machine.axes.index("C")
    run = ideal.rows(("linear",))
    t = ideal.t[run]
    fine_t = np.union1d(np.linspace(t[0], t[-1], 4001), t)
    fine_q = np.column_stack([np.interp(fine_t, t, ideal.q[run, k])
                              for k in range(len(machine.axes))])
    reached = np.interp(t, fine_t, servo.follow(fine_t, fine_q)[:, c])
    turn = np.degrees(np.diff(reached))
    within = np.diff(t) > 0.0  # the step from the plunge's end to the turn's start is none
    within[-1] = False  # the settling step
    pieces = np.where(within, np.ceil(turn / 45.0), 1).astype(int)
    assert pieces.tolist().count(2) == 2 and pieces.max() == 2  # the 78.7 and 56.9 deg steps
    added = [t[i] + (t[i + 1] - t[i]) * k / n for i, n in enumerate(pieces) for k in range(1, n)]
    expected = np.sort(np.concatenate([ideal.t, added]))
    np.testing.assert_allclose(lagged.t, expected, rtol=0.0, atol=1e-12)
    assert np.degrees(np.abs(np.diff(lagged.q[:, c]))).max() <= 45.0


def test_a_lag_beyond_45_deg_settles_in_steps_of_45_deg_at_most():
    # at 1e-5 of the gains the lag at the command's end is 80 deg: the old planner went on
    # from it to C180 in one step (and 125 deg in one followed step before it, which the
    # engine refused naming poses 5 and 6); now straight in steps of at most 45 deg
    machine = load_machine("grooving_4axis")
    lagged = plan(parse_program(HALF_TURN), machine, servo=slow_c(machine, 1e-5),
                  chord_tolerance=1.0)
    c = machine.axes.index("C")
    move = lagged.segments[2]  # G01 C180.
    steps = np.diff(move.q[:, c])
    assert np.all(steps >= 0.0) and np.degrees(steps).max() <= 45.0
    assert move.q[-1, c] == math.pi and move.t[-1] == lagged.segments[3].t[0]
    assert np.all(np.diff(move.t) >= 0.0)
    assert math.degrees(lagged.peak_lag[c]) > 45.0


def test_a_cut_through_lagging_loops_removes_what_the_commanded_half_turn_does():
    # C alone lags and never passes its command: the tool sweeps the same half turn, so the
    # cut removes what the exact axes remove. At 1e-6 of Table 6's gains the lag reaches
    # 165 deg; the old planner went from there to C180 in one step, a chord across the arc
    # the ball cut as a straight groove: 7.548e-11 m^3 of 9.759e-11, without a word
    machine = load_machine("grooving_4axis")
    program = parse_program(HALF_TURN)
    _, exact = cut(program, machine, "ball:1.0", "block:10x10x2", chord_tolerance=1e-6)
    _, lagged = cut(program, machine, "ball:1.0", "block:10x10x2",
                    servo=slow_c(machine, 1e-6), chord_tolerance=1e-6)
    assert math.degrees(lagged.peak_following_error["C"]) > 160.0
    # the two sample the arc at other angles: the ball's mesh (1 um) and the chords (1 um)
    assert lagged.removed_volume_m3 == pytest.approx(exact.removed_volume_m3, rel=1e-3, abs=0.0)


def test_a_followed_path_that_jumps_is_refused_naming_the_line_and_the_servo():
    machine = load_machine("grooving_4axis")
    program = parse_program(HALF_TURN)
    with pytest.raises(NCProgramError, match=re.escape(
            "line 4: the axes' path as the servo model Jump follows this move does not keep "
            "the rules of a commanded move's sub-steps (chords within 1e+09 nm, at most 45 "
            "deg a sub-step): it still breaks them after 8 rounds of finer sampling (its "
            "path jumps); check the servo loops' gains")):
        plan(program, machine, servo=Jump(3), chord_tolerance=1.0)


def test_a_followed_path_refused_names_the_block_s_n_word_beside_its_line():
    # the same refusal in a program with N words names the block as a machinist finds it,
    # 'line 4 (N40)', as the reader's and the planner's refusals do (it had said 'line 4')
    numbered = "\n".join(f"N{10 * i} {text}"
                         for i, text in enumerate(HALF_TURN.splitlines(), 1)) + "\n"
    with pytest.raises(NCProgramError, match=re.escape(
            "line 4 (N40): the axes' path as the servo model Jump follows this move does not "
            "keep the rules")):
        plan(parse_program(numbered), load_machine("grooving_4axis"), servo=Jump(3),
             chord_tolerance=1.0)
