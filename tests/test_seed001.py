"""Paper 001 replay: B-axis equations against the kinematics, compensation round trips, and
the whole procedure (cut, measure, identify, compensate, re-cut) with seeded random errors."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from machinesim import ErrorModel, ToolSetting, load_machine
from machinesim.cutting import cut
from machinesim.exceptions import InputError
from machinesim.identification import seed001
from machinesim.metrology import Microscope
from machinesim.nc import Move, Program

ROOT = Path(__file__).resolve().parents[1]
UM, MM = 1e-6, 1e-3
MACHINE = load_machine("robonano_ui")


def errors_of(d, e) -> ErrorModel:
    return ErrorModel(tool=ToolSetting(d, [0.0, 0.0, 0.0]),
                      location={"C": {"EX0C": e[0], "EY0C": e[1]}})


def paper_offsets(rng):
    """Tool offset and C centre of the paper's size: Table 1 holds distances of 100-850 um,
    i.e. offsets of a few hundred um; every component at least 100 um (50 um for e), with a
    random sign, all within the plan's capture range."""
    d = rng.uniform(100, 450, 3) * UM * rng.choice([-1.0, 1.0], 3)
    e = rng.uniform(50, 650, 2) * UM * rng.choice([-1.0, 1.0], 2)
    return d, e


def run(d, e, noise, seed):
    """The procedure on a machine with errors (d, e), then the compensated re-cuts."""
    errors = errors_of(d, e)

    def cut_plate(program, stock):
        part, report = cut(program, MACHINE, tool="v:90", stock=stock, errors=errors,
                            start=seed001.PARKED)
        assert report.sideways_sweeps == 0 and report.rapids_that_cut == ()
        assert not report.empty_cut
        return part

    microscope = Microscope(rng=seed, noise=noise)
    found = seed001.identify(cut_plate, microscope)
    plates = seed001.plate_cuts()
    after = {s: seed001.measure(s, cut_plate(seed001.compensate(plates[s].program,
                                                                found.compensation),
                                             plates[s].stock), microscope)
             for s in "abc"}
    return found, after


def edge_z(d, a, b):
    q = np.array([0.0, 0.0, 0.0, a, b, 0.0])
    return MACHINE.tool_pose(q, errors_of(d, (0.0, 0.0)))[2, 3]


def printed_eq2(d0, d1, d2, t2, t3):
    """Paper 001's eq 2 as printed (with D the B = 0 depth)."""
    den = math.sin(t2) * (1 - math.cos(t3)) - math.sin(t3) * (1 - math.cos(t2))
    return ((d1 - d0) * math.sin(t2) + (d2 - d0) * math.sin(t3)) / den


def test_b_axis_equations_follow_from_the_kinematics():
    """Depth at a B tilt (A = 90 deg) read from Machine.tool_pose: eq 1 gives -dX, the
    corrected eq 2 gives dZ exactly, the printed eq 2 does not."""
    rng = np.random.default_rng(0)
    for t2, t3 in ((20.0, -20.0), (10.0, 35.0), (-15.0, 30.0)):
        t2, t3 = math.radians(t2), math.radians(t3)
        d = rng.uniform(-450, 450, 3) * UM
        depths = [-edge_z(d, math.pi / 2, t) for t in (0.0, t2, t3)]
        # at A = 90 deg the edge offset in machine X is -dy, in Z dz
        for t, depth in zip((t2, t3), depths[1:], strict=True):
            # 1e-15 m: float64 round-off of the chain at the 0.3 m scale of the machine
            assert depth - depths[0] == pytest.approx(
                -d[1] * math.sin(t) + d[2] * (1 - math.cos(t)), abs=1e-15)
        dx, dz = seed001.b_axis_offsets(*depths, t2, t3)
        # the 1e-15 m round-off above, divided by (1 - cos t) ~ 0.015 at the smallest tilt
        assert dx == pytest.approx(-d[1], abs=1e-13)
        assert dz == pytest.approx(d[2], abs=1e-13)
        assert abs(printed_eq2(*depths, t2, t3) - d[2]) > 10 * UM


def test_compensation_puts_the_edge_where_the_nc_data_put_it():
    rng = np.random.default_rng(1)
    d, e = paper_offsets(rng)
    q = np.column_stack([rng.uniform(-5, 5, (20, 3)) * MM, rng.uniform(-np.pi, np.pi, 20),
                         rng.uniform(-1.0, 1.0, 20), rng.uniform(-np.pi, np.pi, 20)])
    program = Program.from_moves(Move("rapid", dict(zip("XYZABC", row, strict=True)),
                                      line=k + 1) for k, row in enumerate(q))
    fixed = seed001.compensate(program, seed001.Compensation(d, e))
    q_fixed = np.array([[m.target[a] for a in "XYZABC"] for m in fixed.moves])
    np.testing.assert_array_equal(q_fixed[:, 3:], q[:, 3:])
    # 1e-15 m: the same chain evaluated twice, values of a few mm, float64
    np.testing.assert_allclose(MACHINE.tool_pose(q_fixed, errors_of(d, e)),
                               MACHINE.tool_pose(q), rtol=0, atol=1e-15)
    shifted = seed001.compensate(program, seed001.Compensation(z_shift=3 * UM))
    assert [m.target["Z"] for m in shifted.moves] == pytest.approx(q[:, 2] + 3 * UM,
                                                                     abs=1e-18)


@pytest.mark.parametrize("seed", [3, 11])
def test_seeded_offsets_are_identified_and_compensated_with_noise(seed):
    d, e = paper_offsets(np.random.default_rng(seed))
    found, after = run(d, e, noise=True, seed=seed)
    comp = found.compensation
    # before: the pairs' start points part by 2 (dx, dy) and 2 (-dy, dx), the triangle is
    # centred on e; 50 nm covers the microscope readings (see the tolerances below)
    np.testing.assert_allclose(found.a.distances, [2 * d[:2], [-2 * d[1], 2 * d[0]]],
                               atol=50e-9)
    # dx, dy: 20 nm, six sigma of the centre lines (sigma 3 nm over ten seeds with the
    # 12 nm height noise); dx alone is read on the start faces, to 0.05 nm
    np.testing.assert_allclose(comp.tool_offset[:2], d[:2], atol=20e-9)
    # dZ: 0.1 um, six sigma (17 nm) of four depth fits amplified by 1 / (1 - cos 20 deg)
    assert comp.tool_offset[2] == pytest.approx(d[2], abs=0.1 * UM)
    # e: 30 nm, six sigma (5 nm) of the triangle centre from three fitted sides
    np.testing.assert_allclose(comp.c_centre, e, atol=30e-9)
    # second methods: dX after the A compensation is what is left of dy (sign of machine X at
    # A = 90 deg); the touch-off reads the tool length the B tilts read as dZ
    assert found.b.offset_x == pytest.approx(comp.tool_offset[1] - d[1], abs=20e-9)
    assert -found.z_touch == pytest.approx(comp.tool_offset[2], abs=0.1 * UM)
    assert abs(printed_eq2(*found.b.depths, math.radians(20), math.radians(-20))
               - d[2]) > 10 * UM
    # after: the brief's 1 um, and 0.1 um from the identification and reading errors above
    # (at most 25 nm over ten seeds)
    assert np.abs(after["a"].distances).max() < 0.1 * UM
    assert np.abs(after["c"].centre).max() < 0.1 * UM
    assert np.abs(after["b"].depths - seed001.Plan().b_depth).max() < 0.1 * UM


def test_without_noise_the_residuals_stay_below_a_nanometre():
    d, e = paper_offsets(np.random.default_rng(5))
    found, after = run(d, e, noise=False, seed=0)
    comp = found.compensation
    # what is left: the 1 nm height display (spread by the golden-ratio pitch, < 0.1 nm on a
    # centre) and the 0.05 nm pitch of the start-face zoom; 1 nm for dZ, which divides depth
    # errors by 1 - cos 20 deg
    np.testing.assert_allclose(comp.tool_offset[:2], d[:2], atol=0.5e-9)
    assert comp.tool_offset[2] == pytest.approx(d[2], abs=1e-9)
    np.testing.assert_allclose(comp.c_centre, e, atol=0.5e-9)
    assert np.abs(after["a"].distances).max() < 1e-9
    assert np.abs(after["c"].centre).max() < 1e-9
    assert np.abs(after["b"].depths - after["b"].depths[0]).max() < 1e-9


def test_errors_outside_the_capture_range_are_reported():
    plate = seed001.plate_cuts()["a"]
    part, _ = cut(plate.program, MACHINE, tool="v:90", stock=plate.stock,
                  errors=errors_of([0.0, 0.9 * MM, 0.0], [0.0, 0.0]))
    with pytest.raises(InputError, match=r"A axis, groove at A = 0 deg.*plan's range"):
        seed001.measure("a", part, Microscope(noise=False))
    with pytest.raises(InputError, match="Expected stage 'a', 'b' or 'c', got 'd'"):
        seed001.measure("d", part, Microscope(noise=False))
    with pytest.raises(InputError, match="Expected two distinct non-zero B tilts"):
        seed001.b_axis_offsets(0.0, 1e-6, 1e-6, 0.3, 0.3)
    with pytest.raises(InputError, match=r"Expected tool_offset as 3 finite numbers"):
        seed001.Compensation(tool_offset=[1e-6, 2e-6])
    with pytest.raises(InputError, match="Expected a finite z_shift"):
        seed001.Compensation(z_shift=math.nan)


def test_the_scenario_reproduces_table_1(tmp_path):
    out = tmp_path / "report"
    result = subprocess.run([sys.executable, str(ROOT / "scenarios/seed001_tool_setting_6axis.py"),
                             "--noise", "off", "--out", str(out)],
                            capture_output=True, text=True, check=False, cwd=ROOT)
    assert result.returncode == 0, result.stderr
    assert "| A dx | 490.0400 | 4.0600 | 490.0400 |" in result.stdout
    summary = json.loads((out / "summary.json").read_text())
    # defaults: half of Table 1's A distances, its C distances; the original distances come
    # back to 1 nm (noise off) and vanish to 1 nm after compensation
    np.testing.assert_allclose(summary["before"]["a_x_pair_distance_um"], [490.04, 680.12],
                               atol=1e-3)
    np.testing.assert_allclose(summary["before"]["c_centre_displacement_um"],
                               [108.97, 852.81], atol=1e-3)
    assert np.abs(summary["after"]["a_x_pair_distance_um"]).max() < 1e-3
    assert np.abs(summary["after"]["c_centre_displacement_um"]).max() < 1e-3
    for name in ("table1.md", "identification.json", "layout_a_axis.png",
                 "04_a_axis_compensated.nc", "05_c_axis_compensated.ply"):
        assert (out / name).stat().st_size > 0
    bad = subprocess.run([sys.executable, str(ROOT / "scenarios/seed001_tool_setting_6axis.py"),
                          "--tool-offset-um", "1,2", "--out", str(out)],
                         capture_output=True, text=True, check=False, cwd=ROOT)
    assert bad.returncode == 2
    assert "--tool-offset-um '1,2': expected 3 comma-separated numbers" in bad.stderr
