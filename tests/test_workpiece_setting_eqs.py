"""Paper 002 replay, the formulas: robot loading (the scatter its repeatability gives, what it
refuses), eqs 1-7 against the kinematics (a Kabsch fit, a lobing, the spheres' tolerance
against a Monte Carlo, the tip or nose on the path), the compensated program rounded, the
grooves cut before and after, and the bad inputs these take
(`machinesim.identification.workpiece_setting`, `machinesim.procedures.workpiece_setting`)."""

from __future__ import annotations

import math
import re
from dataclasses import replace

import numpy as np
import pytest

from machinesim import ErrorModel, WorkpieceSetting, load_machine
from machinesim.cam import crown as cam
from machinesim.compensation import program_axes
from machinesim.cutting import cut, cut_turned
from machinesim.exceptions import InputError
from machinesim.identification import workpiece_setting as ws
from machinesim.identification import workpiece_setting_uncertainty as wsu
from machinesim.identification.workpiece_setting import Identification
from machinesim.loading import RP_PER_SIGMA, RobotLoader
from machinesim.metrology import Microscope, TouchProbe, groove_depths, part_features
from machinesim.nc import ProgramBuilder
from machinesim.procedures.workpiece_setting import (
    ProbePlan,
    RobotLoadedWorkpiece,
    eqs_5_to_7_program,
    model_based_program,
    read_sphere,
    read_spheres,
)
from machinesim.rotations import rotation_xyz
from machinesim.workpiece import stock_from_spec

UM, MM, NM = 1e-6, 1e-3, 1e-9
MACHINE = load_machine("robonano_a0ib")
NOSE = 2.0 * MM


@pytest.fixture(scope="module")
def groove_stock():
    return stock_from_spec(cam.GROOVE_STOCK)


def truth(setting: WorkpieceSetting, c_centre=(0.0, 0.0)) -> Identification:
    """An identification that found exactly the injected state (to test eqs 5-7 alone)."""
    return Identification(np.zeros((3, 3)), 2.0 * MM, setting, np.zeros(3),
                          np.array(c_centre, dtype=float), np.zeros((3, 2)), ())


def random_setting(rng, scale: float = 1.0) -> WorkpieceSetting:
    """A setting of the robot's size (30 um, ~1 mrad) times ``scale``."""
    return WorkpieceSetting(rng.normal(0.0, 10 * UM, 3) * scale,
                            *(rng.normal(0.0, 1e-3, 3) * scale))


# ------------------------------------------------------------------------ robot loading


def test_the_robot_scatters_as_its_repeatability_says():
    """RP (ISO 9283) = mean + 3 std of the landing distances; the draws must give back the
    parameter. 20000 draws: the RP estimate's standard error is ~0.4 %; 2 % is 5 of them."""
    robot = RobotLoader(30 * UM, lever=20 * MM)
    rng = np.random.default_rng(0)
    draws = [robot.land(rng) for _ in range(20000)]
    distance = np.linalg.norm([d.delta for d in draws], axis=1)
    assert distance.mean() + 3 * distance.std() == pytest.approx(30 * UM, rel=0.02)
    angles = np.array([[d.alpha, d.beta, d.gamma] for d in draws])
    sigma = 30 * UM / RP_PER_SIGMA / (20 * MM)
    np.testing.assert_allclose(angles.std(axis=0), sigma, rtol=0.03)
    # seeded: the same seed lands the same workpiece
    assert robot.land(5) == robot.land(5) and robot.land(5) != robot.land(6)
    assert RobotLoader(0.0).land(1) == WorkpieceSetting()


def test_robot_refuses_bad_parameters():
    with pytest.raises(InputError, match="repeatability >= 0"):
        RobotLoader(-1e-6)
    with pytest.raises(InputError, match="lever > 0"):
        RobotLoader(30e-6, lever=0.0)
    with pytest.raises(InputError, match="rng"):
        RobotLoader().land("seed")


def test_robot_refuses_a_repeatability_whose_landings_no_setting_takes():
    # its landing 3 standard deviations out must be a setting WorkpieceSetting takes (1 m,
    # 180 deg). By hand: RP = 3.6161 s; with a 20 mm lever the angle binds first,
    # 3 s / 20 mm = pi rad at RP = 3.6161 * pi * 20 mm / 3 = 75.74 mm; with a 1 m lever the
    # length does, 3 s = 1 m at RP = 3.6161 / 3 m = 1.2054 m. 2 m (a unit slip for 2 mm)
    # failed each landing one at a time
    assert RobotLoader.largest_repeatability(20 * MM) == pytest.approx(75.74 * MM, rel=1e-3)
    assert RobotLoader.largest_repeatability(1.0) == pytest.approx(1.2054, rel=1e-3)
    RobotLoader(75.7 * MM, lever=20 * MM)
    with pytest.raises(InputError, match=r"key 'repeatability': a robot of repeatability "
                       r"0\.0758 m and lever 0\.02 m .* is no angle error"):
        RobotLoader(75.8 * MM, lever=20 * MM)
    RobotLoader(1.2, lever=1.0)
    with pytest.raises(InputError, match=r"is no length error.*at most 1\.205\d* m"):
        RobotLoader(2.0, lever=1.0)


# ------------------------------------------------------------------ eqs 1-7, exactly


def test_eqs_1_to_4_give_back_the_setting_and_agree_with_a_kabsch_fit():
    rng = np.random.default_rng(1)
    designed = cam.GROOVE_SPHERES.centres
    for _ in range(20):
        s = random_setting(rng, scale=30.0)  # up to ~0.1 rad: the formulas are exact
        r = rotation_xyz(s.alpha, s.beta, s.gamma)
        centres = s.delta + designed @ r.T
        found, delta = ws.setting_from_centres(centres, designed)
        # float64 round-off on mm coordinates and unit-size rotations
        np.testing.assert_allclose(found.delta, s.delta, rtol=0, atol=1e-15)
        np.testing.assert_allclose([found.alpha, found.beta, found.gamma],
                                   [s.alpha, s.beta, s.gamma], rtol=0, atol=1e-13)
        np.testing.assert_allclose(delta, centres[0] - designed[0], rtol=0, atol=0)
        # a second method: least-squares rotation (Kabsch) of the designed onto the measured
        a, b = designed - designed.mean(0), centres - centres.mean(0)
        u, _, vt = np.linalg.svd(b.T @ a)
        kabsch = u @ np.diag([1, 1, np.linalg.det(u @ vt)]) @ vt
        np.testing.assert_allclose(rotation_xyz(found.alpha, found.beta, found.gamma), kabsch,
                                   rtol=0, atol=1e-13)


def test_a_first_order_lobing_shifts_every_centre_by_its_amplitude(groove_stock):
    """A probe stated to lob at first order by a (phase unknown) reads every contact
    a cos(phi - phi_1) further along its normal: to first order the whole cavity moved by a
    towards phi_1 (`Lobing`), so every fitted centre, every bottom touch under it and so the
    C centre and the position move by a in that unknown direction: a / sqrt(2) per
    coordinate, and no angle (derived by hand; 2000 probes drawn: within ~1.6 %)."""
    from machinesim.identification import workpiece_setting_uncertainty as wsu

    probe = TouchProbe(MACHINE, ErrorModel(), groove_stock, noise=False)
    readings = read_spheres(probe, cam.GROOVE_SPHERES)
    assert probe.lobing_amplitudes == {} and wsu.contact_std(readings)["workpiece.x"] == 0.0
    a = 20 * NM
    std = wsu.contact_std(replace(readings, lobing_amplitudes={1: a}), draws=2000)
    for name in ("workpiece.x", "workpiece.y", "location.C.EX0C", "location.C.EY0C"):
        assert std[name] == pytest.approx(a / math.sqrt(2.0), rel=0.06), name
    assert std["workpiece.gamma"] < 1e-3 * a / (12 * MM)


def test_the_spheres_tolerance_through_eqs_1_to_4_matches_a_monte_carlo():
    """Spheres made 1 um (per coordinate) off their design: the linear propagation of
    `design_std` against 4000 drawn workshops through the same eqs (a second method: no
    linearisation), to 5 % (the Monte Carlo's own ~1.1 % and the first order's ~1e-4)."""
    rng = np.random.default_rng(7)
    designed = cam.GROOVE_SPHERES.centres
    s = random_setting(rng)
    r = rotation_xyz(s.alpha, s.beta, s.gamma)
    centres = s.delta + designed @ r.T
    found = Identification(centres, 2.0 * MM, s, np.zeros(3), np.zeros(2), np.zeros((3, 2)),
                           ())
    std = wsu.design_std(found, designed, 1 * UM)
    draws = []
    for _ in range(4000):
        made = centres + rng.normal(0.0, 1 * UM, (3, 3))
        got, _ = ws.setting_from_centres(made, designed)
        draws.append([*got.delta, got.alpha, got.beta, got.gamma])
    spread = np.std(draws, axis=0)
    np.testing.assert_allclose([std[n] for n in ws.PARAMETERS[:6]], spread, rtol=0.05)
    # alpha and beta both read S1: their correlation, as the drawn workshops show it (the
    # Monte Carlo's own ~0.016 at 4000 draws)
    drawn = np.corrcoef(np.array(draws)[:, 3], np.array(draws)[:, 4])[0, 1]
    assert abs(wsu.tilt_correlation(wsu.design_covariance(found, designed, 1 * UM))
               - drawn) < 0.05
    assert abs(drawn) > 0.2  # S1 is shared: not independent
    # ~1 um and ~0.1 mrad (1 um over the 12 mm between spheres): the paper's "less than 1-2
    # um" and ~0.007 deg; the C centre compares each sphere with itself
    assert 0.5 * UM < std["workpiece.x"] < 2 * UM and 5e-5 < std["workpiece.gamma"] < 2e-4
    assert std["location.C.EX0C"] == std["location.C.EY0C"] == 0.0


def lowest_point(pose, wanted_z, rho):
    """The point of a nose arc (radius rho about (0, 0, rho) in the tool's Y-Z plane) lowest
    along ``wanted_z``, by its own closed form: p(phi) = c + rho (sin phi y - cos phi z) is
    lowest where tan(phi) = (w.y) / (w.z), w = wanted_z."""
    y, z = pose[:3, 1], pose[:3, 2]
    centre = pose[:3, 3] + rho * z
    phi = math.atan2(wanted_z @ y, wanted_z @ z)
    return centre + rho * (-math.sin(phi) * y - math.cos(phi) * z)


def test_eqs_5_to_7_put_the_tip_or_the_nose_on_the_path_on_the_true_machine():
    """A random program (x, y, z, b, c) on a machine with a setting error and a C centre
    off the origin: the compensated program puts the tip where the nominal one does on the
    ideal machine (eq 7 is exact for the position), and with the nose correction the arc's
    lowest point; both routes (eqs 5-7 and inverse kinematics), unrounded (the formulas;
    the NC text rounds to 1 nm)."""
    rng = np.random.default_rng(2)
    b = ProgramBuilder(1)
    for _ in range(12):
        b.rapid(X=rng.uniform(-3, 3) * MM, Y=rng.uniform(-3, 3) * MM,
                Z=rng.uniform(-0.2, 0.5) * MM, B=rng.uniform(-0.2, 0.2),
                C=rng.uniform(-math.pi, math.pi))
    nominal = b.build()
    ideal = MACHINE.tool_pose(program_axes(nominal, MACHINE))
    for _ in range(3):
        s, c0 = random_setting(rng, scale=3.0), rng.normal(0.0, 5 * UM, 2)
        errors = ErrorModel(workpiece=s, location={"C": {"EX0C": c0[0], "EY0C": c0[1]}})
        found = truth(s, c0)
        for nose in (0.0, NOSE):
            for route in (eqs_5_to_7_program, model_based_program):
                program = route(nominal, MACHINE, found, nose, rounded=False)
                q = program_axes(program, MACHINE)
                poses = MACHINE.tool_pose(q, errors)
                if nose == 0.0:
                    # 1e-12 m: kinematic agreement of two float64 chains (tolerances.POSE_M)
                    np.testing.assert_allclose(poses[:, :3, 3], ideal[:, :3, 3], rtol=0,
                                               atol=1e-12)
                else:
                    got = [lowest_point(p, w[:3, 2], nose) for p, w in zip(poses, ideal,
                                                                           strict=True)]
                    want = [lowest_point(w, w[:3, 2], nose) for w in ideal]
                    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12)
                if route is eqs_5_to_7_program:
                    np.testing.assert_allclose(q[:, 3:], program_axes(nominal, MACHINE)[:, 3:]
                                               + [s.beta, s.gamma], rtol=0, atol=1e-15)


def test_the_nose_shift_is_nothing_for_a_pitch_and_keeps_the_centre_for_a_roll():
    wanted = np.eye(3)[None]
    pitch = rotation_xyz(0.0, 1e-3, 0.0)[None]
    np.testing.assert_allclose(ws.nose_shift(wanted, pitch, NOSE), 0.0, atol=1e-18)
    roll = rotation_xyz(2e-3, 0.0, 0.0)[None]
    shift = ws.nose_shift(wanted, roll, NOSE)[0]
    # the rolled arc's centre (tip + shift + rho z') is the wanted centre rho z
    np.testing.assert_allclose(shift + NOSE * roll[0, :, 2], NOSE * wanted[0, :, 2], atol=1e-18)
    assert ws.nose_shift(wanted, roll, 0.0).tolist() == [[0.0, 0.0, 0.0]]


def test_the_compensated_program_is_the_formulas_rounded_to_the_resolution():
    """map_program's rule: the NC text's values (1 nm, 0.00001 deg), within half a step of
    the formulas, and every axis in every motion block."""
    setting = WorkpieceSetting([2 * UM, -3 * UM, -1 * UM], 3e-4, 2e-4, 1e-3)
    nominal = cam.groove_program()
    exact = program_axes(eqs_5_to_7_program(nominal, MACHINE, truth(setting), rounded=False),
                         MACHINE)
    program = eqs_5_to_7_program(nominal, MACHINE, truth(setting))
    rounded = program_axes(program, MACHINE)
    step = np.array([1 * NM] * 3 + [math.radians(1e-5)] * 2)
    assert (np.abs(rounded - exact) <= 0.5 * step * (1 + 1e-9)).all()
    assert all(set(m.target) == set("XYZBC") for m in program.moves)


def groove_bottoms(program, errors) -> np.ndarray:
    """Depths (4, stations) the kinematics predict: how far the nose arc's lowest point runs
    below the part's top face, where its path crosses each station's profile (the path is
    straight: the line through its ends, found along each groove's direction)."""
    q = program_axes(program, MACHINE)
    # the feeds along the grooves: the moves the nominal program makes from X = 0 to 1 mm
    plain = program_axes(cam.groove_program(), MACHINE)
    feeds = [n for n in range(1, len(plain)) if plain[n, 0] > 0.0 and plain[n - 1, 0] == 0.0
             and program.moves[n].kind == "linear"]
    up = np.array([0.0, 0.0, 1.0])
    out = np.zeros((4, len(part_features.STATIONS)))
    for k, n in enumerate(feeds):
        ends = [lowest_point(MACHINE.tool_pose(q[i], errors), up, NOSE) for i in (n - 1, n)]
        along = np.array([math.cos(k * math.pi / 2), math.sin(k * math.pi / 2), 0.0])
        for j, t in enumerate(part_features.STATIONS):
            f = (t - ends[0] @ along) / ((ends[1] - ends[0]) @ along)
            out[k, j] = -(ends[0] + f * (ends[1] - ends[0]))[2]
    # a tool above the face cuts nothing there (the paper's groove that "did not appear")
    return np.maximum(out, 0.0)


def test_grooves_follow_the_kinematics_before_and_after(groove_stock):
    """The groove depths read with the microscope (noise off) are the nose's lowest point
    below the misplaced top face, to 2 nm (the microscope's 1 nm rounding and the bottom
    fit). Before: 3 um plus the face's height over the path. After (eqs 5-7, the injected
    state, unrounded): a roll of 0.3 deg (5 mrad) deepens the tip-compensated grooves cut at
    C = 0 and 180 deg by the nose's R (1 - cos th) = 27 nm; the nose-corrected ones are
    3 um. The roll makes one groove an air cut before compensation, as in the paper's
    Fig. 8a."""
    setting = WorkpieceSetting([2 * UM, -3 * UM, -1 * UM], math.radians(0.3), 2e-4, 1e-3)
    errors = ErrorModel(workpiece=setting)
    scope = Microscope(noise=False)
    nominal = cam.groove_program()
    sag = NOSE * (1 - math.cos(setting.alpha))
    for program, expected in (
            (nominal, None),
            (eqs_5_to_7_program(nominal, MACHINE, truth(setting), rounded=False),
             3 * UM + np.array([sag, 0.0, sag, 0.0])[:, None]),
            (eqs_5_to_7_program(nominal, MACHINE, truth(setting), NOSE, rounded=False),
             3 * UM)):
        part, report = cut(program, MACHINE, tool="nose:2.0:90", stock=groove_stock,
                           errors=errors, roi=cam.GROOVE_ROI, start=cam.PARK)
        assert report.rapids_that_cut == () and not report.empty_cut
        read = groove_depths(part, scope).depths
        predicted = groove_bottoms(program, errors)
        np.testing.assert_allclose(read, predicted, rtol=0, atol=2 * NM)
        if expected is not None:
            # the kinematics themselves: sub-nm (the other tilt, 2e-4 rad, sags 0.04 nm)
            np.testing.assert_allclose(predicted, np.broadcast_to(expected, predicted.shape),
                                       rtol=0, atol=0.5 * NM)
    before = groove_bottoms(nominal, errors)
    assert np.ptp(before) > 1 * UM and (before == 0.0).any()


def test_bad_inputs_are_refused(groove_stock):
    with pytest.raises(InputError, match="S1 -> S2 along \\+X"):
        ws.ReferenceSpheres(np.array([[0, 0, 0], [0, 1, 0], [1, 0, 0]]) * MM)
    with pytest.raises(InputError, match="shape \\(3, 3\\)"):
        ws.ReferenceSpheres(np.zeros((2, 3)))
    with pytest.raises(InputError, match="points as a whole number >= 5"):
        ProbePlan(points=3)
    with pytest.raises(InputError, match="press > 0"):
        ProbePlan(press=-1.0)
    program = ProgramBuilder(1).rapid(X=0.0, A=0.1).build()
    with pytest.raises(InputError, match="axes XYZBC"):
        eqs_5_to_7_program(program, MACHINE, truth(WorkpieceSetting()))
    probe = TouchProbe(load_machine("robonano_ui"), None, groove_stock, frame="tool_tip")
    with pytest.raises(InputError, match="robonano_a0ib"):
        read_spheres(probe, cam.GROOVE_SPHERES)
    with pytest.raises(InputError, match="half width"):
        read_sphere(TouchProbe(MACHINE, None, groove_stock), [0, 0, 0],
                    ProbePlan(half_width=1.8 * MM))
    with pytest.raises(InputError, match="row range"):
        cam.crown_passes(top_rows=(1.0, 0.0))
    with pytest.raises(InputError, match="experiment in grooves, crown"):
        RobotLoadedWorkpiece("prism")
    # bool("off") is True: the nose stayed on the path, "no" cut the quick windows
    for flag in ("nose_correction", "all_layers", "quick", "after_only"):
        for value in ("off", "no", 0, None):
            with pytest.raises(InputError, match=f"key '{flag}': Expected {flag} as True or "
                               "False, got "):
                RobotLoadedWorkpiece("grooves", **{flag: value})
    assert RobotLoadedWorkpiece("crown", nose_correction=False).nose == 0.0
    # bare AttributeErrors at measure ('NoneType' object has no attribute 'half_width')
    for fields, message in (({"plan": None}, "key 'plan': expected a ProbePlan"),
                            ({"plan": {"points": 41}}, "key 'plan': expected a ProbePlan"),
                            ({"crown": None}, "key 'crown': expected a CrownPlan"),
                            ({"progress": "yes"}, "key 'progress': expected progress as a "
                             "callable")):
        with pytest.raises(InputError, match=re.escape(message)):
            RobotLoadedWorkpiece("crown", **fields)
    RobotLoadedWorkpiece("grooves", plan=ProbePlan(points=31), progress=print)  # taken
    assert RobotLoadedWorkpiece("crown", nose_correction=np.bool_(True)).nose > 0.0
    with pytest.raises(InputError, match="no axis A"):
        cut_turned(program, MACHINE, turn_axis="A")
