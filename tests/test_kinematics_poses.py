"""Kinematics against an independent chain and the papers' geometry: the five machines, the
edge on the workpiece origin at zero, poses with every error family, the probe tip, the
setting errors, squareness and positioning tables, home, pickles, the error joints left
out of the URDF as read, and each run's own tool poses.

The independent chain below is written from docs/machines.md (its placement tables and its
error formulas) with plain 4x4 matrices: it shares no code with the URDF reading, the error
joints or Pinocchio.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from kinematics_helpers import assert_pose_close, rot, trans

from machinesim.errors import ComponentError, ErrorModel, ToolSetting
from machinesim.exceptions import InputError
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
