"""Tests of machinesim.errors' model: the example's SI values, dict and TOML round trips,
table interpolation and polynomials, parameters by name, immutability, and what a model
says it holds."""

from __future__ import annotations

import dataclasses
import math
import os
import pickle
import re
from pathlib import Path

import numpy as np
import pytest
from errors_helpers import assert_same_si, example_dict
from numpy.testing import assert_allclose, assert_array_equal

from machinesim.errors import (
    AXES,
    LINEAR_AXES,
    ComponentError,
    ErrorModel,
    ToolSetting,
    WorkpieceSetting,
)
from machinesim.exceptions import ErrorModelError
from machinesim.machines import load_machine

EXAMPLE = Path(__file__).resolve().parents[1] / "models" / "errors" / "example.toml"

#: One float64 product (file value times unit factor) against a hand-written literal: each
#: is within half an ulp of the true value, so they agree within ~2 ulp (4.4e-16 relative).
ONE_PRODUCT_RTOL = 1e-15
#: Interpolation and polynomial sums computed in two orders: a few roundings each (Horner
#: takes 2 per degree, degree <= 5 here), so the two agree within 10 ulp of the magnitudes summed.
SUM_ULPS = 10


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


def test_a_parameter_index_in_other_digits_is_no_parameter():
    # '\u0661' (Arabic-Indic 1) set entry 1 of the table, and error_jacobian ended in int()'s
    # ValueError on '\u00b2' (superscript 2), which str.isdigit() passes
    model = ErrorModel.from_toml(EXAMPLE)
    machine = load_machine("grooving_4axis")
    for index in ("\u0661", "\u00b2"):
        name = f"component.X.EXX[{index}]"
        with pytest.raises(ErrorModelError, match="unknown parameter name"):
            model.with_parameters({name: 5e-6})
        with pytest.raises(ErrorModelError, match=r"no component error X\.EXX with an entry"):
            machine.error_jacobian(machine.home, model, [name])


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
