"""Tools: profile geometry against the analytic shapes, chord tolerances, specs."""

import math

import numpy as np
import pytest

from machinesim.exceptions import InputError
from machinesim.tools import (
    BallEndMill,
    RoundNoseTool,
    VTool,
    arc_segments,
    tool_from_spec,
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


def test_round_nose_taller_than_height_is_cut_flat():
    tool = RoundNoseTool(2e-3, math.radians(90.0), height=0.2e-3)
    vertices = tool.vertices()
    assert vertices[:, 2].max() == 0.2e-3
    assert np.count_nonzero(vertices[:, 2] == 0.2e-3) == 2


def test_ball_vertices_on_sphere_and_facets_within_tolerance():
    radius, tol = 1e-3, 2e-6
    tool = BallEndMill(radius, chord_tol=tol)
    vertices = tool.vertices()
    centre = np.array([0.0, 0.0, radius])
    np.testing.assert_allclose(np.linalg.norm(vertices - centre, axis=1), radius, rtol=1e-14)
    assert vertices[:, 2].min() == pytest.approx(0.0, abs=1e-18)
    edges = tool.edges()
    # Closed triangulated sphere: V - E + F = 2 with 2E = 3F.
    assert len(vertices) - len(edges) + 2 * len(edges) // 3 == 2
    # Facet depth read independently: the midpoint of every edge is inside by <= tol.
    middle = 0.5 * (vertices[edges[:, 0]] + vertices[edges[:, 1]])
    assert (radius - np.linalg.norm(middle - centre, axis=1)).max() <= tol


def test_with_errors_moves_only_the_named_geometry():
    tool = RoundNoseTool(2e-3, math.radians(90.0))
    worse = tool.with_errors(nose_radius_error=1e-6, included_angle_error=1e-3)
    assert worse.nose_radius == 2e-3 + 1e-6
    assert worse.included_angle == math.radians(90.0) + 1e-3
    assert worse.height == tool.height and worse.chord_tol == tool.chord_tol
    assert VTool(1.0).with_errors(0.1).included_angle == 1.1
    assert BallEndMill(1e-3).with_errors(-1e-6).radius == 1e-3 - 1e-6


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
    ],
)
def test_tool_from_spec(spec, expected):
    tool = tool_from_spec(spec)
    assert type(tool) is type(expected)
    for field in ("included_angle", "nose_radius", "radius"):
        if hasattr(expected, field):
            assert getattr(tool, field) == pytest.approx(getattr(expected, field), rel=1e-15)


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ("v", "expected 'v:ANGLE_DEG'"),
        ("nose:2.0", "expected 'v:ANGLE_DEG'"),
        ("drill:3", "'drill:3'.*expected"),
        ("v:abc", "'v:abc'.*expected numbers"),
        ("v:200", "'v:200'.*included_angle must lie in"),
        ("ball:-1", "'ball:-1'.*radius must be a positive"),
    ],
)
def test_bad_tool_specs_raise_input_error(spec, message):
    with pytest.raises(InputError, match=message):
        tool_from_spec(spec)
