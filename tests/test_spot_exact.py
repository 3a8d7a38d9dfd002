"""The exact Gaussian spot (`Spot(exact=True)`, `machinesim.metrology.blur`): against closed
forms of a step, a corner and a V groove, and against a brute-force fine grid on a mesh
with slanted walls and an overhang."""

from __future__ import annotations

import math

import manifold3d
import numpy as np
import pytest
from realism_helpers import MM, ROUND_OFF_M, UM
from scipy.special import ndtr

from machinesim.exceptions import InputError
from machinesim.metrology import Microscope
from machinesim.metrology._mesh import mesh_arrays
from machinesim.metrology.blur import gaussian_blur
from machinesim.metrology.imperfections import Spot
from machinesim.metrology.surface import grid_heights
from machinesim.workpiece import Part, block

WIDTH = 1 * UM  # FWHM, the 10x objective's
SIGMA = WIDTH / (2.0 * math.sqrt(2.0 * math.log(2.0)))
H = 10 * UM
#: The closed form is exact but for the faces it leaves out beyond REACH (6.5) sigmas,
#: which weigh Phi(-6.5) = 4e-11 beyond a straight wall (4e-16 m of 10 um), and float64
#: round-off of mm-scale coordinates (~1e-19 m): 1e-15 m is 1e-10 of the wall.
EXACT = 1e-15


def _scope() -> Microscope:
    return Microscope(noise=False, resolution=0.0, spot=Spot(WIDTH, exact=True))


@pytest.mark.parametrize("turn", [0.0, 30.0, 90.0])
def test_a_wall_reads_the_erf_of_a_true_gaussian_spot(turn):
    """A 10 um step (x >= 2.5 mm raised) turned about z, read along its normal: the step
    times Phi(d / sigma) at every distance d, where the sub-grid reads a staircase 26.7 % of
    the step off it (docs/metrology.md)."""
    raised = block(2.5 * MM, 3 * MM, 1 * MM).manifold.translate((2.5 * MM, 0.0, H))
    part = Part((block(5 * MM, 3 * MM, 1 * MM).manifold + raised).rotate((0.0, 0.0, turn)))
    c, s = math.cos(math.radians(turn)), math.sin(math.radians(turn))
    u, n = np.array([c, s]), np.array([-s, c])
    foot = 2.5 * MM * u + 1.5 * MM * n
    prof = _scope().profile(part, foot - 3 * UM * u, foot + 3 * UM * u, spacing=0.01 * UM)
    d = prof.s - 3 * UM
    np.testing.assert_allclose(prof.z, H * ndtr(d / SIGMA), rtol=0, atol=EXACT)
    sub = Microscope(noise=False, resolution=0.0, spot=Spot(WIDTH)).profile(
        part, foot - 3 * UM * u, foot + 3 * UM * u, spacing=0.01 * UM)
    assert np.abs(sub.z - H * ndtr(d / SIGMA)).max() > 0.25 * H  # the staircase


def test_a_corner_reads_the_product_of_two_erfs_in_a_map():
    """The quadrant x >= 2.5 mm, y >= 1.5 mm raised by 10 um: H Phi(dx / s) Phi(dy / s)."""
    raised = block(2.5 * MM, 1.5 * MM, 1 * MM).manifold.translate((2.5 * MM, 1.5 * MM, H))
    part = Part(block(5 * MM, 3 * MM, 1 * MM).manifold + raised)
    hm = _scope().height_map(part, 2.5 * MM - 2 * UM, 2.5 * MM + 2 * UM, 1.5 * MM - 2 * UM,
                             1.5 * MM + 2 * UM, spacing=0.1 * UM)
    expected = H * np.outer(ndtr((hm.y - 1.5 * MM) / SIGMA), ndtr((hm.x - 2.5 * MM) / SIGMA))
    np.testing.assert_allclose(hm.z, expected, rtol=0, atol=EXACT)


def _v_groove(depth: float) -> Part:
    """A 90 deg V groove ``depth`` deep along y at x = 1 mm in a 2 x 1 mm block (top z = 0)."""
    side = depth * math.sqrt(2.0)
    cutter = manifold3d.Manifold.cube((side, 2 * MM, side), center=True).rotate(
        (0.0, 45.0, 0.0)).translate((1 * MM, 0.5 * MM, 0.0))
    return Part(block(2 * MM, 1 * MM, 1 * MM).manifold - cutter)


def test_a_v_groove_reads_its_closed_form_blur_at_the_bottom_and_the_lands():
    """z = |x - x0| - D within the groove, 0 on the land: a min of three lines, whose blur
    is E|x + e| - D - E(x + e - D)+ - E(-x - e - D)+ (e ~ N(0, s^2)); read across the bottom
    and both edges of a groove 3 um deep (the land kinks 7 sigma from the bottom)."""
    depth = 3 * UM
    part = _v_groove(depth)
    prof = _scope().profile(part, (1 * MM - 5 * UM, 0.5 * MM), (1 * MM + 5 * UM, 0.5 * MM),
                            spacing=0.05 * UM)
    x = prof.s - 5 * UM

    def relu(a):  # E (a + e)+
        return SIGMA * np.exp(-0.5 * (a / SIGMA) ** 2) / math.sqrt(2 * math.pi) \
            + a * ndtr(a / SIGMA)

    expected = relu(x) + relu(-x) - depth - relu(x - depth) - relu(-x - depth)
    np.testing.assert_allclose(prof.z, expected, rtol=0, atol=EXACT)


def _brute(part, px, py, fine: float) -> np.ndarray:
    """The blur as a midpoint sum of z-buffer heights on a grid of step sigma / fine over +-6
    sigma, shifted off the sample by 0.37 step: independent of the closed form."""
    n = int(6 * fine)
    offsets = (np.arange(-n, n + 1) + 0.37) * SIGMA / fine
    g = np.exp(-0.5 * (offsets / SIGMA) ** 2)
    w = np.outer(g, g)
    out = []
    for x, y in zip(px, py, strict=True):
        z = grid_heights(part, x + offsets, y + offsets)
        seen = np.isfinite(z)
        out.append(np.sum(np.where(seen, z, 0.0) * w) / np.sum(w[seen]))
    return np.array(out)


def test_slanted_walls_and_a_v_flank_read_as_a_fine_grid_sums_them():
    """A block with a raised square turned 17 deg (walls at 17 and 107 deg to x) and a
    V groove turned 25 deg cut across it: at 30 seeded points where the spot sees a wall, a
    kink or both, the closed form within 2e-4 of the 10 um walls of a fine grid's sum (sigma
    / 40; the grid's own error: it moves by up to 1e-5 of the wall against sigma / 80)."""
    base = block(200 * UM, 200 * UM, 50 * UM).manifold
    raised = manifold3d.Manifold.cube((60 * UM, 60 * UM, H)).rotate((0.0, 0.0, 17.0)).translate(
        (70 * UM, 60 * UM, 0.0))
    groove = manifold3d.Manifold.cube((8 * UM, 300 * UM, 8 * UM), center=True).rotate(
        (0.0, 45.0, 0.0)).rotate((0.0, 0.0, 25.0)).translate((100 * UM, 100 * UM, H))
    part = Part(base + raised - groove)
    rng = np.random.default_rng(0)
    px, py = rng.uniform(40 * UM, 160 * UM, 600), rng.uniform(40 * UM, 160 * UM, 600)
    around = np.linspace(-3, 3, 7) * SIGMA
    busy = [i for i in range(px.size)
            if np.ptp(grid_heights(part, px[i] + around, py[i] + around)) > 0.1 * UM][:30]
    assert len(busy) == 30
    total, weight = gaussian_blur(*mesh_arrays(part), px[busy], py[busy], SIGMA)
    np.testing.assert_allclose(weight, 1.0, rtol=0, atol=1e-9)  # all on the part, but REACH
    np.testing.assert_allclose(total, _brute(part, px[busy], py[busy], 40), rtol=0,
                               atol=2e-4 * H)


def test_an_overhang_is_read_on_the_fine_grid_as_the_z_buffer_sees_it():
    """A raised square tilted 3 deg about x and y leans one wall out over the block: the
    upward faces overlap in plan there (the spot weighs up to 2 on them); those samples read
    the fine grid of the z-buffer's highest faces, as a fine grid sums it."""
    base = block(200 * UM, 200 * UM, 50 * UM).manifold
    raised = manifold3d.Manifold.cube((60 * UM, 60 * UM, 20 * UM)).rotate(
        (3.0, -2.0, 17.0)).translate((70 * UM, 60 * UM, -10 * UM))
    part = Part(base + raised)
    rng = np.random.default_rng(1)
    px, py = rng.uniform(40 * UM, 160 * UM, 4000), rng.uniform(40 * UM, 160 * UM, 4000)
    from machinesim.metrology import blur

    planes = blur._planes(*mesh_arrays(part), SIGMA)
    raw = np.array([blur._block(planes, px[i:i + 1], py[i:i + 1], SIGMA)[1][0]
                    for i in range(200)])
    over = np.flatnonzero(raw > 1.0 + blur.OVERLAP)
    assert over.size >= 3  # the overhang is there and seen
    total, weight = gaussian_blur(*mesh_arrays(part), px[over], py[over], SIGMA)
    np.testing.assert_allclose(total / weight, _brute(part, px[over], py[over], 40), rtol=0,
                               atol=2e-4 * 20 * UM)


def test_an_exact_spot_reads_a_plane_and_lateral_noise_as_the_sub_grid_does(flat):
    """The blur of a plane is the plane at the (jittered) sample, as every spot reads it."""
    from machinesim.metrology.imperfections import Registration

    reg = Registration([0.0, 0.0, 1 * UM], 0.0, [2e-4, 1e-4])
    kw = dict(noise=False, resolution=0.0, registration=reg, lateral_sigma=20e-9)
    readings = []
    for spot in (Spot(WIDTH), Spot(WIDTH, exact=True)):
        a = Microscope(**kw, spot=spot, lateral_rng=np.random.default_rng(3))
        b = Microscope(**kw, spot=spot, lateral_rng=np.random.default_rng(3))
        hm = a.height_map(flat, 1 * MM, 1.01 * MM, 1 * MM, 1.01 * MM, spacing=1 * UM)
        prof = b.profile(flat, (1 * MM, 2 * MM), (2 * MM, 1 * MM), spacing=10 * UM)
        readings.append((hm.z, prof.z))
    (sub_map, sub_line), (exact_map, exact_line) = readings
    np.testing.assert_allclose(exact_map, sub_map, rtol=0, atol=ROUND_OFF_M)
    np.testing.assert_allclose(exact_line, sub_line, rtol=0, atol=ROUND_OFF_M)


def test_an_exact_spot_reads_a_through_hole_where_it_is():
    """The 10 um through hole of test_realism_optical: NaN exactly strictly inside it (less
    than half the spot on the plate), the plate's 0 elsewhere."""
    hole = manifold3d.Manifold.cube((10 * UM, 10 * UM, 1 * MM)).translate(
        (20 * UM, 20 * UM, -0.5 * MM))
    plate = Part(block(50 * UM, 50 * UM, 10 * UM).manifold - hole)
    scope = Microscope(noise=False, resolution=0.0, spot=Spot(3 * UM, exact=True))
    prof = scope.profile(plate, (5 * UM, 25 * UM), (45 * UM, 25 * UM), 0.1 * UM + 1e-12)
    x = prof.xy[:, 0]
    inside = (x > 20 * UM) & (x < 30 * UM)
    assert np.array_equal(prof.missing, inside) and inside.sum() == 100
    np.testing.assert_allclose(prof.z[~inside], 0.0, rtol=0, atol=ROUND_OFF_M)


def test_exact_is_off_by_default_and_for_gaussians_only():
    assert Spot(WIDTH).exact is False
    with pytest.raises(InputError, match="exact=True with a 'gaussian' spot.*'tophat'"):
        Spot(WIDTH, "tophat", exact=True)
    with pytest.raises(InputError, match="exact as True or False, got 'yes'"):
        Spot(WIDTH, exact="yes")


def test_the_fine_grid_reads_a_wall_along_x_and_y_to_1e_4():
    """The fine grid that reads an overhang's samples, against the corner's closed form:
    walls along x and y, as machined parts have them. Laid along them it read up to 3.8e-3
    of the wall off (a wall between two node rows reads where the rows are); turned by
    FINE_TURN it reads within 1e-4."""
    from machinesim.metrology.blur import _fine

    raised = block(2.5 * MM, 1.5 * MM, 1 * MM).manifold.translate((2.5 * MM, 1.5 * MM, H))
    part = Part(block(5 * MM, 3 * MM, 1 * MM).manifold + raised)
    px = 2.5 * MM + np.linspace(-2, 2, 21) * UM
    py = 1.5 * MM + np.linspace(-1.5, 2.5, 21) * UM
    read = np.array([_fine(*mesh_arrays(part), a, b, SIGMA) for a, b in zip(px, py,
                                                                            strict=True)])
    expected = H * ndtr((px - 2.5 * MM) / SIGMA) * ndtr((py - 1.5 * MM) / SIGMA)
    np.testing.assert_allclose(read[:, 1], 1.0, rtol=0, atol=1e-9)
    np.testing.assert_allclose(read[:, 0] / read[:, 1], expected, rtol=0, atol=1e-4 * H)
