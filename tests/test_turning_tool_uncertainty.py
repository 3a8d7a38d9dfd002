"""The tool errors' stated standard uncertainties (s^2 (J^T J)^-1 of the fits) against the
scatter of the fitted values over independent noise draws, on maps made from the exact
forms the fits model (no cutting engine: no feed marks, so the pixels' errors are the noise
alone)."""

import numpy as np
import pytest
from scipy.stats import chi2

import machinesim.cam.spiral as sp
from machinesim.cutting.tool_form_error import nose_radius_error
from machinesim.exceptions import InputError
from machinesim.identification.turning_tool import (
    fit_centre_height,
    identify_centre_height,
    identify_tool_errors,
)
from machinesim.procedures.sts_turning import STSTurning, ToolTest

RS = 2e-3  # the test sphere of paper 004's tool test (sts_plans.TEST_SPHERE)
DESIGN = sp.sphere(RS)
DX, DR, CENTRE = -3.5e-6, 100e-6, (1e-6, -0.5e-6)
SLOPE, DY = 0.02, -3.5e-6  # the tilted test plane, and the centre height it shows
SIGMA = 0.5e-9  # the white-light interferometer's stated noise
DRAWS = 50
# The sample standard deviation s of N draws of a normal variable of standard deviation std:
# (N - 1) s^2 / std^2 is chi-square with N - 1 degrees of freedom; its 0.05 % and 99.95 %
# quantiles bound s / std (0.68 .. 1.34 for N = 50): a correct std fails 1 time in 1000.
RATIO = np.sqrt(chi2.ppf([0.0005, 0.9995], DRAWS - 1) / (DRAWS - 1))


def sphere_map(n=61):
    """The turned sphere with dx, dR (dy 0: no core), as the fit models it, m."""
    x = np.linspace(-0.1e-3, 0.1e-3, n)
    px, py = np.meshgrid(x, x)
    a = np.hypot(px - CENTRE[0], py - CENTRE[1]) - DX
    return x, DESIGN(a, 0.0) + nose_radius_error(DESIGN, a, 0.0, DR)


def plane_map(n=81):
    """The turned tilted plane with dx, dy (z = k a cos(theta - atan(dy / (a + dx)))), m."""
    x = np.linspace(-0.1e-3, 0.1e-3, n)
    px, py = np.meshgrid(x, x)
    rho = np.hypot(px, py)
    a = np.sqrt(np.maximum(rho * rho - DY * DY, 0.0)) - DX
    return x, SLOPE * a * np.cos(np.arctan2(py, px) - np.arctan2(DY, a + DX))


def first_order_std(sigma, n=61):
    """sigma sqrt(diag((J^T J)^-1)) of (x0, y0, piston, dx, dR) on `sphere_map`'s aperture."""
    x = np.linspace(-0.1e-3, 0.1e-3, n)
    px, py = np.meshgrid(x, x)
    inside = np.hypot(px, py) < 0.1e-3

    def heights(p):
        x0, y0, piston, dx, dr = p
        a = np.hypot(px[inside] - x0, py[inside] - y0) - dx
        return DESIGN(a, 0.0) + nose_radius_error(DESIGN, a, 0.0, dr) + piston

    truth = np.array([*CENTRE, 0.0, DX, DR])
    steps = np.array([1e-9, 1e-9, 1e-9, 1e-9, 1e-8])
    jac = np.column_stack([(heights(truth + h * e) - heights(truth - h * e)) / (2 * h)
                           for h, e in zip(steps, np.eye(5), strict=True)])
    return sigma * np.sqrt(np.diag(np.linalg.inv(jac.T @ jac)))


def fit_sphere(x, z):
    return identify_tool_errors(DESIGN, x, x, z, core_step=50e-9, aperture=0.1e-3)


def fit_plane(x, z, noise=None):
    return fit_centre_height(x, x, z, SLOPE, aperture=0.1e-3, core=30e-6, dx=DX, noise=noise)


def test_the_sphere_fit_states_the_scatter_of_dx_and_dr_over_noise_draws():
    x, exact = sphere_map()
    rng = np.random.default_rng(0)
    found = [fit_sphere(x, exact + SIGMA * rng.standard_normal(exact.shape))
             for _ in range(DRAWS)]
    for value, std, truth in (("dx", "dx_std", DX), ("d_radius", "d_radius_std", DR)):
        values = np.array([getattr(f, value) for f in found])
        stated = np.array([getattr(f, std) for f in found])
        # s from each map's own residuals: it varies by ~1 / sqrt(2 n) (n ~ 2900 pixels)
        assert np.ptp(stated) < 0.1 * stated.mean()
        assert RATIO[0] < values.std(ddof=1) / stated.mean() < RATIO[1], value
        # unbiased: the mean within 4 standard errors of the truth
        assert abs(values.mean() - truth) < 4 * stated.mean() / np.sqrt(DRAWS), value


def test_the_stated_std_scales_as_the_noise():
    x, exact = sphere_map()
    pattern = np.random.default_rng(1).standard_normal(exact.shape)
    fits = [fit_sphere(x, exact + sigma * pattern) for sigma in (0.25e-9, 1e-9, 4e-9)]
    # the same pattern scaled: the residuals scale with it; J is evaluated where each fit
    # ends, a few nm apart, so the ratios hold to well within 1 %
    for f, scale in zip(fits[1:], (4.0, 16.0), strict=True):
        assert f.dx_std / fits[0].dx_std == pytest.approx(scale, rel=0.01)
        assert f.d_radius_std / fits[0].d_radius_std == pytest.approx(scale, rel=0.01)
    # against sigma sqrt(diag((J^T J)^-1)) with J by central differences of the map itself
    # over (x0, y0, piston, dx, dR) at the truth: the stated std's s is the residuals' RMS,
    # within 3 / sqrt(2 n) ~ 4 % of sigma (n ~ 2900 pixels in the aperture)
    theory = first_order_std(0.25e-9)
    assert fits[0].dx_std == pytest.approx(theory[3], rel=0.05)
    assert fits[0].d_radius_std == pytest.approx(theory[4], rel=0.05)
    exact_fit = fit_sphere(x, exact)  # no noise: nothing to scatter
    assert exact_fit.dx_std < 1e-6 * fits[0].dx_std


def test_the_plane_fit_states_the_scatter_of_dy_over_noise_draws():
    x, exact = plane_map()
    rng = np.random.default_rng(2)
    maps = [exact + SIGMA * rng.standard_normal(exact.shape) for _ in range(DRAWS)]
    own = [fit_plane(x, z) for z in maps]  # s from the residuals
    stated = [fit_plane(x, z, noise=SIGMA) for z in maps]  # s the stated noise
    dy = np.array([f.dy for f in own])
    assert np.array_equal(dy, [f.dy for f in stated])  # the noise changes the std only
    for fits in (own, stated):
        std = np.mean([f.dy_std for f in fits])
        assert RATIO[0] < dy.std(ddof=1) / std < RATIO[1]
        assert abs(dy.mean() - DY) < 4 * std / np.sqrt(DRAWS)
    # the residuals' RMS is the noise here (~4600 pixels: within 3 / sqrt(2 n) = 3 %)
    assert own[0].dy_std == pytest.approx(stated[0].dy_std, rel=0.03)
    assert own[0].residual_rms == pytest.approx(SIGMA, rel=0.03)
    assert fit_plane(x, maps[0], noise=2 * SIGMA).dy_std == pytest.approx(
        2 * stated[0].dy_std, rel=1e-12)


def test_identify_centre_height_is_the_fits_dy():
    x, exact = plane_map()
    z = exact + SIGMA * np.random.default_rng(3).standard_normal(exact.shape)
    assert identify_centre_height(x, x, z, SLOPE, aperture=0.1e-3, core=30e-6,
                                  dx=DX) == fit_plane(x, z).dy


def test_a_bad_noise_is_named():
    x, exact = plane_map(21)
    for noise in (-1e-9, float("nan")):
        with pytest.raises(InputError, match="noise"):
            fit_plane(x, exact, noise=noise)


def test_the_procedure_reports_each_tool_error_with_its_std():
    found = ToolTest(dx=-3.57e-6, dy=-3.38e-6, d_radius=100.06e-6, dy_abs=3.4e-6,
                     dx_std=0.8e-9, dy_std=0.7e-9, d_radius_std=22e-9)
    identified = STSTurning().identify({"tool_test": found})
    assert dict(identified.parameters) == {
        "tool.x": (-3.57e-6, 0.8e-9), "tool.y": (-3.38e-6, 0.7e-9),
        "tool_geometry.nose_radius": (100.06e-6, 22e-9)}
    assert identified.detail is found


LATERAL = 10e-9  # the interferometer's lateral noise in the lab (Realism's default)


def shifted_maps(rng, n=61):
    """`sphere_map` and `plane_map` read as the lab's interferometer reads them: each column
    off in x and each row in y by its own normal deviate of LATERAL, and SIGMA of height
    noise on each pixel."""
    x = np.linspace(-0.1e-3, 0.1e-3, n)
    px, py = np.meshgrid(x + LATERAL * rng.standard_normal(n),
                         x + LATERAL * rng.standard_normal(n))
    a = np.hypot(px - CENTRE[0], py - CENTRE[1]) - DX
    sphere = DESIGN(a, 0.0) + nose_radius_error(DESIGN, a, 0.0, DR)
    rho = np.hypot(px, py)
    a = np.sqrt(np.maximum(rho * rho - DY * DY, 0.0)) - DX
    plane = SLOPE * a * np.cos(np.arctan2(py, px) - np.arctan2(DY, a + DX))
    return x, (sphere + SIGMA * rng.standard_normal(sphere.shape),
               plane + SIGMA * rng.standard_normal(plane.shape))


def test_the_lateral_noise_of_rows_and_columns_is_in_the_stated_std():
    # a column read off in x moves all its pixels alike: with the lateral term the stated
    # std is the scatter over draws; taking the pixels as independent understates it
    rng = np.random.default_rng(4)
    draws = [shifted_maps(rng) for _ in range(DRAWS)]
    spheres = [identify_tool_errors(DESIGN, x, x, s, core_step=50e-9, aperture=0.1e-3,
                                    lateral_sigma=LATERAL) for x, (s, _) in draws]
    planes = [fit_centre_height(x, x, p, SLOPE, aperture=0.1e-3, core=30e-6, dx=DX,
                                noise=SIGMA, lateral_sigma=LATERAL) for x, (_, p) in draws]
    for fits, value, std in ((spheres, "dx", "dx_std"), (spheres, "d_radius", "d_radius_std"),
                             (planes, "dy", "dy_std")):
        values = np.array([getattr(f, value) for f in fits])
        stated = np.mean([getattr(f, std) for f in fits])
        assert RATIO[0] < values.std(ddof=1) / stated < RATIO[1], value
    x, (s, p) = draws[0]
    alone = identify_tool_errors(DESIGN, x, x, s, core_step=50e-9, aperture=0.1e-3)
    dx = np.array([f.dx for f in spheres])
    # taken as independent pixels, the std is too small for the band above (here 2.1x)
    assert dx.std(ddof=1) / alone.dx_std > RATIO[1]
    with pytest.raises(InputError, match="lateral_sigma"):
        identify_tool_errors(DESIGN, x, x, s, core_step=50e-9, aperture=0.1e-3,
                             lateral_sigma=-1e-9)
