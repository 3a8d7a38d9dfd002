"""Material removal against analytic grooves, pyramids, capsules and arcs; windows; sheets;
determinism. (What remove reports and refuses: test_cutting_engine_reports.py; how the
boolean engine joins sweeps and stitches tiles: test_cutting_engine_joins.py.)"""

import math
import re

import numpy as np
import pytest
from cutting_engine_helpers import LENGTH_TOL, METHODS, VOLUME_REL, groove_x, groove_y, pose

from machinesim.cutting import remove, rotary_substeps
from machinesim.exceptions import InputError
from machinesim.metrology import Microscope
from machinesim.tools import BallEndMill, VTool
from machinesim.workpiece import block


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


def test_overlapping_windows_count_their_common_part_once():
    depth = 6e-6
    stock = block(4e-3, 4e-3, 1e-3)
    windows = [(1e-3, 2e-3, 1e-3, 2e-3), (1.5e-3, 2.5e-3, 1e-3, 2e-3)]
    part, report = remove(stock, VTool(math.pi / 2), [groove_x(1.5e-3, depth)], roi=windows)
    removed = depth * depth * 1.5e-3
    assert part.volume == pytest.approx(1.5e-3 * 1e-3 * 1e-3 - removed, rel=VOLUME_REL)
    assert report.removed_volume == pytest.approx(removed, rel=1e-9, abs=0.0)


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
    # 1e200 m squared to inf in np.linalg.norm: 'lies inf m', 'its spacing there is nan m'
    for far in (1e200, 1e9, 1e7, 1000.01):
        with pytest.raises(InputError, match=rf"path 0: pose 0 lies {re.escape(f'{far:g}')} "
                                             r"m from the workpiece's origin .* expected "
                                             r"within 1000 m"):
            remove(stock, FlatEndMill(0.5e-3),
                   [poses((-far, 5e-3, -depth), (far, 5e-3, -depth))])


def test_a_path_of_no_pose_before_the_others_drops_no_sweep():
    """A flat end mill 1 mm in radius along Y through a 10 mm block 0.5 mm deep cuts 2 x 0.5
    x 10 = 10 mm^3 by hand; a path of no pose given first had ended at pose -1, and the
    sweep that pair was taken from was the cut's last: the slot, cut without a word, 0 mm^3
    (n_sweeps 1 of 2)."""
    from machinesim.end_mills import FlatEndMill

    path = np.tile(np.eye(4), (3, 1, 1))
    path[:, :3, 3] = [(5e-3, -1e-3, 1e-3), (5e-3, -1e-3, -0.5e-3), (5e-3, 11e-3, -0.5e-3)]
    empty = np.zeros((0, 4, 4))
    for paths in ([path], [empty, path], [path, empty], [empty, path, empty]):
        _, report = remove(block(10e-3, 10e-3, 3e-3), FlatEndMill(1e-3), paths)
        assert report.n_sweeps == 2
        assert report.removed_volume == pytest.approx(10e-9, rel=1e-9)
