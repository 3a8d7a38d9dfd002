"""cut(): NC program -> motion -> erroneous poses -> exact part, against analytic geometry."""

from __future__ import annotations

import json
import math

import manifold3d
import numpy as np
import pytest
from cutting_helpers import _slot_in_steps

from machinesim import ErrorModel, ToolSetting
from machinesim.cli import main
from machinesim.cutting import cut
from machinesim.exceptions import AxisLimitError, HolderContactError, InputError, NCProgramError
from machinesim.machines import load_machine
from machinesim.metrology import height_map
from machinesim.nc import ProgramBuilder, parse_program, write_program
from machinesim.tool_specs import tool_from_spec
from machinesim.tools import VTool
from machinesim.workpiece import Part, block

UM, MM = 1e-6, 1e-3


def grooves(n=3, pitch=20 * UM, depth=10 * UM, y0=1 * MM, length=5 * MM):
    """Grooves along X, entering and leaving outside a 5 mm block, with rapids above it."""
    b = ProgramBuilder(1)
    for i in range(n):
        y = y0 + i * pitch
        b.rapid(X=-0.5 * MM, Y=y, Z=0.1 * MM).rapid(Z=-depth)
        b.linear(X=length + 0.5 * MM, feed_mm_per_min=500.0).rapid(Z=0.1 * MM)
    return b.build()


def test_v_grooves_have_the_analytic_section_and_volume():
    part, report = cut(grooves(), "grooving_4axis", tool="v:90", stock="block:5x3x1")
    # 90-deg V, depth d: section d^2 (tan 45 = 1), over the 5 mm block, three grooves
    assert report.removed_volume_m3 == pytest.approx(3 * (10 * UM) ** 2 * 5 * MM, rel=1e-9, abs=0.0)
    assert report.sweeps == 3 and not report.empty_cut and report.rapids_that_cut == ()
    assert report.engine == "relief"  # straight grooves right across the block
    y = np.linspace(0.99 * MM, 1.01 * MM, 2001)
    h = height_map(part, np.array([2.5 * MM]), y)[:, 0]
    # 0.01 nm: the float64 mesh carries the V exactly; heights are plane evaluations
    expected = np.minimum(-10 * UM + np.abs(y - 1 * MM), 0.0)
    np.testing.assert_allclose(h, expected, rtol=0, atol=1e-11)
    # machining time from the feeds: 3 x (6 mm at 500 mm/min) plus rapids at 25 mm/s
    feed = 3 * 6.0 / 500.0 * 60.0
    assert report.cutting_time_s == pytest.approx(feed, rel=1e-12)


def test_roi_windows_that_miss_the_stock_are_refused_by_cut_as_by_the_command_line():
    # cut() gave back the stock clipped to them, empty, without a word (only the command
    # line refused them); a window that only touches the block's side (x 5 .. 6 mm) holds
    # none of it
    from machinesim.cutting import cut_turned

    roi = [(0.1, 0.2, 0.1, 0.2), (5 * MM, 6 * MM, 0.0, 3 * MM)]
    expected = ("roi [(0.1, 0.2, 0.1, 0.2), (0.005, 0.006, 0, 0.003)] m: no window overlaps "
                "the stock, which spans x 0 .. 0.005 m and y 0 .. 0.003 m (workpiece frame): "
                "the part, the stock within the windows, would be empty; expected a window "
                "over the stock")
    for cutter in (cut, cut_turned):
        with pytest.raises(InputError) as info:
            cutter(grooves(), "grooving_4axis", tool="v:90", stock="block:5x3x1", roi=roi)
        assert str(info.value) == expected
    # one window over the stock is enough: the part is the block's half x < 2.5 mm less
    # the grooves' V sections (d^2 each) over that half
    part, report = cut(grooves(), "grooving_4axis", tool="v:90", stock="block:5x3x1",
                       roi=[*roi, (-1 * MM, 2.5 * MM, -1 * MM, 4 * MM)])
    half = 2.5 * MM * 3 * MM * 1 * MM
    assert part.volume == pytest.approx(half - 3 * (10 * UM) ** 2 * 2.5 * MM, rel=1e-9)
    assert not report.empty_cut


@pytest.mark.parametrize("roi, match", [
    ("x", r"Expected roi as windows \(xmin, xmax, ymin, ymax\), m, got 'x'"),
    ([("0", "1", "0", "1")], r"Expected roi as windows .*got \[\('0', "),
    ([(math.nan, 1 * MM, 0.0, 1 * MM)], r"roi: expected finite windows \(m\), got "
                                        r"\[\[nan, 0.001, 0.0, 0.001\]\]"),
    ((0.0, 1 * MM, 0.0, 1 * MM), r"of shape \(n, 4\), got \(4,\) \(one window is "
                                 r"\[\(xmin, xmax, ymin, ymax\)\]\)"),
])
def test_roi_that_is_no_windows_of_numbers_is_refused_naming_it(roi, match):
    # roi="x" had raised numpy's ValueError "could not convert string to float", and a NaN
    # window was told as a shape of (n, 4) while its shape was (1, 4)
    with pytest.raises(InputError, match=match) as info:
        cut(grooves(), "grooving_4axis", tool="v:90", stock="block:5x3x1", roi=roi)
    assert info.value.key == "roi"


def test_a_tool_setting_error_moves_the_groove_by_exactly_the_offset():
    dy, dz = 3 * UM, -2 * UM
    errors = ErrorModel(tool=ToolSetting([0.0, dy, dz], [0.0, 0.0, 0.0]))
    part, _ = cut(grooves(n=1), "grooving_4axis", tool="v:90", stock="block:5x3x1",
                  errors=errors)
    y = np.linspace(0.98 * MM, 1.02 * MM, 4001)
    h = height_map(part, np.array([2.5 * MM]), y)[:, 0]
    expected = np.minimum(-10 * UM + dz + np.abs(y - (1 * MM + dy)), 0.0)
    np.testing.assert_allclose(h, expected, rtol=0, atol=1e-11)


def test_a_rotary_move_stays_within_the_chord_tolerance_of_the_true_path():
    """The planer swings its edge on the 120.5 mm arm while X feeds: the edge follows
    y = r sin(theta), z = Z + r (1 - cos(theta)); the groove bottom under that path may
    stand above it by at most the 1 nm chord tolerance, and never below it."""
    r, z0 = 0.1205, -5 * UM
    a0, a1 = math.radians(-0.3), math.radians(0.3)
    x0, x1 = 0.5 * MM, 4.5 * MM
    program = (ProgramBuilder(1).rapid(X=x0, Y=0.0, Z=0.1 * MM, A=a0).rapid(Z=z0)
               .linear(X=x1, A=a1, feed_mm_per_min=100.0).rapid(Z=0.1 * MM).build())
    part, report = cut(program, "planer_4axis", tool="v:90", stock="block:5x3x1@0,-1.5,0")
    # split into the fewest sub-steps whose sagitta on the arm stays within 1 nm
    assert report.sweeps >= math.ceil((a1 - a0) / (2 * math.acos(1 - 1e-9 / r)))
    s = np.linspace(0.02, 0.98, 97)
    theta = a0 + (a1 - a0) * s
    x, y = x0 + (x1 - x0) * s, r * np.sin(theta)
    z = z0 + r * (1 - np.cos(theta))
    h = np.array([height_map(part, np.array([xi]), np.array([yi]))[0, 0]
                  for xi, yi in zip(x, y, strict=True)])
    assert np.all(h - z <= 1e-9 + 1e-12)
    assert np.all(h - z >= -1e-12)


def test_a_rapid_into_the_stock_is_reported_and_an_empty_cut_flagged():
    b = ProgramBuilder(1).rapid(X=1 * MM, Y=1 * MM, Z=0.1 * MM).rapid(Z=-5 * UM)
    program = b.linear(X=4 * MM, feed_mm_per_min=100.0).rapid(Z=0.1 * MM).build()
    _, report = cut(program, "grooving_4axis", tool="v:90", stock="block:5x3x1")
    assert report.rapids_that_cut == (program.moves[1].line,)
    miss = ProgramBuilder(1).rapid(X=1 * MM, Y=1 * MM, Z=0.1 * MM).linear(
        X=4 * MM, feed_mm_per_min=100.0).build()
    _, report = cut(miss, "grooving_4axis", tool="v:90", stock="block:5x3x1")
    assert report.empty_cut and report.removed_volume_m3 == 0.0


def test_a_rapid_back_along_a_groove_just_cut_cuts_nothing():
    b = ProgramBuilder(1).rapid(X=-0.5 * MM, Y=1 * MM, Z=0.1 * MM).rapid(Z=-5 * UM)
    b.linear(X=4 * MM, feed_mm_per_min=100.0).rapid(X=1 * MM).rapid(Z=0.1 * MM)
    _, report = cut(b.build(), "grooving_4axis", tool="v:90", stock="block:5x3x1")
    assert report.rapids_that_cut == ()


def test_a_retract_up_its_own_plunge_far_from_work_zero_cuts_nothing():
    # A beginner's program (helmancnc.com's simple mill example): plunge at (-75, -75) mm
    # 20 mm deep, a square at that depth, back to the plunge, G00 Z100. The faces of the
    # retract and of the plunge coincide; at 75 mm from zero their booleans leave a film
    # 2.5e-18 m thick (6.6e-24 m^3), which had been listed as a rapid that cut
    text = ("G90 G21 G17\nG00 X-75. Y-75. Z5.\nG01 Z-20. F100.\nX-40.\nY40.\nX40.\nY-40.\n"
            "X-75.\nY-75.\nG00 Z100.\nM30\n")
    program = parse_program(text, "helman.nc")
    part, report = cut(program, "grooving_4axis", tool="flat:5:h=30",
                       stock="block:200x200x30@-100,-100,0")
    assert report.rapids_that_cut == ()
    # a rapid 1 mm below the square's floor first (G00 Z-21.) meets fresh stock, and is
    # listed; the retract after it is not
    deeper = text.replace("G00 Z100.", "G00 Z-21.\nG00 Z100.")
    _, report = cut(parse_program(deeper, "deeper.nc"), "grooving_4axis", tool="flat:5:h=30",
                    stock="block:200x200x30@-100,-100,0")
    assert report.rapids_that_cut == (10,)


def test_rapids_across_many_grooves_are_judged_against_those_they_meet():
    # 70 grooves 5 um deep along X, 20 um apart; then a rapid 3 um deep along Y across all
    # of them, which cuts the ridges between them (listed), and a rapid 5 um deep back along
    # groove 35's bottom, over what that groove cut (not listed). Each overlaps 70 earlier
    # sweeps, past `RAPID_EARLIER_UNION`: those whose solids meet it are taken away.
    b = ProgramBuilder(1).rapid(X=0.5 * MM, Y=0.3 * MM, Z=0.1 * MM)
    for k in range(70):
        b.rapid(X=-0.5 * MM, Y=0.3 * MM + k * 20 * UM).rapid(Z=-5 * UM)
        b.linear(X=4.5 * MM, feed_mm_per_min=100.0).rapid(Z=0.1 * MM)
    b.rapid(X=2 * MM, Y=0.31 * MM).rapid(Z=-3 * UM).rapid(Y=1.69 * MM).rapid(Z=0.1 * MM)
    b.rapid(X=1 * MM, Y=0.3 * MM + 35 * 20 * UM).rapid(Z=-5 * UM).rapid(X=3 * MM)
    program = b.rapid(Z=0.1 * MM).build()
    moves = program.moves
    across, along = moves[-6].line, moves[-2].line
    assert moves[-6].target["Y"] == pytest.approx(1.69 * MM)
    assert moves[-2].target["X"] == pytest.approx(3 * MM)
    _, report = cut(program, "grooving_4axis", tool="v:90", stock="block:5x3x1")
    assert across in report.rapids_that_cut and along not in report.rapids_that_cut


def test_a_rapid_one_earlier_sweep_holds_is_judged_without_a_boolean(monkeypatch):
    # A star of 12 spokes, flat 0.5 mm end mill 0.1 mm deep, from a hub at (5, 5) mm; the
    # first spoke is cut in two feeds. Each later spoke begins with a rapid down to 0.05 mm
    # into the hub the spokes before cut (held whole by the rapid down of the spoke before:
    # not listed); a rapid back along the first spoke 0.05 mm deep spans its two feeds (no
    # one sweep holds it: judged by the union, not listed); the last rapid goes down to
    # 0.15 mm, 0.05 mm below the floor (listed). Asked without the holders (the union
    # alone): the same lines.
    from machinesim.cutting import rapids

    b = ProgramBuilder(1).rapid(X=5 * MM, Y=5 * MM, Z=1 * MM)
    b.linear(Z=-0.1 * MM, feed_mm_per_min=100.0).linear(X=6.5 * MM).linear(X=8 * MM)
    b.rapid(Z=1 * MM)
    for k in range(1, 12):
        a = 2 * math.pi * k / 12
        b.rapid(X=5 * MM, Y=5 * MM).rapid(Z=-0.05 * MM)
        b.linear(Z=-0.1 * MM, feed_mm_per_min=100.0)
        b.linear(X=(5 + 3 * math.cos(a)) * MM, Y=(5 + 3 * math.sin(a)) * MM)
        b.rapid(Z=1 * MM)
    b.rapid(X=5 * MM, Y=5 * MM).rapid(Z=-0.05 * MM).rapid(X=8 * MM).rapid(Z=1 * MM)
    b.rapid(X=5 * MM, Y=5 * MM).rapid(Z=-0.15 * MM).rapid(Z=1 * MM)
    program = b.build()
    crash = program.moves[-2].line
    assert program.moves[-2].target["Z"] == pytest.approx(-0.15 * MM)
    held = []
    real = rapids._Earlier.held
    monkeypatch.setattr(rapids._Earlier, "held",
                        lambda self, *args: held.append(real(self, *args)) or held[-1])
    _, report = cut(program, "grooving_4axis", tool="flat:0.5", stock="block:10x10x1")
    assert report.rapids_that_cut == (crash,)
    assert held.count(True) >= 11  # the hub's rapids down, each held by the one before
    monkeypatch.setattr(rapids, "RAPID_HOLDERS", 0)
    _, alone = cut(program, "grooving_4axis", tool="flat:0.5", stock="block:10x10x1")
    assert alone.rapids_that_cut == report.rapids_that_cut


def test_a_retract_after_turning_c_in_place_is_judged_by_the_last_sweeps():
    # the V tool 10 um deep at (1, 1) mm while C turns 90 deg: hundreds of sweeps over one
    # point, each overlapping the retract. The last of them took away all the retract meets
    # (not listed, and without a union of all of them); a rapid at that depth along X then
    # runs through stock the turn never reached (listed).
    b = ProgramBuilder(1).rapid(X=1 * MM, Y=1 * MM, Z=0.1 * MM, C=0.0)
    b.linear(Z=-10 * UM, feed_mm_per_min=100.0).linear(C=math.pi / 2, feed_mm_per_min=100.0)
    b.rapid(Z=0.1 * MM).rapid(C=0.0)
    b.rapid(X=1 * MM, Y=2.5 * MM).rapid(Z=-10 * UM).rapid(X=4 * MM).rapid(Z=0.1 * MM)
    program = b.build()
    _, report = cut(program, "grooving_4axis", tool="v:90", stock="block:5x3x1")
    assert report.sweeps > 100
    retract, crash = program.moves[3].line, program.moves[7].line
    assert crash in report.rapids_that_cut and retract not in report.rapids_that_cut


def test_feeds_are_listed_as_sideways_past_one_degree_not_for_a_machines_small_skew():
    # three feeds 10 um deep, each 2 mm along X with a Y component of tan(angle) times that:
    # 0.5 deg (a tool's flank clears it) and 2 deg (listed); then a groove along X on a
    # machine whose X axis is turned 3 urad about Z (EC0X): the engine's geometric count
    # sees that drag, the lines do not
    b = ProgramBuilder(1).rapid(Z=0.1 * MM)  # up first: the start is the block's corner
    for y, angle in ((0.5, 0.5), (1.5, 2.0)):
        b.rapid(X=1 * MM, Y=y * MM, Z=0.1 * MM).linear(Z=-10 * UM, feed_mm_per_min=100.0)
        b.linear(X=3 * MM, Y=(y + 2 * math.tan(math.radians(angle))) * MM,
                 feed_mm_per_min=100.0).rapid(Z=0.1 * MM)
    program = b.build()
    _, report = cut(program, "grooving_4axis", tool="v:90", stock="block:5x3x1")
    assert report.sideways_sweeps == 2
    assert report.sideways_lines == (program.moves[7].line,)
    skew = ErrorModel.from_dict({"location": {"X": {"EC0X_urad": 3.0}}})
    b = ProgramBuilder(1).rapid(Z=0.1 * MM).rapid(X=1 * MM, Y=1 * MM)
    b.linear(Z=-10 * UM, feed_mm_per_min=100.0).linear(X=3 * MM).rapid(Z=0.1 * MM)
    _, report = cut(b.build(), "grooving_4axis", tool="v:90", stock="block:5x3x1", errors=skew)
    assert report.sideways_sweeps == 1 and report.sideways_lines == ()


def test_turned_groups_list_the_same_sideways_feeds_as_the_plain_cut():
    # grooves at C = 0 and C = 90 deg: along X (clean), at 2 deg (listed), along Y (listed);
    # cut in turned groups (each in the frame turned back by its C) and plainly: the same
    # lines, since the drag's angle is the tool's own, whichever frame it is read in
    from machinesim.cutting.windows import cut_turned

    b = ProgramBuilder(1).rapid(Z=0.1 * MM)
    for c, (dx, dy) in ((0.0, (2.0, 0.0)), (0.0, (2.0, 2 * math.tan(math.radians(2.0)))),
                        (math.pi / 2, (0.0, 1.0))):
        b.rapid(X=-1.5 * MM, Y=-1.0 * MM, C=c).linear(Z=-10 * UM, feed_mm_per_min=100.0)
        b.linear(X=(-1.5 + dx) * MM, Y=(-1.0 + dy) * MM).rapid(Z=0.1 * MM)
    program = b.build()
    listed = [program.moves[k].line for k in (7, 11)]
    stock = "block:5x5x1@-2.5,-2.5,0"
    _, plain = cut(program, "grooving_4axis", tool="v:90", stock=stock)
    _, turned = cut_turned(program, "grooving_4axis", tool="v:90", stock=stock)
    assert plain.sideways_lines == turned.sideways_lines == tuple(listed)


def test_a_flat_end_mill_groove_removes_its_polygon_swept_along_the_feed():
    # plunge 10 um and feed 3 mm along X: the removed solid is the depth times the
    # Minkowski sum of the tool's polygon and the feed, whose area is the polygon's (by the
    # shoelace formula) plus the feed times its width across the feed
    depth, length = 10 * UM, 3 * MM
    tool = tool_from_spec("flat:0.5")
    x, y = tool.vertices()[: tool.segments, :2].T
    area = 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))
    b = ProgramBuilder(1).rapid(Z=0.1 * MM).rapid(X=1 * MM, Y=1.5 * MM)
    b.linear(Z=-depth, feed_mm_per_min=100.0).linear(X=1 * MM + length).rapid(Z=0.1 * MM)
    part, report = cut(b.build(), "grooving_4axis", tool=tool, stock="block:5x3x1")
    expected = depth * (area + length * (y.max() - y.min()))
    assert report.removed_volume_m3 == pytest.approx(expected, rel=1e-9, abs=0.0)
    assert part.manifold.volume() == pytest.approx(15 * MM**3 - expected, rel=1e-12)
    assert report.sideways_sweeps == 0  # a rotating tool cuts in any direction
    h = height_map(part, np.array([2.5 * MM]), np.array([1.5 * MM, 1.9 * MM, 2.1 * MM]))
    np.testing.assert_allclose(h[:, 0], [-depth, -depth, 0.0], atol=1e-15)


def test_the_command_line_cuts_and_writes_part_and_report(tmp_path, capsys):
    program = tmp_path / "grooves.nc"
    write_program(grooves(n=2, pitch=40 * UM), program)
    errors = tmp_path / "errors.toml"
    ErrorModel(tool=ToolSetting([0.0, 0.0, -1 * UM], [0.0, 0.0, 0.0])).to_toml(errors)
    out, report = tmp_path / "part.ply", tmp_path / "report.json"
    code = main(["cut", str(program), "--machine", "grooving_4axis", "--tool", "v:90",
                 "--stock", "block:5x3x1", "--errors", str(errors), "--out", str(out),
                 "--report", str(report), "--quiet"])
    assert code == 0
    data = json.loads(report.read_text())
    # depth 11 um with the 1 um setting error: 2 x 11^2 um^2 x 5 mm
    assert data["removed_volume_mm3"] == pytest.approx(2 * (11e-3) ** 2 * 5, rel=1e-9)
    assert out.stat().st_size > 0
    assert main(["cut", str(program), "--machine", "nope", "--tool", "v:90", "--stock",
                 "block:5x3x1", "--out", str(out)]) == 2
    assert "unknown machine 'nope'" in capsys.readouterr().err


def test_rapids_that_cut_are_cut_and_listed_with_their_lines():
    # A rapid plunge 5 um into the block, a rapid 3 mm along X through it (a crash), then
    # out: the part shows the 90-deg V the crash cut (section d^2), and both rapids are
    # listed; the plunge of the zero-thickness edge removes nothing itself.
    depth = 5 * UM
    b = ProgramBuilder(1).rapid(X=1 * MM, Y=1 * MM, Z=0.1 * MM).rapid(Z=-depth)
    program = b.rapid(X=4 * MM).rapid(Z=0.1 * MM).build()
    part, report = cut(program, "grooving_4axis", tool="v:90", stock="block:5x3x1")
    assert report.rapids_that_cut == (program.moves[1].line, program.moves[2].line)
    assert report.removed_volume_m3 == pytest.approx(depth**2 * 3 * MM, rel=1e-9, abs=0.0)
    assert not report.empty_cut
    h = height_map(part, np.array([2.5 * MM]), np.array([1 * MM]))[0, 0]
    assert h == pytest.approx(-depth, abs=1e-12)


def test_overtravel_is_an_error_naming_axis_value_travel_and_line_unless_allowed():
    b = ProgramBuilder(1).rapid(X=1 * MM, Y=1 * MM, Z=0.1 * MM).rapid(X=-300 * MM)
    program = b.rapid(X=1 * MM).build()
    line = program.moves[1].line
    with pytest.raises(AxisLimitError, match=rf"axis X = -300\.000000 mm at line {line} "
                                             r"outside its travel -250\.000000 mm \.\. 250"):
        cut(program, "grooving_4axis", tool="v:90", stock="block:5x3x1")
    _, report = cut(program, "grooving_4axis", tool="v:90", stock="block:5x3x1",
                    allow_overtravel=True)
    assert len(report.limit_violations) == 1
    assert f"axis X = -300.000000 mm at line {line}" in report.limit_violations[0]
    assert report.to_dict()["limit_violations"] == list(report.limit_violations)


def test_a_start_outside_the_travel_is_refused_naming_the_start_not_a_line():
    # C given in degrees (90 for 90 deg) at start: grooves never program C, so it stayed at
    # 90 rad and the refusal named the first block's line, which writes no C; grooving_4axis'
    # C travels one turn either way, 360 deg, and 90 rad is 5156.62016 deg
    start = [0.0, 0.0, 0.1, 90.0]
    with pytest.raises(AxisLimitError, match=r"^start: axis C = 5156\.62016 deg outside its "
                                             r"travel -360\.00000 deg \.\. 360\.00000 deg: "
                                             r".*start is in m and rad, in the order XYZC"):
        cut(grooves(), "grooving_4axis", tool="v:90", stock="block:5x3x1", start=start)
    _, report = cut(grooves(), "grooving_4axis", tool="v:90", stock="block:5x3x1",
                    start=start, allow_overtravel=True)
    assert report.limit_violations and "axis C = 5156.62016 deg" in report.limit_violations[0]
    machine = load_machine("grooving_4axis")  # the home is inside: cut as before
    assert cut(grooves(), machine, tool="v:90", stock="block:5x3x1",
               start=machine.home)[1].limit_violations == ()


def test_a_move_a_billion_metres_out_is_refused_even_with_overtravel_allowed():
    # a feed across the block to X = 1e9 m (1e12 mm, a length in the wrong unit): float64's
    # spacing there is 1.2e-7 m and the slot came out uncut, exit 0; 900 m out it cuts
    def slot(x_end):
        b = ProgramBuilder(1).rapid(X=1 * MM, Y=1 * MM, Z=0.1 * MM).linear(
            Z=-10 * UM, feed_mm_per_min=100.0)
        return b.linear(X=x_end, feed_mm_per_min=100.0).rapid(Z=0.1 * MM).build()

    far = slot(1e9)
    with pytest.raises(InputError, match=r"the move takes the tool 1e\+09 m from the "
                                         r"workpiece origin; expected within 1000 m") as info:
        cut(far, "grooving_4axis", tool="v:90", stock="block:5x3x1", allow_overtravel=True)
    assert info.value.line == far.moves[2].line
    _, near = cut(slot(900.0), "grooving_4axis", tool="v:90", stock="block:5x3x1",
                  allow_overtravel=True)  # 900 m out: the V's section over the block's 4 mm
    # to 1.5e-6 (measured): the sweep's ends 900 m apart, its round-off is the extent's
    assert near.removed_volume_m3 == pytest.approx((10 * UM) ** 2 * 4 * MM, rel=1e-5, abs=0.0)


def test_a_slow_move_far_out_is_refused_for_its_distance_not_for_its_time():
    # 1e9 m at F100 takes 6e11 s, beyond a program's 2**39 s: the planner's refusal of the
    # time had replaced the travel's and the distance's, the likelier cause; a program of a
    # time that long within the travel is still refused for it
    program = (ProgramBuilder(1).rapid(X=1 * MM, Y=1 * MM, Z=0.1 * MM)
               .linear(X=1e9, feed_mm_per_min=100.0).build())
    with pytest.raises(AxisLimitError, match=r"axis X = 1000000000000.000000 mm at line 2 "):
        cut(program, "grooving_4axis", tool="v:90", stock="block:5x3x1")
    slow = (ProgramBuilder(1).rapid(X=1 * MM, Y=1 * MM, Z=0.1 * MM).dwell(3e11).dwell(3e11)
            .build())
    with pytest.raises(NCProgramError, match="take more than 5.49756e"):
        cut(slow, "grooving_4axis", tool="v:90", stock="block:5x3x1")


def test_an_axis_value_at_the_float64_edge_is_named_in_six_digits():
    # X = 1e304 m (1e307 mm): the travel refusal had printed its 308 digits and 6 decimals
    program = ProgramBuilder(1).rapid(X=-1e304, Y=1 * MM, Z=0.1 * MM).build()
    with pytest.raises(AxisLimitError) as caught:
        cut(program, "grooving_4axis", tool="v:90", stock="block:5x3x1")
    assert "axis X = -1e+307 mm at line 1 outside its travel -250.000000 mm .. " in str(
        caught.value)
    assert len(str(caught.value)) < 400


def test_a_move_too_far_out_is_named_by_its_own_line_not_the_farthest_after_it():
    # 'G01 X1000000.' (1000 m, a length in the wrong unit) at line 5, then 'G00 Z1.' at
    # line 6: the rapid up is a millimetre farther from the origin, and the refusal had
    # named line 6, a block with no X word in it
    text = ("O1\nG90 G21\nG00 X5. Y5. Z1.\nG01 Z-0.1 F100.\nG01 X1000000.\nG00 Z1.\n"
            "M30\n")
    program = parse_program(text, "far.nc")
    with pytest.raises(InputError, match=r"far\.nc, line 5: the move takes the tool 1e\+03 m "
                                         r"from the workpiece origin \(the farthest, 1e\+03 "
                                         r"m, at line 6\); expected within 1000 m") as info:
        cut(program, "robonano_a0ib", tool="ball:0.5", stock="block:10x10x2",
            allow_overtravel=True)
    assert info.value.line == 5


def test_a_shank_wider_than_the_end_mill_crashes_into_a_slot_it_cannot_enter():
    # a 1 mm end mill with 3 mm of body cuts a slot 1 mm wide down in 0.5 mm levels; its
    # 4 mm shank cannot follow it below 3 mm: the level at 3.5 mm is the first crash. Taken as
    # wide as the tool (no d=), the holder follows the body down the slot it cut
    b = ProgramBuilder(1).rapid(X=3 * MM, Y=5 * MM, Z=1 * MM)
    for level in range(1, 10):
        b = b.linear(Z=-0.5 * MM * level, feed_mm_per_min=50.0).linear(
            X=(7 if level % 2 else 3) * MM, feed_mm_per_min=200.0)
    program = b.rapid(Z=1 * MM).build()
    crash = program.moves[1 + 2 * 6].line  # the plunge to Z -3.5 mm
    stock = "block:10x10x8"  # z from -8 mm to 0
    with pytest.raises(HolderContactError) as refused:
        cut(program, "grooving_4axis", tool="flat:0.5:h=3:d=4", stock=stock)
    message = str(refused.value)
    assert f"line {crash} " in message and "where its holder begins, 4 mm across" in message
    _, report = cut(program, "grooving_4axis", tool="flat:0.5:h=3", stock=stock)
    assert report.holder_contact == ()
    # the same shank over a slot no deeper than the body: nothing to hit
    shallow = ProgramBuilder(1).rapid(X=3 * MM, Y=5 * MM, Z=1 * MM).linear(
        Z=-3 * MM, feed_mm_per_min=50.0).linear(X=7 * MM, feed_mm_per_min=200.0).rapid(
        Z=1 * MM).build()
    _, report = cut(shallow, "grooving_4axis", tool="flat:0.5:h=3:d=4", stock=stock)
    assert report.holder_contact == ()


def test_a_cut_deeper_than_the_tool_is_refused_naming_its_line_or_cut_and_listed():
    # a V 20 um tall fed 30 um deep: the top of its body is 10 um under the stock's top
    tool = VTool(math.pi / 2, height=20 * UM)
    b = ProgramBuilder(1).rapid(X=-0.5 * MM, Y=1 * MM, Z=0.1 * MM).rapid(Z=-30 * UM)
    program = b.linear(X=5.5 * MM, feed_mm_per_min=500.0).rapid(Z=0.1 * MM).build()
    with pytest.raises(HolderContactError) as refused:
        cut(program, "grooving_4axis", tool=tool, stock="block:5x3x1")
    message = str(refused.value)
    assert f"line {program.moves[2].line} takes the top of the tool's body (0.02 mm" in message
    assert "top of the stock (z = 0 mm)" in message and "nothing was cut" in message
    part, report = cut(program, "grooving_4axis", tool=tool, stock="block:5x3x1",
                       allow_holder_contact=True)
    assert report.holder_contact == (program.moves[2].line,)
    # the body alone cuts its own V, 20 um from tip to top (section (20 um)^2 for a 90 deg
    # tip), over the block's 5 mm; the 10 um over it stays: the tunnel the refusal prevents
    assert report.removed_volume_m3 == pytest.approx((20 * UM) ** 2 * 5 * MM, rel=1e-9, abs=0.0)
    assert part.volume == pytest.approx(5 * MM * 3 * MM * 1 * MM - (20 * UM) ** 2 * 5 * MM,
                                        rel=1e-12)
    assert report.to_dict()["holder_contact_lines"] == [program.moves[2].line]
    _, clear = cut(grooves(n=1), "grooving_4axis", tool="v:90", stock="block:5x3x1")
    assert clear.holder_contact == ()


def test_a_slot_cut_in_steps_deeper_than_the_body_opens_the_way_for_its_holder():
    # A flat end mill with 2 mm of body cuts a slot 3 mm deep in 1 mm steps: on the last
    # pass its body's top is 1 mm under the block's top, inside the slot the earlier passes
    # cut, where its holder finds air. The same tool 20 mm tall cuts the same part; the
    # slot is the tool's face swept 6 mm along X, 3 mm deep (shoelace area of the facets).
    stock = "block:10x6x5@-5,-3,0"
    short = tool_from_spec("flat:1.0:h=2")
    _, report = cut(_slot_in_steps(3), "grooving_4axis", tool=short, stock=stock)
    _, tall = cut(_slot_in_steps(3), "grooving_4axis", tool="flat:1.0:h=20", stock=stock)
    face = np.asarray(short.vertices())
    face = face[np.abs(face[:, 2]) < 1e-12]
    face = face[np.argsort(np.arctan2(face[:, 1], face[:, 0]))]
    area = 0.5 * abs(np.dot(face[:, 0], np.roll(face[:, 1], 1))
                     - np.dot(face[:, 1], np.roll(face[:, 0], 1)))
    slot = 3 * MM * (area + 6 * MM * np.ptp(face[:, 1]))
    assert report.holder_contact == ()
    assert report.removed_volume_m3 == pytest.approx(slot, rel=1e-9)
    assert report.removed_volume_m3 == pytest.approx(tall.removed_volume_m3, rel=1e-12)
    # The last pass 0.5 mm to the side: its holder runs into the slot's wall, which no
    # earlier pass cut, and only that pass's feed and lift are named (its plunge's holder,
    # no wider than the body, follows it down the hole the plunge drills).
    program = _slot_in_steps(3, last_y=0.5 * MM)
    lines = [move.line for move in program.moves[-2:]]
    with pytest.raises(HolderContactError,
                       match=f"line {lines[0]} \\(lines {', '.join(map(str, lines))}\\)"):
        cut(program, "grooving_4axis", tool=short, stock=stock)


def test_a_10_nm_groove_on_a_100_mm_block_is_not_an_empty_cut():
    # Judged against the tool's swept size, not the stock's; integrated over the cut, so the
    # 2e-19 m^3 come out to 1e-6 although the block holds 2e-5 m^3.
    depth = 10e-9
    b = ProgramBuilder(1).rapid(X=40 * MM, Y=50 * MM, Z=0.1 * MM)
    b.linear(Z=-depth, feed_mm_per_min=100.0).linear(X=42 * MM).linear(Z=0.1 * MM)
    _, report = cut(b.build(), "grooving_4axis", tool="v:90", stock="block:100x100x2")
    assert not report.empty_cut and report.engine == "boolean"
    assert report.removed_volume_m3 == pytest.approx(depth**2 * 2 * MM, rel=1e-6, abs=0.0)


def test_a_short_tool_deep_in_an_open_slot_is_cut_and_in_solid_stock_is_refused():
    # A V 1 mm tall feeds 50 um into the floor of a slot 5 mm deep, right across the block:
    # its top is 4 mm under the block's top, but over it is the slot's air, not material.
    # The same feed into the solid block puts its holder into the part.
    tool = VTool(math.pi / 2, height=1 * MM)
    b = ProgramBuilder(1).rapid(X=-1 * MM, Y=5 * MM, Z=1 * MM).rapid(Z=-5.05 * MM)
    program = b.linear(X=11 * MM, feed_mm_per_min=500.0).rapid(Z=1 * MM).build()
    solid = block(10 * MM, 10 * MM, 6 * MM)
    slot = manifold3d.Manifold.cube((12 * MM, 4 * MM, 6 * MM)).translate((-1 * MM, 3 * MM,
                                                                          -5 * MM))
    slotted = Part(solid.manifold - slot)
    _, report = cut(program, "grooving_4axis", tool=tool, stock=slotted)
    # the 90-deg V's section (50 um)^2 over the block's 10 mm; the box test's candidate is
    # cleared by the material, so nothing is listed
    assert report.removed_volume_m3 == pytest.approx((50 * UM) ** 2 * 10 * MM, rel=1e-9, abs=0.0)
    assert report.holder_contact == ()
    with pytest.raises(HolderContactError, match=f"line {program.moves[2].line} takes"):
        cut(program, "grooving_4axis", tool=tool, stock=solid)


@pytest.mark.parametrize("text, line, words", [
    ("G21 G90 G94\nG00 X4. Z1. C0.\nG01 Z-0.01 F100.\nG01 C90. F3600.\nG00 Z1.\n", 4,
     "turns the work spindle C of sts_lathe \\(0 to 90 deg\\)"),
    ("G21 G90 G94\nM03 S1000\nG00 X4. Z1. C0.\nG01 Z-0.01 F100.\nX0. F20.\n", 2,
     "M03 runs the work spindle C"),
])
def test_turning_on_a_lathe_is_refused_by_cut_and_named(text, line, words):
    # `cut` would draw one line of the edge a move (a nose tool turning in its own plane):
    # scratches with exit 0, or minutes over a quarter turn. It names the line and the way.
    program = parse_program(text)
    with pytest.raises(NCProgramError, match=f"line {line}: .*{words}.*lathe.turn"):
        cut(program, "sts_lathe", tool="nose:0.5:90", stock="cylinder:5x2")
    # a C that is a table (travel of two turns) turns under a cut; the lathe's is a spindle
    assert not load_machine("grooving_4axis").axis("C").spindle
    assert load_machine("sts_lathe").axis("C").spindle


@pytest.mark.parametrize(("cutter", "flag"), [
    (cutter, flag) for cutter in ("cut", "cut_turned", "lab")
    for flag in ("allow_overtravel", "allow_holder_contact")] + [("turn", "allow_overtravel")])
def test_a_flag_that_is_not_true_or_false_is_refused_not_read_as_true(flag, cutter):
    # allow_overtravel="no" (a string, so true) cut a program 60 mm past X's travel and
    # only listed it in the report, exit 0; a lab's turn did the same with its own flag
    from machinesim import Lab
    from machinesim.cutting import cut_turned
    from machinesim.nc import parse_program

    far = ProgramBuilder(1).rapid(X=1 * MM, Y=1 * MM, Z=0.1 * MM).rapid(X=300 * MM).build()
    if cutter == "turn":
        lathe = Lab("sts_lathe", noise=False)
        program = parse_program("G90 G21\nG00 X150. Z0.01 C0\nG01 Z-0.001 F10\n"
                                "G01 X0 C3600 F36000\n")  # X's travel is +-100 mm
        with pytest.raises(InputError, match=r"allow_overtravel as True or False, got 'no'"):
            lathe.turn(program, allow_overtravel="no")
        with pytest.raises(AxisLimitError):
            lathe.turn(program, allow_overtravel=np.bool_(False))
        return
    run = {"cut": lambda **o: cut(far, "grooving_4axis", "v:90", "block:5x3x1", **o),
           "cut_turned": lambda **o: cut_turned(far, "grooving_4axis", "v:90", "block:5x3x1",
                                                **o),
           "lab": lambda **o: Lab("grooving_4axis", noise=False).cut(far, "v:90",
                                                                     "block:5x3x1", **o)}
    with pytest.raises(InputError, match=rf"{flag} as True or False, got 'no'") as info:
        run[cutter](**{flag: "no"})
    assert info.value.key == flag
    with pytest.raises(AxisLimitError):  # False and numpy's False are False
        run[cutter](**{flag: np.bool_(False)})


@pytest.mark.parametrize(("turn_step", "shown"), [("0.5", "'0.5'"), (True, "True"),
                                                  (None, "None"), (0.0, "0.0")])
def test_a_turn_step_that_is_no_positive_angle_is_refused_naming_it(turn_step, shown):
    # cut_turned(..., turn_step="0.5") (and Lab.cut's) ended in TypeError: must be real
    # number, not str, from math.isfinite; True was taken as a step of 1 rad
    from machinesim.cutting import cut_turned

    with pytest.raises(InputError, match=rf"turn_step .*\(rad\), got {shown}") as info:
        cut_turned(grooves(1), "grooving_4axis", "v:90", "block:5x3x1", turn_step=turn_step)
    assert info.value.key == "turn_step"
