"""What the compensation (machinesim.compensation) refuses, naming what is wrong: a resolution
the NC text cannot carry, a function of the wrong shape, returning NaN, text or flags or not
callable, corrections past the travel or the room left inside it, an estimate given as the
identified model, arguments of the wrong kind, and values that are not finite."""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest
from compensation_helpers import grooves, tilted

from machinesim import ErrorModel, load_machine
from machinesim.compensation import map_program, model_based, rewrite, to_resolution
from machinesim.exceptions import AxisLimitError, InputError
from machinesim.nc import format_program, parse_program
from machinesim.units import RAD_PER_DEG

UM, MM, NM = 1e-6, 1e-3, 1e-9
DEG = RAD_PER_DEG
GROOVING = load_machine("grooving_4axis")
ROBONANO = load_machine("robonano_a0ib")


def test_a_resolution_the_nc_text_cannot_carry_names_the_file_joint_and_a_value_it_can(tmp_path):
    # 0.00001 deg written with four digits, 1.745e-7 rad, as a machine builder writes it:
    # 0.99983 increments; the message said "np.float64(1.745e-07)" and named neither the
    # URDF nor the element to mend
    from machinesim.machines import models_dir

    text = (models_dir() / "grooving_4axis.urdf").read_text()
    old = 'joint="C" resolution="1.7453292519943297e-07"'
    assert old in text
    path = tmp_path / "own.urdf"
    path.write_text(text.replace(old, 'joint="C" resolution="1.745e-07"'))
    with pytest.raises(InputError) as raised:
        to_resolution(np.zeros((1, 4)), load_machine(path))
    message = str(raised.value)
    assert f"{path}: <machinesim:axis joint='C'> resolution 1.745e-07 (rad)" in message
    assert "np.float64" not in message
    # the value offered is one increment, 0.00001 deg, as the NC text carries it
    offered = float(message.split("e.g. ")[1].split()[0])
    assert offered == 1e-5 * DEG


def test_a_function_of_the_wrong_shape_is_refused_naming_the_shape():
    with pytest.raises(InputError, match=r"shape \(6, 4\).*got shape \(6, 3\)"):
        map_program(grooves(), GROOVING, lambda q: q[:, :3])
    with pytest.raises(InputError, match=r"got shape \(4,\)"):
        map_program(grooves(), GROOVING, lambda q: q[0])
    with pytest.raises(InputError, match=r"must return an array of shape \(6, 4\).*got str"):
        map_program(grooves(), GROOVING, lambda q: "nonsense")


def test_a_function_returning_nan_is_refused_naming_the_block_and_axis():
    def function(q):
        q[3, 2] = np.nan
        return q

    where = r"grooves\.nc, line 8, key 'Z': "  # N40, the fourth motion block
    with pytest.raises(InputError, match=where + r".*returned nan for axis Z"):
        map_program(grooves(), GROOVING, function)


def test_rewrite_and_point_check_their_input():
    with pytest.raises(InputError, match=r"shape \(6, 4\).*got \(5, 4\)"):
        rewrite(grooves(), GROOVING, np.zeros((5, 4)))
    with pytest.raises(InputError, match="point must be 3 finite coordinates"):
        model_based(tilted(), ROBONANO, None, point=[0.0, 1.0])
    # a point 25 mm up the tool given in mm had been kept on the path as 25 m up; the
    # reach is the diagonal of robonano_a0ib's travel, 280 x 150 x 130 mm: 343.22 mm
    with pytest.raises(InputError, match=r"key 'point': expected the point at most 343\.22 mm "
                                         r"from tool_tip's origin .*got \[0\.0, 0\.0, 25\.0\], "
                                         r"25000 mm \(25 m\) from it"):
        model_based(tilted(), ROBONANO, None, point=[0.0, 0.0, 25.0])
    kept = model_based(tilted(), ROBONANO, None, point=[0.0, 0.0, 0.343])
    assert format_program(kept.program) == format_program(model_based(tilted(), ROBONANO,
                                                                       None).program)


def test_a_correction_past_the_travel_is_refused_naming_the_lines():
    # Z at the top of robonano_a0ib's travel (100 mm), where a G28 or the home puts it: a
    # tool 1 um short needs Z 1 um higher, which the machine cannot give
    from machinesim.exceptions import AxisLimitError

    machine = load_machine("robonano_a0ib")
    program = parse_program("G90 G21\nG00 X0. Y0. Z100. B0. C0.\nG00 Z1.\nG01 Z0. F10.\n"
                            "G00 Z100.\nM30\n")
    short = ErrorModel.from_dict({"tool": {"offset_um": [0.0, 0.0, -1.0]}})
    with pytest.raises(AxisLimitError, match=r"line 2: .*axis Z to 100\.001000 mm.*the "
                                             r"program had 100\.000000 mm.*2 line\(s\).*2, 5"
                                             r".*reference position \(G28\)"):
        model_based(program, machine, short)
    with pytest.raises(AxisLimitError, match=r"axis X to 1000\.000000 mm.*larger than the room"):
        map_program(program, machine, lambda q: q + [1.0, 0.0, 0.0, 0.0, 0.0])
    # the poses a five-axis machine cannot turn the tool to are told once per direction
    tilted = ErrorModel.from_dict({"workpiece": {"alpha_deg": 1.0}})
    result = model_based(parse_program("G90 G21\nG00 X0. Y0. Z1. B0. C0.\nG01 Z0. F10.\n"
                                       "G01 X1.\n"), machine, tilted)
    assert result.unmatched.count("cannot turn the tool about X") == 1
    assert "at 3 poses" in result.unmatched


def test_an_estimate_or_values_by_name_given_as_the_identified_model_say_how_to_give_them():
    # A newcomer hands model_based what fit returns, or its as_dict: the messages had said
    # only "got Estimate" and "unknown section; expected one of tool, ...", and named the
    # argument 'errors' (Lab's and cut's name), where model_based's is 'identified'.
    from machinesim.exceptions import ErrorModelError
    from machinesim.identification import fit, observations

    q = np.zeros((4, 5))
    q[:, 4] = np.arange(4) * 90 * DEG
    u = np.tile(np.eye(3), (4, 1))
    truth = ErrorModel().with_parameters({"location.C.EX0C": 2 * UM})
    readings = np.einsum("ni,ni->n", u, ROBONANO.tool_pose(np.repeat(q, 3, axis=0), truth)
                         [:, :3, 3] - ROBONANO.tool_pose(np.repeat(q, 3, axis=0))[:, :3, 3])
    estimate = fit(ROBONANO, observations(np.repeat(q, 3, axis=0), directions=u,
                                          values=readings, sigma=50 * NM), ["location.C.EX0C"])
    with pytest.raises(ErrorModelError, match=r"got Estimate \(its identified model is "
                                              r"Estimate.errors\)") as refused:
        model_based(tilted(), ROBONANO, estimate)
    assert refused.value.key == "identified"  # its argument's name; it had said 'errors'
    with pytest.raises(ErrorModelError, match=r"key 'location.C.EX0C': unknown section; .*"
                                              r"ErrorModel\(\).with_parameters"):
        model_based(tilted(), ROBONANO, {"location.C.EX0C": 2 * UM})
    # the way the messages give is the truth's compensation
    by_name = ErrorModel().with_parameters({"location.C.EX0C": 2 * UM})
    assert format_program(model_based(tilted(), ROBONANO, estimate.errors).program) == \
        format_program(model_based(tilted(), ROBONANO, by_name).program)


@pytest.mark.parametrize("given, match", [
    ({"start": "home"}, r"key 'start': Expected start as axis values \(m, rad\), got 'home'"),
    ({"start": [0.0, "1", 0.0, 0.0, 0.0]}, "Expected start as axis values"),
    ({"point": "tip"}, r"key 'point': Expected point as 3 coordinates \(m\) in the tool_tip "
                       r"frame, got 'tip'"),
    ({"program": "tilted.nc"}, r"key 'program': expected the program as a "
                               r"machinesim.nc.Program, got str 'tilted.nc'; read an NC file "
                               r"with machinesim.nc.read_program\(path\)"),
])
def test_a_start_point_or_program_of_the_wrong_kind_is_refused_naming_it(given, match):
    # each had raised numpy's ValueError ("could not convert string to float: 'home'") or
    # AttributeError ("'str' object has no attribute 'targets'"), tracebacks naming nothing
    arguments = {"program": tilted(), "start": None, "point": None} | given
    program = arguments.pop("program")
    with pytest.raises(InputError, match=match):
        model_based(program, ROBONANO, None, **arguments)
    if "point" not in given:
        with pytest.raises(InputError, match=match):
            map_program(program, ROBONANO, lambda q: q, start=arguments["start"])


def test_a_correction_past_the_room_left_inside_the_travel_blames_the_errors_not_a_g28():
    # X runs 1 um inside robonano_a0ib's +140 mm end; at C = 90 deg C's line offset EX0C =
    # 4 um takes X 4 um further out (the offset turned by C), past the end. The message had
    # said the G28 or a start at the limit was the usual cause (any value within 1 mm of
    # the end counted as at it); the room is 1 um and the correction 4 um
    from machinesim.exceptions import AxisLimitError

    program = parse_program("G90 G21\nG00 X0. Y0. Z1. B0. C0.\nG01 X139.999 F100.\nC90.\n"
                            "M30\n", "edge.nc")
    offset = ErrorModel().with_parameters({"location.C.EX0C": 4 * UM})
    with pytest.raises(AxisLimitError, match=r"edge.nc, line 4: .*axis X to 140\.003000 mm.*"
                                             r"the program had 139\.999000 mm.*larger than "
                                             r"the room the axis has there"):
        model_based(program, ROBONANO, offset)


@pytest.mark.parametrize("rounded", ["False", "no", 0, None])
def test_rounded_takes_true_or_false_only(rounded):
    # rounded="False" (or "no") had been taken as true and the program rounded, the opposite
    # of what was asked, with nothing said
    with pytest.raises(InputError, match=rf"key 'rounded': Expected rounded as True or False, "
                                         rf"got {re.escape(repr(rounded))}"):
        model_based(tilted(), ROBONANO, None, rounded=rounded)
    with pytest.raises(InputError, match="Expected rounded as True or False"):
        map_program(tilted(), ROBONANO, lambda q: q, rounded=rounded)


def test_rewrite_refuses_values_that_are_not_finite_naming_the_line_and_axis():
    # NaN in a row had been written as "no word" and refused by the program as "move 1 drops
    # axis X from its target; targets are modal ...", which names no NaN
    program = parse_program("G90 G21\nG00 X0. Y0. Z1. B0. C0.\nG01 Z0. F10.\nG01 X5.\nM30\n",
                            "u.nc")
    q = np.zeros((3, 5))
    q[1, 0], q[2, 1] = np.nan, np.inf
    with pytest.raises(InputError, match=r"u.nc, line 3, key 'X': axis X of this motion block "
                                         r"is given as nan \(2 value\(s\) not finite\)"):
        rewrite(program, ROBONANO, q)


def test_a_function_that_cannot_be_called_or_returns_text_or_flags_is_refused():
    # map_program(program, machine, 5) ended in TypeError: 'int' object is not callable; a
    # function returning q > 0 (flags) or text was converted, True as 1 m, "1e-3" as 1 mm
    with pytest.raises(InputError, match=r"expected the compensation as a function q -> "
                                         r"q_compensated .* got int;") as info:
        map_program(grooves(), GROOVING, 5)
    assert info.value.key == "function"
    with pytest.raises(InputError, match=r"must return an array of shape \(6, 4\).*of "
                                         r"numbers, got an array of bool"):
        map_program(grooves(), GROOVING, lambda q: q > 0)
    with pytest.raises(InputError, match=r"of numbers, got an array of str"):
        map_program(grooves(), GROOVING, lambda q: q.astype(str))
    listed = map_program(grooves(), GROOVING, lambda q: q.tolist(), rounded=False)  # a list
    same = map_program(grooves(), GROOVING, lambda q: q, rounded=False)
    assert np.array_equal(listed.targets, same.targets, equal_nan=True)


def test_a_complex_function_output_is_refused_without_numpy_s_warning_first():
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a ComplexWarning had come out before the refusal
        with pytest.raises(InputError, match=r"of numbers, got an array of complex128"):
            map_program(grooves(), GROOVING, lambda q: q + 0j)


@pytest.mark.parametrize("q, match", [
    ([[0.0, 0.0, np.nan, 0.0]], r"expected finite axis values \(m, rad\), got "
                                r"\[\[0\.0, 0\.0, nan, 0\.0\]\]"),
    ("x", r"Expected q as axis values \(m, rad\), got 'x'"),
    ([["0", "0", "0", "0"]], r"Expected q as axis values"),
])
def test_to_resolution_refuses_what_no_nc_word_carries(q, match):
    # NaN had come back NaN, and text raised numpy's ValueError naming no argument
    with pytest.raises(InputError, match=match) as info:
        to_resolution(q, GROOVING)
    assert info.value.key == "q"
    # a value it rounds: 1.23456789 mm on X to the 1 nm grid, the float the word X1.234568 reads
    assert to_resolution([1.23456789e-3, 0.0, 0.0, 0.0], GROOVING)[0] == float("1.234568") * MM


def test_a_start_outside_the_travel_is_refused_on_both_routes_naming_it():
    # start=[0, 0, 0.1, 90] (C in deg) had been written, 90 rad, into N10, the block before
    # the grooves' first C word: a program beyond C's one turn each way (360 deg), taken
    start = [0.0, 0.0, 0.1, 90.0]
    said = (r"^grooves\.nc: start: axis C = 5156\.62016 deg outside its travel -360\.00000 "
            r"deg \.\. 360\.00000 deg: an axis stays there, in every block written, until "
            r"the program moves it \(start is in m and rad, in the order XYZC\)")
    with pytest.raises(AxisLimitError, match=said):
        model_based(grooves(), GROOVING, None, start=start)
    with pytest.raises(AxisLimitError, match=said):
        map_program(grooves(), GROOVING, lambda q: q, start=start)
    with pytest.raises(InputError, match=r"start must have shape \(4,\)") as info:
        model_based(grooves(), GROOVING, None, start=[0.0, 0.0, 0.1])
    assert info.value.key == "start"
    home = model_based(grooves(), GROOVING, None, start=GROOVING.home).program
    assert home.targets[1, 1] == 0.0 and home.targets[1, 5] == 0.0  # N10's Y and C: the home's

