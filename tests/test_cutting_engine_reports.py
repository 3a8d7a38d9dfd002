"""What remove reports (empty, sideways and degenerate sweeps), how it tells its progress, and
what it refuses, naming it."""

import math
import re

import numpy as np
import pytest
from cutting_engine_helpers import METHODS, groove_x, groove_y, pose

from machinesim.cutting import remove
from machinesim.exceptions import InputError
from machinesim.tools import BallEndMill, VTool
from machinesim.workpiece import block


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
