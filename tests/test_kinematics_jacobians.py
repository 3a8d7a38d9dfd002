"""Kinematics' Jacobians: the error and axis Jacobians against central differences (a whole
turn table beyond its turn too), batched Jacobians against Pinocchio's one by one, the
rotation log against Pinocchio's log3, a linear setting parameter's exact column, and the
columns and calls the many-pose error Jacobian makes."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from kinematics_helpers import rot

from machinesim.errors import ComponentError, ErrorModel
from machinesim.machines import list_machines, load_machine
from machinesim.sampling import random_axis_values as random_q
from machinesim.sampling import random_errors

MM = 1e-3
UM = 1e-6


MACHINES = list_machines()


def _pose_difference(a, b):
    """Position and rotation (axis-angle, frame of the poses) from b to a."""
    return np.concatenate([a[:3, 3] - b[:3, 3], pin.log3(a[:3, :3] @ b[:3, :3].T)])


@pytest.mark.parametrize("name", MACHINES)
def test_error_jacobian_matches_central_differences(name):
    machine = load_machine(name)
    rng = np.random.default_rng(11)
    errors = random_errors(machine, rng)
    names = list(machine.parameter_names(errors))
    q = random_q(machine, rng, 2)
    jac = machine.error_jacobian(q, errors, names)
    assert jac.shape == (2, 6, len(names))
    values = errors.parameters()
    for c, p in enumerate(names):
        h = 1e-6
        base = values.get(p, 0.0)
        plus = machine.tool_pose(q, errors.with_parameters({p: base + h}))
        minus = machine.tool_pose(q, errors.with_parameters({p: base - h}))
        for n in range(2):
            fd = _pose_difference(plus[n], minus[n]) / (2 * h)
            # truncation h^2 * (third derivative ~ lever 1 m) ~ 1e-12 and round-off
            # 1e-16 / 1e-6 ~ 1e-10 per unit: 1e-8 holds with margin, far below the 1e-3..1
            # size of the entries
            np.testing.assert_allclose(jac[n, :, c], fd, rtol=0, atol=1e-8, err_msg=p)


def test_axis_jacobian_matches_central_differences():
    machine = load_machine("robonano_ui")
    rng = np.random.default_rng(5)
    errors = random_errors(machine, rng)
    q = random_q(machine, rng, 1)[0]
    jac = machine.axis_jacobian(q, errors)
    for i in range(len(q)):
        h = 1e-6
        dq = np.zeros_like(q)
        dq[i] = h
        fd = _pose_difference(machine.tool_pose(q + dq, errors),
                              machine.tool_pose(q - dq, errors)) / (2 * h)
        np.testing.assert_allclose(jac[:, i], fd, rtol=0, atol=1e-8)


@pytest.mark.parametrize("c_deg", [100.0, -100.0, -300.0, 340.0])
def test_axis_jacobian_of_a_whole_turn_table_beyond_it_is_the_turns_slope(c_deg):
    """A rotary table of a whole turn repeats each turn (`each_turn`), its slope too: at
    C = -100 deg a 0 .. 360 deg table of EXC is read at 260 deg. Its slope there had been
    zero (held constant beyond the ends): the C column was 2.2e-6 and 2.5e-6 m/rad off the
    central difference at -100 and -300 deg, by Pinocchio and the batched evaluator alike."""
    machine = load_machine("grooving_4axis")
    positions = np.radians(np.arange(0.0, 361.0, 45.0))
    table = ComponentError("table", positions, 5 * UM * np.sin(positions))
    errors = ErrorModel(component={"C": {"EXC": table, "EYC": table}})
    q = np.array([10 * MM, -4 * MM, 0.0, math.radians(c_deg)])
    h = 1e-6  # within one segment of the table
    dq = np.array([0.0, 0.0, 0.0, h])
    fd = _pose_difference(machine.tool_pose(q + dq, errors),
                          machine.tool_pose(q - dq, errors)) / (2 * h)
    _, batched = machine.kin.pose_jacobians(q[None], machine.binding(errors))
    for jac in (machine.axis_jacobian(q, errors), batched[0]):
        np.testing.assert_allclose(jac[:3, 3], fd[:3], rtol=0, atol=1e-10)
        np.testing.assert_allclose(jac[3:, 3], fd[3:], rtol=0, atol=1e-8)


@pytest.mark.parametrize("name", MACHINES)
def test_batched_jacobians_are_pinocchios_one_by_one(name):
    """The batched screw columns (component errors' slopes included) against Pinocchio's
    joint Jacobians, pose by pose, and the batched poses against Pinocchio's."""
    machine = load_machine(name)
    rng = np.random.default_rng(17)
    errors = random_errors(machine, rng)
    qs = random_q(machine, rng, 12)
    kin, binding = machine.kin, machine.binding(errors)
    poses, jacs = kin.pose_jacobians(qs, binding)
    for q, pose, jac in zip(qs, poses, jacs, strict=True):
        np.testing.assert_allclose(jac, kin.axis_jacobian(q, binding), rtol=0, atol=1e-14)
        np.testing.assert_allclose(pose, kin.frame_pose(kin.full_q(q, binding), "tool_tip"),
                                   rtol=0, atol=1e-14)


@pytest.mark.parametrize("angle", [0.0, 1e-12, 1e-7, 0.3, 2.0, math.pi - 1e-6, math.pi])
def test_rotation_log_is_pinocchios_log3(angle):
    from machinesim.rotations import rotation_log

    rng = np.random.default_rng(3)
    axes = rng.normal(size=(20, 3))
    vectors = axes / np.linalg.norm(axes, axis=1)[:, None] * angle
    rotations = np.array([pin.exp3(v) for v in vectors])
    logs = rotation_log(rotations)
    expected = np.array([pin.log3(r) for r in rotations])
    np.testing.assert_allclose(logs, expected, rtol=0, atol=1e-15 * max(angle, 1.0))
    if angle < 3.0:  # at a half turn +axis and -axis are one rotation
        np.testing.assert_allclose(logs, vectors, rtol=0, atol=1e-15 * max(angle, 1.0))
    np.testing.assert_allclose(rotation_log(rotations[0]), logs[0], rtol=0, atol=0)


def test_jacobian_of_a_linear_setting_parameter_is_exact():
    """The tool offset in tool_mount axes moves the edge by R_mount * d: checks columns."""
    machine = load_machine("robonano_ui")
    q = np.array([0.0, 0.0, 0.0, 0.3, -0.5, 0.0])
    jac = machine.error_jacobian(q, ErrorModel(), ["tool.x", "tool.y", "tool.z"])
    # rotation of tool_mount in the workpiece: Ry(B) Rz(A) (C = 0)
    expected = (rot(1, -0.5) @ rot(2, 0.3))[:3, :3]
    np.testing.assert_allclose(jac[:3, :3], expected, atol=1e-15)
    np.testing.assert_allclose(jac[3:, :3], 0.0, atol=1e-15)


def test_error_jacobian_of_many_poses_keeps_only_the_columns_its_parameters_use():
    # Each pose's whole (6, nv) Jacobian had been kept (nv = 107 on robonano_a0ib: 5.1 kB a
    # pose, 26 MB for these 5000 poses, 0.5 GB for a plan of 100,000); the result holds
    # 5000 x 6 x 2 floats (0.48 MB), the poses' rotations 0.36 MB
    import tracemalloc

    machine = load_machine("robonano_a0ib")
    q = np.zeros((5000, 5))
    q[:, 0] = np.linspace(-0.1, 0.1, 5000)
    q[:, 4] = np.linspace(-3.0, 3.0, 5000)
    names = ["location.C.EX0C", "location.B.EZ0B"]
    few = machine.error_jacobian(q[::1000], None, names, point=[0.0, 0.0, 0.01])
    tracemalloc.start()
    try:
        many = machine.error_jacobian(q, None, names, point=[0.0, 0.0, 0.01])
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 5e6, f"{peak / 1e6:.1f} MB"
    np.testing.assert_array_equal(many[::1000], few)


@pytest.mark.parametrize("name", MACHINES)
def test_batched_error_jacobian_is_pinocchios_pose_by_pose(name):
    # error_jacobian had asked Pinocchio for each distinct pose (~0.12 ms a pose on
    # robonano_a0ib); it now walks the model over every pose at once. Held against that
    # pose-by-pose path (pinocchio_error_jacobian, the code before) on every frame, at no
    # error and at every error family, for every parameter, of the frame origin and of points:
    # the two differ by at most 3.6e-15 (m per m or rad; measured), a few ulp of the ~1 m
    # levers the columns are made of (a linear axis's location tilt is the difference of its
    # two joints' ~1 m levers), and agree bit for bit on 80-100 % of the entries (93 % on
    # average)
    machine = load_machine(name)
    rng = np.random.default_rng(21)
    for errors in (None, random_errors(machine, rng)):
        names = list(machine.parameter_names(errors))
        q = random_q(machine, rng, 40)
        for frame in machine.frames:
            for point in (None, rng.normal(0, 0.02, (40, 3))):
                batched = machine.error_jacobian(q, errors, names, frame=frame, point=point)
                pinocchio = machine.pinocchio_error_jacobian(q, errors, names, frame=frame,
                                                             point=point)
                np.testing.assert_allclose(batched, pinocchio, rtol=0, atol=1e-14,
                                           err_msg=f"{frame}, point {point is not None}")


def test_error_jacobian_of_many_poses_asks_pinocchio_for_none(monkeypatch):
    # The batched evaluator reads the model's joints, not Pinocchio's per-pose algorithms;
    # before, this plan of 2000 poses called them 2000 times each
    machine = load_machine("robonano_a0ib")
    q = random_q(machine, np.random.default_rng(22), 2000)
    names = ["workpiece.x", "location.C.EX0C", "location.B.EC0B", "tool.rz"]
    expected = machine.error_jacobian(q, None, names, point=[0.0, 0.0, 0.01])

    def per_pose(*args, **kwargs):
        raise AssertionError("Pinocchio called for one pose")

    monkeypatch.setattr(machine.kin, "relative_jacobian", per_pose)
    monkeypatch.setattr(machine.kin, "frame_pose", per_pose)
    jac = machine.error_jacobian(q, None, names, point=[0.0, 0.0, 0.01])
    np.testing.assert_array_equal(jac, expected)


def test_a_dict_or_a_toml_path_is_the_model_it_reads_everywhere_errors_are_taken(tmp_path):
    # tool_pose took the TOML layout's dict or a TOML path, as Lab and cut do, but
    # error_jacobian and parameter_names read them as the model itself: AttributeError
    # "'dict' object has no attribute 'component'" (or 'parameters'), naming nothing
    machine = load_machine("robonano_a0ib")
    layout = {"tool": {"offset_um": [1.0, 0.0, 0.0]},
              "component": {"X": {"position_mm": [-140.0, 0.0, 140.0],
                                  "EXX_um": [2.0, 0.0, -1.0]}}}
    model = ErrorModel.from_dict(layout)
    path = tmp_path / "errors.toml"
    model.to_toml(path)
    q = np.array([[0.07, 0.01, 0.0, 0.0, 0.0], [-0.03, 0.0, 0.02, -0.1, 1.0]])
    for given in (layout, path, str(path)):
        assert machine.parameter_names(given) == machine.parameter_names(model)
        assert machine.parameter_names(given)[-3:] == tuple(
            f"component.X.EXX[{i}]" for i in range(3))
        np.testing.assert_array_equal(machine.error_jacobian(q, given),
                                      machine.error_jacobian(q, model))
    # X = 0.07 m, halfway between the table's 0 and 140 mm, B = C = 0: entry 1 weighs 0.5
    # and moves the edge along the workpiece's x
    column = machine.error_jacobian(q, layout, ["component.X.EXX[1]"])
    assert column[0, 0, 0] == pytest.approx(0.5, abs=1e-12)
