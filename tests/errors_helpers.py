"""What the error model's test files (tests/test_errors_model.py, _file.py) share (not
collected: no test_ prefix): the brief's example as a dict and a comparison in SI."""

from __future__ import annotations

from numpy.testing import assert_allclose

from machinesim.errors import ErrorModel


def example_dict() -> dict:
    """The brief's example, as the dict tomllib gives for models/errors/example.toml."""
    return {
        "tool": {"offset_um": [0.0, -178.0, 0.0], "rotation_deg": [0.0, 0.0, 0.0]},
        "workpiece": {
            "delta_um": [12.0, -8.0, 3.0], "alpha_deg": 0.01, "beta_deg": -0.02, "gamma_deg": 0.5
        },
        "location": {"C": {"EX0C_um": 2.0, "EB0C_urad": 15.0}},
        "component": {
            "X": {
                "position_mm": [-140.0, 0.0, 140.0],
                "EXX_um": [-3.5, 0.0, 4.1],
                "EYX_poly_um_mm": [0.0, 0.0, 2e-5],
            },
            "C": {"position_deg": [-180.0, 0.0, 180.0], "ECC_arcsec": [1.0, 0.0, 1.0]},
        },
    }


def assert_same_si(actual: ErrorModel, expected: ErrorModel, rtol: float) -> None:
    """Same parameters (names, order, values) and same table positions, to `rtol`."""
    a, e = actual.parameters(), expected.parameters()
    assert list(a) == list(e)
    assert_allclose(list(a.values()), list(e.values()), rtol=rtol, atol=0.0)
    for axis, table in expected.component.items():
        for symbol, error in table.items():
            other = actual.component[axis][symbol]
            assert other.kind == error.kind
            if error.kind == "table":
                assert_allclose(other.positions, error.positions, rtol=rtol, atol=0.0)
