"""Generic identification's observation model (machinesim.identification.observation_model):
error Jacobians agree with central differences, batched readings with Pinocchio's pose by
pose, and a fit of many poses asks Pinocchio for no pose."""

from __future__ import annotations

import numpy as np
import pytest
from identification_fit_helpers import SIGMA, UM, URAD, assert_recovered

from machinesim.errors import ErrorModel
from machinesim.exceptions import InputError
from machinesim.identification.fit import fit, observations
from machinesim.identification.observation_model import _Plan
from machinesim.machines import list_machines, load_machine
from machinesim.sampling import random_axis_values, random_errors


@pytest.mark.parametrize(("name", "frame"), [("robonano_ui", "tool_tip"),
                                             ("robonano_a0ib", "probe_tip"),
                                             ("grooving_4axis", "tool_mount")])
def test_error_jacobian_of_a_point_matches_central_differences(name, frame):
    machine = load_machine(name)
    rng = np.random.default_rng(12)
    errors = random_errors(machine, rng)
    every = machine.parameter_names(errors)
    # every setting and location parameter, and one component entry in 25 (the time)
    names = [n for i, n in enumerate(every) if not n.startswith("component") or i % 25 == 0]
    q = random_axis_values(machine, rng, 3)
    point = rng.normal(0, 0.05, (3, 3))
    jac = machine.error_jacobian(q, errors, names, frame=frame, point=point)
    origin = machine.error_jacobian(q, errors, names, frame=frame)
    assert jac.shape == (3, 6, len(names))
    np.testing.assert_array_equal(jac[:, 3:], origin[:, 3:])  # rotation rows: the frame's
    values = errors.parameters()

    def place(model):
        pose = machine.frame_pose(frame, q, model)
        return pose[:, :3, 3] + np.einsum("nij,nj->ni", pose[:, :3, :3], point)

    h = 1e-6
    for c, p in enumerate(names):
        base = values.get(p, 0.0)
        fd = (place(errors.with_parameters({p: base + h}))
              - place(errors.with_parameters({p: base - h}))) / (2 * h)
        # truncation h^2 / 6 * (third derivative, ~ the 1 m lever) ~ 2e-13, round-off
        # 1e-16 m / 1e-6 ~ 1e-10 per unit: 1e-8 holds with margin, far below the
        # 1e-3 .. 1 size of the entries (as tests/test_kinematics_jacobians.py)
        np.testing.assert_allclose(jac[:, :3, c], fd, rtol=0, atol=1e-8, err_msg=p)
    # one point for all rows, and one configuration, give the same rows
    single = machine.error_jacobian(q[1], errors, names, frame=frame, point=point[1])
    np.testing.assert_array_equal(single, jac[1])
    shared = machine.error_jacobian(q, errors, names, frame=frame, point=point[0])
    np.testing.assert_array_equal(shared[0], jac[0])
    with pytest.raises(InputError, match=r"point coordinates \(m\) of shape \(3,\) or \(3, 3\)"):
        machine.error_jacobian(q, errors, names, frame=frame, point=np.zeros((2, 3)))
    with pytest.raises(InputError, match="frame 'nowhere' is not on"):
        machine.error_jacobian(q, errors, names, frame="nowhere")


def pose_by_pose(monkeypatch, machine):
    """Have ``machine``'s poses made one at a time by Pinocchio (`Machine.pinocchio_pose`),
    as the fit's model readings were before they were batched."""
    monkeypatch.setattr(machine, "frame_pose", lambda frame, q, errors=None:
                        machine.pinocchio_pose(q, errors, frame), raising=False)


@pytest.mark.parametrize("name", list_machines())
def test_model_readings_batched_are_pinocchios_pose_by_pose(name, monkeypatch):
    # The model readings had taken one Pinocchio pass a distinct pose (18-26 us on
    # robonano_a0ib, most of a fit's time); they are now every pose at once by the batched
    # evaluator (Machine.frame_pose). Held against that pose-by-pose path on every frame, at
    # no error and at every error family, of points off the frame origins, along any
    # direction, absolute and zeroed, poses repeated: the readings differ by at most
    # 2.4e-16 m (measured over five draws a machine), an ulp or two of the ~0.5 m
    # coordinates they are differences of; at no error both read exactly 0
    machine = load_machine(name)
    rng = np.random.default_rng(23)
    n = 60
    q = random_axis_values(machine, rng, 40)[rng.integers(0, 40, n)]
    zero_at = random_axis_values(machine, rng, n)
    zero_at[rng.random(n) < 0.5] = np.nan  # half the readings absolute
    obs = observations(q, directions=rng.normal(size=(n, 3)), values=np.zeros(n), sigma=SIGMA,
                       frame=tuple(rng.choice(machine.frames, n).tolist()),
                       point=rng.normal(0, 0.02, (n, 3)), zero_at=zero_at)
    errors = random_errors(machine, rng)
    batched = _Plan(machine, obs, ())
    with monkeypatch.context() as patch:
        pose_by_pose(patch, machine)
        reference = _Plan(machine, obs, ())
        np.testing.assert_array_equal(reference.readings(None), 0.0)
        expected = reference.readings(errors)
    np.testing.assert_array_equal(batched.readings(None), 0.0)
    got = batched.readings(errors)
    assert np.max(np.abs(got)) > 1e-4  # the errors move the points by ~0.1-10 mm
    np.testing.assert_allclose(got, expected, rtol=0, atol=5e-16)
    single = machine.pinocchio_pose(q[0], errors, obs.frames[0])
    np.testing.assert_allclose(single, machine.frame_pose(obs.frames[0], q[0], errors),
                               rtol=0, atol=5e-16)
    with pytest.raises(InputError, match="frame 'nowhere' is not on"):
        machine.pinocchio_pose(q, errors, "nowhere")


def test_a_fit_of_many_poses_asks_pinocchio_for_no_pose(monkeypatch):
    # Before, each Gauss-Newton step read the model at each of these 2000 poses by Pinocchio
    # (a fit of 100,000 readings took 8.7 s, now 1.6 s: benchmarks/fit_speed.py); now none. The
    # estimate is that of the pose-by-pose path to 5e-17 (m, rad; measured 0.8e-18 ..
    # 1.2e-17 over eight draws, this one 1.0e-17; the values are 2-20 um and urad)
    machine = load_machine("robonano_a0ib")
    rng = np.random.default_rng(24)
    names = ["workpiece.x", "workpiece.y", "location.C.EX0C", "location.C.EA0C"]
    truth = ErrorModel().with_parameters(dict(zip(names, (3 * UM, -2 * UM, 5 * UM, 20 * URAD),
                                                  strict=True)))
    q = random_axis_values(machine, rng, 2000)
    u = rng.normal(size=(2000, 3))
    moved = machine.tool_pose(q, truth)[:, :3, 3] - machine.tool_pose(q)[:, :3, 3]
    obs = observations(q, directions=u, sigma=SIGMA, values=np.einsum(
        "ni,ni->n", u / np.linalg.norm(u, axis=1)[:, None], moved))
    with monkeypatch.context() as patch:
        pose_by_pose(patch, machine)
        reference = fit(machine, obs, names)

    def per_pose(*args, **kwargs):
        raise AssertionError("Pinocchio called for one pose")

    monkeypatch.setattr(machine.kin, "frame_pose", per_pose)
    monkeypatch.setattr(machine.kin, "relative_jacobian", per_pose)
    estimate = fit(machine, obs, names)
    assert estimate.rank == 4
    np.testing.assert_allclose(estimate.values, reference.values, rtol=0, atol=5e-17)
    assert_recovered(estimate, truth, names)
