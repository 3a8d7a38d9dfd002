"""Height maps and profiles against closed-form heights of manifold3d parts, exact rational
plane values, and each other."""

from fractions import Fraction

import manifold3d
import numpy as np
import pytest

from machinesim.exceptions import InputError
from machinesim.metrology import height_map, profile
from machinesim.workpiece import Part

#: The brief's exactness: heights agree with the closed form to 0.001 nm on parts of ~10 mm.
#: float64 round-off there is ~1e-18 m, so 1e-12 m fails on any real error (a wrong triangle,
#: a float32 pass, an interpolated height) while leaving room for manifold3d's own rounding
#: of rotated vertices.
HEIGHT_M = 1e-12
MM = 1e-3


def box(size, origin=(0.0, 0.0, 0.0)) -> manifold3d.Manifold:
    return manifold3d.Manifold.cube(size).translate(origin)


def groove(axis: str, centre: float, bottom: float, length: float) -> manifold3d.Manifold:
    """A 90-degree V prism (a cube turned 45 degrees) with its lowest edge at ``bottom``.

    The lowest edge runs along ``axis`` ('x' or 'y') at ``centre`` on the other axis.
    """
    side = 4 * MM
    diamond = manifold3d.Manifold.cube([side, length, side], center=True)
    diamond = diamond.rotate([0.0, 45.0, 0.0]).translate([centre, 0.0, bottom + side / np.sqrt(2)])
    if axis == "x":
        diamond = diamond.rotate([0.0, 0.0, 90.0])
    return diamond


def pyramids(count: int, pitch: float, depth: float):
    """A count x count field of pyramids: a box minus crossing 90-degree V grooves.

    Grooves lie at multiples of the pitch, so the height is
    top - depth + min(distance to the nearest groove in x, in y), capped at the top.
    """
    size = count * pitch
    top = 0.0
    cuts = [groove("y", k * pitch, top - depth, 3 * size) for k in range(count + 1)]
    cuts += [groove("x", k * pitch, top - depth, 3 * size) for k in range(count + 1)]
    stock = box([size, size, 2 * MM], [0.0, 0.0, -2 * MM])
    part = manifold3d.Manifold.batch_boolean([stock, *cuts], manifold3d.OpType.Subtract)

    def heights(x, y):
        to_groove_x = np.abs(x - pitch * np.round(x / pitch))
        to_groove_y = np.abs(y - pitch * np.round(y / pitch))
        return np.minimum(top, top - depth + np.minimum(to_groove_x, to_groove_y))

    return Part(part), heights


def heightfield(z: np.ndarray, pitch, origin=(0.0, 0.0)):
    """A solid whose top is the triangulated grid z[j, i] at origin + (i, j) * pitch.

    Cells are split along alternating diagonals so edges meet at every angle; the sides go
    down to a flat bottom. Returns the vertices and triangles.
    """
    ny, nx = z.shape
    jj, ii = np.mgrid[0:ny, 0:nx]
    pitch = np.broadcast_to(pitch, (2,))
    top = np.column_stack([origin[0] + ii.ravel() * pitch[0], origin[1] + jj.ravel() * pitch[1],
                           z.ravel()])
    bottom = top.copy()
    bottom[:, 2] = z.min() - 1 * MM
    vertices = np.vstack([top, bottom])
    n = nx * ny

    def vid(j, i):
        return j * nx + i

    tris = []
    for j in range(ny - 1):
        for i in range(nx - 1):
            a, b, c, d = vid(j, i), vid(j, i + 1), vid(j + 1, i + 1), vid(j + 1, i)
            if (i + j) % 2:
                tris += [[a, b, c], [a, c, d]]
            else:
                tris += [[a, b, d], [b, c, d]]
    top_tris = np.array(tris)
    rim = [vid(0, i) for i in range(nx)] + [vid(j, nx - 1) for j in range(1, ny)]
    rim += [vid(ny - 1, i) for i in range(nx - 2, -1, -1)]
    rim += [vid(j, 0) for j in range(ny - 2, 0, -1)]
    sides = []
    for k in range(len(rim)):
        a, b = rim[k], rim[(k + 1) % len(rim)]
        sides += [[b, a, a + n], [b, a + n, b + n]]
    centre = len(vertices)
    vertices = np.vstack([vertices, [[origin[0] + (nx - 1) * pitch[0] / 2,
                                      origin[1] + (ny - 1) * pitch[1] / 2, bottom[0, 2]]]])
    base = [[centre, rim[(k + 1) % len(rim)] + n, rim[k] + n] for k in range(len(rim))]
    triangles = np.vstack([top_tris, sides, base]).astype(np.int64)
    assert manifold3d.Manifold(manifold3d.Mesh64(
        vertices, triangles.astype(np.uint64))).status() == manifold3d.Error.NoError
    return vertices, triangles


def exact_height(vertices, triangles, x: float, y: float):
    """Highest plane value over (x, y) among triangles containing it, in rational arithmetic."""
    px, py = Fraction(x), Fraction(y)
    best = None
    for tri in triangles:
        (x0, y0, z0), (x1, y1, z1), (x2, y2, z2) = (map(Fraction, vertices[k]) for k in tri)
        area = (x1 - x0) * (y2 - y0) - (y1 - y0) * (x2 - x0)
        if area <= 0:
            continue
        w1 = ((px - x0) * (y2 - y0) - (py - y0) * (x2 - x0)) / area
        w2 = ((x1 - x0) * (py - y0) - (y1 - y0) * (px - x0)) / area
        if w1 >= 0 and w2 >= 0 and w1 + w2 <= 1:
            z = z0 + w1 * (z1 - z0) + w2 * (z2 - z0)
            best = z if best is None else max(best, z)
    return best


def test_flat_top_is_exact_inside_and_on_the_rim_and_nan_outside():
    part = Part(box([10 * MM, 8 * MM, 2 * MM], [-3 * MM, 1 * MM, 0.5 * MM]))
    x = np.linspace(-4 * MM, 8 * MM, 121)  # steps of 0.1 mm: hits x = -3 and 7 mm exactly
    y = np.linspace(0.0, 10 * MM, 101)
    heights = height_map(part, x, y)
    assert heights.shape == (101, 121)
    assert heights.dtype == np.float64
    on = ((x >= -3 * MM) & (x <= 7 * MM))[None, :] & ((y >= 1 * MM) & (y <= 9 * MM))[:, None]
    # The rim (samples exactly on the side walls) belongs to the top: the highest point there
    # is the top face's edge.
    assert on[10, 10] and x[10] == -3 * MM and y[10] == 1 * MM
    assert np.all(heights[on] == 2.5 * MM)
    assert np.all(np.isnan(heights[~on]))
    with pytest.raises(ValueError):
        heights[0, 0] = 1.0  # results are read-only


def test_inclined_plane_matches_its_closed_form():
    angle = 10.0
    cutter = box([40 * MM, 40 * MM, 40 * MM], [-20 * MM, -20 * MM, 0.0])
    cutter = cutter.rotate([0.0, angle, 0.0]).translate([5 * MM, 0.0, 3 * MM])
    part = Part(box([10 * MM, 10 * MM, 5 * MM]) - cutter)
    x = np.linspace(0.0, 10 * MM, 401)  # 401 x 201 samples on two big triangles: many blocks
    y = np.linspace(0.0, 10 * MM, 201)
    heights = height_map(part, x, y)
    expected = 3 * MM - np.tan(np.radians(angle)) * (x - 5 * MM)
    np.testing.assert_allclose(heights, np.broadcast_to(expected, heights.shape), rtol=0,
                               atol=HEIGHT_M)


def test_v_groove_and_vertical_walls_give_no_spurious_heights():
    depth = 1 * MM
    part = Part(box([10 * MM, 4 * MM, 3 * MM]) - groove("y", 5 * MM, 3 * MM - depth, 20 * MM))
    x = np.linspace(0.0, 10 * MM, 1001)
    y = np.array([0.0, 1 * MM, 4 * MM])
    heights = height_map(part, x, y)
    expected = np.minimum(3 * MM, 3 * MM - depth + np.abs(x - 5 * MM))
    np.testing.assert_allclose(heights, np.broadcast_to(expected, heights.shape), rtol=0,
                               atol=HEIGHT_M)


def test_step_reads_the_top_of_the_wall_exactly_on_it():
    part = Part(box([10 * MM, 4 * MM, 1 * MM]) + box([5 * MM, 4 * MM, 2 * MM]))
    x = np.linspace(0.0, 10 * MM, 101)  # x = 5 mm, the wall, is a sample
    heights = height_map(part, x, [2 * MM])[0]
    np.testing.assert_array_equal(heights, np.where(x <= 5 * MM, 2 * MM, 1 * MM))


def test_pyramids_match_the_closed_form_on_ridges_and_grooves():
    part, heights_of = pyramids(4, 1 * MM, 0.6 * MM)
    x = np.linspace(0.0, 4 * MM, 161)  # 25 um steps: every groove, ridge and apex is a sample
    y = np.linspace(0.0, 4 * MM, 161)
    heights = height_map(part, x, y)
    assert not np.isnan(heights).any()
    np.testing.assert_allclose(heights, heights_of(x[None, :], y[:, None]), rtol=0,
                               atol=HEIGHT_M)


def test_tessellated_surface_has_no_cracks_at_vertices_or_edges():
    rng = np.random.default_rng(0)
    # Non-square cells off the origin: coordinates and edge slopes are not binary fractions,
    # so edge functions round and a sample on a shared edge is a real tie test.
    pitch, origin = np.array([1.3 * MM, 1.7 * MM]), np.array([1.1 * MM, -0.7 * MM])
    z = rng.uniform(0.0, 0.1 * MM, size=(9, 11))
    surface = heightfield(z, pitch, origin)
    # Four samples per cell side: every vertex, every edge midpoint and every cell centre (on
    # a diagonal) is a sample, exactly.
    x = origin[0] + np.arange(41) * (pitch[0] / 4)
    y = origin[1] + np.arange(33) * (pitch[1] / 4)
    heights = height_map(surface, x, y)
    assert not np.isnan(heights).any()
    np.testing.assert_allclose(heights[::4, ::4], z, rtol=0, atol=HEIGHT_M)
    np.testing.assert_allclose(heights[::4, 2::4], (z[:, :-1] + z[:, 1:]) / 2, rtol=0,
                               atol=HEIGHT_M)
    np.testing.assert_allclose(heights[2::4, ::4], (z[:-1] + z[1:]) / 2, rtol=0, atol=HEIGHT_M)
    # Profiles along every shared diagonal: 100 samples within round-off of each edge.
    for j in range(z.shape[0] - 1):
        for i in range(z.shape[1] - 1):
            ends = [[i, j], [i + 1, j + 1]] if (i + j) % 2 else [[i + 1, j], [i, j + 1]]
            start, end = origin + pitch * np.array(ends)  # the vertices, exactly
            _, along = profile(surface, start, end, np.hypot(*pitch) / 100)
            assert not np.isnan(along).any()


def test_long_thin_triangles_across_the_grid_read_their_exact_planes():
    """Cells 5 um by 1 mm sheared along the grid's diagonal: triangles 1.4 mm long and 3.5 um
    wide, whose boxes hold some 200 times the samples they cover (the case the grid's row
    spans are for). Every sample reads the exact rational plane value (or NaN off the part),
    and each row of the map is bit for bit the profile along it (the line sampler's boxes, a
    second method)."""
    rng = np.random.default_rng(4)
    vertices, triangles = heightfield(rng.uniform(0.0, 20e-6, size=(3, 41)), (5e-6, 1 * MM))
    vertices = vertices.copy()
    vertices[:, 0] += vertices[:, 1]  # x + y: the cells' long sides run along (1, 1)
    x = np.sort(rng.uniform(-0.1 * MM, 2.3 * MM, 17))
    y = np.sort(rng.uniform(-0.1 * MM, 2.1 * MM, 13))
    heights = height_map((vertices, triangles), x, y)
    covered = 0
    for j in range(len(y)):
        for i in range(len(x)):
            exact = exact_height(vertices, triangles, x[i], y[j])
            if exact is None:
                assert np.isnan(heights[j, i])
            else:
                covered += 1
                assert abs(Fraction(heights[j, i]) - exact) < HEIGHT_M
    assert covered >= 10
    x = np.linspace(-0.1 * MM, 2.3 * MM, 481)
    y = np.linspace(0.0, 2 * MM, 97)
    heights = height_map((vertices, triangles), x, y)
    # each row crosses the part over 0.2 mm, 40 samples at 5 um: about 3900 in 97 rows
    assert abs(np.isfinite(heights).sum() - 97 * 40) < 97 * 2
    for j in (0, 1, 17, 48, 95, 96):
        _, along = profile((vertices, triangles), (x[0], y[j]), (x[-1], y[j]), x[1] - x[0])
        np.testing.assert_array_equal(along, heights[j])


def test_heights_equal_the_exact_rational_plane_value():
    rng = np.random.default_rng(1)
    vertices, triangles = heightfield(rng.uniform(0.0, 2 * MM, size=(4, 4)), 3 * MM)
    x = np.sort(rng.uniform(0.0, 9 * MM, 12))  # irregular axes: the binary-search bins
    y = np.sort(rng.uniform(0.0, 9 * MM, 10))
    heights = height_map((vertices, triangles), x, y)
    for j in range(len(y)):
        for i in range(len(x)):
            exact = exact_height(vertices, triangles, x[i], y[j])
            assert abs(Fraction(heights[j, i]) - exact) < HEIGHT_M


def test_part_and_mesh_tuple_give_the_same_map():
    part, _ = pyramids(2, 1 * MM, 0.6 * MM)
    x = np.linspace(0.0, 2 * MM, 37)
    np.testing.assert_array_equal(height_map(part, x, x), height_map(part.mesh(), x, x))


def test_diagonal_profile_matches_the_closed_form():
    part, heights_of = pyramids(4, 1 * MM, 0.6 * MM)
    start, end = np.array([0.0, 0.5 * MM]), np.array([4 * MM, 3.5 * MM])
    s, z = profile(part, start, end, 1e-6)
    assert s.size == 5001 and s[-1] == pytest.approx(5 * MM)  # 3-4-5 line: end is sampled
    u = (end - start) / 5e-3
    np.testing.assert_allclose(z, heights_of(start[0] + s * u[0], start[1] + s * u[1]), rtol=0,
                               atol=HEIGHT_M)


def test_large_boxes_read_the_same_heights_bit_for_bit_as_the_batched_pass(monkeypatch):
    """A box over many samples (a triangle's, or one row's span of a thin one) is evaluated
    on its own block of samples (`surface.BOX_RUN`, in blocks of `surface.BOX_BLOCK`); with
    that off every box goes through the batched pass. Both read the same heights bit for
    bit: profiles along a slanted line and along x, maps over large facets and over long
    thin triangles across the grid (the row spans)."""
    from machinesim.metrology import surface

    rng = np.random.default_rng(7)
    large = heightfield(rng.uniform(0.0, 0.3 * MM, size=(6, 6)), 1 * MM)
    thin_v, thin_t = heightfield(rng.uniform(0.0, 20e-6, size=(3, 41)), (5e-6, 1 * MM))
    thin_v = thin_v.copy()
    thin_v[:, 0] += thin_v[:, 1]
    # both solids in one surface, the thin one beside the large: thin row spans and large
    # whole boxes in one pass
    both = (np.vstack([large[0] + [3 * MM, 0.0, 0.0], thin_v]),
            np.vstack([large[1], thin_t + len(large[0])]))
    lines = [((0.1 * MM, 0.2 * MM), (4.9 * MM, 3.7 * MM)), ((0.0, 2.5 * MM), (5 * MM, 2.5 * MM))]
    grid = np.linspace(-0.1 * MM, 5.1 * MM, 900)

    def read():
        return ([profile(large, a, b, 0.37e-6)[1] for a, b in lines]
                + [height_map(large, grid, grid[:300]), height_map(both, 1.6 * grid, grid)])

    default = read()
    assert min(np.isfinite(z).sum() for z in default) > 10000
    monkeypatch.setattr(surface, "BOX_BLOCK", 1000)  # a box split into many blocks
    for z, again in zip(default, read(), strict=True):
        np.testing.assert_array_equal(again, z)
    monkeypatch.setattr(surface, "BOX_RUN", 10**12)
    for z, batched in zip(default, read(), strict=True):
        np.testing.assert_array_equal(batched, z)


def test_profile_along_a_grid_row_is_that_row_of_the_map():
    part, _ = pyramids(3, 1 * MM, 0.6 * MM)
    spacing = 10e-6
    x = np.arange(301) * spacing
    row = height_map(part, x, [1.23 * MM])[0]
    for start, end, flip in (((0.0, 1.23 * MM), (3 * MM, 1.23 * MM), False),
                             ((3 * MM, 1.23 * MM), (0.0, 1.23 * MM), True)):
        s, z = profile(part, start, end, spacing)
        np.testing.assert_array_equal(s, x)
        np.testing.assert_allclose(z, row[::-1] if flip else row, rtol=0, atol=HEIGHT_M)


def test_a_profile_half_off_the_part_reads_its_on_part_samples_and_marks_the_rest():
    # a 2 x 2 x 1 mm block (x, y 0 .. 2 mm, top z = 1 mm); samples at x = -1.05 + 0.1 k mm,
    # k = 0 .. 20: k >= 11 (x = 0.05 .. 0.95 mm) over it, k <= 10 off it (x < 0)
    part = Part(box([2 * MM, 2 * MM, 1 * MM]))
    s, z = profile(part, (-1.05 * MM, 1 * MM), (0.95 * MM, 1 * MM), 0.1 * MM)
    assert s.size == 21
    np.testing.assert_allclose(z[11:], 1 * MM, rtol=0, atol=HEIGHT_M)
    assert np.isnan(z[:11]).all()  # missing: read nothing, as a profilometer off the part
    x = np.arange(-1.05, 1.0, 0.1) * MM + 0.01 * MM  # a map half off likewise, in x
    heights = height_map(part, x, [0.5 * MM, 1.5 * MM])
    assert heights.shape == (2, 21) and np.isnan(heights[:, x < 0]).all()
    np.testing.assert_allclose(heights[:, x > 0], 1 * MM, rtol=0, atol=HEIGHT_M)


def test_a_profile_or_map_wholly_off_the_part_is_refused_naming_it_and_the_part():
    # before: 41 samples, every one NaN, and the fits failed later naming none of it
    part = Part(box([2 * MM, 2 * MM, 1 * MM]))
    with pytest.raises(InputError) as refused:
        profile(part, (-1 * MM, -1 * MM), (-1 * MM, 3 * MM), 0.1 * MM)
    assert str(refused.value) == (
        "key 'start': the profile from (-0.001, -0.001) to (-0.001, 0.003) m reads no "
        "surface: all 41 of its samples lie off the part (no surface below them); the part "
        "spans x 0 .. 0.002 m, y 0 .. 0.002 m. Expected a trace over the part, in m (SI: 5 "
        "mm is 0.005)")
    with pytest.raises(InputError, match=r"the height map over x 0.003 .. 0.004 m, y 0 .. "
                                         r"0.001 m reads no surface: all 4 of its samples"):
        height_map(part, [3 * MM, 4 * MM], [0.0, 1 * MM])
    # inside the part's extent but over a gap between two blocks: nothing below either
    two = Part(box([1 * MM, 2 * MM, 1 * MM]) + box([1 * MM, 2 * MM, 1 * MM], (2 * MM, 0, 0)))
    with pytest.raises(InputError, match=r"the part spans x 0 .. 0.003 m, y 0 .. 0.002 m"):
        profile(two, (1.5 * MM, 0.0), (1.5 * MM, 2 * MM), 0.1 * MM)


@pytest.mark.parametrize(
    ("x", "match"),
    [([1.0, 0.0], "strictly increasing"), ([[0.0, 1.0]], "shape"), ([], "shape"),
     ([0.0, np.nan], "finite")],
)
def test_bad_sample_axes_are_refused(x, match):
    with pytest.raises(InputError, match=match):
        height_map(Part(box([1.0, 1.0, 1.0])), x, [0.5])


def test_bad_meshes_and_profiles_are_refused():
    vertices = np.zeros((3, 3))
    with pytest.raises(InputError, match="float64"):
        height_map((vertices.astype(np.float32), [[0, 1, 2]]), [0.0], [0.0])
    with pytest.raises(InputError, match="indices"):
        height_map((vertices, [[0, 1, 3]]), [0.0], [0.0])
    with pytest.raises(InputError, match="Part"):
        height_map("part.stl", [0.0], [0.0])
    part = Part(box([1.0, 1.0, 1.0]))
    with pytest.raises(InputError, match="non-zero length"):
        profile(part, (0.5, 0.5), (0.5, 0.5), 0.1)
    with pytest.raises(InputError, match="spacing"):
        profile(part, (0.0, 0.5), (1.0, 0.5), 0.0)
    with pytest.raises(InputError, match="start"):
        profile(part, (0.0, 0.5, 0.0), (1.0, 0.5), 0.1)
