"""The corpus programs that cut, cut on small stock: removed volumes against shapes worked
out by hand from the program text (tests/nc_corpus/)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from machinesim.cutting import cut
from machinesim.nc import AXES, KIND_LINEAR, parse_program, read_program
from machinesim.tools import BallEndMill, VTool
from machinesim.workpiece import Part, cylinder

CORPUS = Path(__file__).parent / "nc_corpus"
MM = 1e-3
#: Removed volumes are integrated exactly (docs/cutting.md); float64 round-off over a few
#: thousand faces stays far below this.
VOLUME_REL = 1e-9


def test_subprogram_grooves_remove_four_v_prisms():
    # O3002 called four times: G91 Z-1.01 from Z1 (0.01 mm below the top), a feed 10 mm
    # along X, out, back and 2 mm over in Y. The V edge is a zero-thickness profile in the
    # tool's Y-Z plane, so the plunge removes nothing and each feed leaves a prism of the
    # 90-deg V's section d^2 (half-width d at the top: d * d) over 10 mm.
    program = read_program(CORPUS / "subprogram.nc")
    _, report = cut(program, "grooving_4axis", tool=VTool(math.pi / 2),
                    stock="block:12x8x1@-1,-1,0")
    depth, length = 0.01 * MM, 10 * MM
    assert report.removed_volume_m3 == pytest.approx(4 * depth**2 * length, rel=VOLUME_REL, abs=0.0)
    assert report.rapids_that_cut == () and report.holder_contact == ()


def _ball_hole(tool: BallEndMill, depth: float) -> float:
    """Volume a ball polyhedron leaves plunged straight down to ``depth`` > its radius: the
    hemisphere as frusta of regular pyramids between its rings (`BallEndMill.rings`) and a
    prism of the equator polygon over depth - R."""
    rings, segments = tool.rings
    theta = np.linspace(0.0, math.pi / 2, rings + 1)
    r, z = tool.radius * np.sin(theta), tool.radius * (1 - np.cos(theta))
    area = segments / 2 * r**2 * math.sin(2 * math.pi / segments)
    hemisphere = np.sum(np.diff(z) / 3 * (area[1:] + area[:-1] + np.sqrt(area[1:] * area[:-1])))
    return float(hemisphere + area[-1] * (depth - tool.radius))


def test_drilling_cycles_leave_four_ball_holes():
    # G81 at (5, 5) and (10, 5) to Z-2, G82 at (5, 10) to Z-1.5, G83 pecks at (10, 10) to
    # Z-3 (every peck re-enters the hole it made: the union is one plunge to Z-3). The holes
    # are 5 mm apart, R 0.5 mm: disjoint. Between holes the tool rapids at Z10 or the R
    # level (Z0.5 and Z1), above the top.
    tool = BallEndMill(0.5 * MM, chord_tol=5e-6)
    program = read_program(CORPUS / "drilling.nc")
    _, report = cut(program, "grooving_4axis", tool=tool, stock="block:15x15x4")
    expected = sum(_ball_hole(tool, d * MM) for d in (2.0, 2.0, 1.5, 3.0))
    assert report.removed_volume_m3 == pytest.approx(expected, rel=VOLUME_REL)
    assert report.rapids_that_cut == ()
    # the polyhedron lies within its chord tolerance inside the true ball
    true = sum(2 / 3 * math.pi * tool.radius**3 + math.pi * tool.radius**2
               * (d * MM - tool.radius) for d in (2.0, 2.0, 1.5, 3.0))
    assert true * (1 - 1e-2) < expected <= true


def test_a_haas_variable_peck_hole_is_a_plain_drill_hole():
    # G83 with Haas's I J K (1, 0.3, 0.2 mm: pecks 1, 0.7, 0.4, 0.2, ...) only retracts
    # between pecks, each re-entering the hole it made: the union is one plunge to Z-3
    tool = BallEndMill(0.5 * MM, chord_tol=5e-6)
    program = parse_program("G21 G90 G17\nG00 X5. Y5. Z10.\n"
                            "G98 G83 X5. Y5. Z-3. R0.5 I1. J0.3 K0.2 F100.\nG80\nM30\n")
    _, report = cut(program, "grooving_4axis", tool=tool, stock="block:10x10x4")
    assert report.removed_volume_m3 == pytest.approx(_ball_hole(tool, 3 * MM), rel=VOLUME_REL)
    assert report.rapids_that_cut == ()


def _ball_section(radius: float, depth):
    """Area below the top of a ball end mill's section through its axis, its lowest point
    ``depth`` below the top (a circular segment, then the shank's rectangle)."""
    depth = np.asarray(depth, dtype=np.float64)
    a = radius - np.minimum(depth, radius)
    segment = radius**2 * np.arccos(a / radius) - a * np.sqrt(radius**2 - a**2)
    return segment + 2 * radius * np.maximum(depth - radius, 0.0)


def _ball_below(radius: float, depth: float) -> float:
    """Volume of a ball end mill below the top, its lowest point ``depth`` below it."""
    cap = min(depth, radius)
    return math.pi * cap**2 * (3 * radius - cap) / 3 + math.pi * radius**2 * max(
        depth - radius, 0.0)


#: The CAM program's tools as solids: T1 the 6 mm cutter of its header (a ball, R 3 mm),
#: T2 the R0.5 ball end mill, 2.5 mm longer than the model's tool.
CAM_TOOLS = """
[tool.1]
length_mm = 0.0
shape = "ball:3"
[tool.2]
length_mm = {t2_mm}
shape = "ball:0.5"
"""


def _cam_cut(tmp_path, t2_mm: float, text: str | None = None):
    """cam_header.nc cut on a block round T2's circle only (centre (15, 15) mm, R 5 mm;
    T1's contour stays 3 mm and more outside it). Work zero is 5 mm below machine zero so
    that G28 Z0 clears the block; arcs are read at a 1 um chord to keep the cut short."""
    table = tmp_path / "tools.toml"
    table.write_text(CAM_TOOLS.format(t2_mm=t2_mm))
    program = tmp_path / "cam.nc"
    program.write_text(text or (CORPUS / "cam_header.nc").read_text())
    read = read_program(program, tools=table, work_offsets={"G54": {"Z": -5 * MM}},
                        chord_tolerance=1e-6)
    return cut(read, "grooving_4axis", tool="v:90", stock="block:12x12x3@9,9,-5")[1]


def _torus_below(radius: float, depth: float, centre_radius: float) -> float:
    """Volume of a ball end mill swept round a circle of ``centre_radius`` at ``depth`` (its
    lowest point below the top): its section below the top, symmetric about the tool axis,
    turned about the circle's axis (Pappus)."""
    return 2 * math.pi * centre_radius * float(_ball_section(radius, depth))


def test_cam_program_cuts_with_the_tools_it_changes_to(tmp_path):
    # T1 M06 (line 13) and T02 M06 (line 33) put the table's tools in; G43 H02 lifts Z by
    # T2's 2.5 mm and the longer tool reaches it back down, so T2 cuts 0.2 mm deep round its
    # circle (a ball swept round a circle is a torus: the volume is Pappus's), and the same
    # program with a T2 of length 0 cuts the same part.
    report = _cam_cut(tmp_path, 2.5)
    assert [(t["tool"], t["line"], t["length_m"]) for t in report.tools] == [
        (None, None, 0.0), (1, 13, 0.0), (2, 33, 2.5 * MM)]
    t2 = report.tools[2]["removed_volume_m3"]
    assert report.removed_volume_m3 == t2  # T1's contour is off this block
    true = _torus_below(0.5 * MM, 0.2 * MM, 5 * MM)
    assert true * (1 - 1e-2) < t2 <= true  # polyhedral ball, inscribed path polygon
    assert report.rapids_that_cut == () and report.holder_contact == ()
    same = _cam_cut(tmp_path, 0.0)
    assert same.removed_volume_m3 == pytest.approx(t2, rel=VOLUME_REL)


def test_tool_changes_read_without_a_table_are_noted():
    """T1 M06 and T2 M06 without a tool table: both slots are cut by the cut's own flat end
    mill, 2 mm wide and 0.1 mm deep across the 10 mm block (2 mm^3 each, the 1 um polygon
    at most 1e-3 narrower), and the report says so; one T is the cut's own tool, no note."""
    text = ("G90 G21 G17\nT1 M06\nG00 X-1. Y3. Z1.\nG01 Z-0.1 F100.\nX11.\nG00 Z5.\n"
            "T2 M06\nG00 X-1. Y7. Z1.\nG01 Z-0.1 F100.\nX11.\nG00 Z5.\nM30\n")
    _, report = cut(parse_program(text, "two.nc"), "grooving_4axis", tool="flat:1.0",
                    stock="block:10x10x2")
    assert report.removed_volume_m3 == pytest.approx(4 * MM**3, rel=1e-3)
    assert [n for n in report.notes if "read without a tool table" in n] == [
        "the program selects 2 tools (T1 at line 2, T2 at line 7) but was read without a "
        "tool table, so the cut's own tool (FlatEndMill) cut every move; give a tool table "
        "with each tool's shape and length (--tools; read_program(..., tools=...); "
        "docs/nc.md)"]
    _, one = cut(parse_program(text.replace("T2 M06", "T1 M06"), "one.nc"), "grooving_4axis",
                 tool="flat:1.0", stock="block:10x10x2")
    assert not [n for n in one.notes if "tool table" in n]


def test_a_wrong_length_offset_crashes_the_tool_into_the_part(tmp_path):
    # G43 H01 under T2: Z lifted by T1's 0 mm while the tool in the spindle is 2.5 mm
    # longer, so the ball goes round 2.7 mm deep, its shank cutting the wall above it.
    text = (CORPUS / "cam_header.nc").read_text().replace("Z10. H02", "Z10. H01")
    report = _cam_cut(tmp_path, 2.5, text)
    true = _torus_below(0.5 * MM, 2.7 * MM, 5 * MM)
    assert true * (1 - 1e-2) < report.removed_volume_m3 <= true


#: The polyhedral ball (chord 1 um at R 0.5 mm) lies inside the true one, and the volumes
#: below are integrals of the true ball's section along the path: the cut comes out up to
#: ~0.6 % under them (0.2 % at chord 0.3 um), never over by more than the integrals' own
#: error (path tilt, end caps: < 1e-3).
BALL_BAND = (1 - 1e-2, 1 + 1e-3)


def test_arcs_cut_a_helical_groove_in_a_ring():
    # On a ring (r 8..12 mm) with its top at Z0, only the XY arcs reach the stock (the ZX
    # and YZ arcs and the rapids between stay inside r 5.1). The quarter, half and
    # three-quarter arcs at Z0 only touch the top; the full circle of radius 10 descends
    # from Z0 to Z-1: a ball (and its shank) going round deeper and deeper. The groove's
    # section at each angle is the tool's (symmetric about its axis at r 10), so its volume
    # is 10 mm x the integral of that section over the turn (Pappus, angle by angle), plus
    # the half tool ahead of the end, 1 mm deep.
    ring = Part(cylinder(12 * MM, 3 * MM).manifold
                - cylinder(8 * MM, 4 * MM, origin=(0, 0, 0.5 * MM)).manifold)
    radius = 0.5 * MM
    program = read_program(CORPUS / "arcs_planes.nc", chord_tolerance=1e-6)
    _, report = cut(program, "grooving_4axis", tool=BallEndMill(radius, chord_tol=1e-6),
                    stock=ring)
    depth = np.linspace(0.0, 1 * MM, 200_001)
    turn = 2 * math.pi * 10 * MM * np.mean(
        0.5 * (_ball_section(radius, depth[1:]) + _ball_section(radius, depth[:-1])))
    expected = turn + _ball_below(radius, 1 * MM) / 2
    assert BALL_BAND[0] * expected < report.removed_volume_m3 < BALL_BAND[1] * expected
    assert report.rapids_that_cut == () and report.holder_contact == ()


def test_slow_tool_servo_points_cut_a_spiral_groove():
    # The 720 X Z C points (one turn of C while X goes 5 -> 1.4 mm, Z a 1 um 3-lobe wave)
    # with a ball 0.09 mm below the top of a disc: between points the axes move linearly, so
    # in the workpiece the tool follows (X cos C, X sin C, Z). The volume is the integral of
    # the ball's section, at its depth there, along that path (the grooves are 3.6 mm apart,
    # 0.6 mm wide: no overlap), plus half a ball cap at each end.
    radius, top = 0.5 * MM, 0.09 * MM
    program = read_program(CORPUS / "sts_points.nc")
    _, report = cut(program, "grooving_4axis", tool=BallEndMill(radius, chord_tol=1e-6),
                    stock=cylinder(6 * MM, 1 * MM, origin=(0, 0, top)),
                    start=[5 * MM, 0, 1 * MM, 0], chord_tolerance=1e-6)
    x, z, c = (program.targets[:, AXES.index(a)] for a in "XZC")
    feed = np.flatnonzero(program.kinds == KIND_LINEAR)[1:]  # after the plunge
    u = np.linspace(0.0, 1.0, 201)[:, None]
    xs, zs, cs = (v[feed - 1] + u * (v[feed] - v[feed - 1]) for v in (x, z, c))
    path = np.stack([xs * np.cos(cs), xs * np.sin(cs), zs], axis=-1)
    step = np.linalg.norm(np.diff(path, axis=0), axis=-1)
    groove = np.sum(_ball_section(radius, top - 0.5 * (zs[1:] + zs[:-1])) * step)
    ends = (_ball_below(radius, top - z[feed[0] - 1]) + _ball_below(radius, top - z[feed[-1]]))
    expected = groove + ends / 2
    assert BALL_BAND[0] * expected < report.removed_volume_m3 < BALL_BAND[1] * expected
    assert report.rapids_that_cut == () and report.holder_contact == ()
