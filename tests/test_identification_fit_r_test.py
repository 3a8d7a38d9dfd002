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

import numpy as np
import pytest
from identification_fit_helpers import (
    DEG,
    MACHINE,
    SIGMA,
    UM,
    URAD,
    assert_recovered,
    random_truth,
    read,
    xy_plan,
)

from machinesim.errors import ErrorModel
from machinesim.identification.fit import Observations, fit, observations, plan_quality
from machinesim.sampling import random_axis_values

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
