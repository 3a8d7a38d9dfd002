"""A flat or ball end mill tilted across its straight faces by a rotary move cuts within the
chord tolerance of its true sweep (`machinesim.cutting.tilted_solids`)."""

import math
import warnings

import numpy as np
import pytest
from tilted_cuts import nearest_material, swept_cut, swing, turned_about_y

from machinesim.cutting.tilted_solids import SolidSplitter, tilt_only
from machinesim.end_mills import BallEndMill, FlatEndMill

RADIUS = 0.5e-3
HALF_SWING = math.radians(1.0)
ABOVE = 50e-6  # the pivot above the flat's end face or the ball's equator
UNDER_TOP = 50e-6  # and under the stock's top


def _swing(n: int, tip_depth: float, pivot_height: float):
    """Poses (n + 1, 4, 4) of a tool whose tip stands ``tip_depth`` under the stock's top at
    (5, 5) mm, turned about the Y line ``pivot_height`` above the tip from -HALF_SWING to
    +HALF_SWING."""
    tip = np.array([5e-3, 5e-3, -tip_depth])
    return swing(n, tip, tip + np.array([0.0, 0.0, pivot_height]), HALF_SWING)


@pytest.mark.parametrize("kind", ["flat", "ball"])
def test_a_side_swung_about_a_line_inside_the_stock_keeps_its_waist(kind):
    """Swung +-1 deg in 4 sweeps about a Y line 50 um under the stock's top, the side's
    vertex line at azimuth 0 (at x = R) passes that line's height at R / cos(angle) from the
    pivot: the stock there stays beyond R / cos(1 deg), on either side (by hand). The hull of
    each sweep filled the side's waist: A B / (A + B) d = 25 um * 8.7 mrad = 218 nm past it
    (A, B = 50 um below and above the line), 40.6 nm in 20 sweeps (first order)."""
    if kind == "flat":
        tool, pivot_height = FlatEndMill(RADIUS, chord_tol=1e-5), ABOVE
    else:
        tool, pivot_height = BallEndMill(RADIUS, chord_tol=1e-5), RADIUS + ABOVE
    depth = pivot_height + UNDER_TOP
    part, _ = swept_cut(tool, _swing(4, depth, pivot_height))
    level = np.array([5e-3, 5e-3, -UNDER_TOP])
    for angle in (0.0, math.pi):
        gap = nearest_material(part, level, [angle])
        assert abs(gap - RADIUS / math.cos(HALF_SWING)) <= 1e-10, (angle, gap)


def _pose(angle: float, pivot: np.ndarray):
    return turned_about_y(angle, pivot, np.zeros(3))


def test_the_plane_is_the_line_the_tilt_crosses():
    """A flat end mill tilted about the Y line 50 um up its axis: its sides cross that line,
    all at the plane z = 50 um (its end face, held by the planner's face sub-steps, is not
    split); tilted about the end face's own diameter, or a ball about a line above the cut
    (the clip level under it), no side crosses, and the sweep is not split."""
    tool = FlatEndMill(RADIUS, chord_tol=1e-5)
    splitter = SolidSplitter(tool.vertices(), tool.triangles())
    pivot = np.array([0.0, 0.0, ABOVE])
    r0, o0 = _pose(0.0, pivot)
    r1, o1 = _pose(math.radians(0.5), pivot)
    planes = splitter.planes(r0, o0, r1, o1, level=1e-3)
    assert len(planes) == 1
    normal, offset = planes[0]
    assert np.allclose(normal, [0.0, 0.0, np.sign(normal[2])], rtol=0.0, atol=1e-12)
    assert math.isclose(offset * normal[2], ABOVE, rel_tol=1e-9)
    r1, o1 = _pose(math.radians(0.5), np.zeros(3))
    assert splitter.pieces(r0, np.zeros(3), r1, o1, level=1e-3) is None
    ball = BallEndMill(RADIUS, chord_tol=1e-5)
    splitter = SolidSplitter(ball.vertices(), ball.triangles())
    r1, o1 = _pose(math.radians(0.5), np.array([0.0, 0.0, 2e-3]))
    assert splitter.pieces(r0, np.zeros(3), r1, o1, level=1e-3) is None


def _side_zeros(tool, r0, o0, r1, o1, level):
    """The height (tool frame) where each side's centre line moves neither way along the
    side's mean normal between the poses, for the sides where it lies inside (0, level):
    the displacement is affine in the height, so two heights give it (a second way to the
    planes, from the poses alone)."""
    segments = len(tool.vertices()) // 2
    apothem = RADIUS * math.cos(math.pi / segments)
    zeros = []
    for j in range(segments):
        phi = (j + 0.5) * 2.0 * math.pi / segments
        normal = np.array([math.cos(phi), math.sin(phi), 0.0])
        mean = r0 @ normal + r1 @ normal
        mean /= np.linalg.norm(mean)

        def moved(z, normal=normal, mean=mean):
            point = apothem * normal + np.array([0.0, 0.0, z])
            return mean @ ((r1 - r0) @ point + o1 - o0)

        low, high = moved(0.0), moved(level)
        if low * high < 0.0:
            zeros.append(level * low / (low - high))
    zeros = np.sort(zeros)
    return zeros[np.r_[True, np.diff(zeros) > 1e-12]]


def test_a_swing_with_a_move_along_its_line_cuts_every_side_at_its_own_zero():
    """Swung d = 0.5 deg about a Y line 50 um up its axis while moving t = 0.1 um along Y
    (a B swing with Y on a 5-axis machine), a side at azimuth phi moves neither way along
    its normal at the height 50 um - t tan(phi) / d (by hand, to first order): the 16-sided
    flat end mill's sides at +-11.25, +-33.75 and +-56.25 deg have it inside the cut
    (47.7, 42.3, 32.9 um and 52.3, 57.7, 67.1 um), those at +-78.75 deg do not. Each
    needs its own plane: at most 4 left the sides of the other 2 heights 24.9 nm past their
    sweep (first order), and flat:0.5 of 52 sides swung 2 deg in 4 sweeps with 2 um along Y
    cut 52 nm past the sweep of the same move in 40."""
    tool = FlatEndMill(RADIUS, chord_tol=1e-5)
    splitter = SolidSplitter(tool.vertices(), tool.triangles())
    pivot = np.array([0.0, 0.0, ABOVE])
    d, t, level = math.radians(0.5), 0.1e-6, 100e-6
    r0, o0 = _pose(-d / 2, pivot)
    r1, o1 = _pose(d / 2, pivot)
    o1 = o1 + np.array([0.0, t, 0.0])
    planes = splitter.planes(r0, o0, r1, o1, level)
    heights = []
    for normal, offset in planes:
        assert np.allclose(normal, [0.0, 0.0, np.sign(normal[2])], rtol=0.0, atol=1e-12)
        heights.append(offset * np.sign(normal[2]))
    heights.sort()
    by_hand = sorted(ABOVE - t * math.tan(math.radians(a)) / d
                     for a in (11.25, 33.75, 56.25, -11.25, -33.75, -56.25))
    assert len(heights) == 6, heights
    assert np.allclose(heights, by_hand, rtol=0.0, atol=0.05e-6), np.subtract(heights, by_hand)
    assert np.allclose(heights, _side_zeros(tool, r0, o0, r1, o1, level), rtol=0.0,
                       atol=1e-12)


@pytest.mark.parametrize("kind", ["flat", "ball"])
def test_a_turn_about_the_tools_own_axis_is_not_split(kind):
    """A turn about the tool's own axis (A on robonano_ui) moves no point of the round tool:
    its polygon's sides tilt across their middles (the hull of each fills s d / 4 of a
    notch the polygon leaves, s the side's width, inside the round tool's sweep), and were
    cut by 4 planes into 8 pieces a sweep for nothing. With a tilt, only the tilt is split."""
    tool = (FlatEndMill(RADIUS, chord_tol=1e-5) if kind == "flat"
            else BallEndMill(RADIUS, chord_tol=1e-5))
    splitter = SolidSplitter(tool.vertices(), tool.triangles())
    d = math.radians(0.5)
    c, s = math.cos(d), math.sin(d)
    spin = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    r0, origin = np.eye(3), np.zeros(3)
    assert splitter.planes(r0, origin, spin, origin, level=1e-3) == []
    assert not splitter.crossing([0], r0[None], spin[None], origin[None], origin[None],
                                 np.array([1e-3]))[0]
    assert np.allclose(tilt_only(r0, spin), r0, rtol=0.0, atol=1e-15)
    # the tilt about a Y line 50 um up the flat's side (the ball's equator), spun as well,
    # is cut by the tilt's one plane at that height, as without the spin
    pivot = np.array([0.0, 0.0, ABOVE if kind == "flat" else RADIUS + ABOVE])
    r1, o1 = _pose(d, pivot)
    planes = splitter.planes(r0, origin, r1 @ spin, o1, level=1e-3)
    assert len(planes) == 1
    assert math.isclose(abs(planes[0][1]), pivot[2], rel_tol=1e-9)


def test_a_half_turn_in_one_sweep_is_not_split():
    """A half turn of the tool's axis in one sweep (a chord tolerance as coarse as the tool:
    its points' chords are their whole half circles) has no shortest turn and no mean
    normal: the sweep is the hull of its two poses, unsplit, without a warning."""
    tool = FlatEndMill(RADIUS, chord_tol=1e-5)
    splitter = SolidSplitter(tool.vertices(), tool.triangles())
    pivot = np.array([0.0, 0.0, ABOVE])
    r1, o1 = _pose(math.pi, pivot)
    r0, o0 = np.eye(3), np.zeros(3)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert not splitter.crossing([0], r0[None], r1[None], o0[None], o1[None],
                                     np.array([1e-3]))[0]
        assert splitter.pieces(r0, o0, r1, o1, level=1e-3) is None
    assert np.array_equal(tilt_only(r0, r1), r1)
    # turned about a line across a side's normal, that side is turned right over (its mean
    # normal some 1e-16 long, by round-off): its round-off over that was taken for an
    # excess, and the sweep split by a plane at random
    normal = splitter.normals[0]
    axis = np.cross(normal, [0.0, 0.0, 1.0])
    axis /= np.linalg.norm(axis)
    cross = np.cross(np.eye(3), axis)  # (its cross-product matrix, transposed)
    # the half turn about it by Rodrigues, sin(pi) = 1.2e-16 in float64
    r1 = np.eye(3) - math.sin(math.pi) * cross + (1.0 - math.cos(math.pi)) * cross @ cross
    o1 = pivot - r1 @ pivot
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert not splitter.crossing([0], r0[None], r1[None], o0[None], o1[None],
                                     np.array([1e-3]))[0]
        assert splitter.planes(r0, o0, r1, o1, level=1e-3) == []
