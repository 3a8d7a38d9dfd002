"""Realism's background errors: added to the injected ones in the lab's truth (and
what it cuts), one for every shipped machine, and add_errors' sum of two error models
against the tables summed by hand."""

from __future__ import annotations

import numpy as np
import pytest
from lab_helpers import TRUTH, groove
from realism_helpers import MM, ROUND_OFF_M, UM

import machinesim
from machinesim import ErrorModel, Lab
from machinesim.errors import ComponentError
from machinesim.exceptions import InputError
from machinesim.realism import Realism, add_errors, background_model
from machinesim.tolerances import TABULATED_SUM


def test_background_adds_to_the_injected_errors_in_the_truth(a0ib):
    lab = Lab("robonano_a0ib", TRUTH, realism=Realism.with_only("background_errors"))
    background = background_model(a0ib)
    assert lab.reveal_background() == background
    assert lab.reveal(background=False) == ErrorModel.from_dict(TRUTH)
    total = lab.reveal()
    assert total.location["C"]["EX0C"] == pytest.approx(2 * UM + background.location["C"][
        "EX0C"], abs=1e-21)
    x = np.linspace(-0.14, 0.14, 57)
    np.testing.assert_allclose(total.component["X"]["EYX"].evaluate(x),
                               background.component["X"]["EYX"].evaluate(x), rtol=0,
                               atol=1e-21)
    # what the lab cuts and measures comes from the total
    part, _ = lab.cut(groove(), "v:90", "block:10x10x2")
    direct, _ = machinesim.cut(groove(), a0ib, "v:90", "block:10x10x2", total)
    assert np.array_equal(part.mesh()[0], direct.mesh()[0])
    plain, _ = Lab("robonano_a0ib", TRUTH, noise=False).cut(groove(), "v:90", "block:10x10x2")
    assert not np.array_equal(part.mesh()[0], plain.mesh()[0])
    given = Lab("robonano_a0ib", TRUTH, realism=Realism.lab(), background={})
    assert given.reveal() == ErrorModel.from_dict(TRUTH)


@pytest.mark.parametrize("name", machinesim.list_machines())
def test_every_shipped_machine_has_a_background_it_accepts(name):
    machine = machinesim.load_machine(name)
    model = background_model(machine)
    assert not model.is_zero
    for axis, table in model.component.items():
        for symbol, error in table.items():
            assert error.evaluate([0.0])[0] == 0.0, f"{axis}.{symbol} at the reference"


def test_add_errors_is_exact_on_the_union_of_the_tables():
    a = ErrorModel(location={"C": {"EX0C": 1e-6}}, component={
        "X": {"EXX": ComponentError("table", [-0.1, 0.0, 0.1], [1e-6, 0.0, -2e-6]),
              "EYX": ComponentError("table", [-0.1, 0.0, 0.1], [0.0, 3e-7, 0.0])},
        "Z": {"EZZ": ComponentError("poly", None, [0.0, 1e-5])}})
    b = ErrorModel(location={"C": {"EX0C": 2e-7, "EY0C": -1e-7}}, component={
        "X": {"EXX": ComponentError("table", [-0.12, -0.05, 0.03, 0.12],
                                    [1e-7, -2e-7, 3e-7, 0.0])},
        "Z": {"EZZ": ComponentError("poly", None, [0.0, 0.0, 2e-4])}})
    total = add_errors(a, b)
    assert total.location["C"] == {"EX0C": 1e-6 + 2e-7, "EY0C": -1e-7}
    x = np.linspace(-0.15, 0.15, 301)
    for symbol in ("EXX", "EYX"):
        expected = sum(m.component["X"][symbol].evaluate(x) for m in (a, b)
                       if symbol in m.component["X"])
        np.testing.assert_allclose(total.component["X"][symbol].evaluate(x), expected,
                                   rtol=0, atol=1e-21)
    np.testing.assert_array_equal(total.component["Z"]["EZZ"].values, [0.0, 1e-5, 2e-4])
    with pytest.raises(InputError, match="polynomial"):
        add_errors(ErrorModel(component={"Z": {"EZZ": ComponentError("table", [0.0, 0.1],
                                                                     [0.0, 1e-7])}}), b)
    with pytest.raises(InputError, match="setting"):
        add_errors(a, ErrorModel.from_dict({"tool": {"offset_um": [1.0, 0.0, 0.0]}}))


def test_a_whole_turn_table_summed_with_a_longer_one_still_repeats_each_turn():
    """A rotary table of a whole turn (ECC over -180 .. 180 deg) repeats each turn, and so
    must its part of a sum put on the union with a table of -360 .. 360 deg (EAC, a
    background's wobble, say): at -270 deg it is its value at 90 deg, written out here by
    hand for every 45 deg. It had been held at its end value there (2 urad for 3), and the
    lab's tool at C = -270 deg sat 1 urad turned, 0.1 um off at 100 mm."""
    deg = np.radians
    urad = 1e-6
    ecc = ComponentError("table", deg([-180.0, -90.0, 0.0, 90.0, 180.0]),
                         np.array([2.0, 1.0, 0.0, 3.0, 2.0]) * urad)
    grid = deg(np.arange(-360.0, 361.0, 45.0))
    wobble = ComponentError("table", grid, 1.5 * urad * np.sin(2 * grid))
    total = add_errors(ErrorModel(component={"C": {"ECC": ecc}}),
                       ErrorModel(component={"C": {"EAC": wobble}}))
    each_turn = [0.0, 1.5, 3.0, 2.5, 2.0, 1.5, 1.0, 0.5, 0.0, 1.5, 3.0, 2.5, 2.0, 1.5, 1.0,
                 0.5, 0.0]  # at -360, -315, ... 360 deg: ECC a turn back where beyond it
    np.testing.assert_array_equal(total.component["C"]["ECC"].positions, grid)
    np.testing.assert_allclose(total.component["C"]["ECC"].values,
                               np.array(each_turn) * urad, rtol=0, atol=1e-21)
    np.testing.assert_array_equal(total.component["C"]["EAC"].values, wobble.values)
    machine = machinesim.load_machine("grooving_4axis")
    by_hand = ErrorModel(component={"C": {
        "ECC": ComponentError("table", grid, np.array(each_turn) * urad), "EAC": wobble}})
    q = np.array([[100 * MM, 0.0, 0.0, deg(c)] for c in (-300.0, -270.0, -200.0, 250.0)])
    np.testing.assert_allclose(machine.tool_pose(q, total), machine.tool_pose(q, by_hand),
                               rtol=0, atol=ROUND_OFF_M)


def test_a_polynomial_plus_a_table_is_tabulated_over_the_travel_within_its_tolerance():
    """Linear interpolation of c x^2 at spacing h is off by c h^2 / 4 at each midpoint (by
    hand): the spacing the sum is tabulated at keeps that within TABULATED_SUM, and the other
    tables of the axis move onto the same positions, to round-off."""
    c = 2e-5  # 1/m: the README's example EYX, 2e-5 um/mm^2, 0.39 um at 140 mm
    injected = ErrorModel(component={"X": {"EYX": ComponentError("poly", None, [0.0, 0.0, c])}})
    background = ErrorModel(component={"X": {
        "EYX": ComponentError("table", [-0.14, 0.0, 0.14], [-5e-8, 0.0, 3e-8]),
        "EXX": ComponentError("table", [-0.14, 0.0, 0.14], [2e-8, 0.0, -1e-8])}})
    total = add_errors(injected, background, {"X": (-0.14, 0.14)})
    eyx = total.component["X"]["EYX"]
    assert eyx.kind == "table"
    assert np.array_equal(total.component["X"]["EXX"].positions, eyx.positions)
    h = np.diff(eyx.positions).max()
    assert c * h**2 / 4.0 <= TABULATED_SUM < 1.1 * c * h**2 / 4.0  # not needlessly fine
    x = np.linspace(-0.14, 0.14, 280_001)
    off = eyx.evaluate(x) - (c * x**2 + background.component["X"]["EYX"].evaluate(x))
    assert np.abs(off).max() <= TABULATED_SUM
    assert np.abs(off).max() > 0.5 * TABULATED_SUM  # the bound is what the midpoints reach
    np.testing.assert_allclose(total.component["X"]["EXX"].evaluate(x),
                               background.component["X"]["EXX"].evaluate(x), rtol=0,
                               atol=1e-22)  # round-off of 2e-8 m values: ulp 3.3e-24


def test_a_polynomial_too_curved_to_tabulate_is_refused_naming_it():
    curved = ErrorModel(component={"X": {"EYX": ComponentError("poly", None, [0.0, 0.0, 1e3])}})
    table = ErrorModel(component={"X": {"EYX": ComponentError("table", [0.0, 0.1], [0.0, 1e-8])}})
    with pytest.raises(InputError, match=r"component\.X\.EYX: .* positions .*give it as a table"):
        add_errors(curved, table, {"X": (-0.14, 0.14)})


def test_the_readme_example_errors_run_in_a_lab_with_the_background():
    """robonano_a0ib's background holds EYX as a table; the example's EYX is a polynomial.
    Before, Lab(..., realism=Realism.lab()) refused the pair (so did the flagship scenario's
    --errors models/errors/example.toml); the lab's machine is now their sum."""
    lab = Lab("robonano_a0ib", "models/errors/example.toml", realism=Realism.lab())
    injected, own = lab.reveal(background=False), lab.reveal_background()
    x = np.linspace(-0.14, 0.14, 2801)
    machine_eyx = lab.reveal().component["X"]["EYX"].evaluate(x)
    expected = (injected.component["X"]["EYX"].evaluate(x)
                + own.component["X"]["EYX"].evaluate(x))
    np.testing.assert_allclose(machine_eyx, expected, rtol=0, atol=TABULATED_SUM)

