"""Paper 000's scenario script (scenarios/tool_rotation_arm.py): the paper's case reported,
an error file and its own options on top, a MachineSimError ended with one line."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from tool_rotation_arm_helpers import PAPER_E, PAPER_R

from machinesim import load_machine
from machinesim.identification import tool_rotation_arm as arm
from machinesim.report import check_summary

MM, UM, NM = 1e-3, 1e-6, 1e-9
ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def machine():
    return load_machine("planer_4axis")


@pytest.fixture(scope="module")
def r0(machine):
    return arm.arm_radius(machine)


def scenario(*args, cwd=ROOT):
    return subprocess.run([sys.executable, str(ROOT / "scenarios" / "tool_rotation_arm.py"),
                           *args], capture_output=True, text=True, check=False, cwd=cwd)


def test_the_scenario_reports_the_papers_case(tmp_path, r0):
    result = scenario("--realism", "ideal", "--out", str(tmp_path))
    assert result.returncode == 0, result.stderr
    assert "> 50" in result.stdout and "< 1" in result.stdout
    summary = json.loads((tmp_path / "summary.json").read_text())
    check_summary(summary)
    assert (summary["paper"], summary["procedure"], summary["machine"]) == (
        "000", "tool_rotation_arm", "planer_4axis")
    # the paper's r = 120.555 mm and e_ys = -178 um, as the tool setting (1e-18 m: the
    # subtraction r - r0 of two ~0.12 m numbers)
    assert summary["injected"].keys() == {"tool.y", "tool.z"}
    assert summary["injected"]["tool.y"] == -178.0 * UM
    assert summary["injected"]["tool.z"] == pytest.approx(-(PAPER_R - r0), abs=1e-18)
    identified = {name: entry["value"] for name, entry in summary["identified"].items()}
    # noise off: the display rounding leaves <= 1.8 nm on r and 0.65 nm on e_ys (see above)
    assert r0 - identified["tool.z"] == pytest.approx(PAPER_R, abs=1.8e-9)
    assert identified["tool.y"] == pytest.approx(PAPER_E, abs=0.65e-9)
    figures = {f["name"]: f for f in summary["figures"]}
    assert figures["depth_error"]["before"] > 50.0
    assert figures["depth_error"]["note"] == "paper: > 50 before, < 1 after"
    # < 1 nm with the formulas' exact axis values; the NC program's 1 nm grid adds up to 1 nm
    # (test_identification_and_compensation_without_noise)
    assert figures["depth_variation"]["after"] < 2e-3
    # the generic fit agrees with eq 1's fit to round-off (test below)
    assert abs(summary["details"]["fit_check"]["r_difference_nm"]) < 1e-3
    assert abs(summary["details"]["fit_check"]["e_ys_difference_nm"]) < 1e-3
    for name in ("calibration.ply", "pattern_before.ply", "pattern_after.ply",
                 "pattern_compensated.nc", "pattern_depth.png", "identification.md",
                 "figures.md", "identified.json"):
        assert (tmp_path / name).stat().st_size > 0


def test_the_scenario_takes_an_error_file_and_its_own_options_on_top(tmp_path, r0):
    errors = tmp_path / "errors.toml"
    errors.write_text("[tool]\noffset_um = [0.0, 120.0, 30.0]\n"
                      "[workpiece]\ndelta_um = [0.0, 0.0, 4.0]\n")
    result = scenario("--realism", "ideal", "--errors", str(errors), "--r-mm", "120.48",
                      "--out", str(tmp_path / "out"))
    assert result.returncode == 0, result.stderr
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    injected = summary["injected"]
    assert injected["tool.y"] == pytest.approx(120.0 * UM, abs=1e-18)  # from the file
    assert injected["tool.z"] == pytest.approx(-(120.48 * MM - r0), abs=1e-18)  # --r-mm
    assert injected["workpiece.z"] == pytest.approx(4.0 * UM, abs=1e-18)
    identified = {name: entry["value"] for name, entry in summary["identified"].items()}
    # the workpiece height goes into eq 1's offset, not into r or e_ys (bounds as above)
    assert identified["tool.y"] == pytest.approx(120.0 * UM, abs=0.65e-9)
    assert identified["tool.z"] == pytest.approx(injected["tool.z"], abs=1.8e-9)


def test_the_scenario_ends_a_machinesim_error_with_one_line(tmp_path):
    # an arm 1.2 mm long: the edge 1.2 mm low, beyond the ramps' 1 mm capture range
    for options, message in ((("--r-mm", "121.7"), "exceeds the plan's capture range 1 mm"),
                             (("--r-mm", "121.7", "--capture-mm", "0"),
                              "--capture-mm 0.0: expected a length in mm above 0"),
                             (("--r-mm", "121", "--capture-mm", "0.3"),
                              "exceeds the plan's capture range 0.3 mm"),
                             (("--r-mm", "-5"), "--r-mm -5.0: expected the arm radius, a "
                              "length in mm above 0 (the nominal arm is r0 = 120.500 mm")):
        result = scenario("--realism", "ideal", *options, "--out", str(tmp_path))
        assert result.returncode == 2
        assert "Traceback" not in result.stderr
        # the steps begun before it (progress), then the error: one line, last
        *steps, last = result.stderr.splitlines()
        assert all(line.startswith("tool_rotation_arm [") for line in steps), steps
        assert last.startswith("tool_rotation_arm: error: ") and message in last
