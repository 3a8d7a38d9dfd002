"""Material removal against analytic grooves, pyramids and capsules; reports; determinism."""

import math
import re

import manifold3d
import numpy as np
import pytest

from machinesim.cutting import remove, rotary_substeps
from machinesim.cutting.stitch import exact_box, stitch
from machinesim.exceptions import InputError
from machinesim.metrology import Microscope
from machinesim.tools import BallEndMill, VTool
from machinesim.workpiece import block

#: Geometry read off the exact float64 mesh: vertices at mm scale carry ~1e-19 m round-off
#: per operation, so 0.01 nm (1e-11 m) leaves eight orders of margin and still catches any
#: real geometric error.
LENGTH_TOL = 1e-11
#: Volumes of exact meshes agree to float64 summation round-off (~1e-15 relative).
VOLUME_REL = 1e-12

#: Both engines, with the method each reports: the height-field mesher takes straight
#: grooves across a block when allowed, the boolean engine always can.
METHODS = pytest.mark.parametrize(("method", "used"), [("auto", "relief"),
                                                        ("boolean", "boolean")])

ALONG_Y = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])


def pose(position, rotation=None):
    matrix = np.eye(4)
    matrix[:3, :3] = np.eye(3) if rotation is None else rotation
    matrix[:3, 3] = position
    return matrix


def groove_x(y, depth, x0=-1e-3, x1=5e-3, dz=0.0):
    return np.array([pose((x0, y, -depth + dz)), pose((x1, y, -depth + dz))])


def groove_y(x, depth, y0=-1e-3, y1=5e-3):
    return np.array([pose((x, y0, -depth), ALONG_Y), pose((x, y1, -depth), ALONG_Y)])


def v_section(part, x):
    """Vertices of the part on the plane x (its end face), as (y, z) rows."""
    vertices, _ = part.mesh()
    return vertices[np.abs(vertices[:, 0] - x) < LENGTH_TOL][:, 1:]


@METHODS
@pytest.mark.parametrize("angle_deg", [90.0, 60.0])
def test_v_groove_section_is_the_analytic_v(angle_deg, method, used):
    depth, y0, length = 7e-6, 1.234567e-3, 4e-3
    angle = math.radians(angle_deg)
    stock = block(length, 3e-3, 1e-3)
    part, report = remove(stock, VTool(angle), [groove_x(y0, depth)], method=method)
    assert report.method == used
    half = depth * math.tan(angle / 2)
    for x in (0.0, length):
        section = v_section(part, x)
        notch = section[section[:, 1] > -0.5e-3]
        bottom = notch[np.argmin(notch[:, 1])]
        assert bottom == pytest.approx([y0, -depth], abs=LENGTH_TOL)
        top = notch[(notch[:, 1] == 0.0) & (np.abs(notch[:, 0] - y0) < 2 * half)]
        assert np.sort(top[:, 0]) == pytest.approx([y0 - half, y0 + half], abs=LENGTH_TOL)
    area = depth * half  # the V: depth d, width 2 d tan(included / 2)
    assert report.removed_volume == pytest.approx(area * length, rel=VOLUME_REL, abs=0.0)
    assert report.n_sweeps == report.n_sweeps_cut == 1
    assert not report.empty_cut and report.sideways == ()


@METHODS
def test_shifted_poses_shift_the_groove_exactly(method, used):
    rng = np.random.default_rng(0)
    stock = block(4e-3, 3e-3, 1e-3)
    tool = VTool(math.pi / 2)
    base, report = remove(stock, tool, [groove_x(1.5e-3, 8e-6)], method=method)
    assert report.method == used
    dy, dz = rng.uniform(-0.5e-3, 0.5e-3), rng.uniform(-3e-6, 3e-6)
    shifted, _ = remove(stock, tool, [groove_x(1.5e-3 + dy, 8e-6, dz=dz)], method=method)
    a = v_section(base, 0.0)
    b = v_section(shifted, 0.0)
    a = a[a[:, 1] > -0.5e-3]
    b = b[b[:, 1] > -0.5e-3]
    bottom_a, bottom_b = a[np.argmin(a[:, 1])], b[np.argmin(b[:, 1])]
    assert bottom_b - bottom_a == pytest.approx([dy, dz], abs=LENGTH_TOL)


@METHODS
def test_crossing_grooves_leave_pyramids_of_the_analytic_height(method, used):
    # Pitch p, 90-deg tool, depth D >= p/2: neighbouring flanks (45 deg) meet halfway between
    # grooves, p/2 above the groove bottom, so the apexes sit at z = p/2 - D and the
    # pyramids (base p x p, height p/2, volume p^3 / 6) stand on the plane z = -D.
    pitch, n, depth, height = 40e-6, 8, 26e-6, 0.2e-3
    side = n * pitch
    stock = block(side, side, height)
    centres = pitch / 2 + pitch * np.arange(n)
    ends = dict(x0=-0.1e-3, x1=side + 0.1e-3)
    paths = [groove_x(c, depth, **ends) for c in centres]
    paths += [groove_y(c, depth, y0=ends["x0"], y1=ends["x1"]) for c in centres]
    part, report = remove(stock, VTool(math.pi / 2), paths, method=method)
    assert report.method == used
    apex = pitch / 2 - depth
    assert part.bounds[1, 2] == pytest.approx(apex, abs=LENGTH_TOL)
    vertices, _ = part.mesh()
    tops = vertices[np.abs(vertices[:, 2] - apex) < LENGTH_TOL]
    grid = pitch * np.arange(1, n)
    interior = tops[(tops[:, 0] > pitch / 2) & (tops[:, 0] < side - pitch / 2)
                    & (tops[:, 1] > pitch / 2) & (tops[:, 1] < side - pitch / 2)]
    assert len(interior) == (n - 1) ** 2
    assert np.sort(np.unique(np.round(interior[:, 0] / pitch))) == pytest.approx(grid / pitch)
    expected = side * side * (height - depth) + n * n * pitch**3 / 6
    assert part.volume == pytest.approx(expected, rel=VOLUME_REL, abs=0.0)
    assert report.n_sweeps_cut == 2 * n


def test_tiling_does_not_change_the_solid():
    pitch, n, depth = 40e-6, 16, 25e-6
    side = n * pitch
    stock = block(side, side, 0.1e-3)
    centres = pitch / 2 + pitch * np.arange(n)
    paths = [groove_x(c, depth, x0=-0.1e-3, x1=side + 0.1e-3) for c in centres]
    paths += [groove_y(c, depth, y0=-0.1e-3, y1=side + 0.1e-3) for c in centres]
    whole, _ = remove(stock, VTool(math.pi / 2), paths, sweeps_per_tile=10**9,
                      method="boolean")
    tiled, report = remove(stock, VTool(math.pi / 2), paths, sweeps_per_tile=4,
                           method="boolean")
    assert report.n_cells > 1
    assert tiled.volume == pytest.approx(whole.volume, rel=VOLUME_REL, abs=0.0)
    assert np.array_equal(tiled.bounds, whole.bounds)


def test_ball_sweep_removes_the_swept_ball_and_shank_within_the_tessellation_bound():
    # The ball end mill is a hemisphere under a cylindrical shank of its radius. Its polygon
    # has its vertices on the true surface and facets at most tol inside, so it lies between
    # the tools of radius R - tol and R, and so do their sweeps. Swept along X by l with the
    # tip D below the top, the true tool removes, slice by slice in z: the stadium of the
    # shank (pi r^2 + 2 r l) over D - r, and over the hemisphere pi rho^2 + 2 rho l, whose
    # integrals are 2/3 pi r^3 and l pi r^2 / 2.
    radius, tol, travel, depth = 1e-3, 2e-6, 3e-3, 5e-3
    tool = BallEndMill(radius, chord_tol=tol)
    stock = block(10e-3, 10e-3, 10e-3)
    path = np.array([pose((3e-3, 5e-3, -depth)), pose((3e-3 + travel, 5e-3, -depth))])
    _, report = remove(stock, tool, [path])

    def swept(r):
        return (2.0 / 3.0 * math.pi * r**3 + travel * math.pi * r * r / 2.0
                + (depth - r) * (math.pi * r * r + 2.0 * r * travel))

    assert swept(radius - tol) * (1 - 1e-12) <= report.removed_volume
    assert report.removed_volume <= swept(radius) * (1 + 1e-12)
    assert report.sideways == ()  # a rotating tool is never dragged sideways
    assert report.holder_contact == ()  # the 10 mm body stands out of the stock


def test_reports_flag_empty_sideways_and_degenerate_sweeps():
    stock = block(4e-3, 3e-3, 1e-3)
    tool = VTool(math.pi / 2)
    _, above = remove(stock, tool, [groove_x(1.5e-3, -5e-6)])
    assert above.empty_cut and above.removed_volume == 0.0 and above.n_sweeps_cut == 0
    drag = np.array([pose((1e-3, 1e-3, -5e-6)), pose((2e-3, 1.01e-3, -5e-6))])
    plunge = np.array([pose((1e-3, 1e-3, 1e-6)), pose((1e-3, 1e-3, -5e-6))])
    _, report = remove(stock, tool, [groove_x(0.5e-3, 5e-6), drag, plunge])
    assert report.sideways == (1,)
    assert report.n_degenerate == 1  # the plunge moves the profile within its own plane
    assert report.n_sweeps == 3 and not report.empty_cut


@pytest.mark.parametrize("gap", [2.6e-13, 9e-13])
def test_a_sheet_thinner_than_a_picometre_between_two_grooves_is_cut_away(gap):
    # Two grooves along one line, the second run back towards the first and ending `gap`
    # short of its end: the stock between their end faces is a V-shaped sheet `gap` thick,
    # standing from the groove bottom to the plate top, which a height map reads as a wall.
    depth, y0, x0 = 10e-6, 1.5e-3, 2e-3
    back = np.diag([-1.0, -1.0, 1.0])  # the tool turned to cut along -X
    first = np.array([pose((-1e-3, y0, -depth)), pose((x0, y0, -depth))])
    second = np.array([pose((5e-3, y0, -depth), back), pose((x0 + gap, y0, -depth), back)])
    part, report = remove(block(4e-3, 3e-3, 1e-3), VTool(math.pi / 2), [first, second],
                          method="boolean")
    assert report.sheets.count >= 1
    assert report.sheets.thickness_max == pytest.approx(gap, abs=1e-15)
    # a profile along the groove through x0 at 0.01 pm spacing sees the bottom all the way
    along = Microscope(noise=False).profile(part, (x0 - 1e-12, y0), (x0 + 2e-12, y0),
                                            spacing=1e-14)
    assert len(along.z) > 250 and np.nanmax(along.z) <= -depth + 2e-12
    # all else is the two grooves: the removed volume is the V's area along 5 mm (the
    # groove over the block's 4 mm), to the sheet's volume and the slab's pm notch
    assert part.volume == pytest.approx(4e-3 * 3e-3 * 1e-3 - depth ** 2 * 4e-3, rel=1e-12)
    # a gap of 3 pm is kept: that is stock, thin as it is, and the engine leaves it
    thicker = second.copy()
    thicker[-1, 0, 3] = x0 + 3e-12
    _, kept = remove(block(4e-3, 3e-3, 1e-3), VTool(math.pi / 2), [first, thicker],
                     method="boolean")
    assert kept.sheets.count == 0


@METHODS
def test_roi_cuts_only_the_windows(method, used):
    depth = 6e-6
    stock = block(4e-3, 4e-3, 1e-3)
    paths = [groove_x(y, depth) for y in (0.5e-3, 1.5e-3, 2.5e-3, 3.5e-3)]
    windows = [(1e-3, 2e-3, 1e-3, 2e-3), (3e-3, 3.5e-3, 3e-3, 4e-3)]
    part, report = remove(stock, VTool(math.pi / 2), paths, roi=windows, method=method)
    assert report.method == used
    assert report.n_sweeps_cut == 2
    window_volume = (1e-3 * 1e-3 + 0.5e-3 * 1e-3) * 1e-3
    removed = depth * depth * (1e-3 + 0.5e-3)
    assert part.volume == pytest.approx(window_volume - removed, rel=VOLUME_REL)
    assert report.removed_volume == pytest.approx(removed, rel=1e-9, abs=0.0)
    np.testing.assert_allclose(part.bounds, [[1e-3, 1e-3, -1e-3], [3.5e-3, 4e-3, 0.0]],
                               atol=LENGTH_TOL)


def test_rotary_sub_steps_keep_the_chord_error():
    radius, angle, tol = 0.1, math.radians(20.0), 1e-9
    n = rotary_substeps(radius, angle, tol)
    assert radius * (1 - math.cos(angle / n / 2)) <= tol
    assert radius * (1 - math.cos(angle / (n - 1) / 2)) > tol


def test_rotating_sweep_cuts_the_arc_groove():
    # A fly-cut: the tool on an arm of radius r swings about the Y axis and dips d into the
    # top face, leaving an arc groove whose deepest point is at -d and whose length on the
    # top face is the chord 2 sqrt(2 r d - d^2).
    radius, depth = 5e-3, 10e-6
    stock = block(4e-3, 2e-3, 1e-3)
    axis = np.array([2e-3, 1e-3, radius - depth])
    angles = np.linspace(0.1, -0.1, rotary_substeps(radius, 0.2, 1e-9) + 1)
    poses = []
    for a in angles:
        rotation = np.array([[math.cos(a), 0, math.sin(a)], [0, 1, 0],
                             [-math.sin(a), 0, math.cos(a)]])
        poses.append(pose(axis + rotation @ [0.0, 0.0, -radius], rotation))
    part, report = remove(stock, VTool(math.pi / 2), [np.array(poses)])
    assert part.bounds[0, 2] == -1e-3
    vertices, _ = part.mesh()
    assert vertices[:, 2][vertices[:, 2] > -0.5e-3].min() == pytest.approx(-depth, abs=1e-9)
    on_top = vertices[(vertices[:, 2] == 0.0) & (np.abs(vertices[:, 1] - 1e-3) < 1e-12)]
    chord = 2 * math.sqrt(2 * radius * depth - depth**2)
    # The sub-step chords lie above the arc by at most 1 nm; where the path meets the top
    # face at slope s that shortens each end by at most 1 nm / s.
    slope = math.sqrt(2 * radius * depth - depth**2) / (radius - depth)
    assert 0.0 <= chord - np.ptp(on_top[:, 0]) <= 2 * 1e-9 / slope
    assert report.sideways == ()


@METHODS
def test_same_inputs_give_the_same_bytes(method, used):
    rng = np.random.default_rng(0)
    stock = block(1e-3, 1e-3, 0.2e-3)
    paths = [groove_x(y, 10e-6, x0=-0.1e-3, x1=1.1e-3) for y in rng.uniform(0, 1e-3, 12)]
    paths += [groove_y(x, 10e-6, y0=-0.1e-3, y1=1.1e-3) for x in rng.uniform(0, 1e-3, 12)]
    first, report = remove(stock, VTool(math.pi / 2), paths, sweeps_per_tile=8,
                           method=method)
    second, _ = remove(stock, VTool(math.pi / 2), paths, sweeps_per_tile=8, method=method)
    assert report.method == used
    (v1, t1), (v2, t2) = first.mesh(), second.mesh()
    assert v1.tobytes() == v2.tobytes() and t1.tobytes() == t2.tobytes()


@METHODS
def test_progress_reaches_its_total(method, used):
    calls = []
    stock = block(2e-3, 2e-3, 0.2e-3)
    paths = [groove_x(y, 5e-6) for y in (0.5e-3, 1.5e-3)]
    _, report = remove(stock, VTool(math.pi / 2), paths, method=method,
                       progress=lambda done, total: calls.append((done, total)))
    assert report.method == used
    assert calls[0][0] == 0 and calls[-1][0] == calls[-1][1] == 2
    assert all(a[0] <= b[0] for a, b in zip(calls, calls[1:], strict=False))


def test_progress_counts_each_sweep_once_across_tiles():
    """Crossing grooves in tiles of 8 sweeps: each groove reaches several tiles, and the
    progress counts it once, so its total is the report's sweeps (it had counted one per
    tile a sweep reached, more "sweeps" than the cut had)."""
    calls = []
    stock = block(1e-3, 1e-3, 0.2e-3)
    ys = np.linspace(0.05e-3, 0.95e-3, 12)
    paths = [groove_x(y, 10e-6, x0=-0.1e-3, x1=1.1e-3) for y in ys]
    paths += [groove_y(x, 10e-6, y0=-0.1e-3, y1=1.1e-3) for x in ys + 0.01e-3]
    _, report = remove(stock, VTool(math.pi / 2), paths, sweeps_per_tile=8, method="boolean",
                       progress=lambda done, total: calls.append((done, total)))
    assert report.n_sweeps_cut == 24 and report.n_cells == 16  # tiles
    assert calls[0] == (0, 24) and calls[-1] == (24, 24)
    assert all(a[0] <= b[0] and a[1] == b[1] for a, b in zip(calls, calls[1:], strict=False))


def test_progress_tells_a_stage_aware_caller_the_sweeps_being_built_first():
    """A ball end mill's sweeps take most of a raster's wait to build (3,819 sweeps: 22 s)
    before the first tile is cut, and nothing was told: a callable that takes ``stage`` is
    told the building, over every sweep of the paths, then the cut as before; one that
    takes (done, total) alone only the cut."""
    calls, plain = [], []
    stock = block(2e-3, 2e-3, 0.2e-3)
    tool = BallEndMill(0.2e-3, chord_tol=5e-6)
    ys = (0.5e-3, 1.0e-3, 1.5e-3)
    paths = [np.array([pose((x, y, -5e-6)) for x in np.linspace(-0.5e-3, 2.5e-3, 4)])
             for y in ys]
    _, report = remove(stock, tool, paths, method="boolean",
                       progress=lambda done, total, stage="cutting": calls.append(
                           (stage, done, total)))
    remove(stock, tool, paths, method="boolean",
           progress=lambda done, total: plain.append((done, total)))
    building = [call for call in calls if call[0] == "building"]
    cutting = [call for call in calls if call[0] == "cutting"]
    assert calls[:len(building)] == building  # all before the cut
    assert building[0] == ("building", 0, 9) and building[-1] == ("building", 9, 9)
    assert len(building) > 2  # told sweep by sweep, not just at both ends
    assert all(a[1] <= b[1] for a, b in zip(building, building[1:], strict=False))
    assert cutting[-1] == ("cutting", report.n_sweeps_cut, report.n_sweeps_cut)
    assert plain == [call[1:] for call in cutting]


def test_building_is_told_at_most_progress_steps_times(monkeypatch):
    """Told per sweep built, a cut of 10,000 level passes would redraw a terminal's bar
    10,000 times: the building is told about every `PROGRESS_STEPS`-th of the sweeps, and
    at both ends."""
    from machinesim.cutting import sweepset

    monkeypatch.setattr(sweepset, "PROGRESS_STEPS", 3)
    calls = []
    stock = block(2e-3, 2e-3, 0.2e-3)
    path = np.array([pose((x, 1e-3, -5e-6)) for x in np.linspace(-0.5e-3, 2.5e-3, 13)])
    remove(stock, BallEndMill(0.2e-3, chord_tol=5e-6), [path], method="boolean",
           progress=lambda done, total, stage="cutting": calls.append((stage, done)))
    building = [done for stage, done in calls if stage == "building"]
    assert building[0] == 0 and building[-1] == 12 and len(building) <= 3 + 2


@pytest.mark.parametrize(
    ("paths", "roi", "message"),
    [
        ([np.eye(4)], None, r"path 0: expected poses of shape \(N, 4, 4\)"),
        ([np.stack([np.eye(4), 2 * np.eye(4)])], None, "path 0: pose 1 is not a rigid"),
        ([np.stack([np.eye(4), np.full((4, 4), np.nan)])], None, "pose 1 is not a rigid"),
        ([np.stack([np.eye(4), np.diag([1.0, 1.0, -1.0, 1.0])])], None,
         "pose 1 is not a rigid"),  # a mirror: orthonormal, determinant -1
        ([np.stack([np.eye(4)] * 2)], [(0, 1, 0)], r"roi: expected windows"),
        ([np.stack([np.eye(4)] * 2)], [(1, 0, 0, 1)], "xmin < xmax"),
    ],
)
def test_bad_inputs_raise_input_error(paths, roi, message):
    with pytest.raises(InputError, match=message):
        remove(block(1e-3, 1e-3, 1e-3), VTool(math.pi / 2), paths, roi=roi)


@pytest.mark.parametrize(("tool", "got"), [("v:90", "str 'v:90'"), (None, "NoneType None")])
def test_a_tool_that_is_no_tool_object_is_refused_by_name(tool, got):
    # remove read tool.rotational first: AttributeError 'str' object has no attribute
    # 'rotational' (cut() takes the spec; remove, the engine, a tool object)
    with pytest.raises(InputError) as caught:
        remove(block(1e-3, 1e-3, 1e-3), tool, [np.stack([np.eye(4)] * 2)])
    assert str(caught.value) == (
        "key 'tool': Expected tool as a tool object (machinesim.tools: VTool, RoundNoseTool, "
        f"BallEndMill, FlatEndMill), got {got}; a spec such as 'v:90' is made one by "
        "machinesim.tool_specs.tool_from_spec")


def test_overlapping_windows_count_their_common_part_once():
    depth = 6e-6
    stock = block(4e-3, 4e-3, 1e-3)
    windows = [(1e-3, 2e-3, 1e-3, 2e-3), (1.5e-3, 2.5e-3, 1e-3, 2e-3)]
    part, report = remove(stock, VTool(math.pi / 2), [groove_x(1.5e-3, depth)], roi=windows)
    removed = depth * depth * 1.5e-3
    assert part.volume == pytest.approx(1.5e-3 * 1e-3 * 1e-3 - removed, rel=VOLUME_REL)
    assert report.removed_volume == pytest.approx(removed, rel=1e-9, abs=0.0)


def _tile_pieces(walls_x, walls_y, hull):
    boxes, pieces = [], []
    for x0, x1 in zip(walls_x[:-1], walls_x[1:], strict=True):
        for y0, y1 in zip(walls_y[:-1], walls_y[1:], strict=True):
            boxes.append((x0, x1, y0, y1))
            pieces.append(exact_box(x0, x1, y0, y1, -1e-3, 0.0) - hull)
    return boxes, pieces


def test_stitched_tiles_are_the_union_of_the_tiles():
    # A groove running diagonally across four tiles: its flanks cross every wall.
    tool = VTool(math.pi / 2).vertices()
    rotation = np.array([[math.cos(0.3), -math.sin(0.3), 0], [math.sin(0.3), math.cos(0.3), 0],
                         [0, 0, 1.0]])
    ends = [tool @ rotation.T + p for p in ([-0.2e-3, 0.1e-3, -20e-6], [1.2e-3, 0.6e-3, -20e-6])]
    hull = manifold3d.Manifold.hull_points(np.vstack(ends))
    walls = [0.0, 0.4123e-3, 1e-3]
    boxes, pieces = _tile_pieces(walls, walls, hull)
    joined = stitch(pieces, boxes, (0.0, 1e-3, 0.0, 1e-3), 1e-3)
    union = manifold3d.Manifold.batch_boolean(pieces, manifold3d.OpType.Add)
    assert joined is not None
    assert joined.volume() == pytest.approx(union.volume(), rel=VOLUME_REL)
    assert joined.num_tri() <= union.num_tri() + 8  # no wall faces left inside
    v_joined = np.unique(np.asarray(joined.to_mesh64().vert_properties), axis=0)
    v_union = np.unique(np.asarray(union.to_mesh64().vert_properties), axis=0)
    assert len(v_joined) == len(v_union)
    np.testing.assert_allclose(v_joined, v_union, atol=1e-18)


def test_stitch_refuses_tiles_whose_walls_do_not_match():
    hull = manifold3d.Manifold.hull_points(np.vstack(
        [VTool(math.pi / 2).vertices() + p for p in ([-1e-4, 0.5e-3, -2e-5],
                                                       [1.1e-3, 0.5e-3, -2e-5])]))
    boxes, pieces = _tile_pieces([0.0, 0.5e-3, 1e-3], [0.0, 1e-3], hull)
    # The right tile's groove 1 nm off: its wall section no longer matches the left one's.
    pieces[1] = exact_box(*boxes[1], -1e-3, 0.0) - hull.translate((0.0, 1e-9, 0.0))
    assert stitch(pieces, boxes, (0.0, 1e-3, 0.0, 1e-3), 1e-3) is None


def test_stitch_keeps_the_wall_of_an_empty_neighbour():
    hull = manifold3d.Manifold.hull_points(np.vstack(
        [VTool(math.pi / 2).vertices() + p for p in ([-1e-4, 0.5e-3, -2e-5],
                                                       [1.1e-3, 0.5e-3, -2e-5])]))
    boxes, pieces = _tile_pieces([0.0, 0.5e-3, 1e-3], [0.0, 1e-3], hull)
    pieces[1] = manifold3d.Manifold()  # all material of the right tile is gone
    joined = stitch(pieces, boxes, (0.0, 1e-3, 0.0, 1e-3), 1e-3)
    assert joined is not None
    assert joined.volume() == pytest.approx(pieces[0].volume(), rel=VOLUME_REL)


def test_union_runs_cap_the_overlapping_pairs_and_keep_side_by_side_sweeps_together():
    from machinesim.cutting.tiling import PAIRS_PER_UNION, union_runs

    # Boxes that all overlap: a run of n holds n (n - 1) / 2 pairs, so runs of 8 (28 pairs).
    count = 100
    lower = np.zeros((count, 3)) + 1e-9 * np.arange(count)[:, None]
    upper = lower + 1e-6
    runs = union_runs(np.arange(count), lower, upper)
    longest = max(n for n in range(2, count) if n * (n - 1) // 2 <= PAIRS_PER_UNION)
    assert [len(r) for r in runs] == [longest] * (count // longest) + [count % longest]
    np.testing.assert_array_equal(np.concatenate(runs), np.arange(count))
    # Grooves at their own width's pitch only touch: one union, as before the runs.
    pitch = 20e-6
    lower = np.stack([np.zeros(count), pitch * np.arange(count), np.zeros(count)], axis=1)
    upper = lower + [1e-3, pitch, 10e-6]
    assert [len(r) for r in union_runs(np.arange(count), lower, upper)] == [count]
    assert union_runs(np.arange(0), lower, upper) == []


def test_passes_stacked_down_a_slope_cut_the_analytic_staircase(monkeypatch):
    from machinesim.cutting import engine
    from machinesim.cutting.tiling import union_runs
    from machinesim.metrology.surface import height_map

    runs = []

    def recorded(*args):
        found = union_runs(*args)
        runs.extend(found)
        return found

    monkeypatch.setattr(engine, "union_runs", recorded)
    # Finishing passes down an inclined face: each 90-deg V pass is 0.2 um from the last
    # sideways and 0.1 um deeper, so its tool body overlaps the passes above it and the
    # engine cuts them in runs (`union_runs`). The top is the lowest of the V's:
    # z(y) = min_k (|y - y_k| - d_k), exact at every sample.
    count, step, drop, top_depth = 120, 0.2e-6, 0.1e-6, 1e-6
    stock = block(2e-3, 1e-3, 0.5e-3)
    ys = 0.45e-3 + step * np.arange(count)
    depths = top_depth + drop * np.arange(count)
    paths = [groove_x(y, d, x0=-0.5e-3, x1=2.5e-3) for y, d in zip(ys, depths, strict=True)]
    part, report = remove(stock, VTool(math.radians(90.0)), paths, method="boolean")
    assert report.method == "boolean" and report.n_sweeps_cut == count
    assert len(runs) > 10
    np.testing.assert_array_equal(np.concatenate(runs), np.arange(count))
    y = np.linspace(0.44e-3, 0.48e-3, 801)
    heights = height_map(part, np.array([0.3e-3, 1.7e-3]), y)
    expected = np.minimum(np.min(np.abs(y[:, None] - ys) - depths, axis=1), 0.0)
    np.testing.assert_allclose(heights, np.repeat(expected[:, None], 2, axis=1), rtol=0,
                               atol=LENGTH_TOL)


def _helix_levels(radius, depths, steps=48, rise=0.0):
    """A flat end mill's circle of chords at each depth, one path per level (m); with
    ``rise``, each a helix's turn going that much down (a level chord is a footprint
    prism, united in the plane, `machinesim.cutting.footprints`)."""
    angle = np.linspace(0.0, 2.0 * math.pi, steps + 1)
    return [np.array([pose((2e-3 + radius * math.cos(a), 2e-3 + radius * math.sin(a),
                            -depth - rise * a / (2.0 * math.pi))) for a in angle])
            for depth in depths]


def _recorded_containment(monkeypatch) -> list:
    """The list each call of `engine.contained_sweeps` appends its answer to."""
    import machinesim.cutting.engine as engine

    found, original = [], engine.contained_sweeps

    def record(*args):
        found.append(original(*args))
        return found[-1]

    monkeypatch.setattr(engine, "contained_sweeps", record)
    return found


def test_passes_repeated_deeper_are_dropped_and_the_part_is_the_same(monkeypatch):
    """A pass repeated over the same path deeper holds the shallower one: those sweeps are
    dropped (`contained_sweeps`) and the part is the one cut with all of them. (The turns
    of a helix, 50 um down a turn: level passes would be united in the plane instead, and
    are not tested.)"""
    import machinesim.cutting.engine as engine
    from machinesim.tools import FlatEndMill

    tool = FlatEndMill(0.5e-3, chord_tol=1e-6, height=5e-3)
    paths = _helix_levels(0.6e-3, [0.2e-3, 0.4e-3, 0.6e-3], rise=50e-6)
    stock = block(4e-3, 4e-3, 1e-3)
    found = _recorded_containment(monkeypatch)
    part, report = remove(stock, tool, paths, method="boolean")
    assert int(found[0].sum()) == 2 * 48  # the two upper levels, all inside the lowest
    monkeypatch.setattr(engine, "contained_sweeps",
                        lambda hulls, *rest: np.zeros(len(hulls), dtype=bool))
    every, every_report = remove(stock, tool, paths, method="boolean")
    assert report.n_sweeps_cut == every_report.n_sweeps_cut == 3 * 48
    assert report.removed_volume == pytest.approx(every_report.removed_volume, rel=VOLUME_REL)
    apart = (part.manifold - every.manifold).volume() + (every.manifold - part.manifold).volume()
    assert apart <= VOLUME_REL * report.removed_volume


def test_a_sweep_poking_out_of_another_is_kept(monkeypatch):
    """Containment is read off the vertices: a pass 1 nm outside the deeper one is cut."""
    from machinesim.tools import FlatEndMill

    tool = FlatEndMill(0.5e-3, chord_tol=1e-6, height=5e-3)
    deep = groove_x(2e-3, 0.4e-3)
    shallow = groove_x(2e-3 + 1e-9, 0.2e-3)
    stock = block(4e-3, 4e-3, 1e-3)
    found = _recorded_containment(monkeypatch)
    remove(stock, tool, [deep, shallow], method="boolean")
    assert not found[0].any()
    # at the same place the shallow pass lies inside the deep one: dropped
    remove(stock, tool, [deep, groove_x(2e-3, 0.2e-3)], method="boolean")
    assert found[1].tolist() == [False, True]


def test_a_move_a_km_long_cuts_its_hand_volume_and_a_pose_farther_out_is_refused():
    """A V from the middle of a 10 mm block to 40 m away cuts the groove of 5 mm by hand
    (d^2 tan 45 deg per length), to 1 km within 1e-5 (1.7e-6 measured); remove refuses a
    pose beyond FARTHEST_M (1 km), as cut refuses a move: from -1e9 to 1e9 m a flat end
    mill's slot through the block removed nothing (an empty cut), from -1e7 to 1e7 m 1.5 %
    less, with no word."""
    from machinesim.end_mills import FlatEndMill

    def poses(*points):
        out = np.tile(np.eye(4), (len(points), 1, 1))
        out[:, :3, 3] = points
        return out

    stock, depth = block(10e-3, 10e-3, 2e-3), 0.1e-3
    hand = 5e-3 * depth ** 2
    for end, rel in ((39.99, 1e-14), (-39.99, 1e-14), (999.99, 1e-5), (-999.99, 1e-14)):
        _, report = remove(stock, VTool(math.pi / 2),
                           [poses((5e-3, 5e-3, -depth), (end, 5e-3, -depth))])
        assert report.removed_volume == pytest.approx(hand, rel=rel, abs=0), end
    for far in (1e9, 1e7, 1000.01):
        with pytest.raises(InputError, match=rf"path 0: pose 0 lies {re.escape(f'{far:g}')} "
                                             r"m from the workpiece's origin .* expected "
                                             r"within 1000 m"):
            remove(stock, FlatEndMill(0.5e-3),
                   [poses((-far, 5e-3, -depth), (far, 5e-3, -depth))])


@pytest.mark.parametrize(
    ("stock", "paths", "key", "words"),
    [
        (None, [], "stock", "Expected stock as a machinesim.workpiece.Part, got NoneType None"),
        ("block:10x10x2", [], "stock", "got str 'block:10x10x2'; a spec such as"),
        ("part", "abc", "paths", "Expected paths as a sequence of pose arrays (N, 4, 4), "
                                 "got str 'abc'"),
        ("part", None, "paths", "got NoneType None"),
        ("part", ["abc"], "paths", "path 0: expected poses of shape (N, 4, 4) as numbers, "
                                   "got str 'abc'"),
        ("part", [[[1.0, 2.0], [3.0]]], "paths", "path 0: expected poses of shape (N, 4, 4) "
                                                 "as numbers, got list"),
    ],
)
def test_remove_refuses_a_stock_or_paths_of_the_wrong_kind_naming_them(stock, paths, key,
                                                                        words):
    """remove(None, ...) ended in "AttributeError: 'NoneType' object has no attribute
    'bounds'", paths 'abc' or a path of text in "ValueError: could not convert string to
    float", a ragged path in numpy's "inhomogeneous shape"."""
    stock = block(1e-3, 1e-3, 1e-3) if stock == "part" else stock
    with pytest.raises(InputError, match=re.escape(words)) as raised:
        remove(stock, VTool(math.pi / 2), paths)
    assert raised.value.key == key
    # an iterator of paths is still taken
    _, report = remove(block(1e-3, 1e-3, 1e-3), VTool(math.pi / 2), iter([np.eye(4)[None]]))
    assert report.removed_volume == 0.0


def test_a_ball_line_in_short_moves_is_cut_as_one_move(monkeypatch):
    # A level ball groove from x = 0.5 to 3.5 mm in 60 moves of 50 um, exactly in line:
    # joined into one sweep (`machinesim.cutting.collinear`), the part is the one-move
    # cut's, volume and removed volume to 1e-12; a turn of 1e-6 rad at one point keeps the
    # two lines apart, and their part stays the one of two moves (to 1e-12).
    from machinesim.cutting import collinear, engine

    chains = []

    def recorded(*args):
        head, solids = collinear.joined_ball_sweeps(*args)
        chains.append(None if head is None else len(np.unique(head)))
        return head, solids

    stock, tool = block(4e-3, 4e-3, 1e-3), BallEndMill(0.25e-3)
    xs = 0.5e-3 + 50e-6 * np.arange(61)
    short = np.array([pose((x, 2e-3, -40e-6)) for x in xs])
    one, report_one = remove(stock, tool, [short[[0, -1]]], method="boolean")
    monkeypatch.setattr(engine, "joined_ball_sweeps", recorded)
    many, report_many = remove(stock, tool, [short], method="boolean")
    bent = short.copy()
    bent[30:, 1, 3] += (bent[30:, 0, 3] - bent[30, 0, 3]) * 1e-6
    turned, _ = remove(stock, tool, [bent], method="boolean")
    assert report_many.n_sweeps_cut == 60
    # the first line is one chain; the bent line's moves, rounded, join where in line
    assert chains[0] == 1 and 2 <= chains[1] <= 31
    assert many.manifold.volume() == pytest.approx(one.manifold.volume(), rel=VOLUME_REL)
    assert report_many.removed_volume == pytest.approx(report_one.removed_volume,
                                                       rel=VOLUME_REL, abs=0.0)
    two, _ = remove(stock, tool, [bent[[0, 30, -1]]], method="boolean")
    assert turned.manifold.volume() == pytest.approx(two.manifold.volume(), rel=VOLUME_REL)
