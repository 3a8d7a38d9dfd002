"""Tools: profile geometry against the analytic shapes, chord tolerances, specs."""

import math
import re
from pathlib import Path

import numpy as np
import pytest

from machinesim.cutting import cut
from machinesim.exceptions import InputError
from machinesim.tool_specs import tool_from_spec
from machinesim.tools import (
    MAX_TOOL_SIZE_M,
    MIN_TOOL_SIZE_M,
    TOOL_HEIGHT_M,
    BallEndMill,
    FlatEndMill,
    RoundNoseTool,
    VTool,
    arc_segments,
)


def test_v_tool_flanks_make_the_included_angle():
    tool = VTool(math.radians(60.0), height=0.1e-3)
    vertices = tool.vertices()
    np.testing.assert_array_equal(vertices[0], [0.0, 0.0, 0.0])
    # Flank direction from the edge point: the angle between them is the included angle.
    left, right = vertices[1], vertices[2]
    cosine = left @ right / (np.linalg.norm(left) * np.linalg.norm(right))
    assert math.degrees(math.acos(cosine)) == pytest.approx(60.0, abs=1e-12)
    assert np.all(vertices[:, 0] == 0.0)  # zero thickness: the profile lies in Y-Z
    assert vertices[1:, 2] == pytest.approx([0.1e-3, 0.1e-3], abs=0.0)


def test_round_nose_arc_lies_on_the_circle_within_the_chord_tolerance():
    radius, tol = 2e-3, 1e-9
    tool = RoundNoseTool(radius, math.radians(90.0), chord_tol=tol)
    yz = tool.vertices()[:, 1:]
    centre = np.array([0.0, radius])
    distance = np.linalg.norm(yz - centre, axis=1)
    on_arc = np.abs(distance - radius) < 1e-15  # round-off of sin/cos at 2 mm (~10 ulp)
    assert on_arc.sum() == len(yz) - 2 or on_arc.all()
    assert np.any(np.all(yz == 0.0, axis=1)), "the edge point must be a vertex"
    arc = yz[on_arc]
    middle = 0.5 * (arc[1:] + arc[:-1])
    sagitta = radius - np.linalg.norm(middle - centre, axis=1)
    assert sagitta.max() <= tol * (1 + 1e-6)
    assert sagitta.max() > 0.5 * tol  # not needlessly finer than asked


def test_round_nose_flanks_are_tangent_to_the_arc():
    radius, angle = 0.1e-3, math.radians(90.0)
    tool = RoundNoseTool(radius, angle, height=0.2e-3)
    yz = tool.vertices()[:, 1:]
    top, arc_end = yz[-1], yz[-2]
    flank = (top - arc_end) / np.linalg.norm(top - arc_end)
    to_centre = np.array([0.0, radius]) - arc_end
    assert flank @ to_centre == pytest.approx(0.0, abs=1e-12 * radius)
    # The flank leaves the arc at included/2 from -Z: its direction makes that angle with Y.
    assert math.atan2(flank[1], flank[0]) == pytest.approx(angle / 2, abs=1e-12)
    assert top[1] == 0.2e-3


def test_round_nose_taller_than_its_flanks_is_cut_flat_and_continues_as_a_shank():
    tool = RoundNoseTool(2e-3, math.radians(90.0), height=0.2e-3)
    vertices = tool.vertices()
    assert vertices[:, 2].max() == 0.2e-3
    assert np.count_nonzero(vertices[:, 2] == 0.2e-3) == 2
    # Flanks stop at 0.1 mm, the shank goes straight up from their top to the holder.
    shank = RoundNoseTool(2e-3, math.radians(90.0), height=0.2e-3, flank_height=0.1e-3)
    yz = shank.vertices()[:, 1:]
    half = math.sqrt(2e-3**2 - (2e-3 - 0.1e-3) ** 2)  # the arc's half width at 0.1 mm
    for side in (-1.0, 1.0):
        corners = yz[np.abs(yz[:, 0] - side * half) < 1e-15]
        assert sorted(corners[:, 1]) == pytest.approx([0.1e-3, 0.2e-3], abs=1e-18)


def test_tools_reach_the_holder_at_their_full_height_by_default():
    for tool in (VTool(math.pi / 2), RoundNoseTool(2e-3, math.pi / 2), BallEndMill(1e-3)):
        assert tool.height == TOOL_HEIGHT_M
        assert tool.vertices()[:, 2].max() == TOOL_HEIGHT_M
        assert tool.vertices()[:, 2].min() == 0.0
    # A 90-deg V's flanks go all the way: the top is 2 x 10 mm wide.
    v = VTool(math.pi / 2)
    assert v.flank_height == v.height
    assert np.ptp(v.vertices()[:, 1]) == pytest.approx(2 * TOOL_HEIGHT_M, rel=1e-15)
    assert BallEndMill(8e-3).height == 16e-3  # at least the diameter


def test_v_tool_with_a_shank_has_straight_sides_above_its_flanks():
    tool = VTool(math.radians(60.0), height=2e-3, flank_height=0.5e-3)
    yz = tool.vertices()[:, 1:]
    half = 0.5e-3 * math.tan(math.radians(30.0))
    expected = [[0.0, 0.0], [-half, 0.5e-3], [-half, 2e-3], [half, 2e-3], [half, 0.5e-3]]
    np.testing.assert_allclose(yz, expected, rtol=0, atol=1e-18)


def test_a_v_near_180_deg_stops_its_flanks_at_the_size_bound():
    tool = tool_from_spec("v:179")
    assert tool.flank_height < tool.height
    top = tool.vertices()[:, 1]
    assert np.ptp(top) == pytest.approx(MAX_TOOL_SIZE_M, rel=1e-12)


@pytest.mark.parametrize("angle_deg", [60.0, 120.0, 179.0])
def test_a_nose_is_as_wide_at_its_flanks_top_as_its_tangent_flanks_make_it(angle_deg):
    # The flanks leave the arc at +-a/2 from -Z along its tangent, pi - a apart, so above
    # the arc the half width grows by cot(a/2) per unit of height. The flanks' default top
    # had taken tan(a/2): 'nose:0.5:179' (flanks 1 deg apart, 1.17 mm wide at 10 mm) stopped
    # them at 4.85 mm, taken for 1 m wide.
    radius, end, height = 0.5e-3, math.radians(angle_deg) / 2, TOOL_HEIGHT_M
    tool = tool_from_spec(f"nose:0.5:{angle_deg:g}")
    half = radius * math.sin(end) + (height - radius * (1 - math.cos(end))) / math.tan(end)
    assert tool.flank_height == height
    assert np.ptp(tool.vertices()[:, 1]) == pytest.approx(2 * half, rel=1e-12, abs=0.0)


def test_a_nose_of_a_small_angle_stops_its_flanks_at_the_size_bound():
    # 'nose:1:0.1' (flanks 179.9 deg apart) had made a tool 22.9 m wide
    for spec in ("nose:1:1", "nose:1:0.1"):
        tool = tool_from_spec(spec)
        assert tool.flank_height < tool.height
        assert np.ptp(tool.vertices()[:, 1]) == pytest.approx(MAX_TOOL_SIZE_M, rel=1e-12)


def test_flanks_whose_default_top_is_under_the_size_bound_are_refused():
    # The flanks' default top is where they are MAX_TOOL_SIZE_M apart: for a V of angle
    # pi - g, MAX / 2 tan(g / 2) up. 'nose:1:1e-9' stopped them 4.4e-12 m up (a blade 1 m
    # wide), though a flank_height under MIN_TOOL_SIZE_M given is refused.
    gap = 2.0 * math.atan(2.0 * MIN_TOOL_SIZE_M / MAX_TOOL_SIZE_M)  # the top MIN up
    tool = VTool(math.pi - 1.01 * gap)
    assert tool.flank_height == pytest.approx(
        MAX_TOOL_SIZE_M / 2.0 * math.tan(1.01 * gap / 2.0), rel=1e-6, abs=0.0)
    assert 1.0e-9 < tool.flank_height < 1.02e-9
    with pytest.raises(InputError, match=r"included_angle 179.9999997\d* deg \(3.1415926\d* "
                       r"rad\) opens the flanks 1000 mm \(1 m, .* apart 9.9\d*e-07 mm .*above "
                       r"the edge point, under 1e-06 mm \(1e-09 m, MIN_TOOL_SIZE_M.*give a "
                       r"smaller included angle$"):
        VTool(math.pi - 0.99 * gap)
    # a nose's tangent flanks open as its arc's angle closes: 4.36 nm up at 1e-6 deg
    # (half width R sin(e) + h / tan(e) = 0.5 m, e = 5e-7 deg), 4.4e-12 m at 1e-9 deg
    end = math.radians(1e-6) / 2.0
    assert tool_from_spec("nose:1:1e-6").flank_height == pytest.approx(
        (0.5 - 1e-3 * math.sin(end)) * math.tan(end), rel=1e-6, abs=0.0)
    with pytest.raises(InputError, match=r"^tool spec 'nose:1:1e-9': included_angle 1e-09 deg "
                       r"\(1.745329\d*e-11 rad\) opens the flanks 1000 mm .*give a larger "
                       r"included angle$"):
        tool_from_spec("nose:1:1e-9")


def _frusta_volume(radius, rings, segments, height):
    """Volume of the ring polyhedron from its construction: regular m-gons of circumradius
    R sin(theta_k) at height R (1 - cos(theta_k)), theta_k = k pi / (2 rings), aligned; each
    band is a frustum of a regular pyramid, V = h (A1 + A2 + sqrt(A1 A2)) / 3 with
    A = m r^2 sin(2 pi / m) / 2, then a prism of the equator polygon up to ``height``."""
    theta = np.linspace(0.0, math.pi / 2, rings + 1)
    r, z = radius * np.sin(theta), radius * (1 - np.cos(theta))
    area = segments / 2 * r**2 * math.sin(2 * math.pi / segments)
    bands = np.diff(z) / 3 * (area[1:] + area[:-1] + np.sqrt(area[1:] * area[:-1]))
    return bands.sum() + area[-1] * (height - radius), area[-1]


def test_ball_is_a_ring_polyhedron_on_the_sphere_under_its_shank():
    radius, tol = 1e-3, 2e-6
    tool = BallEndMill(radius, chord_tol=tol)
    vertices, triangles = tool.vertices(), tool.triangles()
    rings, segments = tool.rings
    centre = np.array([0.0, 0.0, radius])
    lower = vertices[:, 2] <= radius
    np.testing.assert_allclose(np.linalg.norm(vertices[lower] - centre, axis=1), radius,
                               rtol=1e-14)
    assert np.all(vertices[~lower, 2] == tool.height)
    np.testing.assert_allclose(np.hypot(*vertices[~lower, :2].T), radius, rtol=1e-14)
    assert np.array_equal(vertices[0], [0.0, 0.0, 0.0])
    assert len(vertices) == 1 + (rings + 1) * segments
    edges = tool.edges()
    assert len(vertices) - len(edges) + len(triangles) == 2  # a closed polyhedron
    # Facet depth read independently: the planes of the hemisphere's triangles lie within
    # tol of the sphere (distance of each plane from the centre).
    corner = vertices[triangles]
    on_ball = np.all(corner[:, :, 2] <= radius, axis=1)
    normal = np.cross(corner[:, 1] - corner[:, 0], corner[:, 2] - corner[:, 0])
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    distance = np.einsum("ij,ij->i", normal, corner[:, 0] - centre)[on_ball]
    assert np.all(distance > 0)  # outward
    assert (radius - distance).max() <= tol
    # Its volume by the divergence theorem equals the closed form of its construction.
    volume = np.einsum("ij,ij->i", corner[:, 0], np.cross(corner[:, 1], corner[:, 2])).sum() / 6
    assert volume == pytest.approx(_frusta_volume(radius, rings, segments, tool.height)[0],
                                   rel=1e-13)


def test_flat_end_mill_is_a_polygon_prism_on_its_circle():
    radius, tol = 1e-3, 1e-6
    tool = FlatEndMill(radius, chord_tol=tol)
    vertices, triangles, n = tool.vertices(), tool.triangles(), tool.segments
    assert n % 4 == 0 and len(vertices) == 2 * n
    np.testing.assert_allclose(np.hypot(*vertices[:, :2].T), radius, rtol=1e-15)
    assert np.all(vertices[:n, 2] == 0.0) and np.all(vertices[n:, 2] == tool.height)
    # the sagitta of a side, R (1 - cos(pi / n)), within tol; one corner fewer would not be
    assert radius * (1 - math.cos(math.pi / n)) <= tol < radius * (1 - math.cos(math.pi / (n - 4)))
    assert len(vertices) - len(tool.edges()) + len(triangles) == 2  # a closed polyhedron
    # volume by the divergence theorem: the regular n-gon's area n/2 R^2 sin(2 pi / n) times h
    corner = vertices[triangles]
    volume = np.einsum("ij,ij->i", corner[:, 0], np.cross(corner[:, 1], corner[:, 2])).sum() / 6
    assert volume == pytest.approx(n / 2 * radius**2 * math.sin(2 * math.pi / n) * tool.height,
                                   rel=1e-13)


def test_with_errors_moves_only_the_named_geometry():
    tool = RoundNoseTool(2e-3, math.radians(90.0))
    worse = tool.with_errors(nose_radius_error=1e-6, included_angle_error=1e-3)
    assert worse.nose_radius == 2e-3 + 1e-6
    assert worse.included_angle == math.radians(90.0) + 1e-3
    assert worse.height == tool.height and worse.chord_tol == tool.chord_tol
    assert VTool(1.0).with_errors(0.1).included_angle == 1.1
    assert BallEndMill(1e-3).with_errors(-1e-6).radius == 1e-3 - 1e-6
    assert FlatEndMill(1e-3).with_errors(2e-6).radius == 1e-3 + 2e-6


def test_arc_segments_meet_the_sagitta_formula():
    radius, angle, tol = 2e-3, math.pi / 2, 1e-9
    n = arc_segments(radius, angle, tol)
    assert radius * (1 - math.cos(angle / n / 2)) <= tol
    assert radius * (1 - math.cos(angle / (n - 1) / 2)) > tol


@pytest.mark.parametrize(
    ("spec", "expected"),
    [
        ("v:90", VTool(math.pi / 2)),
        ("V:60", VTool(math.pi / 3)),
        ("nose:2.0:90", RoundNoseTool(2e-3, math.pi / 2)),
        ("ball:2.0", BallEndMill(2e-3)),
        ("flat:1.0", FlatEndMill(1e-3)),
    ],
)
def test_tool_from_spec(spec, expected):
    tool = tool_from_spec(spec)
    assert type(tool) is type(expected)
    for field in ("included_angle", "nose_radius", "radius"):
        if hasattr(expected, field):
            assert getattr(tool, field) == pytest.approx(getattr(expected, field), rel=1e-15)


@pytest.mark.parametrize(
    ("spec", "height_m"),
    [("v:90:h=5", 5e-3), ("v:90:h=5mm", 5e-3), ("ball:0.5:h=20mm", 20e-3),
     ("nose:2.0:90:H=3", 3e-3), ("V:60", 10e-3), ("flat:0.5:h=4", 4e-3)],
)
def test_a_spec_height_sets_where_the_holder_begins(spec, height_m):
    # the body's highest vertex is the holder plane, at the spec's height (mm -> m)
    tool = tool_from_spec(spec)
    assert tool.height == pytest.approx(height_m, rel=1e-15)
    assert tool.vertices()[:, 2].max() == pytest.approx(height_m, rel=1e-15)


def test_a_spec_shank_diameter_widens_the_holder_not_the_tool():
    # d= is a diameter in mm: the shank's radius, m; h= and d= in either order
    for spec in ("flat:0.5:h=3:d=4", "flat:0.5:d=4mm:h=3"):
        tool = tool_from_spec(spec)
        assert (tool.height, tool.shank_radius) == (3e-3, 2e-3)
        # the cutting body is the end mill's own: 1 mm across
        assert np.ptp(tool.vertices()[:, 0]) == pytest.approx(1e-3, rel=1e-12)
    assert tool_from_spec("ball:0.5:d=4").shank_radius == 2e-3
    assert tool_from_spec("ball:0.5").shank_radius == 0.0


def test_every_size_of_a_spec_may_end_in_mm_and_every_angle_in_deg():
    # 'ball:0.5mm' was refused ('expected numbers after the kind') where 'ball:0.5:h=20mm'
    # was read: now a unit may end every number, and reads as the bare number
    for spec, plain in [("ball:0.5mm", "ball:0.5"), ("ball:0.5 MM:h=20mm", "ball:0.5:h=20"),
                        ("flat:1mm:h=3mm:d=4mm", "flat:1:h=3:d=4"), ("v:90deg", "v:90"),
                        ("v:60 deg:h=5", "v:60:h=5"), ("nose:0.2mm:90deg", "nose:0.2:90")]:
        assert tool_from_spec(spec) == tool_from_spec(plain), spec
    assert tool_from_spec("ball:0.5mm").radius == 0.5e-3  # mm to m
    assert tool_from_spec("v:90deg").included_angle == math.pi / 2


def test_a_spec_ball_too_large_for_its_facets_says_what_a_spec_can_build():
    # 'ball:500' said 'give a larger chord_tol', which neither --tool nor a tool table can
    # set. The largest spec ball: 80.6 mm builds, 80.7 mm passes MAX_TOOL_VERTICES at the
    # 1 um chord_tol, as BallEndMill itself says
    assert tool_from_spec("ball:80.6").radius == pytest.approx(80.6e-3, rel=1e-15)
    with pytest.raises(InputError, match="201,601 vertices at chord_tol 1e-06 m"):
        BallEndMill(80.7e-3)
    with pytest.raises(InputError) as caught:
        tool_from_spec("ball:500", name="--tool")
    assert str(caught.value) == (
        "--tool 'ball:500': the ball polygon would have 1,238,769 vertices at chord_tol 1e-06 "
        "m, over MAX_TOOL_VERTICES (200,000). A spec's ball keeps its facets within 1 um and "
        "is at most 80.6 mm in radius (500 um would be ball:0.5); a larger ball is built in "
        "Python, BallEndMill(radius_m, chord_tol=...) with a coarser chord_tol")
    # as the message says: in Python, with a coarser chord_tol, the 500 mm ball builds
    assert BallEndMill(0.5, chord_tol=1e-5).radius == 0.5


def test_a_spec_shank_diameter_of_zero_is_refused():
    # 'd=0' became shank_radius 0, the API's "as wide as the tool": a cut with a shank the
    # user did not give, exit 0
    with pytest.raises(InputError) as caught:
        tool_from_spec("flat:0.5:d=0")
    assert str(caught.value) == ("tool spec 'flat:0.5:d=0': a shank diameter of "
                                 "0 mm; expected a diameter above 0 mm, or no 'd=' for a shank "
                                 "as wide as the tool")


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ("v", "expected 'v:ANGLE_DEG'"),
        ("nose:2.0", "expected 'v:ANGLE_DEG'"),
        ("drill:3", "'drill:3'.*expected"),
        ("v:abc", "^tool spec 'v:abc': 'abc' is not an included angle; expected "
                  "'v:ANGLE_DEG': a number in deg, which may end in 'deg'$"),
        # a size in another unit than mm, an angle in mm
        ("ball:0.5um", "^tool spec 'ball:0.5um': '0.5um' is not a radius; expected "
                       "'ball:RADIUS_MM': a number in mm, which may end in 'mm'$"),
        ("v:90mm", "'90mm' is not an included angle; expected 'v:ANGLE_DEG'"),
        # float() reads '0_5' as 5 (a typo of 0.5 had made a 5 mm ball, exit 0) and
        # full-width digits as ASCII ones
        ("ball:0_5", "^tool spec 'ball:0_5': '0_5' is not a radius; expected "
                     "'ball:RADIUS_MM': a number in mm"),
        ("ball:\uff10.\uff15", "'\uff10.\uff15' is not a radius"),
        ("v:90:h=1_0", "'h=1_0' is not a height"),
        ("nose:0.5deg:90", "'0.5deg' is not a nose radius; expected 'nose:RADIUS_MM:ANGLE_DEG'"),
        ("v:90:h=2um", "'h=2um' is not a height; expected 'h=HEIGHT_MM', e.g. 'h=5': a number "
                       "in mm"),
        ("ball:0,5", "^tool spec 'ball:0,5': '0,5' is not a number: the decimal mark is a "
                     "point, e.g. 'ball:0.5'$"),
        ("nose:0,5:90:h=2", "'0,5' is not a number: .* e.g. 'nose:0.5:90:h=2'$"),
        ("v:200", "'v:200'.*included_angle must lie between 0 and 180 deg"),
        ("ball:-1", "'ball:-1'.*radius must be a positive"),
        ("ball:1e9", r"'ball:1e9'.*radius must be at most 1000 mm \(1 m"),
        ("nose:2000:90", r"nose_radius must be at most 1000 mm \(1 m"),
        ("ball:nan", "radius must be a positive finite"),
        ("v:90:h=2000", r"'v:90:h=2000'.*height must be at most 1000 mm \(1 m"),
        ("v:90:h=-1", r"height must be a positive finite number, got -1 mm \(-0.001 m\)"),
        ("v:90:h=abc", "'h=abc' is not a height; expected 'h=HEIGHT_MM'"),
        ("ball:2:h=1", r"height 1 mm \(0.001 m\) must be at least the radius, 2 mm \(0.002 m\)"),
        ("v:h=5", "expected 'v:ANGLE_DEG'"),
        ("v:90:d=4", "a shank diameter \\(d=\\) is for a ball or flat end mill"),
        ("flat:0.5:d=abc", "'d=abc' is not a shank diameter; expected 'd=SHANK_DIAMETER_MM'"),
        ("flat:0.5:h=3:h=4", "height given twice"),
        ("flat:0.5:d=-4", r"a shank diameter of -4 mm; expected a diameter above 0 mm"),
    ],
)
def test_bad_tool_specs_raise_input_error(spec, message):
    with pytest.raises(InputError, match=message):
        tool_from_spec(spec)


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda: VTool(math.pi / 2, height=2.0), r"height must be at most 1000 mm \(1 m"),
        (lambda: VTool(math.pi / 2, height=1e-3, flank_height=2e-3), "must not exceed the height"),
        (lambda: BallEndMill(2e-3, height=1e-3), "at least the radius"),
        (lambda: BallEndMill(0.5, chord_tol=1e-9), "vertices at chord_tol"),
        (lambda: RoundNoseTool(0.5, math.pi / 2, chord_tol=1e-15), "vertices at chord_tol"),
    ],
)
def test_tool_sizes_are_bounded(make, message):
    with pytest.raises(InputError, match=message):
        make()


EXAMPLES = Path(__file__).resolve().parents[1] / "models" / "examples"


def test_the_smallest_tool_cuts_its_hand_derived_grooves():
    # A ball of MIN_TOOL_SIZE_M radius, under its 1 um chord_tol, is a square pyramid up to
    # z = r (corners at +-r) under a square prism: each of grooves.nc's four grooves, 20 um
    # deep right across the 10 mm block, has the section 2 r (d - r) + r^2. A ball of 1e-14 m
    # had removed nothing, one of 2e-14 m 50 times this (1e-14 m is manifold3d's tolerance
    # on the block). 1e-6: float64 on 10 mm coordinates (ulp 1.7e-18 m) against 1 nm.
    r, depth = MIN_TOOL_SIZE_M, 20e-6
    _, report = cut(EXAMPLES / "grooves.nc", str(EXAMPLES / "mill3.urdf"), BallEndMill(r),
                    "block:10x10x2")
    expected = 4 * 10e-3 * (2.0 * r * (depth - r) + r * r)
    assert report.removed_volume_m3 == pytest.approx(expected, rel=1e-6, abs=0.0)


@pytest.mark.parametrize(
    ("make", "name"),
    [
        (lambda size: BallEndMill(size), "radius"),
        (lambda size: FlatEndMill(size), "radius"),
        (lambda size: RoundNoseTool(size, math.pi / 2), "nose_radius"),
        (lambda size: VTool(math.pi / 2, height=size), "height"),
        (lambda size: BallEndMill(0.5e-3, shank_radius=size), "shank_radius"),
    ],
)
def test_a_tool_below_what_the_engine_resolves_is_refused(make, name):
    make(MIN_TOOL_SIZE_M)  # the bound itself is a tool
    with pytest.raises(InputError,
                       match=rf"{name} must be at least 1e-06 mm \(1e-09 m, MIN_TOOL_SIZE_M"):
        make(math.nextafter(MIN_TOOL_SIZE_M, 0.0))


@pytest.mark.parametrize(
    ("make", "name", "shown"),
    [
        (lambda: FlatEndMill("1"), "radius", "'1' (str)"),
        (lambda: FlatEndMill(True), "radius", "True (bool)"),
        (lambda: FlatEndMill(np.array([1e-3])), "radius", "array([0.001]) (ndarray)"),
        (lambda: FlatEndMill(1e-3, chord_tol="1e-6"), "chord_tol", "'1e-6' (str)"),
        (lambda: FlatEndMill(1e-3, shank_radius=True), "shank_radius", "True (bool)"),
        (lambda: BallEndMill("0.001"), "radius", "'0.001' (str)"),
        (lambda: BallEndMill(5e-4, height="5"), "height", "'5' (str)"),
        (lambda: FlatEndMill(None), "radius", "None (NoneType)"),
        (lambda: VTool("1.5"), "included_angle", "'1.5' (str)"),
        (lambda: VTool(True), "included_angle", "True (bool)"),
        (lambda: RoundNoseTool("0.001", 1.5), "nose_radius", "'0.001' (str)"),
        (lambda: RoundNoseTool(1e-3, 1.5, flank_height="0.001"), "flank_height",
         "'0.001' (str)"),
    ],
)
def test_a_tool_size_that_is_no_number_is_refused_naming_it(make, name, shown):
    """FlatEndMill("1") ended in "TypeError: '>=' not supported", VTool("1.5") in one of
    'str' / 'float', an array radius in "unhashable type", and True was taken as 1 (a V
    of 1 rad, a 1 m shank)."""
    unit = "rad" if name == "included_angle" else "m"
    with pytest.raises(InputError, match=rf"{name} must be a number in {unit}, got "
                                         rf"{re.escape(shown)}") as raised:
        make()
    assert raised.value.key == name


def test_a_spec_refusal_names_the_spec_once_and_its_parameter_once():
    # it had read "key 'tool': tool spec 'ball:-1': key 'radius': radius must be ..."
    with pytest.raises(InputError) as caught:
        tool_from_spec("ball:-1")
    assert str(caught.value) == ("tool spec 'ball:-1': radius must be a positive finite "
                                 "number, got -1 mm (-0.001 m)")
    assert caught.value.key is None
    with pytest.raises(InputError) as caught:
        tool_from_spec("ball:1:h=0.5", name="--tool")
    assert str(caught.value) == ("--tool 'ball:1:h=0.5': height 0.5 mm (0.0005 m) must be at "
                                 "least the radius, 1 mm (0.001 m)")
    with pytest.raises(InputError, match=r"^tool spec 'flat:1:d=1e-11': shank_radius \(half "
                       r"the d= diameter\) must be at least 1e-06 mm .*got 5e-12 mm \(5e-15 m\)$"):
        tool_from_spec("flat:1:d=1e-11")


def test_the_narrowest_v_cuts_its_hand_derived_grooves_and_a_narrower_is_refused():
    # A V whose flanks are MIN_TOOL_SIZE_M apart 10 mm up: each of grooves.nc's grooves has
    # the section d^2 tan(a/2) (measured 3.2e-7 off: 1e-6). 'v:1e-9' (flanks 1.7e-13 m
    # apart) had cut nothing of a groove inside a block.
    angle = 2.0 * math.atan(MIN_TOOL_SIZE_M / (2.0 * TOOL_HEIGHT_M)) * (1.0 + 1e-12)
    _, report = cut(EXAMPLES / "grooves.nc", str(EXAMPLES / "mill3.urdf"), VTool(angle),
                    "block:10x10x2")
    expected = 4 * 10e-3 * 20e-6**2 * math.tan(angle / 2.0)
    assert report.removed_volume_m3 == pytest.approx(expected, rel=1e-6, abs=0.0)
    with pytest.raises(InputError, match="leaves the flanks 9.99999999.*e-07 mm .* apart at "
                       "their top, 10 mm \\(0.01 m\\) up; they must be at least 1e-06 mm"):
        VTool(angle * (1.0 - 2e-12))
    with pytest.raises(InputError, match=r"^tool spec 'v:1e-9': included_angle 1e-09 deg "
                       r"\(1.7453292519\d*e-11 rad\) leaves the flanks"):
        tool_from_spec("v:1e-9")


def test_a_ball_of_10_fm_is_refused_naming_the_bound_not_cut_to_nothing():
    # 'ball:1e-11' (mm) had cut nothing and warned "does it reach the stock?"
    with pytest.raises(InputError) as caught:
        tool_from_spec("ball:1e-11")
    assert "radius must be at least 1e-06 mm (1e-09 m, MIN_TOOL_SIZE_M: " in str(caught.value)
    assert str(caught.value).endswith("got 1e-11 mm (1e-14 m)")
