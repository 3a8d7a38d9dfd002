"""The procedures' plans (ProbePlan, tool_setting_plates.Plan, ProgramPlan, TestSphere,
TestPlane) check every field by the shared checks of `machinesim.metrology._arrays`
(`as_number`, `as_count`): a bool is no 1 m, a numpy number is a number."""

from __future__ import annotations

import math

import numpy as np
import pytest

from machinesim.cam.tool_setting_plates import Plan
from machinesim.exceptions import InputError
from machinesim.procedures import sts_plans as sts
from machinesim.procedures.sphere_probing import ProbePlan
from machinesim.procedures.sts_plans import ProgramPlan
from machinesim.procedures.tool_rotation_arm import CalibrationPlan

CA = {"distribution": "CA", "step": 0.01}
# sts.TestSphere, not imported by its name: pytest would collect a class named Test*


@pytest.mark.parametrize("plan, fields, key, message", [
    # True passed isinstance(int | float) as 1 m / 1 mm/min: taken
    (ProbePlan, {"half_width": True}, "half_width",
     "Expected half_width as a number (m), got True"),
    (Plan, {"depth": True}, "depth", "Expected depth as a number (m), got True"),
    (Plan, {"feed_mm_per_min": True}, "feed_mm_per_min",
     "Expected feed_mm_per_min as a number (mm/min), got True"),
    # ProgramPlan was not checked: step True made 1571 steps of 1 rad, 'cubic' was linear,
    # substeps True or 0 taken
    (ProgramPlan, {**CA, "step": True}, "step", "Expected step as a number (rad), got True"),
    (ProgramPlan, {"distribution": "CAL", "step": -1e-6}, "step",
     "Expected step > 0 (m), got -1e-06"),
    (ProgramPlan, {**CA, "interpolation": "cubic"}, "interpolation",
     "Expected interpolation 'linear' or 'spline', got 'cubic'"),
    (ProgramPlan, {**CA, "substeps": True}, "substeps",
     "Expected substeps as a whole number >= 1, got True"),
    (ProgramPlan, {**CA, "substeps": 0}, "substeps",
     "Expected substeps as a whole number >= 1, got 0"),
    # the test pieces were not checked until their path was made (radius True: a 1 m sphere)
    (sts.TestSphere, {"radius": True}, "radius", "Expected radius as a number (m), got True"),
    (sts.TestSphere, {"pixel": True}, "pixel", "Expected pixel as a number (m), got True"),
    (sts.TestSphere, {"core_step": "1"}, "core_step",
     "Expected core_step as a number (m), got '1'"),
    (sts.TestSphere, {"read_half_width": math.nan}, "read_half_width",
     "Expected read_half_width > 0 (m), got nan"),
    (sts.TestPlane, {"slope": True}, "slope", "Expected slope as a number (m per m), got True"),
    (sts.TestPlane, {"core": -1.0}, "core", "Expected core >= 0 (m), got -1.0"),
    (sts.TestPlane, {"top": math.inf}, "top", "Expected top >= 0 (m), got inf"),
])
def test_a_plan_field_that_is_no_number_of_it_is_refused_naming_it(plan, fields, key, message):
    with pytest.raises(InputError) as info:
        plan(**fields)
    assert info.value.key == key
    assert str(info.value) == f"key '{key}': {message}"


def test_numpy_numbers_are_numbers_of_the_plans():
    """np.int64(41) points was 'Expected points an int >= 5, got np.int64(41)', np.float32
    lengths 'Expected half_width > 0 (m), got np.float32(...)': refused as what they are
    not. They are kept as the int / float of the same value."""
    plan = ProbePlan(points=np.int64(41), passes=np.int32(3), half_width=np.float32(2 ** -10))
    assert (plan.points, plan.passes, plan.half_width) == (41, 3, 2 ** -10)
    assert type(plan.points) is int and type(plan.half_width) is float
    assert ProbePlan(points=np.int64(41)) == ProbePlan()
    plates = Plan(depth=np.float32(2 ** -17), feed_mm_per_min=np.int64(200))
    assert plates.depth == 2 ** -17 and plates.feed_mm_per_min == 200.0
    program = ProgramPlan("CA", np.float64(0.01), substeps=np.int64(10))
    assert program == ProgramPlan("CA", 0.01) and type(program.substeps) is int
    assert sts.TestSphere(radius=np.float32(0.5)).radius == 0.5
    with pytest.raises(InputError, match=r"points as a whole number >= 5, got 41\.0"):
        ProbePlan(points=41.0)


@pytest.mark.parametrize("make, key, message", [
    (lambda: ProbePlan(half_width=10**400), "half_width",
     "Expected a finite half_width (m), got an int of 1329 bits, beyond float64"),
    (lambda: Plan(depth=-10**400), "depth",
     "Expected a finite depth (m), got an int of 1329 bits, beyond float64"),
    (lambda: CalibrationPlan(angles=(0.0, 10**400)), "angles",
     "Expected angles as tool angles (rad) within float64's range, got an int too large to "
     "convert"),
])
def test_an_int_beyond_float64_is_refused_naming_its_field(make, key, message):
    """A Python int has no bound: 10**400 (1329 bits) went to float() and raised Python's
    OverflowError ('int too large to convert to float'), a traceback naming no field."""
    with pytest.raises(InputError) as info:
        make()
    assert info.value.key == key
    assert str(info.value) == f"key '{key}': {message}"
