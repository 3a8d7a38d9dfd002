"""A spiral path run through a servo and turned: the X lag of a PD loop is a radial tool offset;
the followed path cuts the surface the servo's own motion cuts."""

import math
import re

import numpy as np
import pytest
from slow_loops import Jump

import machinesim.cam.spiral as sp
from machinesim.cutting.lathe import LEAD_IN_S, followed
from machinesim.cutting.servo_path import followed_edge_path, path_times
from machinesim.cutting.tool_form_error import alignment_error_x
from machinesim.cutting.turning import EdgePath, turned_heights, turned_surface
from machinesim.exceptions import InputError
from machinesim.servo import AxisServo, PIDServo, table6_servo

RS, FEED, RADIUS, R, RPM = 0.5e-3, 2e-6, 0.17e-3, 0.2e-3, 600.0
DESIGN = sp.sphere(RS)


@pytest.fixture(scope="module")
def tool_path():
    spiral = sp.Spiral(RADIUS, FEED)
    return sp.tool_path(sp.cutting_points(DESIGN, spiral, sp.constant_angle(spiral, 0.01)), R)


@pytest.mark.parametrize("ki", [0.0, 1e7])
def test_x_lag_of_a_servo_cuts_the_cone_of_a_radial_offset(tool_path, ki):
    # compensated X on a sphere is rho (1 + R / Rs): a ramp of speed v (1 + R / Rs), v = f n.
    # A PD loop lags it by speed c / kp (final-value theorem), i.e. the tip sits that much
    # further out: the form error of a radial offset dx (eq 12, exact form). With integral
    # action the ramp's lag vanishes and so does the cone.
    kp, kd, c, mass = 2e5, 2e3, 1e4, 4.0
    servo = PIDServo((AxisServo(kp=kp, ki=ki, kd=kd, mass=mass, damping=c), None, None))
    speed = FEED * RPM / 60.0 * (1 + R / RS)
    dx = speed * c / kp if ki == 0.0 else 0.0
    x = np.linspace(0.02e-3, 0.15e-3, 40) + 3e-9
    y = np.array([1e-9])
    heights = turned_surface(followed_edge_path(tool_path, servo, RPM), R, x, y)[0]
    error = heights - DESIGN(x, y[0])
    expected = alignment_error_x(DESIGN, np.hypot(x, y[0]), 0.0, dx)
    scallop = (FEED * (1 + R / RS)) ** 2 / (8 * R)
    assert (error - expected).min() > -1e-11
    assert (error - expected).max() < scallop
    if ki == 0.0:
        assert np.abs(expected).max() > 50 * scallop


def test_times_and_bad_input(tool_path):
    t = path_times(tool_path, 60.0)
    assert t[0] == 0.0
    assert t[-1] == pytest.approx((tool_path.c[-1] - tool_path.c[0]) / (2 * np.pi))
    with pytest.raises(InputError, match="spindle_rpm"):
        path_times(tool_path, 0.0)
    # a str or None was a TypeError ('>' not supported), True was taken as 1 rpm
    for rpm in ("60", None, True, float("inf")):
        with pytest.raises(InputError, match="key 'spindle_rpm'"):
            path_times(tool_path, rpm)
    assert np.array_equal(path_times(tool_path, np.int64(60)), t)


@pytest.fixture(scope="module")
def grid_path():
    """Paper 004's sine grid over r 0.5 mm by Constant Angle, 2 deg (its Case 4 program,
    not spline-interpolated), at a coarser 50 um feed: ten turns, 1,801 points."""
    spiral = sp.Spiral(sp.PART_RADIUS_M, 50e-6)
    points = sp.cutting_points(sp.sine_grid(), spiral, sp.constant_angle(spiral, sp.CA_STEP_RAD))
    return sp.tool_path(points, sp.NOSE_RADIUS_M)


def test_a_followed_path_turns_the_surface_the_servo_s_own_motion_cuts(grid_path):
    # the reference: the path's straight steps sampled 64 times finer, followed by the same
    # loops, joined straight from those samples (its joins 64^2 times closer to the motion)
    servo = table6_servo("before")
    t = path_times(grid_path)
    q = np.column_stack([grid_path.x, grid_path.z, grid_path.c])
    k = 64
    fine_t = np.interp(np.arange((len(t) - 1) * k + 1) / k, np.arange(len(t)), t)
    fine = followed(servo.follow, fine_t,
                    np.column_stack([np.interp(fine_t, t, q[:, j]) for j in range(3)]))
    reference = EdgePath(fine[:, 2], fine[:, 0], 0.0, fine[:, 1])
    radius = np.linspace(0.1e-3, 0.49e-3, 60)[:, None]
    angle = np.linspace(0.0, 2.0 * math.pi, 73)[None, :]
    x, y = (radius * np.cos(angle)).ravel(), (radius * np.sin(angle)).ravel()
    lagged = followed_edge_path(grid_path, servo)
    error = (turned_heights(lagged, sp.NOSE_RADIUS_M, x, y)
             - turned_heights(reference, sp.NOSE_RADIUS_M, x, y))
    # the old path joined the 1,801 followed points straight, where the Z loop's motion bends
    # between them: 10.3 nm off the reference; its joins now keep the 1 nm chord (0.61 nm)
    assert np.abs(error).max() < 1e-9
    assert len(lagged.angle) > len(grid_path)


def test_a_followed_path_that_jumps_is_refused_naming_the_step_and_the_servo(grid_path):
    with pytest.raises(InputError, match=re.escape(
            "the axes as the servo model Jump follows this move (C turns ")) as err:
        followed_edge_path(grid_path, Jump(2))
    assert err.value.key == "servo"
    # the step it jumps on: past halfway through the times the loops follow (lead-in too)
    t = path_times(grid_path)
    step = int(np.searchsorted(t, (t[0] - LEAD_IN_S + t[-1]) / 2.0, side="right")) - 1
    assert f"path step {step} (points {step} to {step + 1}): the axes" in str(err.value)
    assert str(err.value).endswith(
        "break the rules of a commanded step (at most 90 deg of C, the straight join within "
        "1 nm of the path) still after 8 rounds of sampling the move finer: its output "
        "jumps; check the servo loops' gains")
