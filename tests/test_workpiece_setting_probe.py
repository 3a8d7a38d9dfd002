"""Paper 002 replay, the probe procedure: seeded robot placements (noise on and off) and the
C centre found, spheres far above or aside, and the generic fit against eqs 1-4 and fig. 6
(`machinesim.identification.workpiece_setting`, `machinesim.procedures.workpiece_setting`)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from machinesim import ErrorModel, WorkpieceSetting, load_machine
from machinesim.cam import crown as cam
from machinesim.exceptions import InputError
from machinesim.identification import workpiece_setting as ws
from machinesim.loading import RobotLoader
from machinesim.metrology import TouchProbe
from machinesim.procedures.workpiece_setting import read_sphere, read_spheres
from machinesim.rotations import rotation_xyz
from machinesim.workpiece import stock_from_spec

UM, MM, NM = 1e-6, 1e-3, 1e-9
MACHINE = load_machine("robonano_a0ib")


@pytest.fixture(scope="module")
def groove_stock():
    return stock_from_spec(cam.GROOVE_STOCK)


@pytest.mark.parametrize("noise", [False, True])
def test_identify_finds_a_seeded_robot_placement_and_the_c_centre(groove_stock, noise):
    """Tolerances (4x the largest error over 8 seeded placements, measured): noise off, x y
    10 nm, the angles 0.3 urad, the C centre 1 nm, z 40 nm: the sphere polygons' 0.1 um
    facets (workpiece.SPHERE_CHORD_M) lift the ball at the bottom touch and shrink the
    fitted radius by different amounts (measured 4-23 nm). Noise on (probe sigma 20 nm):
    x y and the C centre 30 nm, z 150 nm, the angles 25 urad (20 nm over 12 mm is 1.7 urad)."""
    rng = np.random.default_rng(3)
    landed = RobotLoader().land(rng)
    c0 = rng.normal(0.0, 3 * UM, 2)
    errors = ErrorModel(workpiece=landed, location={"C": {"EX0C": c0[0], "EY0C": c0[1]}})
    readings = read_spheres(TouchProbe(MACHINE, errors, groove_stock, noise=noise, rng=rng),
                            cam.GROOVE_SPHERES)
    found = ws.identify(readings)
    s = found.setting
    xy, z, angle, centre = (30 * NM, 150 * NM, 25e-6, 30 * NM) if noise else (
        10 * NM, 40 * NM, 0.3e-6, 1 * NM)
    np.testing.assert_allclose(s.delta[:2], landed.delta[:2], rtol=0, atol=xy)
    assert abs(s.delta[2] - landed.delta[2]) < z
    np.testing.assert_allclose([s.alpha, s.beta, s.gamma],
                               [landed.alpha, landed.beta, landed.gamma], rtol=0, atol=angle)
    np.testing.assert_allclose(found.c_centre, c0, rtol=0, atol=centre)
    # eq 4: S1's offset, as the paper reports it, is the setting moved to S1
    r = rotation_xyz(s.alpha, s.beta, s.gamma)
    s1 = cam.GROOVE_SPHERES.centres[0]
    np.testing.assert_allclose(found.delta, s.delta + r @ s1 - s1, rtol=0, atol=1e-18)
    assert found.radius == pytest.approx(2 * MM, abs=0.1 * UM)  # facets: up to 0.1 um in
    # the parameters by name, as the error model spells them: identified ~ injected
    truth_parameters = errors.parameters()
    for name, value in ws.parameters(found).items():
        bound = {"workpiece.z": z, "location.C.EX0C": centre, "location.C.EY0C": centre}.get(
            name, angle if name.split(".")[1] in ("alpha", "beta", "gamma") else xy)
        assert abs(value - truth_parameters[name]) < bound, name


def test_spheres_far_above_the_expected_height_are_found_by_a_bottom_touch_first(
        groove_stock):
    """A block set 0.3 mm high and tilted 1 deg: the planned scans run 0.1 mm below the
    expected surface, so they run into the cavities (stylus over-travel) or miss them. The
    probing then touches each cavity's bottom first and scans again about it, as an
    operator would; the setting comes out as for a small one (noise off: 10 nm, 40 nm in
    z, 0.3 urad as in the test above)."""
    landed = WorkpieceSetting(np.array([20.0, -10.0, 300.0]) * UM, math.radians(1.0), 0.0,
                              math.radians(0.3))
    errors = ErrorModel(workpiece=landed)
    found = ws.identify(read_spheres(TouchProbe(MACHINE, errors, groove_stock, noise=False),
                                     cam.GROOVE_SPHERES))
    np.testing.assert_allclose(found.setting.delta[:2], landed.delta[:2], rtol=0, atol=10 * NM)
    assert abs(found.setting.delta[2] - landed.delta[2]) < 40 * NM
    s = found.setting
    np.testing.assert_allclose([s.alpha, s.beta, s.gamma], [landed.alpha, 0.0, landed.gamma],
                               rtol=0, atol=0.3e-6)


def test_a_sphere_far_aside_is_a_clear_error_after_the_bottom_touch(groove_stock):
    """Looked for 3 mm aside (beyond the 2 mm cavity): the scans miss, the bottom touch
    meets the flat, the scans about that height miss again: one InputError naming the
    expected centre, not a traceback or a wrong reading."""
    probe = TouchProbe(MACHINE, ErrorModel(), groove_stock, noise=False)
    centre = cam.GROOVE_SPHERES.centres[0] + np.array([3.0, 0.0, 0.0]) * MM
    with pytest.raises(InputError, match="bottom touch under") as error:
        read_sphere(probe, centre)
    assert error.value.key == "centre"


@pytest.mark.parametrize("noise", [False, True])
def test_the_generic_fit_agrees_with_eqs_1_to_4_and_fig_6(groove_stock, noise):
    """The cross-check (`fit_setting`): the same readings, the six probed centres as probe
    displacements, the same eight parameters by weighted least squares. Measured over 6
    seeded placements with a C centre 3 um off (docs/procedures/workpiece_setting.md):
    noise off, fit - eqs <= 0.25 nm (x, y, C centre), 0.0002 nm (z), 0.05 urad (gamma; alpha
    and beta 1e-5 urad); noise on, <= 8.6 nm (x, y), 12 nm (z), 3.6 urad (alpha, beta),
    0.85 urad (gamma), 0.19 nm (C centre): the fit also uses the three centres read at
    C = 180 deg, which eqs 1-4 leave out. Bounds: about 3x those."""
    rng = np.random.default_rng(11)
    landed = RobotLoader().land(rng)
    c0 = rng.normal(0.0, 3 * UM, 2)
    errors = ErrorModel(workpiece=landed, location={"C": {"EX0C": c0[0], "EY0C": c0[1]}})
    readings = read_spheres(TouchProbe(MACHINE, errors, groove_stock, noise=noise, rng=rng),
                            cam.GROOVE_SPHERES)
    found = ws.identify(readings)
    check = ws.fit_setting(MACHINE, readings, found)
    assert check.names == ws.PARAMETERS and check.rank == 8 and not check.unidentifiable
    paper = ws.parameters(found)
    length, angle, centre = (30 * NM, 10e-6, 1 * NM) if noise else (1 * NM, 0.2e-6, 1 * NM)
    for name, value in zip(check.names, check.values, strict=True):
        bound = (centre if name.startswith("location") else
                 angle if name.split(".")[1] in ("alpha", "beta", "gamma") else length)
        assert abs(value - paper[name]) < bound, name
    if noise:
        # the reported std is the probe noise's: the errors are of its size
        truth_parameters = errors.parameters()
        for name, value, std in zip(check.names, check.values, check.std, strict=True):
            scale = 4.0 if name != "workpiece.z" else 8.0  # z: the facet bias, ~25 nm
            assert abs(value - truth_parameters[name]) < scale * std + 30 * NM * (
                name == "workpiece.z"), name
