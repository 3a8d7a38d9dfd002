"""Straight grooves in any XY direction by height field: against the boolean engine and by hand."""

import math

import manifold3d
import numpy as np
import pytest

from machinesim.cutting import remove
from machinesim.cutting.relief_mesh import Family, Relief, mesh_relief
from machinesim.exceptions import MachineSimWarning
from machinesim.metrology.surface import height_map
from machinesim.tools import RoundNoseTool, VTool
from machinesim.workpiece import Part, block, mesh_volume

#: Two exact meshes of one solid: heights agree to float64 round-off at mm scale.
HEIGHT_TOL = 1e-13
#: Volumes of two exact meshes of one solid agree to summation round-off.
VOLUME_REL = 1e-12
V90 = VTool(math.pi / 2)


def turn(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def grooves(angle, offsets, depths, centre=(1.5e-3, 1.5e-3), half=4e-3):
    """Grooves along direction ``angle`` (rad from +X), tool turned with them, right across
    a 3 mm block: each at ``offset`` (m) from ``centre`` across its direction."""
    rotation = turn(angle)
    d, n = rotation[:, 0], rotation[:, 1]
    paths = []
    for offset, depth in zip(offsets, depths, strict=True):
        middle = np.array([centre[0], centre[1], -depth]) + offset * n
        poses = []
        for p in (middle - half * d, middle + half * d):
            pose = np.eye(4)
            pose[:3, :3], pose[:3, 3] = rotation, p
            poses.append(pose)
        paths.append(np.array(poses))
    return paths


def random_pattern(seed: int, first: float, second: float):
    rng = np.random.default_rng(seed)
    paths = grooves(first, rng.uniform(-2.2e-3, 2.2e-3, 9), rng.uniform(2e-6, 40e-6, 9))
    paths += grooves(second, rng.uniform(-2.2e-3, 2.2e-3, 7), rng.uniform(2e-6, 40e-6, 7))
    return paths


def assert_closed(part: Part):
    vertices, triangles = part.mesh()
    assert part.manifold.status() == manifold3d.Error.NoError
    assert part.manifold.num_tri() == len(triangles)
    assert mesh_volume(vertices, triangles) == pytest.approx(part.volume, rel=VOLUME_REL)


def assert_same_solid(a: Part, b: Part):
    assert a.volume == pytest.approx(b.volume, rel=VOLUME_REL)
    np.testing.assert_allclose(a.bounds, b.bounds, atol=HEIGHT_TOL)
    x = np.linspace(0.0, 3e-3, 157)[1:-1] + 1.234e-7
    y = np.linspace(0.0, 3e-3, 141)[1:-1] + 2.345e-7
    ha, hb = height_map(a, x, y), height_map(b, x, y)
    np.testing.assert_array_equal(np.isnan(ha), np.isnan(hb))
    np.testing.assert_allclose(ha, hb, atol=HEIGHT_TOL)


@pytest.mark.parametrize(("first", "second", "tool"), [
    (0.3, 0.3 + math.pi / 2 + 0.2, V90),                   # two arbitrary directions
    (math.radians(0.3), math.radians(90.3) + 1e-4, V90),   # C turn and squareness
    (1e-10, math.pi / 2 + 1e-4, V90),                      # nearly along X
    (-0.45, 0.0, RoundNoseTool(0.2e-3, math.pi / 2)),      # one set along X exactly
], ids=["arbitrary", "pyramid", "near-axis", "one-slanted"])
def test_slanted_grooves_are_the_boolean_solid(first, second, tool):
    stock = block(3e-3, 3e-3, 0.5e-3)
    paths = random_pattern(4, first, second)
    relief, by_relief = remove(stock, tool, paths)
    boolean, by_boolean = remove(stock, tool, paths, method="boolean")
    assert (by_relief.method, by_boolean.method) == ("relief", "boolean")
    assert len(relief.reliefs[0].families) == 2
    assert_same_solid(relief, boolean)
    assert by_relief.removed_volume == pytest.approx(by_boolean.removed_volume, rel=1e-9, abs=0.0)
    assert_closed(relief)


def test_one_slanted_groove_removes_its_profile_times_its_chord():
    # A 90-deg V groove h deep leaves a triangle of area h^2 across it; at angle phi through
    # the middle of an L x L block every line along it runs from the side x = 0 to x = L,
    # a chord of L / cos(phi): removed volume h^2 L / cos(phi), by hand.
    phi, depth, side = 0.4, 30e-6, 3e-3
    stock = block(side, side, 0.5e-3)
    part, report = remove(stock, V90, grooves(phi, [0.0], [depth]))
    assert report.method == "relief"
    expected = depth**2 * side / math.cos(phi)
    assert report.removed_volume == pytest.approx(expected, rel=1e-12, abs=0.0)
    assert stock.volume - part.volume == pytest.approx(expected, rel=1e-9, abs=0.0)
    assert_closed(part)


def test_pyramid_apexes_stand_where_the_ridges_cross_at_their_height():
    # 90-deg V grooves at pitch p, depth h > p / 2: neighbouring flanks meet at height
    # p / 2 - h on the line halfway between two grooves, whatever the angle between the
    # sets; the apexes are where the ridge lines of the two sets cross.
    pitch, depth = 50e-6, 40e-6
    first, second = math.radians(0.3), math.radians(90.3) + 1e-4
    offsets = pitch * (np.arange(16) - 7.5)
    paths = (grooves(first, offsets, [depth] * 16, centre=(0.4e-3, 0.4e-3), half=1.5e-3)
             + grooves(second, offsets, [depth] * 16, centre=(0.4e-3, 0.4e-3), half=1.5e-3))
    stock = block(0.8e-3, 0.8e-3, 0.2e-3)
    part, report = remove(stock, V90, paths)
    assert report.method == "relief"
    vertices, _ = part.mesh()
    vertices = vertices[vertices[:, 2] > -0.1e-3]  # the top (the bottom is at -0.2 mm)
    n1, n2 = turn(first)[:2, 1], turn(second)[:2, 1]
    ridges = offsets[:-1] + pitch / 2
    s1, s2 = np.meshgrid(ridges, ridges, indexing="ij")
    matrix = np.array([n1, n2])
    apex = np.linalg.solve(matrix, np.stack([s1.ravel(), s2.ravel()])) + 0.4e-3
    inside = ((apex > 0.0) & (apex < 0.8e-3)).all(axis=0)
    apex = apex[:, inside].T
    assert len(apex) > 150
    gap = np.linalg.norm(vertices[None, :, :2] - apex[:, None, :], axis=2)
    nearest = gap.argmin(axis=1)
    assert gap.min(axis=1).max() < 1e-15
    np.testing.assert_allclose(vertices[nearest, 2], pitch / 2 - depth, atol=HEIGHT_TOL)
    assert vertices[:, 2].max() == pytest.approx(pitch / 2 - depth, abs=HEIGHT_TOL)
    boolean, _ = remove(stock, V90, paths, method="boolean")
    assert part.volume == pytest.approx(boolean.volume, rel=VOLUME_REL)


def test_a_second_program_extends_the_slanted_envelopes():
    stock = block(3e-3, 3e-3, 0.5e-3)
    first, second = 0.25, 0.25 + math.pi / 2 - 0.1
    rng = np.random.default_rng(9)
    a = grooves(first, rng.uniform(-2e-3, 2e-3, 6), rng.uniform(2e-6, 30e-6, 6))
    b = grooves(second, rng.uniform(-2e-3, 2e-3, 6), rng.uniform(2e-6, 30e-6, 6))
    c = grooves(first, rng.uniform(-2e-3, 2e-3, 4), rng.uniform(2e-6, 30e-6, 4))
    once, _ = remove(stock, V90, a)
    twice, report = remove(once, V90, b + c)
    assert report.method == "relief" and len(twice.reliefs[0].families) == 2
    boolean, _ = remove(stock, V90, a + b + c, method="boolean")
    assert_same_solid(twice, boolean)
    assert report.removed_volume == pytest.approx(once.volume - twice.volume, rel=1e-9, abs=0.0)
    # A third direction on that part is the boolean engine's.
    _, third = remove(twice, V90, grooves(1.0, [0.0], [10e-6]))
    assert third.method == "boolean"


def test_windows_cut_slanted_grooves_like_the_boolean_engine():
    stock = block(3e-3, 3e-3, 0.5e-3)
    paths = random_pattern(12, 0.2, 0.2 + math.pi / 2)
    windows = [(0.3e-3, 1.1e-3, 0.2e-3, 1.3e-3), (1.5e-3, 2.9e-3, 1.7e-3, 2.6e-3)]
    relief, report = remove(stock, V90, paths, roi=windows)
    boolean, by_boolean = remove(stock, V90, paths, roi=windows, method="boolean")
    assert report.method == "relief" and report.n_cells == 2
    assert_same_solid(relief, boolean)
    assert report.removed_volume == pytest.approx(by_boolean.removed_volume, rel=1e-9, abs=0.0)
    assert_closed(relief)


@pytest.mark.parametrize("case", ["three directions", "nearly parallel", "short"])
def test_what_the_grid_cannot_hold_falls_back_to_the_boolean_engine(case):
    stock = block(3e-3, 3e-3, 0.5e-3)
    if case == "three directions":
        paths = grooves(0.1, [0.0], [10e-6]) + grooves(1.2, [0.0], [10e-6]) + grooves(
            2.3, [0.0], [10e-6])
    elif case == "nearly parallel":
        paths = grooves(0.1, [-0.5e-3], [10e-6]) + grooves(0.15, [0.5e-3], [10e-6])
    else:  # ends inside the block along its direction
        paths = grooves(0.3, [0.0], [10e-6], half=1e-3)
    _, report = remove(stock, V90, paths)
    assert report.method == "boolean"


def test_a_hand_made_relief_meshes_to_its_volume_by_hand():
    # A V groove (half-width and depth w) along each diagonal of a unit square, written as
    # envelopes directly: the mesher alone, clipping on all four sides. A line along a
    # diagonal at offset a crosses the square over sqrt(2) - 2|a|, so one groove removes
    # 2 * integral_0^w (w - a)(sqrt(2) - 2a) da = sqrt(2) w^2 - 2 w^3 / 3; where both cut,
    # the top is the lower V and the part removed twice, integral of min(w - |a|, w - |b|)
    # over |a|, |b| <= w, is 4 * (w^3 - 2 w^3 / 3) = 4 w^3 / 3.
    w, r = 0.2, math.sqrt(0.5)
    # s1 = n1 . p spans [-r, r] over the square, the diagonal x = y at s1 = 0; s2 spans
    # [-2r, 0], the diagonal x + y = 1 at s2 = -r.
    f1 = Family(np.array([-r, r]), np.array([-r, -w, 0.0, w, r]),
                np.array([0.0, 0.0, -w, 0.0, 0.0]))
    f2 = Family(np.array([-r, -r]), np.array([-2 * r, -r - w, -r, -r + w, 0.0]),
                np.array([0.0, 0.0, -w, 0.0, 0.0]))
    relief = Relief(0.0, 1.0, 0.0, 1.0, -1.0, 0.0, (f1, f2))
    vertices, triangles, volume, cut = mesh_relief(relief)
    expected = 2.0 * (math.sqrt(2.0) * w**2 - 2.0 * w**3 / 3.0) - 4.0 * w**3 / 3.0
    assert cut == pytest.approx(expected, rel=1e-12)
    assert volume == pytest.approx(1.0 - expected, rel=1e-12)
    with pytest.warns(MachineSimWarning, match="measures 1 x 1 x 1 m"):  # a unit cube by hand
        part = Part.from_mesh(vertices, triangles)
    assert part.volume == pytest.approx(volume, rel=1e-12)
    # Sampled heights against the two Vs evaluated directly.
    x = np.linspace(0.0, 1.0, 61)[1:-1] + 1.234e-4
    s1 = r * (x[None, :] - x[:, None])  # rows y, columns x: -r x + r y
    s2 = -r * (x[None, :] + x[:, None])
    depth = np.minimum(np.maximum(np.abs(s1) - w, -w), 0.0)
    other = np.minimum(np.maximum(np.abs(s2 + r) - w, -w), 0.0)
    np.testing.assert_allclose(height_map(part, x, x), np.minimum(depth, other), atol=1e-15)


def test_clipping_splits_a_shared_edge_at_one_vertex():
    # Two triangles of the square [-1, 1]^2 sharing its diagonal, clipped to [0, 2] x
    # [-2, 2]: the diagonal is split once, at (0, 0), and both halves use that vertex; of
    # the square's right half the lower triangle keeps 3/2, the upper 1/2.
    from machinesim.cutting.clip import clip_polygons

    vertices = np.array([[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 1.0, 0.0]])
    fan = np.array([[0, 1, 2], [0, 2, 3]])
    count = np.array([3, 3])
    flags = np.zeros(fan.shape, dtype=bool)
    fan, count, flags, made = clip_polygons(fan, count, flags, vertices, (0.0, 2.0, -2.0, 2.0))
    np.testing.assert_array_equal(made[:, :2][np.argsort(made[:, 1])][1], [0.0, 0.0])
    shared = set(fan[0, :count[0]].tolist()) & set(fan[1, :count[1]].tolist())
    centre = 4 + int(np.flatnonzero((made[:, 0] == 0.0) & (made[:, 1] == 0.0))[0])
    assert centre in shared and 2 in shared
    points = np.concatenate([vertices, made])
    for row, n, expected in zip(fan, count, (1.5, 0.5), strict=True):
        p = points[row[:n], :2]
        area = 0.5 * np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1])
        assert area == pytest.approx(expected, rel=1e-15)
    # The edges made along x = 0 are flagged as lying on the rectangle's side.
    on_side = [(row[k], row[(k + 1) % n]) for row, n, f in zip(fan, count, flags, strict=True)
               for k in range(n) if f[k]]
    assert all(points[a, 0] == 0.0 and points[b, 0] == 0.0 for a, b in on_side)
    assert len(on_side) == 2


# ------------------------------------------------------------ sloped grooves (tilted table)

def tilted(paths, tilt_x: float, tilt_y: float, about=(1.5e-3, 1.5e-3, 0.0)):
    """The paths as a table tilted by ``tilt_x`` about X and ``tilt_y`` about Y (rad) leaves
    them on the block: positions turned about ``about``, the tool turned with them, so every
    groove of one direction slopes alike and keeps its orientation."""
    cx, sx, cy, sy = math.cos(tilt_x), math.sin(tilt_x), math.cos(tilt_y), math.sin(tilt_y)
    turn_xy = (np.array([[cy, 0.0, sy], [0.0, 1.0, 0.0], [-sy, 0.0, cy]])
               @ np.array([[1.0, 0.0, 0.0], [0.0, cx, -sx], [0.0, sx, cx]]))
    centre = np.array(about)
    out = []
    for path in paths:
        moved = path.copy()
        moved[:, :3, :3] = turn_xy @ path[:, :3, :3]
        moved[:, :3, 3] = (path[:, :3, 3] - centre) @ turn_xy.T + centre
        out.append(moved)
    return out


@pytest.mark.parametrize(("first", "second", "tilt"), [
    (0.3, 0.3 + math.pi / 2 + 0.2, (2e-3, -3e-3)),          # arbitrary, steep tilts
    (math.radians(0.3), math.radians(90.3) + 1e-4, (8e-6, -6e-6)),  # a C table's tilts
    (0.0, math.pi / 2, (0.0, 4e-3)),                         # along X and Y, one sloped
], ids=["arbitrary", "c-table", "axes"])
def test_sloped_grooves_are_the_boolean_solid(first, second, tilt):
    stock = block(3e-3, 3e-3, 0.5e-3)
    paths = tilted(random_pattern(7, first, second), *tilt)
    relief, by_relief = remove(stock, V90, paths)
    boolean, by_boolean = remove(stock, V90, paths, method="boolean")
    assert (by_relief.method, by_boolean.method) == ("relief", "boolean")
    slopes = [f.slope for f in relief.reliefs[0].families]
    assert len(slopes) == 2 and any(s != 0.0 for s in slopes)
    assert_same_solid(relief, boolean)
    assert by_relief.removed_volume == pytest.approx(by_boolean.removed_volume, rel=1e-9, abs=0.0)
    assert_closed(relief)


def test_pyramids_on_a_tilted_table_rise_through_the_top_like_the_boolean_solid():
    # Ridges exactly at the top when level (pitch = 2 depth): tilted 20 urad, they stand
    # above the top on one side of the block (cut flat there) and below it on the other,
    # so the surface is cut at the top along lines across the grid's cells.
    pitch, depth = 50e-6, 25e-6
    offsets = pitch * (np.arange(16) - 7.5)
    level = (grooves(0.01, offsets, [depth] * 16, centre=(0.4e-3, 0.4e-3), half=1.5e-3)
             + grooves(0.01 + math.pi / 2 + 1e-4, offsets, [depth] * 16,
                       centre=(0.4e-3, 0.4e-3), half=1.5e-3))
    paths = tilted(level, 2e-5, 1.5e-5, about=(0.4e-3, 0.4e-3, 0.0))
    stock = block(0.8e-3, 0.8e-3, 0.2e-3)
    part, report = remove(stock, V90, paths)
    boolean, _ = remove(stock, V90, paths, method="boolean")
    assert report.method == "relief"
    vertices, _ = part.mesh()
    top = vertices[vertices[:, 2] > -0.1e-3, 2]
    assert top.max() == 0.0 and np.sum(top == 0.0) > 100  # flat strips left on the top
    x = np.linspace(0.0, 0.8e-3, 201)[1:-1] + 1.234e-9
    ha, hb = height_map(part, x, x), height_map(boolean, x, x)
    np.testing.assert_allclose(ha, hb, atol=HEIGHT_TOL)
    assert part.volume == pytest.approx(boolean.volume, rel=VOLUME_REL)
    assert_closed(part)


@pytest.mark.parametrize(("h0", "h1"), [(10e-6, 30e-6), (20e-6, -10e-6)],
                         ids=["deeper", "out through the top"])
def test_a_sloped_groove_removes_the_integral_of_its_section(h0, h1):
    # A 90-deg V groove along X whose depth below the top runs linearly from h0 at x = 0 to
    # h1 at x = L: the section at x is the V, area h(x)^2 where h > 0, so the removed
    # volume is the integral of max(h, 0)^2 over [0, L], by hand. Lines ending outside the
    # block at the same slope.
    side = 3e-3
    stock = block(side, side, 0.5e-3)
    slope = (h0 - h1) / side                      # dz/dx of the tool's edge
    ends = np.array([-1e-3, side + 1e-3])
    paths = [np.array([pose_at((x, 1.5e-3, -h0 + slope * x)) for x in ends])]
    part, report = remove(stock, V90, paths)
    assert report.method == "relief"
    a = 0.0 if h1 >= 0.0 else h0 / (h0 - h1) * side  # where the groove leaves the top
    if h1 >= 0.0:
        expected = side * (h0**2 + h0 * h1 + h1**2) / 3.0
    else:
        expected = a * h0**2 / 3.0
    assert report.removed_volume == pytest.approx(expected, rel=1e-12, abs=0.0)
    assert stock.volume - part.volume == pytest.approx(expected, rel=1e-9, abs=0.0)
    assert_closed(part)


def pose_at(position) -> np.ndarray:
    pose = np.eye(4)
    pose[:3, 3] = position
    return pose


def test_grooves_of_one_direction_at_two_slopes_fall_back_to_the_boolean_engine():
    stock = block(3e-3, 3e-3, 0.5e-3)
    ends = np.array([-1e-3, 4e-3])
    paths = [np.array([pose_at((x, y, -10e-6 + slope * x)) for x in ends])
             for y, slope in ((1e-3, 1e-3), (2e-3, 2e-3))]
    _, report = remove(stock, V90, paths)
    assert report.method == "boolean"


def test_a_pyramid_window_on_a_tilted_c_table_is_cut_by_relief_as_by_the_boolean_engine(
        monkeypatch):
    # The machine's own route: the C table's location errors (tilts EA0C, EB0C, offsets)
    # and the squareness of Y slope and slant both groove sets; relief against the boolean
    # engine on the same program.
    from machinesim import load_machine
    from machinesim.cam.pyramids import PyramidPlan, pyramid_program
    from machinesim.cutting import cut, engine
    from machinesim.errors import ErrorModel

    machine = load_machine("grooving_4axis")
    errors = ErrorModel.from_dict({"location": {
        "Y": {"EC0Y_urad": 24.0},
        "C": {"EX0C_um": 3.0, "EY0C_um": -2.0, "EA0C_urad": 80.0, "EB0C_urad": -60.0}}})
    plan = PyramidPlan(window=0.4e-3)
    program = pyramid_program(machine, (0.0, 0.0), plan)
    stock = "block:0.4x0.4x1@-0.2,-0.2,0"  # top at z = 0
    part, report = cut(program, machine, "v:90", stock, errors)
    assert report.engine == "relief"
    assert any(f.slope != 0.0 for f in part.reliefs[0].families)
    monkeypatch.setattr(engine, "cut_reliefs", lambda *args, **kwargs: None)
    boolean, by_boolean = cut(program, machine, "v:90", stock, errors)
    assert by_boolean.engine == "boolean"
    assert part.volume == pytest.approx(boolean.volume, rel=VOLUME_REL)
    x = np.linspace(-0.2e-3, 0.2e-3, 121)[1:-1] + 1.234e-9
    np.testing.assert_allclose(height_map(part, x, x), height_map(boolean, x, x),
                               atol=HEIGHT_TOL)


def test_a_second_program_on_a_tilted_table_extends_the_sloped_envelopes():
    stock = block(3e-3, 3e-3, 0.5e-3)
    first, second = 0.25, 0.25 + math.pi / 2 - 0.1
    rng = np.random.default_rng(19)
    a = tilted(grooves(first, rng.uniform(-2e-3, 2e-3, 5), rng.uniform(5e-6, 30e-6, 5)),
               3e-4, 2e-4)
    b = tilted(grooves(second, rng.uniform(-2e-3, 2e-3, 5), rng.uniform(5e-6, 30e-6, 5))
               + grooves(first, rng.uniform(-2e-3, 2e-3, 3), rng.uniform(5e-6, 30e-6, 3)),
               3e-4, 2e-4)
    once, _ = remove(stock, V90, a)
    twice, report = remove(once, V90, b)
    assert report.method == "relief" and len(twice.reliefs[0].families) == 2
    boolean, _ = remove(stock, V90, a + b, method="boolean")
    assert_same_solid(twice, boolean)
    assert report.removed_volume == pytest.approx(once.volume - twice.volume, rel=1e-9, abs=0.0)
    # The same direction at another slope on that part is the boolean engine's.
    _, other = remove(twice, V90, tilted(grooves(first, [0.0], [10e-6]), -3e-4, 2e-4))
    assert other.method == "boolean"


def test_a_sweep_ending_in_the_stock_is_declined_before_the_reaching_bounds(monkeypatch):
    # A groove right across the block and a pass that stops 1 mm in: the second cannot span
    # the block, so the height field declines the cut. It is found from the tool's lowest
    # vertex at the sweeps' ends, before the bounds of the tool's reaching part (seconds on
    # a raster of thousands of short lines, all to be declined); the part is the boolean
    # engine's either way.
    from machinesim.cutting.sweepset import SweepSet

    called = []
    bounds = SweepSet.pose_bounds
    monkeypatch.setattr(SweepSet, "pose_bounds",
                        lambda self: called.append(1) or bounds(self))
    stock = block(3e-3, 3e-3, 0.5e-3)
    across = np.array([pose_at((x, 1e-3, -10e-6)) for x in (-1e-3, 4e-3)])
    stops = np.array([pose_at((x, 2e-3, -10e-6)) for x in (-1e-3, 1e-3)])
    part, report = remove(stock, V90, [across, stops])
    assert report.method == "boolean" and not called
    # the groove alone spans the block: measured by its reaching part, cut by height field
    _, alone = remove(stock, V90, [across])
    assert alone.method == "relief" and called
    # the boolean part holds both grooves, a 90 deg V 10 um deep (section 1e-10 m^2) over
    # the 3 mm block and over the 1 mm the second runs in before it stops
    assert stock.volume - part.volume == pytest.approx((3e-3 + 1e-3) * 1e-10, rel=1e-9,
                                                       abs=0.0)
