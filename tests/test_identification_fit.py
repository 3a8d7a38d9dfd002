"""Generic identification (machinesim.identification.fit) on an R-test plan of robonano_ui.

The plan follows the R-test of ISO 10791-6: a ball on the tool, read by three displacement
sensors along the workpiece X, Y and Z, at poses that turn A, B and C together while X, Y
and Z move. Two balls are read at each pose (a two-length R-test): one centred on the tool
edge, one 40 mm up the tool axis, whose lever is what shows tilts of the tool and of the A
axis line. The tests make the readings from a truth ErrorModel with `Machine.frame_pose`
(the truth minus the nominal machine, projected on the directions); `fit` only receives the
readings.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from machinesim.errors import ErrorModel
from machinesim.exceptions import ErrorModelError, InputError
from machinesim.identification.fit import (
    Combination,
    NotConvergedError,
    Observation,
    Observations,
    fit,
    observations,
    plan_quality,
)
from machinesim.identification.observation_model import _Plan
from machinesim.machines import list_machines, load_machine
from machinesim.sampling import random_axis_values, random_errors

DEG = np.pi / 180
UM = 1e-6
URAD = 1e-6
MACHINE = load_machine("robonano_ui")
SETTING = ("tool.x", "tool.y", "tool.z", "tool.rx", "tool.ry", "tool.rz",
           "workpiece.x", "workpiece.y", "workpiece.z",
           "workpiece.alpha", "workpiece.beta", "workpiece.gamma")
LOCATION = tuple(n for n in MACHINE.parameter_names()
                 if n.startswith(("location.A.", "location.B.", "location.C.")))
FULL = SETTING + LOCATION
#: No reading of points on the tool sees these 7 directions (`test_full_set_...` finds them):
#: the tool's rotation about its own axis; a rotary axis' zero offset, which a rotation of the
#: tool (A; B with the A line's tilt) or workpiece setting (C) undoes; and a shift of
#: everything along X, Y or Z. A lab fixes a datum, one parameter per direction, by not
#: fitting it: here the zero of each rotary axis, the C axis line as the XY origin and the B
#: axis line as the Z origin.
DATUM = ("tool.rz", "location.A.EC0A", "location.B.EB0B", "location.C.EC0C",
         "location.C.EX0C", "location.C.EY0C", "location.B.EZ0B")
FITTED = tuple(n for n in FULL if n not in DATUM)
BALLS = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.04]])
SIGMA = 50e-9


def r_test_plan(poses_deg, seed=0):
    """Axis values, directions and ball centres (6 readings per pose: 2 balls x X, Y, Z).

    ``poses_deg`` are (A, B, C) in degrees; X, Y, Z are drawn within the travel.
    """
    rng = np.random.default_rng(seed)
    abc = np.asarray(poses_deg, dtype=float) * DEG
    xyz = rng.uniform([-0.05, -0.03, -0.01], [0.05, 0.03, 0.05], (len(abc), 3))
    q = np.repeat(np.column_stack([xyz, abc]), 6, axis=0)
    points = np.tile(np.repeat(BALLS, 3, axis=0), (len(abc), 1))
    directions = np.tile(np.eye(3), (2 * len(abc), 1))
    return q, directions, points


#: 12 poses: A at four angles, B at three, C at four, each combination of A and B once.
PLAN = r_test_plan([(a, b, c) for (a, b), c in zip(
    [(a, b) for a in (0, 90, 180, 270) for b in (-45, 0, 45)], [0, 90, 180, 270] * 3,
    strict=True)])


def read(truth, q, directions, points, frame="tool_tip"):
    """What the sensors read: the point's displacement from its nominal place, along u."""
    points = np.broadcast_to(points, (len(q), 3))

    def place(errors):
        pose = MACHINE.frame_pose(frame, q, errors)
        return pose[:, :3, 3] + np.einsum("nij,nj->ni", pose[:, :3, :3], points)
    return np.einsum("ni,ni->n", directions, place(truth) - place(None))


def random_truth(rng, names, length=20 * UM, angle=50 * URAD, tool=200 * UM,
                 tool_angle=1e-3, workpiece=50 * UM, workpiece_angle=5e-3):
    """Errors on ``names`` only (normal, standard deviations by family), zero elsewhere."""
    values = {}
    for name in names:
        rotation = name.split(".")[-1] in ("rx", "ry", "rz", "alpha", "beta", "gamma") or (
            name.startswith("location") and name.split(".")[-1][1] in "ABC")
        if name.startswith("tool."):
            values[name] = rng.normal(0, tool_angle if rotation else tool)
        elif name.startswith("workpiece."):
            values[name] = rng.normal(0, workpiece_angle if rotation else workpiece)
        else:
            values[name] = rng.normal(0, angle if rotation else length)
    return ErrorModel().with_parameters(values)


def assert_recovered(estimate, truth, names):
    """1e-6 relative or 1e-12 (m or rad) absolute: far above the float64 floor of the fit
    (its steps bottom out at ~1e-16 m and ~1e-15 rad), far below anything a plan with 50 nm
    sensors resolves."""
    values = truth.parameters()
    for name in names:
        got = estimate.values[estimate.names.index(name)]
        want = values.get(name, 0.0)
        assert abs(got - want) <= max(1e-6 * abs(want), 1e-12), (name, got, want)


def test_datum_fixed_r_test_identifies_every_parameter():
    rng = np.random.default_rng(1)
    truth = random_truth(rng, FITTED)
    q, u, p = PLAN
    estimate = fit(MACHINE, observations(q, directions=u, values=read(truth, q, u, p),
                                         sigma=SIGMA, point=p), FITTED)
    assert estimate.rank == len(FITTED) == 20
    assert estimate.unidentifiable == ()
    assert np.all(np.isfinite(estimate.std))
    assert estimate.condition < 30  # measured 13.5 on this plan
    assert_recovered(estimate, truth, FITTED)
    assert estimate.residual_rms < 1e-15
    assert estimate.errors.parameters()["tool.x"] == estimate.values[0]
    report = estimate.as_dict()
    assert set(report) == set(FITTED)
    assert report["tool.y"]["std"] == estimate.std[1]
    # the tool and workpiece settings were drawn at 200 um and 5 mrad: Gauss-Newton needs
    # a few steps, then converges quadratically
    assert estimate.iterations <= 6


def test_full_set_names_the_symmetries_and_recovers_the_rest():
    rng = np.random.default_rng(2)
    truth = random_truth(rng, FULL)
    q, u, p = PLAN
    estimate = fit(MACHINE, observations(q, directions=u, values=read(truth, q, u, p),
                                         sigma=SIGMA, point=p), FULL)
    assert estimate.rank == len(FULL) - 7
    combinations = estimate.combinations
    assert len(combinations) == 7
    members = [set(c.names) for c in combinations]

    def named(*names):
        return any(set(names) <= m for m in members)

    # the seven symmetries of tool-ball readings (see DATUM)
    assert {"tool.rz"} in members
    # no reading moves A's zero offset at the prior (the balls lie on the A line): the fit
    # holds it at the prior's value, a datum, where it had followed the tool offset it trades
    # against (EC0A + tool.x + tool.y at the estimate)
    assert {"location.A.EC0A"} in members
    assert named("location.B.EB0B", "location.A.EB0A", "tool.ry")
    assert named("location.C.EC0C", "workpiece.gamma")
    assert named("tool.x", "workpiece.x", "location.A.EX0A", "location.B.EX0B",
                 "location.C.EX0C")
    assert named("tool.y", "workpiece.y", "location.A.EY0A", "location.C.EY0C")
    assert named("tool.z", "workpiece.z", "location.B.EZ0B")
    # the tilts of the B and C axis lines take part in none of them
    tilts = ("location.B.EA0B", "location.B.EC0B", "location.C.EA0C", "location.C.EB0C")
    assert set(tilts) <= set(estimate.identifiable)
    assert_recovered(estimate, truth, estimate.identifiable)
    # A parameter no reading sees keeps the prior's value exactly, and its std is NaN.
    i = FULL.index("tool.rz")
    assert estimate.values[i] == 0.0 and np.isnan(estimate.std[i])
    assert "tool.rz" in estimate.unidentifiable
    # Along the null space the estimate keeps the prior's part: estimate minus prior (zero)
    # is orthogonal (SI) to every named combination (measured 3e-11 of the norms; the
    # coefficients dropped from a combination, below 1e-6 of its largest, bound it).
    values = dict(zip(FULL, estimate.values, strict=True))
    for c in combinations:
        scale = np.linalg.norm(c.coefficients) * np.linalg.norm(estimate.values)
        assert abs(c.value(values)) <= 1e-6 * scale, str(c)
    # So a combination's own value (coefficients . truth) is exactly what the readings
    # cannot fix: along an exact linear symmetry (the shifts, tool.rz) the estimate holds
    # the prior's, and the rest is fixed; the zero-offset symmetries are curved (each turns
    # the settings it is traded against), so not even that is linear. What is guaranteed is
    # that the estimate lies on the truth's orbit: it predicts every reading of a ball on
    # the tool axis, at any pose and along any direction, as the truth does; checked at
    # fresh poses (to 1e-12 m; measured 1e-16 m). The check can fail: a ball off the tool
    # axis would see tool.rz, and there the two models differ by micrometres.
    check_indistinguishable(estimate.errors, truth)
    q_new = random_axis_values(MACHINE, np.random.default_rng(8), 20)
    off_axis = np.broadcast_to([0.01, 0.0, 0.02], (20, 3))
    u_new = np.tile([1.0, 0.0, 0.0], (20, 1))
    miss = read(estimate.errors, q_new, u_new, off_axis) - read(truth, q_new, u_new, off_axis)
    assert np.max(np.abs(miss)) > 1 * UM
    # Fixing a datum makes the same readings fully identifiable (rank 20), on the same orbit.
    datum = fit(MACHINE, observations(q, directions=u, values=read(truth, q, u, p),
                                      sigma=SIGMA, point=p), FITTED)
    assert datum.rank == len(FITTED) and datum.unidentifiable == ()
    check_indistinguishable(datum.errors, truth)


def check_indistinguishable(estimate, truth):
    rng = np.random.default_rng(7)
    q = random_axis_values(MACHINE, rng, 50, fraction=0.9)
    u = rng.normal(size=(50, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    for ball in BALLS:
        points = np.broadcast_to(ball, (50, 3))
        np.testing.assert_allclose(read(estimate, q, u, points), read(truth, q, u, points),
                                   rtol=0, atol=1e-12)


def test_reported_std_matches_the_scatter_of_noisy_fits():
    rng = np.random.default_rng(1)
    truth = random_truth(rng, FITTED)
    q, u, p = PLAN
    clean = read(truth, q, u, p)
    noise = np.random.default_rng(2024)
    # A lab recalibrating starts from its previous calibration: one noisy fit from no prior,
    # then the 200 trials from it (3 Gauss-Newton steps each instead of 4: this test's time).
    previous = fit(MACHINE, observations(q, directions=u,
                                         values=clean + noise.normal(0, SIGMA, len(q)),
                                         sigma=SIGMA, point=p), FITTED)
    estimates, stds = [], []
    for _ in range(200):
        readings = clean + noise.normal(0, SIGMA, len(q))
        estimate = fit(MACHINE, observations(q, directions=u, values=readings, sigma=SIGMA,
                                             point=p), FITTED, prior=previous.errors)
        estimates.append(estimate.values)
        stds.append(estimate.std)
    estimates, stds = np.array(estimates), np.array(stds)
    want = np.array([truth.parameters().get(n, 0.0) for n in FITTED])
    # 200 trials give the sample std to ~5 % (1 / sqrt(2 * 199)): 20 % is 4 of those
    np.testing.assert_allclose(estimates.std(axis=0, ddof=1) / stds.mean(axis=0), 1.0, atol=0.2)
    z = (estimates - want) / stds
    assert abs(z.mean()) < 0.15
    assert abs(z.std() - 1.0) < 0.2


def xy_plan():
    """Tool vertical (A = B = 0), C at 10 angles, readings along workpiece X and Y only."""
    rng = np.random.default_rng(3)
    n = 10
    xyz = rng.uniform([-0.05, -0.03, -0.01], [0.05, 0.03, 0.05], (n, 3))
    q = np.column_stack([xyz, np.zeros((n, 2)), np.arange(n) * 36 * DEG])
    return np.repeat(q, 2, axis=0), np.tile(np.eye(3)[:2], (n, 1))


def test_a_plan_that_cannot_see_a_parameter_names_it():
    # location.C.EZ0C would move the C line along itself: the machine refuses that symbol.
    # What XY readings cannot see is the workpiece's Z: at the nominal machine its column is
    # exactly zero.
    names = ("workpiece.x", "workpiece.y", "workpiece.z", "workpiece.alpha", "workpiece.beta",
             "workpiece.gamma", "location.C.EX0C", "location.C.EY0C", "location.C.EA0C",
             "location.C.EB0C")
    q, u = xy_plan()
    before = plan_quality(MACHINE, q, names, directions=u, sigma=SIGMA)
    assert before.rank == len(names) - 1
    assert "workpiece.z" in before.unidentifiable
    assert [str(c) for c in before.combinations] == ["workpiece.z"]
    assert np.isnan(before.std[2]) and np.all(np.isfinite(np.delete(before.std, 2)))
    # and says so in words, where a person reads before trusting the figures
    assert [n.split(":")[:2] for n in before.notes] == [
        ["rank 9 of 10", " the readings cannot see workpiece.z"]]
    truth = ErrorModel().with_parameters({
        "workpiece.x": 30 * UM, "workpiece.y": -20 * UM, "workpiece.z": 10 * UM,
        "workpiece.alpha": 2e-3, "workpiece.beta": -1e-3, "workpiece.gamma": 4e-3,
        "location.C.EX0C": 5 * UM, "location.C.EY0C": -7 * UM,
        "location.C.EA0C": 30 * URAD, "location.C.EB0C": -20 * URAD})
    obs = observations(q, directions=u, values=read(truth, q, u, np.zeros(3)), sigma=SIGMA)
    estimate = fit(MACHINE, obs, names)
    assert estimate.rank == len(names) - 1
    assert "workpiece.z" in estimate.unidentifiable
    # No reading moves it at the prior, so the fit holds it there, exactly, for good: a datum,
    # as if left out of the fit (tilted by alpha and beta, the workpiece's Z leans into X and
    # Y at the estimate, where it would have been one combination with x and y)
    (c,) = estimate.combinations
    assert str(c) == "workpiece.z"
    (note,) = estimate.notes  # the rank is 9 at the prior too: nothing newly seen
    assert note.startswith("rank 9 of 10: the readings cannot see workpiece.z: its value is "
                           "the prior's, not measured")
    assert estimate.unseen_at_prior == ()
    assert estimate.values[2] == 0.0 and np.isnan(estimate.std[2])
    assert_recovered(estimate, truth, names[3:])
    # x and y take up the truth's 10 um of Z leaning through the tilts: |beta| z = 10 nm and
    # |alpha| z = 20 nm (to 1e-3 * 10 um * 1e-3, second order), the readings fitted exactly
    assert abs(estimate.values[0] - 30 * UM) == pytest.approx(1e-3 * 10 * UM, rel=1e-4, abs=0.0)
    assert abs(estimate.values[1] + 20 * UM) == pytest.approx(2e-3 * 10 * UM, rel=1e-4, abs=0.0)
    assert estimate.residual_rms < 1e-15
    # the same as the fit without it (measured 3e-20 m apart, std equal)
    without = [n for n in names if n != "workpiece.z"]
    datum = fit(MACHINE, obs, without)
    np.testing.assert_allclose(np.delete(estimate.values, 2), datum.values, rtol=0, atol=1e-15)
    np.testing.assert_allclose(np.delete(estimate.std, 2), datum.std, rtol=1e-9)
    # plan_quality linearised where the fit ended, of what it fitted, gives the fit's figures
    after = plan_quality(MACHINE, q, without, directions=u, sigma=SIGMA, prior=estimate.errors)
    assert after.rank == estimate.rank
    assert after.condition == pytest.approx(estimate.condition, rel=1e-9)
    r = estimate.rank
    np.testing.assert_allclose(after.singular_values[:r], estimate.singular_values[:r],
                               rtol=1e-9)
    assert after.unidentifiable == ()
    assert [str(x) for x in estimate.unidentifiable] == ["workpiece.z", "workpiece.z"]


def test_large_setting_errors_converge():
    rng = np.random.default_rng(4)
    small = dict(random_truth(rng, FITTED).parameters())
    large = {"workpiece.x": 80 * UM, "workpiece.y": -80 * UM, "workpiece.z": 80 * UM,
             "workpiece.alpha": 1.0 * DEG, "workpiece.beta": -0.5 * DEG,
             "workpiece.gamma": 2.0 * DEG, "tool.x": 300 * UM, "tool.y": -450 * UM,
             "tool.z": 250 * UM, "tool.rx": 0.3 * DEG, "tool.ry": -0.2 * DEG}
    truth = ErrorModel().with_parameters(small | large)
    q, u, p = PLAN
    estimate = fit(MACHINE, observations(q, directions=u, values=read(truth, q, u, p),
                                         sigma=SIGMA, point=p), FITTED)
    assert estimate.rank == len(FITTED)
    assert_recovered(estimate, truth, FITTED)
    assert estimate.iterations <= 6  # measured 4


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
        # 1e-3 .. 1 size of the entries (as tests/test_kinematics.py)
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


def test_observations_as_objects_or_batches_agree():
    truth = ErrorModel().with_parameters({"workpiece.x": 3 * UM, "location.C.EX0C": 2 * UM})
    q, u = xy_plan()
    values = read(truth, q, u, np.zeros(3))
    batch = observations(q, directions=2 * u, values=values, sigma=SIGMA)
    np.testing.assert_array_equal(batch.directions, u)  # normalised
    singles = [Observation(q[i], value=values[i], direction=u[i], sigma=SIGMA)
               for i in range(len(values))]
    assert singles[3].frame == "tool_tip" and singles[3].point.tolist() == [0.0, 0.0, 0.0]
    names = ["workpiece.x", "location.C.EX0C"]
    a, b = fit(MACHINE, batch, names), fit(MACHINE, singles, names)
    np.testing.assert_array_equal(a.values, b.values)
    assert Observations.of([batch[0], batch]).q.shape == (21, 6)
    assert len(batch) == 20 and batch[5].value == values[5]
    with pytest.raises(ValueError, match="read-only"):
        batch.values[0] = 1.0
    assert str(Combination(("a", "b", "c"), [1.0, -0.5, 1e-5])) == "a - 0.5*b + 1e-05*c"
    assert str(Combination(("a", "b"), [-0.25, 1.0])) == "-0.25*a + b"


def test_readings_and_sigma_go_by_name_so_a_swap_cannot_pass():
    # Readings and sigma are both metres: observations(q, u, SIGMA, values), the two swapped
    # by position, passed when every reading was positive (here 2 and 3 um) and fitted
    # workpiece.x and .y at -50 nm each (the truth -3 and -2 um), std 0.6-0.9 um, residual
    # 1.5e-12, no note. No check on the numbers parts the two (readings steadier than
    # their sigma, or all equal, are real), so each takes them by name after q.
    q, u = xy_plan()
    truth = ErrorModel().with_parameters({"workpiece.x": -3 * UM, "workpiece.y": -2 * UM})
    values = read(truth, q, u, np.zeros(3))
    assert values.min() > 0.0
    names = ["workpiece.x", "workpiece.y"]
    estimate = fit(MACHINE, observations(q, directions=u, values=values, sigma=SIGMA), names)
    assert estimate.values == pytest.approx([-3 * UM, -2 * UM], abs=1e-15)
    with pytest.raises(TypeError, match="positional argument"):
        observations(q, u, SIGMA, values)
    with pytest.raises(TypeError, match="positional argument"):
        Observations(q, SIGMA, u, values)
    with pytest.raises(TypeError, match="positional argument"):
        Observation(q[0], SIGMA, u[0], values[0])
    with pytest.raises(TypeError, match="positional argument"):
        plan_quality(MACHINE, q, "tool_tip", u, names, SIGMA)


def test_bad_input_is_refused_with_the_value_named():
    q, u = xy_plan()
    values = np.zeros(len(q))
    with pytest.raises(InputError, match=r"reading 2: direction \[0.0, 0.0, 0.0\] is zero"):
        observations(q, directions=np.where(np.arange(len(q))[:, None] == 2, 0.0, u),
                     values=values, sigma=SIGMA)
    with pytest.raises(InputError, match=r"reading 0: sigma -5e-08 m; expected a finite"):
        observations(q, directions=u, values=values, sigma=-SIGMA)
    with pytest.raises(InputError, match="disagree on the number of readings"):
        observations(q, directions=u, values=values[:5], sigma=SIGMA)
    with pytest.raises(ErrorModelError, match="unknown error parameter 'location.C.EZ0C'"):
        fit(MACHINE, observations(q, directions=u, values=values, sigma=SIGMA),
            ["workpiece.x", "location.C.EZ0C"])
    with pytest.raises(InputError, match="'workpiece.x' is listed more than once"):
        fit(MACHINE, observations(q, directions=u, values=values, sigma=SIGMA),
            ["workpiece.x", "workpiece.x"])
    with pytest.raises(InputError, match=r"expected axis values of shape \(N, 6\), got \(20, 5\)"):
        fit(MACHINE, observations(q[:, :5], directions=u, values=values, sigma=SIGMA),
            ["workpiece.x"])
    with pytest.raises(InputError, match="frame 'probe_tip' is not on robonano_ui"):
        plan_quality(MACHINE, q, ["workpiece.x"], directions=u, sigma=SIGMA, frame="probe_tip")
    with pytest.raises(InputError, match="expected a sequence of parameter names"):
        fit(MACHINE, observations(q, directions=u, values=values, sigma=SIGMA), "workpiece.x")
    truth = ErrorModel().with_parameters({"workpiece.gamma": 2 * DEG})
    with pytest.raises(NotConvergedError, match="did not converge in 1 Gauss-Newton steps"):
        fit(MACHINE, observations(q, directions=u, values=read(truth, q, u, np.zeros(3)),
                                  sigma=SIGMA), ["workpiece.gamma"], max_iterations=1)
    # readings in um given as m (12 um read as 12 m): the first step takes x past 1 m
    truth = ErrorModel().with_parameters({"workpiece.x": 12 * UM})
    with pytest.raises(NotConvergedError, match=r"diverged: after 1 Gauss-Newton steps "
                                                r"workpiece.x = 12 m, beyond any error \(1\)"):
        fit(MACHINE, observations(q, directions=u, values=1e6 * read(truth, q, u, np.zeros(3)),
                                  sigma=SIGMA), ["workpiece.x"])


def test_the_documented_example_runs(capsys):
    text = (Path(__file__).parents[1] / "docs" / "identification.md").read_text()
    code = re.search(r"```python\n(.*?)```", text, re.S).group(1)
    exec(compile(code, "docs/identification.md", "exec"), {})
    out = capsys.readouterr().out
    assert "rank 6" in out and "unidentifiable: []" in out
    assert "tool.x        120.0000 um" in out


def test_through_the_lab_an_r_test_plan_identifies_the_injected_errors():
    """The honest path: a Lab holds the truth, its R-test reads two balls on the tool, the
    fit sees only the readings; then the identified values are compared with lab.reveal()."""
    from machinesim import Lab
    from machinesim.identification import from_r_test

    q = PLAN[0][::6]  # one row per pose
    truth = random_truth(np.random.default_rng(5), FITTED)
    for noise in (False, True):
        lab = Lab(MACHINE, truth, noise=noise, seed=4)
        readings = [lab.r_test(label=f"ball {k}", point=ball, resolution=0.0).read(q)
                    for k, ball in enumerate(BALLS)]
        obs = Observations.of([from_r_test(r) for r in readings])
        estimate = fit(MACHINE, obs, FITTED)
        assert estimate.rank == len(FITTED)
        injected = lab.reveal().parameters()
        if not noise:
            assert_recovered(estimate, lab.reveal(), FITTED)
            continue
        z = [(estimate.values[i] - injected[n]) / estimate.std[i]
             for i, n in enumerate(estimate.names)]
        # 20 standard normal scores: none beyond 4.5 (a chance of 1e-4 for the set)
        assert np.max(np.abs(z)) < 4.5, z


def _a0ib_r_test(injected, noise, seed=0):
    """An R-test of robonano_a0ib at B -30, 0, 30 deg and C every 90 deg, through a lab."""
    import machinesim
    from machinesim.identification import from_r_test

    q = np.array([[0.01, 0.005, 0.002, b * DEG, c * DEG]
                  for b in (-30, 0, 30) for c in range(0, 360, 90)])
    lab = machinesim.Lab("robonano_a0ib", injected, noise=noise, seed=seed)
    return lab.machine, from_r_test(lab.r_test().read(q))


def test_a_near_symmetry_and_a_missing_error_are_told_in_the_notes():
    # C's zero offset EC0C and the workpiece's rotation gamma turn the same way about the
    # C line: with the line off centre (EX0C, EY0C) they part only by the offset's lever, so
    # the fit has full rank, std in mrad and a correlation of ~1, which the notes name
    machine, obs = _a0ib_r_test({"location": {"C": {"EX0C_um": 3.0, "EY0C_um": -2.0}}}, True)
    estimate = fit(machine, obs, ["location.C.EC0C", "workpiece.gamma", "location.C.EX0C",
                                  "location.C.EY0C"])
    assert estimate.rank == 4 and estimate.std[0] > 1e-3
    assert abs(estimate.correlation[0, 1]) > 0.999
    assert any("location.C.EC0C and workpiece.gamma are correlated" in n
               for n in estimate.notes)
    assert not any("do not fit the model" in n for n in estimate.notes)
    assert not any(n.startswith("rank ") for n in estimate.notes)  # full rank
    # the plan at the nominal machine sees them as one: a combination, and a note of it
    from machinesim.identification.fit import plan_quality as quality
    nominal = quality(machine, obs.q, list(estimate.names), directions=obs.directions,
                      sigma=obs.sigma, frame=obs.frames)
    assert nominal.rank == 3
    assert sum("cannot see the combination" in n for n in nominal.notes) == 1
    # and the fit, which started there, says it sees that symmetry only through its own
    # estimate's errors (the line's offset): the same combination as the plan names
    (c,) = estimate.unseen_at_prior
    assert str(c) == str(nominal.combinations[0])
    assert set(c.names) == {"location.C.EC0C", "workpiece.gamma"}
    assert sum(n.startswith(f"at the prior the readings cannot see {c}; the fit, of rank 4")
               for n in estimate.notes) == 1
    # a tool offset the readings show and the parameters lack: the residual says so
    machine, obs = _a0ib_r_test({"location": {"C": {"EX0C_um": 3.0}},
                                 "tool": {"offset_um": [1.0, 0.5, 0.0]}}, False)
    estimate = fit(machine, obs, ["location.C.EC0C", "location.C.EX0C"])
    assert estimate.normalised_residual_rms > 10.0
    assert any("do not fit the model" in n for n in estimate.notes)


def test_readings_outside_the_travel_none_and_zero_iterations_are_refused():
    from machinesim.exceptions import AxisLimitError

    q = np.zeros((3, 5))
    q[:, 3] = [0.0, 30.0, -30.0]  # B given in degrees: 30 rad is past its travel
    with pytest.raises(AxisLimitError, match="axis B = .* outside its travel.*m and rad"):
        plan_quality(load_machine("robonano_a0ib"), q, ["tool.x"], directions=np.eye(3),
                     sigma=50e-9)
    with pytest.raises(InputError, match="at least one reading"):
        observations(np.zeros((0, 5)), directions=np.zeros((0, 3)), values=np.zeros(0), sigma=50e-9)
    machine, obs = _a0ib_r_test(None, False)
    with pytest.raises(InputError, match="max_iterations"):
        fit(machine, obs, ["tool.x"], max_iterations=0)


@pytest.mark.parametrize("key, bad", [
    ("values", "abc"), ("values", ["1e-6"] * 20), ("values", None), ("sigma", "50nm"),
    ("sigma", True), ("q", [[0.0] * 6, [0.0] * 2]), ("q", "zeros"),
    ("directions", np.eye(3)[[0] * 20] + 0j), ("point", ["0", "0", "0"]),
    ("zero_at", [[0.0] * 6, [0.0]]),
])
def test_readings_that_are_not_numbers_are_refused_naming_the_argument(key, bad):
    # Text, None, booleans, complex numbers and ragged lists had gone to numpy as they were:
    # "abc" and a ragged q raised numpy's ValueError (a traceback naming no argument), and
    # ["1e-6"] * 20 or True were read as numbers
    q, u = xy_plan()
    given = {"q": q, "directions": u, "values": np.zeros(len(q)), "sigma": SIGMA,
             "point": None, "zero_at": None, key: bad}
    name = {"point": "points"}.get(key, key)
    with pytest.raises(InputError, match=rf"Expected {name} as .*, got "):
        observations(**given)


def test_the_machine_may_be_named_as_everywhere_else_and_anything_else_is_refused():
    # fit("robonano_ui", ...) had raised AttributeError: 'str' object has no attribute
    # 'check_errors', while Lab, cut and the compensation take a shipped machine's name
    obs = observations(np.zeros((3, 6)), directions=np.eye(3), values=[1e-6, -2e-6, 0.0],
                       sigma=1e-8)
    named = fit("robonano_ui", obs, ["workpiece.x", "workpiece.y"])
    np.testing.assert_allclose(named.values, [-1e-6, 2e-6], rtol=1e-12)
    quality = plan_quality("robonano_ui", np.zeros((3, 6)), ["workpiece.x"],
                           directions=np.eye(3), sigma=1e-8)
    assert quality.std[0] == pytest.approx(1e-8, rel=1e-12)  # read once along X, sigma 10 nm
    with pytest.raises(InputError, match="Expected machine as a Machine or the name of a "
                                         "shipped one .*got 3"):
        fit(3, obs, ["workpiece.x"])


@pytest.mark.parametrize("name, hint", [
    # C on robonano_a0ib has no EZ0C (a shift of the C line along itself): its five listed
    ("location.C.EZ0C", "the location errors of its axis C are location.C.EX0C, "
                        "location.C.EY0C, location.C.EA0C, location.C.EB0C, location.C.EC0C;"),
    ("location.c.EX0C", "the location errors of its axis C are location.C.EX0C,"),
    ("EX0C", r"\(did you mean location.C.EX0C\?\)"),
    ("EZ0B", r"\(did you mean location.B.EZ0B\?\)"),
    ("workpiece.gama", r"\(did you mean workpiece.gamma\?\)"),
    ("component.X.EXX[1]", r"a component error is a parameter only when the prior holds its "
                           r"table or polynomial"),
])
def test_an_unknown_parameter_name_is_told_the_names_it_may_mean(name, hint):
    # the message had given only the patterns of every name (location.<axis>.<symbol>, ...)
    a0ib = load_machine("robonano_a0ib")
    obs = observations(np.zeros((3, 5)), directions=np.eye(3), values=np.zeros(3), sigma=SIGMA)
    with pytest.raises(ErrorModelError, match=rf"unknown error parameter '{re.escape(name)}' "
                                              rf"for robonano_a0ib; {hint}"):
        fit(a0ib, obs, ["tool.x", name])


def test_readings_in_micrometres_given_as_metres_are_named_in_the_notes():
    # An R-test of C's line offsets (0.3 and -0.2 um) read in um and handed over as m: the
    # fit, linear in the readings, returned EX0C = 0.3 m and EY0C = -0.2 m with no note (the
    # readings fit the model exactly, so no misfit), on a machine whose X travels 280 mm
    a0ib = load_machine("robonano_a0ib")
    q = np.zeros((8, 5))
    q[:, 4] = np.arange(8) * 45 * DEG
    q[:, :3] = np.random.default_rng(5).uniform(-0.01, 0.01, (8, 3))
    qs, u = np.repeat(q, 3, axis=0), np.tile(np.eye(3), (8, 1))
    names = ["location.C.EX0C", "location.C.EY0C"]
    truth = ErrorModel().with_parameters(dict(zip(names, [0.3 * UM, -0.2 * UM], strict=True)))
    readings = np.einsum("ni,ni->n", u, a0ib.tool_pose(qs, truth)[:, :3, 3]
                         - a0ib.tool_pose(qs)[:, :3, 3])
    right = fit(a0ib, observations(qs, directions=u, values=readings, sigma=SIGMA), names)
    np.testing.assert_allclose(right.values, [0.3 * UM, -0.2 * UM], rtol=1e-9)
    assert right.notes == ()
    as_um = fit(a0ib, observations(qs, directions=u, values=readings / UM, sigma=SIGMA), names)
    np.testing.assert_allclose(as_um.values, [0.3, -0.2], rtol=1e-3)  # a factor 1e6 off
    worst = int(np.argmax(np.abs(readings)))
    assert as_um.notes[0] == (
        f"reading {worst} is {readings[worst] / UM:.3g} m; location.C.EX0C = 0.3 m; "
        "location.C.EY0C = -0.2 m: beyond 0.01 m, more than a displacement sensor reads of a "
        "machine's errors. Readings and sigma are in metres: were they given in um or mm? "
        "The values are then off by that factor")
    # a sigma of 50 nm given in um (0.05) is named before anything is measured
    quality = plan_quality(a0ib, qs, names, directions=u, sigma=0.05)
    assert quality.notes == ("sigma 0 is 0.05 m: beyond 0.01 m, more than a displacement "
                             "sensor reads of a machine's errors. Readings and sigma are in "
                             "metres: were they given in um or mm? The values are then off "
                             "by that factor",)
    assert plan_quality(a0ib, qs, names, directions=u, sigma=SIGMA).notes == ()


@pytest.mark.parametrize("sigma", [1e-30, 1e-200, 5e-324, 50.0, 1e200, 1e308])
def test_a_sigma_no_sensor_has_is_refused_before_its_weight_leaves_float64(sigma):
    # 1e-200, 5e-324 and 1e200 and beyond had ended in numpy's LinAlgError "SVD did not
    # converge" (the weights 1/sigma, squared, overflowed or underflowed), 1e-200 in fit as
    # "location.C.EX0C: expected a finite number, got nan"; 50 (50 nm given as metres) had
    # passed
    q, u = xy_plan()
    with pytest.raises(InputError, match=rf"reading 0: sigma {re.escape(repr(sigma))} m; "
                                         r"expected a finite "
                                         r"standard uncertainty from 1e-18 m to 1 m"):
        fit(MACHINE, observations(q, directions=u, values=np.zeros(len(q)), sigma=sigma),
            ["workpiece.x"])
    with pytest.raises(InputError, match=r"from 1e-18 m to 1 m"):
        plan_quality(MACHINE, q, ["workpiece.x"], directions=u, sigma=sigma)


@pytest.mark.parametrize("scale", [1e300, 1e-320])
def test_a_direction_of_any_length_is_normalised(scale):
    # Directions are normalised; one of length 1e300 had a norm of inf (its square overflows)
    # and came out zero, so every reading was ignored and workpiece.x stayed 0 with a note
    # that nothing saw it; one of 1e-320 was refused as zero
    q, u = xy_plan()
    truth = ErrorModel().with_parameters({"workpiece.x": 3 * UM, "workpiece.y": -2 * UM})
    readings = read(truth, q, u, np.zeros(3))
    estimate = fit(MACHINE, observations(q, directions=u * scale, values=readings, sigma=SIGMA),
                   ["workpiece.x", "workpiece.y"])
    np.testing.assert_allclose(estimate.values, [3 * UM, -2 * UM], rtol=1e-9)


def test_progress_is_told_each_gauss_newton_step():
    # A fit of 100,000 readings took ~40 s with nothing said; progress tells each step.
    # Readings 1 and -2 um along X and Y of workpiece.x, .y (sigma 10 nm): before the first
    # step (reading - model) / sigma is (100, -200, 0), RMS sqrt(50000 / 3) = 129.1; the
    # step is the whole answer, workpiece.y -(-2 um)
    told = []
    obs = observations(np.zeros((3, 6)), directions=np.eye(3), values=[1e-6, -2e-6, 0.0],
                       sigma=1e-8)
    estimate = fit(MACHINE, obs, ["workpiece.x", "workpiece.y"], progress=told.append)
    assert len(told) == estimate.iterations == 2
    assert told[0] == ("Gauss-Newton step 1 on 3 readings: RMS of (reading - model) / sigma "
                       "before it 129.1, largest step workpiece.y 2e-06 m (2e+06 x the "
                       "stopping rule)")
    assert re.fullmatch(r"Gauss-Newton step 2 on 3 readings: RMS of \(reading - model\) / "
                        r"sigma before it (0|\S+e-\d\d), .*", told[1])


def test_an_r_test_reading_given_where_observations_go_is_told_the_way_in():
    # fit(machine, lab.r_test().read(q), ...) had raised TypeError "'RTestReading' object is
    # not iterable", and from_r_test of anything else AttributeError "... has no attribute
    # 'q'": tracebacks
    from machinesim import Lab
    from machinesim.identification import from_r_test

    lab = Lab("robonano_a0ib", noise=False)
    reading = lab.r_test().read(np.zeros((2, 5)))
    for given in (reading, [reading]):
        with pytest.raises(InputError, match=r"key 'observations': expected Observation or "
                                             r"Observations.*got an RTestReading: an R-test's "
                                             r"readings go in as from_r_test\(reading\)"):
            fit(lab.machine, given, ["location.C.EX0C"])
    with pytest.raises(InputError, match="expected Observation or Observations, or a sequence "
                                         "of them, got int"):
        fit(lab.machine, 3, ["location.C.EX0C"])
    with pytest.raises(InputError, match=r"key 'reading': expected the RTestReading that "
                                         r"lab.r_test\(\).read\(q\) returns, got ndarray"):
        from_r_test(np.zeros((2, 3)))
    assert len(from_r_test(reading)) == 6  # the way in: 2 poses x X, Y, Z


def test_estimate_and_plan_quality_say_what_they_are_with_units():
    """Their repr had been the dataclass dump: every std, the k x k covariance and
    correlation as bare SI arrays (some 4,000 characters for 6 parameters), the values
    themselves after them, no unit anywhere. Now the counts, then each value and std with
    its unit. Hand values: X, Y, Z read at 8 poses, sigma 50 nm: std 50 nm / sqrt(8) for
    the X offsets, and 2 x 50 nm / sqrt(8) for tool.z + workpiece.z told apart by B."""
    machine = load_machine("robonano_ui")
    deg = np.pi / 180
    abc = [(a, b, c) for a in (0, 180) for b in (-30, 30) for c in (0, 120)]
    q = np.repeat([[0.01 * i, 0.0, 0.02, a * deg, b * deg, c * deg]
                   for i, (a, b, c) in enumerate(abc)], 3, axis=0)
    u = np.tile(np.eye(3), (len(abc), 1))
    names = ["tool.x", "workpiece.x", "workpiece.gamma"]
    quality = plan_quality(machine, q, names, directions=u, sigma=50e-9)
    assert repr(quality).startswith("PlanQuality(3 parameters, 24 readings, rank 3, ")
    assert f"tool.x std {50e-9 / np.sqrt(8):.3g} m" in repr(quality)
    assert "workpiece.gamma std " in repr(quality) and repr(quality).endswith(" rad)")
    truth = ErrorModel().with_parameters({"tool.x": 120e-6, "workpiece.x": 15e-6,
                                          "workpiece.gamma": 1e-3})
    readings = np.einsum("ni,ni->n", u, machine.tool_pose(q, truth)[:, :3, 3]
                         - machine.tool_pose(q)[:, :3, 3])
    estimate = fit(machine, observations(q, directions=u, values=readings, sigma=50e-9),
                   names)
    text = repr(estimate)
    assert text.startswith("Estimate(3 parameters, 24 readings, rank 3, ")
    assert "tool.x = 0.00012 m +- " in text and "workpiece.gamma = 0.001 rad +- " in text
    assert "covariance" not in text and len(text) < 600
    many = plan_quality(machine, q, list(machine.parameter_names())[:12], directions=u,
                        sigma=50e-9)
    assert repr(many).endswith("... 4 more)") and " unidentifiable" in repr(many)


def test_an_estimate_names_a_polynomial_coefficient_s_unit():
    """A polynomial's coefficient k is m per m^k (ErrorModel.parameter_unit): the repr
    gives it so, where the plan, without a model, says SI."""
    machine = load_machine("grooving_4axis")
    prior = ErrorModel.from_dict({"component": {"X": {"EYX_poly_um_mm": [0.0, 0.0]}}})
    q = np.zeros((5, 4))
    q[:, 0] = np.linspace(-0.1, 0.1, 5)
    u = np.tile([0.0, 1.0, 0.0], (5, 1))
    names = ["component.X.EYX[0]", "component.X.EYX[1]"]
    estimate = fit(machine, observations(q, directions=u, values=1e-6 * q[:, 0] + 2e-7,
                                         sigma=1e-8), names, prior=prior)
    assert np.allclose(estimate.values, [2e-7, 1e-6], rtol=1e-6, atol=1e-15)
    assert "component.X.EYX[1] = 1e-06 m/m +- " in repr(estimate)
    assert "component.X.EYX[0] std " in repr(plan_quality(machine, q, names, directions=u,
                                                         sigma=1e-8, prior=prior))
