"""Paper 001 replay, plans and refusals: tilts eqs 1-2 or the B axis cannot take, Python
arguments of the wrong kind, an evaluation without what identify and compensate give,
end faces and plates read past the capture range, and the plates' bounds."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from tool_setting_6axis_helpers import errors_of

from machinesim import ErrorModel, Lab, load_machine
from machinesim.cam.tool_setting_plates import Plan, b_depth_range, b_tilt_limit
from machinesim.exceptions import InputError
from machinesim.experiment import Identified
from machinesim.identification import tool_setting_6axis as ident
from machinesim.procedures.tool_setting_6axis import ToolSetting6Axis
from machinesim.realism import Realism

UM, MM = 1e-6, 1e-3
MACHINE = load_machine("robonano_ui")


@pytest.mark.parametrize(("fields", "message"), [
    ({"theta2": 0}, "key 'theta2': Expected a non-zero B tilt: eqs 1-2 of paper 001 take dX "
     "and dZ from the depth changes at two distinct non-zero tilts, got theta2 = 0 rad "
     "(0 deg), theta3 = -0.34906585 rad (-20 deg)"),
    ({"theta3": math.radians(20)}, "key 'theta3': Expected a B tilt other than theta2 (two "
     "distinct tilts): eqs 1-2 of paper 001 take dX and dZ from the depth changes at two "
     "distinct non-zero tilts, got theta2 = 0.34906585 rad (20 deg), theta3 = 0.34906585 rad "
     "(20 deg)"),
    # degrees where radians are expected: beyond robonano_ui's B travel of +-100 deg (URDF)
    ({"theta2": 20}, "key 'theta2': Expected theta2 within the B travel of robonano_ui, "
     "-1.74533 .. 1.74533 rad (-100 .. 100 deg), got 20 rad (1145.92 deg); the angles are in "
     "rad: 20 deg is math.radians(20) = 0.349066 rad"),
    ({"theta3": -1.8}, "key 'theta3': Expected theta3 within the B travel of robonano_ui, "
     "-1.74533 .. 1.74533 rad (-100 .. 100 deg), got -1.8 rad (-103.132 deg)"),
    ({"theta2": "a"}, "key 'theta2': Expected theta2 as a finite angle in rad (the B axis of "
     "robonano_ui), got 'a'"),
    ({"theta1": math.nan}, "key 'theta1': Expected theta1 as a finite angle in rad (the A "
     "axis of robonano_ui), got nan"),
    # the tool's X at A = 0 runs along the B grooves' Y path in its own edge plane: the B
    # plate was cut empty (0 mm^3) and read as errors beyond the capture range
    ({"theta1": 0.0}, "key 'theta1': Expected theta1 turning the tool's cutting direction "
     "(its own X) onto Y, +-90 or +-270 deg within 1 deg (the B grooves run along Y), got "
     "0 rad (0 deg): the V tool would be dragged 90 deg sideways"),
    ({"theta1": math.radians(60)}, "key 'theta1': Expected theta1 turning the tool's cutting "
     "direction (its own X) onto Y, +-90 or +-270 deg within 1 deg (the B grooves run along "
     "Y), got 1.04719755 rad (60 deg): the V tool would be dragged 30 deg sideways"),
])
def test_a_plan_refuses_tilts_eqs_1_2_or_the_b_axis_cannot_take(fields, message):
    """Checked when the Plan is made, not after the plates are cut (minutes later)."""
    with pytest.raises(InputError) as caught:
        Plan(**fields)
    assert str(caught.value) == message


def test_a_plan_takes_any_two_distinct_tilts_its_b_plate_reads():
    limit = b_tilt_limit(Plan().b_depth) * (1.0 - 1e-9)
    plan = Plan(theta2=limit, theta3=-limit, theta1=-math.pi / 2)
    assert plan.tilts == (0.0, limit, -limit)
    assert Plan(theta2=np.float64(0.1), theta3=0.2).theta3 == 0.2
    for theta1 in (-0.5, 0.5, 1.5, -1.5, 0.5 + 0.99 / 180):  # turns, the last 0.99 deg off
        assert Plan(theta1=theta1 * math.pi).theta1 == theta1 * math.pi


@pytest.mark.parametrize(("call", "message"), [
    (lambda: ToolSetting6Axis().measure(None), "key 'lab': expected a machinesim.Lab to run "
     "on, got NoneType None (make one with Lab(machine, errors, seed=...))"),
    (lambda: ToolSetting6Axis().identify({}), "key 'measurements': ToolSetting6Axis.identify "
     "expects the measurements ToolSetting6Axis.measure(lab) returned (a Readings), got dict "
     "{}"),
    (lambda: ToolSetting6Axis().compensate(Identified({}, None)), "key 'identified': "
     "ToolSetting6Axis.compensate expects the Identified ToolSetting6Axis.identify"
     "(measurements) returned, its detail an Identification, got an Identified whose detail "
     "is NoneType None"),
    (lambda: ToolSetting6Axis(plan=None), "key 'plan': expected a Plan "
     "(machinesim.cam.tool_setting_plates), e.g. Plan(), got NoneType None"),
    (lambda: ToolSetting6Axis(machine=5), "key 'machine': expected the name of a 6-axis X Y Z "
     "A B C machine, e.g. 'robonano_ui', got int 5"),
])
def test_the_python_api_refuses_arguments_of_the_wrong_kind(call, message):
    """Each was a bare AttributeError from deep inside."""
    with pytest.raises(InputError) as caught:
        call()
    assert str(caught.value) == message


SIX_PROGRAMS = ("key 'programs': ToolSetting6Axis.evaluate expects the programs "
                "ToolSetting6Axis.compensate(identified) returned (a dict of "
                "'04_a_axis_compensated' (a Program), '05_c_axis_compensated' (a Program) and "
                "'06_b_axis_compensated' (a Program)), got ")


@pytest.mark.parametrize(("detail", "programs", "message"), [
    ("found", {}, "key 'identified': ToolSetting6Axis.evaluate expects the Identified "
     "ToolSetting6Axis.identify(measurements) returned, its detail an Identification, got an "
     "Identified whose detail is str 'found'"),
    (None, {}, SIX_PROGRAMS + "a dict without '04_a_axis_compensated', "
     "'05_c_axis_compensated' and '06_b_axis_compensated'"),
    (None, [], SIX_PROGRAMS + "list []"),
    (None, {"04_a_axis_compensated": None, "05_c_axis_compensated": None,
            "06_b_axis_compensated": None},
     SIX_PROGRAMS + "a dict whose '04_a_axis_compensated' is NoneType None"),
])
def test_evaluate_refuses_what_identify_and_compensate_did_not_give(detail, programs, message):
    """evaluate without compensate's programs raised KeyError '04_a_axis_compensated' (after
    cutting the plates measure cut again, when the detail holds them), a list a TypeError,
    None in place of a program the cutter's refusal (key 'program', no step named), another
    detail a refusal naming no step: now each names the step and is refused before anything
    is cut (machinesim.procedures.step_inputs)."""
    if detail is None:  # the kind identify gives, with no readings
        detail = ident.Identification(0.0, None, None, None, None)
    lab = Lab(MACHINE, ErrorModel(), noise=False)
    with pytest.raises(InputError) as caught:
        ToolSetting6Axis().evaluate(lab, Identified({}, detail), programs)
    assert str(caught.value) == message


def test_an_end_face_missed_names_where_it_looked_and_the_capture_range():
    """dx = 2 mm, four times the plan's range, through the Python API (the scenario refuses
    it before cutting): the message showed numpy's "[5.235 0.   ] mm" and no range. With the
    noise off the profile there is flat (its heights span 0 nm); with a noisy lab (Realism
    lab, seed 0) it said "found 611" end faces, every crossing of the noise's mid level."""
    where = ("A axis, groove at A = 0, C = 0 deg: expected one end face within 0.335 mm of "
             "(x, y) = (5.235, {y}) mm along the groove, found none: nothing stands out of the "
             "surface's noise there (its heights span {span} nm; an end face is a step of the "
             "10 um cut depth); the errors may exceed the plan's capture range (|dx|, |dy|, "
             "|dz| <= 0.5 mm, |e| <= 1 mm)")
    lab = Lab(MACHINE, errors_of([2 * MM, 0.0, 0.0], [0.0, 0.0]), noise=False)
    with pytest.raises(InputError) as caught:
        ToolSetting6Axis().measure(lab)
    assert str(caught.value) == where.format(y=0, span=0)
    lab = Lab(MACHINE, errors_of([2 * MM, 0.0, 0.0], [0.0, 0.0]), seed=0,
              realism=Realism.lab())
    with pytest.raises(InputError) as caught:
        ToolSetting6Axis().measure(lab)
    span = re.search(r"span (\d+) nm", str(caught.value))
    # the microscope's noise: tens to hundreds of nanometres, far below the 10 um face
    assert span is not None and 10 <= int(span[1]) <= 1000, str(caught.value)
    assert str(caught.value) == where.format(y=-0.0008, span=span[1])


def test_a_plate_read_past_a_plan_names_the_plan_beside_the_capture_range():
    """A plan that is not the paper's, with errors beyond the capture range (dx = 2 mm):
    the refusal names the plan's fields that are not the paper's beside the range (it had
    said only 'the errors may exceed the plan's capture range'). A plan the layout cannot
    read within the range (depth 40 um, whose V is as wide as the profiles that follow the
    A grooves: they lost it at 5.5 mm) is now refused when it is made
    (test_a_plan_refuses_what_its_plates_cannot_read_naming_the_range)."""
    lab = Lab(MACHINE, errors_of([2 * MM, 0.0, 0.0], [0.0, 0.0]), noise=False)
    with pytest.raises(InputError) as caught:
        ToolSetting6Axis(plan=Plan(depth=39 * UM)).measure(lab)
    assert str(caught.value).endswith(
        "an end face is a step of the 39 um cut depth); the errors may exceed the plan's "
        "capture range (|dx|, |dy|, |dz| <= 0.5 mm, |e| <= 1 mm), or the plan's depth = 39 "
        "um (not the paper's) beyond what the plates' layout and reading windows are sized "
        "for"), str(caught.value)


CAPTURE = ("over the capture range |dx|, |dy|, |dz| <= 0.5 mm, |e| <= 1 mm")


@pytest.mark.parametrize(("fields", "message"), [
    # robonano_ui's linear axes: velocity 0.025 m/s in its URDF, 1500 mm/min; F1e7 had been
    # written into the programs and run at the limit without a word
    ({"feed_mm_per_min": 1500.001}, "key 'feed_mm_per_min': Expected feed_mm_per_min up to "
     "1500 mm/min, the velocity limit of robonano_ui's linear axes (its URDF), got 1500.001 "
     "mm/min"),
    # the feed as given, not rounded to the limit it passes ('up to 1500 ..., got 1500')
    ({"feed_mm_per_min": 1500 + 1e-9}, "key 'feed_mm_per_min': Expected feed_mm_per_min up "
     "to 1500 mm/min, the velocity limit of robonano_ui's linear axes (its URDF), got "
     "1500.000000001 mm/min"),
    ({"depth": 40 * UM}, "key 'depth': Expected depth below 40 um, got 40 um: the 90-deg V of "
     "depth D is 2 D wide and the profiles that follow the A grooves to their ends are 80 um "
     "wide (TRACK_WINDOW)"),
    ({"b_depth": 460 * UM}, "key 'b_depth': Expected b_depth below 450 um, got 460 um: the "
     "B = 0 groove, 2 D wide, would fill the 0.9 mm profiles across it (B_WINDOW)"),
    # the B travel is +-100 deg, and 60 deg had been taken; from 45 deg on the V's lower
    # flank lies on the plate
    ({"theta2": math.radians(60)}, "key 'theta2': Expected theta2 within +-23.07 deg for "
     f"b_depth = 40 um (at 60 deg no b_depth, {CAPTURE}), got 1.04719755 rad (60 deg): the "
     "tilted V reaches beyond the profiles across it where dz = +0.5 mm"),
    ({"theta3": math.radians(-25)}, "key 'theta3': Expected theta3 within +-23.07 deg for "
     f"b_depth = 40 um (at 25 deg no b_depth, {CAPTURE}), got -0.436332313 rad (-25 deg): the "
     "groove is not cut where dz = -0.5 mm"),
    ({"b_depth": 110 * UM}, "key 'theta2': Expected theta2 within +-19.22 deg for b_depth = "
     f"110 um (at 20 deg b_depth 30.15 .. 99.94 um, {CAPTURE}), got 0.34906585 rad (20 deg): "
     "the tilted V reaches beyond the profiles across it where dz = +0.5 mm"),
])
def test_a_plan_refuses_what_its_plates_cannot_read_naming_the_range(fields, message):
    """Depths, tilts and feed had been taken up to the B travel (+-100 deg) and any size:
    the plates were cut and then a reading found no groove, naming the plan without a
    bound. Each is refused when the plan is made, with the range that works."""
    with pytest.raises(InputError) as caught:
        Plan(**fields)
    assert str(caught.value) == message
    assert Plan(feed_mm_per_min=1500.0).feed_mm_per_min == 1500.0


def test_the_b_plates_bounds_are_its_grooves_geometry():
    """By hand, R = 0.5 mm of dz and the 0.45 mm half window: at 20 deg the groove is cut
    where dz = -R from D = R (1 - cos 20) = 30.154 um, and the tilted V, D + that deep, with
    its edge R sin 20 = 171.0 um off, reaches D + 30.154 um times tan 65 deg to one side:
    within 450 um up to D = (450 - 171.01) / 2.1445 - 30.154 = 99.94 um. At D = 40 um the
    lower bound binds: cos t = 1 - 40 / 500, t = 23.0739 deg (the bisection's)."""
    lower, upper = b_depth_range(math.radians(20))
    assert lower == pytest.approx(500 * UM * (1 - math.cos(math.radians(20))), rel=1e-12)
    assert lower / UM == pytest.approx(30.154, abs=1e-3)
    assert upper / UM == pytest.approx(99.94, abs=1e-2)
    assert b_tilt_limit(40 * UM) == pytest.approx(math.acos(1 - 40 / 500), abs=1e-11)
    assert b_depth_range(math.radians(45)) == (0.0, 0.0) and b_tilt_limit(450 * UM) == 0.0


@pytest.mark.parametrize("fields", [
    {"theta2": math.radians(22), "theta3": math.radians(-22)},  # 23.07 deg the bound
    {"b_depth": 90 * UM},  # 99.94 um the bound at 20 deg
    {"depth": 39 * UM},  # below 40 um
])
def test_a_plan_within_its_bounds_is_read_at_the_capture_ranges_corners(fields):
    """The bounds hold over the capture range, not only for the default errors: at its
    corner (d = (500, -500, +-500) um, e = (600, -800) um, noise off) each of these plans
    is read. Past them it was not: at 25 deg with dz = -0.5 mm the B plate 'found 0'
    grooves, at b_depth 110 um with dz = +0.5 mm too (old code, by hand)."""
    for dz in (500 * UM, -500 * UM):
        lab = Lab(MACHINE, errors_of([500 * UM, -500 * UM, dz], [600 * UM, -800 * UM]),
                  noise=False)
        readings = ToolSetting6Axis(plan=Plan(**fields)).measure(lab)
        assert len(readings.b) == 3
