"""C-table squareness by simultaneous XY + C motion (paper 003 Figs 7-9)."""

from pathlib import Path

import numpy as np
import pytest

import machinesim
from machinesim.compensation_table import ModelCompensation
from machinesim.exceptions import MachineSimError
from machinesim.identification.c_axis_squareness import (
    LOCATION,
    first_harmonic,
    fixed_axes,
    following_axes,
    height_from_commands,
    separate,
)

PAPER = Path(__file__).resolve().parents[1] / "models" / "errors" / "xy_plane_grooving_4axis.toml"
THETA = np.radians(np.arange(0.0, 360.0, 10.0))
R = 0.1


def run_tests(lab, sigma=10e-9):
    m = lab.machine
    rt = lab.r_test(sigma=sigma, label="c_squareness")
    fq = following_axes(m, THETA, R)
    fixed = [fixed_axes(m, THETA, R, 0.0), fixed_axes(m, THETA, 0.0, R)]
    sep = separate(m, fq, rt.read(fq).displacement, fixed,
                   [rt.read(q).displacement for q in fixed])
    return rt, fq, sep


def test_following_keeps_the_tool_on_one_table_point():
    m = machinesim.load_machine("grooving_4axis")
    q = following_axes(m, THETA, R)
    np.testing.assert_allclose(m.tool_pose(q)[:, :2, 3], np.tile([R, 0.0], (THETA.size, 1)),
                               atol=1e-15)
    # The point circles the C centre in machine XY: radius R.
    np.testing.assert_allclose(np.hypot(q[:, 0], q[:, 1]), R, atol=1e-15)


def test_tilts_alone_give_the_once_per_revolution_height_by_hand():
    # EA0C, EB0C tilt the C line; the followed point at radius R rises and falls by R times
    # the tilt once per revolution (first order): the first harmonic's amplitude is
    # R hypot(EA0C, EB0C) = 0.1 * 10 urad = 1 um.
    lab = machinesim.Lab("grooving_4axis", {"location": {"C": {"EA0C_urad": 6.0,
                                                               "EB0C_urad": -8.0}}},
                         noise=False)
    _, _, sep = run_tests(lab)
    # (the sensors display to 1 nm: rounding of +-0.5 nm per reading)
    assert first_harmonic(THETA, sep.h) == pytest.approx(R * 10e-6, abs=5e-10)
    assert sep.perpendicularity_angle == pytest.approx(10e-6, rel=1e-3)
    np.testing.assert_allclose(sep.wobble, 0.0, atol=2e-9)
    np.testing.assert_allclose(sep.xy_motion, 0.0, atol=2e-9)


def test_identified_against_injected_with_all_errors_noise_off():
    lab = machinesim.Lab("grooving_4axis", PAPER, noise=False)
    _, _, sep = run_tests(lab)
    truth = lab.reveal().parameters()
    for name in LOCATION:
        tol = 1e-9 if name.endswith(("EX0C", "EY0C")) else 2e-9   # second-order terms
        assert sep.location[name] == pytest.approx(truth[name], abs=tol), name
    # The wobble part is the height the injected tilt motion alone gives the followed
    # point (a second lab with only EAC, EBC); the XY motion errors (EZX, EZY, pitch,
    # roll) remain in Fig 9(c).
    wobble_only = {"component": {"C": lab.reveal().to_dict()["component"]["C"]}}
    _, _, alone = run_tests(machinesim.Lab("grooving_4axis", wobble_only, noise=False))
    np.testing.assert_allclose(sep.wobble, alone.h, atol=3e-9)
    assert np.ptp(sep.wobble) > 0.2e-6 and np.ptp(sep.xy_motion) > 0.3e-6


def test_identified_with_noise_within_its_uncertainty():
    lab = machinesim.Lab("grooving_4axis", PAPER, seed=5)
    _, _, sep = run_tests(lab)
    truth = lab.reveal().parameters()
    for name in LOCATION:
        assert abs(sep.location[name] - truth[name]) < 5 * sep.std[name] + 1e-9, name


def test_compensation_removes_the_perpendicularity_from_h():
    lab = machinesim.Lab("grooving_4axis", PAPER, noise=False)
    rt, fq, sep = run_tests(lab)
    comp = ModelCompensation(lab.machine, sep.identified())
    commanded = comp.apply(fq)
    after = height_from_commands(lab.machine, fq, commanded, rt.read(commanded).displacement)
    # What is left is what the location model does not hold: tilt motion and XY motion.
    np.testing.assert_allclose(after, sep.h - sep.perpendicularity, atol=2e-9)
    # The removed part: R hypot(EA0C, EB0C) = 0.1 m * 10 urad once per revolution.
    assert first_harmonic(THETA, sep.perpendicularity) == pytest.approx(1e-6, rel=1e-3)


def test_bad_plans_are_refused():
    m = machinesim.load_machine("grooving_4axis")
    q = following_axes(m, THETA, R)
    readings = np.zeros((THETA.size, 3))
    fixed = [fixed_axes(m, THETA, R, 0.0), fixed_axes(m, THETA, 0.0, R)]
    with pytest.raises(MachineSimError):                      # half a revolution
        separate(m, q[::2][:10], readings[:10], [f[:10] for f in fixed], [readings[:10]] * 2)
    with pytest.raises(MachineSimError):                      # readings of a wrong shape
        separate(m, q, readings[:, :2], fixed, [readings] * 2)
    with pytest.raises(MachineSimError):                      # one fixed test only
        separate(m, q, readings, fixed[:1], [readings])


def test_the_stated_std_is_the_sensors_and_the_scatter_over_labs_matches_it():
    # the paper's errors, wobble (EAC, EBC twice a turn) included: the residuals hold the
    # wobble, so a std scaled by them stated 6 to 7 times the scatter (z std 0.14-0.17 over
    # 40 campaign trials); with the sensors' stated sigma the std is sigma sqrt(diag
    # ((J^T J)^-1)) and the scatter of EX0C .. EB0C over 100 labs matches it
    sigma = 10e-9
    found, stds, residual_stds = [], [], []
    for seed in range(100):
        lab = machinesim.Lab("grooving_4axis", PAPER, seed=seed)
        rt = lab.r_test(sigma=sigma, resolution=0.0, label="c_squareness")
        m = lab.machine
        fq = following_axes(m, THETA, R)
        fixed = [fixed_axes(m, THETA, R, 0.0), fixed_axes(m, THETA, 0.0, R)]
        reads = (rt.read(fq).displacement, [rt.read(q).displacement for q in fixed])
        stated = separate(m, fq, reads[0], fixed, reads[1], sigma)
        found.append([stated.location[n] for n in LOCATION])
        stds.append([stated.std[n] for n in LOCATION])
        residual_stds.append([separate(m, fq, reads[0], fixed, reads[1]).std[n]
                              for n in LOCATION])
    found, stds = np.array(found), np.array(stds)
    # the stated std does not depend on the draw
    np.testing.assert_allclose(stds, np.tile(stds[0], (100, 1)), rtol=1e-12)
    ratio = found.std(axis=0, ddof=1) / stds[0]
    # 100 draws: a correct std gives a ratio within 0.77 .. 1.24 (chi-square, 99.9 %)
    assert np.all((ratio > 0.77) & (ratio < 1.24)), ratio
    assert np.all(np.array(residual_stds).mean(axis=0) > 3.0 * stds[0])
    with pytest.raises(MachineSimError, match="sigma as a standard uncertainty > 0"):
        separate(m, fq, reads[0], fixed, reads[1], -1.0)
