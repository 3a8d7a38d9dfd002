"""Stage positioning of the optical instruments: each reading is taken a fresh (dx, dy) off
where it was asked for and reported where it was asked for."""

import numpy as np
import pytest

from machinesim import Lab
from machinesim.metrology import Microscope, WhiteLightInterferometer
from machinesim.realism import MICROSCOPE, Realism

SLOPE = np.array([2e-3, -3e-3])  # a tilted plane: z = SLOPE . (x, y), heights tell positions


class Plane:
    """A height field whose heights give the point read."""

    def heights_at(self, px, py):
        return SLOPE[0] * np.asarray(px) + SLOPE[1] * np.asarray(py)


def plane_mesh():
    corners = np.array([[-1e-3, -1e-3], [1e-3, -1e-3], [1e-3, 1e-3], [-1e-3, 1e-3]])
    vertices = np.column_stack([corners, corners @ SLOPE])
    return vertices, np.array([[0, 1, 2], [0, 2, 3]])


@pytest.mark.parametrize("part", [Plane(), plane_mesh()], ids=["field", "mesh"])
def test_each_reading_sits_where_the_stage_put_it(part):
    sigma = 1e-6
    wli = WhiteLightInterferometer(noise=False, resolution=1e-15, stage_sigma=sigma,
                                   stage_rng=np.random.default_rng(5))
    draws = sigma * np.random.default_rng(5).standard_normal((2, 2))
    x = np.linspace(-1e-4, 1e-4, 5)
    profile = wli.profile(part, (-1e-4, 2e-5), (1e-4, 2e-5), 5e-5)
    np.testing.assert_allclose(profile.xy, np.column_stack([x, np.full(5, 2e-5)]), atol=1e-18)
    expected = (profile.xy + draws[0]) @ SLOPE
    np.testing.assert_allclose(profile.z, expected, atol=1e-15)
    grid = wli.height_map(part, -1e-4, 1e-4, -1e-4, 1e-4, 1e-4)
    gx, gy = np.meshgrid(grid.x, grid.y)
    np.testing.assert_allclose(grid.z, (gx + draws[1][0]) * SLOPE[0]
                               + (gy + draws[1][1]) * SLOPE[1], atol=1e-15)


def test_the_lab_gives_its_stage_only_with_the_switch():
    on = Lab("robonano_a0ib", seed=1, realism=Realism.with_only("stage_positioning"))
    off = Lab("robonano_a0ib", seed=1, realism=Realism.ideal())
    assert on.microscope(label="m").stage_sigma == MICROSCOPE.stage_sigma == 1e-6
    assert off.microscope(label="m").stage_sigma == 0.0
    # without the switch a reading is exactly what it was without the feature
    a = off.microscope(label="m").profile(plane_mesh(), (0, 0), (1e-4, 0), 1e-5)
    b = Microscope(noise=False).profile(plane_mesh(), (0, 0), (1e-4, 0), 1e-5)
    np.testing.assert_array_equal(a.z, b.z)


def test_readings_of_one_placement_share_the_stage_offset():
    sigma = 1e-6
    wli = WhiteLightInterferometer(noise=False, resolution=1e-15, stage_sigma=sigma,
                                   stage_rng=np.random.default_rng(8))
    draws = sigma * np.random.default_rng(8).standard_normal((2, 2))
    with wli.placement():
        first = wli.profile(Plane(), (0.0, 0.0), (1e-4, 0.0), 5e-5)
        second = wli.profile(Plane(), (0.0, 1e-4), (1e-4, 1e-4), 5e-5)
    after = wli.profile(Plane(), (0.0, 0.0), (1e-4, 0.0), 5e-5)
    for reading, shift in ((first, draws[0]), (second, draws[0]), (after, draws[1])):
        np.testing.assert_allclose(reading.z, (reading.xy + shift) @ SLOPE, atol=1e-15)


@pytest.mark.parametrize("part", [Plane(), plane_mesh()], ids=["field", "mesh"])
def test_a_placement_inside_another_is_the_same_and_the_outer_holds_on_after_it(part):
    # the inner placement's end had let go of the outer one: a reading after it, inside the
    # outer placement, was taken at a fresh draw of the stage (draws[1]), 1 um off
    sigma = 1e-6
    wli = WhiteLightInterferometer(noise=False, resolution=1e-15, stage_sigma=sigma,
                                   stage_rng=np.random.default_rng(8))
    draws = sigma * np.random.default_rng(8).standard_normal((3, 2))
    with wli.placement():
        before = wli.profile(part, (0.0, 0.0), (1e-4, 0.0), 5e-5)
        with wli.placement():
            inner = wli.profile(part, (0.0, 1e-4), (1e-4, 1e-4), 5e-5)
        after = wli.profile(part, (0.0, -1e-4), (1e-4, -1e-4), 5e-5)
    alone = wli.profile(part, (0.0, 0.0), (1e-4, 0.0), 5e-5)
    for reading, shift in ((before, draws[0]), (inner, draws[0]), (after, draws[0]),
                           (alone, draws[1])):
        np.testing.assert_allclose(reading.z, (reading.xy + shift) @ SLOPE, atol=1e-15)
