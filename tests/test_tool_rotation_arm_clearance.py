"""Paper 000's programs at the edge of their capture: how far over the work their rapids
pass (measured from the planned motion on the erroneous machine and the cut part), and
plans copied with another capture sized for it."""

from __future__ import annotations

import dataclasses
import math
import pickle

import pytest
from rapid_clearance import rapid_clearances

from machinesim import ErrorModel, load_machine
from machinesim.cam.prisms import APPROACH_MARGIN_M, CalibrationPlan, PrismPattern
from machinesim.cutting import cut
from machinesim.exceptions import InputError
from machinesim.identification.tool_rotation_arm import ArmEstimate, arm_radius
from machinesim.nc import format_program
from machinesim.procedures.tool_rotation_arm import (
    TOOL,
    ToolRotationArm,
    compensate_program,
    max_capture,
    pattern_clearance,
)

MM, UM, NM = 1e-3, 1e-6, 1e-9
MACHINE = load_machine("planer_4axis")
R0 = arm_radius(MACHINE)


def arm_errors(rho, e_ys):
    return ErrorModel().with_parameters({"tool.y": e_ys, "tool.z": -rho})


def least(clearances, what):
    return min(getattr(c, what) for c in clearances if getattr(c, what) is not None)


@pytest.mark.parametrize("degrees", [0.0, 40.0])
def test_the_calibration_rapids_keep_the_margin_over_the_block_at_the_captures_edge(degrees):
    """A ramp starts search = capture + 36 um over the block's top, and an edge offset of
    length capture, turned by the ramp's angle straight down, sinks the edge by the whole
    capture: the rapid down to the ramp's start ended 36 um + 8/9 nm over the top, whatever
    the capture. Now rapids come down to capture + 0.1 mm (`approach`) and the program
    feeds on: by hand the least height of the edge over the block in any rapid is
    approach - capture = 0.1 mm, and the tool's gap to the cut part the same (the block is
    uncut under the approach). Rapids across the block, at the clearance search + 0.5 mm,
    pass clearance - capture = 0.536 mm over it."""
    t = math.radians(degrees)
    plan = CalibrationPlan(angles=(t,))
    c = plan.capture
    rho, e_ys = c * math.cos(t), -c * math.sin(t)  # dz(t) = e_ys sin t - rho cos t = -c
    errors = arm_errors(rho, e_ys)
    program = plan.program(R0)
    part, report = cut(program, MACHINE, tool=TOOL, stock=plan.stock, errors=errors)
    assert report.rapids_that_cut == ()
    footprint = ((plan.origin[0], plan.origin[0] + plan.length),
                 (plan.origin[1], plan.origin[1] + plan.width))
    clearances = rapid_clearances(program, MACHINE, errors, TOOL, part, 0.0, footprint)
    assert plan.approach == c + 0.1 * MM
    assert least(clearances, "over_top") == pytest.approx(0.1 * MM, abs=1e-12)
    assert least(clearances, "gap") == pytest.approx(0.1 * MM, abs=1e-12)
    across = [k.over_top for k in clearances if k.over_top is not None
              and k.over_top > 0.2 * MM]
    assert min(across) == pytest.approx(plan.clearance - c, abs=1e-12)
    assert plan.clearance - c == pytest.approx(0.536 * MM, abs=1 * NM)


def test_the_uncompensated_patterns_rapids_keep_the_margin_at_the_largest_capture():
    """Touched off at 0 deg, the pattern's edge at 20 deg stands up to 2 c sin 10 deg lower
    than programmed (0.98909 mm at the largest capture, 2.848 mm), rapids too: at the
    pattern's 1 mm its last rapid back over the block passed 10.9 um over the top. By hand,
    with the clearance sized from the capture (`pattern_clearance`: that sink and 0.1 mm, up
    to the um, 1.090 mm), the edge passes 1.090 - 0.98909 = 0.1009 mm over the top; the
    tool's gap to the cut part is the clearance and the 10 um depth (the rapid runs back
    over the groove it cut, at the same angle and error)."""
    plan = CalibrationPlan(capture=max_capture())
    c, half = plan.capture, math.radians(10.0)
    pattern = ToolRotationArm(plan=plan).pattern
    sink = 2.0 * c * math.sin(half)
    assert pattern.clearance == pytest.approx(math.ceil((sink + 0.1 * MM) / UM) * UM,
                                              abs=1e-15)
    assert pattern.clearance == pytest.approx(1.090 * MM, abs=1e-15)
    # the offset of length c that sinks the edge most at 20 deg (against (1 - cos, sin))
    rho, e_ys = -c * math.sin(half), -c * math.cos(half)
    before = ArmEstimate(r0=R0, r=R0, e_ys=0.0, z_offset=-rho, y_offset=e_ys)
    program = compensate_program(pattern.program(R0), MACHINE, before)
    errors = arm_errors(rho, e_ys)
    part, report = cut(program, MACHINE, tool=TOOL, stock=pattern.stock, errors=errors)
    assert report.rapids_that_cut == ()
    footprint = ((pattern.origin[0], pattern.origin[0] + pattern.length),
                 (pattern.origin[1], pattern.origin[1] + pattern.width))
    clearances = rapid_clearances(program, MACHINE, errors, TOOL, part, 0.0, footprint)
    # the program is rounded to the machine's 1 nm
    assert least(clearances, "over_top") == pytest.approx(pattern.clearance - sink, abs=2 * NM)
    assert least(clearances, "over_top") > APPROACH_MARGIN_M
    assert least(clearances, "gap") == pytest.approx(pattern.clearance + pattern.depth,
                                                     abs=2 * NM)


def test_the_patterns_clearance_is_sized_from_the_capture_and_a_lower_one_refused():
    plan = CalibrationPlan()
    assert pattern_clearance(plan, PrismPattern()) == pytest.approx(0.448 * MM, abs=1e-15)
    assert ToolRotationArm().pattern == PrismPattern()  # 1 mm holds it: the figures stay
    big = CalibrationPlan(capture=2.8 * MM)  # 2 x 2.8 sin 10 deg + 0.1 = 1.0725 mm
    assert pattern_clearance(big, PrismPattern()) == pytest.approx(1.073 * MM, abs=1e-15)
    assert ToolRotationArm(plan=big).pattern == PrismPattern(height=1.083 * MM,
                                                             clearance=1.073 * MM)
    low = PrismPattern(height=1.083 * MM, clearance=1.072 * MM)
    with pytest.raises(InputError) as info:
        ToolRotationArm(plan=big, pattern=low)
    assert info.value.key == "pattern"
    message = str(info.value)
    assert "the pattern's rapids cross its block 0.001072 m up" in message
    assert "expected a clearance at least 0.001073 m (0.0001 m over the block's top)" in message
    assert "give the pattern clearance=0.001073" in message
    given = dataclasses.replace(low, clearance=1.073 * MM)
    assert ToolRotationArm(plan=big, pattern=given).pattern is given


def test_a_calibration_clearance_below_the_capture_and_margin_is_refused():
    """The rapids cross the block at the clearance: below capture + 0.1 mm an edge offset
    within the capture would take the edge closer to the block than the margin (it had
    only to be above the search range, capture + 36 um)."""
    with pytest.raises(InputError) as info:
        CalibrationPlan(clearance=1.05 * MM)
    assert info.value.key == "clearance"
    assert ("Expected a clearance at least 0.0011 m, the capture range 0.001 m and 0.0001 m"
            in str(info.value))
    assert CalibrationPlan(clearance=1.1 * MM).clearance == 1.1 * MM


def test_a_plan_copied_with_another_capture_is_derived_for_it():
    """dataclasses.replace hands every field back as given: a copy of the default plan with
    a 2.8 mm capture kept the 1 mm capture's search and block and was refused ('got
    0.003036000888888889 m: the ramps would cut out through the block's bottom', a height
    never given), and one with 0.1 mm kept search 1.036 mm and spacing 4.79 mm. What the
    plan derived is derived again; what was given stays."""
    for capture in (0.1 * MM, 2.8 * MM):
        copy = dataclasses.replace(CalibrationPlan(), capture=capture)
        fresh = CalibrationPlan(capture=capture)
        assert copy == fresh
        assert (copy.search, copy.clearance, copy.spacing, copy.height) == (
            fresh.search, fresh.clearance, fresh.spacing, fresh.height)
        assert format_program(copy.program(R0)) == format_program(fresh.program(R0))
    given = CalibrationPlan(spacing=6 * MM, height=5 * MM)
    copy = dataclasses.replace(given, capture=0.5 * MM)
    assert (copy.spacing, copy.height) == (6 * MM, 5 * MM)
    assert copy.search == CalibrationPlan(capture=0.5 * MM).search
    assert "search=0.001036000888888889, " in repr(CalibrationPlan())  # a float as before
    again = pickle.loads(pickle.dumps(CalibrationPlan()))
    assert again == CalibrationPlan() and repr(again) == repr(CalibrationPlan())
    assert dataclasses.replace(again, capture=2.8 * MM) == CalibrationPlan(capture=2.8 * MM)


def test_a_procedure_copied_with_another_plan_sizes_its_pattern_for_it():
    """ToolRotationArm sizes its default pattern from the plan's capture; dataclasses.replace
    handed that pattern to the copy as given: a 2.8 mm arm copied with the default plan kept
    its 1.083 mm block (and 1.073 mm clearance), the default arm copied with a 2.8 mm plan
    was refused as a block too thin for it. A pattern given stays as given."""
    small, big = CalibrationPlan(), CalibrationPlan(capture=2.8 * MM)
    assert dataclasses.replace(ToolRotationArm(plan=big), plan=small).pattern == PrismPattern()
    assert (dataclasses.replace(ToolRotationArm(), plan=big).pattern
            == ToolRotationArm(plan=big).pattern)
    given = PrismPattern(height=2 * MM, clearance=2 * MM)
    assert dataclasses.replace(ToolRotationArm(pattern=given), plan=big).pattern is given
