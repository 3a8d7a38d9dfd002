"""Realism of the touch probe and the laser interferometer, each against a closed form:
the probe's pre-travel lobing and ball form on a fitted centre and radius, drawn forms,
the beam's misalignment as the cosine error; values in the wrong unit refused."""

from __future__ import annotations

import math

import manifold3d
import numpy as np
import pytest
from realism_helpers import MM, NM, UM

from machinesim.exceptions import InputError
from machinesim.metrology import LaserInterferometer, TouchProbe
from machinesim.metrology.imperfections import FORM_POINTS, Lobing, ZonalForm, fibonacci_sphere
from machinesim.workpiece import Part

R = 0.25 * MM
#: A fitted centre from exact contacts on mm-scale geometry: round-off ~1e-18 m, and the
#: first-order pre-travel model's second order, (0.1 um)^2 / 2 mm ~ 1e-12 m.
FIT_M = 1e-11


# --------------------------------------------------------------------------- touch probe


def _octagon_touches(a0ib, probe_options, radius=2 * MM):
    """Touch an octagonal prism (circumradius 2 mm, axis z through the origin) square to
    each face, at mid-height, and fit a circle to the recorded ball centres."""
    prism = Part(manifold3d.Manifold.cylinder(1 * MM, radius, radius, 8).translate(
        (0.0, 0.0, -1 * MM)))
    probe = TouchProbe(a0ib, None, prism, noise=False, resolution=0.0, **probe_options)
    normals = np.radians(22.5 + 45.0 * np.arange(8))
    apothem = radius * math.cos(math.pi / 8)
    centres = []
    for phi in normals:
        e = np.array([math.cos(phi), math.sin(phi)])
        start = np.zeros(5)
        start[:2] = (apothem + R + 0.2 * MM) * e + [0.0, -40 * MM]
        start[2] = -0.5 * MM - 1 * MM
        q = probe.touch(start, [-e[0], -e[1], 0.0, 0.0, 0.0], 0.4 * MM)
        centres.append(probe.nominal_centres(q)[:2])
    centres = np.array(centres)
    # least-squares circle (Kasa): x^2 + y^2 = 2 a x + 2 b y + c
    design = np.column_stack([2 * centres, np.ones(8)])
    a, b, c = np.linalg.lstsq(design, (centres**2).sum(axis=1), rcond=None)[0]
    return np.array([a, b]), math.sqrt(c + a * a + b * b), normals


def test_pretravel_first_harmonic_biases_a_fitted_centre_and_three_lobes_do_not(a0ib):
    exact, rho, _ = _octagon_touches(a0ib, {})
    np.testing.assert_allclose(exact, 0.0, atol=FIT_M)
    a1, phi1, a3 = 40 * NM, 0.7, 100 * NM
    three, _, _ = _octagon_touches(a0ib, {"pretravel": Lobing(((3, a3, 0.3),))})
    np.testing.assert_allclose(three, exact, atol=FIT_M)
    both, rho_both, _ = _octagon_touches(a0ib, {"pretravel": Lobing(((1, a1, phi1),
                                                                     (3, a3, 0.3)))})
    # each centre is pressed in by p(n) along -n: the circle fit keeps the first harmonic,
    # -a1 (cos phi1, sin phi1)
    np.testing.assert_allclose(both - exact, -a1 * np.array([math.cos(phi1), math.sin(phi1)]),
                               rtol=0, atol=FIT_M)
    assert rho_both == pytest.approx(rho, abs=FIT_M)


def test_ball_form_changes_the_effective_radius_by_its_value_where_it_touches(a0ib, flat):
    """A degree-2 form a P2(v . z): touching from the side the ball's equator is a P2(0) =
    -a/2 smaller, so the centres come a/2 closer; from above its bottom is a P2(-1) = a
    larger, so it stops a higher."""
    a = 0.1 * UM
    form = ZonalForm((2,), [a], [[0.0, 0.0, 1.0]])
    exact, rho, _ = _octagon_touches(a0ib, {})
    centre, rho_form, _ = _octagon_touches(a0ib, {"ball_form": form})
    np.testing.assert_allclose(centre, exact, atol=FIT_M)
    assert rho_form - rho == pytest.approx(-a / 2, abs=FIT_M)
    start = np.array([2.5 * MM, 1.5 * MM - 40 * MM, 0.0, 0.0, 0.0])
    plain = TouchProbe(a0ib, None, flat, noise=False, resolution=0.0).touch(start, "-Z", 2 * MM)
    formed = TouchProbe(a0ib, None, flat, noise=False, resolution=0.0, ball_form=form).touch(
        start, "-Z", 2 * MM)
    assert formed[2] - plain[2] == pytest.approx(a, abs=1e-18)
    # pre-travel does not act along the probe axis
    lobed = TouchProbe(a0ib, None, flat, noise=False, resolution=0.0,
                       pretravel=Lobing(((3, a, 0.0),))).touch(start, "-Z", 2 * MM)
    assert np.array_equal(lobed, plain)


def test_a_pretravel_or_ball_form_in_um_given_as_m_is_refused(a0ib, flat):
    """0.1 um of lobing given as 0.1 read a touch of the block's side 0.1 m early (the ball
    centre at x = -100.25 mm for -0.25 mm), and 0.1 um of form given as 0.1 one 50 mm
    inside the part; both stay far beyond the first-order model they feed. Up to 1 % of the
    radius (DEPARTURE_SHARE) is read, on the closed form: touched square to a face along x,
    a lobe of order k at phase 0 presses a cos(k pi) in."""
    start = np.array([-1 * MM, 1.5 * MM - 40 * MM, -0.5 * MM - 1 * MM, 0.0, 0.0])
    for options in ({"pretravel": Lobing(((3, 0.1, 0.0),))},
                    {"ball_form": ZonalForm((2,), [0.1], [[0.0, 0.0, 1.0]])},
                    {"pretravel": Lobing(((3, 1.5 * UM, 0.0),)),
                     "ball_form": ZonalForm((2,), [1.5 * UM], [[0.0, 0.0, 1.0]])}):
        with pytest.raises(InputError, match=r"amplitudes to sum to at most 0.0025 mm"):
            TouchProbe(a0ib, None, flat, noise=False, resolution=0.0, **options)
    plain = TouchProbe(a0ib, None, flat, noise=False, resolution=0.0).touch(start, "+X", 2 * MM)
    lobed = TouchProbe(a0ib, None, flat, noise=False, resolution=0.0,
                       pretravel=Lobing(((3, 2.5 * UM, 0.0),))).touch(start, "+X", 2 * MM)
    assert plain[0] == pytest.approx(-R, abs=1e-18)
    # the normal points along -x (phi = pi): p = 2.5 um cos(3 pi), read 2.5 um early
    assert lobed[0] - plain[0] == pytest.approx(-2.5 * UM, abs=1e-18)


def test_drawn_forms_have_the_stated_peak_to_valley():
    form = ZonalForm.draw(np.random.default_rng(1), 0.13 * UM)
    assert np.ptp(form(fibonacci_sphere(FORM_POINTS))) == pytest.approx(0.13 * UM, rel=1e-12)
    assert form.degrees == (2, 3, 4)
    with pytest.raises(InputError, match="degrees"):
        ZonalForm((1,), [1e-7], [[0, 0, 1]])


@pytest.mark.parametrize("degrees", [(2.7,), ("3",), "2", (True,), 2])
def test_a_form_degree_is_a_whole_number(degrees):
    # int() read 2.7 as degree 2 and "3" (or the text "2") as a degree without a word; a
    # bare 2 ended in a TypeError ('int' object is not iterable)
    with pytest.raises(InputError, match="form degrees as whole numbers >= 2"):
        ZonalForm(degrees, [1e-7], [[0, 0, 1]])
    # a numpy integer is a degree: P2(v . z) on the pole is the amplitude itself
    form = ZonalForm((np.int64(2),), [1e-7], [[0, 0, 1]])
    assert form.degrees == (2,) and form([0.0, 0.0, 1.0]) == pytest.approx(1e-7, rel=1e-15)


# --------------------------------------------------------------------- laser interferometer


def test_beam_misalignment_gives_the_cosine_error(a0ib):
    a, b = 3e-4, -4e-4
    laser = LaserInterferometer(a0ib, None, noise=False, resolution=0.0, alignment=[a, b])
    x = np.linspace(-0.1, 0.1, 5)
    reading = laser.positioning("X", x)
    np.testing.assert_allclose(reading.deviation, (x - x[0]) * (1 / math.sqrt(1 + a * a + b * b)
                                                                - 1), rtol=0, atol=1e-18)


def test_beam_misalignment_in_mrad_given_as_rad_is_refused(a0ib):
    # alignment=(0.1, 0), 0.1 mrad meant, read every travel short by 1 - 1/sqrt(1.01):
    # 0.50 mm over 0.1 m, the cosine error of 0.1 rad
    with pytest.raises(InputError, match=r"alignment angles within 0.01 rad .* got \[0.1, 0.0\]"):
        LaserInterferometer(a0ib, None, alignment=[0.1, 0.0])
    with pytest.raises(InputError, match="alignment angles within 0.01 rad"):
        LaserInterferometer(a0ib, None, alignment=[0.0, -0.02])
    # at the bound it reads, with its cosine error: 5e-5 of the travel
    laser = LaserInterferometer(a0ib, None, noise=False, resolution=0.0, alignment=[1e-2, 0.0])
    reading = laser.positioning("X", [0.0, 0.1])
    assert reading.deviation[1] == pytest.approx(0.1 * (1 / math.sqrt(1 + 1e-4) - 1),
                                                 rel=1e-9, abs=0)

