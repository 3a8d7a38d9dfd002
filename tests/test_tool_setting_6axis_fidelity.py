"""Paper 001 as a real lab would see it: the C triangle placed by its reference mark (the
microscope does not know the workpiece origin), and the error budget in the report."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from machinesim import ErrorModel, Lab
from machinesim.budget import Budget, quadrature_share
from machinesim.cam.tool_setting_plates import C_TURNS, TRIANGLE_R, mark_point
from machinesim.experiment import run
from machinesim.identification.tool_setting_6axis import c_axis_triangle
from machinesim.procedures.tool_setting_6axis import ToolSetting6Axis
from machinesim.realism import Realism
from machinesim.report import check_summary
from machinesim.rotations import rot_z

UM, MM = 1e-6, 1e-3
ROOT = Path(__file__).resolve().parents[1]


def turned(points, angle, about=(0.0, 0.0)):
    about = np.asarray(about)
    return (np.asarray(points) - about) @ rot_z(angle)[:2, :2].T + about


def test_the_mark_places_the_triangle_whatever_the_stage_did():
    e = np.array([100.0, 850.0]) * UM
    x = np.linspace(-2, 2, 5) * MM
    side = np.column_stack([x, np.full(5, -TRIANGLE_R)])
    sides = [turned(side, c, e) for c in C_TURNS]  # one groove turned about e (paper Fig. 3)
    mark = mark_point() + np.column_stack([np.zeros(4), np.array([-1, -0.5, 0.5, 1]) * MM])
    # the microscope's frame: turned by 1.3 mrad and shifted by (6, -4) um from the part's
    rotation, offset = 1.3e-3, np.array([6.0, -4.0]) * UM
    seen = [turned(p - offset, -rotation) for p in (*sides, mark)]
    placed = c_axis_triangle(seen, mark_at=mark_point())
    np.testing.assert_allclose(placed.centre, e, atol=1e-12)
    assert placed.rotation == pytest.approx(-rotation, abs=1e-12)
    # read in the microscope's frame alone, the stage's offset and rotation would be in it
    absolute = c_axis_triangle(seen[:3]).centre
    assert np.linalg.norm(absolute - e) > 5 * UM
    with pytest.raises(Exception, match="mark_at"):
        c_axis_triangle(seen)


def test_with_the_stage_registration_c_is_off_only_by_the_residual_tool_offset():
    """The mark is cut with the A stage's dx, dy compensated: it lands off its programmed
    crossing by the residual offset d - d_identified, across the C = 0 side (A = 0) by its
    y and across the mark (A = 90 deg, Rz(90) d) by minus its y. So e comes out off by
    exactly (-1, +1) times the error of the identified dy, whatever the stage did."""
    truth = {"tool.x": 250 * UM, "tool.y": 350 * UM, "tool.z": 150 * UM,
             "location.C.EX0C": 100 * UM, "location.C.EY0C": 850 * UM}
    lab = Lab("robonano_ui", ErrorModel().with_parameters(truth), seed=0,
              realism=Realism.with_only("registration"))
    result = run(ToolSetting6Axis(), lab)
    error = {name: value - truth[name] for name, (value, _) in result.identified.items()}
    drawn = lab.reveal_instruments()["microscope/c"]["registration"]
    assert np.linalg.norm(drawn.offset[:2]) > 1 * UM and abs(drawn.rotation) > 1e-4
    # 5 nm: the readings' own scatter (display rounding, the spot-free sections)
    assert error["location.C.EX0C"] == pytest.approx(-error["tool.y"], abs=5e-9)
    assert error["location.C.EY0C"] == pytest.approx(error["tool.y"], abs=5e-9)
    # and after compensation the triangle sits on its mark to the same few nanometres
    assert abs(result.figure("c_dx").after) < 0.01 and abs(result.figure("c_dy").after) < 0.01


def test_the_scenario_writes_its_error_budget(tmp_path):
    result = subprocess.run([sys.executable, str(ROOT / "scenarios" / "tool_setting_6axis.py"),
                             "--realism", "noise_only", "--out", str(tmp_path)],
                            capture_output=True, text=True, check=False, cwd=ROOT)
    assert result.returncode == 0, result.stderr
    summary = json.loads((tmp_path / "summary.json").read_text())
    check_summary(summary)
    budget = Budget.from_dict(summary["budget"])
    assert budget.sources == ("instrument_noise",)
    figures = {f["name"]: f for f in summary["figures"]}
    assert set(budget.figures) == set(figures)
    for row in budget.rows:
        assert row.after_all == figures[row.figure]["after"]
        assert row.share == quadrature_share(row.after_all, row.after_without)
        assert abs(row.after_without) < 1e-3  # noise off: below 1 nm
    assert (tmp_path / "budget.png").stat().st_size > 0 and "### Error budget" in result.stdout
    # stderr tells each step as it begins and ends, the run's then the budget rerun's
    steps = [line.split("] ", 1)[1] for line in result.stderr.splitlines()]
    assert all(line.startswith("tool_setting_6axis [") for line in result.stderr.splitlines())
    expected = [f"{stage}: {step} {when}" for stage in ("run", "budget, instrument_noise off")
                for step in ("measure", "identify", "compensate", "evaluate")
                for when in ("...", "done in")]
    assert [line[:len(want)] for line, want in zip(steps, expected, strict=True)] == expected
