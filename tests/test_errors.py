"""Tests of machinesim.errors: SI conversion, round trips, interpolation, refusals, immutability."""

from __future__ import annotations

import dataclasses
import math
import os
import pickle
import re
import tomllib
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from machinesim.errors import (
    AXES,
    LINEAR_AXES,
    ComponentError,
    ErrorModel,
    ToolSetting,
    WorkpieceSetting,
)
from machinesim.exceptions import ErrorModelError, InputError

EXAMPLE = Path(__file__).resolve().parents[1] / "models" / "errors" / "example.toml"

#: One float64 product (file value times unit factor) against a hand-written literal: each
#: is within half an ulp of the true value, so they agree within ~2 ulp (4.4e-16 relative).
ONE_PRODUCT_RTOL = 1e-15
#: Interpolation and polynomial sums computed in two orders: a few roundings each (Horner
#: takes 2 per degree, degree <= 5 here), so the two agree within 10 ulp of the magnitudes summed.
SUM_ULPS = 10


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


def random_model(rng: np.random.Generator) -> ErrorModel:
    """A model with every family, magnitudes spread over 1e-9..1e-3, tables and polynomials."""

    def magnitudes(n):
        return rng.choice([-1.0, 1.0], n) * 10.0 ** rng.uniform(-9.0, -3.0, n)

    location, component = {}, {}
    for axis in rng.choice(list(AXES), size=3, replace=False):
        symbols = rng.choice(list(AXES), size=2, replace=False)
        location[axis] = {f"E{d}0{axis}": float(v) for d, v in zip(symbols, magnitudes(2),
                                                                        strict=True)}
    for axis in rng.choice(list(AXES), size=4, replace=False):
        half = 0.5 if axis in LINEAR_AXES else math.pi
        positions = np.sort(rng.uniform(-half, half, int(rng.integers(2, 20))))
        table_symbol, poly_symbol = rng.choice(list(AXES), size=2, replace=False)
        degree, values = int(rng.integers(0, 6)), magnitudes(positions.size)
        component[axis] = {
            f"E{table_symbol}{axis}": ComponentError("table", positions, values),
            f"E{poly_symbol}{axis}": ComponentError(
                "poly", None, magnitudes(degree + 1) / half ** np.arange(degree + 1)
            ),
        }
    return ErrorModel(
        ToolSetting(magnitudes(3), magnitudes(3)),
        WorkpieceSetting(magnitudes(3), *magnitudes(3)),
        location,
        component,
    )


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


# --- reading -------------------------------------------------------------------------------


@pytest.mark.parametrize("load", ["file", "dict"])
def test_example_gives_the_hand_converted_si_values(load):
    model = (
        ErrorModel.from_toml(EXAMPLE) if load == "file" else ErrorModel.from_dict(example_dict())
    )
    rtol = ONE_PRODUCT_RTOL
    assert_allclose(model.tool.offset, [0.0, -1.78e-4, 0.0], rtol=rtol, atol=0.0)
    assert_array_equal(model.tool.rotation, [0.0, 0.0, 0.0])
    assert_allclose(model.workpiece.delta, [1.2e-5, -8e-6, 3e-6], rtol=rtol, atol=0.0)
    # 0.01 deg = 0.01 * pi / 180 rad, written out by hand.
    assert model.workpiece.alpha == pytest.approx(1.7453292519943295e-4, rel=rtol)
    assert model.workpiece.beta == pytest.approx(-3.490658503988659e-4, rel=rtol)
    assert model.workpiece.gamma == pytest.approx(8.726646259971648e-3, rel=rtol)
    assert dict(model.location) == {"C": pytest.approx({"EX0C": 2e-6, "EB0C": 1.5e-5}, rel=rtol)}
    exx, eyx = model.component["X"]["EXX"], model.component["X"]["EYX"]
    assert exx.kind == "table" and eyx.kind == "poly" and eyx.positions is None
    assert_allclose(exx.positions, [-0.14, 0.0, 0.14], rtol=rtol, atol=0.0)
    assert_allclose(exx.values, [-3.5e-6, 0.0, 4.1e-6], rtol=rtol, atol=0.0)
    # 2e-5 um/mm^2 = 2e-5 * 1e-6 m / (1e-3 m)^2 = 2e-5 m/m^2.
    assert_allclose(eyx.values, [0.0, 0.0, 2e-5], rtol=rtol, atol=0.0)
    # EYX at x = 500 mm: 2e-5 * 500^2 um = 5 um.
    assert eyx.evaluate(np.array([0.5]))[0] == pytest.approx(5e-6, rel=rtol)
    ecc = model.component["C"]["ECC"]
    assert_allclose(ecc.positions, [-math.pi, 0.0, math.pi], rtol=rtol, atol=0.0)
    # 1 arcsec = pi / 648000 rad.
    assert_allclose(ecc.values, [4.84813681109536e-6, 0.0, 4.84813681109536e-6], rtol=rtol)
    assert model.component["C"]["ECC"].span() == (ecc.positions[0], ecc.positions[-1])
    assert eyx.span() is None
    assert not model.is_zero


def test_file_and_dict_readings_agree():
    assert ErrorModel.from_toml(EXAMPLE) == ErrorModel.from_dict(example_dict())


def test_integers_arrays_and_any_section_order_read_alike():
    d = example_dict()
    d["tool"] = {"rotation_deg": (0, 0, 0), "offset_um": np.array([0, -178, 0])}
    assert ErrorModel.from_dict(d) == ErrorModel.from_dict(example_dict())


def test_empty_model_has_no_errors():
    model = ErrorModel()
    assert model.is_zero
    assert model == ErrorModel.from_dict({})
    assert set(model.parameters().values()) == {0.0}
    assert len(model.parameters()) == 12
    assert ErrorModel.from_dict({"location": {"C": {"EX0C_um": 0.0}}}).is_zero
    assert not ErrorModel(location={"C": {"EX0C": 1e-9}}).is_zero


# --- round trips ---------------------------------------------------------------------------


@pytest.mark.parametrize("seed", range(5))
def test_dict_round_trip_is_exact(seed):
    model = random_model(np.random.default_rng(seed))
    back = ErrorModel.from_dict(model.to_dict())
    assert back == model
    assert list(back.parameters().items()) == list(model.parameters().items())


@pytest.mark.parametrize("seed", range(5))
def test_toml_round_trip_reproduces_si_values(tmp_path, seed):
    model = random_model(np.random.default_rng(seed))
    path = tmp_path / "model.toml"
    model.to_toml(path)
    # Two roundings per value (divide by the unit factor, multiply back): <= 2.2e-16 relative.
    assert_same_si(ErrorModel.from_toml(path), model, rtol=1e-15)
    assert ErrorModel.from_dict(model.to_dict(readable=True)) == ErrorModel.from_toml(path)


def test_toml_is_written_in_readable_units(tmp_path):
    path = tmp_path / "example.toml"
    ErrorModel.from_toml(EXAMPLE).to_toml(path)
    text = path.read_text()
    for key in ("offset_um", "rotation_urad", "delta_um", "gamma_urad", "EX0C_um", "EB0C_urad",
                "position_mm", "EXX_um", "EYX_poly_um_mm", "position_deg", "ECC_urad"):
        assert re.search(rf"^{key} = ", text, re.MULTILINE), key
    d = ErrorModel.from_toml(EXAMPLE).to_dict(readable=True)
    assert d["component"]["X"]["position_mm"] == pytest.approx([-140.0, 0.0, 140.0], rel=1e-15)
    assert d["component"]["C"]["position_deg"] == pytest.approx([-180.0, 0.0, 180.0], rel=1e-15)
    assert d["workpiece"]["gamma_urad"] == pytest.approx(0.5 * math.pi / 180 * 1e6, rel=1e-15)


def test_to_toml_replaces_whole_or_leaves_the_old_file(tmp_path, monkeypatch):
    path = tmp_path / "model.toml"
    ErrorModel().to_toml(path)
    before = path.read_bytes()
    model = random_model(np.random.default_rng(0))

    def broken_replace(src, dst):
        raise OSError("disk full")

    monkeypatch.setattr(os, "replace", broken_replace)
    with pytest.raises(OSError, match="disk full"):
        model.to_toml(path)
    monkeypatch.undo()
    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["model.toml"]
    model.to_toml(path)
    assert [p.name for p in tmp_path.iterdir()] == ["model.toml"]
    assert ErrorModel.from_toml(path).parameters() == pytest.approx(model.parameters(), rel=1e-15)


def test_pickle_keeps_values_and_immutability():
    model = random_model(np.random.default_rng(1))
    back = pickle.loads(pickle.dumps(model))
    assert back == model
    assert not back.tool.offset.flags.writeable
    error = next(iter(back.component.values()))
    assert not next(iter(error.values())).values.flags.writeable


# --- component errors ----------------------------------------------------------------------


def test_table_interpolates_midpoints_and_is_constant_beyond_the_ends():
    error = ComponentError("table", [0.0, 0.25, 0.5], [0.0, 4.1e-6, 11.6e-6])
    x = np.array([-1.0, 0.0, 0.125, 0.25, 0.375, 0.5, 2.0])
    expected = [0.0, 0.0, 2.05e-6, 4.1e-6, 7.85e-6, 11.6e-6, 11.6e-6]
    assert_allclose(error.evaluate(x), expected, rtol=1e-15, atol=0.0)
    assert_allclose(error.basis(x) @ error.values, expected, rtol=1e-15, atol=0.0)
    assert_array_equal(error.basis([0.125, -1.0, 2.0]), [[0.5, 0.5, 0.0], [1, 0, 0], [0, 0, 1]])
    assert error.span() == (0.0, 0.5)


def test_single_point_table_is_a_constant():
    error = ComponentError("table", [0.1], [3e-6])
    assert_array_equal(error.evaluate([-1.0, 0.1, 5.0]), [3e-6, 3e-6, 3e-6])
    assert_array_equal(error.basis([-1.0, 5.0]), [[1.0], [1.0]])


def test_polynomial_matches_hand_values():
    error = ComponentError("poly", None, [1.0, -2.0, 3.0])
    # 1 - 2x + 3x^2 at x = 0, 1, 2, -1: 1, 2, 9, 6 (exact in float64).
    assert_array_equal(error.evaluate([0.0, 1.0, 2.0, -1.0]), [1.0, 2.0, 9.0, 6.0])
    assert_array_equal(error.basis([2.0, -1.0]), [[1.0, 2.0, 4.0], [1.0, -1.0, 1.0]])
    assert error.evaluate(2.0) == 9.0 and error.basis(2.0).shape == (3,)
    assert error.span() is None


@pytest.mark.parametrize("seed", range(3))
def test_evaluate_equals_basis_times_values(seed):
    rng = np.random.default_rng(seed)
    model = random_model(rng)
    for axis, table in model.component.items():
        half = 0.5 if axis in LINEAR_AXES else math.pi
        for error in table.values():
            knots = error.positions if error.kind == "table" else np.array([0.0])
            x = np.concatenate([rng.uniform(-1.5 * half, 1.5 * half, 200), knots])
            basis = error.basis(x)
            assert basis.shape == (x.size, error.values.size)
            # Round-off scales with the magnitudes summed: every value a row touches (np.interp
            # forms v0 + slope * dx, not w0 v0 + w1 v1), every term of a polynomial.
            scale = (basis != 0.0) @ np.abs(error.values)
            if error.kind == "poly":
                scale = np.abs(basis) @ np.abs(error.values)
            tolerance = SUM_ULPS * np.finfo(np.float64).eps * scale
            assert np.all(np.abs(error.evaluate(x) - basis @ error.values) <= tolerance)
            if error.kind == "table":
                assert_allclose(basis.sum(axis=1), 1.0, rtol=1e-15)
                assert np.all(basis >= 0.0) and np.all(np.count_nonzero(basis, axis=1) <= 2)


# --- parameters ----------------------------------------------------------------------------


def test_parameter_names_and_order_of_the_example():
    names = list(ErrorModel.from_toml(EXAMPLE).parameters())
    assert names == [
        "tool.x", "tool.y", "tool.z", "tool.rx", "tool.ry", "tool.rz",
        "workpiece.x", "workpiece.y", "workpiece.z",
        "workpiece.alpha", "workpiece.beta", "workpiece.gamma",
        "location.C.EX0C", "location.C.EB0C",
        "component.X.EXX[0]", "component.X.EXX[1]", "component.X.EXX[2]",
        "component.X.EYX[0]", "component.X.EYX[1]", "component.X.EYX[2]",
        "component.C.ECC[0]", "component.C.ECC[1]", "component.C.ECC[2]",
    ]


@pytest.mark.parametrize("seed", range(3))
def test_with_parameters_round_trips(seed):
    rng = np.random.default_rng(seed)
    model = random_model(rng)
    assert model.with_parameters(model.parameters()) == model
    new = {name: float(v) for name, v in zip(model.parameters(),  # mm and mrad, as errors are
                                            1e-3 * rng.normal(size=len(model.parameters())),
                                            strict=True)}
    changed = model.with_parameters(new)
    assert changed.parameters() == new
    assert changed.with_parameters(model.parameters()) == model
    for axis, table in model.component.items():
        for symbol, error in table.items():
            assert changed.component[axis][symbol].span() == error.span()


def test_with_parameters_sets_the_named_fields():
    model = ErrorModel.from_toml(EXAMPLE).with_parameters(
        {"tool.ry": 1e-4, "workpiece.z": 2e-6, "workpiece.beta": 3e-5, "component.X.EXX[1]": 5e-6,
         "location.C.EA0C": 7e-6, "location.Y.EC0Y": 8e-6}
    )
    assert_array_equal(model.tool.rotation, [0.0, 1e-4, 0.0])
    assert model.workpiece.delta[2] == 2e-6 and model.workpiece.beta == 3e-5
    assert model.component["X"]["EXX"].values[1] == 5e-6
    # New symbols take their canonical place (d in X Y Z A B C order).
    assert list(model.location["C"].items()) == [("EX0C", 2e-6), ("EA0C", 7e-6),
                                                 ("EB0C", pytest.approx(1.5e-5, rel=1e-15))]
    assert dict(model.location["Y"]) == {"EC0Y": 8e-6}


def test_parameter_unit_tells_a_polynomial_coefficient_from_a_table_value():
    """Every parameter's SI unit; a polynomial's coefficient k is its value's unit per the
    position's to the k, checked against the error it gives: EYX = c2 x**2 (x in m)."""
    model = ErrorModel.from_toml(EXAMPLE)
    units = {name: model.parameter_unit(name) for name in model.parameters()}
    assert units == {
        **{f"tool.{a}": "m" for a in "xyz"}, **{f"tool.r{a}": "rad" for a in "xyz"},
        **{f"workpiece.{a}": "m" for a in "xyz"},
        **{f"workpiece.{a}": "rad" for a in ("alpha", "beta", "gamma")},
        "location.C.EX0C": "m", "location.C.EB0C": "rad",
        **{f"component.X.EXX[{k}]": "m" for k in range(3)},  # a table's values, at any k
        "component.X.EYX[0]": "m", "component.X.EYX[1]": "m/m", "component.X.EYX[2]": "m/m^2",
        **{f"component.C.ECC[{k}]": "rad" for k in range(3)}}
    # 2e-5 um/mm**2 is 2e-5 m/m**2 (1e-6 / 1e-3**2): the error at x = 0.1 m is c2 x**2 in m
    c2 = model.parameters()["component.X.EYX[2]"]
    assert c2 == pytest.approx(2e-5, rel=ONE_PRODUCT_RTOL)
    assert model.component["X"]["EYX"].evaluate(0.1) == pytest.approx(c2 * 0.1**2, rel=1e-14)
    # a location error the model lacks (with_parameters adds it), the nose radius
    assert model.parameter_unit("location.Y.EC0Y") == "rad"
    assert model.parameter_unit("tool_geometry.nose_radius") == "m"
    # polynomials of a rotary axis: an offset per rad**k, an angle per rad**k
    rotary = ErrorModel(component={"C": {
        "EXC": ComponentError("poly", None, [1e-6, 2e-6]),
        "ECC": ComponentError("poly", None, [0.0, 1e-6, 1e-7, 1e-8])}})
    assert [rotary.parameter_unit(n) for n in rotary.parameters() if "component" in n] == [
        "m", "m/rad", "rad", "rad/rad", "rad/rad^2", "rad/rad^3"]
    for name, match in (("tool.w", "tool.w"), ("component.X.EZX[0]", "no such error"),
                        ("component.X.EYX[3]", "3 values"), ("location.C.EX0Y", "EX0Y")):
        with pytest.raises(ErrorModelError, match=match):
            model.parameter_unit(name)


@pytest.mark.parametrize(
    ("name", "value", "match"),
    [
        ("tool.w", 1.0, "tool.w"),
        ("component.X.EZX[0]", 1.0, r"component\.X\.EZX\[0\].*no such error"),
        ("component.X.EXX[3]", 1.0, r"component\.X\.EXX\[3\].*3 values"),
        ("location.W.EX0W", 1.0, "'W'"),
        ("location.C.EXX", 1.0, "EXX"),
        ("location.C.EX0Y", 1.0, "EX0Y"),
        ("tool.x", float("nan"), r"tool\.x.*nan"),
        ("tool.x", True, r"tool\.x.*True"),
    ],
)
def test_with_parameters_refuses(name, value, match):
    with pytest.raises(ErrorModelError, match=match):
        ErrorModel.from_toml(EXAMPLE).with_parameters({name: value})


@pytest.mark.parametrize(("given", "got"), [
    ([("tool.y", 1e-6)], "[('tool.y', 1e-06)] (list); (name, value) pairs are given as "
                         "dict(pairs)"),
    ("tool.y", "'tool.y' (str)"), (None, "None (NoneType)")])
def test_with_parameters_refuses_what_is_no_mapping(given, got):
    # a list of (name, value) pairs ended in "AttributeError: 'list' object has no
    # attribute 'items'"; the signature, the docstring and the docs all give a mapping
    with pytest.raises(ErrorModelError) as info:
        ErrorModel().with_parameters(given)
    assert str(info.value) == ("key 'parameters': expected the parameters as a mapping "
                               "{name: value} (names as ErrorModel.parameters gives them, SI "
                               f"values), got {got}")
    # the pairs as a dict set the value named
    assert ErrorModel().with_parameters(dict([("tool.y", 1e-6)])).tool.offset[1] == 1e-6


# --- refusals ------------------------------------------------------------------------------


def with_(section: str, content) -> dict:
    return {section: content}


REFUSALS = [
    (with_("tools", {}), r"key 'tools'.*unknown section"),
    (with_("tool", {"offsett_um": [0, 0, 0]}), r"'tool\.offsett_um'.*unknown key"),
    (with_("tool", {"offset": [0, 0, 0]}), r"'tool\.offset'.*no unit suffix"),
    (with_("tool", {"offset_inch": [0, 0, 0]}), r"'tool\.offset_inch'.*'inch' is not recog"),
    (with_("tool", {"rotation_um": [0, 0, 0]}), r"'tool\.rotation_um'.*angle unit.*'um'"),
    (with_("tool", {"offset_deg": [0, 0, 0]}), r"'tool\.offset_deg'.*length unit.*'deg'"),
    (with_("tool", {"offset_um": [1, 2, 3], "offset_mm": [1, 2, 3]}), r"offset_mm.*twice"),
    (with_("workpiece", {"alpha_mm": 1.0}), r"'workpiece\.alpha_mm'.*angle unit.*'mm'"),
    (with_("location", {"C": {"EB0C_um": 1.0}}), r"'location\.C\.EB0C_um'.*angle unit.*'um'"),
    (with_("location", {"C": {"EX0C_deg": 1.0}}), r"'location\.C\.EX0C_deg'.*length.*'deg'"),
    (with_("location", {"C": {"EX0C": 1.0}}), r"'location\.C\.EX0C'.*no unit suffix"),
    (with_("component", {"X": {"position_deg": [0, 1], "EXX_um": [0, 1]}}),
     r"'component\.X\.position_deg'.*length unit.*'deg'"),
    (with_("component", {"C": {"position_mm": [0, 1], "ECC_urad": [0, 1]}}),
     r"'component\.C\.position_mm'.*angle unit.*'mm'"),
    (with_("component", {"X": {"EYX_poly_urad_mm": [0.0, 1.0]}}),
     r"'component\.X\.EYX_poly_urad_mm'.*length unit.*'urad'"),
    (with_("component", {"X": {"EYX_poly_um_deg": [0.0, 1.0]}}),
     r"'component\.X\.EYX_poly_um_deg'.*length unit.*'deg'"),
    (with_("component", {"X": {"EYX_poly_um": [0.0, 1.0]}}), r"EYX_poly_um'.*polynomial key"),
    (with_("tool", {"offset_um": [float("nan"), 0, 0]}), r"'tool\.offset_um'.*finite.*nan"),
    (with_("location", {"C": {"EX0C_um": float("inf")}}), r"'location\.C\.EX0C_um'.*inf"),
    (with_("tool", {"offset_um": [0.0, 1.0]}), r"'tool\.offset_um'.*3 values.*\[0\.0, 1\.0\]"),
    (with_("tool", {"offset_um": [[0.0, 1.0, 2.0]]}), r"'tool\.offset_um'.*\[0\.0, 1\.0, 2\.0\]"),
    (with_("tool", {"offset_um": 1.0}), r"'tool\.offset_um'.*list of numbers.*1\.0"),
    (with_("workpiece", {"alpha_deg": [0.1]}), r"'workpiece\.alpha_deg'.*number.*\[0\.1\]"),
    (with_("component", {"X": {"position_mm": [0, 1, 2], "EXX_um": [0, 1]}}),
     r"'component\.X\.EXX_um'.*2 values, \[0, 1\].*position_mm has 3"),
    (with_("component", {"X": {"position_mm": [0, 250, 250], "EXX_um": [0, 1, 2]}}),
     r"'component\.X\.position_mm'.*strictly increasing.*250.*250"),
    (with_("component", {"X": {"position_mm": [0, 500, 250], "EXX_um": [0, 1, 2]}}),
     r"'component\.X\.position_mm'.*strictly increasing.*500.*250"),
    (with_("component", {"X": {"position_mm": [], "EXX_um": []}}), r"position_mm'.*empty"),
    (with_("component", {"X": {"EXX_um": [0, 1, 2]}}), r"'component\.X\.EXX_um'.*no position_"),
    (with_("tool", {"offset_um": [True, 0, 0]}), r"'tool\.offset_um'.*number.*True"),
    (with_("workpiece", {"alpha_deg": "0.1"}), r"'workpiece\.alpha_deg'.*number.*'0\.1'"),
    (with_("location", {"W": {"EX0W_um": 1.0}}), r"'location\.W'.*'W' is not one of X, Y, Z"),
    (with_("component", {"Q": {"EXQ_um": [1.0]}}), r"'component\.Q'.*'Q' is not one of"),
    (with_("component", {"X": {"position_mm": [0], "EXY_um": [1.0]}}),
     r"'component\.X\.EXY_um'.*'EXY' is of axis Y, not \[component\.X\]"),
    (with_("location", {"C": {"EX0A_um": 1.0}}), r"'EX0A' is of axis A, not \[location\.C\]"),
    (with_("location", {"C": {"EXC_um": 1.0}}), r"'EXC' is a component.*E<d>0C"),
    (with_("component", {"C": {"EX0C_poly_um_deg": [1.0]}}), r"'EX0C' is a location"),
    (with_("location", {"C": {"FOO_um": 1.0}}), r"'location\.C\.FOO_um'.*'FOO' is not an ISO"),
    (with_("component", {"X": {"EQX_um": [1.0]}}), r"'EQX' is not an ISO 230 component"),
    (with_("component", {"X": {"EXX_um": [1.0], "EXX_poly_um_mm": [1.0]}}), r"EXX is given tw"),
    (with_("location", {"C": 2.0}), r"'location\.C'.*expected a table, got 2\.0"),
    (with_("workpiece", {"gamma_deg": 1e308}), r"'workpiece\.gamma_deg'.*1e\+308 deg is no "
     r"angle error: expected at most 180 deg"),
    (with_("workpiece", {"gamma_deg": -180.5}), r"180\.5 deg is no angle error"),
    (with_("tool", {"offset_mm": [0, 1001, 0]}), r"'tool\.offset_mm'.*1001 mm is no length "
     r"error: expected at most 1000 mm"),
    (with_("location", {"C": {"EB0C_urad": 4e6}}), r"4e\+06 urad is no angle error"),
    (with_("component", {"X": {"position_mm": [0, 1], "EXX_m": [0, -2]}}),
     r"'component\.X\.EXX_m'.*2000 mm \(2 m\) is no length error: expected at most 1000 mm "
     r"\(1 m\) either way"),  # a key in SI told as the API's values are: mm first
]


@pytest.mark.parametrize(("data", "match"), REFUSALS)
def test_from_dict_refuses_naming_the_key_and_value(data, match):
    with pytest.raises(ErrorModelError, match=match) as info:
        ErrorModel.from_dict(data, source="my.toml")
    assert str(info.value).startswith("my.toml, key ")
    assert isinstance(info.value, InputError)


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("[tool]\noffset_um = [0.0, inf, 0.0]\n", r"'tool\.offset_um'.*finite.*inf"),
        ("[location.C]\nEX0C_um = nan\n", r"'location\.C\.EX0C_um'.*nan"),
        ("[tool]\noffset_um = [true, 0.0, 0.0]\n", r"'tool\.offset_um'.*True"),
        ("[workpiece]\nalpha_deg = '0.1'\n", r"'workpiece\.alpha_deg'.*'0\.1'"),
        # TOML reads an integer of any length exactly; 10**400 has 1329 bits, beyond float64
        # (it was an internal OverflowError, exit 1 on the command line)
        ("[tool]\noffset_um = [1" + "0" * 400 + ", 0, 0]\n",
         r"'tool\.offset_um'.*integer of 1329 bits, beyond float64"),
        ("[location.C]\nEX0C_um = -1" + "0" * 400 + "\n",
         r"'location\.C\.EX0C_um'.*integer of 1329 bits"),
    ],
)
def test_from_toml_refuses_naming_the_file(tmp_path, text, match):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ErrorModelError, match=re.escape(str(path)) + ".*" + match):
        ErrorModel.from_toml(path)


def test_unreadable_toml_gives_line_and_column(tmp_path):
    path = tmp_path / "broken.toml"
    path.write_text("[tool]\noffset_um = [0.0, 0.0 0.0]\n")
    with pytest.raises(ErrorModelError, match=re.escape(f"{path}, line 2, column ")) as info:
        ErrorModel.from_toml(path)
    assert info.value.line == 2 and info.value.column is not None
    assert "not valid TOML" in str(info.value)


def test_toml_left_open_at_its_end_gives_the_last_line(tmp_path):
    # "not valid TOML: Unclosed array (at end of document)" named no line
    path = tmp_path / "open.toml"
    path.write_text("[tool]\noffset_um = [0.0,\n  0.0,\n  0.0\n")
    with pytest.raises(ErrorModelError, match=re.escape(f"{path}, line 4, column 6")) as info:
        ErrorModel.from_toml(path)
    assert "Unclosed array (at end of document)" in str(info.value)


def test_a_file_not_in_utf8_gives_the_line_and_column_of_the_byte(tmp_path):
    # a micro sign saved as Latin-1 (0xB5) in a comment: the message gave only "at byte 38"
    # and no expectation; the byte order mark, allowed, does not count in the column
    path = tmp_path / "latin1.toml"
    path.write_bytes(b"\xef\xbb\xbf[tool]\n# \xc3\xa9 um\noffset_um = [1.0, 0.0, 0.0]  # 1 \xb5m\n")
    with pytest.raises(ErrorModelError) as info:
        ErrorModel.from_toml(path)
    # 0xb5 follows the 33 characters before it on line 3
    assert (info.value.line, info.value.column) == (3, 34)
    assert "byte 0xb5" in str(info.value) and "expected UTF-8 TOML" in str(info.value)
    path.write_bytes("[tool]\noffset_um = [1.0, 0.0, 0.0]\n".encode("utf-16"))
    with pytest.raises(ErrorModelError, match=r"line 1, column 1: .*UTF-16"):
        ErrorModel.from_toml(path)
    # a PNG given for the TOML (zero bytes, not UTF-16 text) was called UTF-16 from Notepad
    path.write_bytes(b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR\x00\x00\x01\x00")
    with pytest.raises(ErrorModelError) as info:
        ErrorModel.from_toml(path)
    assert str(info.value) == (f"{path}, line 1, column 1: not UTF-8 text (byte 0x89, invalid "
                               "start byte: binary data, not a text file); expected UTF-8 "
                               "TOML: save the file as UTF-8")


def test_a_pipe_or_a_device_is_refused_before_it_is_read(tmp_path):
    # a named pipe with no writer hung the reading for ever, /dev/zero filled the memory
    # (15 GB in 100 s: scenarios/sts_turning.py --errors /dev/zero) and /dev/null read as
    # a model without errors
    fifo = tmp_path / "errors.toml"
    os.mkfifo(fifo)
    for path, kind in ((Path(os.devnull), "a character device"),
                       (fifo, "a named pipe (FIFO)")):
        with pytest.raises(ErrorModelError) as info:
            ErrorModel.from_toml(path)
        assert str(info.value) == (f"{path}: is {kind}, not a regular file; "
                                   "expected a TOML file")


def test_a_folder_given_as_the_toml_file_is_named_a_folder(tmp_path):
    # 'scenarios/tool_rotation_arm.py --errors DIR' said 'DIR: cannot read the file: Is a
    # directory' (the reading's OSError); the command line's checks say 'is a folder'
    folder = tmp_path / "errors.toml"
    folder.mkdir()
    with pytest.raises(ErrorModelError) as info:
        ErrorModel.from_toml(folder)
    assert str(info.value) == f"{folder}: is a folder; expected a TOML file"


@pytest.mark.parametrize(("given", "got"), [
    ({"tool": {"offset_um": [0.0, 1.0, 0.0]}},
     "got dict; a dict of the TOML layout is read by ErrorModel.from_dict"),
    (None, "got NoneType"), (3, "got int")])
def test_from_toml_given_no_path_says_what_came(given, got):
    # a dict given to from_toml (for from_dict) ended in "TypeError: stat: path should be
    # string, bytes, os.PathLike or integer, not dict"; 3 was read as file descriptor 3
    with pytest.raises(ErrorModelError) as info:
        ErrorModel.from_toml(given)
    assert info.value.key == "path"
    assert str(info.value) == f"key 'path': expected the TOML file's path as a str or Path, {got}"


def test_missing_file_is_named(tmp_path):
    path = tmp_path / "absent.toml"
    with pytest.raises(ErrorModelError, match=re.escape(str(path)) + ".*cannot read"):
        ErrorModel.from_toml(path)


@pytest.mark.parametrize(
    ("build", "match"),
    [
        (lambda: ComponentError("spline", None, [1.0]), r"'kind'.*'spline'"),
        (lambda: ComponentError("table", None, [1.0]), r"'positions'.*needs positions"),
        (lambda: ComponentError("poly", [0.0], [1.0]), r"'positions'.*no positions"),
        (lambda: ComponentError("table", [0.0, 1.0], [1.0]), r"'values'.*1 values for 2"),
        (lambda: ComponentError("table", [1.0, 0.0], [1.0, 2.0]), r"strictly increasing"),
        (lambda: ComponentError("poly", None, []), r"'values'.*empty"),
        (lambda: ComponentError("poly", None, np.array([1.0, np.nan])), r"'values'.*nan"),
        (lambda: ToolSetting(offset=[0.0, 0.0]), r"'offset'.*3 values"),
        (lambda: WorkpieceSetting(alpha=float("inf")), r"'alpha'.*inf"),
        (lambda: ErrorModel(tool=None), r"'tool'.*ToolSetting"),
        (lambda: ErrorModel(location={"C": {"EX0C": "1"}}), r"'location\.C\.EX0C'.*'1'"),
        (lambda: ErrorModel(component={"X": {"EXX": 1.0}}), r"'component\.X\.EXX'.*Compon"),
        (
            lambda: ErrorModel(component={"X": {
                "EXX": ComponentError("table", [0.0, 1.0], [0.0, 1.0]),
                "EYX": ComponentError("table", [0.0, 2.0], [0.0, 1.0]),
            }}),
            r"'component\.X\.EYX'.*share their positions",
        ),
    ],
)
def test_constructors_refuse(build, match):
    with pytest.raises(ErrorModelError, match=match):
        build()


# --- immutability --------------------------------------------------------------------------


def test_values_are_immutable():
    model = ErrorModel.from_toml(EXAMPLE)
    error = model.component["X"]["EXX"]
    with pytest.raises(dataclasses.FrozenInstanceError):
        model.tool = ToolSetting()
    with pytest.raises(dataclasses.FrozenInstanceError):
        model.workpiece.alpha = 1.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        error.values = np.zeros(3)
    for array in (model.tool.offset, model.tool.rotation, model.workpiece.delta,
                  error.positions, error.values):
        with pytest.raises(ValueError, match="read-only"):
            array[0] = 1.0
    with pytest.raises(TypeError):
        model.location["C"] = {}
    with pytest.raises(TypeError):
        model.location["C"]["EX0C"] = 1.0
    with pytest.raises(TypeError):
        model.component["X"]["EXX"] = error


def test_inputs_are_copied():
    offset = np.array([1e-6, 0.0, 0.0])
    positions, values = np.array([0.0, 1.0]), np.array([0.0, 1e-6])
    location = {"C": {"EX0C": 1e-6}}
    tool = ToolSetting(offset=offset)
    error = ComponentError("table", positions, values)
    model = ErrorModel(tool=tool, location=location)
    offset[0], positions[1], values[1] = 9.0, 9.0, 9.0
    location["C"]["EX0C"] = 9.0
    assert tool.offset[0] == 1e-6
    assert error.positions[1] == 1.0 and error.values[1] == 1e-6
    assert model.location["C"]["EX0C"] == 1e-6
    assert offset.flags.writeable


# --- the file as written: byte order mark, source, keys --------------------------------------


BOM = "\ufeff"


def test_a_byte_order_mark_is_dropped(tmp_path):
    plain, marked = tmp_path / "plain.toml", tmp_path / "marked.toml"
    text = EXAMPLE.read_text(encoding="utf-8")
    plain.write_text(text, encoding="utf-8")
    marked.write_bytes(b"\xef\xbb\xbf" + text.encode("utf-8"))
    assert marked.read_bytes()[:3] == b"\xef\xbb\xbf"
    model = ErrorModel.from_toml(marked)
    assert model == ErrorModel.from_toml(plain) == ErrorModel.from_dict(example_dict())
    back = tmp_path / "back.toml"
    model.to_toml(back)
    assert_same_si(ErrorModel.from_toml(back), model, rtol=1e-15)


def test_after_a_byte_order_mark_lines_and_columns_count_as_without(tmp_path):
    for name, prefix in (("plain.toml", ""), ("marked.toml", BOM)):
        path = tmp_path / name
        path.write_text(prefix + "[tool]\noffset_um = [0.0, 0.0 0.0]\n", encoding="utf-8")
        with pytest.raises(ErrorModelError) as info:
            ErrorModel.from_toml(path)
        assert (info.value.line, info.value.column) == (2, 23)  # the 0 after "0.0 "
        assert "not valid TOML" in info.value.message and "Invalid statement" not in str(
            info.value)


def test_a_model_read_from_a_file_keeps_its_name_and_keys_as_written(tmp_path):
    path = tmp_path / "nose.toml"
    path.write_text("[tool_geometry]\nnose_radius_mm = -0.6\n[location.C]\nEX0C_nm = 20\n"
                    "[component.X]\nposition_mm = [-10, 10]\nEXX_um = [1, 2]\n"
                    "EBX_poly_urad_mm = [0.5, 0.25]\n")
    model = ErrorModel.from_toml(path)
    assert model.source == str(path)
    assert model.tool_geometry.nose_radius == -0.6 * 1e-3
    key, value = model.written["tool_geometry.nose_radius"]
    assert (key, value) == ("tool_geometry.nose_radius_mm", -0.6)
    assert model.written["location.C.EX0C"] == ("location.C.EX0C_nm", 20.0)
    assert model.written["component.X.position"][0] == "component.X.position_mm"
    assert_array_equal(model.written["component.X.EXX"][1], [1.0, 2.0])
    assert model.written["component.X.EBX"][0] == "component.X.EBX_poly_urad_mm"
    assert model.key_as_written("component.X.EBX") == "component.X.EBX_poly_urad_mm"
    assert model.key_as_written("location.C") == "location.C"  # a section: as it is
    assert ErrorModel().source is None and dict(ErrorModel().written) == {}
    # equal values are equal models, wherever they came from, and pickle alike (the cut
    # memo keys on pickles): a pickle holds the values, not the origin
    same = ErrorModel.from_dict(model.to_dict())
    assert same == model and same.source == "<dict>"
    assert pickle.dumps(same) == pickle.dumps(model)
    back = pickle.loads(pickle.dumps(model))
    assert back == model and back.source is None and dict(back.written) == {}
    with pytest.raises(TypeError):
        model.written["tool.offset"] = ("tool.offset_m", [0.0, 0.0, 0.0])
    # values set in Python are no longer the file's
    changed = model.with_parameters({"location.C.EX0C": 1e-6})
    assert changed.source is None and dict(changed.written) == {}


# Lines counted by hand in each text (line 1 is the first). tomllib gives no positions: a
# refusal of a key named the file and the key but not its line.
KEY_LINE_SHAPES = [
    # a plain key under its [section] header
    ("# an error model\n\n[tool]\noffset_um = [0.0, 1.0]\n", 4, "tool.offset_um",
     "expected 3 values"),
    # an unknown section: a plain key at the top, after a header of a known one
    ("[tool]\noffset_um = [0.0, 1.0, 0.0]\n\n[tools]\noffset_um = [0.0, 1.0, 0.0]\n", 4,
     "tools", "unknown section"),
    # dotted keys, under a header and at the top (a quoted part among them)
    ("[workpiece]\nalpha_deg = 0.1\n[location]\nC.EX0C_um = 2.0\nC.'EB0C_urad' = '15'\n", 5,
     "location.C.EB0C_urad", "expected a number, got '15'"),
    ("tool.offset_um = [0.0, 0.0, 0.0]\nlocation.C.EX0C_xx = 1.0\n", 2,
     "location.C.EX0C_xx", "unit 'xx' is not recognised"),
    # an array spanning lines: its key's line, not the line of the value refused
    ("[tool]\nrotation_deg = [0.0, 0.0, 0.0]\noffset_um = [  # x, y, z\n  0.0,\n  -178.0,\n"
     "  'z',\n]\n", 3, "tool.offset_um", "expected a number, got 'z'"),
    # after a multi-line string holding a header, a '#' and '=' (no key: not counted)
    ('[tool]\nnote = """\n[location.C]\n# x = 1\n"""\n', 2, "tool.note", "unknown key"),
    # a key in an inline table
    ("tool = { offset_um = [0.0,\n  1.0, 0.0], rotation_urad = [1.0, 2.0, 3.0] }\n"
     "workpiece = {delta_um = [1, 2, 3], gamma_um = 1}\n", 3, "workpiece.gamma_um",
     "expected an angle unit"),
    # Windows line ends; a table's header alone
    ("[component.X]\r\nposition_mm = [0.0, 1.0]\r\nEXX_um = [0, 1]\r\n\r\n[component.Y]\r\n"
     "position_mm = [0, 1]\r\nEYY_um = [1.0]\r\n", 7, "component.Y.EYY_um",
     "the table has 1 values"),
    ("\n[location.W]\nEX0W_um = 1.0\n", 2, "location.W", "'W' is not one of"),
]


@pytest.mark.parametrize(("text", "line", "key", "match"), KEY_LINE_SHAPES)
def test_a_refused_key_of_a_file_names_its_line(tmp_path, text, line, key, match):
    path = tmp_path / "errors.toml"
    path.write_bytes(text.encode())
    with pytest.raises(ErrorModelError, match=re.escape(match)) as info:
        ErrorModel.from_toml(path)
    assert (info.value.source, info.value.line, info.value.key) == (str(path), line, key)
    assert str(info.value).startswith(f"{path}, line {line}, key '{key}': ")
    # the same dict given to from_dict names no line (there is no text to count in)
    with pytest.raises(ErrorModelError) as info:
        ErrorModel.from_dict(tomllib.loads(text), source="d")
    assert info.value.line is None and str(info.value).startswith(f"d, key '{key}': ")


def test_key_lines_of_every_shape_are_counted_as_by_hand():
    from machinesim.errors.toml import key_lines

    text = ("# head [tool]\n"                                    # 1
            "[tool]  # the tool\n"                               # 2
            "offset_um = [0.0,   # x = 1\n"                      # 3
            "   -178.0,\n   0.0]\n"                              # 4, 5
            "s = '''a\n[b]\n'''  # c\n"                          # 6, 7, 8
            't = "q\\" = ["\n'                                   # 9
            "[location]\n"                                       # 10
            "C.EX0C_um = 2.0\n"                                  # 11
            "\"C\" . 'EB0C_urad' = 1.5\n"                        # 12
            "[ component . X ]\n"                                # 13
            "position_mm = [\n  [1, 2], {a = 1},\n]\n"           # 14, 15, 16
            "[[w]]\n"                                            # 17
            "q = {a = 1, b.c = [1,\n 2], d = {e = 'x'}}\n")      # 18, 19
    tomllib.loads(text)  # valid TOML
    assert key_lines(text) == {
        "tool": 2, "tool.offset_um": 3, "tool.s": 6, "tool.t": 9, "location": 10,
        "location.C": 11, "location.C.EX0C_um": 11, "location.C.EB0C_urad": 12,
        "component": 13, "component.X": 13, "component.X.position_mm": 14, "w": 17,
        "w.q": 18, "w.q.a": 18, "w.q.b": 18, "w.q.b.c": 18, "w.q.d": 19, "w.q.d.e": 19}
    # a scan that loses its way (text tomllib would refuse) gives no lines, not a traceback
    assert key_lines("[tool]\noffset_um = " + "[" * 5000 + "]" * 5000) == {}
    assert key_lines("[tool]\noffset_um = '") == {}


def test_a_value_below_any_machine_is_noted_in_its_keys_unit_with_si_beside(tmp_path):
    """A key in um, urad, deg or nm: its note gave the size in mm or deg ('4e-09 mm (4e-12 m)'
    for EX0C_um = 4e-6), a unit the file never wrote. By hand: 4e-6 um = 4e-12 m, 2e-6 urad =
    2e-12 rad, 1e-10 deg = 1e-10 pi / 180 = 1.74533e-12 rad, 0.004 nm = 4e-12 m; a key in m
    keeps mm first, m beside, as every message does for SI."""
    from machinesim.errors.toml import below_any_machine

    path = tmp_path / "slip.toml"
    path.write_text("[tool]\noffset_m = [0.0, 3e-12, 0.0]\n[location.C]\nEX0C_um = 4e-6\n"
                    "EA0C_urad = 2e-6\nEB0C_deg = 1e-10\nEY0C_nm = 0.004\n")
    sizes = [line.split(" is at most ")[1].split(", below")[0]
             for line in below_any_machine(ErrorModel.from_toml(path))]
    assert sizes == ["3e-09 mm (3e-12 m)", "4e-06 um (4e-12 m)", "2e-06 urad (2e-12 rad)",
                     "1e-10 deg (1.74533e-12 rad)", "0.004 nm (4e-12 m)"]


def test_a_value_below_any_machine_in_an_si_key_asks_no_unit_question(tmp_path):
    """A key in m or rad cannot hold SI where a smaller unit was asked: its note asked 'was
    it written in m, where the key asks m?'. It now asks whether the value was converted to
    SI twice (3 um as 3e-6 m, then again: 3e-12 m), and a key in um still asks for m."""
    from machinesim.errors.toml import below_any_machine

    path = tmp_path / "slip.toml"
    path.write_text("[tool]\noffset_m = [0.0, 3e-12, 0.0]\n[workpiece]\ngamma_rad = 5e-12\n"
                    "[location.C]\nEX0C_um = 4e-6\n")
    lines = below_any_machine(ErrorModel.from_toml(path))
    assert [line.split(", below anything a machine shows")[1] for line in lines] == [
        ": was it converted to m twice? (the key takes 1 um as 1e-06)",
        ": was it converted to rad twice? (the key takes 1 urad as 1e-06)",
        ": was it written in m, where the key asks um?"]
    assert not any("where the key asks m?" in line or "asks rad?" in line for line in lines)


def test_a_misfit_on_a_machine_names_the_line_of_the_key(tmp_path):
    from machinesim.machines import load_machine
    from machinesim.tool_specs import tool_from_spec
    from machinesim.tools import with_nose_radius_error

    path = tmp_path / "misfit.toml"
    path.write_text("[tool]\noffset_um = [0.0, 0.0, 0.0]\n\n[location.B]\nEX0B_um = 2.0\n"
                    "[tool_geometry]\nnose_radius_um = 1.0\n")
    model = ErrorModel.from_toml(path)
    assert model.line_of("location.B") == 4 and model.line_of("tool_geometry.nose_radius") == 7
    with pytest.raises(ErrorModelError) as info:
        load_machine("grooving_4axis").check_errors(model)  # X Y Z C: no B
    assert (info.value.source, info.value.line, info.value.key) == (str(path), 4, "location.B")
    with pytest.raises(InputError) as info:  # a V tool has no nose radius
        with_nose_radius_error(tool_from_spec("v:90"), model)
    assert (info.value.source, info.value.line) == (str(path), 7)
    assert info.value.key == "tool_geometry.nose_radius_um"


def test_misfit_names_the_model_file_first_then_the_machine(tmp_path):
    path = tmp_path / "axis_missing.toml"
    path.write_text("[location.C]\nEX0C_um = 2.0\n[component.X]\nEYX_poly_um_mm = [0.0, 1.0]\n")
    model = ErrorModel.from_toml(path)
    found = ErrorModelError("axis 'C' is not on this machine; it has X, Y, Z",
                            source="m/mill3.urdf", key="location.C")
    told = model.misfit(found, "mill3")
    assert isinstance(told, ErrorModelError)
    assert str(told) == (f"{path}, line 1, key 'location.C': axis 'C' is not on this machine; "
                         "it has X, Y, Z (machine mill3, m/mill3.urdf)")
    assert (told.source, told.key) == (str(path), "location.C")
    # a key the file wrote is named as written, unit and all
    symbol = ErrorModelError("EYX is no good here", source="m/mill3.urdf", key="component.X.EYX")
    assert model.misfit(symbol, "mill3").key == "component.X.EYX_poly_um_mm"
    # a model built in Python has no file: the machine's message stands
    assert ErrorModel.from_dict(model.to_dict()).with_parameters({}).misfit(found, "m") is found
    assert ErrorModel().misfit(found, "mill3") is found


# --- polynomials over an axis travel --------------------------------------------------------


def brute_largest(error: ComponentError, lower: float, upper: float) -> tuple[float, float]:
    """The largest |value| on a dense grid, summed power by power (tables: np.interp): an
    independent, approximate reference."""
    x = np.linspace(lower, upper, 2_000_001)
    if error.kind == "poly":
        dense = np.sum(error.values[:, None] * x ** np.arange(error.values.size)[:, None], axis=0)
    else:
        dense = np.interp(x, error.positions, error.values)
    i = int(np.argmax(np.abs(dense)))
    return float(dense[i]), float(x[i])


@pytest.mark.parametrize(
    ("error", "lower", "upper"),
    [
        # a maximum inside the travel, off any grid: 1.5 - 100 (x - 0.0123)**2
        (ComponentError("poly", None, [1.5 - 100 * 0.0123**2, 200 * 0.0123, -100.0]), -0.1, 0.1),
        (ComponentError("poly", None, [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]), -0.15, 0.1),
        (ComponentError("poly", None, [1e-6, -3e-5, 2e-4, 5e-3]), -0.05, 0.1),
        (ComponentError("poly", None, [7e-6]), -1.0, 1.0),
        (ComponentError("table", [-0.1, 0.0, 0.05, 0.2], [1e-6, -4e-6, 3e-6, 9e-6]), -0.08, 0.1),
    ],
)
def test_largest_agrees_with_a_dense_grid(error, lower, upper):
    value, where = error.largest(lower, upper)
    expected, at = brute_largest(error, lower, upper)
    assert lower <= where <= upper
    assert value == pytest.approx(expected, rel=1e-9, abs=1e-18)
    assert where == pytest.approx(at, abs=1e-6 * (upper - lower))
    assert value == error.evaluate([where])[0]


def test_largest_of_the_interior_maximum_is_at_the_root():
    error = ComponentError("poly", None, [1.5 - 100 * 0.0123**2, 200 * 0.0123, -100.0])
    value, where = error.largest(-0.1, 0.1)
    assert where == pytest.approx(0.0123, rel=1e-12)
    assert value == pytest.approx(1.5, rel=1e-12)


@pytest.mark.parametrize(
    ("text", "axis", "travel", "key", "value", "at", "units"),
    [
        # the new user's file: 1e300 um/mm**2 at the end of a +-150 mm travel
        ("[component.X]\nEYX_poly_um_mm = [0.0, 0.0, 1e300]\n", "X", (-0.15, 0.15),
         "component.X.EYX_poly_um_mm", 1e300 * 150.0**2, -150.0, ("um", "mm")),
        # x**8 in um per mm**8: refused here, before the planner's million sub-steps
        ("[component.X]\nEYX_poly_um_mm = [0, 0, 0, 0, 0, 0, 0, 0, 1.0]\n", "X", (-0.15, 0.15),
         "component.X.EYX_poly_um_mm", 150.0**8, -150.0, ("um", "mm")),
        # a rotary axis: 1 urad per deg**3 reaches 5.832 rad at 180 deg, beyond half a turn
        ("[component.C]\nEBC_poly_urad_deg = [0.0, 0.0, 0.0, 1.0]\n", "C",
         (-math.pi / 2, math.pi), "component.C.EBC_poly_urad_deg", 180.0**3, 180.0,
         ("urad", "deg")),
        # nm per m: the units of the key, whatever they are
        ("[component.Z]\nEXZ_poly_nm_m = [2e9]\n", "Z", (-0.05, 0.1),
         "component.Z.EXZ_poly_nm_m", 2e9, -0.05, ("nm", "m")),
    ],
)
def test_a_polynomial_beyond_the_bound_within_the_travel_is_refused(
        tmp_path, text, axis, travel, key, value, at, units):
    path = tmp_path / "F.toml"
    path.write_text(text)
    model = ErrorModel.from_toml(path)  # every coefficient is a finite number: read
    with pytest.raises(ErrorModelError) as info:
        model.check_travel(axis, *travel)
    factor = {"mm": 1e-3, "m": 1.0, "deg": math.pi / 180}[units[1]]

    def place(value):  # a position in the key's unit; for a key in m, in mm first, m beside
        return f"{value * 1e3:g} mm ({value:g} m)" if units[1] == "m" else f"{value:g} {units[1]}"

    low, high = travel[0] / factor, travel[1] / factor
    shown = (f"{place(low)} .. {place(high)}" if units[1] == "m" else
             f"{low:g} .. {high:g} {units[1]}")

    limit = "1e+06 um (1 m)" if units[0] == "um" else (
        "3.14159e+06 urad (3.14159 rad)" if units[0] == "urad" else "1e+09 nm (1 m)")
    quantity = "length" if units[0] in ("um", "nm") else "angle"
    assert str(info.value) == (
        f"{path}, key '{key}': over the travel of axis {axis}, {shown}, the polynomial "
        f"reaches {value:g} {units[0]} at "
        f"{axis} = {place(at)}, no {quantity} error: expected at most {limit} either way")
    assert (info.value.source, info.value.key) == (str(path), key)
    # the machine's check names the machine's file; misfit then tells it from the model's side
    with pytest.raises(ErrorModelError) as info:
        model.check_travel(axis, *travel, source="m.urdf")
    assert info.value.source == "m.urdf"
    assert str(model.misfit(info.value, "m")).startswith(  # the key is on line 2 of each text
        f"{path}, line 2, key '{key}': over the travel")


def test_a_polynomial_within_the_bound_over_the_travel_passes():
    model = ErrorModel.from_toml(EXAMPLE)  # EYX = 2e-5 um/mm**2 x**2: 0.39 um at 140 mm
    model.check_travel("X", -0.14, 0.14)
    model.check_travel("Y", -1.0, 1.0)  # no component error on Y
    # just within: 1 m exactly at the end of the travel
    ErrorModel.from_dict({"component": {"X": {"EYX_poly_m_m": [0.0, 10.0]}}}).check_travel(
        "X", -0.1, 0.1)
    beyond = ErrorModel.from_dict({"component": {"X": {"EYX_poly_m_m": [0.0, 10.0 + 1e-9]}}})
    with pytest.raises(ErrorModelError, match=r"'component\.X\.EYX_poly_m_m'.*travel of axis X, "
                       r"-100 mm \(-0\.1 m\) \.\. 100 mm \(0\.1 m\), the polynomial reaches "
                       r"-1000\.0000001 mm \(-1\.0000000001 m\) at X = -100 mm \(-0\.1 m\)"):
        beyond.check_travel("X", -0.1, 0.1)


def test_a_polynomial_on_a_rotary_axis_is_held_to_the_bound_and_on_a_spindle_refused():
    # robonano_a0ib's C turns within a turn each way: a polynomial there is an error model,
    # held to 1 m over the travel. sts_lathe's C turns +-1e5 rad: a polynomial in the angle
    # does not repeat each turn (1 um/rad was 0.1 m at the travel's end), so it is refused
    from machinesim.machines import load_machine

    table = load_machine("robonano_a0ib")
    lower, upper = table.lower[4], table.upper[4]
    assert -2 * math.pi <= lower and upper <= 2 * math.pi
    table.check_errors(ErrorModel.from_dict({"component": {"C": {
        "EXC_poly_um_rad": [0.0, 1.0]}}}))
    lathe = load_machine("sts_lathe")
    small = ErrorModel.from_dict({"component": {"C": {"EXC_poly_um_rad": [0.0, 1.0]}}})
    with pytest.raises(ErrorModelError, match=r"component\.C\.EXC.*does not repeat each "
                                              r"turn, and C turns -5729577\.95131 deg "
                                              r"\(-100000 rad\) \.\. 5729577\.95131 deg "
                                              r"\(100000 rad\); "):
        lathe.check_errors(small)


def test_a_polynomial_built_in_python_is_named_by_its_symbol_in_um_and_mm():
    model = ErrorModel(component={"X": {"EZX": ComponentError("poly", None, [0.0, 0.0, 200.0])}})
    with pytest.raises(ErrorModelError) as info:
        model.check_travel("X", -0.05, 0.1)
    # 200 m/m**2 at 0.1 m: 2 m
    assert str(info.value) == (
        "key 'component.X.EZX': over the travel of axis X, -50 .. 100 mm, the polynomial "
        "reaches 2e+06 um at X = 100 mm, no length error: expected at most 1e+06 um (1 m) "
        "either way")


def test_a_polynomial_beyond_float64_in_the_units_shown_is_told_so():
    error = ComponentError("poly", None, [0.0] * 10 + [1e300])  # 1e300 m/rad**10 x**10
    model = ErrorModel(component={"C": {"EXC": error}})
    with pytest.raises(ErrorModelError) as info:  # 9.6e307 m is finite, in um it is not
        model.check_travel("C", -2 * math.pi, 2 * math.pi)
    # told in um, the unit of the key (a Python model's: um), SI beside; it was told in m
    # alone: (2 pi)**10 = 95895600.6 by hand, so 9.58956e307 m, 9.58956e313 um
    assert ("reaches 9.58956e+313 um (9.58956e+307 m) at C = -360 deg, no length error: "
            "expected at most 1e+06 um (1 m)") in str(info.value)
    with pytest.raises(ErrorModelError, match=r"reaches more than float64 holds at C = -720 deg"):
        model.check_travel("C", -4 * math.pi, 4 * math.pi)


def test_a_coefficient_beyond_float64_in_si_is_refused_at_its_key(tmp_path):
    path = tmp_path / "F.toml"
    path.write_text("[component.X]\nEYX_poly_um_mm = [0, 0, 0, 0, 0, 0, 0, 0, 1e300]\n")
    with pytest.raises(ErrorModelError) as info:
        ErrorModel.from_toml(path)
    # 1 um/mm**8 is 1e-6 / (1e-3)**8 = 1e18 m/m**8: 1e300 of them would be 1e318 m/m**8
    assert str(info.value) == (
        f"{path}, line 2, key 'component.X.EYX_poly_um_mm': coefficient c_8 = 1e+300 um/mm**8 is "
        "1e+18 times as large in m/m**8, beyond float64; expected a length error of at most "
        "1e+06 um (1 m) over the travel")  # in um, as the key writes it (was 1000 mm)


def test_a_component_error_out_of_order_names_the_unit_its_positions_were_written_in(tmp_path):
    # positions and a range that do not increase were told as bare numbers, "got 0.1 then
    # 0.05", whatever unit they were written in
    with pytest.raises(ErrorModelError, match=r"strictly increasing, got 0\.1 then 0\.05 m or "
                                              r"rad \(indices 0, 1\)"):
        ComponentError("table", [0.1, 0.05], [0.0, 0.0])
    with pytest.raises(ErrorModelError, match=r"expected lower <= upper, got 0\.1 \.\. 0\.05 m "
                                              r"or rad"):
        ComponentError("poly", None, [0.0, 1.0]).largest(0.1, 0.05)
    path = tmp_path / "F.toml"
    for unit in ("mm", "deg"):
        axis = "X" if unit == "mm" else "C"
        path.write_text(f"[component.{axis}]\nposition_{unit} = [0, 100, 50]\n"
                        f"EX{axis}_um = [0, 1, 2]\n")
        with pytest.raises(ErrorModelError, match=rf"line 2, key 'component\.{axis}\.position_"
                                                  rf"{unit}': positions must be strictly "
                                                  rf"increasing, got 100\.0 then 50\.0 {unit} "
                                                  r"\(indices 1, 2\)"):
            ErrorModel.from_toml(path)


def test_a_move_bent_into_too_many_sub_steps_names_the_command_line_option():
    from machinesim.exceptions import NCProgramError
    from machinesim.machines import load_machine
    from machinesim.motion import plan
    from machinesim.nc import ProgramBuilder

    machine = load_machine(Path(__file__).resolve().parents[1] / "models" / "grooving_4axis.urdf")
    # 1 m/m**2: 10 mm at X = 100 mm, well within the bound, but a parabola's chord of
    # length h sags h**2 / 4 m: a million sub-steps sag 2.5e-15 m, above 1e-16 m
    errors = ErrorModel.from_dict({"component": {"X": {"EYX_poly_m_m": [0.0, 0.0, 1.0]}}})
    x = machine.axes.index("X")
    errors.check_travel("X", machine.lower[x], machine.upper[x])  # 62.5 mm at most: passes
    program = ProgramBuilder().rapid(X=0.0, Y=0.0, Z=1e-3, C=0.0).linear(
        X=0.1, feed_mm_per_min=100).build()
    with pytest.raises(NCProgramError) as info:
        plan(program, machine, errors, chord_tolerance=1e-16)
    assert info.value.line == 2
    assert info.value.message == (
        "a move would need more than 1000000 sub-steps to keep the chord within 1e-07 nm; "
        "raise chord_tolerance (--chord-nm on the command line)")


def test_a_rotary_axis_s_table_of_a_turn_repeats_each_turn_and_a_polynomial_is_refused():
    # sts_lathe's C is a spindle (+-1e5 rad): its error at 45 deg is its error 1, 2 and 10
    # turns on and one turn back; the end value was held instead (0 at 405 deg)
    import numpy as np

    import machinesim

    machine = machinesim.load_machine("sts_lathe")
    wobble = machinesim.ErrorModel.from_dict({"component": {"C": {
        "position_deg": list(np.arange(0.0, 361.0, 45.0)),
        "EZC_nm": [0.0, 10.0, 0.0, -10.0, 0.0, 10.0, 0.0, -10.0, 0.0]}}})
    q = np.zeros((6, 3))
    q[:, 2] = np.radians([45.0, 405.0, 765.0, 3645.0, -315.0, 90.0])
    dz = machine.tool_pose(q, wobble)[:, 2, 3] - machine.tool_pose(q)[:, 2, 3]
    assert dz[:5] == pytest.approx([10e-9] * 5, rel=1e-6) and abs(dz[5]) < 1e-15
    # the identification's derivative turns the same way
    jac = machine.error_jacobian(q[:2], wobble, ["component.C.EZC[1]"])
    assert jac[0, 2, 0] == pytest.approx(jac[1, 2, 0], rel=1e-12) and abs(jac[0, 2, 0]) > 0.5
    # a table shorter than a turn holds its end value beyond it, as on a linear axis
    short = machinesim.ErrorModel.from_dict({"component": {"C": {
        "position_deg": [0.0, 90.0], "EZC_nm": [0.0, 10.0]}}})
    q[:, 2] = np.radians([90.0, 180.0, 450.0, 0.0, 0.0, 0.0])
    dz = machine.tool_pose(q[:3], short)[:, 2, 3] - machine.tool_pose(q[:3])[:, 2, 3]
    assert dz == pytest.approx([10e-9] * 3, rel=1e-6)
    # a polynomial in the angle grows without end over a spindle's turns: refused
    growing = machinesim.ErrorModel.from_dict({"component": {"C": {
        "EZC_poly_mm_deg": [0.0, 0.0, 7e-3]}}})
    with pytest.raises(ErrorModelError, match="component.C.EZC.*does not repeat each turn"):
        machine.tool_pose(q[:1], growing)


def test_the_example_s_table_of_a_whole_turn_closes():
    # the README's example had ECC 1 arcsec at -180 deg and -1 arcsec at 180 deg: read each
    # turn, the error stepped 2 arcsec where C passed 180 deg, ~53 nm at the grooves' tool
    # points, and the planner raised a C move's sub-steps from 1842 by 10 % a round towards
    # a million (a chord cannot follow a step), silent for more than 15 minutes
    ecc = ErrorModel.from_toml(EXAMPLE).component["C"]["ECC"]
    assert ecc.positions[-1] - ecc.positions[0] == pytest.approx(2 * math.pi, rel=1e-15)
    assert ecc.evaluate(np.array([-math.pi]))[0] == ecc.evaluate(np.array([math.pi]))[0]


def test_positions_without_a_table_are_refused_not_dropped():
    # a [component.X] with positions and no table was read as no error at all
    with pytest.raises(ErrorModelError, match=r"component\.X\.position_mm.*no table uses it"):
        ErrorModel.from_dict({"component": {"X": {"position_mm": [-10.0, 0.0, 10.0]}}})


@pytest.mark.parametrize("data", [
    {"workpiece": {"gamma_deg": -180.0}},
    {"location": {"C": {"EC0C_deg": 180.0}}},
    {"tool": {"rotation_rad": [math.pi, 0.0, -math.pi]}},
])
def test_an_angle_at_the_bound_written_by_to_toml_reads_back(tmp_path, data):
    # 180 deg is within the bound; to_toml writes it as 3141592.6535897935 urad, which read
    # back (times 1e-6) is pi + 4.4e-16 and was refused as "no angle error", so a model
    # machinesim accepted and wrote could not be read again
    model = ErrorModel.from_dict(data)
    path = tmp_path / "bound.toml"
    model.to_toml(path)
    back = ErrorModel.from_toml(path)
    for name, value in model.parameters().items():
        assert back.parameters()[name] == pytest.approx(value, rel=1e-15, abs=0.0)
    with pytest.raises(ErrorModelError, match="no angle error"):  # a bit more is still refused
        ErrorModel.from_dict({"workpiece": {"gamma_deg": -180.000001}})


@pytest.mark.parametrize(("build", "expected"), [
    (lambda: ToolSetting([0.0, 1000.0, 0.0], [0.0, 0.0, 0.0]),
     "key 'offset': 1000000 mm (1000 m) is no length error: expected at most 1000 mm (1 m) "
     "either way"),
    (lambda: ToolSetting([0.0, 0.0, 0.0], [0.0, -4.0, 0.0]),  # 4 rad: 229.18... deg by hand
     f"key 'rotation': {math.degrees(4.0):.12g} deg (4 rad) is no angle error: expected at "
     "most 180 deg (3.14159265359 rad) either way"),
    (lambda: ErrorModel(component={"X": {"EZX": ComponentError("table", [0.0, 0.1],
                                                               [0.0, 1.5])}}),
     "key 'component.X.EZX': 1500 mm (1.5 m) is no length error: expected at most 1000 mm "
     "(1 m) either way"),
])
def test_a_python_value_beyond_the_bound_is_told_in_mm_or_deg_first_and_si_beside(build,
                                                                                  expected):
    # the values of the Python API, in m and rad, were told in metres and radians first
    # ("1000 m is no length error: expected at most 1 m"), where every other refusal gives
    # mm or deg first with SI in parentheses (machinesim.units.length_text, angle_text)
    with pytest.raises(ErrorModelError) as info:
        build()
    assert str(info.value) == expected


def test_an_error_model_says_what_it_holds_with_units():
    """Its repr had been the dataclass dump of every family, the zero ones too, as bare SI
    arrays: ErrorModel(tool=ToolSetting(offset=array([ 4.e-06, -2.e-06,  0.e+00]), ...),
    no unit anywhere, and a background file's 70 table values at full length. Now the
    non-zero parameters with their units, where it was read from, the first 8."""
    assert repr(ErrorModel()) == "ErrorModel(no errors)"
    model = ErrorModel.from_dict({"tool": {"offset_um": [4.0, -2.0, 0.0]},
                                  "workpiece": {"gamma_deg": 1.0}}, source="mine")
    assert repr(model) == (f"ErrorModel(tool.x = 4e-06 m, tool.y = -2e-06 m, "
                           f"workpiece.gamma = {math.pi / 180:.6g} rad; from mine)")
    assert str(ErrorModel.from_dict({"component": {"X": {"EYX_poly_um_mm": [0.0, 2.0]}}})
               ) == "ErrorModel(component.X.EYX[1] = 0.002 m/m; from <dict>)"
    many = ErrorModel().with_parameters({f"tool.{n}": 1e-6 for n in ("x", "y", "z")}
                                        | {f"workpiece.{n}": 1e-6 for n in ("x", "y", "z")}
                                        | {"location.C.EX0C": 1e-6, "location.C.EY0C": 1e-6,
                                           "location.C.EA0C": 1e-6, "location.C.EB0C": 1e-6})
    assert repr(many).endswith("location.C.EY0C = 1e-06 m, ... 2 more non-zero)")
