"""Least-squares fits against a second method or hand values: `form_error`'s shift against
scipy's least_squares on a sphere, `fit_sphere` with its radius held."""

import numpy as np
import pytest
from scipy.optimize import least_squares

from machinesim.exceptions import InputError
from machinesim.metrology.fits import form_error

UM = 1e-6
RADIUS = 5e-3


def sphere(x, y):
    """A sphere cap of radius 5 mm, its pole at the origin (m)."""
    return RADIUS - np.sqrt(RADIUS**2 - x * x - y * y)


def sphere_map(amplitude):
    """The cap shifted by (2, -1) um, raised 3 um, tilted 1e-4 along x, with a ripple of
    ``amplitude`` that is odd in x as the shift's signature (x^3) is: it moves the shift."""
    x = np.linspace(-0.5e-3, 0.5e-3, 101)
    y = np.linspace(-0.5e-3, 0.5e-3, 81)
    grid_x, grid_y = np.meshgrid(x, y)
    ripple = np.sin(2 * np.pi * grid_x / 0.1e-3) * np.cos(2 * np.pi * grid_y / 0.13e-3)
    z = sphere(grid_x - 2 * UM, grid_y + UM) + 3 * UM + 1e-4 * grid_x + amplitude * ripple
    return x, y, z


def by_least_squares(x, y, z):
    """Piston, tilt and shift by scipy's Levenberg-Marquardt with the sphere's exact Jacobian
    (parameters in um and mrad, so that all are of order one)."""
    grid_x, grid_y = np.meshgrid(x, y)

    def residual(p):
        return (z - sphere(grid_x - p[3] * UM, grid_y - p[4] * UM)
                - (p[0] * UM + p[1] * 1e-3 * grid_x + p[2] * 1e-3 * grid_y)).ravel()

    def jacobian(p):
        u, v = grid_x - p[3] * UM, grid_y - p[4] * UM
        w = np.sqrt(RADIUS**2 - u * u - v * v)
        return np.column_stack([np.full(u.size, -UM), -1e-3 * grid_x.ravel(),
                                -1e-3 * grid_y.ravel(), (UM * u / w).ravel(),
                                (UM * v / w).ravel()])

    p = least_squares(residual, np.zeros(5), jac=jacobian, method="lm", xtol=1e-15,
                      ftol=1e-15, gtol=1e-15).x
    return p[0] * UM, p[1:3] * 1e-3, p[3:] * UM


def test_form_error_shift_on_an_exact_sphere():
    # The shift's columns nearly match the tilt's, so Gauss-Newton's steps stop shrinking at
    # ~1e-16 m (round-off of R - sqrt(R^2 - r^2)): the old stopping rule, 4e-18 m, refused
    # this fit after 100 steps.
    form = form_error(*sphere_map(0.0), sphere, shift=True)
    # round-off ~1e-16 m, as the steps show; 1e-15 m fails on any real error
    np.testing.assert_allclose(form.shift, [2 * UM, -UM], rtol=0, atol=1e-15)
    assert abs(form.piston - 3 * UM) < 1e-18
    np.testing.assert_allclose(form.tilt, [1e-4, 0.0], rtol=0, atol=1e-13)
    assert form.rms < 1e-18


@pytest.mark.parametrize("amplitude", [1e-12, 1e-11, 1e-10, 1e-9, 1e-8])
def test_form_error_shift_on_a_rippled_sphere_as_least_squares_finds_it(amplitude):
    x, y, z = sphere_map(amplitude)
    form = form_error(x, y, z, sphere, shift=True)
    piston, tilt, shift = by_least_squares(x, y, z)
    # The ripple moves the shift by ~26 times its amplitude (0.26 um at 10 nm); the two
    # methods agree to 1e-3 of the amplitude (they do to ~1e-4), 1e-15 m for round-off.
    atol = 1e-15 + 1e-3 * amplitude
    assert abs(form.shift[0] - 2 * UM) > 10 * amplitude
    np.testing.assert_allclose(form.shift, shift, rtol=0, atol=atol)
    assert abs(form.piston - piston) < atol
    np.testing.assert_allclose(form.tilt, tilt, rtol=0, atol=1e3 * atol)
    # no better minimum: least squares' residual is not below form_error's (but for the
    # round-off of 5e-5 m heights, ~1e-20 m)
    grid_x, grid_y = np.meshgrid(x, y)
    theirs = z - sphere(grid_x - shift[0], grid_y - shift[1]) - (
        piston + tilt[0] * grid_x + tilt[1] * grid_y)
    assert form.rms <= np.sqrt(np.mean(theirs**2)) + 1e-19


def test_form_error_still_refuses_a_shift_that_does_not_settle():
    # A nominal that is no function (a new cubic term at every call): the steps never fall
    # within the shift's uncertainty, and the fit says so instead of returning a shift.
    rng = np.random.default_rng(0)
    x, y, z = sphere_map(0.0)

    def drifting(a, b):
        return sphere(a, b) + 1e-9 * rng.standard_normal() * (a / 0.5e-3) ** 3

    with pytest.raises(InputError, match="The shift fit did not settle in 100 steps"):
        form_error(x, y, z, drifting, shift=True)
