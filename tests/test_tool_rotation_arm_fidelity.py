"""Paper 000 as a real lab would see it: a capture range derived from the plan, the
microscope's stage rotation found and taken out, the paper's "before", and the error budget
in the scenario's report."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from machinesim import ErrorModel, Lab, load_machine
from machinesim.budget import Budget, quadrature_share
from machinesim.cam.prisms import SEARCH_MARGIN_M, CalibrationPlan
from machinesim.exceptions import HolderContactError, InputError
from machinesim.identification.tool_rotation_arm import arm_radius
from machinesim.procedures.tool_rotation_arm import ToolRotationArm, holder_depth, max_capture
from machinesim.realism import Realism
from machinesim.report import check_summary

MM, UM, NM = 1e-3, 1e-6, 1e-9
ROOT = Path(__file__).resolve().parents[1]
MACHINE = load_machine("planer_4axis")
R0 = arm_radius(MACHINE)
#: Paper 000: r = 120.555 mm, e_ys = -0.178 mm; depth error "over 50 um" before.
PAPER_R, PAPER_E, PAPER_BEFORE_UM = 120.555 * MM, -0.178 * MM, 50.0


def arm_errors(rho, e_ys):
    return ErrorModel().with_parameters({"tool.y": e_ys, "tool.z": -rho})


def test_the_search_range_and_spacing_follow_from_the_capture_range():
    plan = CalibrationPlan()
    assert plan.capture == 1.0 * MM
    # search = capture + the deepest station (16 um and 8/9 nm of dither) + the margin
    assert plan.search == pytest.approx(1.0 * MM + 16 * UM + 8e-9 / 9 + SEARCH_MARGIN_M,
                                        abs=1e-15)
    assert plan.clearance > plan.search
    # by hand: the next groove (40 deg) deeper by 2 sin(5 deg) x 1 mm + 16 um + 20 um, its
    # low flank 5 deg from the surface, plus the window, the capture and 0.1 mm
    depth = 2 * math.sin(math.radians(5)) * MM + 16 * UM + 8e-9 / 9 + 20 * UM
    expected = plan.search + 0.25 * MM + 1 * MM + depth / math.tan(math.radians(5)) + 0.1 * MM
    assert plan.spacing == pytest.approx(expected, abs=1e-12)
    small = CalibrationPlan(capture=0.1 * MM)
    assert small.spacing == 3 * MM  # the old spacing where the capture needs no more
    # the first ramp in from the block's low-y edge by at least its window and 0.1 mm of
    # land: 1.036 + 0.25 + 0.1 = 1.386 mm (it was 1 mm, so a groove moved 0.995 mm towards
    # -y lay 5 um from the edge, its 16 um half width off the block); the 0 deg ramp's
    # deepest cut needs more (test_the_calibration_block_holds_every_ramps_deepest_cut)
    assert plan.window + 0.1 * MM == pytest.approx(1.386 * MM + 8e-9 / 9, abs=1e-15)
    assert plan.edge(0, plan.ramp[0])[0] - plan.origin[1] == pytest.approx(plan.lead)
    assert small.lead == 1 * MM


def test_the_calibration_block_holds_the_ramps_deepest_cut():
    """The ramps end search = 1.036 mm below the top and an edge offset within the 1 mm
    capture cuts up to 1 mm lower again: 2.036 mm (the block was 1 mm thick, so even the
    errorless edge cut 36 um out through its bottom). By hand, a 90-deg V at 0 deg whose edge
    goes down to D at slope 0.1 and climbs back at slope 1 removes D^2 per unit of x:
    D^3 / 3 x (1 / 0.1 + 1); with the edge 0.3 mm low, D = 1.336 mm, 8.744 mm^3 (the 1 mm
    block lost 8.605 mm^3: 1.6 % of the groove lay under its bottom)."""
    from machinesim.cutting import cut
    from machinesim.procedures.tool_rotation_arm import TOOL
    from machinesim.workpiece import stock_from_spec

    one = CalibrationPlan(angles=(0.0,))
    low = 0.3 * MM
    part, _ = cut(one.program(R0), MACHINE, tool=TOOL, stock=one.stock,
                  errors=arm_errors(low, 0.0))
    d = one.search + low
    block = stock_from_spec(one.stock)
    assert block.volume - part.volume == pytest.approx(d ** 3 / 3 * (1 / one.slope + 1),
                                                       rel=1e-9)
    assert part.bounds[0][2] == block.bounds[0][2]  # its bottom left whole
    deepest = 1.0 * MM + 16 * UM + 8e-9 / 9 + SEARCH_MARGIN_M + 1.0 * MM
    assert one.depth == pytest.approx(deepest, abs=1e-15)
    assert block.bounds[0][2] == pytest.approx(-(deepest + 1.0 * MM), abs=1e-14)  # 12 digits


@pytest.mark.parametrize("rho, e_ys", [
    (0.5 * MM, 0.0),                        # the edge 0.5 mm low
    (0.7 * MM, -0.7 * MM),                  # 0.99 mm low and towards -y: the widest reach
])
def test_the_calibration_block_holds_every_ramps_deepest_cut(rho, e_ys):
    """A 90-deg V at 0 deg ends D = search + rho deep, D either side of its apex, the apex
    e_ys aside: with the first ramp 1.386 mm in from the block's low-y edge, the edge 0.5 mm
    low cut 0.150 mm past it near the ramp's end (0.05 % of the groove off the block), and
    0.7 mm low and -0.7 mm aside 1.06 mm. The most over offsets within the 1 mm capture is
    search + sqrt(2) mm; with 0.1 mm of land, lead = 2.550 mm. By hand the groove removes
    D^3 / 3 x (1 / 0.1 + 1), all of it from the block."""
    from machinesim.cutting import cut
    from machinesim.procedures.tool_rotation_arm import TOOL
    from machinesim.workpiece import stock_from_spec

    one = CalibrationPlan(angles=(0.0,))
    part, _ = cut(one.program(R0), MACHINE, tool=TOOL, stock=one.stock,
                  errors=arm_errors(rho, e_ys))
    d = one.search + rho
    block = stock_from_spec(one.stock)
    assert block.volume - part.volume == pytest.approx(d ** 3 / 3 * (1 / one.slope + 1),
                                                       rel=1e-9)
    assert one.lead + e_ys - d > 0.1 * MM  # the groove ends on the block, with land beside
    assert one.lead == pytest.approx(one.search + math.sqrt(2.0) * MM + 0.1 * MM, abs=1e-15)
    assert one.lead == CalibrationPlan().lead  # the five ramps': the 0 deg one's the most


def test_the_calibration_block_is_wide_enough_for_the_last_ramps_deepest_cut():
    """The +y side by hand: a single -40 deg ramp (its low flank, 5 deg from the surface,
    towards +y, its end 2 search tan 40 deg towards -y) reaches search / tan 5 deg + capture
    / sin 5 deg - 2 search tan 40 deg beyond its start; the block is that and 0.1 mm wider
    than lead: 21.67 mm (spacing alone, 3 mm, left it 18.67 mm short)."""
    plan = CalibrationPlan(angles=(math.radians(-40.0),))
    five, forty = math.radians(5.0), math.radians(40.0)
    reach = (plan.search / math.tan(five) + plan.capture / math.sin(five)
             - 2.0 * plan.search * math.tan(forty))
    assert plan.reach(0)[1] == pytest.approx(reach, rel=1e-12)
    assert plan.width == pytest.approx(plan.lead + reach + 0.1 * MM, rel=1e-12)
    assert plan.width > plan.lead + plan.spacing
    assert plan.stock.split("x")[1] == f"{plan.width / MM:.6g}"


def test_a_block_thinner_than_the_ramps_deepest_cut_is_refused():
    with pytest.raises(InputError) as info:
        CalibrationPlan(height=1.0 * MM)
    assert info.value.key == "height"
    message = str(info.value)
    assert "deepest cut 0.002036 m" in message and "got 0.001 m" in message
    assert "out through the block's bottom" in message
    with pytest.raises(InputError, match="thickness height above .* got -1.0 m"):
        CalibrationPlan(height=-1.0)
    # no number is no thickness, not one the ramps cut through (nan and '3' had been told
    # 'the ramps would cut out through the block's bottom'), and True no 1 m block (it had
    # made the stock 'block:...x1000')
    for bad in (math.nan, math.inf, "3", "3mm", True):
        with pytest.raises(InputError) as info:
            CalibrationPlan(height=bad)
        assert info.value.key == "height"
        assert str(info.value) == (f"key 'height': Expected height, the calibration block's "
                                   f"thickness, as a finite number of m (default None: "
                                   f"0.003036 m), got {bad!r}"), str(info.value)
    assert CalibrationPlan(height=2.1 * MM).stock.split("@")[0].endswith("x2.1")


@pytest.mark.parametrize("capture, tilt", [(1.5 * MM, 0.6e-3), (1.5 * MM, -0.6e-3),
                                           (2.8 * MM, 0.7e-3)])
def test_a_tilted_stage_neither_widens_the_fine_sections_nor_hides_the_groove(capture, tilt):
    """The stage's tilt across Y (0.2 mrad std, docs/metrology.md) at 3 sigma puts the ends
    of a coarse section 1.5 mm of capture wide (+-1.786 mm) 1.07 um off its median, past the
    0.8 um (0.1 x 8 um) that marks the groove at the first station: its land read as groove,
    and each fine section ran from there (2.4-3.0 mm instead of 34-49 um). At 3.5 sigma and a
    2.8 mm capture the 2 um that finds a groove was met at the ramp's first station, and
    the reading refused the offset as beyond the capture range. By hand, levelled: a 90-deg
    V at 0 deg is 2 D wide at depth D, 1.8 D below 0.1 D, and a fine section adds 10 um
    either side; the readings are the edge offset (dz = -(r - r0), dy = e_ys)."""
    from machinesim.cutting import cut
    from machinesim.metrology import Microscope
    from machinesim.metrology.imperfections import Registration
    from machinesim.procedures.tool_rotation_arm import TOOL, measure_calibration
    from machinesim.procedures.tool_rotation_arm_reading import FINE_SPACING_M

    plan = CalibrationPlan(angles=(0.0,), capture=capture)
    rho, e_ys = PAPER_R - R0, PAPER_E
    part, _ = cut(plan.program(R0), MACHINE, tool=TOOL, stock=plan.stock,
                  errors=arm_errors(rho, e_ys))
    microscope = Microscope(noise=False, registration=Registration(tilt=[0.0, tilt]))
    fine, profile = [], microscope.profile

    def recorded(part, start, end, spacing=None):
        # the fine sections, not the two across the block's edge that find its rotation
        if spacing == FINE_SPACING_M and abs(start[1] - plan.origin[1]) > 0.2 * MM:
            fine.append(end[1] - start[1])
        return profile(part, start, end, spacing=spacing)

    microscope.profile = recorded
    (reading,) = measure_calibration(part, plan, microscope)
    expected = 1.8 * np.array(plan.station_depths) + 20 * UM
    # the groove's extent read on 1 um samples: up to one sample short at each end
    assert np.all(np.abs(np.array(fine) - expected + 1 * UM) <= 1 * UM + 1e-12), fine
    # noise off: the 1 nm display rounding, dithered over the nine stations
    assert reading.mean("dz")[0] == pytest.approx(-rho, abs=0.1 * NM)
    assert reading.mean("dy")[0] == pytest.approx(e_ys, abs=0.1 * NM)
@pytest.mark.parametrize("rho, e_ys", [
    (119.8 * MM - R0, -178 * UM),            # the issue's --r-mm 119.8
    (0.0, -0.9 * MM),                         # neighbours' flanks in the search window
    (0.98 * MM * math.sin(2.0), 0.98 * MM * math.cos(2.0)),  # at the capture's edge
    (0.0, -0.995 * MM),                       # the first groove towards the block's edge
])
def test_any_offset_within_the_capture_range_is_identified(rho, e_ys):
    lab = Lab(MACHINE, arm_errors(rho, e_ys), noise=False)
    procedure = ToolRotationArm()
    detail = procedure.identify(procedure.measure(lab)).detail
    # noise off: the 1 nm display rounding, amplified by the design (test_tool_rotation_arm)
    assert detail.r - R0 == pytest.approx(rho, abs=1.8 * NM)
    assert detail.e_ys == pytest.approx(e_ys, abs=0.65 * NM)


def test_the_largest_capture_is_where_the_holder_would_meet_the_stock():
    """By hand: the top corners of the tool's body (y = +-3 mm, 10 mm up its axis) turned by
    40 deg stand 10 cos 40 - 3 sin 40 = 5.7321 mm over the edge (less than at 0-30 deg). A
    ramp goes capture + 16 um (+ 8/9 nm of dither) + 20 um deep, and an offset of length
    capture puts the edge that much lower again: capture <= (5.7321 - 0.0360) / 2 =
    2.84804 mm."""
    by_hand = (10 * math.cos(math.radians(40)) - 3 * math.sin(math.radians(40))) * MM
    assert holder_depth(CalibrationPlan().angles) == pytest.approx(by_hand, abs=1e-15)
    assert max_capture() == pytest.approx(0.5 * (by_hand - 16 * UM - 8e-9 / 9 - 20 * UM),
                                          abs=1e-15)
    assert max_capture() == pytest.approx(2.84804 * MM, abs=1e-8)
    # 0 and 10 deg only: 10 cos 10 - 3 sin 10 = 9.3270 mm
    by_hand = (10 * math.cos(math.radians(10)) - 3 * math.sin(math.radians(10))) * MM
    assert holder_depth((0.0, math.radians(10))) == pytest.approx(by_hand, abs=1e-15)


def down_at_40_deg(length):
    """(r - r0, e_ys) of an offset ``length`` long that puts the edge ``length`` low at 40
    deg (dz(40) = e_ys sin 40 - (r - r0) cos 40 = -length), the deepest it can go."""
    t = math.radians(40)
    return length * math.cos(t), -length * math.sin(t)


def test_the_largest_capture_cuts_its_deepest_offset_and_no_more():
    # just inside: capture 2.847 mm, the offset 2.846 mm long straight down at 40 deg, cut,
    # read and identified within 3 of its stated std (seed 0: 1.3 and 1.1)
    rho, e_ys = down_at_40_deg(2.846 * MM)
    lab = Lab(MACHINE, arm_errors(rho, e_ys), seed=0, realism=Realism.noise_only())
    procedure = ToolRotationArm(plan=CalibrationPlan(capture=2.847 * MM))
    identified = procedure.identify(procedure.measure(lab))
    for name, truth in (("tool.y", e_ys), ("tool.z", -rho)):
        value, std = identified.parameters[name]
        assert abs(value - truth) < 3 * std, (name, value - truth, std)
    # just outside: capture 2.849 mm, 2.849 mm down: the holder's top under the stock
    rho, e_ys = down_at_40_deg(2.849 * MM)
    lab = Lab(MACHINE, arm_errors(rho, e_ys), noise=False)
    procedure = ToolRotationArm(plan=CalibrationPlan(capture=2.849 * MM))
    with pytest.raises(HolderContactError, match="top of the tool's body"):
        procedure.measure(lab)


def test_the_scenario_refuses_a_capture_beyond_the_holder(tmp_path):
    empty = tmp_path / "empty.toml"
    empty.write_text("")
    fast = ("--errors", str(empty), "--budget", "off", "--realism", "noise_only")
    result = scenario(*fast, "--capture-mm", "2.849", "--out", str(tmp_path / "out"))
    assert result.returncode == 2
    last = result.stderr.splitlines()[-1]
    assert last.startswith("tool_rotation_arm: error: ")
    assert "--capture-mm 2.849: expected a length in mm above 0 and at most 2.848" in last
    assert "--tool" not in last and "allow-holder-contact" not in last
    assert not result.stdout  # refused up front, before the lab is built
    result = scenario(*fast, "--capture-mm", "2.848", "--out", str(tmp_path / "in"))
    assert result.returncode == 0, result.stderr
    summary = json.loads((tmp_path / "in" / "summary.json").read_text())
    for name, entry in summary["identified"].items():
        assert abs(entry["value"]) < 3 * entry["std"], (name, entry)


def test_the_stage_rotation_is_found_on_the_block_edge_and_taken_out():
    truth = arm_errors(PAPER_R - R0, PAPER_E)
    lab = Lab(MACHINE, truth, seed=0, realism=Realism.with_only("registration"))
    procedure = ToolRotationArm()
    identified = procedure.identify(procedure.measure(lab))
    drawn = lab.reveal_instruments()["microscope/calibration"]["registration"]
    assert abs(drawn.rotation) > 5e-4  # a stage turned by ~1 mrad, as the lab draws it
    # the edge found to a 0.1 um sample at both ends of the 24 mm block: 1e-5 rad
    plan = procedure.plan
    from machinesim.metrology import MeshIndex
    from machinesim.procedures.tool_rotation_arm import stage_rotation

    part, _ = lab.cut(plan.program(R0), "v:90", plan.stock)
    found = stage_rotation(MeshIndex.from_surface(part), plan,
                           lab.microscope(label="calibration"))
    assert found == pytest.approx(drawn.rotation, abs=1e-5)
    # without the alignment a 1.5 mrad stage moved e_ys by 4.4 um (ramps 20 mm apart at
    # slope 0.1); with it, what is left is the stage's offset and tilt, below 50 nm
    detail = identified.detail
    assert detail.e_ys == pytest.approx(PAPER_E, abs=50 * NM)
    assert detail.r == pytest.approx(PAPER_R, abs=50 * NM)


def test_the_stated_uncertainty_holds_the_stage_positioning():
    """Each section is its own placement of the stage, 1 um off in x and y: along a ramp of
    slope 0.1 that reads the edge 0.1 um higher or lower, ten times the fits' few nm. The
    fit's sigma holds it: the errors stay within 4 sigma (seeds 0-6 gave 0.1-2.9 sigma,
    docs/procedures/tool_rotation_arm.md), and without it they were 112-167 sigma."""
    lab = Lab(MACHINE, arm_errors(PAPER_R - R0, PAPER_E), seed=0,
              realism=Realism.with_only("stage_positioning"))
    procedure = ToolRotationArm()
    identified = procedure.identify(procedure.measure(lab))
    for name, truth in (("tool.y", PAPER_E), ("tool.z", -(PAPER_R - R0))):
        value, std = identified.parameters[name]
        assert 50 * NM < std < 1 * UM, (name, std)
        assert abs(value - truth) < 4 * std, (name, value - truth, std)
    # the larger of the two errors is far above what the fits alone could state
    assert abs(identified.parameters["tool.z"][0] + (PAPER_R - R0)) > 100 * NM


def scenario(*args):
    return subprocess.run([sys.executable, str(ROOT / "scenarios" / "tool_rotation_arm.py"),
                           *args], capture_output=True, text=True, check=False, cwd=ROOT)


def test_the_scenario_reproduces_the_papers_before_and_writes_a_budget(tmp_path):
    result = scenario("--realism", "noise_only", "--out", str(tmp_path))
    assert result.returncode == 0, result.stderr
    summary = json.loads((tmp_path / "summary.json").read_text())
    check_summary(summary)
    figures = {f["name"]: f for f in summary["figures"]}
    # the paper: "over 50 um" before; within 25 % of it, over it
    before = figures["depth_error"]["before"]
    assert PAPER_BEFORE_UM < before < 1.25 * PAPER_BEFORE_UM
    assert figures["depth_error"]["after"] < 1.0  # the paper's "under 1 um"
    budget = Budget.from_dict(summary["budget"])
    assert budget.sources == ("instrument_noise",)
    assert budget.figures == ("depth_error", "depth_variation", "pitch_error")
    for row in budget.rows:
        assert row.after_all == figures[row.figure]["after"]
        assert row.share == quadrature_share(row.after_all, row.after_without)
        # noise off, the 1 nm display is what is left (test_tool_rotation_arm): the noise
        # is nearly all of the "after"
        assert abs(row.after_without) < 2e-3 and row.share > 0.9
    assert "### Error budget" in result.stdout
    assert (tmp_path / "budget.png").read_bytes()[:4] == b"\x89PNG"
    assert np.isfinite([r.share for r in budget.rows]).all()


def test_the_scenario_admits_the_edge_offsets_its_capture_finds_and_names_the_option(
        tmp_path):
    """By hand, at the default capture of 1 mm: with the paper's r - r0 = 55 um, e_ys within
    +-sqrt(1 - 0.055**2) = +-0.998487 mm (printed +-998.48 um), either sign alike; with its
    e_ys = -178 um, r within 120.5 +- sqrt(1 - 0.178**2) = 120.5 +- 0.984031 mm (printed
    119.5160 to 121.4840 mm). Beyond it the scenario stops before cutting, naming the option
    and the range; -999 um used to end in a groove fit ("found 0"), 121.485 mm ran, 1e6 um
    and 1e300 mm named the tool setting's keys."""
    fast = ("--budget", "off", "--realism", "noise_only")
    e_range = "expected e_ys within +-998.48 um at r - r0 = 55.00 um"
    r_range = "expected r within 119.5160 to 121.4840 mm at e_ys = -178.00 um"
    for option, value, message in (("--e-ys-um", "-999", e_range), ("--e-ys-um", "999", e_range),
                                   ("--e-ys-um", "1e6", e_range),
                                   ("--r-mm", "121.485", r_range), ("--r-mm", "119.515", r_range),
                                   ("--r-mm", "1e300", r_range), ("--r-mm", "125", r_range)):
        result = scenario(option, value, *fast, "--out", str(tmp_path / "out"))
        assert result.returncode == 2, (option, value, result.stderr)
        last = result.stderr.splitlines()[-1]
        assert last.startswith("tool_rotation_arm: error: ")
        assert f"{option} {float(value)!r}: the edge offset" in last, last
        assert "exceeds the plan's capture range 1 mm" in last and message in last, last
        assert not result.stdout  # refused before the lab is built
    # just inside, on either side: run, and identify e_ys and r within 3 of their std
    for option, value in (("--e-ys-um", "-998"), ("--r-mm", "121.484")):
        out = tmp_path / value
        result = scenario(option, value, *fast, "--out", str(out))
        assert result.returncode == 0, result.stderr
        summary = json.loads((out / "summary.json").read_text())
        for name in ("tool.y", "tool.z"):
            entry = summary["identified"][name]
            error = entry["value"] - summary["injected"][name]
            assert abs(error) < 3 * entry["std"], (option, name, error, entry["std"])


def test_a_capture_below_the_papers_offset_names_the_capture_and_the_least_one_that_finds_it(
        tmp_path):
    """With no --e-ys-um, --r-mm or --errors, the offset is the paper's: |(-178, 55)| um =
    sqrt(178**2 + 55**2) = 186.3035 um by hand, so --capture-mm must be at least 0.186304.
    The message used to name "--errors None (tool.y, tool.z)", a file nobody gave, and
    expect "a shorter offset"; and an offset just beyond the capture read "1 mm exceeds
    the plan's capture range 1 mm" (998.49 um at r - r0 = 55 um: 1.00000364 mm)."""
    result = scenario("--capture-mm", "0.18", "--out", str(tmp_path / "out"))
    assert result.returncode == 2
    assert result.stderr.splitlines()[-1] == (
        "tool_rotation_arm: error: key 'capture-mm': --capture-mm 0.18 with the paper's "
        "errors (e_ys = -178 um, r = 120.555 mm): the edge offset |(e_ys, r - r0)| = 0.186304 "
        "mm exceeds the plan's capture range 0.18 mm (--capture-mm, at most 2.848): expected "
        "--capture-mm at least 0.186304 mm")
    result = scenario("--e-ys-um", "998.49", "--out", str(tmp_path / "out"))
    assert result.returncode == 2
    assert ("the edge offset |(e_ys, r - r0)| = 1.00000364004 mm exceeds the plan's capture "
            "range 1 mm") in result.stderr.splitlines()[-1]


def test_an_arm_at_the_capture_as_given_is_taken(tmp_path):
    """--r-mm 121.5 --e-ys-um 0 is an edge offset of 1 mm, the default capture, which the
    plan finds; it was refused as '|(e_ys, r - r0)| = 1 mm exceeds the plan's capture range
    1 mm ... expected ... r within 119.5000 to 121.5000 mm', since 121.5 mm - 120.5 mm in
    metres is 1.0000000000000009 mm. Past it by 0.1 um it is still refused."""
    import argparse
    import importlib.util

    spec = importlib.util.spec_from_file_location(
        "tool_rotation_arm_scenario", Path(__file__).parents[1] / "scenarios"
        / "tool_rotation_arm.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert R0 == pytest.approx(120.5 * MM)

    def check(r_mm, e_ys_um):
        args = argparse.Namespace(e_ys_um=e_ys_um, r_mm=r_mm, capture_mm=None, errors=None)
        module.check_offset(args, 1.0 * MM, R0, e_ys_um * UM, r_mm * MM - R0)

    assert 121.5 * MM - R0 > 1.0 * MM  # the rounding the check met
    check(121.5, 0.0)
    check(119.5, 0.0)
    check(120.5, -1000.0)
    with pytest.raises(InputError, match=r"--r-mm 121.5001: the edge offset"):
        check(121.5001, 0.0)
