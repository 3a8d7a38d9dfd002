"""Realism of the optical instruments (microscope, white-light interferometer), each
imperfection against a closed form: a registration's offset, turn and tilt, a spot's
weights across edges and holes, lateral noise, and the lab's instruments with them."""

from __future__ import annotations

import math

import manifold3d
import numpy as np
import pytest
import realism_helpers
from lab_helpers import TRUTH
from realism_helpers import MM, NM, ROUND_OFF_M, UM

from machinesim import Lab
from machinesim.exceptions import InputError
from machinesim.metrology import Microscope
from machinesim.metrology.imperfections import Registration, Spot
from machinesim.realism import Realism
from machinesim.workpiece import Part, block

#: The groove cut under the lab's truth (a fixture: imported by name, pytest's argument
#: of that name would read as its redefinition)
cut_part = realism_helpers.cut_part

STEP_X, STEP_H = 2.5 * MM, 1.0 * UM


@pytest.fixture(scope="module")
def step():
    """The flat block with its half x >= 2.5 mm raised by 1 um: a step edge along y."""
    raised = block(2.5 * MM, 3 * MM, 1 * MM).manifold.translate((STEP_X, 0.0, STEP_H))
    return Part(block(5 * MM, 3 * MM, 1 * MM).manifold + raised)


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

