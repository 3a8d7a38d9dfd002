"""machinesim.campaign.statistics against values by hand, known distributions and scipy.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from machinesim.campaign.statistics import coverage_interval, ranks, spearman, z_scores, z_summary


def test_coverage_interval_on_sorted_integers_by_hand():
    # M = 100, p = 0.95: q = 95; symmetric r = (M - q + 1) / 2 = 3 -> [y_3, y_98] (JCGM 101
    # 7.7.1); shortest: every window of q + 1 values is 95 wide, the first wins -> [y_1, y_96]
    y = np.arange(1.0, 101.0)
    rng = np.random.default_rng(0)
    assert coverage_interval(rng.permutation(y), kind="symmetric") == (3.0, 98.0)
    assert coverage_interval(y, kind="shortest") == (1.0, 96.0)
    assert all(math.isnan(v) for v in coverage_interval([1.0, 2.0]))


def test_coverage_interval_on_known_distributions():
    rng = np.random.default_rng(7)
    z = rng.standard_normal(200_000)
    low, high = coverage_interval(z, kind="symmetric")
    assert (low, high) == pytest.approx((-1.959964, 1.959964), abs=0.02)
    # exponential(1): the shortest 95 % interval is [0, ln 20]
    e = rng.exponential(size=200_000)
    low, high = coverage_interval(e, kind="shortest")
    assert low == pytest.approx(0.0, abs=1e-3) and high == pytest.approx(math.log(20), abs=0.03)
    low, high = coverage_interval(e, kind="symmetric")        # [-ln 0.975, -ln 0.025]
    assert (low, high) == pytest.approx((-math.log(0.975), -math.log(0.025)), abs=0.03)


def test_z_scores_of_honest_and_dishonest_uncertainty():
    rng = np.random.default_rng(3)
    truth = rng.uniform(-1, 1, 50_000)
    std = rng.uniform(0.5, 2.0, truth.size)
    found = truth + std * rng.standard_normal(truth.size)
    honest = z_summary(z_scores(found, truth, std))
    assert honest["mean"] == pytest.approx(0.0, abs=0.02)
    assert honest["std"] == pytest.approx(1.0, abs=0.02)
    assert honest["within_1_96_ratio"] == pytest.approx(0.95, abs=0.005)
    optimistic = z_summary(z_scores(found, truth, std / 2))
    assert optimistic["std"] == pytest.approx(2.0, abs=0.04)
    assert math.isnan(z_scores([1.0], [0.0], [math.nan])[0])


def test_spearman_against_scipy_and_monotonic_maps():
    rng = np.random.default_rng(5)
    x = rng.integers(0, 6, 300).astype(float)           # many ties
    y = x + rng.normal(0, 2, x.size)
    assert spearman(x, y) == pytest.approx(stats.spearmanr(x, y).statistic, abs=1e-12)
    assert spearman(x[:50], np.exp(x[:50] + 0.01 * np.arange(50))) == pytest.approx(
        stats.spearmanr(x[:50], np.exp(x[:50] + 0.01 * np.arange(50))).statistic)
    u = rng.uniform(size=40)
    assert spearman(u, u**3) == pytest.approx(1.0) and spearman(u, -u) == pytest.approx(-1.0)
    assert list(ranks([3.0, 1.0, 3.0, 2.0])) == [3.5, 1.0, 3.5, 2.0]
