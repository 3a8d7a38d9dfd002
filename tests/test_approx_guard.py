"""The suite's guard on pytest.approx (tests/conftest.py): a value below APPROX_SMALL must
give its absolute tolerance, since pytest's default abs of 1e-12 would decide instead."""

import pytest


def test_a_small_expected_value_without_abs_is_refused_and_with_it_compared_by_rel():
    with pytest.raises(AssertionError, match="without abs"):
        assert 4e-13 == pytest.approx(5e-13, rel=1e-9)  # passed before: |4e-13 - 5e-13| < 1e-12
    assert 4e-13 != pytest.approx(5e-13, rel=1e-9, abs=0.0)
    assert 5e-13 * (1 + 1e-10) == pytest.approx(5e-13, rel=1e-9, abs=0.0)
    assert 1.0 == pytest.approx(1.0 + 1e-9)  # values of everyday size as pytest has them
