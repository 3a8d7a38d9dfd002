"""Kinematics inverted (axis_values): one batch against one by one, round trips of poses,
from zero on the nominal machine, a machine or its name and nothing else, orientations a
machine cannot make or makes only with C turned first, tool axes no axis can tilt, and
clear errors for bad input."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from kinematics_helpers import assert_pose_close, rot, trans

from machinesim.errors import ComponentError, ErrorModel
from machinesim.exceptions import AxisLimitError, ErrorModelError, InputError, UnreachableError
from machinesim.machines import list_machines, load_machine
from machinesim.sampling import random_axis_values as random_q
from machinesim.sampling import random_errors

MM = 1e-3


MACHINES = list_machines()


@pytest.mark.parametrize("name", MACHINES)
def test_axis_values_in_one_batch_are_the_poses_solved_one_by_one(name):
    """Independent starts are solved all at once; each pose alone from its own start (the
    Pinocchio route) lands on the same axis values."""
    machine = load_machine(name)
    rng = np.random.default_rng(19)
    errors = random_errors(machine, rng, tool_rotation=1e-4, workpiece_rotation=1e-4)
    qs = random_q(machine, rng, 6, fraction=0.5)
    poses = machine.tool_pose(qs, errors)
    start = qs + rng.normal(0, 0.01, qs.shape)
    batch = machine.axis_values(poses, errors, q_start=start)
    for n in range(len(qs)):
        one = machine.axis_values(poses[n], errors, q_start=start[n])
        np.testing.assert_allclose(batch.q[n], one.q, rtol=0, atol=1e-12)
        np.testing.assert_allclose(batch.position_residual[n], one.position_residual,
                                   rtol=0, atol=1e-15)


@pytest.mark.parametrize("name", MACHINES)
def test_axis_values_round_trips_poses(name):
    machine = load_machine(name)
    rng = np.random.default_rng(13)
    errors = random_errors(machine, rng)
    qs = random_q(machine, rng, 4, fraction=0.5)
    poses = machine.tool_pose(qs, errors)
    start = qs + rng.normal(0, 0.02, qs.shape)
    solution = machine.axis_values(poses, errors, q_start=start)
    assert solution.unmatched == ""
    assert_pose_close(machine.tool_pose(solution.q, errors), poses)
    np.testing.assert_allclose(solution.q, qs, rtol=0, atol=1e-10)


def test_axis_values_from_zero_on_the_nominal_machine():
    machine = load_machine("robonano_a0ib")
    q = np.array([3 * MM, -2 * MM, 1 * MM, math.radians(20), math.radians(-30)])
    solution = machine.axis_values(machine.tool_pose(q))
    np.testing.assert_allclose(solution.q, q, atol=1e-12)


def test_inverse_axis_values_takes_a_machine_or_its_name_and_refuses_anything_else():
    # machinesim.inverse.axis_values('robonano_a0ib', ...) ended in "AttributeError: 'str'
    # object has no attribute 'axes'", None likewise; check_limits="no" counted as True
    from machinesim.exceptions import ModelError
    from machinesim.inverse import axis_values

    machine = load_machine("robonano_a0ib")
    q = np.array([3 * MM, -2 * MM, 1 * MM, math.radians(20), math.radians(-30)])
    solution = axis_values("robonano_a0ib", machine.tool_pose(q))
    np.testing.assert_allclose(solution.q, q, atol=1e-12)
    for bad in (None, 3, {}):
        with pytest.raises(InputError) as info:
            axis_values(bad, np.eye(4))
        assert info.value.key == "machine"
    with pytest.raises(ModelError, match="nope"):
        axis_values("nope", np.eye(4))
    with pytest.raises(InputError) as info:
        axis_values(machine, np.eye(4), check_limits="no")
    assert info.value.key == "check_limits"


def test_axis_values_reports_the_orientation_a_planer_cannot_make():
    machine = load_machine("planer_4axis")
    target = trans([1 * MM, 2 * MM, 0.0]) @ rot(1, 0.01)  # a tilt about Y: no axis for it
    solution = machine.axis_values(target)
    np.testing.assert_allclose(solution.position_residual, 0.0, atol=1e-13)
    assert solution.rotation_residual[1] == pytest.approx(0.01, abs=1e-12)
    assert "cannot turn the tool about Y" in solution.unmatched


def test_axis_values_matches_a_tool_axis_whose_tilt_needs_c_turned_first():
    """On robonano_a0ib (B tilts the tool about Y, C turns the work about Z) a tool axis
    tilted 30 deg about X is B = +-30 deg with C = -+90 deg (by hand: C about Z turns
    nothing of the tool axis's angle to Z, which is |B|, and brings the tilt from the X-Z
    plane to the Y-Z plane). The whole orientation (a pure Rx) no axis values give; from
    zero, where C cannot tilt the tool, that left the tilt unmatched."""
    machine = load_machine("robonano_a0ib")
    target = trans([1 * MM, 2 * MM, -0.5 * MM]) @ rot(0, math.radians(30))
    whole = machine.axis_values(target)
    assert "cannot turn the tool about X" in whole.unmatched
    assert whole.q[3] == whole.q[4] == 0.0
    for q_start in (None, np.zeros(5), np.array([0.0, 0.0, 0.0, 0.0, math.radians(45)])):
        solution = machine.axis_values(target, q_start=q_start, orientation="tool_axis")
        assert abs(math.degrees(solution.q[3])) == pytest.approx(30.0, abs=1e-9)
        assert abs(math.degrees(solution.q[4])) == pytest.approx(90.0, abs=1e-9)
        assert solution.unmatched == ""
        reached = machine.tool_pose(solution.q)  # a second method: the forward chain
        np.testing.assert_allclose(reached[:3, 2], target[:3, 2], atol=1e-15)
        np.testing.assert_allclose(reached[:3, 3], target[:3, 3], atol=1e-15)
        assert np.linalg.norm(solution.rotation_residual) < 1e-15
    # a batch from one start: every pose its own retry
    batch = machine.axis_values(np.stack([target, trans([0.0, 0.0, 0.0])]), q_start=np.zeros(5),
                                orientation="tool_axis")
    np.testing.assert_allclose(batch.q[1], 0.0, atol=1e-15)
    assert abs(math.degrees(batch.q[0, 3])) == pytest.approx(30.0, abs=1e-9)
    with pytest.raises(InputError, match="orientation='axis': expected 'whole' or 'tool_axis'"):
        machine.axis_values(target, orientation="axis")


@pytest.mark.parametrize("place", [(128, 58, 77, -55), (100, 50, 50, -55), (128, 58, 77, 30),
                                   (50, 20, 0, -55)])
def test_axis_values_of_a_tool_axis_no_axis_can_tilt_still_reach_the_position(place):
    """grooving_4axis (X Y Z C) with its tool and its workpiece tilted by a few mrad, the
    tool axis alone matched: C turns the workpiece's tilt against the tool's but cannot
    match it, and Newton, chasing it, turned C by pi each step while X and Y doubled:
    an UnreachableError with a 'best miss' of 100 m to 630 km, where X, Y, Z reach the
    position (from the same start) to round-off. The position comes first: it is reached,
    the tilt reported unmatched."""
    machine = load_machine("grooving_4axis")
    errors = ErrorModel.from_dict({"tool": {"rotation_urad": [-1700.0, -560.0, 0.0]},
                                   "workpiece": {"alpha_urad": 4100.0, "beta_urad": -3900.0}})
    q = np.array([place[0] * MM, place[1] * MM, place[2] * MM, math.radians(place[3])])
    solution = machine.axis_values(machine.tool_pose(q), errors, q_start=q,
                                   orientation="tool_axis")
    reached = machine.tool_pose(solution.q, errors)[:3, 3]
    np.testing.assert_allclose(reached, machine.tool_pose(q)[:3, 3], rtol=0, atol=1e-15)
    assert "cannot turn the tool about" in solution.unmatched
    assert np.max(np.abs(solution.q - q)) < 1 * MM  # no turn of C, no leap of X, Y


def test_axis_values_errors_are_clear():
    machine = load_machine("planer_4axis")
    with pytest.raises(AxisLimitError, match="axis X = 300.000000 mm outside its travel"):
        machine.axis_values(trans([300 * MM, 0.0, 0.0]))
    lathe = load_machine("sts_lathe")
    with pytest.raises(UnreachableError, match="no axis values reach"):
        # one Newton step from the spindle axis cannot reach a point 80 mm off it at 90 deg
        lathe.axis_values(trans([0.0, 80 * MM, 0.0]), max_iterations=1)
    with pytest.raises(InputError, match=r"expected a pose of shape \(4, 4\)"):
        machine.axis_values(np.eye(3))
    shear = np.eye(4)
    shear[0, 1] = 1e-6
    moved = np.eye(4)
    moved[3] = [5.0, 5.0, 5.0, 7.0]
    for pose in (np.diag([1.0, 1.0, -1.0, 1.0]), np.diag([2.0, 2.0, 2.0, 1.0]), shear, moved,
                 np.zeros((4, 4))):
        with pytest.raises(InputError, match="pose 0 is not a rigid motion"):
            machine.axis_values(pose)
    batch = np.stack([np.eye(4), np.eye(4), np.diag([-1.0, -1.0, -1.0, 1.0])])
    with pytest.raises(InputError, match="pose 2 is not a rigid motion"):
        machine.axis_values(batch)


@pytest.mark.parametrize("pose", [np.eye(4) + 1e-3j, np.eye(4).astype(str).tolist(),
                                  np.eye(4).astype(object).tolist() + [[None] * 4]])
def test_a_pose_that_is_not_real_numbers_is_refused_naming_it(pose):
    # a complex pose lost its imaginary part with numpy's ComplexWarning and was solved; a
    # pose of texts ("1.0", "0.0") was read as numbers; a None raised numpy's TypeError
    machine = load_machine("planer_4axis")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # refused, not warned about and solved
        with pytest.raises(InputError, match=r"key 'wMt': Expected wMt as a pose \(4 x 4, m\)"):
            machine.axis_values(pose)


def test_a_bad_q_start_is_named_q_start_not_q():
    # axis_values(wMt, q_start=...) refused a NaN or short start under key 'q', the name of
    # no argument it takes
    machine = load_machine("planer_4axis")
    with pytest.raises(InputError, match=r"^key 'q_start': axis values contain NaN or inf: "
                                         r"Y = nan \(XYZA, m and rad\)"):
        machine.axis_values(np.eye(4), q_start=[0.0, np.nan, 0.0, 0.0])
    with pytest.raises(InputError, match=r"^key 'q_start': planer_4axis has axes XYZA: "
                                         r"expected axis values of shape \(4,\) or \(N, 4\), "
                                         r"got \(3,\)"):
        machine.axis_values(np.eye(4), q_start=[0.0, 0.0, 0.0])
    with pytest.raises(InputError, match=r"^key 'q': planer_4axis has axes XYZA"):
        machine.tool_pose([0.0, 0.0])


def test_a_pose_with_nan_is_refused_naming_which():
    machine = load_machine("planer_4axis")
    batch = np.stack([np.eye(4), np.eye(4)])
    batch[1, 0, 3] = np.nan
    with pytest.raises(InputError, match=r"key 'wMt': planer_4axis: the requested pose 1 has "
                                         r"NaN or inf entries, \[\[1.0, 0.0, 0.0, nan\]"):
        machine.axis_values(batch)


def test_bad_input_is_refused_with_the_machine_and_shape():
    machine = load_machine("planer_4axis")
    with pytest.raises(InputError, match=r"axes XYZA: expected axis values of shape \(4,\)"):
        machine.tool_pose([0.0, 0.0])
    with pytest.raises(InputError, match="NaN"):
        machine.tool_pose([0.0, np.nan, 0.0, 0.0])
    with pytest.raises(ErrorModelError, match="EX0X has no effect on linear axis X"):
        machine.tool_pose(np.zeros(4), ErrorModel(location={"X": {"EX0X": 1e-6}}))
    with pytest.raises(ErrorModelError, match="axis 'C' is not on this machine"):
        machine.tool_pose(np.zeros(4), ErrorModel(location={"C": {"EX0C": 1e-6}}))
    table = ComponentError("table", np.array([0.0, 0.5]), np.array([0.0, 1e-6]))
    with pytest.raises(ErrorModelError, match=r"outside the travel of axis X, -200 \.\. 200 mm"):
        machine.tool_pose(np.zeros(4), ErrorModel(component={"X": {"EXX": table}}))
