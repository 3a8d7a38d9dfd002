"""Exact stop (G09 in a block, G61 until G64): the block ends in position, so servo lag does
not carry into the next block. Read, written, kept, and followed by the planner."""

import pickle

import numpy as np
import pytest

import machinesim
from machinesim.exceptions import NCProgramError
from machinesim.motion import plan
from machinesim.nc import Program, format_program, parse_program
from machinesim.servo import AxisServo, PIDServo

# a PD loop on a 4 kg slide with 1e4 N s/m: a ramp at speed v lags by v c / Kp (13.33 um at
# 10 mm/s); its poles (-3750 +- 968j 1/s) settle in milliseconds
M, C, KP, KD = 4.0, 1e4, 6e7, 2e4
V = 10e-3  # m/s, F600
LAG = V * C / KP


def _servo():
    return PIDServo(tuple(AxisServo(kp=KP, ki=0.0, kd=KD, mass=M, damping=C, name=a)
                          for a in "XY") + (None, None))


def _corner(mode: str) -> Program:
    # two feed lines meeting at a right angle at (10, 0) mm
    first, second = {"G64": ("", ""), "G09": ("G09 ", ""), "G61": ("", "")}[mode]
    head = "G61\n" if mode == "G61" else ""
    return parse_program(f"G90 G21\nG00 X0. Y0. Z0.\n{head}G01 {first}X10. F600.\n"
                         f"{second}Y10.\nG64\nG00 Z1.\n")


def test_the_reader_marks_the_blocks_that_end_in_an_exact_stop():
    text = ("G90 G21\nG00 X0. Y0. Z1.\nG01 Z0. F100.\nG09 X1.\nY1.\nG61\nX0.\n"
            "G02 X1. Y1. I0.5 J0.\nG64\nG01 X2.\nG09 G04 P100\nM30\n")
    program = parse_program(text)
    lines = program.lines[program.exact_stops].tolist()
    # G09's line; under G61 each block's last move (the arc's last chord only); the dwell
    assert lines == [4, 7, 8, 11]
    arc = np.flatnonzero(program.lines == 8)
    assert arc.size > 1 and program.exact_stops.tolist().count(int(arc[-1])) == 1
    assert {"G09", "G61", "G64"} <= set(program.states)


def test_g61_over_a_long_point_list_reads_alike_on_both_paths():
    points = "".join(f"X{i * 0.001:.3f} Y{i % 7 * 0.001:.3f}\n" for i in range(300))
    text = f"G90 G21\nG00 X0. Y0.\nG01 F100.\nG61\n{points}G64\n{points}M30\n"
    fast, slow = parse_program(text), parse_program(text, fast=False)
    assert fast == slow
    assert fast.exact_stops.tolist() == list(range(1, 301))


def test_exact_stops_survive_writing_pickling_and_new_targets():
    program = _corner("G61")
    again = parse_program(format_program(program))
    assert again.exact_stops.tolist() == program.exact_stops.tolist() == [1, 2]
    assert pickle.loads(pickle.dumps(program)) == program
    moved = program.with_targets(program.targets + 1e-6)
    assert moved.exact_stops.tolist() == [1, 2]
    plain = parse_program(format_program(_corner("G64")))
    assert plain.exact_stops.size == 0 and plain != again
    with pytest.raises(NCProgramError, match="exact_stops must be move indices 0..3"):
        Program.from_arrays(program.targets, program.kinds, program.feeds, exact_stops=[4])


def test_the_builder_marks_an_exact_stop_as_g09_does():
    from machinesim.nc import ProgramBuilder

    built = (ProgramBuilder(source="<string>").rapid(X=0.0, Y=0.0, Z=0.0)
             .linear(X=0.01, feed_mm_per_min=600.0, exact_stop=True).linear(Y=0.01).build())
    read = parse_program("G00 X0. Y0. Z0.\nG01 G09 X10. F600.\nY10.\n")
    assert built.exact_stops.tolist() == read.exact_stops.tolist() == [1]
    assert np.array_equal(built.targets, read.targets, equal_nan=True)


def test_a_corner_in_cutting_mode_carries_the_lag_and_an_exact_stop_does_not():
    machine = machinesim.load_machine("grooving_4axis")
    servo = _servo()
    rows = {}
    for mode in ("G64", "G09", "G61"):
        trajectory = plan(_corner(mode), machine, servo=servo)
        rows[mode] = trajectory
        assert trajectory.peak_lag[:2] == pytest.approx([LAG, LAG], rel=1e-3)
    corner = rows["G64"].segments[1].q[-1]
    # G64: the X line's steady ramp error at the corner, v c / Kp (1 s after its start)
    assert 0.01 - corner[0] == pytest.approx(LAG, rel=1e-6)
    assert corner[1] == 0.0
    # G09 / G61: the X line ends in position, and the Y line starts from rest there
    for mode in ("G09", "G61"):
        segments = rows[mode].segments
        assert segments[1].q[-1].tolist() == segments[2].q[0].tolist() == [0.01, 0.0, 0.0, 0.0]
    assert np.array_equal(rows["G09"].q, rows["G61"].q)
    # every motion ends in position: the Y line's end too
    assert rows["G64"].segments[2].q[-1][:2].tolist() == [0.01, 0.01]


def test_a_line_under_lag_is_cut_to_its_end():
    # a straight groove along X with lag on X only: the tool runs behind along its own line
    # and settles at the end, so the groove is the ideal one. Without the settling the line
    # ended v c / Kp short and the rapid left from the commanded end: 1.7e-18 m^3 less,
    # 2e-4 of the groove
    program = parse_program("G90 G21\nG00 X1. Y5. Z0.1\nG01 Z-0.001 F60.\n"
                            "G01 X9. F600.\nG00 Z1.\n")
    servo = PIDServo((AxisServo(kp=KP, ki=0.0, kd=KD, mass=M, damping=C, name="X"),
                      None, None, None))
    _, lagged = machinesim.cut(program, "grooving_4axis", "v:90", "block:10x10x2",
                               servo=servo)
    _, ideal = machinesim.cut(program, "grooving_4axis", "v:90", "block:10x10x2")
    assert lagged.peak_following_error["X"] == pytest.approx(LAG, rel=1e-3)
    assert lagged.removed_volume_m3 == pytest.approx(ideal.removed_volume_m3, rel=1e-12, abs=0.0)


def test_the_encoders_record_an_exact_stop_as_the_cut_follows_it():
    # the control's trace: under G64 the Y line starts with X still v c / Kp behind; after
    # G09 it starts from rest at the corner
    lab = machinesim.Lab("grooving_4axis", noise=False, servo=_servo())
    lag = {}
    for mode in ("G64", "G09"):
        reading = lab.encoders().record(_corner(mode))
        # samples: the rapid's two, the X line's two, the Y line's two (a start per move)
        lag[mode] = reading.following_error[4, 0]
    assert lag["G64"] == pytest.approx(LAG, rel=1e-3)
    assert abs(lag["G09"]) < 1e-9  # the encoders' 1 nm display step
