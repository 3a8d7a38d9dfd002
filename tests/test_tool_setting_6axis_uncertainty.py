"""Paper 001's stated uncertainty: each reading error propagated to the identified values,
checked against geometry worked by hand, against the generic fit's own covariance, and
against the errors a lab with a registered, positioning stage really makes."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from machinesim import ErrorModel, Lab
from machinesim.cam.tool_setting_plates import mark_point, pair_grooves
from machinesim.experiment import run
from machinesim.identification.tool_setting_6axis import identify
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
PROGRAMMED = np.array([spot for _, spot in pair_grooves()])
FLOOR = 1e-15  # below SIGMA_FLOOR_M: a reading held exact


@pytest.fixture(scope="module")
def readings():
    """The four plates of the default plan, cut and read exactly (no noise, no realism)."""
    lab = Lab("robonano_ui", ErrorModel().with_parameters(dict(DEFAULT_INJECTED)),
              noise=False, seed=0)
    procedure = ToolSetting6Axis()
    return procedure, procedure.measure(lab)


def with_sigma(plate, point=FLOOR, start=FLOOR, depth=FLOOR):
    return tuple(replace(g, point_sigma=np.full(len(g.points), point),
                         depth_sigma=np.full(len(g.depths), depth),
                         start_sigma=start if g.start is not None else g.start_sigma)
                 for g in plate)


def paper_std(m, a, c, b, registration=None):
    plan = ToolSetting6Axis().plan
    found = identify(m.z_touch, a, c, b, PROGRAMMED, plan.theta2, plan.theta3,
                     mark_at=mark_point(), registration=registration)
    return found.std


def test_a_turned_frame_moves_the_pair_by_the_turn_times_their_distance(readings):
    """The A plate read in a frame turned by t about the origin: each start point p moves by
    t (-p_y, p_x), so their difference (dX, dY) by t (-dY, dX) and dx, dy, its half, by
    t/2 (-dY, dX). Offsets move both alike and cancel."""
    _, m = readings
    a, c, b = with_sigma(m.a), with_sigma(m.c), with_sigma(m.b)
    turn = 1e-3
    std = paper_std(m, a, c, b, {"a": RegistrationScatter(5 * UM, 10 * UM, turn, 0.2e-3)})
    gap = m.a[0].start - m.a[1].start
    assert std["tool.x"] == pytest.approx(turn * abs(gap[1]) / 2, rel=1e-6)
    assert std["tool.y"] == pytest.approx(turn * abs(gap[0]) / 2, rel=1e-6)
    # the triangle is placed by its mark, on its own plate: plate a's frame is not in it
    # (beyond the A result it was cut with, below)
    assert std["location.C.EX0C"] == pytest.approx(std["tool.y"], rel=1e-6)


def test_the_mark_carries_the_error_of_dy_into_the_c_centre(readings):
    """The C plate is cut with the A pair's dx, dy: an error of dy moves its C = 0 side
    across by that much and its mark (cut at A = 90 deg) along x by minus it; the triangle's
    centre stays (its three sides move out alike). The mark places the triangle, so e is off
    by (-1, +1) times the error of dy: each std of e is dy's, and dx is not in it."""
    _, m = readings
    a = with_sigma(m.a, point=1 * UM, start=1 * UM)
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
    a = with_sigma(m.a, point=30e-9, start=20e-9)
    c, b = with_sigma(m.c, point=40e-9), with_sigma(m.b, point=25e-9, depth=10e-9)
    check = fit_check(machine, a, c, b)
    std = propagated_std(lambda a, c, b: fit_check(machine, a, c, b).values, a, c, b,
                         PROGRAMMED)
    np.testing.assert_allclose(std, check.std, rtol=1e-4)


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


def test_with_the_background_on_the_pair_reads_the_edge_from_the_real_a_centre():
    """With the machine's own errors alone, the A axis turns about (EX0A, EY0A) off its
    nominal centre: the start points part by 2 (d - c_A), so dx, dy come out off the
    injected offset by -c_A (0.2, -0.15 um in the background file), to the few nm its
    angular errors add."""
    lab = Lab("robonano_ui", ErrorModel().with_parameters(dict(DEFAULT_INJECTED)), seed=0,
              realism=Realism.with_only("background_errors"))
    result = run(ToolSetting6Axis(), lab)
    machine = lab.reveal().parameters()
    centre = np.array([machine["location.A.EX0A"], machine["location.A.EY0A"]])
    assert np.linalg.norm(centre) > 0.2 * UM
    found = np.array([result.identified[n][0] for n in ("tool.x", "tool.y")])
    injected = np.array([result.injected[n] for n in ("tool.x", "tool.y")])
    np.testing.assert_allclose(found - injected, -centre, atol=10e-9)


# ---------------------------------------------------------------- the "after" over labs

def table(procedure, plates):
    return dict(zip(("a_dx", "a_dy", "c_dx", "c_dy", "b2", "b3"),
                    procedure._table_values(*plates), strict=True))


def test_compensating_more_moves_what_is_read_after_by_minus_as_much(readings):
    """Plates cut with the C centre compensated by de more read a C centre de lower (the
    programs turn about e + de), and the A pair, cut at C = 0, does not move; cut with the
    tool offset compensated by dd more, the pair's distance (2 d) is 2 dd lower, and the
    triangle, placed by its mark, reads (-1, +1) dd_y (the mark test above)."""
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
    for key in ("a_dx", "a_dy", "b2", "b3"):
        assert got[key] == pytest.approx(base[key], abs=1e-9)
    dd = np.array([1.0, -2.0, 0.0]) * UM
    got = moved(dd, None)
    assert got["a_dx"] - base["a_dx"] == pytest.approx(-2.0, abs=1e-9)
    assert got["a_dy"] - base["a_dy"] == pytest.approx(4.0, abs=1e-9)
    assert got["c_dx"] - base["c_dx"] == pytest.approx(2.0, abs=1e-9)
    assert got["c_dy"] - base["c_dy"] == pytest.approx(-2.0, abs=1e-9)


def test_the_after_holds_both_readings_and_the_mark_cancels(readings):
    """With the same readings before and after, an A figure's after std is sqrt(2) times its
    reading's (the identification's error, compensated in, and the after's own reading).
    With only the A pair uncertain, the identified e carries dy's error (the mark) but the C
    figures after do not: the compensated C plate is cut with the same dy and its mark
    reads it alike, so the two cancel."""
    procedure, m = readings
    a = with_sigma(m.a, point=1 * UM, start=1 * UM)
    c, b = with_sigma(m.c), with_sigma(m.b)
    plates = (a, c, b)
    std = dict(zip(("a_dx", "a_dy", "c_dx", "c_dy", "b2", "b3"), after_std(
        procedure._table_values, procedure._compensation_values, plates, plates,
        PROGRAMMED), strict=True))
    reading = propagated_std(procedure._table_values, *plates, PROGRAMMED)
    assert reading[0] > 1.0 and reading[1] > 1.0        # um: the pair is uncertain
    assert std["a_dx"] == pytest.approx(np.sqrt(2.0) * reading[0], rel=1e-6)
    assert std["a_dy"] == pytest.approx(np.sqrt(2.0) * reading[1], rel=1e-6)
    assert paper_std(m, a, c, b)["location.C.EX0C"] > 0.5 * UM
    # um: what is left is the exact C readings' floor (SIGMA_FLOOR_M, picometres)
    assert std["c_dx"] < 1e-5 and std["c_dy"] < 1e-5
