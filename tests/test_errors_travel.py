"""Errors over an axis's travel: a polynomial's largest value (against a dense grid) held to
the bound over the travel, on a rotary axis too and refused on a spindle; values beyond
float64; a table out of order or of a whole turn; positions without a table; angles at
the bound read back; a value beyond the bound told in mm or deg first."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from machinesim.errors import ComponentError, ErrorModel, ToolSetting
from machinesim.exceptions import ErrorModelError

EXAMPLE = Path(__file__).resolve().parents[1] / "models" / "errors" / "example.toml"


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
