"""The turning engine (machinesim.cutting.turning) against closed forms, an independent brute
force, and the mesh engine."""

import math

import numpy as np
import pytest

from machinesim.cam import spiral as sp
from machinesim.cutting import remove
from machinesim.cutting.turning import (
    EdgePath,
    edge_path_from_poses,
    edge_path_from_tips,
    nose_profile,
    turned_surface,
)
from machinesim.exceptions import InputError
from machinesim.metrology import height_map
from machinesim.tools import RoundNoseTool
from machinesim.workpiece import block

R = 1e-3  # nose radius of paper 004 (section 2.3)


def spiral_path(radius, feed, step, z=None, *, start=0.3, along=None, offset=0.0):
    """Archimedean tip path from ``radius`` inwards, one point every ``step`` rad, starting
    at angle ``start`` (off the grids' axes: a crossing exactly at the first point of the
    path is a tie that round-off decides)."""
    turns = radius / feed
    alpha = start + np.linspace(0.0, 2 * math.pi * turns, int(round(turns * 2 * math.pi / step))
                                + 1)
    rho = radius - feed / (2 * math.pi) * (alpha - start)
    return alpha, rho if along is None else along, offset, np.zeros_like(alpha) if z is None else z


def brute_force(alpha, along, offset, z, profile, x, y):
    """Every revolution, both branches, constant offset: the envelope by its definition."""
    gx, gy = np.meshgrid(x, y)
    rho, theta = np.hypot(gx, gy), np.arctan2(gy, gx)
    best = np.full(rho.shape, np.inf)
    turns = int((alpha[-1] - alpha[0]) / (2 * math.pi)) + 3
    with np.errstate(invalid="ignore"):
        root = np.sqrt(rho * rho - offset * offset)
    for sigma in (1.0, -1.0):
        phase = alpha[0] + np.mod(theta - np.arctan2(offset, sigma * np.nan_to_num(root))
                                  - alpha[0], 2 * math.pi)
        for k in range(-1, turns):
            at = phase + 2 * math.pi * k
            on = (at >= alpha[0]) & (at <= alpha[-1]) & ~np.isnan(root)
            s = sigma * np.nan_to_num(root) - np.interp(at, alpha, along)
            best = np.minimum(best, np.where(on, np.interp(at, alpha, z) + profile(s), np.inf))
    return np.where(np.isinf(best), np.nan, best)


def test_flat_face_leaves_the_cusps_of_the_closed_form():
    # a face turned at feed f: between revolutions the nose leaves R - sqrt(R^2 - f^2/4)
    feed, radius = 10e-6, 0.2e-3
    alpha, rho, _, z = spiral_path(radius, feed, math.radians(2.0))
    path = EdgePath(alpha, rho, 0.0, z)
    # on the +x axis (theta = 0) the tip passes at radius - f (k - 0.3 / 2 pi)
    k = np.arange(1, 15)
    tips = radius - feed * (k - alpha[0] / (2 * math.pi))
    cusps = tips - feed / 2
    x = np.sort(np.concatenate([tips, cusps]))
    heights = turned_surface(path, R, x, [0.0])[0]
    expected = np.where(np.isin(x, cusps), R - math.sqrt(R * R - feed * feed / 4), 0.0)
    np.testing.assert_allclose(heights, expected, rtol=0, atol=1e-11)  # the 0.01 nm
    # anywhere on the face with a revolution on either side (3 f from the centre and the
    # rim): the nose over the nearest tip at that angle
    rng = np.random.default_rng(0)
    gx, gy = rng.uniform(-0.12e-3, 0.12e-3, 40), rng.uniform(-0.12e-3, 0.12e-3, 30)
    heights = turned_surface(path, R, gx, gy)
    px, py = np.meshgrid(gx, gy)
    phase = np.mod(np.arctan2(py, px) - alpha[0], 2 * math.pi)
    offset = np.mod(radius - feed * phase / (2 * math.pi) - np.hypot(px, py), feed)
    s = np.minimum(offset, feed - offset)
    face = np.hypot(px, py) > 3 * feed
    np.testing.assert_allclose(heights[face], (R - np.sqrt(R * R - s * s))[face], rtol=0,
                               atol=1e-18)


@pytest.mark.parametrize("compensated", [True, False])
def test_sphere_is_turned_as_designed_or_offset_by_the_nose(compensated):
    # compensated (eqs 18-19): the design sphere plus scallops <= f_c^2 / 8R, f_c the spacing
    # of the nose centres (f (1 + R / Rs) on the offset sphere). Uncompensated (tip on the
    # sphere): the nose centres ride a sphere of radius Rs about (0, 0, R - Rs) and leave the
    # sphere of radius Rs - R about it, plus scallops <= f^2 / 8R, where the contact, R rho /
    # (Rs - R) inwards of its tip, comes from a tip with revolutions on both sides:
    # rho < (r - 3 f) (Rs - R) / Rs.
    rs, feed, radius = 5e-3, 2e-6, 0.2e-3
    spiral = sp.Spiral(radius, feed)
    points = sp.cutting_points(sp.sphere(rs), spiral, sp.constant_angle(spiral, 0.01))
    tool_path = sp.tool_path(points, R if compensated else None)
    path = edge_path_from_tips(tool_path.tips(), tool_path.c)
    x = np.linspace(-0.15e-3, 0.15e-3, 61) + 3e-9
    y = np.linspace(-0.15e-3, 0.15e-3, 59) + 2e-9
    heights = turned_surface(path, R, x, y)
    px, py = np.meshgrid(x, y)
    rho = np.hypot(px, py)
    if compensated:
        reference, scallop = sp.sphere(rs)(px, py), (feed * (1 + R / rs)) ** 2 / (8 * R)
    else:
        reference, scallop = (R - rs) + np.sqrt((rs - R) ** 2 - rho * rho), feed ** 2 / (8 * R)
    inside = rho < (radius - 3 * feed) * (rs - R) / rs
    error = (heights - reference)[inside]
    assert error.min() > -1e-15  # never below: the nose touches the surface, no gouging
    assert error.max() < scallop
    assert error.max() > 0.5 * scallop  # the scallops are there


def test_sine_grid_of_eq_2_with_an_ideal_tool_and_a_dense_path():
    # the paper's grid (A 50 nm, lambda 100 um), compensated, f 0.5 um, 5 mrad steps: the
    # design plus scallops f^2 / 8 (1 / R + kappa) (kappa <= 2 A (2 pi / lambda)^2, the
    # curvature of the radial profile) and the chord of the tip path between points,
    # kappa (rho dtheta)^2 / 8
    amplitude, wavelength, feed, radius, step = 50e-9, 100e-6, 0.5e-6, 0.1e-3, 0.005
    design = sp.sine_grid(amplitude, wavelength)
    spiral = sp.Spiral(radius, feed)
    tool_path = sp.tool_path(sp.cutting_points(design, spiral, sp.constant_angle(spiral, step)),
                             R)
    x = np.linspace(-0.09e-3, 0.09e-3, 61) + 3e-9
    y = x + 1e-9
    heights = turned_surface(edge_path_from_tips(tool_path.tips(), tool_path.c), R, x, y)
    px, py = np.meshgrid(x, y)
    kappa = 2 * amplitude * (2 * math.pi / wavelength) ** 2
    scallop = feed ** 2 / 8 * (1 / R + kappa)
    chord = kappa * (radius * step) ** 2 / 8
    error = (heights - design(px, py))[np.hypot(px, py) < 0.09e-3]
    assert error.min() > -chord
    assert error.max() < scallop + chord
    assert np.ptp(heights[np.hypot(px, py) < 0.09e-3]) > 3.5 * amplitude  # the grid is cut


@pytest.mark.parametrize("case", ["sine", "ripple", "large ripple", "centre height", "tool"])
def test_exact_minimum_whatever_the_path(case):
    # the search visits few revolutions; an independent brute force visits them all
    rng = np.random.default_rng(1)
    alpha, rho, _, _ = spiral_path(0.1e-3, 2e-6, math.radians(2.0))
    z = (50e-9 * np.sin(2 * math.pi * rho * np.cos(alpha) / 100e-6)
         + 50e-9 * np.cos(2 * math.pi * rho * np.sin(alpha) / 100e-6))
    along, offset, tool = rho, 0.0, R
    if case in ("ripple", "large ripple", "tool"):
        size = {"ripple": 20e-9, "large ripple": 200e-9, "tool": 50e-9}[case]
        z = z + size * rng.standard_normal(z.size)            # servo ripple in Z
        along = rho + 10 * size * rng.standard_normal(z.size)  # and in X
    if case in ("centre height", "tool"):
        offset = 1e-6 if case == "centre height" else -0.5e-6
    if case == "tool":
        tool = RoundNoseTool(R, math.radians(60), flank_height=5e-6)
    x = np.linspace(-0.12e-3, 0.12e-3, 49)
    y = np.linspace(-0.11e-3, 0.11e-3, 45)
    heights = turned_surface(EdgePath(alpha, along, offset, z), tool, x, y)
    expected = brute_force(alpha, along, offset, z, nose_profile(tool), x, y)
    np.testing.assert_array_equal(np.isnan(heights), np.isnan(expected))
    np.testing.assert_allclose(heights, expected, rtol=0, atol=1e-17, equal_nan=True)


def test_a_centre_height_error_leaves_an_uncut_core_of_its_radius():
    alpha, rho, _, z = spiral_path(0.05e-3, 2e-6, math.radians(2.0))
    x = np.linspace(-2e-6, 2e-6, 41)
    heights = turned_surface(EdgePath(alpha, rho, 1e-6, z), R, x, [0.0], top=5e-9)[0]
    assert (heights[np.abs(x) < 1e-6 - 1e-12] == 5e-9).all()  # never in the edge plane
    assert (heights[np.abs(x) > 1e-6 + 1e-12] < 5e-9).all()


def test_an_offset_of_round_off_is_no_centre_height_error():
    # the poses of a tool on the centre height leave ~1e-17 m in the offset: within
    # OFFSET_CONSTANT_M (1e-15 m) of zero it is zero, so the axis point is cut as with an
    # offset of exactly 0; 2e-15 m is a centre-height error, with its core of that radius
    alpha, rho, _, z = spiral_path(0.05e-3, 2e-6, math.radians(2.0))
    x = np.array([0.0, 1e-18, 1e-15, 1e-9, 3e-6])
    exact = turned_surface(EdgePath(alpha, rho, 0.0, z), R, x, [0.0], top=5e-9)[0]
    assert (exact < 5e-9).all()
    for offset in (3e-17, -8e-16):
        heights = turned_surface(EdgePath(alpha, rho, offset, z), R, x, [0.0], top=5e-9)[0]
        np.testing.assert_array_equal(heights, exact)
    # an offset that varies fits a spindle axis ~1e-17 m off the origin: the points beside
    # it are seen from other directions, where the centre's last revolution leaves other
    # heights, within the scallop f^2 / 8R
    noise = 3e-17 * np.sin(7.0 * alpha) + 2e-17
    heights = turned_surface(EdgePath(alpha, rho, noise, z), R, x, [0.0], top=5e-9)[0]
    np.testing.assert_allclose(heights, exact, rtol=0, atol=(2e-6) ** 2 / (8 * R))
    np.testing.assert_allclose(heights[3:], exact[3:], rtol=0, atol=1e-20)
    core = turned_surface(EdgePath(alpha, rho, 2e-15, z), R, x, [0.0], top=5e-9)[0]
    assert (core[:3] == 5e-9).all() and (core[3:] < 5e-9).all()


def test_an_off_centre_spindle_turns_the_same_surface_about_its_axis():
    # tips about a spindle axis at e: the offset varies as e x u along the path; the engine
    # fits the axis and works about it, so the surface is the centred one shifted by e
    alpha, rho, _, _ = spiral_path(0.1e-3, 2e-6, math.radians(2.0))
    centre, dy = np.array([3e-6, -2e-6]), 0.7e-6
    cos, sin = np.cos(alpha), np.sin(alpha)
    lx, ly = rho * cos - dy * sin, rho * sin + dy * cos
    z = 50e-9 * np.sin(2 * math.pi * lx / 100e-6) + 50e-9 * np.cos(2 * math.pi * ly / 100e-6)
    about = edge_path_from_tips(np.column_stack([lx, ly, z]), alpha)
    off = edge_path_from_tips(np.column_stack([lx + centre[0], ly + centre[1], z]), alpha)
    assert np.ptp(off.offset) > 7e-6
    x = np.linspace(-0.09e-3, 0.09e-3, 37) + 1.1e-7
    y = np.linspace(-0.08e-3, 0.08e-3, 33) + 0.7e-7
    np.testing.assert_allclose(turned_surface(off, R, x, y),
                               turned_surface(about, R, x - centre[0], y - centre[1]),
                               rtol=0, atol=1e-18)


def test_a_varying_centre_height_crosses_each_point_where_it_is_in_the_edge_plane():
    # a centre height drifting along the path: crossings by fixed-point iteration against
    # crossings found by bisection on p . u_perp(alpha) - d(alpha)
    alpha, rho, _, _ = spiral_path(0.06e-3, 4e-6, math.radians(0.4))
    offset = (0.5e-6 + 0.4e-6 * (alpha - alpha[0]) / np.ptp(alpha)
              + 0.05e-6 * np.sin(7 * alpha))
    z = (50e-9 * np.sin(2 * math.pi * rho * np.cos(alpha) / 100e-6)
         + 50e-9 * np.cos(2 * math.pi * rho * np.sin(alpha) / 100e-6))
    path = EdgePath(alpha, rho, offset, z)
    x = np.linspace(-0.065e-3, 0.065e-3, 9) + 1.3e-7
    y = np.linspace(-0.06e-3, 0.06e-3, 7) + 0.9e-7
    heights = turned_surface(path, R, x, y)
    profile = nose_profile(R)
    fine = np.linspace(alpha[0], alpha[-1], 100_001)
    d_fine = np.interp(fine, alpha, offset)

    def g(a, px, py):
        return -np.sin(a) * px + np.cos(a) * py - np.interp(a, alpha, offset)

    for j, py in enumerate(y):
        for i, px in enumerate(x):
            values = -np.sin(fine) * px + np.cos(fine) * py - d_fine
            best = np.inf
            for k in np.flatnonzero(np.sign(values[:-1]) != np.sign(values[1:])):
                lo, hi = fine[k], fine[k + 1]
                for _ in range(60):
                    mid = 0.5 * (lo + hi)
                    if np.sign(g(mid, px, py)) == np.sign(g(lo, px, py)):
                        lo = mid
                    else:
                        hi = mid
                at = 0.5 * (lo + hi)
                s = math.cos(at) * px + math.sin(at) * py - np.interp(at, alpha, rho)
                best = min(best, float(np.interp(at, alpha, z) + profile(s)))
            # the engine joins points about the fitted spindle axis (here 8 nm off the
            # origin), the brute force about the origin: chords differ by |e| dalpha^2 / 8
            if math.isinf(best):
                assert math.isnan(heights[j, i])
            else:
                assert heights[j, i] == pytest.approx(best, abs=1e-15)


def test_the_mesh_engine_cuts_the_same_surface():
    # A sector of a turned face, cut by the boolean engine from the tool's poses: the nose
    # polygon's vertices lie on the arc and its chords 1 nm (chord_tol) inside it, so the
    # mesh lies up to 1 nm above the exact envelope, never below it by more than the sweep
    # hulls' chords across the spiral (rho dtheta^2 / 8 = 0.25 nm radially, times the
    # envelope's slope <= f / 2R + the design's ~ 0.01: 3 pm).
    radius, feed, step = 0.6e-3, 10e-6, 2e-3
    tool = RoundNoseTool(0.5e-3, math.radians(60), height=0.1e-3, chord_tol=1e-9,
                         flank_height=2e-6)
    design = sp.sine_grid(20e-9, 100e-6)
    spiral = sp.Spiral(radius, feed)
    turns = range(int((radius - 0.532e-3) / feed), int((radius - 0.468e-3) / feed) + 1)
    sector = np.arange(-0.03, 0.03 + step / 2, step)

    def poses(theta):
        # the tool's +X along the cut (tangential), its Y radial: the profile of
        # machinesim.tools (in the tool's Y-Z plane) is then the turning edge
        cut = sp.tool_path(sp.cutting_points(design, spiral, theta), tool.nose_radius)
        c = cut.c + math.pi / 2
        wMt = np.zeros((len(cut), 4, 4))
        wMt[:, 0, 0], wMt[:, 1, 0] = np.cos(c), np.sin(c)
        wMt[:, 0, 1], wMt[:, 1, 1] = -np.sin(c), np.cos(c)
        wMt[:, 2, 2] = wMt[:, 3, 3] = 1.0
        wMt[:, :3, 3] = cut.tips()
        return wMt

    paths = [poses(2 * math.pi * k + sector) for k in turns]
    top = 0.3e-6
    part, _ = remove(block(20e-6, 20e-6, 5e-6, origin=(0.49e-3, -0.01e-3, top)), tool, paths)
    x = np.linspace(0.491e-3, 0.509e-3, 37) + 1e-9
    y = np.linspace(-0.009e-3, 0.009e-3, 37) + 1e-9
    mesh = height_map(part, x, y)
    # the same path, continuous over the same revolutions, from the same poses (their Y
    # axis spans the edge plane)
    whole = np.arange(2 * math.pi * turns[0] - 0.1, 2 * math.pi * (turns[-1] + 1) + 0.1, step)
    turned = turned_surface(edge_path_from_poses(poses(whole), tool.nose_radius, edge_axis=1),
                            tool, x, y, top=top)
    difference = mesh - turned
    assert difference.min() > -1e-11
    assert difference.max() < tool.chord_tol + 1e-11
    assert np.ptp(turned) > 30e-9  # the sine and the cusps are there


def test_poses_of_the_sts_lathe_give_the_path_of_its_axis_values():
    import machinesim
    from machinesim.errors import ErrorModel

    machine = machinesim.load_machine("sts_lathe")
    spiral = sp.Spiral(0.05e-3, 2e-6)
    cut = sp.tool_path(sp.cutting_points(sp.sine_grid(), spiral,
                                         sp.constant_angle(spiral, math.radians(5))), R)
    q = np.column_stack([cut.x, cut.z, cut.c])  # configuration order X Z C
    nominal = edge_path_from_poses(machine.tool_pose(q), R)
    np.testing.assert_allclose(nominal.angle, cut.c, rtol=0, atol=1e-12)  # atan2 at 157 rad
    np.testing.assert_allclose(nominal.along, cut.x, rtol=0, atol=1e-15)
    np.testing.assert_allclose(nominal.z, cut.z, rtol=0, atol=1e-15)
    assert np.abs(nominal.offset).max() < 1e-15
    # a tool set 1.5 um off the centre height (paper 004's dy) is the edge plane's offset
    errors = ErrorModel.from_dict({"tool": {"offset_um": [0.0, 1.5, 0.0]}})
    shifted = edge_path_from_poses(machine.tool_pose(q, errors), R)
    np.testing.assert_allclose(shifted.offset, 1.5e-6, rtol=0, atol=1e-15)


def test_unreached_points_read_nan_or_the_stock_top():
    alpha, rho, _, z = spiral_path(0.05e-3, 5e-6, math.radians(5.0))
    x = np.array([0.0, 0.04e-3, 2.0e-3])  # centre, face, beyond the nose's reach
    bare = turned_surface(EdgePath(alpha, rho, 0.0, z), R, x, [1e-9])[0]
    assert np.isfinite(bare[:2]).all() and np.isnan(bare[2])
    topped = turned_surface(EdgePath(alpha, rho, 0.0, z), R, x, [1e-9], top=1e-9)[0]
    assert topped[2] == 1e-9 and (topped[:2] <= 1e-9).all()


def test_path_orientations_describe_the_same_edge_planes():
    alpha, rho, _, z = spiral_path(0.05e-3, 5e-6, math.radians(5.0))
    z = z + 1e-8 * np.sin(3 * alpha)
    x = np.linspace(-0.04e-3, 0.04e-3, 11) + 1e-9
    reference = turned_surface(EdgePath(alpha, rho, 0.0, z), R, x, x)
    reversed_ = EdgePath(alpha[::-1], rho[::-1], 0.0, z[::-1])
    flipped = EdgePath(alpha + math.pi, -rho, 0.0, z)
    assert flipped.along[0] > 0
    for path in (reversed_, flipped):
        np.testing.assert_allclose(turned_surface(path, R, x, x), reference, rtol=0,
                                   atol=1e-21)


def test_bad_paths_are_refused_with_what_was_expected():
    with pytest.raises(InputError, match="monotonic spindle angle"):
        EdgePath([0.0, 1.0, 0.5], [1e-3] * 3, 0.0, [0.0] * 3)
    with pytest.raises(InputError, match="turn along the path"):
        EdgePath([1.0, 1.0], [1e-3] * 2, 0.0, [0.0] * 2)
    with pytest.raises(InputError, match=r"along of shape \(3,\)"):
        EdgePath([0.0, 1.0, 2.0], [1e-3] * 2, 0.0, [0.0] * 3)
    with pytest.raises(InputError, match="finite z"):
        EdgePath([0.0, 1.0], [1e-3] * 2, 0.0, [0.0, np.nan])
    with pytest.raises(InputError, match=r"tips of shape \(N, 3\)"):
        edge_path_from_tips(np.zeros((4, 2)), np.arange(4.0))
    with pytest.raises(InputError, match="an EdgePath"):
        turned_surface(np.zeros((4, 3)), R, [0.0], [0.0])
    with pytest.raises(InputError, match="nose_radius > 0"):
        turned_surface(EdgePath([0.0, 1.0], [1e-3] * 2, 0.0, [0.0] * 2), 0.0, [0.0], [0.0])
