"""The lathe's followed path keeps its command's rules, its samples on the servo's own
motion: a quarter turn of C a step, and each straight join within the chord tolerance of
that motion, so it cuts the surface the motion cuts (`machinesim.cutting.lathe_following`)."""

import math
import re

import numpy as np
import pytest
from slow_loops import Jump, slow_c

from machinesim import load_machine
from machinesim.cutting.lathe import TurnedPart, followed, turn, turning_runs
from machinesim.cutting.lathe_following import follow_run
from machinesim.cutting.turning import edge_path_from_poses
from machinesim.exceptions import NCProgramError
from machinesim.nc import parse_program

# ten turns of C facing in from X 1 mm to 0.5 mm, 1 um deep: 40 quarter-turn steps
FACING = ("G90 G21\nG00 X1.0 Z0.01 C0\nG01 Z-0.001 F10\nG01 X0.5 C3600. F36000\n"
          "G00 Z0.01\n")
SLOWER = FACING.replace("F36000", "F3600")



def test_a_slow_spindle_loop_is_followed_in_quarter_turns_on_its_own_motion():
    machine = load_machine("sts_lathe")
    program = parse_program(FACING)
    servo = slow_c(machine, 1e-4)
    c = machine.axes.index("C")
    part, _ = turn(program, machine, servo=servo)
    # the old turn followed the command's 41 samples: steps of 166.6 deg of C
    assert np.degrees(np.diff(part.paths[0].angle)).max() <= 90.0
    (t, q), = turning_runs(program, machine)
    fine_t, fine_q, reached = follow_run(servo, t, q, np.full(len(t) - 1, 4), machine, "f")
    assert len(fine_t) == len(part.paths[0].angle) > len(t)
    assert np.degrees(np.abs(np.diff(reached[:, c]))).max() <= 90.0
    # the added samples lie on the command, and the followed values on the servo's own
    # motion: the command sampled 64 times finer (and at these times), followed by the
    # same loops, reads the same there, within what these slow loops make of the
    # command's round-off (7e-15 rad of C moves their output by 3.6e-7 rad; a sample off
    # the motion would be degrees off)
    assert np.allclose(fine_q[:, c], np.interp(fine_t, t, q[:, c]), rtol=0.0, atol=1e-12)
    k = 64
    dense = np.interp(np.arange((len(t) - 1) * k + 1) / k, np.arange(len(t)), t)
    both = np.union1d(dense, fine_t)
    command = np.column_stack([np.interp(both, t, q[:, j]) for j in range(q.shape[1])])
    reference = followed(servo.follow, both, command)[np.searchsorted(both, fine_t)]
    assert np.abs(reached[:, c] - reference[:, c]).max() < 1e-6


def _finely_followed(machine, program, servo, tool, k: int = 64) -> TurnedPart:
    """The reference: the same command sampled ``k`` times finer (on its moves), followed
    by the same loops, its edge path joined straight from those samples."""
    (t, q), = turning_runs(program, machine)
    fine_t = np.interp(np.arange((len(t) - 1) * k + 1) / k, np.arange(len(t)), t)
    fine_q = np.column_stack([np.interp(fine_t, t, q[:, j]) for j in range(q.shape[1])])
    reached = followed(servo.follow, fine_t, fine_q)
    path = edge_path_from_poses(machine.tool_pose(reached, None), tool.nose_radius)
    return TurnedPart((path,), tool, 0.0)


@pytest.mark.parametrize(("text", "scale"), [(FACING, 1e-4), (SLOWER, 1e-6)],
                         ids=["F36000 x1e-4", "F3600 x1e-6"])
def test_a_slow_spindle_loop_turns_the_surface_its_own_motion_cuts(text, scale):
    machine = load_machine("sts_lathe")
    program = parse_program(text)
    servo = slow_c(machine, scale)
    part, _ = turn(program, machine, servo=servo)
    # the old turn joined its followed samples straight where the motion bends between
    # them: 40.9 nm (F36000, x 1e-4) and 100.4 nm (F3600, x 1e-6) off the reference; now
    # 0.03 and 0.05 nm
    radius = np.linspace(0.5e-3, 1.0e-3, 51)[:, None]
    angle = np.linspace(0.0, 2.0 * math.pi, 73)[None, :]
    x, y = (radius * np.cos(angle)).ravel(), (radius * np.sin(angle)).ravel()
    reference = _finely_followed(machine, program, servo, part.tool)
    assert np.abs(part.heights_at(x, y) - reference.heights_at(x, y)).max() < 0.2e-9


def test_a_loop_that_keeps_the_rules_is_followed_on_the_command_s_samples():
    machine = load_machine("sts_lathe")
    program = parse_program(FACING)
    servo = slow_c(machine, 1.0)  # Table 6 "after": 90.00000002 deg a step at most
    part, report = turn(program, machine, servo=servo)
    (t, q), = turning_runs(program, machine)
    assert report.points == len(t) == 41
    path = edge_path_from_poses(machine.tool_pose(followed(servo.follow, t, q), None),
                                part.tool.nose_radius)
    assert np.array_equal(part.paths[0].angle, path.angle)
    assert np.array_equal(part.paths[0].z, path.z)


def test_a_followed_run_that_jumps_is_refused_naming_the_line_and_the_servo():
    machine = load_machine("sts_lathe")
    with pytest.raises(NCProgramError, match=re.escape(
            "line 4: the axes as the servo model Jump follows this move (C turns ")) as err:
        turn(parse_program(FACING), machine, servo=Jump(2))
    assert re.search(r"turns 9\d\.\d+ deg between two samples, at \d+\.\d+ s into the "
                     r"turning run\) ", str(err.value))
    assert str(err.value).endswith(
        "break the rules of a commanded step (at most 90 deg of C, the straight join within "
        "1 nm of the path) still after 8 rounds of sampling the move finer: its output "
        "jumps; check the servo loops' gains")


class _Overshoot:
    """Servo loops whose X settles 2 um beyond the command (an overshoot, held)."""

    def follow(self, t, q):
        reached = np.array(q, dtype=np.float64)
        reached[:, 0] += 2e-6
        return reached


def test_a_followed_path_that_overshoots_the_travel_is_refused_naming_line_and_overshoot():
    # the command ends at X 99.9999 mm, inside sts_lathe's +-100 mm; followed 2 um beyond
    # it X reaches 100.0019 mm, 1.9 um past the travel, at line 5 (X99.9999 C720.). Only
    # the command was checked, so the lathe turned it; cut() checks its followed samples
    from machinesim.exceptions import AxisLimitError

    program = parse_program("G90 G21 G94\nG00 X99.999 Z0.1 C0.\nG01 Z0. F10.\n"
                            "G01 X99.9995 C360.\nG01 X99.9999 C720.\nM30\n")
    _, report = turn(program, "sts_lathe", "nose:0.2:90")
    assert report.limit_violations == ()
    with pytest.raises(AxisLimitError, match=re.escape(
            "axis X = 100.001900 mm at line 5 as the servo follows it, 0.001900 mm beyond "
            "its travel -100.000000 mm .. 100.000000 mm")):
        turn(program, "sts_lathe", "nose:0.2:90", servo=_Overshoot())
    _, report = turn(program, "sts_lathe", "nose:0.2:90", servo=_Overshoot(),
                     allow_overtravel=True)
    assert len(report.limit_violations) == 1
    assert report.limit_violations[0].startswith("axis X = 100.001900 mm at line 5")


def test_an_axis_that_overshoots_in_several_runs_is_listed_once_at_its_worst():
    # two turning runs (a plunge between them) each overshooting X by 2 um: X was listed
    # once per run ('at line 5' and 'at line 7'), where the report lists an axis once. The
    # second run ends at X 99.99995 mm: followed 100.00195 mm, 1.95 um past the travel
    from machinesim.exceptions import AxisLimitError

    program = parse_program("G90 G21 G94\nG00 X99.999 Z0.1 C0.\nG01 Z0. F10.\n"
                            "G01 X99.9995 C360.\nG01 X99.9999 C720.\nG01 Z-0.001\n"
                            "G01 X99.99995 C1080.\nM30\n")
    _, report = turn(program, "sts_lathe", "nose:0.2:90", servo=_Overshoot(),
                     allow_overtravel=True)
    assert report.limit_violations == (
        "axis X = 100.001950 mm at line 7 as the servo follows it, 0.001950 mm beyond its "
        "travel -100.000000 mm .. 100.000000 mm, which the command keeps (the loop "
        "overshoots)",)
    with pytest.raises(AxisLimitError, match=re.escape(  # refused at the first run, as before
            "axis X = 100.001900 mm at line 5 as the servo follows it")):
        turn(program, "sts_lathe", "nose:0.2:90", servo=_Overshoot())


def test_the_lathe_s_following_refusals_name_the_block_s_n_word_beside_its_line():
    # with N words the refusals of a followed run (a servo that jumps, an overshoot past the
    # travel, refused or listed) name the block, 'line 4 (N40)', as the reader's do; they
    # had named the line alone
    from machinesim.exceptions import AxisLimitError

    machine = load_machine("sts_lathe")
    numbered = "\n".join(f"N{10 * i} {text}" for i, text in enumerate(FACING.splitlines(), 1))
    with pytest.raises(NCProgramError, match=re.escape(
            "line 4 (N40): the axes as the servo model Jump follows this move (C turns ")):
        turn(parse_program(numbered), machine, servo=Jump(2))
    program = parse_program("N1 G90 G21 G94\nN2 G00 X99.999 Z0.1 C0.\nN3 G01 Z0. F10.\n"
                            "N4 G01 X99.9995 C360.\nN5 G01 X99.9999 C720.\nN6 M30\n")
    with pytest.raises(AxisLimitError, match=re.escape(
            "axis X = 100.001900 mm at line 5 (N5) as the servo follows it, 0.001900 mm")):
        turn(program, machine, "nose:0.2:90", servo=_Overshoot())
    _, report = turn(program, machine, "nose:0.2:90", servo=_Overshoot(),
                     allow_overtravel=True)
    assert report.limit_violations[0].startswith("axis X = 100.001900 mm at line 5 (N5) as")
