"""ISO 230-2 positioning and ISO 230-6 diagonal squareness (machinesim.metrology.iso230)."""

import math

import numpy as np
import pytest

import machinesim
from machinesim.exceptions import InputError, MachineSimError
from machinesim.metrology.iso230 import (
    evaluate_positioning,
    iso230_2_targets,
    positioning_test,
    squareness_from_diagonals,
)

UM = 1e-6
ROOT2 = math.sqrt(2.0)


def hand_case():
    """Three targets, two runs: worked by hand in the comments of the tests below."""
    targets = [0.0, 0.1, 0.2]
    up = np.array([[1.0, 3.0, -2.0], [3.0, 5.0, 0.0]]) * UM      # means 2, 4, -1; s = sqrt 2
    down = np.array([[0.0, 2.0, -3.0], [0.0, 2.0, -3.0]]) * UM   # means 0, 2, -3; s = 0
    return evaluate_positioning(targets, up, down)


def test_means_reversal_and_uncertainty_by_hand():
    ev = hand_case()
    np.testing.assert_allclose(ev.mean_up / UM, [2.0, 4.0, -1.0], atol=1e-12)
    np.testing.assert_allclose(ev.mean_down / UM, [0.0, 2.0, -3.0], atol=1e-12)
    np.testing.assert_allclose(ev.mean / UM, [1.0, 3.0, -2.0], atol=1e-12)
    np.testing.assert_allclose(ev.s_up / UM, [ROOT2] * 3, rtol=1e-12)   # ddof = 1
    np.testing.assert_allclose(ev.reversal / UM, [2.0, 2.0, 2.0], atol=1e-12)
    assert ev.B / UM == pytest.approx(2.0) and ev.B_mean / UM == pytest.approx(2.0)


def test_systematic_deviation_takes_its_minimum_over_both_directions():
    ev = hand_case()
    assert ev.E_up / UM == pytest.approx(5.0)            # 4 - (-1)
    assert ev.E_down / UM == pytest.approx(5.0)          # 2 - (-3)
    # Max 4 (up, 0.1 m), min -3 (down, 0.2 m): 7, not 5 as the up direction alone gives.
    assert ev.E / UM == pytest.approx(7.0)
    assert ev.M / UM == pytest.approx(5.0)               # 3 - (-2)


def test_bidirectional_repeatability_keeps_the_unidirectional_when_larger():
    ev = hand_case()
    assert ev.R_up / UM == pytest.approx(4.0 * ROOT2)
    assert ev.R_down == pytest.approx(0.0)
    # 2 s_up + 2 s_down + |B| = 2 sqrt 2 + 2 = 4.83 < R_up = 5.66: R is R_up.
    assert ev.R / UM == pytest.approx(4.0 * ROOT2)


def test_bidirectional_repeatability_uses_the_magnitude_of_a_negative_reversal():
    up = np.zeros((2, 3))
    down = np.array([[2.0] * 3, [4.0] * 3]) * UM          # mean 3, s = sqrt 2, B = -3
    ev = evaluate_positioning([0.0, 0.1, 0.2], up, down)
    assert ev.reversal / UM == pytest.approx([-3.0] * 3)
    assert ev.R / UM == pytest.approx(2.0 * ROOT2 + 3.0)  # > R_down = 4 sqrt 2
    assert ev.B / UM == pytest.approx(3.0) and ev.B_mean / UM == pytest.approx(-3.0)


def test_accuracy_by_hand():
    ev = hand_case()
    assert ev.A_up / UM == pytest.approx(5.0 + 4.0 * ROOT2)   # (4 + 2 s) - (-1 - 2 s)
    assert ev.A_down / UM == pytest.approx(5.0)
    # max(4 + 2 sqrt 2, 2) - min(-1 - 2 sqrt 2, -3) = 5 + 4 sqrt 2
    assert ev.A / UM == pytest.approx(5.0 + 4.0 * ROOT2)
    assert ev.figures_um()["A"] == pytest.approx(5.0 + 4.0 * ROOT2)


def test_unidirectional_test_has_no_reversal():
    up = np.array([[1.0, -1.0], [3.0, 1.0]]) * UM
    ev = evaluate_positioning([0.0, 0.3], up)
    assert ev.B == 0.0 and ev.E == pytest.approx(ev.E_up) == pytest.approx(2.0 * UM)
    assert ev.R == pytest.approx(4.0 * ROOT2 * UM)


def test_targets_follow_the_standard():
    # 400 mm: five targets per metre would give 2; five in all is the floor.
    uniform = iso230_2_targets(-0.2, 0.2)
    np.testing.assert_allclose(uniform, [-0.2, -0.1, 0.0, 0.1, 0.2], atol=1e-15)
    assert iso230_2_targets(0.0, 2.0).size == 11
    drawn = iso230_2_targets(-0.2, 0.2, count=21, rng=3)
    assert drawn[0] == -0.2 and drawn[-1] == 0.2
    step = 0.4 / 20
    offsets = drawn - (-0.2 + step * np.arange(21))
    assert np.all(np.abs(offsets) <= step / 4 + 1e-15) and np.all(np.diff(drawn) > 0)
    assert np.unique(np.round(offsets[1:-1] / step, 12)).size == 19   # a different r_i each


@pytest.mark.parametrize("count", [5.9, "7", True, 7.0])
def test_a_target_count_that_is_no_whole_number_is_refused(count):
    # count=5.9 once gave 5 targets, count="7" seven
    with pytest.raises(InputError, match=f"count as a whole number of targets, got {count!r}"):
        iso230_2_targets(-0.2, 0.2, count=count)
    assert iso230_2_targets(-0.2, 0.2, count=np.int64(7)).size == 7


@pytest.mark.parametrize("rng", [True, -1, "7", 2.5])
def test_a_target_seed_that_is_no_seed_is_refused_by_name(rng):
    # rng=True drew the offsets of seed 1 without a word; -1, "7" and 2.5 ended in numpy's
    # ValueError / TypeError ("SeedSequence expects int or sequence of ints")
    with pytest.raises(InputError, match="rng as a numpy Generator, a non-negative int"):
        iso230_2_targets(-0.2, 0.2, rng=rng)
    # a seed, a numpy integer and a Generator draw the same offsets as before
    drawn = iso230_2_targets(-0.2, 0.2, count=9, rng=3)
    step = 0.4 / 8
    expected = -0.2 + step * np.arange(9)
    expected[1:-1] += np.random.default_rng(3).uniform(-0.25, 0.25, 7) * step
    np.testing.assert_array_equal(drawn, expected)
    np.testing.assert_array_equal(iso230_2_targets(-0.2, 0.2, count=9, rng=np.int64(3)), drawn)
    np.testing.assert_array_equal(
        iso230_2_targets(-0.2, 0.2, count=9, rng=np.random.default_rng(3)), drawn)


@pytest.mark.parametrize("call", [
    lambda: iso230_2_targets(0.0, 0.4, count=3),
    lambda: iso230_2_targets(0.4, 0.0),
    lambda: evaluate_positioning([0.0, 0.0], np.zeros((2, 2))),
    lambda: evaluate_positioning([0.0, 0.1], np.zeros((1, 2))),
    lambda: evaluate_positioning([0.0, 0.1], np.zeros((2, 3))),
    lambda: evaluate_positioning([0.0, 0.1], [[0.0, float("nan")], [0.0, 0.0]]),
    lambda: squareness_from_diagonals(0.0, 1e-6, 0.0, 0.4),
])
def test_bad_input_is_refused_clearly(call):
    with pytest.raises(MachineSimError):
        call()


def test_positioning_test_through_the_lab_recovers_the_injected_positioning():
    errors = {"component": {"X": {"position_mm": [-250.0, 0.0, 250.0],
                                  "EXX_um": [-4.0, 1.0, 5.0]}}}
    lab = machinesim.Lab("grooving_4axis", errors, noise=False)
    targets = iso230_2_targets(-0.2, 0.2, count=9)
    ev = positioning_test(lab.laser_interferometer(), "X", targets)
    exx = lab.reveal().component["X"]["EXX"].evaluate(targets)
    # Piecewise-linear table: deviations zeroed at the first target.
    expected = np.interp(targets, [-0.25, 0.0, 0.25], [-4.0, 1.0, 5.0]) * UM
    np.testing.assert_allclose(ev.mean_up, expected - expected[0], atol=1e-9)
    np.testing.assert_allclose(ev.mean_down, ev.mean_up, atol=1e-12)
    assert ev.E == pytest.approx(np.ptp(expected), abs=1e-9)
    assert ev.R == pytest.approx(0.0, abs=2e-9) and ev.B == pytest.approx(0.0, abs=2e-9)
    np.testing.assert_allclose(exx, expected, atol=1e-15)   # the table is linear between


def test_noise_gives_the_repeatability_of_its_sigma():
    lab = machinesim.Lab("grooving_4axis", seed=4)
    li = lab.laser_interferometer(sigma=20e-9, resolution=0.0)
    ev = positioning_test(li, "Y", iso230_2_targets(-0.2, 0.2, count=11), runs=5)
    # The interferometer adds its noise once to each displayed (zeroed) displacement;
    # 110 readings of s (4 degrees of freedom each): the pooled s within 20 % of sigma.
    s = np.concatenate([ev.s_up, ev.s_down])
    assert np.sqrt(np.mean(s ** 2)) == pytest.approx(20e-9, rel=0.2)
    assert ev.R >= max(ev.R_up, ev.R_down) > 0.0


def test_an_air_compensation_miss_reads_every_travel_on_its_scale():
    # (1 + s) times each displacement along the beam: s times the travel from the
    # reference on a positioning test and along a diagonal, nothing across the beam
    lab = machinesim.Lab("grooving_4axis", noise=False)
    s = 0.7e-6
    exact, off = (lab.laser_interferometer(resolution=0.0, scale=k, label=f"s{k}")
                  for k in (0.0, s))
    x = np.linspace(-0.2, 0.2, 5)
    np.testing.assert_allclose(off.positioning("Y", x, reference=0.0).deviation,
                               exact.positioning("Y", x, reference=0.0).deviation + s * x,
                               rtol=0, atol=1e-16)
    d = np.array([0.1, math.hypot(0.4, 0.4)])
    np.testing.assert_allclose(off.diagonal(d, [-0.2, -0.2], [0.2, 0.2]).deviation,
                               exact.diagonal(d, [-0.2, -0.2], [0.2, 0.2]).deviation + s * d,
                               rtol=0, atol=1e-16)
    np.testing.assert_array_equal(off.straightness("X", x, "Y").deviation,
                                  exact.straightness("X", x, "Y").deviation)
    with pytest.raises(InputError, match="scale error below 1e-3"):
        lab.laser_interferometer(scale=0.01)


def test_two_diagonals_give_the_squareness_free_of_scale_errors():
    errors = {"location": {"Y": {"EC0Y_urad": 20.0}},
              "component": {"X": {"position_mm": [-250.0, 250.0], "EXX_um": [-5.0, 5.0]},
                            "Y": {"position_mm": [-250.0, 250.0], "EYY_um": [-3.0, 3.0]}}}
    lab = machinesim.Lab("grooving_4axis", errors, noise=False)
    li = lab.laser_interferometer(resolution=0.0)
    d = math.hypot(0.4, 0.4)
    same = li.diagonal([d], [-0.2, -0.2], [0.2, 0.2]).deviation[0]
    opposite = li.diagonal([d], [-0.2, 0.2], [0.2, -0.2]).deviation[0]
    # First order: scale 2e-5 (X) and 1.2e-5 (Y) add 0.4**2 (ex + ey) / d to both.
    assert same == pytest.approx((0.16 * (2e-5 + 1.2e-5) - 0.16 * 20e-6) / d, rel=1e-3)
    e = squareness_from_diagonals(same, opposite, 0.4, 0.4)
    assert e == pytest.approx(20e-6, rel=1e-4)
