"""Paper 001 replay, the equations: the B-axis equations and the A sets against the
kinematics, an A groove within reach read at the capture range's worst corner, and the
compensation rule (the edge where the NC data put it, the plate programs as before)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from tool_setting_6axis_helpers import errors_of, paper_offsets, printed_eq2

from machinesim import load_machine
from machinesim.cam.tool_setting_plates import A_REACH, PARKED, SET_LENGTH, a_grooves, plate_cuts
from machinesim.compensation import program_axes
from machinesim.exceptions import InputError
from machinesim.identification import tool_setting_6axis as ident
from machinesim.nc import Move, Program
from machinesim.procedures.tool_setting_6axis import compensate_program
from machinesim.procedures.tool_setting_6axis_reading import A_WINDOW, STATIONS

UM, MM = 1e-6, 1e-3
MACHINE = load_machine("robonano_ui")


def edge_z(d, a, b):
    q = np.array([0.0, 0.0, 0.0, a, b, 0.0])
    return MACHINE.tool_pose(q, errors_of(d, (0.0, 0.0)))[2, 3]


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
        dx, dz = ident.b_axis_offsets(*depths, t2, t3)
        # the 1e-15 m round-off above, divided by (1 - cos t) ~ 0.015 at the smallest tilt
        assert dx == pytest.approx(-d[1], abs=1e-13)
        assert dz == pytest.approx(d[2], abs=1e-13)
        assert abs(printed_eq2(*depths, t2, t3) - d[2]) > 10 * UM
        result = ident.b_axis_tilts(depths, t2, t3)
        assert (result.offset_x, result.offset_z) == (dx, dz)


def test_a_sets_follow_from_the_kinematics():
    """The A sets' grooves where Machine.tool_pose puts the edge (each groove from the
    programmed origin, L along the tool's X at A, at C and C + 180 deg): their end points and
    centre lines give d and e back exactly, whatever the signs, and the relations are
    2 (d - e) at A = 0 and 2 (d + e) at A = 180 deg."""
    rng = np.random.default_rng(4)
    for _ in range(4):
        d = rng.uniform(-450, 450, 3) * UM
        e = rng.uniform(-900, 900, 2) * UM
        grooves = []
        for angle, turn in a_grooves():
            q0 = np.array([0.0, 0.0, 0.0, angle, 0.0, turn])
            q1 = q0 + [SET_LENGTH * math.cos(angle), SET_LENGTH * math.sin(angle), 0, 0, 0, 0]
            stations = q0 + np.linspace(0.4, 0.6, 5)[:, None] * (q1 - q0)
            tip = MACHINE.tool_pose(np.vstack([stations, q1]), errors_of(d, e))[:, :2, 3]
            grooves.append(ident.GrooveReading(q0, q1, tip[:-1], np.full(5, 1e-9),
                                               np.zeros(5), np.full(5, 1e-9), end=tip[-1]))
        found = ident.a_axis_sets(grooves, SET_LENGTH)
        # 1e-13 m: float64 round-off of the chain at the 0.3 m scale of the machine
        np.testing.assert_allclose(found.offset, d[:2], atol=1e-13)
        np.testing.assert_allclose(found.centre, e, atol=1e-13)
        np.testing.assert_allclose(found.relations, [2 * (d[:2] - e), 2 * (d[:2] + e)],
                                   atol=1e-13)
        np.testing.assert_allclose(found.distances, [2 * d[:2]], atol=1e-13)
    with pytest.raises(InputError, match="two or more sets of two A grooves"):
        ident.a_axis_sets(grooves[:3], SET_LENGTH)
    with pytest.raises(InputError, match="separate d from e"):
        ident.a_axis_sets(grooves[:2] * 2, SET_LENGTH)


def test_an_a_groove_lands_within_a_reach_and_is_read_at_the_capture_s_worst_corner():
    # a groove cut at C lands at e + Rz(C) (P + Rz(A) d - e): the start of the C = 180 deg
    # groove at A = 0 lands at 2 e - (dx, dy), |(dx, dy)| + 2 |e| = sqrt(2) 0.5 + 2 mm from
    # its place when dx, dy are at the capture's +-0.5 mm and e (1 mm) points against them
    # (A_REACH was |d| + 2 |e| with |d| taken as 0.5 mm: 2.5 mm)
    worst = math.sqrt(2.0) * 0.5 * MM + 2.0 * MM
    assert A_REACH == pytest.approx(worst, abs=1e-15)
    d = np.array([-0.5, 0.5, -0.5]) * MM
    e = np.array([1.0, -1.0]) * MM / math.sqrt(2.0)
    tip = MACHINE.tool_pose(np.array([0.0, 0.0, 0.0, 0.0, 0.0, math.pi]), errors_of(d, e))
    assert np.hypot(*tip[:2, 3]) == pytest.approx(worst, abs=1e-12)
    # every groove's start and far end stay within A_REACH of their places, over the
    # capture's corners (dz turns with A about the tool's Z, out of the plate)
    for signs in ((1, 1, 1), (1, -1, 1), (-1, 1, -1), (-1, -1, 1)):
        for turn_e in np.linspace(0.0, 2.0 * math.pi, 16, endpoint=False):
            d = np.array(signs) * 0.5 * MM
            e = np.array([math.cos(turn_e), math.sin(turn_e)]) * MM
            for angle, turn in a_grooves():
                q0 = np.array([0.0, 0.0, 0.0, angle, 0.0, turn])
                q1 = q0 + [SET_LENGTH * math.cos(angle), SET_LENGTH * math.sin(angle), 0, 0, 0,
                           0]
                got = MACHINE.tool_pose(np.vstack([q0, q1]), errors_of(d, e))[:, :2, 3]
                want = MACHINE.tool_pose(np.vstack([q0, q1]))[:, :2, 3]
                assert np.hypot(*(got - want).T).max() <= A_REACH + 1e-12
    # the windows across the A grooves hold it and a groove's 10 um half width, and the
    # first station lies beyond it (where neither the other groove nor the other set is)
    assert A_REACH + 10 * UM < A_WINDOW < STATIONS["a"][0]


def random_program(rng, n=20):
    q = np.column_stack([rng.uniform(-5, 5, (n, 3)) * MM, rng.uniform(-np.pi, np.pi, n),
                         rng.uniform(-1.0, 1.0, n), rng.uniform(-np.pi, np.pi, n)])
    program = Program.from_moves(Move("rapid", dict(zip("XYZABC", row, strict=True)),
                                      line=k + 1) for k, row in enumerate(q))
    return q, program


def test_compensation_puts_the_edge_where_the_nc_data_put_it():
    rng = np.random.default_rng(1)
    d, e = paper_offsets(rng)
    q, program = random_program(rng)
    q_fixed = ident.corrected_axes(q, ident.Compensation(d, e))
    np.testing.assert_array_equal(q_fixed[:, 3:], q[:, 3:])
    # 1e-15 m: the same chain evaluated twice, values of a few mm, float64
    np.testing.assert_allclose(MACHINE.tool_pose(q_fixed, errors_of(d, e)),
                               MACHINE.tool_pose(q), rtol=0, atol=1e-15)
    shifted = ident.corrected_axes(q, ident.Compensation(z_shift=3 * UM))
    assert shifted[:, 2] == pytest.approx(q[:, 2] + 3 * UM, abs=1e-18)
    # the same rule through map_program: exact unrounded, and within the machine's
    # resolution rounded (0.5 nm on X, Y, Z, 0.000005 deg on C at |P| < 9 mm: 0.8 nm)
    fixed = compensate_program(program, MACHINE, ident.Compensation(d, e))
    q_rounded = program_axes(fixed, MACHINE, start=PARKED)
    assert np.abs(q_rounded[:, :3] - q_fixed[:, :3]).max() <= 0.5e-9 + 1e-18
    assert np.abs(q_rounded[:, 3:] - q_fixed[:, 3:]).max() <= math.radians(0.5e-5) * (1 + 1e-9)
    np.testing.assert_allclose(MACHINE.tool_pose(q_rounded, errors_of(d, e))[:, :3, 3],
                               MACHINE.tool_pose(q)[:, :3, 3], rtol=0, atol=2e-9)
    with pytest.raises(InputError, match=r"shape \(N, 6\)"):
        ident.corrected_axes(q[:, :5], ident.Compensation())


def test_the_plate_programs_are_compensated_as_before_the_port():
    """The rule through map_program gives the NC text the old ad-hoc rewrite gave (the writer
    rounds to 1 nm either way): every block of every plate within half a nanometre of the
    unrounded rule, on the machine's grid."""
    d, e = np.array([245.02, 340.06, 150.0]) * UM, np.array([108.97, 852.81]) * UM
    for stage, plate in plate_cuts().items():
        if stage == "touch":
            continue
        nominal = program_axes(plate.program, MACHINE, start=PARKED)
        exact = ident.corrected_axes(nominal, ident.Compensation(d, e, z_shift=-1.5e-4))
        got = program_axes(compensate_program(plate.program, MACHINE,
                                              ident.Compensation(d, e, z_shift=-1.5e-4)),
                           MACHINE, start=PARKED)
        assert np.abs(got[:, :3] - exact[:, :3]).max() <= 0.5e-9 + 1e-18
        np.testing.assert_allclose(np.round(got[:, :3] / 1e-9), got[:, :3] / 1e-9, atol=1e-6)
