"""Kinematics against an independent chain, paper geometry, finite differences, round trips.

The independent chain below is written from docs/machines.md (its placement tables and its
error formulas) with plain 4x4 matrices: it shares no code with the URDF reading, the error
joints or Pinocchio.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

from machinesim.errors import ComponentError, ErrorModel, ToolSetting
from machinesim.exceptions import AxisLimitError, ErrorModelError, InputError, UnreachableError
from machinesim.machines import list_machines, load_machine
from machinesim.sampling import random_axis_values as random_q
from machinesim.sampling import random_errors

MM = 1e-3
UM = 1e-6
URAD = 1e-6

# docs/machines.md, tables of joint origins (mm), axis direction and sign, per branch.
# ("fixed", xyz) or (letter, xyz, direction, sign).
GEOMETRY = {
    "robonano_ui": {
        "workpiece": [("Y", (0, 0, 100), 1, -1), ("C", (0, 0, 80), 2, -1),
                      ("fixed", (0, 0, 20)), ("fixed", (0, 0, 5))],
        "tool": [("X", (0, 300, 400), 0, 1), ("Z", (0, -300, -50), 2, 1),
                 ("B", (0, 0, -145), 1, 1), ("A", (0, 0, 0), 2, 1),
                 ("fixed", (0, 0, 20)), ("fixed", (0, 0, -20))],
    },
    "robonano_a0ib": {
        "workpiece": [("Y", (0, 0, 100), 1, -1), ("C", (0, 0, 80), 2, -1),
                      ("fixed", (0, 0, 20)), ("fixed", (0, 0, 5))],
        "tool": [("X", (0, 300, 400), 0, 1), ("Z", (0, -300, -50), 2, 1),
                 ("B", (0, 0, -145), 1, 1), ("fixed", (0, 0, 20)), ("fixed", (0, 0, -20))],
        "probe": [("X", (0, 300, 400), 0, 1), ("Z", (0, -300, -50), 2, 1),
                  ("B", (0, 0, -145), 1, 1), ("fixed", (0, 40, 1)), ("fixed", (0, 0, 0))],
    },
    "planer_4axis": {
        "workpiece": [("X", (0, 0, 100), 0, -1), ("fixed", (0, 0, 95)), ("fixed", (0, 0, 5))],
        "tool": [("Y", (0, 0, 450), 1, 1), ("Z", (0, 0, -50), 2, 1),
                 ("A", (0, 0, -79.5), 0, 1), ("fixed", (0, 0, -100.5)),
                 ("fixed", (0, 0, -20))],
    },
    "grooving_4axis": {
        "workpiece": [("Y", (0, 0, 80), 1, -1), ("C", (0, 0, 60), 2, -1),
                      ("fixed", (0, 0, 55)), ("fixed", (0, 0, 5))],
        "tool": [("X", (0, 400, 550), 0, 1), ("Z", (0, -400, -250), 2, 1),
                 ("fixed", (0, 0, -80)), ("fixed", (0, 0, -20))],
    },
    "sts_lathe": {
        "workpiece": [("X", (0, 0, 80), 0, -1), ("C", (0, 0, 70), 2, -1),
                      ("fixed", (0, 0, 45)), ("fixed", (0, 0, 5))],
        "tool": [("Z", (0, 0, 350), 2, 1), ("fixed", (0, 0, -130)), ("fixed", (0, 0, -20))],
    },
}


def trans(v) -> np.ndarray:
    out = np.eye(4)
    out[:3, 3] = v
    return out


def rot(k: int, angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    i, j = (k + 1) % 3, (k + 2) % 3
    out = np.eye(4)
    out[i, i], out[i, j], out[j, i], out[j, j] = c, -s, s, c
    return out


def six(t, r) -> np.ndarray:
    """T(t) Rx(r0) Ry(r1) Rz(r2), the error transform of docs/machines.md."""
    return trans(t) @ rot(0, r[0]) @ rot(1, r[1]) @ rot(2, r[2])


def reference_branch(machine, branch, q, errors: ErrorModel, terminal=None):
    """Pose of the branch's end in the base, by the docs' formulas."""
    values = dict(zip(machine.axes, q, strict=True))
    out = np.eye(4)
    for element in GEOMETRY[machine.name][branch]:
        if element[0] == "fixed":
            out = out @ trans(np.array(element[1]) * MM)
            continue
        letter, xyz, k, sign = element
        ax = machine.axis(letter)
        loc = errors.location.get(letter, {})
        vec = {d: loc.get(f"E{d}0{letter}", 0.0) for d in "XYZABC"}
        own = "ABC"[k] if ax.rotary else None
        zero = vec.pop(own) if own else 0.0
        e = six([vec["X"], vec["Y"], vec["Z"]],
                 [vec.get("A", 0.0), vec.get("B", 0.0), vec.get("C", 0.0)])
        comp = errors.component.get(letter, {})
        cv = {d: float(comp[f"E{d}{letter}"].evaluate([values[letter]])[0])
              if f"E{d}{letter}" in comp else 0.0 for d in "XYZABC"}
        c = six([cv["X"], cv["Y"], cv["Z"]], [cv["A"], cv["B"], cv["C"]])
        c = c if ax.side > 0 else np.linalg.inv(c)
        if ax.rotary:
            motion = c @ rot(k, sign * (values[letter] + zero))
        else:
            step = np.zeros(3)
            step[k] = sign * values[letter]
            motion = trans(step) @ c
        out = out @ trans(np.array(xyz) * MM) @ e @ motion @ np.linalg.inv(e)
    if terminal is not None:
        out = out @ terminal
    return out


def reference_pose(machine, q, errors, frame="tool_tip"):
    wp = errors.workpiece
    w = reference_branch(machine, q=q, errors=errors, branch="workpiece",
                         terminal=six(wp.delta, [wp.alpha, wp.beta, wp.gamma]))
    if frame == "tool_tip":
        t = reference_branch(machine, "tool", q, errors,
                             terminal=six(errors.tool.offset, errors.tool.rotation))
    else:
        t = reference_branch(machine, "probe", q, errors)
    return np.linalg.inv(w) @ t


def assert_pose_close(a, b, tol=1e-12):
    """Positions within tol m, rotation matrices within tol (rad, to first order)."""
    np.testing.assert_allclose(a[..., :3, 3], b[..., :3, 3], rtol=0, atol=tol)
    np.testing.assert_allclose(a[..., :3, :3], b[..., :3, :3], rtol=0, atol=tol)


MACHINES = list_machines()


def test_the_five_machines_ship():
    assert MACHINES == ("grooving_4axis", "planer_4axis", "robonano_a0ib", "robonano_ui",
                        "sts_lathe")
    axes = {name: load_machine(name).axes for name in MACHINES}
    assert axes == {"robonano_ui": ("X", "Y", "Z", "A", "B", "C"),
                    "robonano_a0ib": ("X", "Y", "Z", "B", "C"),
                    "planer_4axis": ("X", "Y", "Z", "A"),
                    "grooving_4axis": ("X", "Y", "Z", "C"),
                    "sts_lathe": ("X", "Z", "C")}


@pytest.mark.parametrize("name", MACHINES)
def test_nominal_zero_puts_the_edge_on_the_workpiece_origin(name):
    machine = load_machine(name)
    pose = machine.tool_pose(np.zeros(len(machine.axes)))
    # 1e-15 m: the placements are decimal millimetres, summed in float64 along the chain
    assert_pose_close(pose, np.eye(4), tol=1e-15)


@pytest.mark.parametrize("name", MACHINES)
def test_pose_matches_the_independent_chain_with_every_error_family(name):
    machine = load_machine(name)
    rng = np.random.default_rng(7)
    for _ in range(3):
        errors = random_errors(machine, rng)
        qs = random_q(machine, rng, 8)
        batch = machine.tool_pose(qs, errors)
        for q, pose in zip(qs, batch, strict=True):
            expected = reference_pose(machine, q, errors)
            assert_pose_close(pose, expected)  # batched evaluator
            assert_pose_close(machine.pinocchio_pose(q, errors), expected)  # Pinocchio


def test_probe_tip_follows_the_same_erroneous_kinematics():
    machine = load_machine("robonano_a0ib")
    rng = np.random.default_rng(3)
    errors = random_errors(machine, rng)
    for q in random_q(machine, rng, 5):
        pose = machine.frame_pose("probe_tip", q, errors)
        assert_pose_close(pose, reference_pose(machine, q, errors, frame="probe_tip"))


def test_zero_error_model_is_the_nominal_machine():
    machine = load_machine("robonano_ui")
    q = random_q(machine, np.random.default_rng(1), 20)
    np.testing.assert_array_equal(machine.tool_pose(q, ErrorModel()), machine.tool_pose(q))


def test_planer_edge_swings_on_its_arm_with_the_setting_error():
    """Paper 000: edge on an arm of radius r below the A axis, offset e_ys sideways.

    At tool angle theta the edge sits at y = e cos(theta) + r sin(theta),
    z = r0 + e sin(theta) - r cos(theta) in the workpiece frame (A axis at height r0 = 120.5
    mm over the origin), so the depth grows by e sin(theta) + r (1 - cos(theta)) -
    derived in docs/procedures/tool_rotation_arm.md.
    """
    machine = load_machine("planer_4axis")
    r0, r, e = 120.5 * MM, 120.555 * MM, -0.178 * MM
    errors = ErrorModel(tool=ToolSetting([0.0, e, -(r - r0)], [0.0, 0.0, 0.0]))
    for theta_deg in (0.0, 10.0, 20.0, 30.0, 40.0):
        t = math.radians(theta_deg)
        pose = machine.tool_pose([0.0, 0.0, 0.0, t], errors)
        expected = [0.0, e * math.cos(t) + r * math.sin(t), r0 + e * math.sin(t) - r * math.cos(t)]
        np.testing.assert_allclose(pose[:3, 3], expected, rtol=0, atol=1e-15)
        z0 = machine.tool_pose([0.0, 0.0, 0.0, 0.0], errors)[2, 3]
        rise = e * math.sin(t) + r * (1 - math.cos(t))
        assert pose[2, 3] - z0 == pytest.approx(rise, abs=1e-15)


def test_robonano_ui_a_flip_moves_the_edge_by_twice_its_offset():
    """Paper 001: an edge offset (dx, dy) from the A centre line flips with A = 180 deg."""
    machine = load_machine("robonano_ui")
    dx, dy = 490.04 / 2 * UM, 680.12 / 2 * UM
    errors = ErrorModel(tool=ToolSetting([dx, dy, 0.0], [0.0, 0.0, 0.0]))
    at0 = machine.tool_pose([1 * MM, 2 * MM, 0.0, 0.0, 0.0, 0.0], errors)
    at180 = machine.tool_pose([1 * MM, 2 * MM, 0.0, math.pi, 0.0, 0.0], errors)
    np.testing.assert_allclose(at0[:3, 3] - at180[:3, 3], [2 * dx, 2 * dy, 0.0], atol=1e-15)


def test_c_axis_offset_turns_the_part_about_the_true_centre():
    """A C centre line at (ex, ey): the tool at C = 180 lands at 2 (ex, ey) - p."""
    machine = load_machine("grooving_4axis")
    ex, ey = 12 * UM, -7 * UM
    errors = ErrorModel(location={"C": {"EX0C": ex, "EY0C": ey}})
    x, y = 3 * MM, 4 * MM
    pose = machine.tool_pose([x, y, 0.0, math.pi], errors)
    # the workpiece turned by pi about (ex, ey) in the machine; the tool at (x, y) then sits at
    # the workpiece point that was at 2 e - (x, y)
    np.testing.assert_allclose(pose[:2, 3], [2 * ex - x, 2 * ey - y], atol=1e-15)
    assert_pose_close(machine.tool_pose([x, y, 0.0, 0.0], errors), trans([x, y, 0.0]), 1e-15)


def test_squareness_tilts_the_y_motion():
    """EC0Y: Y moves along (-sin e, cos e) in the XY plane, relative to the workpiece."""
    machine = load_machine("grooving_4axis")
    eps = 10 * URAD
    errors = ErrorModel(location={"Y": {"EC0Y": eps}})
    y = 200 * MM
    pose = machine.tool_pose([0.0, y, 0.0, 0.0], errors)
    np.testing.assert_allclose(pose[:3, 3], [-y * math.sin(eps), y * math.cos(eps), 0.0],
                               atol=1e-15)


def test_positioning_error_table_adds_along_the_axis():
    machine = load_machine("grooving_4axis")
    table = ComponentError("table", np.array([-250, 0, 250]) * MM, np.array([-3, 0, 8]) * UM)
    errors = ErrorModel(component={"X": {"EXX": table}, "Y": {"EYY": table}})
    for v in (-250 * MM, -100 * MM, 125 * MM):
        expected = v + table.evaluate([v])[0]
        assert machine.tool_pose([v, 0, 0, 0], errors)[0, 3] == pytest.approx(expected, abs=1e-15)
        assert machine.tool_pose([0, v, 0, 0], errors)[1, 3] == pytest.approx(expected, abs=1e-15)


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


def test_jacobian_of_a_linear_setting_parameter_is_exact():
    """The tool offset in tool_mount axes moves the edge by R_mount * d: checks columns."""
    machine = load_machine("robonano_ui")
    q = np.array([0.0, 0.0, 0.0, 0.3, -0.5, 0.0])
    jac = machine.error_jacobian(q, ErrorModel(), ["tool.x", "tool.y", "tool.z"])
    # rotation of tool_mount in the workpiece: Ry(B) Rz(A) (C = 0)
    expected = (rot(1, -0.5) @ rot(2, 0.3))[:3, :3]
    np.testing.assert_allclose(jac[:3, :3], expected, atol=1e-15)
    np.testing.assert_allclose(jac[3:, :3], 0.0, atol=1e-15)


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


@pytest.mark.parametrize("name", ["grooving_4axis", "planer_4axis", "robonano_a0ib",
                                  "robonano_ui", "sts_lathe"])
def test_home_is_z_at_the_top_of_its_travel_and_every_other_axis_at_zero(name):
    machine = load_machine(name)
    z = machine.axes.index("Z")
    expected = np.zeros(len(machine.axes))
    expected[z] = machine.upper[z]
    np.testing.assert_array_equal(machine.home, expected)
    assert machine.upper[z] > 0.0  # clear of a work zero at machine zero


def test_a_pickled_machine_carries_no_pinocchio_workspace_and_computes_the_same():
    import pickle

    machine = load_machine("robonano_a0ib")
    errors = random_errors(machine, np.random.default_rng(3))
    q = random_q(machine, np.random.default_rng(4), 5)
    raw = pickle.dumps(machine)
    # the workspace (pin.Data) alone pickles to more than the whole machine does now
    assert len(raw) < len(pickle.dumps(machine.kin.data))
    back = pickle.loads(raw)
    assert isinstance(back.kin.data, pin.Data)
    np.testing.assert_array_equal(back.tool_pose(q, errors), machine.tool_pose(q, errors))
    full = machine.kin.full_q(q[0], machine.binding(errors))
    np.testing.assert_array_equal(back.kin.relative_jacobian(full),
                                  machine.kin.relative_jacobian(full))


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


@pytest.mark.parametrize("name", list_machines())
def test_the_error_joints_leave_the_urdf_as_read(name):
    # augment_urdf builds its <robot> from the file's own link and joint elements rather
    # than a deep copy of them: none of them may change (Machine.digest is taken from the
    # tree as read), and the same tree gives the same text again
    import hashlib
    import xml.etree.ElementTree as ET

    from machinesim.kinematics import augment_urdf
    from machinesim.urdf import read_urdf

    machine = load_machine(name)
    as_read = read_urdf(machine.path)
    assert machine.digest == hashlib.sha256(ET.tostring(as_read)).hexdigest()
    axes = {a.letter: a for a in machine._axes}
    assert augment_urdf(as_read, axes) == augment_urdf(as_read, axes) == machine.urdf_xml


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


def test_tool_poses_of_runs_are_each_runs_own_call_bit_for_bit(monkeypatch):
    """`Machine.tool_poses` poses many runs in one batch as a call per run does. The
    evaluator picks a series or numpy's sin/cos by the largest angle of each call's block:
    a run turned 3 mrad about C (series) batched naively with one at 1 rad (cos/sin) comes
    out other bits; tool_poses keeps each run's, also when a run spans several blocks
    (`_BLOCK` made 4 here: the 6-row run is two calls' blocks, small then large)."""
    import machinesim.batched_kinematics as bk

    machine = load_machine("robonano_a0ib")
    errors = random_errors(machine, np.random.default_rng(3))
    rng = np.random.default_rng(7)

    def run(c_values):
        q = np.column_stack([rng.uniform(-1e-3, 1e-3, (len(c_values), 3)),
                             np.zeros(len(c_values)), c_values])
        return q

    small = run(np.array([5e-3, 3.5e-3, 5e-3]))  # sin(x) not the series' bits
    large = run(np.full(2, 1.0))
    spanning = run(np.array([5e-3, 3.5e-3, 5e-3, 3.5e-3, 1.0, 1.2]))
    runs = [small, large, spanning, small[:1]]
    monkeypatch.setattr(bk, "_BLOCK", 4)
    own = [machine.tool_pose(q) for q in runs]  # nominal: C turns by the values given
    naive = machine.tool_pose(np.concatenate(runs[:2]))
    assert not np.array_equal(naive[:3], own[0])  # the choice matters at these angles
    monkeypatch.setattr(bk, "_BLOCK", 8)
    assert not np.array_equal(machine.tool_pose(spanning)[:4], own[2][:4])
    monkeypatch.setattr(bk, "_BLOCK", 4)
    for model in (None, errors):
        own = [machine.tool_pose(q, model) for q in runs]
        batched = machine.tool_poses(runs, model)
        assert [p.shape for p in batched] == [p.shape for p in own]
        for got, want in zip(batched, own, strict=True):
            assert np.array_equal(got, want)
    assert machine.tool_poses([], errors) == []
    with pytest.raises(InputError):
        machine.tool_poses([np.zeros(5)], errors)
