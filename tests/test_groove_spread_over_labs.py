"""Paper 002's crossing grooves after compensation: the spread of their four end depths over
labs, from the stated uncertainty of the identified tilts, against a closed form and against
drawn labs."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.special import erfinv

from machinesim.exceptions import InputError
from machinesim.identification.workpiece_setting_uncertainty import (
    tilt_spread_quantile,
    tilt_spread_quantiles,
)

SPAN = 1.9e-3


def test_equal_tilt_stds_give_the_closed_form_median():
    """With both tilts of std s, P(spread <= t) = erf(t / (L s sqrt 2))^2, so the median is
    L s sqrt(2) erfinv(sqrt(1/2)) (about 1.05 L s)."""
    s = 0.126e-3
    median = tilt_spread_quantiles(s, s, SPAN, [0.5])[0]
    assert median == pytest.approx(SPAN * s * math.sqrt(2.0) * erfinv(math.sqrt(0.5)),
                                   rel=1e-10)


def test_quantiles_are_those_of_drawn_labs():
    """A second method: 400 000 labs, each tilt drawn normal with its std, the four ends at
    +-L/2 along x and y read as heights db x - da y; the spread's quantiles agree to 1 %."""
    sa, sb = 0.129e-3, 0.08e-3
    rng = np.random.default_rng(7)
    da, db = rng.normal(0.0, sa, 400_000), rng.normal(0.0, sb, 400_000)
    ends = np.array([[SPAN / 2, 0.0], [0.0, SPAN / 2], [-SPAN / 2, 0.0], [0.0, -SPAN / 2]])
    heights = db[:, None] * ends[None, :, 0] - da[:, None] * ends[None, :, 1]
    drawn = np.percentile(np.ptp(heights, axis=1), [10, 50, 90])
    np.testing.assert_allclose(tilt_spread_quantiles(sa, sb, SPAN, [0.1, 0.5, 0.9]), drawn,
                               rtol=0.01)


def test_a_spread_is_found_back_at_its_quantile():
    q = [0.05, 0.25, 0.5, 0.75, 0.99]
    spreads = tilt_spread_quantiles(0.1e-3, 0.2e-3, SPAN, q)
    assert np.all(np.diff(spreads) > 0)
    got = [tilt_spread_quantile(t, 0.1e-3, 0.2e-3, SPAN) for t in spreads]
    np.testing.assert_allclose(got, q, rtol=1e-9)
    assert tilt_spread_quantile(0.0, 0.1e-3, 0.2e-3, SPAN) == 0.0


@pytest.mark.parametrize("args", [(0.0, 0.0, SPAN), (math.nan, 1e-4, SPAN), (1e-4, 1e-4, 0.0),
                                  (-1e-4, 1e-4, SPAN)])
def test_bad_stds_or_span_are_refused(args):
    with pytest.raises(InputError, match="tilt stds"):
        tilt_spread_quantiles(*args, [0.5])


def test_quantiles_outside_zero_one_are_refused():
    with pytest.raises(InputError, match="quantiles in"):
        tilt_spread_quantiles(1e-4, 1e-4, SPAN, [0.5, 1.0])


def test_uncorrelated_the_integral_is_the_closed_form():
    """The correlated route (one integral over da) at a correlation of 1e-9 against the erf
    product of independent tilts, at five spreads."""
    for t in (5e-8, 1.5e-7, 2.5e-7, 4e-7, 8e-7):
        closed = tilt_spread_quantile(t, 0.129e-3, 0.08e-3, SPAN)
        assert tilt_spread_quantile(t, 0.129e-3, 0.08e-3, SPAN, correlation=1e-9) == \
            pytest.approx(closed, rel=1e-9, abs=1e-12)


def test_fully_correlated_equal_tilts_are_one_variable():
    """At a correlation of +-1, db = +-da: the spread is L |da|, whose median is
    L s sqrt(2) erfinv(1/2); at 1 - 1e-12 the integral reaches it too."""
    s = 0.126e-3
    expected = SPAN * s * math.sqrt(2.0) * erfinv(0.5)
    for rho in (1.0, -1.0, 1.0 - 1e-12):
        assert tilt_spread_quantiles(s, s, SPAN, [0.5], correlation=rho)[0] == \
            pytest.approx(expected, rel=1e-6), rho


@pytest.mark.parametrize("rho", [0.5, -0.5, 0.9])
def test_correlated_quantiles_are_those_of_drawn_labs(rho):
    """A second method, as above, with the two tilts drawn correlated; a correlation of
    either sign gives the same spread (db -> -db mirrors the four ends)."""
    sa, sb = 0.129e-3, 0.123e-3
    rng = np.random.default_rng(11)
    cov = [[sa * sa, rho * sa * sb], [rho * sa * sb, sb * sb]]
    da, db = rng.multivariate_normal([0.0, 0.0], cov, 400_000).T
    ends = np.array([[SPAN / 2, 0.0], [0.0, SPAN / 2], [-SPAN / 2, 0.0], [0.0, -SPAN / 2]])
    heights = db[:, None] * ends[None, :, 0] - da[:, None] * ends[None, :, 1]
    drawn = np.percentile(np.ptp(heights, axis=1), [10, 50, 90])
    got = tilt_spread_quantiles(sa, sb, SPAN, [0.1, 0.5, 0.9], correlation=rho)
    np.testing.assert_allclose(got, drawn, rtol=0.01)
    independent = tilt_spread_quantiles(sa, sb, SPAN, [0.5])[0]
    assert got[1] < independent  # correlated tilts are more often small together


@pytest.mark.parametrize("rho", [1.5, -1.01, math.nan, math.inf])
def test_a_correlation_outside_minus_one_one_is_refused(rho):
    with pytest.raises(InputError, match="correlation in -1 .. 1"):
        tilt_spread_quantiles(1e-4, 1e-4, SPAN, [0.5], correlation=rho)
