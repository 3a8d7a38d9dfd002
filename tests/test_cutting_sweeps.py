"""Exact sweep solids (machinesim.cutting.sweeps) against closed forms and a second method."""

import math

import manifold3d
import numpy as np
import pytest
from scipy.spatial import ConvexHull

from machinesim.cutting import remove
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
from machinesim.metrology import height_map
from machinesim.tools import BallEndMill, FlatEndMill, RoundNoseTool, VTool
from machinesim.workpiece import Part, block

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
        assert built[2] == pytest.approx(abs(vector_area(clipped) @ move), rel=1e-14, abs=0.0)
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
    assert solid.volume() == pytest.approx(volume, rel=1e-12, abs=0.0)
    assert hull_mesh(np.concatenate([profile, profile + [0.0, 1e-4, 0.0]])) is None  # flat


def _rolled(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


@pytest.mark.parametrize("tool", ["v", "nose"])
def test_a_tool_turned_within_the_twist_tolerance_cuts_as_translated(tool, monkeypatch):
    # A tool rolled about its travel (X) along one groove by an angle that moves its farthest
    # vertex half of `TWIST_M`. Cut as the start pose's translation it is the unturned
    # groove exactly; cut as the hull of the two poses (tolerance 0) it differs from that by
    # at most the vertices' displacement, the bound the tolerance stands on.
    from machinesim.cutting import sweepset
    from machinesim.metrology.surface import height_map
    from machinesim.tolerances import TWIST_M

    shape = VTool(math.pi / 2) if tool == "v" else RoundNoseTool(2e-3, math.pi / 2, 50e-6)
    vertices = shape.vertices()
    angle = 0.5 * TWIST_M / np.hypot(vertices[:, 1], vertices[:, 2]).max()
    start, end = np.eye(4), np.eye(4)
    start[:3, 3], end[:3, 3] = (-1e-3, 0.5e-3, -20e-6), (2e-3, 0.5e-3, -20e-6)
    end[:3, :3] = _rolled(angle)
    stock = block(1e-3, 1e-3, 0.2e-3)
    twisted, _ = remove(stock, shape, [np.array([start, end])], method="boolean")
    straight_end = end.copy()
    straight_end[:3, :3] = np.eye(3)
    straight, _ = remove(stock, shape, [np.array([start, straight_end])], method="boolean")
    assert twisted.volume == straight.volume
    monkeypatch.setattr(sweepset, "TWIST_M", 0.0)
    hull, _ = remove(stock, shape, [np.array([start, end])], method="boolean")
    assert hull.volume != straight.volume
    x = np.linspace(0.0, 1e-3, 81)[1:-1] + 1.234e-9
    gap = np.nanmax(np.abs(height_map(hull, x, x) - height_map(straight, x, x)))
    reach = np.abs((_rolled(angle) - np.eye(3)) @ vertices.T).max()
    assert 0.0 < gap <= reach + 1e-15


def test_a_move_within_the_profile_plane_sweeps_no_prism():
    """A planar profile moved along its own plane (a plunge of paper 002's crown tool,
    turned 45 deg about Z and tilted, so rounding leaves |area . move| ~1e-26 m^3 of either
    sign) sweeps volume 0, so no sliver joins the union of the sweeps; 1e-6 rad out of the
    plane it sweeps |area| |move| 1e-6."""
    from machinesim.cutting.sweeps import clipped_prisms, prism_mesh
    from machinesim.rotations import rotation_xyz

    square = np.array([[0.0, 0.0, 0.0], [3e-4, 0.0, 0.0], [3e-4, 0.0, 3e-4], [0.0, 0.0, 3e-4]])
    turn = rotation_xyz(0.0337, -0.0003, math.pi / 4)
    polygon = square @ turn.T
    area = 9e-8
    for move, volume in ((turn @ np.array([0.0, 0.0, -1e-4]), 0.0),
                         (turn @ np.array([0.0, 1e-4 * math.sin(1e-6), -1e-4]),
                          area * 1e-4 * math.sin(1e-6))):
        assert prism_mesh(polygon, move)[2] == pytest.approx(volume, rel=1e-6, abs=0.0)
        prisms = clipped_prisms(polygon[None], move[None], np.array([1.0]))
        assert prisms[0][2] == pytest.approx(volume, rel=1e-6, abs=0.0)


@pytest.mark.parametrize("tool", [BallEndMill(0.5e-3, chord_tol=2e-6),
                                  FlatEndMill(0.5e-3, chord_tol=2e-6)])
def test_the_engine_cuts_a_rotating_tools_move_as_the_hull_of_its_two_places(tool):
    # The engine builds a rotating tool's translated sweep from its faces (SolidSweep); the
    # same sweep as Qhull's hull of the tool's points at both places, trimmed at the clip
    # plane and subtracted, must leave the same part: volume and heights.
    stock = block(4e-3, 4e-3, 2e-3)
    turn = np.eye(4)
    turn[:3, :3] = np.array([[math.cos(0.3), -math.sin(0.3), 0.0],
                             [math.sin(0.3), math.cos(0.3), 0.0], [0.0, 0.0, 1.0]])
    start, end = turn.copy(), turn.copy()
    start[:3, 3], end[:3, 3] = (0.7e-3, 1.1e-3, -0.2e-3), (3.1e-3, 2.6e-3, -0.35e-3)
    part, report = remove(stock, tool, [np.array([start, end])], method="boolean")
    vertices = tool.vertices() @ turn[:3, :3].T
    points = np.concatenate([vertices + start[:3, 3], vertices + end[:3, 3]])
    hull_vertices, hull_triangles, _ = hull_mesh(points)
    hull = manifold_from(hull_vertices, hull_triangles, manifold3d.Manifold.reserve_ids(1))
    expected = stock.manifold - hull
    assert report.removed_volume == pytest.approx(stock.volume - expected.volume(),
                                                  rel=1e-9)
    assert part.volume == pytest.approx(expected.volume(), rel=VOLUME_REL)
    x, y = np.linspace(0.2e-3, 3.8e-3, 37), np.linspace(0.2e-3, 3.8e-3, 37)
    np.testing.assert_allclose(height_map(part, x, y), height_map(Part(expected), x, y),
                               rtol=0, atol=1e-12)


@pytest.mark.parametrize("tilt", [0.0, 0.02])
def test_a_ball_end_mill_cut_at_a_ring_leaves_the_part_of_its_whole_sweep_trimmed(
        tilt, monkeypatch):
    """A ball end mill's sweep is built from the tool below its lowest ring wholly above
    the clip plane (plus the move's fall), untrimmed (`SweepSet._ball_cut`): a raster's
    3,819 sweeps took 23 s trimmed, 5 s so. Its part is the whole sweeps' trimmed by the
    plane, as before, to round-off: the same removed volume and heights within manifold3d's
    tolerance of the part (`SOLID_TOLERANCE_REL`; measured on the raster: 3e-17 m)."""
    from machinesim.cutting.sweeps import SOLID_TOLERANCE_REL
    from machinesim.cutting.sweepset import SweepSet
    from machinesim.rotations import rotation_xyz

    tool = BallEndMill(0.5e-3, chord_tol=2e-6)
    stock = block(3e-3, 2e-3, 1e-3)
    paths = []
    for k, y in enumerate((0.5e-3, 0.9e-3, 1.3e-3)):
        xs = np.linspace(-0.6e-3, 3.6e-3, 9)[::(-1) ** k]
        poses = np.repeat(np.eye(4)[None], len(xs), axis=0)
        poses[:, :3, :3] = rotation_xyz(tilt, -tilt, 0.0)
        poses[:, :3, 3] = np.stack([xs, np.full(len(xs), y),
                                    -30e-6 - 40e-6 * np.sin(xs / 1e-3)], axis=1)
        paths.append(poses)
    told = []
    ring_cut = SweepSet._ball_cut

    def spy(self, rotation, origin, move):
        told.append(ring_cut(self, rotation, origin, move))
        return told[-1]

    monkeypatch.setattr(SweepSet, "_ball_cut", spy)
    rings, report = remove(stock, tool, paths, method="boolean")
    assert told and all(built != "whole" for built in told)  # every sweep cut at a ring
    monkeypatch.setattr(SweepSet, "_ball_cut", lambda self, *pose: "whole")
    whole, whole_report = remove(stock, tool, paths, method="boolean")
    assert report.removed_volume == pytest.approx(whole_report.removed_volume, rel=1e-12)
    apart = ((rings.manifold - whole.manifold).volume()
             + (whole.manifold - rings.manifold).volume())
    assert apart <= 1e-12 * report.removed_volume
    x, y = np.linspace(-0.1e-3, 3.1e-3, 161), np.linspace(0.1e-3, 1.9e-3, 91)
    np.testing.assert_allclose(height_map(rings, x, y), height_map(whole, x, y), rtol=0,
                               atol=SOLID_TOLERANCE_REL * 3e-3)


def test_a_deferred_solid_is_made_once_when_read_and_its_mesh_volume_is_the_boxs():
    """A level pass's solid is made only when read (`Solids`); its volume beforehand comes
    from the mesh, taken about its first vertex: a 1 x 2 x 3 mm box 0.5 m from zero is
    6 mm^3 to 1e-12 of it (about the origin the same sum is off by 2.5e-10)."""
    from machinesim.cutting.sweeps import DeferredSolid, Solids, mesh_volume

    box = manifold3d.Manifold.cube((1e-3, 2e-3, 3e-3)).translate((0.5, -0.5, 0.1))
    mesh = box.to_mesh64()
    vertices = np.array(mesh.vert_properties[:, :3], dtype=np.float64)
    triangles = np.array(mesh.tri_verts)
    assert mesh_volume(vertices, triangles) == pytest.approx(6e-9, rel=1e-12)
    solids = Solids([DeferredSolid(vertices, triangles, 7)])
    assert solids.deferred(0)
    first = solids[0]
    assert isinstance(first, manifold3d.Manifold) and not solids.deferred(0)
    assert solids[0] is first and list(solids) == [first]
    assert first.volume() == pytest.approx(6e-9, rel=1e-12)


def test_a_rotary_groove_ends_on_its_profile_planes_and_keeps_pappus_volume():
    """A v:90 (10 mm tall) held 0.1 mm deep 0.3 mm off the C axis while C turns 90 deg: the
    revolved V, (pi / 2) r d^2 by Pappus (area d^2, centroid at r), less the chords'
    share (~phi^2 / 6 of each sub-step), and its two ends on the planes x = 0 and y = 0
    through the axis. The hull of the whole tall V at both ends of each sub-step, clipped
    after, reached past both ends by 78 nm (its flanks cross the C axis) and removed 1.1e-4
    more than Pappus."""
    import machinesim
    from machinesim.nc import parse_program

    r, d = 0.3e-3, 0.1e-3
    text = ("G90 G21 G94\nG00 X0 Y-0.3 Z0.1 C0\nG01 Z-0.1 F100.\nG01 C90. F100.\n"
            "G00 Z0.1\nM30\n")
    part, report = machinesim.cut(parse_program(text, "turn.nc"), "grooving_4axis",
                                  tool="v:90", stock="block:1x1x0.5@-0.5,-0.5,0")
    pappus = math.pi / 2 * r * d * d
    assert -1e-6 < report.removed_volume_m3 / pappus - 1.0 < 0.0
    v, _ = part.mesh()
    floor = v[(v[:, 2] < 1e-13) & (np.abs(v[:, 0]) < 0.45e-3) & (np.abs(v[:, 1]) < 0.45e-3)]
    assert floor[floor[:, 1] < 0.0, 0].min() >= -1e-15  # the start: no material cut at x < 0
    assert floor[floor[:, 0] > 0.0, 1].max() <= 1e-15  # the end: none at y > 0


def test_a_rotary_groove_about_a_tilted_c_axis_is_the_same_for_a_tall_and_a_short_v():
    """C tilted 8 and -6 urad (its heights change along each sub-step): a v:90 10 mm tall,
    whose flanks cross the C axis above the stock, and one 0.25 mm tall, whose do not,
    cut the same groove but for their chords (their sub-steps differ: ~1e-6 of it). The
    tall V's hull of both poses, clipped after, removed 1.1e-4 more."""
    import machinesim
    from machinesim.nc import parse_program

    text = ("G90 G21 G94\nG00 X0 Y-0.3 Z0.1 C0\nG01 Z-0.1 F100.\nG01 C90. F100.\n"
            "G00 Z0.1\nM30\n")
    errors = {"location": {"C": {"EA0C_urad": 8.0, "EB0C_urad": -6.0}}}
    tall, short = (machinesim.cut(parse_program(text, "turn.nc"), "grooving_4axis",
                                  tool=tool, stock="block:1x1x0.5@-0.5,-0.5,0",
                                  errors=errors)[1].removed_volume_m3
                   for tool in ("v:90", "v:90:h=0.25"))
    assert abs(tall / short - 1.0) < 1e-5


@pytest.mark.parametrize("tilt", [0.0, 0.02])
def test_a_ball_end_mills_sweeps_are_made_again_when_read_and_cut_the_same_part(
        tilt, monkeypatch):
    """A ball end mill's sweeps are not held from building to cutting (`RebuiltSolid`):
    `ball:0.5`'s are ~230 kB each, and a 100,000-line program's took 23 GB before its
    first tile. Each is made again from its poses when read, the same mesh bit for bit as
    the one built first, the last `REBUILT_KEPT` read are kept, and the part and report are
    those of the sweeps held (`REBUILD_BALL_SWEEPS` False), to the bit."""
    import machinesim.cutting.sweeps as sweeps_module
    import machinesim.cutting.sweepset as sweepset
    from machinesim.cutting.sweeps import RebuiltSolid
    from machinesim.rotations import rotation_xyz

    tool = BallEndMill(0.5e-3, chord_tol=2e-6)
    stock = block(3e-3, 2e-3, 1e-3)
    angle = np.linspace(0.0, 4.0 * np.pi, 41)
    poses = np.repeat(np.eye(4)[None], len(angle), axis=0)
    poses[:, :3, :3] = rotation_xyz(tilt, -tilt, 0.0)
    radius = 0.8e-3 - 0.1e-3 * angle / np.pi
    poses[:, :3, 3] = np.stack([1.5e-3 + radius * np.cos(angle), 1e-3 + radius * np.sin(angle),
                                -40e-6 - 2e-6 * angle], axis=1)

    def everything(low, high):
        return np.ones(len(low), dtype=bool)

    def meshes(solids):
        return [(np.asarray(m.vert_properties), np.asarray(m.tri_verts))
                for m in (solid.to_mesh64() for solid in solids)]

    held = sweepset.SweepSet(tool, [poses], 1e-9)
    monkeypatch.setattr(sweepset, "REBUILD_BALL_SWEEPS", False)
    held_solids = held.hulls(everything)[0]
    monkeypatch.setattr(sweepset, "REBUILD_BALL_SWEEPS", True)
    made = sweepset.SweepSet(tool, [poses], 1e-9).hulls(everything)[0]
    assert len(made) == len(held_solids) == 40
    assert all(isinstance(list.__getitem__(made, i), RebuiltSolid) for i in range(len(made)))
    for (v0, t0), (v1, t1) in zip(meshes(held_solids), meshes(made), strict=True):
        assert v0.tobytes() == v1.tobytes() and t0.tobytes() == t1.tobytes()
    monkeypatch.setattr(sweeps_module, "REBUILT_KEPT", 3)
    kept = sweepset.SweepSet(tool, [poses], 1e-9).hulls(everything)[0]
    read = [kept[i] for i in range(6)]
    assert list(kept._made) == [3, 4, 5]  # the last three read
    assert kept[5] is read[5] and kept[0] is not read[0]

    parts = []
    for rebuild in (False, True):
        monkeypatch.setattr(sweepset, "REBUILD_BALL_SWEEPS", rebuild)
        parts.append(remove(stock, tool, [poses], method="boolean", sweeps_per_tile=8))
    (held_part, held_report), (part, report) = parts
    assert report.n_cells > 1  # tiles share sweeps: read more than once
    assert report.removed_volume == held_report.removed_volume > 0.0
    assert report.swept_volume == held_report.swept_volume
    for a, b in zip(held_part.mesh(), part.mesh(), strict=True):
        assert a.tobytes() == b.tobytes()


def test_a_path_of_one_pose_removes_the_tool_standing_there():
    """One pose is the tool standing there: it removes its own volume, as the same pose
    given twice does (it had formed no sweep and removed nothing, without a word). A flat
    end mill 1 mm into a block, well inside it: the regular polygon of its corners on the
    circle, n/2 r^2 sin(2 pi / n), times the depth."""
    tool = FlatEndMill(0.5e-3)
    n, depth = tool.segments, 1e-3
    assert np.allclose(np.hypot(*tool.vertices()[:n, :2].T), 0.5e-3, rtol=1e-15)
    by_hand = n / 2 * 0.5e-3 ** 2 * math.sin(2 * math.pi / n) * depth
    stock = block(10e-3, 10e-3, 2e-3)
    at = np.eye(4)
    at[:3, 3] = (5e-3, 5e-3, -depth)
    one, one_report = remove(stock, tool, [at[None]])
    two, two_report = remove(stock, tool, [np.stack([at, at])])
    assert one_report.removed_volume == pytest.approx(by_hand, rel=VOLUME_REL)
    assert one_report.n_sweeps == two_report.n_sweeps == 1
    assert not one_report.empty_cut
    assert one_report.removed_volume == two_report.removed_volume
    assert one.manifold.volume() == pytest.approx(two.manifold.volume(), rel=VOLUME_REL)
    assert stock.manifold.volume() - one.manifold.volume() == pytest.approx(by_hand, rel=1e-9)
