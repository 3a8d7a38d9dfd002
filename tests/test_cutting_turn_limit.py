"""A sweep that turns the tool too far in one step is refused, not cut as a false hull."""

import math

import numpy as np
import pytest

from machinesim.cutting import remove
from machinesim.exceptions import InputError, MachineSimError
from machinesim.tools import FlatEndMill, VTool
from machinesim.workpiece import block


def _about(axis, angle):
    """Rotation by ``angle`` about the unit ``axis`` (Rodrigues)."""
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]],
                  [-axis[1], axis[0], 0.0]])
    return np.eye(3) + math.sin(angle) * k + (1.0 - math.cos(angle)) * k @ k


def _pose(rotation, position):
    matrix = np.eye(4)
    matrix[:3, :3] = rotation
    matrix[:3, 3] = position
    return matrix


def _swing(angle, axis=(0.0, 1.0, 0.0), pivot=(1e-3, 1e-3, 50e-6), move=(0.0, 0.0, 0.0)):
    """Poses turning the tool tip by ``angle`` about a line through ``pivot`` in one step
    while moving by ``move``, the tip starting 20 um into the stock's top."""
    tip = np.array([0.5e-3, 1e-3, -20e-6])
    rotation = _about(np.asarray(axis), angle)
    return np.array([_pose(np.eye(3), tip),
                     _pose(rotation, pivot + rotation @ (tip - pivot) + move)])


def test_a_half_turn_in_one_sweep_is_refused_naming_the_turn_and_the_limit():
    stock = block(2e-3, 2e-3, 1e-3)
    with pytest.raises(InputError) as caught:
        remove(stock, FlatEndMill(0.5e-3, chord_tol=1e-5), [_swing(math.pi)])
    message = str(caught.value)
    assert isinstance(caught.value, MachineSimError)
    assert "path 0: the tool's axis tilts by 180 deg from pose 0 to pose 1" in message
    assert "more than 90 deg" in message and "mean normal" in message
    assert "sub-steps" in message


def test_a_turn_just_past_a_quarter_is_refused_and_one_within_it_is_cut():
    stock = block(2e-3, 2e-3, 1e-3)
    tool = VTool(math.radians(90.0))
    over = math.pi / 2.0 + 1e-3  # a quarter turn, the limit, and 0.057 deg
    with pytest.raises(InputError, match=r"the tool turns by 90\.0573 deg from pose 0"):
        remove(stock, tool, [_swing(over, axis=(1.0, 0.0, 0.0))])
    part, _ = remove(stock, tool, [_swing(math.radians(2.0), axis=(1.0, 0.0, 0.0),
                                    move=(1e-3, 0.0, 0.0))])
    assert part.volume < stock.volume


def test_a_half_turn_about_a_round_tool_s_own_axis_is_no_turn():
    """A spin moves no point of the round tool: its sweep is its translation's."""
    stock = block(2e-3, 2e-3, 1e-3)
    tip = np.array([0.5e-3, 1e-3, -20e-6])
    spun = np.array([_pose(np.eye(3), tip),
                     _pose(_about(np.array([0.0, 0.0, 1.0]), math.pi), tip + [1e-3, 0, 0])])
    part, _ = remove(stock, FlatEndMill(0.5e-3, chord_tol=1e-5), [spun])
    assert part.volume < stock.volume


@pytest.mark.parametrize(("words", "steps"), [("C180.", 4), ("B90. C-180.", 6)])
def test_a_coarse_chord_tolerance_still_sub_steps_a_turn_by_an_eighth_turn(words, steps):
    """At a chord tolerance of 1 m (--chord-nm 1e9, the largest taken) every chord rule
    passes a turn in one step; the planner still cuts it into steps of at most 45 deg, half
    the engine's quarter turn, counted on the rotary axes' turns added up: 180 / 45 = 4,
    (90 + 180) / 45 = 6."""
    from machinesim.motion import plan
    from machinesim.nc import parse_program

    program = parse_program(f"G90 G21\nG00 X5. Y0. Z0. B0. C0.\nG01 {words} F36000.\nM30\n")
    q = plan(program, "robonano_ui", chord_tolerance=1.0).segments[1].q
    assert len(q) - 1 == steps
    turns = np.abs(np.diff(q, axis=0)).max(axis=0)
    assert np.all(turns <= math.pi / 4.0 + 1e-12)


def test_a_turn_past_a_million_eighth_turns_is_refused_at_its_line():
    """A block turning C by more than MAX_SUBSTEPS eighth turns (45e6 deg) would need more
    sub-steps than the planner makes: refused naming that block's turn and line, not the
    largest turn of the program (here the later, larger one)."""
    from machinesim.exceptions import NCProgramError
    from machinesim.motion import plan
    from machinesim.nc import parse_program

    program = parse_program("G90 G21\nG00 X5. Y0. Z0. B0. C0.\nG01 C45000045. F36000.\n"
                            "G01 C0.\nG01 C90000000.\nM30\n")
    with pytest.raises(NCProgramError, match=r"line 3: a rotary move of 4\.5e\+07 deg would "
                       r"need more than 1000000 sub-steps of at most 45 deg"):
        plan(program, "robonano_ui", chord_tolerance=1.0)
