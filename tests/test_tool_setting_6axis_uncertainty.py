"""Paper 001's stated uncertainty: each reading error propagated to the identified values,
checked against geometry worked by hand, against the generic fit's own covariance, and
against the errors a lab with a registered, positioning stage really makes."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import machinesim.identification.tool_setting_6axis_uncertainty as uncertainty
from machinesim import ErrorModel, Lab
from machinesim.cam.tool_setting_plates import SET_LENGTH, mark_point
from machinesim.experiment import run
from machinesim.identification.tool_setting_6axis import a_axis_sets, identify
from machinesim.identification.tool_setting_6axis_fit import fit_check
from machinesim.identification.tool_setting_6axis_uncertainty import (
    _displaced,
    after_std,
    propagated_std,
)
from machinesim.metrology.imperfections import RegistrationScatter
from machinesim.procedures.tool_setting_6axis import DEFAULT_INJECTED, ToolSetting6Axis
from machinesim.realism import Realism

UM = 1e-6
FLOOR = 1e-15  # below SIGMA_FLOOR_M: a reading held exact


@pytest.fixture(scope="module")
def readings():
    """The four plates of the default plan, cut and read exactly (no noise, no realism)."""
    lab = Lab("robonano_ui", ErrorModel().with_parameters(dict(DEFAULT_INJECTED)),
              noise=False, seed=0)
    procedure = ToolSetting6Axis()
    return procedure, procedure.measure(lab)


def with_sigma(plate, point=FLOOR, end=FLOOR, depth=FLOOR):
    return tuple(replace(g, point_sigma=np.full(len(g.points), point),
                         depth_sigma=np.full(len(g.depths), depth),
                         end_sigma=end if g.end is not None else g.end_sigma)
                 for g in plate)


def paper_std(m, a, c, b, registration=None):
    plan = ToolSetting6Axis().plan
    found = identify(m.z_touch, a, c, b, SET_LENGTH, plan.theta2, plan.theta3,
                     mark_at=mark_point(), registration=registration)
    return found.std


def turned(plate, turn, shift):
    """Readings of ``plate`` as a frame turned by ``turn`` about the origin and shifted by
    ``shift`` would give them (exactly, not to first order)."""
    rot = np.array([[np.cos(turn), -np.sin(turn)], [np.sin(turn), np.cos(turn)]])
    return tuple(replace(g, points=g.points @ rot.T + shift,
                         end=None if g.end is None else rot @ g.end + shift) for g in plate)


def test_the_a_sets_read_the_same_in_a_turned_and_shifted_frame(readings):
    """Each A set is read between its own two lines: along them the end points' distance,
    across them the lines' offset. A frame turned by 1.3 mrad and shifted by 7 um moves
    every end point by micrometres (1.3 mrad at 10 mm: 13 um), and leaves d and e as they
    were, to rounding; with the old pair 2 mm apart the turn alone moved dx by 1.3 um."""
    _, m = readings
    moved = turned(m.a, 1.3e-3, np.array([7.0, -4.0]) * UM)
    assert np.abs(np.array([g.end for g in moved]) - [g.end for g in m.a]).max() > 10 * UM
    base, got = a_axis_sets(m.a, SET_LENGTH), a_axis_sets(moved, SET_LENGTH)
    np.testing.assert_allclose(got.offset, base.offset, atol=1e-12)
    np.testing.assert_allclose(got.centre, base.centre, atol=1e-12)
    # the propagation finds the same: the stated registration of plate a adds nothing
    a, c, b = with_sigma(m.a), with_sigma(m.c), with_sigma(m.b)
    std = paper_std(m, a, c, b, {"a": RegistrationScatter(5 * UM, 10 * UM, 1e-3, 0.2e-3)})
    assert max(std.values()) < 1e-11


def test_the_mark_carries_the_error_of_dy_into_the_c_centre(readings):
    """The C plate is cut with the A sets' dx, dy: an error of dy moves its C = 0 side
    across by that much and its mark (cut at A = 90 deg) along x by minus it; the triangle's
    centre stays (its three sides move out alike). The mark places the triangle, so e is off
    by (-1, +1) times the error of dy: each std of e is dy's, and dx is not in it."""
    _, m = readings
    a = with_sigma(m.a, point=1 * UM, end=1 * UM)
    std = paper_std(m, a, with_sigma(m.c), with_sigma(m.b))
    assert std["tool.y"] > 0.1 * UM
    assert std["location.C.EX0C"] == pytest.approx(std["tool.y"], rel=1e-6)
    assert std["location.C.EY0C"] == pytest.approx(std["tool.y"], rel=1e-6)
    # the B depths are taken back to one commanded Z: dZ is not moved by the A result
    assert std["tool.z"] < 1e-10


def test_the_propagation_through_the_fit_is_its_own_covariance(readings):
    """Without registration, the fit's central-difference uncertainty is the one its
    normal equations give: the same independent errors, a second method. The plates cut
    with the A result move with the programs they were cut with, which the fit reads, so
    that coupling leaves the fit alone."""
    procedure, m = readings
    machine = procedure._machine()
    a = with_sigma(m.a, point=30e-9, end=20e-9)
    c, b = with_sigma(m.c, point=40e-9), with_sigma(m.b, point=25e-9, depth=10e-9)
    check = fit_check(machine, a, c, b)
    std = propagated_std(lambda a, c, b: fit_check(machine, a, c, b).values, a, c, b,
                         SET_LENGTH)
    np.testing.assert_allclose(std, check.std, rtol=1e-4)


def test_the_propagated_std_holds_at_three_times_the_step_either_way(readings, monkeypatch):
    """The step is on the plateau: the std the procedure states (the fit's own covariance
    with the registration propagated through the fit, and the paper's) moves neither with a
    step 3x smaller (round-off) nor 3x larger (truncation). The lab's sigmas (1 um per
    reading, depths 3-7 nm) and registration (5 um, 1 mrad) give tool.y's fit std 3.4 nm,
    2.0 nm of it from the registration, mostly through plate a's turn: a small column, off
    by 1e-3 eps / h with the fit's eps ~ 4e-17 m, so by at most ~7e-13 m over the three turns
    at h / 3 = 1e-7 (PROPAGATION_STEP's note; here 9e-14 m); from the old step, 1e-9, it
    moved by 3.3e-12 m at 3e-9 and by 3.4e-11 m at 3.3e-10. The paper's formulas are
    truncation-limited: 5e4 h^2 relative, 4e-8 at 3h (here 3.7e-8 on C centre y)."""
    procedure, m = readings
    machine = procedure._machine()
    a = with_sigma(m.a, point=1 * UM, end=1 * UM, depth=6e-9)
    c = with_sigma(m.c, point=1 * UM, depth=7e-9)
    b = with_sigma(m.b, point=1 * UM, depth=3e-9)
    registration = dict.fromkeys("acb", RegistrationScatter(5 * UM, 10 * UM, 1e-3, 0.2e-3))
    own = fit_check(machine, a, c, b).std

    def stated(step):
        monkeypatch.setattr(uncertainty, "PROPAGATION_STEP", step)
        frames = propagated_std(lambda a, c, b: fit_check(machine, a, c, b).values, a, c,
                                b, SET_LENGTH, registration, own_errors=False)
        paper = paper_std(m, a, c, b, registration)
        return np.hypot(own, frames), np.array(list(paper.values()))

    h = uncertainty.PROPAGATION_STEP
    fit, paper = stated(h)
    assert fit[1] > 3e-9 and paper.min() > 1e-8    # m: the registration's small column
    for step in (h / 3.0, 3.0 * h):
        other_fit, other_paper = stated(step)
        np.testing.assert_allclose(other_fit, fit, rtol=1e-6, atol=1e-12)
        np.testing.assert_allclose(other_paper, paper, rtol=1e-6)


def test_a_lab_with_a_registered_stage_errs_within_the_stated_uncertainty():
    """The lab's registration (5 um, 1 mrad) and stage positioning (1 um per reading) move
    the identified values by micrometres, far beyond the readings' fits: the stated std
    covers them (within 4 std), and is not blown up beyond them (below 3 um)."""
    lab = Lab("robonano_ui", ErrorModel().with_parameters(dict(DEFAULT_INJECTED)), seed=0,
              realism=Realism.with_only("registration", "stage_positioning"))
    result = run(ToolSetting6Axis(), lab)
    check = result.evaluation.details["fit_check"]
    for name, (value, std) in result.identified.items():
        error = value - result.injected[name]
        assert abs(error) < 4 * std < 12 * UM, (name, error, std)
        fit_error = check[name]["fit_um"] * UM - result.injected[name]
        assert abs(fit_error) < 4 * check[name]["fit_std_nm"] * 1e-9, (name, fit_error)
    assert result.identified["tool.x"][1] > 0.5 * UM


def test_with_the_background_on_the_sets_read_the_edge_from_the_real_a_centre():
    """With the machine's own errors alone, the A axis turns about c_A = (EX0A, EY0A) off
    its nominal centre: the edge offset at A is ``c_A + Rz(A) (d - c_A)``, so the A = 0 set
    relates as 2 (d - e) and the A = 180 deg set as 2 (d - 2 c_A + e): dx, dy come out off
    the injected offset by -c_A (0.2, -0.15 um in the background file), to what its angular
    errors and the X axis's own positioning and straightness add where the grooves end,
    8 mm out (up to 12 nm there in the background file: 20 nm)."""
    lab = Lab("robonano_ui", ErrorModel().with_parameters(dict(DEFAULT_INJECTED)), seed=0,
              realism=Realism.with_only("background_errors"))
    result = run(ToolSetting6Axis(), lab)
    machine = lab.reveal().parameters()
    centre = np.array([machine["location.A.EX0A"], machine["location.A.EY0A"]])
    assert np.linalg.norm(centre) > 0.2 * UM
    found = np.array([result.identified[n][0] for n in ("tool.x", "tool.y")])
    injected = np.array([result.injected[n] for n in ("tool.x", "tool.y")])
    np.testing.assert_allclose(found - injected, -centre, atol=20e-9)


# ---------------------------------------------------------------- the "after" over labs

def table(procedure, plates):
    return dict(zip(("a_dx", "a_dy", "c_dx", "c_dy", "b2", "b3"),
                    procedure._table_values(*plates), strict=True))


def test_compensating_more_moves_what_is_read_after_by_minus_as_much(readings):
    """Plates cut with the C centre compensated by de more read a C centre de lower (the
    programs turn about e + de); the A sets' grooves cut at C = 180 deg move by -2 de, so
    the A = 0 set's relation 2 (d - e) grows by 2 de and the A = 180 deg set's 2 (d + e)
    shrinks by as much: their half sum, the A figures, does not move, and the A sets' own
    reading of e is de lower. Cut with the tool offset compensated by dd more, the A
    distance (2 d) is 2 dd lower, and the triangle, placed by its mark, reads (-1, +1) dd_y
    (the mark test above).

    The A figures hold to 1e-6 um, not to round-off: a move in the workpiece frame is read
    across lines whose direction the 1 nm height display turns by ~1e-8 rad, which projects
    a 6 um move by ~1e-13 m."""
    procedure, m = readings
    plates = (m.a, m.c, m.b)
    base = table(procedure, plates)

    def moved(delta, centre):
        return table(procedure, tuple(tuple(_displaced(g, np.asarray(delta), centre)
                                            for g in plate) for plate in plates))

    de = np.array([3.0, -1.0]) * UM
    got = moved([0.0, 0.0, 0.0], de)
    assert got["c_dx"] - base["c_dx"] == pytest.approx(-3.0, abs=1e-9)
    assert got["c_dy"] - base["c_dy"] == pytest.approx(1.0, abs=1e-9)
    for key in ("a_dx", "a_dy"):
        assert got[key] == pytest.approx(base[key], abs=1e-6)
    for key in ("b2", "b3"):
        assert got[key] == pytest.approx(base[key], abs=1e-9)
    sets = a_axis_sets(tuple(_displaced(g, np.zeros(3), de) for g in m.a), SET_LENGTH)
    np.testing.assert_allclose(sets.centre - a_axis_sets(m.a, SET_LENGTH).centre, -de,
                               atol=1e-12)
    dd = np.array([1.0, -2.0, 0.0]) * UM
    got = moved(dd, None)
    assert got["a_dx"] - base["a_dx"] == pytest.approx(-2.0, abs=1e-6)
    assert got["a_dy"] - base["a_dy"] == pytest.approx(4.0, abs=1e-6)
    assert got["c_dx"] - base["c_dx"] == pytest.approx(2.0, abs=1e-9)
    assert got["c_dy"] - base["c_dy"] == pytest.approx(-2.0, abs=1e-9)


def test_the_after_holds_both_readings_and_the_mark_cancels(readings):
    """With the same readings before and after, an A figure's after std is sqrt(2) times its
    reading's (the identification's error, compensated in, and the after's own reading).
    With only the A sets uncertain, the identified e carries dy's error (the mark) but the C
    figures after do not: the compensated C plate is cut with the same dy and its mark
    reads it alike, so the two cancel."""
    procedure, m = readings
    a = with_sigma(m.a, point=1 * UM, end=1 * UM)
    c, b = with_sigma(m.c), with_sigma(m.b)
    plates = (a, c, b)
    std = dict(zip(("a_dx", "a_dy", "c_dx", "c_dy", "b2", "b3"), after_std(
        procedure._table_values, procedure._compensation_values, plates, plates,
        SET_LENGTH), strict=True))
    reading = propagated_std(procedure._table_values, *plates, SET_LENGTH)
    assert reading[0] > 1.0 and reading[1] > 1.0        # um: the sets are uncertain
    assert std["a_dx"] == pytest.approx(np.sqrt(2.0) * reading[0], rel=1e-6)
    assert std["a_dy"] == pytest.approx(np.sqrt(2.0) * reading[1], rel=1e-6)
    assert paper_std(m, a, c, b)["location.C.EX0C"] > 0.5 * UM
    # um: what is left is the exact C readings' floor (SIGMA_FLOOR_M, picometres)
    assert std["c_dx"] < 1e-5 and std["c_dy"] < 1e-5
