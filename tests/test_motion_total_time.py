"""Motion: a program's time in all is bounded by MAX_PROGRAM_TIME_S (2**39 s), where its
float64 clock still keeps 0.1 ms; long dwells within it are read and noted."""

from __future__ import annotations

import math

import numpy as np
import pytest

from machinesim import load_machine
from machinesim.cutting.lathe import turn
from machinesim.exceptions import NCProgramError
from machinesim.motion import plan
from machinesim.nc import ProgramBuilder, parse_program
from machinesim.nc.words import MAX_PROGRAM_TIME_S

#: 1e308 s written out in full: the reader reads no exponent (``X1e308`` is X1 and E308).
HUGE = "1" + "0" * 308 + "."


def test_the_bound_keeps_a_tenth_of_a_millisecond_and_a_billion_second_dwell():
    # below 2**39 s float64 seconds are 2**-14 s = 61 us apart, within the 0.1 ms of IS-C's
    # G04 X; at the bound the spacing doubles to 122 us, beyond it
    assert MAX_PROGRAM_TIME_S == 2.0**39
    assert np.spacing(np.nextafter(MAX_PROGRAM_TIME_S, 0.0)) == 2.0**-14 < 1e-4
    assert np.spacing(MAX_PROGRAM_TIME_S) == 2.0**-13 > 1e-4
    assert MAX_PROGRAM_TIME_S > 1e9 * 500  # 500 dwells of 31 years


@pytest.mark.parametrize("dwell", [f"G04 X{HUGE}", f"G04 P{HUGE}", "G04 X600000000000.",
                                   "G82 X2. Z-0.1 R1. P600000000000. F10."])
def test_a_dwell_longer_than_any_program_is_refused_at_its_word(dwell):
    # G04 X1e308 written out had been read as 1e308 s (two of them summed to inf)
    with pytest.raises(NCProgramError) as caught:
        parse_program(f"G90 G21\nG00 X1. Z1.\n{dwell}\nG80\nM30\n", "d.nc")
    error = caught.value
    assert (error.source, error.line) == ("d.nc", 3)
    assert error.key[0] in "PX" and "more than the 5.49756e+11 s" in str(error)


def test_dwells_that_add_up_beyond_the_bound_are_refused_at_the_line_that_passes_it():
    # each dwell is read (3e11 s, within the bound); the second takes the clock to 6e11 s.
    # It had planned (two of 1e308 s: a duration of inf)
    text = ("G90 G21\nG00 X1. Z1.\nN10 G04 X300000000000.\nG01 X2. F100.\n"
            "N20 G04 P300000000000.\nM30\n")
    program = parse_program(text, "d.nc")
    assert [float(d) for d in program.dwells if d > 0] == [3e11, 3e11]
    with pytest.raises(NCProgramError) as caught:
        plan(program, load_machine("grooving_4axis"))
    error = caught.value
    assert (error.source, error.line, error.block) == ("d.nc", 5, 20)
    assert "the longest the dwell (X300000000000.) of line 3 (N10), 3e+11 s" in str(error)


def test_built_dwells_whose_sum_overflows_are_refused_not_timed_as_inf():
    built = ProgramBuilder(1).rapid(X=1e-3, Z=1e-3).dwell(1e308).dwell(1e308).build()
    with pytest.raises(NCProgramError, match="more than 5.49756e"):
        plan(built, load_machine("grooving_4axis"))


def test_a_move_whose_time_overflows_is_refused_naming_it():
    # 2.54e302 m each way at F1 inch/min: its length squared overflowed to inf, its time too
    # (with numpy's RuntimeWarnings), and the trajectory's times were NaN
    text = f"G90 G20\nG00 X1{'0' * 304}.\nG01 X-1{'0' * 304}. F1.\nM30\n"
    with np.errstate(all="raise"), pytest.raises(NCProgramError) as caught:
        plan(parse_program(text), load_machine("grooving_4axis"))
    assert caught.value.line == 2  # the rapid there takes 1e305 s already
    assert "the longest the feed move of line 3, a time beyond float64" in str(caught.value)


def test_a_long_program_within_the_bound_is_timed_and_noted():
    # a 5e11 s dwell (noted) and 199 mm at F0.000001 mm/min (1.194e10 s, noted): 5.1194e11 s
    text = "G90 G21\nG00 X1. Z1.\nG04 X500000000000.\nG01 X200. F0.000001\nM30\n"
    trajectory = plan(parse_program(text), load_machine("grooving_4axis"))
    assert math.isclose(trajectory.duration, 5e11 + 199.0 / 1e-6 * 60.0 + 0.04, rel_tol=1e-9)
    assert len(trajectory.notes) == 2


def test_a_turning_programs_dwells_beyond_the_bound_are_refused_before_it_is_turned():
    text = ("G21 G90 G94\nG00 X5.5 Z1. C0.\nG04 X300000000000.\nG01 Z-0.01 F100.\n"
            "G01 X0. C18000. F20.\nG04 X300000000000.\nG00 Z1.\nM30\n")
    with pytest.raises(NCProgramError) as caught:
        turn(parse_program(text, "t.nc"), "sts_lathe", "nose:0.5:90")
    assert (caught.value.source, caught.value.line) == ("t.nc", 6)
