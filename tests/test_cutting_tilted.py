"""A tool tilted in the workpiece frame is cut in its own frame (`machinesim.cutting.frame`).

A workpiece set with a tilt turns every sweep, and the faces sweeps share (an end mill's
flat end on every sweep of a pass) then coincide only to round-off: cut where they stand,
they broke the floor into slivers (a quarter circle of an end mill: 105,000 triangles; one
circle on the README's example errors: 1.7 million, and two levels ran out of memory).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import machinesim.cutting.engine as engine
import machinesim.cutting.footprints as footprints
from machinesim.cutting import cut
from machinesim.cutting.frame import flat_end, into_frame, out_of_frame, tool_frame
from machinesim.errors import ErrorModel
from machinesim.exceptions import HolderContactError
from machinesim.rotations import rot_x, rot_y, rot_z
from machinesim.tool_specs import tool_from_spec
from machinesim.workpiece import stock_from_spec

#: A quarter circle of a 0.4 mm end mill, 0.2 mm deep, on grooving_4axis (mm).
QUARTER = """%
O1 (quarter circle)
G90 G21 G17 G94
G00 X1. Y0. Z1.
G01 Z-0.2 F300.
G03 X0. Y1. I-1. J0. F300.
G00 Z1.
M30
%
"""
TILT = {"workpiece": {"alpha_deg": 0.01, "beta_deg": -0.02}}
STOCK = "block:4x4x2@-2,-2,0"


@pytest.fixture(scope="module")
def quarter(tmp_path_factory):
    path = tmp_path_factory.mktemp("tilted") / "quarter.nc"
    path.write_text(QUARTER)
    return path


def _cut(program, errors):
    return cut(program, "grooving_4axis", tool="flat:0.4", stock=STOCK,
               errors=None if errors is None else ErrorModel.from_dict(errors))


def test_a_tilted_cut_is_the_cut_made_where_the_tool_stands(quarter, monkeypatch):
    """Second method: the same cut in the workpiece frame, sweep by sweep as before."""
    part, report = _cut(quarter, TILT)
    monkeypatch.setattr(engine, "tool_frame", lambda poses, tool: None)
    where, where_report = _cut(quarter, TILT)
    assert report.removed_volume_m3 == pytest.approx(where_report.removed_volume_m3, rel=1e-12)
    assert part.volume == pytest.approx(where.volume, rel=1e-12)
    # the parts differ by round-off: less than a 1e-15 m film over the cut's 1.5 mm^2
    apart = (part.manifold - where.manifold).volume() + (where.manifold - part.manifold).volume()
    assert apart < 1e-15 * 1.5e-6
    # and the frame's floor is whole: no more triangles than the same cut on an upright
    # block, its passes united in 3-D as the frame's are (on the tilted floor no two sweeps
    # share a level floor, so none is united by its footprint)
    monkeypatch.setattr(footprints, "FEWEST", 10 ** 9)
    upright, _ = _cut(quarter, None)
    assert part.triangle_count <= 2 * upright.triangle_count
    assert where.triangle_count > 10 * upright.triangle_count  # the slivers it avoids


def test_levels_on_a_tilted_block_lie_inside_the_deepest_where_the_tool_stands(tmp_path):
    """Two levels of one arc: where the tool stands the upper level is the lower one moved
    up along the tool, inside it, so the two remove what the lower level alone does."""
    both, lowest = tmp_path / "levels.nc", tmp_path / "lowest.nc"
    both.write_text(QUARTER.replace(
        "G00 Z1.\nM30", "G00 Z1.\nG00 X1. Y0.\nG01 Z-0.4\nG03 X0. Y1. I-1. J0.\nG00 Z1.\nM30"))
    lowest.write_text(QUARTER.replace("Z-0.2", "Z-0.4"))
    part, report = _cut(both, TILT)
    alone, alone_report = _cut(lowest, TILT)
    assert report.removed_volume_m3 == pytest.approx(alone_report.removed_volume_m3, rel=1e-12)
    assert part.triangle_count <= 2 * alone.triangle_count


END_MILL = tool_from_spec("flat:0.4")


@pytest.mark.parametrize("turn", [np.eye(3), rot_z(0.3)])
def test_an_upright_tool_keeps_the_workpiece_frame(turn):
    poses = np.tile(np.eye(4), (3, 1, 1))
    poses[:, :3, :3] = turn
    assert tool_frame(poses, END_MILL) is None


def test_a_tool_that_turns_keeps_the_workpiece_frame():
    poses = np.tile(np.eye(4), (2, 1, 1))
    poses[0, :3, :3] = rot_x(1e-4)
    poses[1, :3, :3] = rot_x(1e-4) @ rot_y(1e-9)
    assert tool_frame(poses, END_MILL) is None
    poses[1, :3, :3] = poses[0, :3, :3]
    assert np.array_equal(tool_frame(poses, END_MILL), rot_x(1e-4))


@pytest.mark.parametrize("spec", ["ball:0.5", "v:90", "nose:2:60"])
def test_a_tool_without_a_flat_end_keeps_the_workpiece_frame(spec):
    """Only an end mill's flat end is shared by every sweep of a level pass; a ball's, a V's
    or a round nose's lowest point is one vertex (`frame.flat_end`)."""
    poses = np.tile(np.eye(4), (2, 1, 1))
    poses[:, :3, :3] = rot_x(1e-4)
    assert not flat_end(tool_from_spec(spec)) and flat_end(END_MILL)
    assert tool_frame(poses, tool_from_spec(spec)) is None


def test_the_frame_turns_there_and_back():
    stock = stock_from_spec(STOCK)
    frame = rot_x(3e-4) @ rot_y(-2e-4) @ rot_z(0.01)
    poses = np.tile(np.eye(4), (2, 1, 1))
    poses[:, :3, :3] = frame
    poses[:, :3, 3] = [[1e-3, 0.0, -2e-4], [0.0, 1e-3, -2e-4]]
    turned, paths = into_frame(stock, [poses], frame)
    assert np.array_equal(paths[0][:, :3, :3], np.tile(np.eye(3), (2, 1, 1)))
    # the tip where it was: frame @ (turned tip) is the tip in the workpiece frame
    assert np.allclose(paths[0][:, :3, 3] @ frame.T, poses[:, :3, 3], rtol=0, atol=1e-18)
    back = out_of_frame(turned, frame)
    assert np.allclose(back.bounds, stock.bounds, rtol=0, atol=1e-18)
    assert back.volume == pytest.approx(stock.volume, rel=1e-14)


def test_windows_are_boxes_of_the_workpiece_frame(quarter):
    """A window cut in the tool's frame is the stock inside the window, as without tilt:
    the windowed part is the whole part clipped to the window (second method)."""
    window = (0.0, 1.5e-3, 0.0, 1.5e-3)
    whole, _ = _cut(quarter, TILT)
    part, _ = cut(quarter, "grooving_4axis", tool="flat:0.4", stock=STOCK,
                  errors=ErrorModel.from_dict(TILT), roi=[window])
    low, high = part.bounds
    assert low[0] == pytest.approx(0.0, abs=1e-15) and high[0] == pytest.approx(1.5e-3, abs=1e-15)
    from machinesim.cutting.windows import clip_to
    clipped = clip_to(whole, [window])
    assert part.volume == pytest.approx(clipped.volume, rel=1e-12)


def test_a_retract_from_a_tilted_pass_cuts_nothing_and_is_not_called_a_cut(tmp_path):
    """A face raster of five rows on a tilted block (`models/errors/example.toml`), then
    G00 Z1. straight up the tool: the engine removes the same volume with and without the
    retract (to round-off), and the rapid check, judged where the tool stands, does not call
    the retract a cut. In the workpiece frame its booleans did (line 15), with and without
    the engine's frame: the retract's faces meet the last pass's only to round-off."""
    rows = ["G00 X-3. Y-3. Z1.", "G01 Z-0.01 F300."]
    for k in range(5):
        rows.append(f"G01 X{3.0 if k % 2 == 0 else -3.0:.1f} Y{-3.0 + 0.3 * k:.1f}")
        if k < 4:
            rows.append(f"G01 Y{-3.0 + 0.3 * (k + 1):.1f}")
    body = "%\nO1 (facing)\nG90 G21 G17 G94\n" + "\n".join(rows)
    retract, ends = tmp_path / "retract.nc", tmp_path / "ends.nc"
    retract.write_text(body + "\nG00 Z1.\nM30\n%\n")
    ends.write_text(body + "\nM30\n%\n")
    assert retract.read_text().splitlines()[14] == "G00 Z1."  # line 15
    example = ErrorModel.from_toml(Path(__file__).resolve().parents[1] / "models" / "errors"
                                   / "example.toml")
    kwargs = {"tool": "flat:0.8", "stock": "block:8x8x4@-4,-4,0", "errors": example}
    part, report = cut(retract, "grooving_4axis", **kwargs)
    alone, alone_report = cut(ends, "grooving_4axis", **kwargs)
    assert abs(report.removed_volume_m3 - alone_report.removed_volume_m3) < 1e-21
    assert 15 not in report.rapids_that_cut


def test_a_holder_in_the_slot_its_own_levels_cut_meets_nothing_on_a_tilted_block(tmp_path):
    """Three levels of a quarter circle, 0.3 mm apart, with a body 0.5 mm long: from the
    second level down the body's top is below the stock's, but the holder's room (the body's
    section, lifted along the tool) lies in the slot the levels above cut, where the tool
    stands (the same path in the machine). Judged in the workpiece frame the booleans left
    material in it and refused the cut as a crash; a plunge 0.9 mm deep at once is one."""
    levels = ["G00 X1. Y0. Z1."]
    for depth in ("-0.3", "-0.6", "-0.9"):
        levels += [f"G01 Z{depth} F300.", "G03 X0. Y1. I-1. J0.", "G00 Z1.", "G00 X1. Y0."]
    program = tmp_path / "levels.nc"
    program.write_text("%\nO1\nG90 G21 G17 G94\n" + "\n".join(levels) + "\nM30\n%\n")
    kwargs = {"tool": "flat:0.4:h=0.5", "stock": STOCK, "errors": ErrorModel.from_dict(TILT)}
    part, report = cut(program, "grooving_4axis", **kwargs)
    assert report.holder_contact == ()
    alone = tmp_path / "alone.nc"
    alone.write_text("%\nO1\nG90 G21 G17 G94\n" + "\n".join(levels[:1] + levels[9:])
                     + "\nM30\n%\n")
    with pytest.raises(HolderContactError):
        cut(alone, "grooving_4axis", **kwargs)
