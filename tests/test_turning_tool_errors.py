"""Form error of tool errors (dx, dy, dR): predicted from the design (paper 004, eqs 12-20, and
the exact forms) against the turning engine cutting with the errors."""

import numpy as np
import pytest

import machinesim.cam.spiral as sp
from machinesim.cutting.tool_form_error import (
    alignment_error_x,
    alignment_error_y,
    nose_radius_error,
)
from machinesim.cutting.turning import EdgePath, turned_surface
from machinesim.exceptions import InputError

RS, FEED, RADIUS, R = 0.5e-3, 0.5e-6, 0.17e-3, 0.2e-3
DESIGN = sp.sphere(RS)


@pytest.fixture(scope="module")
def tool_path():
    spiral = sp.Spiral(RADIUS, FEED)
    return sp.tool_path(sp.cutting_points(DESIGN, spiral, sp.constant_angle(spiral, 0.01)), R)


@pytest.mark.parametrize("name, value, predict", [
    ("dx", 1e-6, alignment_error_x), ("dy", 5e-6, alignment_error_y),
    ("dR", 10e-6, nose_radius_error)])
def test_cut_matches_the_predicted_form_error(tool_path, name, value, predict):
    # the engine cuts the design plus the tool error's form error plus scallops in
    # [0, f_c^2 / 8R], f_c = f (1 + R / Rs) the spacing of the compensated nose centres
    x = np.linspace(0.01e-3, 0.15e-3, 57) + 3e-9
    y = np.array([1e-9])
    rho, theta = np.hypot(x, y[0]), np.arctan2(y[0], x)
    path = EdgePath(tool_path.c, tool_path.x + (value if name == "dx" else 0.0),
                    value if name == "dy" else 0.0, tool_path.z)
    heights = turned_surface(path, R + (value if name == "dR" else 0.0), x, y)[0]
    error = heights - DESIGN(x, y[0])
    exact = predict(DESIGN, rho, theta, value)
    scallop = (FEED * (1 + R / RS)) ** 2 / (8 * R)
    assert np.abs(exact).max() > 50 * scallop  # the tool error shows
    assert (error - exact).min() > -1e-12
    assert (error - exact).max() < scallop
    # the paper's forms: off by higher-order terms in the error (and, for dy, in dy / rho),
    # here < 3 % away from the centre (rho > 10 x the error)
    paper = predict(DESIGN, rho, theta, value, form="paper")
    away = rho > 10 * value
    assert np.abs(paper - exact)[away].max() < 0.03 * np.abs(exact).max()


def test_exact_forms_on_a_sphere_are_closed_forms():
    # sphere z = sqrt(Rs^2 - rho^2) - Rs: dx shifts it, dy reads it at sqrt(rho^2 - dy^2),
    # dR leaves the concentric sphere of radius Rs - dR raised by dR
    rho = np.linspace(0.0, 0.2e-3, 41)
    z = np.sqrt(RS**2 - rho**2) - RS
    dx, dy, dr = 2e-6, 3e-6, 20e-6
    np.testing.assert_allclose(alignment_error_x(DESIGN, rho, 0.3, dx),
                               np.sqrt(RS**2 - (rho - dx) ** 2) - RS - z, atol=1e-15)
    outside = rho > dy
    np.testing.assert_allclose(alignment_error_y(DESIGN, rho, 0.3, dy)[outside],
                               (np.sqrt(RS**2 - rho**2 + dy**2) - RS - z)[outside], atol=1e-15)
    assert np.isnan(alignment_error_y(DESIGN, rho, 0.3, dy)[~outside]).all()
    np.testing.assert_allclose(nose_radius_error(DESIGN, rho, 0.3, dr),
                               np.sqrt((RS - dr) ** 2 - rho**2) - RS + dr - z, atol=1e-13)
    # and eq 20 at phi: -dR (1 / cos phi - 1), cos phi = sqrt(Rs^2 - rho^2) / Rs
    np.testing.assert_allclose(nose_radius_error(DESIGN, rho, 0.3, dr, form="paper"),
                               -dr * (RS / np.sqrt(RS**2 - rho**2) - 1), rtol=1e-6, atol=1e-15)


def test_bad_input_is_named():
    with pytest.raises(InputError, match="form"):
        alignment_error_x(DESIGN, 1e-4, 0.0, 1e-6, form="linear")
    with pytest.raises(InputError, match="Design"):
        nose_radius_error(lambda x, y: x, 1e-4, 0.0, 1e-6)
