"""Readings of sensors set to zero at a pose (an R-test nest zeroed at the start pose): the
fit models each as its displacement less the displacement where it was zeroed, so constant
offsets drop out and what changes with the axes is still identified."""

import numpy as np
import pytest

import machinesim
from machinesim.exceptions import InputError
from machinesim.identification import Observations, fit, observations, plan_quality

DEG = np.pi / 180.0
MACHINE = machinesim.load_machine("robonano_a0ib")
# an R-test plan: B -30, 0, 30 deg and C every 90 deg, the ball on the tool tip
Q = np.array([[0.01, 0.005, 0.002, b * DEG, c * DEG]
              for b in (-30, 0, 30) for c in range(0, 360, 90)])
Q_ALL = np.repeat(Q, 3, axis=0)
U = np.tile(np.eye(3), (len(Q), 1))
SIGMA = 50e-9


def _displacement(errors, q):
    """Ball centre (tool tip) actual minus nominal in the workpiece frame, m (second method:
    the machine's poses, not the fit's model)."""
    actual = MACHINE.frame_pose("tool_tip", q, errors)[:, :3, 3]
    nominal = MACHINE.frame_pose("tool_tip", q)[:, :3, 3]
    return actual - nominal


def test_a_zeroed_reading_is_the_change_of_the_displacement_from_the_zero_pose():
    truth = machinesim.ErrorModel().with_parameters({
        "location.C.EX0C": 3e-6, "location.C.EY0C": -2e-6, "workpiece.x": 5e-6,
        "tool.z": 4e-6})
    d = _displacement(truth, Q)
    readings = (d - d[0]).reshape(-1)
    obs = observations(Q_ALL, directions=U, values=readings, sigma=SIGMA, zero_at=Q[0])
    names = ["location.C.EX0C", "location.C.EY0C"]
    # the model at the truth reads the readings (both fitted and held parameters)
    estimate = fit(MACHINE, obs, names, prior={"workpiece.x": 5e-6, "tool.z": 4e-6})
    assert estimate.values == pytest.approx([3e-6, -2e-6], abs=1e-12)
    # a constant offset is not seen: without it in the prior the fit is the same
    again = fit(MACHINE, obs, names, prior={"tool.z": 4e-6})
    assert again.values == pytest.approx([3e-6, -2e-6], abs=1e-12)
    # read as absolute displacements, the same numbers would be misread
    absolute = fit(MACHINE, observations(Q_ALL, directions=U, values=readings, sigma=SIGMA), names)
    assert abs(absolute.values[0] - 3e-6) > 1e-7


def test_zeroed_readings_cannot_see_the_workpiece_offset_that_absolute_ones_do():
    names = ["workpiece.x", "workpiece.y", "workpiece.z", "location.C.EX0C"]
    absolute = plan_quality(MACHINE, Q_ALL, names, directions=U, sigma=SIGMA)
    assert absolute.rank == 4
    zeroed = plan_quality(MACHINE, Q_ALL, names, directions=U, sigma=SIGMA, zero_at=Q[0])
    # the workpiece's offset moves every reading alike: it drops out of each difference
    assert zeroed.rank == 1
    assert {"workpiece.x", "workpiece.y", "workpiece.z"} <= set(
        str(x) for x in zeroed.unidentifiable)
    # C's location offset turns with C: the differences still carry it
    assert np.isfinite(zeroed.std[3])


def test_zero_at_is_checked_and_kept_through_batches():
    obs = Observations(Q_ALL[:3], values=[0.0, 0.0, 0.0], directions=np.eye(3), sigma=SIGMA,
                       zero_at=Q[0])
    assert obs.zeroed.all() and np.array_equal(obs.zero_at[1], Q[0])
    mixed = Observations.of([obs, observations(Q[1], directions=np.eye(3)[0], values=0.0,
                                               sigma=SIGMA)])
    assert mixed.zeroed.tolist() == [True, True, True, False]
    assert mixed[0].zero_at.tolist() == Q[0].tolist() and mixed[3].zero_at is None
    with pytest.raises(InputError, match="zero_at of shape"):
        Observations(Q_ALL[:3], values=0.0, directions=np.eye(3), sigma=SIGMA, zero_at=np.zeros(4))
    with pytest.raises(InputError, match="or all NaN for a reading not zeroed"):
        Observations(Q_ALL[:1], values=0.0, directions=np.eye(3)[0], sigma=SIGMA,
                     zero_at=[0.0, np.nan, 0.0, 0.0, 0.0])


def test_an_r_test_zeroed_at_its_first_pose_identifies_c_without_the_constant_offsets():
    from machinesim.identification import from_r_test

    # C's location offsets, and the nest's placement on the table (the lab's workpiece
    # setting), which moves every reading alike: not known, and not needed when zeroed
    injected = {"location": {"C": {"EX0C_um": 3.0, "EY0C_um": -2.0}},
                "workpiece": {"delta_um": [4.0, -6.0, 2.5]}}
    lab = machinesim.Lab("robonano_a0ib", injected, noise=False)
    zeroed = lab.r_test(zero="first", resolution=0.0).read(Q)
    nominal = lab.r_test(resolution=0.0).read(Q)
    assert zeroed.displacement[0].tolist() == [0.0, 0.0, 0.0]
    np.testing.assert_allclose(zeroed.displacement, nominal.displacement
                               - nominal.displacement[0], rtol=0, atol=1e-18)
    assert np.array_equal(zeroed.zero_at, Q[0]) and nominal.zero_at is None
    names = ["location.C.EX0C", "location.C.EY0C"]
    found = fit(lab.machine, from_r_test(zeroed), names)
    assert found.values == pytest.approx([3e-6, -2e-6], abs=1e-12)
    # read against the nominal place, the nest's placement is in every reading and the
    # same two parameters cannot explain it
    misread = fit(lab.machine, from_r_test(nominal), names)
    assert misread.normalised_residual_rms > 10.0
    with pytest.raises(InputError, match="zero as one of nominal, first"):
        lab.r_test(zero="start")


def test_an_r_test_reading_says_what_it_read_with_units():
    """Its repr had been the dataclass dump of bare SI arrays (q, displacement, point) and
    sigma=5.0000833326389e-08, no unit. Now the poses, the ball, the zero, each direction's
    range in um and sigma in m. Hand values: a tool offset of 1 um along X reads 1 um in X
    at q = 0 (the tool frame is the workpiece's there); zeroed on that pose, 0, with sqrt(2)
    times the stated sigma."""
    lab = machinesim.Lab("robonano_a0ib", {"tool": {"offset_um": [1.0, 0.0, 0.0]}},
                         noise=False)
    nominal = lab.r_test(label="nominal").read(np.zeros((2, 5)))
    assert repr(nominal) == (
        "RTestReading(2 poses of 5 axes, ball at (0, 0, 0) mm in tool_tip, against the "
        f"nominal place: displacement X 1 .. 1, Y 0 .. 0, Z 0 .. 0 um, sigma "
        f"{nominal.sigma:.3g} m)")
    zeroed = lab.r_test(label="zeroed", zero="first").read(np.zeros((2, 5)))
    assert repr(zeroed).endswith(
        f"zeroed at q[0]: displacement X 0 .. 0, Y 0 .. 0, Z 0 .. 0 um, sigma "
        f"{nominal.sigma * np.sqrt(2):.3g} m)")
