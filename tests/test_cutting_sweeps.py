"""Exact sweep solids (machinesim.cutting.sweeps) against closed forms and a second method."""

import math

import manifold3d
import numpy as np
import pytest
from scipy.spatial import ConvexHull

from machinesim.cutting.sweeps import (
    SolidSweep,
    clip_polygon,
    clipped_prisms,
    hull_mesh,
    manifold_from,
    polygon_triangles,
    prism_mesh,
    vector_area,
)
from machinesim.tools import BallEndMill, RoundNoseTool, VTool

#: Volumes of float64 meshes at mm scale agree to summation round-off (~1e-15 relative).
VOLUME_REL = 1e-12


def test_polygon_triangles_cover_the_polygon_once():
    angles = np.linspace(0.0, 2 * math.pi, 37)[:-1]
    polygon = np.stack([np.cos(angles), np.sin(angles), np.zeros_like(angles)], axis=1)
    triangles = polygon_triangles(len(polygon))
    assert len(triangles) == len(polygon) - 2
    corner = polygon[triangles]
    areas = np.cross(corner[:, 1] - corner[:, 0], corner[:, 2] - corner[:, 0])[:, 2] / 2
    assert np.all(areas > 0)  # all turn the polygon's way
    assert areas.sum() == pytest.approx(vector_area(polygon)[2], rel=1e-14)


@pytest.mark.parametrize("tool", [VTool(math.pi / 2), RoundNoseTool(2e-3, math.pi / 2)],
                         ids=["v90", "nose"])
@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_a_prism_holds_area_times_the_move_across_its_plane(tool, sign):
    rng = np.random.default_rng(3)
    rotation = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    profile = tool.vertices() @ rotation.T + rng.normal(0.0, 1e-3, 3)
    move = sign * rng.normal(0.0, 1e-3, 3)
    vertices, triangles, volume = prism_mesh(profile, move)
    area = vector_area(profile)
    assert volume == pytest.approx(abs(area @ move), rel=1e-15)
    solid = manifold_from(vertices, triangles, manifold3d.Manifold.reserve_ids(1))
    assert solid.status() == manifold3d.Error.NoError
    assert solid.volume() == pytest.approx(volume, rel=VOLUME_REL)
    # A second method: Qhull's volume of the same points.
    assert ConvexHull(vertices).volume == pytest.approx(volume, rel=1e-9)


def test_clipped_prisms_are_the_prisms_of_the_clipped_profiles():
    rng = np.random.default_rng(5)
    profile = RoundNoseTool(2e-3, math.pi / 2, flank_height=1e-3).vertices()
    polygons = profile + rng.normal(0.0, 1e-3, (40, 1, 3))
    moves = rng.normal(0.0, 1e-3, (40, 3))
    levels = rng.uniform(-2e-3, 12e-3, 40)
    levels[:4] = polygons[:4, 3, 2]  # a vertex exactly on the plane
    for polygon, move, level, built in zip(polygons, moves, levels,
                                           clipped_prisms(polygons, moves, levels),
                                           strict=True):
        clipped = clip_polygon(polygon, level)
        if len(clipped) < 3:
            assert built is None
            continue
        assert built[2] == pytest.approx(abs(vector_area(clipped) @ move), rel=1e-14)
        np.testing.assert_array_equal(np.sort(built[0], axis=0),
                                      np.sort(prism_mesh(clipped, move)[0], axis=0))


@pytest.mark.parametrize("move", [(0.0, 0.0, -1e-3), (1e-3, 0.5e-3, -0.2e-3), (1e-13, 0, 0)])
def test_a_solid_swept_is_its_minkowski_sum_with_the_move(move):
    tool = BallEndMill(1e-3, chord_tol=5e-6, height=3e-3)
    move = np.array(move)
    vertices, triangles = SolidSweep(tool.vertices(), tool.triangles()).mesh(
        np.eye(3), np.array([1e-3, 2e-3, 0.0]), move)
    solid = manifold_from(vertices, triangles, manifold3d.Manifold.reserve_ids(1))
    assert solid.status() == manifold3d.Error.NoError
    points = np.concatenate([tool.vertices(), tool.vertices() + move]) + [1e-3, 2e-3, 0.0]
    assert solid.volume() == pytest.approx(ConvexHull(points).volume, rel=1e-9)
    if move[0] == move[1] == 0.0:
        # Vertical: the tool plus the prism of its shadow, the equator polygon.
        _, segments = tool.rings
        shadow = segments / 2 * tool.radius**2 * math.sin(2 * math.pi / segments)
        tool_volume = manifold_from(tool.vertices(), tool.triangles(), 1).volume()
        assert solid.volume() == pytest.approx(tool_volume + shadow * abs(move[2]),
                                               rel=VOLUME_REL)


def test_qhull_hulls_are_closed_and_keep_their_volume_after_retriangulation():
    rng = np.random.default_rng(2)
    profile = RoundNoseTool(2e-3, math.pi / 2, flank_height=0.5e-3).vertices()
    turn = np.array([[1.0, 0.0, 0.0], [0.0, math.cos(0.01), -math.sin(0.01)],
                     [0.0, math.sin(0.01), math.cos(0.01)]])
    points = np.concatenate([profile, profile @ turn.T + rng.normal(0.0, 1e-5, 3)])
    vertices, triangles, volume = hull_mesh(points)
    solid = manifold_from(vertices, triangles, manifold3d.Manifold.reserve_ids(1))
    assert solid.status() == manifold3d.Error.NoError
    assert solid.volume() == pytest.approx(volume, rel=1e-12)
    assert hull_mesh(np.concatenate([profile, profile + [0.0, 1e-4, 0.0]])) is None  # flat
