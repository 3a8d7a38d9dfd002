"""A planar profile (V tool) tilted across itself by a rotary move cuts within the chord
tolerance of its true sweep (`machinesim.cutting.tilted_profiles`)."""

import math

import numpy as np
from tilted_cuts import nearest_material, swept_cut, swing

import machinesim
from machinesim.cutting.tilted_profiles import clip_halfspace, halves
from machinesim.nc import parse_program
from machinesim.tools import VTool

DEPTH = 50e-6


def test_a_spun_v_leaves_the_wedges_it_never_swept():
    """A v:90 50 um deep, spun 20 deg about its own axis (A on robonano_ui): its blade, a
    line through the axis, sweeps two 20 deg sectors, and the stock between them keeps its
    edge on the axis (by hand: every pose's blade passes through it). The hull of each
    sub-step's two poses filled the sectors' waist there: 72 nm at 10 nm chords (124
    sub-steps of d = 0.16 deg), w sin(d / 2) / sin 80 deg = 71.4 nm by hand, w = 50 um the
    blade's half-width at the top of the stock, 80 deg the angle from the unswept wedge's
    middle to either sector."""
    program = parse_program("G21 G90\nG00 X5. Y5. Z1.\nG01 Z-0.05 F10.\nA20. F100.\n"
                            "G00 Z1.\nM30\n", "spin.nc")
    tolerance = 1e-8
    part, report = machinesim.cut(program, "robonano_ui", tool="v:90", stock="block:10x10x2",
                                  chord_tolerance=tolerance)
    # the two sectors at height z over the edge point hold w**2 * turn (w = z), so the
    # blade takes turn * DEPTH**3 / 3; each sub-step's triangles fall short of their sectors
    # by d**2 / 6 of them. The whole blade's hull reached w sin(d / 2) past the blade's first
    # and last positions too: 1 / (its 124 sub-steps) of it, 0.8 % more
    turn = math.radians(20.0)
    assert math.isclose(report.removed_volume_m3, turn * DEPTH**3 / 3, rel_tol=1e-5), (
        report.removed_volume_m3 / (turn * DEPTH**3 / 3) - 1)
    # the blade lies along Y at A = 0 and turns to 110 deg: the wedges (110, 270) and its
    # opposite are never swept
    angles = np.radians(np.linspace(111.0, 269.0, 80))
    for z in (-0.01e-6, -DEPTH / 2):
        gap = nearest_material(part, np.array([5e-3, 5e-3, z]), angles)
        assert gap <= tolerance, (z, gap)


def _swing(n: int, pivot_height: float, swing_angle: float):
    """Poses (n + 1, 4, 4) of a profile whose edge point stands DEPTH * 2 under the stock's
    top at (5, 5) mm, turned about the Y line ``pivot_height`` above it from
    -swing_angle / 2 to +swing_angle / 2 (rad)."""
    tip = np.array([5e-3, 5e-3, -2 * DEPTH])
    return swing(n, tip, tip + np.array([0.0, 0.0, pivot_height]), swing_angle / 2)


def test_a_flank_swung_about_a_line_inside_the_stock_keeps_its_waist():
    """A v:90 100 um deep swung +-2 deg about a Y line 50 um above its edge point (a B
    axis with the tool's length set beyond the pivot): on that line every pose's profile
    stands still, so the stock beside it, at the line's height, stays (true sweep: the
    bow-tie's waist, of no width). 20 sub-steps of 0.2 deg: the hull of each filled the
    waist A B / (A + B) d = 25 um * 3.5e-3 = 87 nm wide (A, B = 50 um, the profile below
    and above the line in the stock); each half's hull leaves it by its chords, under 0.1 nm
    (50 um * d**2 / 8)."""
    tool = VTool(math.radians(90.0))
    poses = _swing(20, DEPTH, math.radians(4.0))
    part, _ = swept_cut(tool, poses)
    level = np.array([5e-3, 5e-3, -DEPTH])
    for angle in (0.0, math.pi):
        gap = nearest_material(part, level, [angle])
        assert gap <= 1e-10, (angle, gap)
    # and it cut: 10 um below the line the profile's centre line, turned 2 deg, reaches
    # 10 um tan 2 deg = 349 nm to either side
    for angle in (0.0, math.pi):
        below = nearest_material(part, level - np.array([0.0, 0.0, 10e-6]), [angle])
        assert math.isclose(below, 10e-6 * math.tan(math.radians(2.0)), rel_tol=1e-6), below


def test_a_swing_about_the_edge_point_is_not_split():
    """robonano_a0ib's B turns the tool about its edge point: the profile lies on one side of
    the line it tilts about, its one hull is its sweep to second order, and it is cut as
    before."""
    tool = VTool(math.radians(90.0))
    poses = _swing(2, 0.0, math.radians(1.0))
    assert halves(tool.vertices(), poses[0, :3, :3], poses[0, :3, 3], poses[1, :3, :3],
                  poses[1, :3, 3], 0.0) is None


def test_the_halves_are_the_profile_at_both_poses():
    """The two halves' points hold the profile's part under the level at each pose: their
    areas add up to it (by the shoelace formula), pose by pose."""
    tool = VTool(math.radians(90.0))
    poses = _swing(1, DEPTH, math.radians(1.0))
    level = 0.0
    pieces = halves(tool.vertices(), poses[0, :3, :3], poses[0, :3, 3], poses[1, :3, :3],
                    poses[1, :3, 3], level)
    assert pieces is not None and all(p is not None for p in pieces)

    def area(points):  # a convex polygon in the Y-Z plane of its pose, in order
        y, z = points[:, 1], points[:, 2]
        return 0.5 * abs(np.dot(y, np.roll(z, -1)) - np.dot(z, np.roll(y, -1)))

    for pose in poses:
        rotation, origin = pose[:3, :3], pose[:3, 3]
        whole = clip_halfspace(tool.vertices(), rotation[2], level - origin[2])
        local = [(p - origin) @ rotation for p in pieces]
        # each piece holds its half at this pose first or second: the points on its plane
        parts = [q[np.abs(q[:, 0]) < 1e-15] for q in local]
        assert math.isclose(sum(area(q) for q in parts), area(whole), rel_tol=1e-12)
