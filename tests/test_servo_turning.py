"""A spiral path run through a servo and turned: the X lag of a PD loop is a radial tool offset."""

import numpy as np
import pytest

import machinesim.cam.spiral as sp
from machinesim.cutting.servo_path import followed_edge_path, path_times
from machinesim.cutting.tool_form_error import alignment_error_x
from machinesim.cutting.turning import turned_surface
from machinesim.exceptions import InputError
from machinesim.servo import AxisServo, PIDServo

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
