"""Realism: each imperfection against a closed form, off-switchable bit for bit, each drawn
from its own stream; the background and the artefacts as part of the lab's truth."""

from __future__ import annotations

import math

import manifold3d
import numpy as np
import pytest

import machinesim
from machinesim import ErrorModel, Lab
from machinesim.errors import ComponentError
from machinesim.exceptions import InputError
from machinesim.metrology import (
    LaserInterferometer,
    Microscope,
    TouchProbe,
    WhiteLightInterferometer,
    fit_sphere,
)
from machinesim.metrology.imperfections import (
    FORM_POINTS,
    Lobing,
    Registration,
    Spot,
    ZonalForm,
    fibonacci_sphere,
)
from machinesim.nc import ProgramBuilder
from machinesim.realism import (
    ARTEFACT,
    Realism,
    SphereArtefacts,
    add_errors,
    background_model,
)
from machinesim.streams import stream
from machinesim.tolerances import TABULATED_SUM
from machinesim.workpiece import Part, block, block_with_spheres

MM, UM, NM = 1e-3, 1e-6, 1e-9
R = 0.25 * MM
#: Heights of mm-scale geometry carry float64 round-off of ~1e-19 m; a transformed mesh
#: (registration) ~1e-18 m: 1e-15 m fails on any modelling error above a femtometre.
ROUND_OFF_M = 1e-15
#: A fitted centre from exact contacts on mm-scale geometry: round-off ~1e-18 m, and the
#: first-order pre-travel model's second order, (0.1 um)^2 / 2 mm ~ 1e-12 m.
FIT_M = 1e-11
TRUTH = {"tool": {"offset_um": [5.0, -3.0, 1.0]}, "location": {"C": {"EX0C_um": 2.0}}}
STEP_X, STEP_H = 2.5 * MM, 1.0 * UM


def groove():
    return (ProgramBuilder(1).rapid(X=1e-3, Y=1e-3, Z=1e-3).linear(Z=-1e-5, feed_mm_per_min=100)
            .linear(X=8e-3, feed_mm_per_min=100).rapid(Z=1e-3).build())



@pytest.fixture(scope="module")
def step():
    """The flat block with its half x >= 2.5 mm raised by 1 um: a step edge along y."""
    raised = block(2.5 * MM, 3 * MM, 1 * MM).manifold.translate((STEP_X, 0.0, STEP_H))
    return Part(block(5 * MM, 3 * MM, 1 * MM).manifold + raised)


@pytest.fixture(scope="module")
def cut_part():
    part, _ = Lab("robonano_a0ib", TRUTH, noise=False).cut(groove(), "v:90", "block:10x10x2")
    return part


# ------------------------------------------------------------------------------- switches


def test_presets_and_variants():
    assert Realism.ideal().on == () and Realism() == Realism.ideal()
    assert Realism.noise_only().on == ("instrument_noise",)
    assert Realism.lab().on == Realism.names() and len(Realism.names()) == 10
    budget = [Realism.lab().without(name) for name in Realism.names()]
    assert all(len(r.on) == 9 for r in budget)
    assert Realism.with_only("registration", "lateral_noise").on == ("lateral_noise",
                                                                      "registration")
    assert str(Realism.lab()) == "lab" and str(Realism.noise_only()) == "noise_only"
    assert str(Realism.with_only("registration")) == "registration"
    with pytest.raises(InputError, match="realism switch"):
        Realism.lab().without("thermal")
    with pytest.raises(InputError, match="registration"):
        Realism(registration="yes")


def test_a_realism_says_which_switches_are_on():
    """Its repr had been the dataclass dump of all ten flags ('Realism(instrument_noise=
    True, lateral_resolution=False, ...)'): the preset, or the switches on (in their order)
    and how many are off, or the lab's without the few that are off."""
    assert repr(Realism.ideal()) == "Realism(ideal: all 10 off)"
    assert repr(Realism.lab()) == "Realism(lab: all 10 on)"
    assert repr(Realism.noise_only()) == "Realism(noise_only: instrument_noise on; 9 off)"
    assert repr(Realism.with_only("registration", "lateral_noise")) == (
        "Realism(lateral_noise, registration on; 8 off)")
    assert repr(Realism.lab().without("air_refraction", "registration")) == (
        "Realism(lab without registration, air_refraction)")


def test_lab_arguments():
    assert repr(Lab("robonano_a0ib", seed=2)) == "Lab(robonano_a0ib, noise=on, seed=2)"
    assert repr(Lab("robonano_a0ib", seed=2, realism=Realism.lab().without("registration"))
                ).endswith("realism=instrument_noise+lateral_resolution+lateral_noise+"
                           "probe_pretravel+probe_ball_form+artefact_errors+background_errors+"
                           "stage_positioning+air_refraction)")
    assert Lab("robonano_a0ib", noise=False).realism == Realism.ideal()
    assert Lab("robonano_a0ib", realism=Realism.ideal()).noise is False
    with pytest.raises(InputError, match="not both"):
        Lab("robonano_a0ib", noise=False, realism=Realism.lab())
    with pytest.raises(InputError, match="Realism"):
        Lab("robonano_a0ib", realism="lab")


# ------------------------------------------------------- off gives today's readings exactly


def test_the_default_lab_reads_as_instruments_built_directly_and_as_noise_only(a0ib,
                                                                                cut_part):
    """Lab(...) and Lab(..., realism=Realism.noise_only()) read bit for bit what the
    instruments built as before (the lab's stream, no imperfection) read."""
    seed = 5
    labs = [Lab("robonano_a0ib", TRUTH, seed=seed),
            Lab("robonano_a0ib", TRUTH, seed=seed, realism=Realism.noise_only())]
    truth = ErrorModel.from_dict(TRUTH)
    direct = {
        "microscope": Microscope(rng=stream(seed, "microscope", "0")),
        "white": WhiteLightInterferometer(rng=stream(seed, "white_light_interferometer", "0")),
        "probe": TouchProbe(a0ib, truth, cut_part, rng=stream(seed, "touch_probe", "0")),
        "laser": LaserInterferometer(a0ib, truth, rng=stream(seed, "laser_interferometer",
                                                             "0")),
    }

    def read(instruments):
        q = np.zeros(5)
        q[:3] = 5 * MM, 1 * MM - 40 * MM, 1 * MM
        return [instruments["microscope"].profile(cut_part, (5e-3, 0.5e-3), (5e-3, 1.5e-3)).z,
                instruments["microscope"].height_map(cut_part, 4e-3, 4.01e-3, 1e-3, 1.01e-3).z,
                instruments["white"].profile(cut_part, (2e-3, 0.0), (2e-3, 2e-3)).z,
                instruments["probe"].touch(q, "-Z", 2 * MM),
                instruments["laser"].positioning("X", np.linspace(-0.1, 0.1, 5)).deviation]

    expected = read(direct)
    for lab in labs:
        got = read({"microscope": lab.microscope(), "white": lab.white_light_interferometer(),
                    "probe": lab.touch_probe(cut_part), "laser": lab.laser_interferometer()})
        for a, b in zip(got, expected, strict=True):
            assert np.array_equal(a, b, equal_nan=True)
    assert labs[0].reveal() is labs[0].reveal(background=False)
    assert labs[0].reveal_background().is_zero and labs[0].reveal_artefacts() == {}


def test_each_imperfection_draws_from_its_own_stream(cut_part):
    """Turning one switch off changes nothing another draws: the registrations, the probe's
    lobing and ball form, and the height noise are the same in every variant."""
    def drawn(realism):
        lab = Lab("robonano_a0ib", TRUTH, seed=9, realism=realism)
        lab.microscope(label="m")
        lab.white_light_interferometer(label="w")
        lab.touch_probe(cut_part, label="p")
        lab.laser_interferometer(label="l")
        return lab.reveal_instruments()

    full = drawn(Realism.lab())
    for name in Realism.names():
        variant = drawn(Realism.lab().without(name))
        for instrument, imperfections in variant.items():
            for key, value in imperfections.items():
                reference = full[instrument][key]
                if isinstance(value, Registration):
                    assert np.array_equal(value.offset, reference.offset)
                    assert value.rotation == reference.rotation
                elif isinstance(value, Lobing):
                    assert value.harmonics == reference.harmonics
                elif isinstance(value, ZonalForm):
                    assert np.array_equal(value.amplitudes, reference.amplitudes)
                else:
                    assert np.array_equal(value, reference)
    assert set(full["microscope/m"]) == {"registration"}
    assert set(full["touch_probe/p"]) == {"pretravel", "ball_form"}
    assert set(drawn(Realism.lab().without("registration"))["microscope/m"]) == set()

    # the height noise: (noise + registration) - registration == noise - exact, exactly
    def z(realism):
        lab = Lab("robonano_a0ib", TRUTH, seed=9, realism=realism)
        scope = lab.microscope(label="m", resolution=0.0)
        return scope.profile(cut_part, (5e-3, 0.5e-3), (5e-3, 1.5e-3)).z

    with_registration = z(Realism.with_only("instrument_noise", "registration")) - z(
        Realism.with_only("registration"))
    alone = z(Realism.noise_only()) - z(Realism.ideal())
    np.testing.assert_allclose(with_registration, alone, rtol=0, atol=ROUND_OFF_M)


# ------------------------------------------------------------------------ optical instruments


def test_registration_shows_on_a_flat_as_the_drawn_offset_and_tilt(flat):
    reg = Registration([3 * UM, -2 * UM, 7 * UM], 2e-3, [1.5e-4, -0.8e-4])
    scope = Microscope(noise=False, resolution=0.0, registration=reg)
    heights = scope.height_map(flat, 1 * MM, 1.2 * MM, 1 * MM, 1.1 * MM, spacing=20 * UM)
    x, y = np.meshgrid(heights.x, heights.y)
    np.testing.assert_allclose(heights.z, 7 * UM + 1.5e-4 * x - 0.8e-4 * y, rtol=0,
                               atol=ROUND_OFF_M)
    prof = scope.profile(flat, (1 * MM, 2 * MM), (2 * MM, 1 * MM), spacing=0.1 * MM)
    np.testing.assert_allclose(prof.z, 7 * UM + prof.xy @ [1.5e-4, -0.8e-4], rtol=0,
                               atol=ROUND_OFF_M)
    # the one instrument keeps its registration; reading again gives the same
    assert np.array_equal(scope.profile(flat, (1 * MM, 2 * MM), (2 * MM, 1 * MM),
                                        spacing=0.1 * MM).z, prof.z)


def test_a_registration_tilt_in_mrad_given_as_rad_is_refused(flat):
    # tilt=(0.2, 0), the lab's 0.2 mrad meant, sheared the flat to a slope of 0.2 (11 deg)
    # and it read so, silently; the shear model holds for a levelled part only
    with pytest.raises(InputError, match=r"tilt slopes within 0.01 rad .* got \[0.2, 0.0\]"):
        Registration([0.0, 0.0, 0.0], 0.0, [0.2, 0.0])
    with pytest.raises(InputError, match="tilt slopes within 0.01 rad"):
        Registration(tilt=[0.0, -0.011])
    # at the bound it reads the flat as that slope
    scope = Microscope(noise=False, resolution=0.0,
                       registration=Registration(tilt=[1e-2, -1e-2]))
    prof = scope.profile(flat, (1 * MM, 2 * MM), (2 * MM, 1 * MM), spacing=0.1 * MM)
    np.testing.assert_allclose(prof.z, prof.xy @ [1e-2, -1e-2], rtol=0, atol=ROUND_OFF_M)


def test_registration_moves_an_edge_to_where_the_instrument_frame_puts_it(step):
    """The step x = 2.5 mm of the workpiece lies, along the instrument's line y = y0, at
    xi = (2.5 mm - tx + sin(t) y0) / cos(t)."""
    theta, tx, ty, y0 = 3e-3, 4 * UM, -6 * UM, 1.5 * MM
    scope = Microscope(noise=False, resolution=0.0,
                       registration=Registration([tx, ty, 0.0], theta, [0.0, 0.0]))
    spacing = 10 * NM
    prof = scope.profile(step, (2.45 * MM, y0), (2.55 * MM, y0), spacing=spacing)
    first_up = prof.xy[np.argmax(prof.z > STEP_H / 2), 0]
    edge = (STEP_X - tx + math.sin(theta) * y0) / math.cos(theta)
    assert edge <= first_up < edge + spacing
    unregistered = Microscope(noise=False, resolution=0.0).profile(
        step, (2.45 * MM, y0), (2.55 * MM, y0), spacing=spacing)
    assert unregistered.xy[np.argmax(unregistered.z > STEP_H / 2), 0] == pytest.approx(
        STEP_X, abs=spacing)


@pytest.mark.parametrize("shape", ["tophat", "gaussian"])
def test_a_spot_turns_a_step_into_the_spots_cumulative_weights(step, shape):
    """Across a step edge each reading is the step height times the weight of the spot's
    points beyond the edge: for a top-hat of width w, a staircase of n equal steps over w
    (the ramp of width w in the limit)."""
    spot = Spot(2 * UM, shape, samples=7)
    scope = Microscope(noise=False, resolution=0.0, spot=spot)
    prof = scope.profile(step, (STEP_X - 3 * UM, 1 * MM), (STEP_X + 3 * UM, 1 * MM),
                         spacing=0.1 * UM + 1e-12)  # never exactly on the edge
    offsets, weights = spot.axis()
    x = prof.xy[:, 0]
    beyond = (x[:, None] + offsets[None, :]) >= STEP_X
    np.testing.assert_allclose(prof.z, STEP_H * (beyond * weights).sum(axis=1), rtol=0,
                               atol=ROUND_OFF_M)
    if shape == "tophat":
        # (the raised top is 1 um to round-off of the 1 mm block it was translated with)
        rising = x[(prof.z > 1e-3 * STEP_H) & (prof.z < (1 - 1e-3) * STEP_H)]
        assert rising.min() >= STEP_X - spot.width / 2
        assert rising.max() < STEP_X + spot.width / 2
        assert len(np.unique(np.round(prof.z / STEP_H * 7))) == 8
    # the same through a height map, rows alike
    heights = scope.height_map(step, STEP_X - 3 * UM, STEP_X + 3 * UM, 1 * MM, 1.0004 * MM,
                               spacing=0.1 * UM + 1e-12)
    beyond = (heights.x[:, None] + offsets[None, :]) >= STEP_X
    for row in heights.z:
        np.testing.assert_allclose(row, STEP_H * (beyond * weights).sum(axis=1), rtol=0,
                                   atol=ROUND_OFF_M)


def test_a_round_spot_reads_a_slanted_edge_as_a_square_one(step):
    """A Gaussian spot is round: across a step edge turned by 30 deg, read along the edge's
    normal, each reading is the step height times the weight of the spot's points beyond the
    edge along that normal, the closed form of the square edge (its quadrature laid along
    the line; split into the instrument's x and y it would be 7 x 7 different offsets)."""
    turn = 30.0
    slanted = Part(step.manifold.rotate((0.0, 0.0, turn)))
    spot = Spot(2 * UM, "gaussian", samples=7)
    scope = Microscope(noise=False, resolution=0.0, spot=spot)
    u = np.array([math.cos(math.radians(turn)), math.sin(math.radians(turn))])
    n = np.array([-u[1], u[0]])
    foot = STEP_X * u + 1 * MM * n  # on the turned edge
    s0 = 3 * UM
    prof = scope.profile(slanted, foot - s0 * u, foot + s0 * u, spacing=0.1 * UM + 1e-12)
    offsets, weights = spot.axis()
    beyond = (prof.s[:, None] - s0 + offsets[None, :]) >= 0.0
    np.testing.assert_allclose(prof.z, STEP_H * (beyond * weights).sum(axis=1), rtol=0,
                               atol=1e-14)


def test_a_spot_reads_an_edge_and_a_through_hole_where_they_are_whatever_its_samples():
    """A plate 50 um square with a through hole x, y in [20, 30] um: read along y = 25 um
    without a spot, the samples strictly inside the hole read NaN, the rest the top (0).
    Through a symmetric spot the same samples read NaN (less than half its weight on the
    plate) and the rest 0: the hole's edges stay where they are. Averaging any sub-sample
    that hit the plate, a 3 um Gaussian had read into the hole up to its outermost node,
    3.6 um at 5 samples, 10 um at 25 (no NaN left), the finer the smaller the hole."""
    hole = manifold3d.Manifold.cube((10 * UM, 10 * UM, 1 * MM)).translate(
        (20 * UM, 20 * UM, -0.5 * MM))
    plate = Part(block(50 * UM, 50 * UM, 10 * UM).manifold - hole)
    a, b, spacing = (5 * UM, 25 * UM), (45 * UM, 25 * UM), 0.1 * UM + 1e-12  # off the edges
    bare = Microscope(noise=False, resolution=0.0).profile(plate, a, b, spacing)
    x = bare.xy[:, 0]
    inside = (x > 20 * UM) & (x < 30 * UM)
    assert np.array_equal(bare.missing, inside) and inside.sum() == 100
    np.testing.assert_allclose(bare.z[~inside], 0.0, rtol=0, atol=ROUND_OFF_M)
    for shape in ("gaussian", "tophat"):
        for samples in (5, 9, 25):
            scope = Microscope(noise=False, resolution=0.0, spot=Spot(3 * UM, shape, samples))
            prof = scope.profile(plate, a, b, spacing)
            assert np.array_equal(prof.missing, inside), (shape, samples)
            np.testing.assert_allclose(prof.z[~inside], 0.0, rtol=0, atol=ROUND_OFF_M)
        hm = scope.height_map(plate, 5 * UM, 45 * UM, 24 * UM, 26 * UM, spacing)  # 25 too
        assert np.array_equal(hm.missing, np.broadcast_to(inside, hm.z.shape))


def test_a_spot_of_even_samples_reads_a_through_hole_where_it_is():
    """The plate with its 10 um through hole of the test above, read along y = 25 um through
    spots of 2, 4 and 6 samples. Such a spot has no node at its centre: within its innermost
    node's offset of the hole's edge (a 3 um FWHM Gaussian of 2 samples: sigma = 1.27 um) half
    its weight lies on the plate on either side of the edge, so at 'at least half' the samples
    up to 1.27 um inside the hole read the plate: 75 NaN of the 100 at 2 samples, 81 and 85
    at 4 and 6 (innermost nodes 0.95, 0.79 um), a top-hat's 85, 93, 95 (0.75, 0.375, 0.25
    um). A tie goes by the spot's centre, read as a point sample: NaN exactly at the 100
    samples strictly inside the hole, as without a spot."""
    hole = manifold3d.Manifold.cube((10 * UM, 10 * UM, 1 * MM)).translate(
        (20 * UM, 20 * UM, -0.5 * MM))
    plate = Part(block(50 * UM, 50 * UM, 10 * UM).manifold - hole)
    a, b, spacing = (5 * UM, 25 * UM), (45 * UM, 25 * UM), 0.1 * UM + 1e-12  # off the edges
    for shape in ("gaussian", "tophat"):
        for samples in (2, 4, 6):
            scope = Microscope(noise=False, resolution=0.0, spot=Spot(3 * UM, shape, samples))
            prof = scope.profile(plate, a, b, spacing)
            x = prof.xy[:, 0]
            inside = (x > 20 * UM) & (x < 30 * UM)
            assert inside.sum() == 100
            assert np.array_equal(prof.missing, inside), (shape, samples, prof.missing.sum())
            np.testing.assert_allclose(prof.z[~inside], 0.0, rtol=0, atol=ROUND_OFF_M)
            # rows of y 24.5 .. 25.5 um: the 6-sample Gaussian's outermost nodes (4.24 um)
            # stay inside the hole's y extent, 20 .. 30 um
            hm = scope.height_map(plate, 5 * UM, 45 * UM, 24.5 * UM, 25.5 * UM, spacing)
            assert np.array_equal(hm.missing, np.broadcast_to(inside, hm.z.shape)), (
                shape, samples)


def test_a_spot_reads_a_plane_unchanged(flat):
    reg = Registration([0.0, 0.0, 1 * UM], 0.0, [2e-4, 1e-4])
    for shape in ("tophat", "gaussian"):
        scope = Microscope(noise=False, resolution=0.0, registration=reg,
                           spot=Spot(0.5 * UM, shape))
        heights = scope.height_map(flat, 1 * MM, 1.01 * MM, 1 * MM, 1.01 * MM, spacing=1 * UM)
        x, y = np.meshgrid(heights.x, heights.y)
        np.testing.assert_allclose(heights.z, 1 * UM + 2e-4 * x + 1e-4 * y, rtol=0,
                                   atol=ROUND_OFF_M)


def test_lateral_noise_moves_each_sample_by_its_drawn_amount(flat):
    """On a tilted flat (slopes sx, sy) a profile along x reads the plane at x + ds_i and
    y + d_across; a map at x_i + dx_i, y_j + dy_j. The draws come from the lateral stream
    alone, in that order, and do not touch the height noise's."""
    sx, sy, sigma = 2e-4, -3e-4, 50 * NM
    reg = Registration([0.0, 0.0, 0.0], 0.0, [sx, sy])
    scope = Microscope(noise=False, resolution=0.0, registration=reg, lateral_sigma=sigma,
                       lateral_rng=11)
    prof = scope.profile(flat, (1 * MM, 1 * MM), (1.01 * MM, 1 * MM), spacing=1 * UM)
    draws = np.random.default_rng(11).standard_normal(len(prof.s) + 1) * sigma
    np.testing.assert_allclose(prof.z, sx * (prof.xy[:, 0] + draws[:-1])
                               + sy * (1 * MM + draws[-1]), rtol=0, atol=ROUND_OFF_M)
    heights = scope.height_map(flat, 1 * MM, 1.005 * MM, 1 * MM, 1.003 * MM, spacing=1 * UM)
    rng = np.random.default_rng(11)
    rng.standard_normal(len(prof.s) + 1)
    dx = rng.standard_normal(len(heights.x)) * sigma
    dy = rng.standard_normal(len(heights.y)) * sigma
    np.testing.assert_allclose(heights.z, sx * (heights.x + dx)[None, :]
                               + sy * (heights.y + dy)[:, None], rtol=0, atol=ROUND_OFF_M)
    # the height noise is drawn from the instrument's own stream, as without lateral noise
    noisy = Microscope(resolution=0.0, rng=3, lateral_sigma=sigma, lateral_rng=11)
    plain = Microscope(resolution=0.0, rng=3)
    a = noisy.profile(flat, (1 * MM, 1 * MM), (1.01 * MM, 1 * MM), spacing=1 * UM).z
    b = plain.profile(flat, (1 * MM, 1 * MM), (1.01 * MM, 1 * MM), spacing=1 * UM).z
    assert np.array_equal(a, b)  # a level flat: the jitter moves nothing


def test_the_lab_optical_instruments_with_realism(cut_part):
    lab = Lab("robonano_a0ib", TRUTH, seed=4, realism=Realism.lab())
    scope = lab.microscope(label="a")
    assert scope.spot.width == 0.3 * UM and scope.lateral_sigma == 20 * NM
    assert lab.white_light_interferometer().spot.width == 0.8 * UM
    own = lab.microscope(spot=None, lateral_sigma=0.0, registration=None)
    assert own.spot is None and lab.reveal_instruments()["microscope/0"] == {}
    z = scope.profile(cut_part, (5e-3, 0.5e-3), (5e-3, 1.5e-3)).z
    assert np.isfinite(z).all()


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


# ------------------------------------------------------------------------------- artefacts


def _same_mesh(a: Part, b: Part) -> bool:
    """The same vertices, bit for bit, and the same triangles in any order (manifold3d's
    output order depends on which operands it had evaluated before)."""
    (va, ta), (vb, tb) = a.mesh(), b.mesh()

    def canonical(vertices, triangles):
        corners = [tuple(map(tuple, vertices[t])) for t in triangles]
        return sorted(min(c[k:] + c[:k] for k in range(3)) for c in corners)

    return canonical(va, ta) == canonical(vb, tb)


def test_artefacts_off_are_the_design_made_exactly(flat):
    design = SphereArtefacts(np.array([[1.2, 1.0, 0.0], [3.8, 1.0, 0.0], [1.2, 2.0, 0.0]]) * MM,
                             0.25 * MM, cavities=True)
    lab = Lab("robonano_a0ib", seed=1)
    made = lab.make_artefacts(flat, design, label="block")
    reference = block_with_spheres(5 * MM, 3 * MM, 1 * MM, 0.25 * MM,
                                   design.centres[:, :2], dimples=True)
    assert _same_mesh(made, reference)
    actual = lab.reveal_artefacts()["block"]
    assert np.array_equal(actual.centres, design.centres) and actual.radius == 0.25 * MM
    with pytest.raises(InputError, match="label"):
        lab.make_artefacts(flat, design, label=None)


def test_artefacts_are_made_in_a_stock_given_as_a_spec_as_cut_takes_it():
    """docs/lab.md's lab.make_artefacts(stock, design, label=) took a Part only: the spec
    lab.cut takes, "block:10x10x2", ended in TypeError: unsupported operand type(s) for -:
    'str' and 'Manifold' inside realism.make_spheres. Now it is read as cut reads it (mm),
    the same workpiece as the Part built by hand; anything else is refused naming 'stock'."""
    design = SphereArtefacts(np.array([[1.2, 1.0, 0.0], [3.8, 1.0, 0.0], [1.2, 2.0, 0.0]]) * MM,
                             0.25 * MM)
    made = Lab("robonano_a0ib", seed=1).make_artefacts("block:5x3x1", design, label="a")
    reference = block_with_spheres(5 * MM, 3 * MM, 1 * MM, 0.25 * MM,
                                   design.centres[:, :2], dimples=True)
    assert _same_mesh(made, reference)
    with pytest.raises(InputError, match=r"key 'stock': Expected stock as a spec such as "
                                         r"'block:10x10x2' or a Part, got NoneType"):
        Lab("robonano_a0ib").make_artefacts(None, design, label="a")


def test_a_sphere_design_in_mm_is_refused_before_its_polygon_is_built():
    """SphereArtefacts(centres, 1.0), a radius of 1 mm given as m, was taken, and
    make_artefacts then built a sphere polygon of some 12 million vertices per sphere at
    the default chord_tol (over 120 s, never finishing). Now refused at design, naming the
    radius, the polygon's size against MAX_TOOL_VERTICES and the unit; 1 mm is made."""
    centres = np.array([[2.0, 2.0, 0.0], [8.0, 2.0, 0.0], [5.0, 8.0, 0.0]])
    with pytest.raises(InputError, match=r"key 'radius': a sphere of radius 1 m at chord_tol "
                                         r"1e-07 m would be a polygon of some 12,348,196 "
                                         r"vertices, over MAX_TOOL_VERTICES \(200,000\): "
                                         r"expected the radius in m"):
        SphereArtefacts(centres, 1.0)
    assert SphereArtefacts(centres * MM, 1.0 * MM).radius == 1e-3


def test_artefacts_on_are_drawn_per_workpiece_and_cut_where_they_are(flat):
    centres = np.array([[1.2, 1.0, 0.0], [3.8, 1.0, 0.0], [1.2, 2.0, 0.0]]) * MM
    design = SphereArtefacts(centres, 0.4 * MM)

    def made(label, extra=False):
        lab = Lab("robonano_a0ib", seed=2, realism=Realism.with_only("artefact_errors"))
        if extra:
            lab.make_artefacts(flat, design, label="other")
            lab.microscope()
        part = lab.make_artefacts(flat, design, label=label)
        return part, lab.reveal_artefacts()[label]

    part, actual = made("crown")
    _, again = made("crown", extra=True)
    _, other = made("grooves")
    assert np.array_equal(actual.centres, again.centres) and actual.radius == again.radius
    assert not np.array_equal(actual.centres, other.centres)
    shift = actual.centres - centres
    assert 0.1 * UM < np.abs(shift).max() < 5 * ARTEFACT.position
    assert abs(actual.radius - 0.4 * MM) < 5 * ARTEFACT.radius
    # the cavity's vertices lie on the actual sphere: its radius plus the form there
    vertices, _ = part.mesh()
    for c, form in zip(actual.centres, actual.forms, strict=True):
        d = vertices - c
        r = np.linalg.norm(d, axis=1)
        near = np.flatnonzero((np.abs(r - actual.radius) < 3 * ARTEFACT.form)
                              & (vertices[:, 2] < -1 * UM))
        assert len(near) > 100
        np.testing.assert_allclose(r[near], actual.radius + form(d[near] / r[near, None]),
                                   rtol=0, atol=1e-12)
        fitted = fit_sphere(vertices[near])
        assert np.linalg.norm(fitted.centre - c) < ARTEFACT.form


def test_a_workpiece_asked_for_again_is_the_one_the_lab_made(flat):
    # A procedure asks the lab in measure and again in evaluate, keeping no lab between them
    # (RobotLoadedWorkpiece had kept every lab it met, and the workpiece, in _workpieces:
    # its identify could reach lab.reveal()). Made twice, a workpiece came back with its
    # triangles in another order (manifold3d), a stock its cuts' memo keys apart.
    centres = np.array([[1.2, 1.0, 0.0], [3.8, 1.0, 0.0], [1.2, 2.0, 0.0]]) * MM
    design = SphereArtefacts(centres, 0.4 * MM)
    lab = Lab("robonano_a0ib", seed=2, realism=Realism.with_only("artefact_errors"))
    first = lab.make_artefacts(flat, design, label="crown")
    actual = lab.reveal_artefacts()["crown"]
    again = lab.make_artefacts(Part(flat.manifold), design, label="crown")  # an equal stock
    assert again is first and lab.reveal_artefacts()["crown"] is actual
    # another design under the label is another workpiece, drawn from the label's stream
    bumps = SphereArtefacts(centres, 0.4 * MM, cavities=False)
    other = lab.make_artefacts(flat, bumps, label="crown")
    assert other is not first and other.volume > first.volume
    assert np.array_equal(lab.reveal_artefacts()["crown"].centres, actual.centres)


# -------------------------------------------------------------------------------- background


def test_background_adds_to_the_injected_errors_in_the_truth(a0ib):
    lab = Lab("robonano_a0ib", TRUTH, realism=Realism.with_only("background_errors"))
    background = background_model(a0ib)
    assert lab.reveal_background() == background
    assert lab.reveal(background=False) == ErrorModel.from_dict(TRUTH)
    total = lab.reveal()
    assert total.location["C"]["EX0C"] == pytest.approx(2 * UM + background.location["C"][
        "EX0C"], abs=1e-21)
    x = np.linspace(-0.14, 0.14, 57)
    np.testing.assert_allclose(total.component["X"]["EYX"].evaluate(x),
                               background.component["X"]["EYX"].evaluate(x), rtol=0,
                               atol=1e-21)
    # what the lab cuts and measures comes from the total
    part, _ = lab.cut(groove(), "v:90", "block:10x10x2")
    direct, _ = machinesim.cut(groove(), a0ib, "v:90", "block:10x10x2", total)
    assert np.array_equal(part.mesh()[0], direct.mesh()[0])
    plain, _ = Lab("robonano_a0ib", TRUTH, noise=False).cut(groove(), "v:90", "block:10x10x2")
    assert not np.array_equal(part.mesh()[0], plain.mesh()[0])
    given = Lab("robonano_a0ib", TRUTH, realism=Realism.lab(), background={})
    assert given.reveal() == ErrorModel.from_dict(TRUTH)


@pytest.mark.parametrize("name", machinesim.list_machines())
def test_every_shipped_machine_has_a_background_it_accepts(name):
    machine = machinesim.load_machine(name)
    model = background_model(machine)
    assert not model.is_zero
    for axis, table in model.component.items():
        for symbol, error in table.items():
            assert error.evaluate([0.0])[0] == 0.0, f"{axis}.{symbol} at the reference"


def test_add_errors_is_exact_on_the_union_of_the_tables():
    a = ErrorModel(location={"C": {"EX0C": 1e-6}}, component={
        "X": {"EXX": ComponentError("table", [-0.1, 0.0, 0.1], [1e-6, 0.0, -2e-6]),
              "EYX": ComponentError("table", [-0.1, 0.0, 0.1], [0.0, 3e-7, 0.0])},
        "Z": {"EZZ": ComponentError("poly", None, [0.0, 1e-5])}})
    b = ErrorModel(location={"C": {"EX0C": 2e-7, "EY0C": -1e-7}}, component={
        "X": {"EXX": ComponentError("table", [-0.12, -0.05, 0.03, 0.12],
                                    [1e-7, -2e-7, 3e-7, 0.0])},
        "Z": {"EZZ": ComponentError("poly", None, [0.0, 0.0, 2e-4])}})
    total = add_errors(a, b)
    assert total.location["C"] == {"EX0C": 1e-6 + 2e-7, "EY0C": -1e-7}
    x = np.linspace(-0.15, 0.15, 301)
    for symbol in ("EXX", "EYX"):
        expected = sum(m.component["X"][symbol].evaluate(x) for m in (a, b)
                       if symbol in m.component["X"])
        np.testing.assert_allclose(total.component["X"][symbol].evaluate(x), expected,
                                   rtol=0, atol=1e-21)
    np.testing.assert_array_equal(total.component["Z"]["EZZ"].values, [0.0, 1e-5, 2e-4])
    with pytest.raises(InputError, match="polynomial"):
        add_errors(ErrorModel(component={"Z": {"EZZ": ComponentError("table", [0.0, 0.1],
                                                                     [0.0, 1e-7])}}), b)
    with pytest.raises(InputError, match="setting"):
        add_errors(a, ErrorModel.from_dict({"tool": {"offset_um": [1.0, 0.0, 0.0]}}))


def test_a_whole_turn_table_summed_with_a_longer_one_still_repeats_each_turn():
    """A rotary table of a whole turn (ECC over -180 .. 180 deg) repeats each turn, and so
    must its part of a sum put on the union with a table of -360 .. 360 deg (EAC, a
    background's wobble, say): at -270 deg it is its value at 90 deg, written out here by
    hand for every 45 deg. It had been held at its end value there (2 urad for 3), and the
    lab's tool at C = -270 deg sat 1 urad turned, 0.1 um off at 100 mm."""
    deg = np.radians
    urad = 1e-6
    ecc = ComponentError("table", deg([-180.0, -90.0, 0.0, 90.0, 180.0]),
                         np.array([2.0, 1.0, 0.0, 3.0, 2.0]) * urad)
    grid = deg(np.arange(-360.0, 361.0, 45.0))
    wobble = ComponentError("table", grid, 1.5 * urad * np.sin(2 * grid))
    total = add_errors(ErrorModel(component={"C": {"ECC": ecc}}),
                       ErrorModel(component={"C": {"EAC": wobble}}))
    each_turn = [0.0, 1.5, 3.0, 2.5, 2.0, 1.5, 1.0, 0.5, 0.0, 1.5, 3.0, 2.5, 2.0, 1.5, 1.0,
                 0.5, 0.0]  # at -360, -315, ... 360 deg: ECC a turn back where beyond it
    np.testing.assert_array_equal(total.component["C"]["ECC"].positions, grid)
    np.testing.assert_allclose(total.component["C"]["ECC"].values,
                               np.array(each_turn) * urad, rtol=0, atol=1e-21)
    np.testing.assert_array_equal(total.component["C"]["EAC"].values, wobble.values)
    machine = machinesim.load_machine("grooving_4axis")
    by_hand = ErrorModel(component={"C": {
        "ECC": ComponentError("table", grid, np.array(each_turn) * urad), "EAC": wobble}})
    q = np.array([[100 * MM, 0.0, 0.0, deg(c)] for c in (-300.0, -270.0, -200.0, 250.0)])
    np.testing.assert_allclose(machine.tool_pose(q, total), machine.tool_pose(q, by_hand),
                               rtol=0, atol=ROUND_OFF_M)


def test_a_polynomial_plus_a_table_is_tabulated_over_the_travel_within_its_tolerance():
    """Linear interpolation of c x^2 at spacing h is off by c h^2 / 4 at each midpoint (by
    hand): the spacing the sum is tabulated at keeps that within TABULATED_SUM, and the other
    tables of the axis move onto the same positions, to round-off."""
    c = 2e-5  # 1/m: the README's example EYX, 2e-5 um/mm^2, 0.39 um at 140 mm
    injected = ErrorModel(component={"X": {"EYX": ComponentError("poly", None, [0.0, 0.0, c])}})
    background = ErrorModel(component={"X": {
        "EYX": ComponentError("table", [-0.14, 0.0, 0.14], [-5e-8, 0.0, 3e-8]),
        "EXX": ComponentError("table", [-0.14, 0.0, 0.14], [2e-8, 0.0, -1e-8])}})
    total = add_errors(injected, background, {"X": (-0.14, 0.14)})
    eyx = total.component["X"]["EYX"]
    assert eyx.kind == "table"
    assert np.array_equal(total.component["X"]["EXX"].positions, eyx.positions)
    h = np.diff(eyx.positions).max()
    assert c * h**2 / 4.0 <= TABULATED_SUM < 1.1 * c * h**2 / 4.0  # not needlessly fine
    x = np.linspace(-0.14, 0.14, 280_001)
    off = eyx.evaluate(x) - (c * x**2 + background.component["X"]["EYX"].evaluate(x))
    assert np.abs(off).max() <= TABULATED_SUM
    assert np.abs(off).max() > 0.5 * TABULATED_SUM  # the bound is what the midpoints reach
    np.testing.assert_allclose(total.component["X"]["EXX"].evaluate(x),
                               background.component["X"]["EXX"].evaluate(x), rtol=0,
                               atol=1e-22)  # round-off of 2e-8 m values: ulp 3.3e-24


def test_a_polynomial_too_curved_to_tabulate_is_refused_naming_it():
    curved = ErrorModel(component={"X": {"EYX": ComponentError("poly", None, [0.0, 0.0, 1e3])}})
    table = ErrorModel(component={"X": {"EYX": ComponentError("table", [0.0, 0.1], [0.0, 1e-8])}})
    with pytest.raises(InputError, match=r"component\.X\.EYX: .* positions .*give it as a table"):
        add_errors(curved, table, {"X": (-0.14, 0.14)})


def test_the_readme_example_errors_run_in_a_lab_with_the_background():
    """robonano_a0ib's background holds EYX as a table; the example's EYX is a polynomial.
    Before, Lab(..., realism=Realism.lab()) refused the pair (so did the flagship scenario's
    --errors models/errors/example.toml); the lab's machine is now their sum."""
    lab = Lab("robonano_a0ib", "models/errors/example.toml", realism=Realism.lab())
    injected, own = lab.reveal(background=False), lab.reveal_background()
    x = np.linspace(-0.14, 0.14, 2801)
    machine_eyx = lab.reveal().component["X"]["EYX"].evaluate(x)
    expected = (injected.component["X"]["EYX"].evaluate(x)
                + own.component["X"]["EYX"].evaluate(x))
    np.testing.assert_allclose(machine_eyx, expected, rtol=0, atol=TABULATED_SUM)


def test_a_labs_seed_and_realism_are_fixed_so_its_artefacts_stay_as_made(flat):
    """make_artefacts hands back the part it made for the same label, stock and design; the
    seed and the realism decide the spheres too. A lab whose seed or realism was set anew
    had handed back the part drawn under the old ones (then made them again, its instruments
    still from the old ones): both are now fixed for the lab's life, and another seed is
    another Lab."""
    from machinesim.exceptions import ReadOnlyError

    design = SphereArtefacts(np.array([[1.2, 1.0, 0.0], [3.8, 1.0, 0.0]]) * MM, 0.4 * MM)
    errors = Realism.with_only("artefact_errors")
    lab = Lab("robonano_a0ib", seed=2, realism=errors)
    first = lab.make_artefacts(flat, design, label="crown")
    assert lab.make_artefacts(flat, design, label="crown") is first  # asked again: the same
    centres = lab.reveal_artefacts()["crown"].centres
    with pytest.raises(ReadOnlyError, match=r"^Lab\.seed cannot be set \(to 3\)"):
        lab.seed = 3
    with pytest.raises(ReadOnlyError, match=r"^Lab\.realism cannot be set"):
        lab.realism = Realism.ideal()
    assert (lab.seed, lab.realism) == (2, errors)
    assert lab.make_artefacts(flat, design, label="crown") is first
    assert np.array_equal(lab.reveal_artefacts()["crown"].centres, centres)
    # another seed is another lab, its spheres drawn from its own streams
    fresh = Lab("robonano_a0ib", seed=3, realism=errors)
    fresh.make_artefacts(flat, design, label="crown")
    assert not np.array_equal(fresh.reveal_artefacts()["crown"].centres, centres)
