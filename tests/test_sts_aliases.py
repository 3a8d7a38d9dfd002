"""Paper 004's tool test: the error terms it reads as the tool's, from the machine's model."""

from __future__ import annotations

import importlib.util
from dataclasses import replace
from pathlib import Path

import pytest

import machinesim
from machinesim.errors import ComponentError
from machinesim.machines import load_machine
from machinesim.procedures.sts_aliases import tool_test_aliases
from machinesim.procedures.sts_plans import TEST_SPHERE
from machinesim.procedures.sts_turning import STSTurning
from machinesim.report import ReportFolder

NOSE = STSTurning().nose_radius
ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def aliases():
    return {(a.term, a.form): a for a in tool_test_aliases(load_machine("sts_lathe"), NOSE)}


def test_the_aliases_are_those_derived_by_hand(aliases):
    """The sphere is cut about the spindle axis, so an axis off by EX0C is a tool off by
    -EX0C (dx); a tool tilted by ry moves its nose centre, R above the tip, by R ry; a
    straightness slope of X in Z (EZX = c1 X) raises the tip at X by c1 X, where the tip
    of a nose-compensated path on a sphere of radius Rs lies at X = rho (1 + R / Rs), and
    dx moves the sphere by -tan(phi) = -rho / Rs (to first order): the cone of dx times
    -c1 (Rs + R)."""
    got = {key: (a.reading, a.per_unit) for key, a in aliases.items()}
    assert got[("location.C.EX0C", "")] == ("tool.x", pytest.approx(-1.0, abs=1e-9))
    assert got[("location.C.EY0C", "")] == ("tool.y", pytest.approx(-1.0, abs=1e-9))
    assert got[("tool.ry", "")] == ("tool.x", pytest.approx(NOSE, rel=1e-9))
    assert got[("tool.rx", "")] == ("tool.y", pytest.approx(-NOSE, rel=1e-9))
    reading, per_unit = got[("component.X.EZX", "slope")]
    assert reading == "tool.x"
    assert per_unit == pytest.approx(TEST_SPHERE.radius + NOSE, rel=5e-3)
    # a piston (the tool's or the workpiece's height) and the part's place are the fits'
    # own nuisances, not tool errors
    for term in ("tool.z", "workpiece.z", "workpiece.x", "workpiece.y"):
        assert (term, "") not in aliases


def test_a_cut_with_a_straightness_slope_moves_dx_by_the_predicted_amount(aliases):
    """A straightness slope of X in Z (EZX, 0.05 um/mm) put the identified tool.x about 150
    nm off against a std of 3.4 nm, with no word: the test reads it as dx. A second method:
    the lab's cut and fit of the test pieces with the slope and without it."""
    slope = 0.05e-3  # 0.05 um/mm
    base = machinesim.ErrorModel().with_parameters(
        {"tool.x": -3.5e-6, "tool.y": -3.5e-6, "tool_geometry.nose_radius": 100e-6})
    sloped = replace(base, component={"X": {"EZX": ComponentError("poly", None,
                                                                  [0.0, slope])}})
    found = [STSTurning().measure(machinesim.Lab("sts_lathe", errors, noise=False))[
        "tool_test"] for errors in (base, sloped)]
    predicted = aliases[("component.X.EZX", "slope")].per_unit * slope
    assert predicted == pytest.approx(150e-9, rel=5e-3)
    assert found[1].dx - found[0].dx == pytest.approx(predicted, abs=1e-9)


def test_the_scenario_reports_the_aliases(tmp_path):
    spec = importlib.util.spec_from_file_location("sts_turning_scenario",
                                                  ROOT / "scenarios" / "sts_turning.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    text = module.alias_table(ReportFolder(tmp_path / "out"), load_machine("sts_lathe"))
    rows = {tuple(c.strip() for c in line.split("|")[1:4]): [c.strip() for c in
                                                            line.split("|")[4:-1]]
            for line in text.splitlines() if line.startswith("| component") or
            line.startswith("| location")}
    # read as dx, while the tool against the spindle axis does not move: the test's error.
    # By hand, in the file's units: (Rs + R) = 3 mm of dx per m/m of slope is 3 mm * 1e-3
    # (m/m per um/mm) = 3 um, 3000 nm per um/mm (to 0.5 %, as the first test)
    read, against, unit = rows[("component.X.EZX", "slope", "tool.x")][:3]
    assert float(read) == pytest.approx((TEST_SPHERE.radius + NOSE) * 1e-3 * 1e9, rel=5e-3)
    assert abs(float(against)) < 5e-5 and unit == "um/mm"
    # read as dx, and the tool against the axis moves as much: what the test reads
    assert rows[("location.C.EX0C", "-", "tool.x")][:3] == ["-1000.0000", "-1000.0000", "um"]
    assert "Computed from the machine's model" in text
