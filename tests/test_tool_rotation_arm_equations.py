"""Paper 000's equations and fits (`machinesim.identification.tool_rotation_arm`): eqs 1 and 2
are the erroneous machine, compensation lands on the nominal path, `fit_arm` and the
generic fit agree on exact readings, calibration plans refuse what is no number of them,
`fit_apexes` reads shared ridges, and a machine whose A axis is no arm is refused."""

from __future__ import annotations

import math

import numpy as np
import pytest
from tool_rotation_arm_helpers import PAPER_E, PAPER_R, errors_for

from machinesim import ErrorModel, Lab, load_machine
from machinesim.cam.prisms import CalibrationPlan, PrismPattern
from machinesim.exceptions import InputError
from machinesim.identification import tool_rotation_arm as arm
from machinesim.metrology import fit_apexes
from machinesim.procedures import tool_rotation_arm as procedure
from machinesim.procedures.tool_rotation_arm import (
    AngleReading,
    ToolRotationArm,
    compensate_program,
)

MM, UM, NM = 1e-3, 1e-6, 1e-9
#: Kinematic round-off: sums and products of ~0.12 m quantities in float64 (ulp 1.4e-17 m)
#: through a chain of ~10 transforms.
KINEMATIC_TOL = 1e-15


@pytest.fixture(scope="module")
def machine():
    return load_machine("planer_4axis")


@pytest.fixture(scope="module")
def r0(machine):
    return arm.arm_radius(machine)


def test_the_nominal_program_puts_the_nominal_edge_where_asked(machine, r0):
    assert r0 == pytest.approx(120.5 * MM, abs=KINEMATIC_TOL)  # docs/machines.md
    rng = np.random.default_rng(0)
    for _ in range(20):
        x, y, z = rng.uniform(-5 * MM, 5 * MM, 3)
        t = rng.uniform(-math.radians(40), math.radians(40))
        Y, Z = arm.nominal_axes(y, z, t, r0)
        pose = machine.tool_pose([x, Y, Z, t])
        np.testing.assert_allclose(pose[:3, 3], [x, y, z], rtol=0, atol=KINEMATIC_TOL)


def test_equations_1_and_2_are_the_erroneous_machine(machine, r0):
    """Eqs 1-2 (derived, the paper's print lost them) against the kinematic chain."""
    rng = np.random.default_rng(1)
    for _ in range(5):
        r, e = r0 + rng.uniform(-0.1, 0.1) * MM, rng.uniform(-0.3, 0.3) * MM
        errors = errors_for(r, e, r0)
        truth = arm.ArmEstimate(r0=r0, r=r, e_ys=e, z_offset=-(r - r0), y_offset=e)
        landed = []
        for t in np.radians([0.0, 7.0, 10.0, 20.0, 33.0, 40.0]):
            Y, Z = arm.nominal_axes(1 * MM, -10 * UM, t, r0)
            position = machine.tool_pose([0.0, Y, Z, t], errors)[:3, 3]
            landed.append(position[1:] - [1 * MM, -10 * UM])
            np.testing.assert_allclose(truth.edge_error(t), landed[-1], rtol=0,
                                       atol=KINEMATIC_TOL)
            change = landed[-1] - landed[0]
            assert arm.height_change(t, r, e, r0) == pytest.approx(change[1],
                                                                       abs=KINEMATIC_TOL)
            assert arm.lateral_change(t, r, e, r0) == pytest.approx(change[0],
                                                                        abs=KINEMATIC_TOL)
    # the paper's numbers: at 20 deg the edge drops by more than 50 um (the grooves deepen)
    drop = -arm.height_change(math.radians(20), PAPER_R, PAPER_E, r0)
    assert drop == pytest.approx(0.178 * math.sin(math.radians(20)) * MM
                                 - 0.055 * (1 - math.cos(math.radians(20))) * MM, rel=1e-12)
    assert drop > 50 * UM


def test_compensation_lands_every_move_on_the_nominal_path(machine, r0):
    r, e = r0 + 0.07 * MM, -0.21 * MM
    errors = errors_for(r, e, r0)
    truth = arm.ArmEstimate(r0=r0, r=r, e_ys=e, z_offset=-(r - r0), y_offset=e)
    nominal = PrismPattern().program(r0)
    # the paper's formulas exactly (rounded=False): every move lands on the nominal path
    compensated = compensate_program(nominal, machine, truth, rounded=False)
    assert [m.kind for m in compensated] == [m.kind for m in nominal]
    assert [m.feed_m_per_s for m in compensated] == [m.feed_m_per_s for m in nominal]
    axes = ("X", "Y", "Z", "A")
    q_nominal = np.array([[m.target.get(a, 0.0) for a in axes] for m in nominal])
    q_compensated = np.array([[m.target.get(a, 0.0) for a in axes] for m in compensated])
    np.testing.assert_allclose(machine.tool_pose(q_compensated, errors),
                               machine.tool_pose(q_nominal), rtol=0, atol=KINEMATIC_TOL)
    # as the NC program carries it (the compensation rule rounds to the 1 nm resolution):
    # each edge position is off by at most half a step of Y and of Z; A keeps its whole
    # degrees, which the 0.00001-deg grid holds exactly
    rounded = compensate_program(nominal, machine, truth)
    assert [m.kind for m in rounded] == [m.kind for m in nominal]
    q_rounded = np.array([[m.target[a] for a in axes] for m in rounded])
    np.testing.assert_allclose(q_rounded[:, 3], q_nominal[:, 3], rtol=0, atol=1e-15)
    np.testing.assert_allclose(machine.tool_pose(q_rounded, errors)[:, :3, 3],
                               machine.tool_pose(q_nominal)[:, :3, 3], rtol=0,
                               atol=0.5 * NM + KINEMATIC_TOL)


def synthetic_readings(r, e, r0, z0, y0, sigma, angles_deg=(0, 10, 20, 30, 40)):
    readings = []
    for t in np.radians(angles_deg):
        dz = z0 + arm.height_change(t, r, e, r0)
        dy = y0 + arm.lateral_change(t, r, e, r0)
        readings.append(AngleReading(t, np.zeros(1), np.array([dz]), np.array([dy]),
                                             np.array([sigma]), np.array([sigma])))
    return readings


def test_fit_arm_solves_exact_readings_and_propagates_their_uncertainty(r0):
    r, e, z0, y0 = r0 - 0.04 * MM, 0.25 * MM, 3 * UM, -7 * UM
    readings = synthetic_readings(r, e, r0, z0, y0, sigma=1 * NM)
    t = np.radians([0, 10, 20, 30, 40])
    # the least-squares covariance of eq 1 with a free offset, by the normal equations
    design = np.column_stack([np.ones(5), 1 - np.cos(t), np.sin(t)])
    expected = np.sqrt(np.diag(np.linalg.inv(design.T @ design))) * 1 * NM
    for lateral in (False, True):
        fit = arm.fit_arm(readings, r0, lateral=lateral)
        # 1e-16 m: a 3x3 or 4x4 least-squares solve of readings of ~1e-4 m
        assert fit.r == pytest.approx(r, abs=1e-16)
        assert fit.e_ys == pytest.approx(e, abs=1e-16)
        assert fit.z_offset == pytest.approx(z0, abs=1e-16)
        assert fit.y_offset == pytest.approx(y0, abs=1e-16)
    paper = arm.fit_arm(readings, r0)
    np.testing.assert_allclose([paper.z_offset_sigma, paper.r_sigma, paper.e_ys_sigma],
                               expected, rtol=1e-9)
    # the lateral readings fix r ~10x better: eq 2's sin t against eq 1's 1 - cos t
    assert arm.fit_arm(readings, r0, lateral=True).r_sigma < paper.r_sigma / 5
    with pytest.raises(InputError, match="three or more distinct angles"):
        arm.fit_arm(readings[:2], r0)
    with pytest.raises(InputError, match="reading at tool angle 0"):
        arm.touch_off(readings[1:], r0)


def test_plans_refuse_angles_where_a_flank_turns_flat_and_bad_sizes():
    with pytest.raises(InputError, match=r"within \+-45 deg"):
        CalibrationPlan(angles=(0.0, math.radians(50)))
    with pytest.raises(InputError, match="depth > 0"):
        PrismPattern(depth=-10 * UM)
    with pytest.raises(InputError, match="clearance above the search range"):
        CalibrationPlan(search=2 * MM, clearance=1 * MM)
    with pytest.raises(InputError, match="capture > 0"):
        CalibrationPlan(capture=-1 * MM)


@pytest.mark.parametrize("plan, field, value, message", [
    # True passed isinstance(int) as 1 m (1 rad, 1 mm/min): taken
    (CalibrationPlan, "capture", True, "Expected capture as a number (m), got True"),
    (CalibrationPlan, "search", True, "Expected search as a number (m), got True"),
    (CalibrationPlan, "slope", True, "Expected slope as a number (m per m of x), got True"),
    (CalibrationPlan, "spacing", True, "Expected spacing as a number (m), got True"),
    (CalibrationPlan, "clearance", True, "Expected clearance as a number (m), got True"),
    (PrismPattern, "pitch", True, "Expected pitch as a number (m), got True"),
    (PrismPattern, "length", True, "Expected length as a number (m), got True"),
    (PrismPattern, "margin", True, "Expected margin as a number (m), got True"),
    (PrismPattern, "clearance", True, "Expected clearance as a number (m), got True"),
    (PrismPattern, "depth", True, "Expected depth as a number (m), got True"),  # 'depth 1 m'
    (CalibrationPlan, "tool_angle", True, "Expected tool_angle as a number (rad), got True"),
    # tool_angle and feed were not checked at all
    (PrismPattern, "tool_angle", -1.0, "Expected tool_angle > 0 (rad), got -1.0"),
    (CalibrationPlan, "tool_angle", math.pi,
     "Expected tool_angle, the V tool's included angle, below pi rad (180 deg), got "
     f"{math.pi!r}"),
    (CalibrationPlan, "tool_angle", "1.5", "Expected tool_angle as a number (rad), got '1.5'"),
    (CalibrationPlan, "tool_angle", math.nan, "Expected tool_angle > 0 (rad), got nan"),
    (CalibrationPlan, "feed_mm_per_min", math.nan,
     "Expected feed_mm_per_min > 0 (mm/min), got nan"),
    (PrismPattern, "feed_mm_per_min", 0.0, "Expected feed_mm_per_min > 0 (mm/min), got 0.0"),
    (PrismPattern, "feed_mm_per_min", "100",
     "Expected feed_mm_per_min as a number (mm/min), got '100'"),
    # a str angle was float()ed, a bare number or a bool a TypeError, a bool in it 1 rad
    (CalibrationPlan, "angles", ("0.1",), "Expected angles as tool angles (rad), got ('0.1',)"),
    (PrismPattern, "angles", 0.1,
     "Expected angles as a sequence of one or more tool angles (rad), got 0.1"),
    (PrismPattern, "angles", (True, 0.1), "Expected angles as tool angles (rad), got (True, 0.1)"),
    # station depths and the origin were not checked: TypeError, max() of nothing, taken
    (CalibrationPlan, "station_depths", ("1e-5",),
     "Expected station_depths as groove depths (m), got ('1e-5',)"),
    (CalibrationPlan, "station_depths", (),
     "Expected station_depths as a sequence of one or more groove depths (m), got ()"),
    (CalibrationPlan, "station_depths", (True,),
     "Expected station_depths as groove depths (m), got (True,)"),
    (CalibrationPlan, "station_depths", (math.nan,),
     "Expected station_depths as finite groove depths (m), got (nan,)"),
    (CalibrationPlan, "station_depths", (-1e-5,),
     "Expected station_depths > 0 (m, below the surface), got (-1e-05,)"),
    (CalibrationPlan, "origin", (math.nan, 0.0),
     "Expected origin as finite lengths (x, y) (m), got (nan, 0.0)"),
    (PrismPattern, "origin", (1.0,),
     "Expected origin as a sequence of 2 lengths (x, y) (m), got (1.0,)"),
    (PrismPattern, "origin", ("1", "1"), "Expected origin as lengths (x, y) (m), got ('1', '1')"),
    (PrismPattern, "origin", (True, 0.0), "Expected origin as lengths (x, y) (m), got (True, 0.0)"),
])
def test_every_plan_field_refuses_what_is_no_number_of_it(plan, field, value, message):
    """Each field of CalibrationPlan and PrismPattern goes through one check (`as_number`,
    `as_floats`): a bool, a str, a non-finite value or a wrong shape is refused naming the
    field, where some were taken (True as 1 m, feed nan, origin (nan, 0)) or failed as a
    TypeError (``'float' object is not iterable``)."""
    with pytest.raises(InputError) as info:
        plan(**{field: value})
    assert info.value.key == field
    assert str(info.value) == f"key '{field}': {message}"


def test_plan_fields_take_numpy_numbers_as_the_floats_they_are():
    """np.float32 and np.int64 are numbers: they were refused as 'Expected capture > 0 (m),
    got np.float32(0.001)'. They are kept as Python floats of the same value."""
    plan = CalibrationPlan(capture=np.float32(0.5e-3), slope=np.float32(0.25),
                           height=np.int64(1), tool_angle=np.float64(math.pi / 2),
                           angles=np.radians([0.0, 10.0, 20.0]).astype(np.float32))
    assert plan.capture == float(np.float32(0.5e-3)) and type(plan.capture) is float
    assert plan.slope == 0.25 and plan.height == 1.0 and type(plan.height) is float
    assert plan.angles == tuple(float(a) for a in np.radians([0.0, 10.0, 20.0])
                                .astype(np.float32))
    pattern = PrismPattern(depth=np.float32(2 ** -17), clearance=np.int64(1),
                           origin=np.array([0.0, 1e-3]))
    assert pattern.depth == 2 ** -17 and pattern.clearance == 1.0
    assert pattern.origin == (0.0, 1e-3) and type(pattern.origin) is tuple


def v_profile(apexes, depths, left_slopes, right_slopes, s):
    """Grooves that meet in ridges: the surface is the lowest of the V's and the top z = 0."""
    z = np.zeros_like(s)
    for a, d, lo, hi in zip(apexes, depths, left_slopes, right_slopes, strict=True):
        z = np.minimum(z, -d + np.where(s < a, lo * (a - s), hi * (s - a)))
    return z


def test_fit_apexes_reads_grooves_that_share_ridges_exactly():
    t = np.radians(np.arange(6) * 4.0)
    apexes = 100 * UM + 20 * UM * np.arange(6) + 1.3 * UM * np.arange(6) ** 2
    depths = 10 * UM + 3 * UM * np.arange(6)
    # a 90-deg V tilted by t: flanks at 45 - t (towards -s) and 45 + t from horizontal
    s = np.arange(0.0, 400 * UM, 0.3 * UM)
    z = v_profile(apexes, depths, np.tan(np.pi / 4 - t), np.tan(np.pi / 4 + t), s)
    centre, depth, centre_sigma, depth_sigma = fit_apexes(s, z, 6, prominence=2 * UM)
    # 1e-17 m: the flanks are exact lines, so the fits only add float64 round-off
    np.testing.assert_allclose(depth, depths, rtol=0, atol=1e-17)
    np.testing.assert_allclose(centre, apexes, rtol=0, atol=1e-15)
    with pytest.raises(InputError, match="Expected 7 groove apexes in the profile, found 6"):
        fit_apexes(s, z, 7, prominence=2 * UM)


@pytest.mark.parametrize("noise", [False, True])
def test_the_generic_fit_agrees_with_eq_1(noise):
    """The cross-check of paper 000's fit by `fit` on the machine's error Jacobians.

    tool.y, tool.z and workpiece.z from the stations' edge heights are a linear change of eq
    1's (offset, r - r0, e_ys), and the per-angle weighted means `fit_arm` fits are a
    sufficient statistic of the stations: both are the same weighted least-squares estimate,
    noise or not. So they agree to round-off, far below the fit's 1e-12 m stopping step
    (`tolerances.FIT_STEP_M`) and a thousand times below the reported std with noise.
    """
    machine = load_machine("planer_4axis")
    r0 = arm.arm_radius(machine)
    rng = np.random.default_rng(5)
    r, e = r0 + rng.uniform(-0.1, 0.1) * MM, rng.uniform(-0.3, 0.3) * MM
    lab = Lab(machine, errors_for(r, e, r0).with_parameters({"workpiece.z": 3 * UM}),
              noise=noise, seed=5)
    procedure_ = ToolRotationArm()
    identified = procedure_.identify(procedure_.measure(lab))
    detail = identified.detail
    for check, paper in ((detail.check, detail.estimate), (detail.check_lateral,
                                                           detail.lateral)):
        assert check.estimate.unidentifiable == ()  # tool.z turns with A, workpiece.z not
        assert check.estimate.rank == len(check.estimate.names)
        assert abs(check.r - paper.r) < 1e-12
        assert abs(check.e_ys - paper.e_ys) < 1e-12
        # the same a-priori covariance (1e-9 relative: two inversions of a 3x3 or 4x4)
        assert check.r_sigma == pytest.approx(paper.r_sigma, rel=1e-9)
        assert check.e_ys_sigma == pytest.approx(paper.e_ys_sigma, rel=1e-9)
        assert abs(check.r - paper.r) < 1e-3 * paper.r_sigma
    # the workpiece height is what eq 1's offset took: dz(0) = tool.z - workpiece.z
    values = dict(zip(detail.check.estimate.names, detail.check.estimate.values, strict=True))
    assert values["tool.z"] - values["workpiece.z"] == pytest.approx(
        detail.estimate.z_offset, abs=1e-12)


def test_the_check_needs_the_programmed_edge_and_three_angles(machine, r0):
    readings = synthetic_readings(r0, 0.1 * MM, r0, 0.0, 0.0, sigma=1 * NM)
    with pytest.raises(InputError, match="programmed edge"):
        arm.fit_check(readings, machine, r0)
    with pytest.raises(InputError, match="three or more distinct angles"):
        arm.fit_check(readings[:2], machine, r0)


def test_the_correction_needs_y_z_and_a():
    with pytest.raises(InputError, match="axes Y, Z and A"):
        procedure.arm_correction(arm.ArmEstimate(r0=0.1, r=0.1, e_ys=0.0), ("X", "Y", "Z"))


def test_the_procedure_refuses_a_machine_whose_a_axis_is_no_arm():
    """robonano_ui has an A axis, but it turns the tool about its own axis through the edge
    (docs/procedures/tool_setting_6axis.md): r0 came out 0 and the ramps were cut and read
    on a planer's plan as if it were one, the calibration returned as measured."""
    ui = load_machine("robonano_ui")
    expected = ("Expected a machine whose A axis turns the tool about +X on an arm, the edge "
                "r0 > 0 below the axis (paper 000's planer, e.g. planer_4axis); machine "
                "robonano_ui's A moves the edge by (0, 0, 0) mm at A = -0.5 rad and (0, 0, 0) "
                "mm at +0.5 rad (r0 = 0 mm)")
    with pytest.raises(InputError) as refused:
        arm.arm_radius(ui)
    assert str(refused.value) == f"key 'machine': {expected}"
    with pytest.raises(InputError, match="no arm|turns the tool about \\+X on an arm"):
        ToolRotationArm().measure(Lab(ui, ErrorModel(), noise=False))
    # the planer's arm: docs/machines.md, 120.5 mm
    assert arm.arm_radius(load_machine("planer_4axis")) == pytest.approx(120.5 * MM, rel=1e-12)
