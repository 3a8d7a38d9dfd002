"""The height-field cutter against brute force, the boolean engine and manifold3d's checks."""

import math

import manifold3d
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from machinesim.cutting import relief as relief_engine
from machinesim.cutting import remove
from machinesim.cutting.relief import envelope, lower_hull
from machinesim.exceptions import InputError
from machinesim.metrology.surface import height_map
from machinesim.tools import BallEndMill, RoundNoseTool, VTool
from machinesim.workpiece import Part, block, mesh_volume

#: Two exact meshes of the same solid: heights agree to float64 round-off at mm scale
#: (~1e-19 m per operation); 1e-13 m leaves a wide margin and still catches any real error.
HEIGHT_TOL = 1e-13
#: Volumes of two exact meshes of one solid agree to summation round-off.
VOLUME_REL = 1e-12

ALONG_Y = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])


def pose(position, rotation=None):
    matrix = np.eye(4)
    matrix[:3, :3] = np.eye(3) if rotation is None else rotation
    matrix[:3, 3] = position
    return matrix


def groove(axis, across, depth, low=-1e-3, high=4e-3, rotation=None):
    """A straight groove along X (axis 0) or Y (axis 1) right across a 3 mm block."""
    if axis == 0:
        ends = [(low, across, -depth), (high, across, -depth)]
        turn = np.eye(3) if rotation is None else rotation
    else:
        ends = [(across, low, -depth), (across, high, -depth)]
        turn = ALONG_Y if rotation is None else rotation
    return np.array([pose(p, turn) for p in ends])


def brute_envelope(u0, z0, u1, z1, top, at):
    """min(top, segments) at the points ``at``, segment by segment."""
    best = np.full(len(at), top)
    for a, za, b, zb in zip(u0, z0, u1, z1, strict=True):
        inside = (at >= a) & (at <= b)
        best[inside] = np.minimum(best[inside], za + (zb - za) * (at[inside] - a) / (b - a))
    return best


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(1, 12))
def test_envelope_equals_the_pointwise_minimum(seed, count):
    # Random profiles as a groove leaves them: polylines that start and end above the top
    # (z = 0), anywhere in between, overlapping each other and the ends of the domain.
    rng = np.random.default_rng(seed)
    pieces = []
    for _ in range(count):
        n = int(rng.integers(2, 6))
        u = np.sort(rng.uniform(-0.5, 1.5, n + 1)) + np.arange(n + 1) * 1e-3
        z = rng.uniform(-1.0, 0.5, n + 1)
        z[[0, -1]] = rng.uniform(0.01, 0.5, 2)
        pieces.append((u[:-1], z[:-1], u[1:], z[1:]))
    u0, z0, u1, z1 = (np.concatenate([p[i] for p in pieces]) for i in range(4))
    u, z = envelope(u0, z0, u1, z1, 0.0, 1.0, 0.0)
    assert u[0] == 0.0 and u[-1] == 1.0 and np.all(np.diff(u) > 0.0)
    at = np.concatenate([rng.uniform(0.0, 1.0, 400), u])
    np.testing.assert_allclose(np.interp(at, u, z), brute_envelope(u0, z0, u1, z1, 0.0, at),
                               atol=1e-12)


def test_envelope_of_a_dense_raster_splits_into_halves_and_equals_the_one_table(monkeypatch):
    # 3000 V profiles 1 mm wide stepped by 1 um (a raster's passes), each point under ~1000
    # of them: one table of every pair over each interval would hold ~4.5e9 entries. Split
    # between chains and merged, the envelope is the pointwise minimum, and on a part small
    # enough for one table it is the same, point for point.
    from machinesim.cutting import profiles

    rng = np.random.default_rng(4)
    centres = np.arange(3000) * 1e-6
    depth = 1e-5 + rng.uniform(0.0, 1e-8, len(centres))
    u0 = np.concatenate([centres - 5e-4, centres])
    u1 = np.concatenate([centres, centres + 5e-4])
    z0 = np.concatenate([np.full(len(centres), 1e-6), -depth])
    z1 = np.concatenate([-depth, np.full(len(centres), 1e-6)])
    order = np.argsort(np.concatenate([np.arange(3000), np.arange(3000)]), kind="stable")
    u0, z0, u1, z1 = u0[order], z0[order], u1[order], z1[order]  # chain by chain
    u, z = envelope(u0, z0, u1, z1, -1e-3, 4e-3, 0.0)
    at = np.concatenate([rng.uniform(-1e-3, 4e-3, 2000), u])
    np.testing.assert_allclose(np.interp(at, u, z), brute_envelope(u0, z0, u1, z1, 0.0, at),
                               rtol=0, atol=1e-18)
    few = slice(0, 120)  # 60 profiles: one table
    one = envelope(u0[few], z0[few], u1[few], z1[few], -1e-3, 4e-3, 0.0)
    monkeypatch.setattr(profiles, "MOST_PAIRS", 10)
    split = envelope(u0[few], z0[few], u1[few], z1[few], -1e-3, 4e-3, 0.0)
    np.testing.assert_array_equal(split[0], one[0])
    np.testing.assert_allclose(split[1], one[1], rtol=0, atol=1e-21)


def test_envelope_keeps_only_the_corners():
    # Two V's whose inner flanks cross below the top: corners at the two bottoms, the ridge
    # between them and where the outer flanks meet the top, nothing else.
    u0 = np.array([0.1, 0.3, 0.3, 0.5])
    u1 = np.array([0.3, 0.5, 0.5, 0.7])
    z0 = np.array([0.2, -0.2, 0.2, -0.2])
    z1 = np.array([-0.2, 0.2, -0.2, 0.2])
    u, z = envelope(u0, z0, u1, z1, 0.0, 1.0, 0.0)
    np.testing.assert_allclose(u, [0.0, 0.2, 0.3, 0.4, 0.5, 0.6, 1.0], atol=1e-15)
    np.testing.assert_allclose(z, [0.0, 0.0, -0.2, 0.0, -0.2, 0.0, 0.0], atol=1e-15)


def test_lower_hull_of_a_square_and_its_centre():
    u = np.array([0.0, 1.0, 1.0, 0.0, 0.5, 0.5])
    z = np.array([0.0, 0.0, 1.0, 1.0, 0.5, 0.0])  # (0.5, 0) is collinear: dropped
    np.testing.assert_array_equal(lower_hull(u, z), [[0.0, 0.0], [1.0, 0.0]])


def crossing_paths(rng, tool_rotation=None):
    paths = [groove(0, y, d, rotation=tool_rotation)
             for y, d in zip(rng.uniform(0.2e-3, 2.8e-3, 9), rng.uniform(2e-6, 30e-6, 9),
                             strict=True)]
    paths += [groove(1, x, d) for x, d in zip(rng.uniform(0.2e-3, 2.8e-3, 7),
                                              rng.uniform(2e-6, 30e-6, 7), strict=True)]
    return paths


def assert_same_solid(a: Part, b: Part):
    assert a.volume == pytest.approx(b.volume, rel=VOLUME_REL)
    np.testing.assert_allclose(a.bounds, b.bounds, atol=HEIGHT_TOL)
    x = np.linspace(0.0, 3e-3, 157)[1:-1] + 1.234e-7
    y = np.linspace(0.0, 3e-3, 141)[1:-1] + 2.345e-7
    np.testing.assert_allclose(height_map(a, x, y), height_map(b, x, y), atol=HEIGHT_TOL)


@pytest.mark.parametrize("tool", [VTool(math.pi / 2), VTool(math.radians(60.0)),
                                  RoundNoseTool(0.2e-3, math.pi / 2),
                                  BallEndMill(0.5e-3, chord_tol=1e-6)],
                         ids=["v90", "v60", "nose", "ball"])
def test_relief_is_the_boolean_solid(tool):
    rng = np.random.default_rng(7)
    stock = block(3e-3, 3e-3, 0.5e-3)
    paths = crossing_paths(rng)
    relief, by_relief = remove(stock, tool, paths)
    boolean, by_boolean = remove(stock, tool, paths, method="boolean")
    assert (by_relief.method, by_boolean.method) == ("relief", "boolean")
    assert_same_solid(relief, boolean)
    assert by_relief.removed_volume == pytest.approx(by_boolean.removed_volume, rel=1e-9, abs=0.0)
    # Closed and oriented: manifold3d takes the mesh as it is, and agrees on the volume.
    vertices, triangles = relief.mesh()
    assert relief.manifold.status() == manifold3d.Error.NoError
    assert relief.manifold.num_tri() == len(triangles)
    assert mesh_volume(vertices, triangles) == pytest.approx(relief.volume, rel=VOLUME_REL)


def test_tilted_tool_and_a_second_program_on_the_cut_part():
    # Seed 000 tilts the V about the groove direction; a second program of grooves cuts the
    # relief the first one left, and both equal one boolean run of all the grooves.
    c, s = math.cos(0.2), math.sin(0.2)
    tilt = np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
    rng = np.random.default_rng(3)
    stock = block(3e-3, 3e-3, 0.5e-3)
    first = crossing_paths(rng, tool_rotation=tilt)
    second = crossing_paths(rng)
    tool = VTool(math.pi / 2)
    once, _ = remove(stock, tool, first)
    twice, report = remove(once, tool, second)
    assert report.method == "relief" and once.reliefs is not None
    boolean, _ = remove(stock, tool, first + second, method="boolean")
    assert_same_solid(twice, boolean)
    assert report.removed_volume == pytest.approx(once.volume - twice.volume, rel=1e-9, abs=0.0)


def test_separated_windows_are_cut_by_relief_and_touching_ones_are_not():
    rng = np.random.default_rng(11)
    stock = block(3e-3, 3e-3, 0.5e-3)
    paths = crossing_paths(rng)
    tool = VTool(math.pi / 2)
    windows = [(0.3e-3, 1.1e-3, 0.2e-3, 1.3e-3), (1.5e-3, 2.9e-3, 1.7e-3, 2.6e-3)]
    relief, report = remove(stock, tool, paths, roi=windows)
    boolean, by_boolean = remove(stock, tool, paths, roi=windows, method="boolean")
    assert report.method == "relief" and report.n_cells == 2
    assert relief.volume == pytest.approx(boolean.volume, rel=VOLUME_REL)
    assert report.removed_volume == pytest.approx(by_boolean.removed_volume, rel=1e-9, abs=0.0)
    touching = [(0.3e-3, 1.1e-3, 0.2e-3, 1.3e-3), (1.1e-3, 2.9e-3, 0.2e-3, 1.3e-3)]
    _, report = remove(stock, tool, paths, roi=touching)
    assert report.method == "boolean"


def test_a_part_too_large_to_build_is_refused_with_advice(monkeypatch):
    monkeypatch.setattr(relief_engine, "MAX_CELLS", 20)
    rng = np.random.default_rng(5)
    with pytest.raises(InputError, match=r"about [\d,]+ triangles.*roi="):
        remove(block(3e-3, 3e-3, 0.5e-3), VTool(math.pi / 2), crossing_paths(rng))


@pytest.mark.parametrize("case", ["short groove", "turned block", "through the bottom",
                                  "plunge", "two slopes"])
def test_other_cuts_fall_back_to_the_boolean_engine(case):
    stock = block(3e-3, 3e-3, 0.5e-3)
    paths = [groove(0, 1.5e-3, 10e-6)]
    if case == "short groove":
        paths = [groove(0, 1.5e-3, 10e-6, low=0.5e-3)]  # starts inside the block
    elif case == "turned block":
        stock = Part(stock.manifold.rotate((0.0, 0.0, 30.0)))
    elif case == "through the bottom":
        stock = block(3e-3, 3e-3, 5e-6)
    elif case == "plunge":
        paths.append(np.array([pose((1e-3, 1e-3, 1e-6)), pose((1e-3, 1e-3, -5e-6))]))
    else:
        # Two grooves along one direction at different slopes: not one extrusion (grooves
        # of one direction at one slope are the relief's, tests/test_relief_slanted.py).
        paths = [np.array([pose((-1e-3, -1e-3, -5e-6)), pose((4e-3, 4e-3, -15e-6))]),
                 np.array([pose((-1e-3, 0.0, -5e-6)), pose((4e-3, 5e-3, -25e-6))])]
    _, report = remove(stock, VTool(math.pi / 2), paths)
    assert report.method == "boolean"
