"""The one program mapping of every compensation procedure (machinesim.compensation): the
planner's walk, (a) a tool offset, (b) rotary-axis errors, (c) the function route, (d) the
round trip through the NC writer and reader (tool changes kept), a tool tilt left
unmatched, and what a compensated program says it left.

Truths are independent of the module: offsets subtracted on paper, tool poses from the
kinematics, the planner's walk of the program, and the NC writer and reader.
"""

from __future__ import annotations

import dataclasses
import math
import re
import warnings

import numpy as np
import pinocchio as pin
import pytest
from compensation_helpers import grooves, tilted

from machinesim import ErrorModel, load_machine, motion
from machinesim.compensation import (
    Compensated,
    map_program,
    model_based,
    program_axes,
    to_resolution,
)
from machinesim.exceptions import InputError, NCProgramError
from machinesim.nc import Program, format_program, parse_program, read_program, write_program
from machinesim.tolerances import POSE_M
from machinesim.units import RAD_PER_DEG

UM, MM, NM = 1e-6, 1e-3, 1e-9
DEG = RAD_PER_DEG
GROOVING = load_machine("grooving_4axis")
ROBONANO = load_machine("robonano_a0ib")


#: The full nominal axis vector (mm, mm, mm, deg) of each motion block of GROOVES_NC from
#: the zero start, written out by hand.
GROOVES_FULL = np.array([
    [0.0, 0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0, 30.0],
    [0.0, 0.0, -0.002, 30.0],
    [5.123456, 2.5, -0.002, 30.0],
    [6.0, 2.5, -0.002, 45.5],
    [6.0, 2.5, 1.0, 45.5],
]) * np.array([MM, MM, MM, DEG])


def targets(program: Program, machine) -> np.ndarray:
    """Targets of the motion blocks, which the rule says carry every machine axis."""
    rows = [[move.target[a] for a in machine.axes] for move in program.moves
            if move.kind != "dwell"]
    return np.array(rows)


def same_program(a: Program, b: Program) -> None:
    """Equal moves (source lines aside: the writer adds a header), number and offsets."""
    assert a.number == b.number
    assert dict(a.work_offsets) == dict(b.work_offsets)
    assert [dataclasses.replace(m, line=1) for m in a.moves] == [
        dataclasses.replace(m, line=1) for m in b.moves]


def rotation_angle(r_a: np.ndarray, r_b: np.ndarray) -> np.ndarray:
    """Angle (rad) between orientations, (N, 3, 3) each."""
    return np.array([np.linalg.norm(pin.log3(a.T @ b)) for a, b in zip(r_a, r_b, strict=True)])


def rounding_bound(machine, q, errors) -> tuple[np.ndarray, np.ndarray]:
    """First-order bound on what rounding every axis by half its resolution moves the tool:
    position (m) and rotation (rad) per block. The second-order term, (1e-7 rad)^2 times
    ~0.1 m, is 1e-15 m, inside the POSE_M slack the tests add."""
    jac = np.array([machine.axis_jacobian(qn, errors) for qn in q])
    half = machine.resolution / 2.0
    return (np.linalg.norm(jac[:, :3], axis=1) @ half,
            np.linalg.norm(jac[:, 3:], axis=1) @ half)


# ---------------------------------------------------------------------------- the walk


def test_the_walk_is_the_planners():
    """program_axes gives each move's full vector exactly where motion.plan ends the move,
    for a start that is not zero: one convention for an axis not yet programmed."""
    start = np.array([1.0 * MM, 3.0 * MM, 10.0 * MM, 20.0 * DEG])
    program = grooves()
    q = program_axes(program, GROOVING, start=start)
    planned = motion.plan(program, GROOVING, start=start)
    # the planner interpolates q0 + 1.0 * (q1 - q0): its ends are q1 to round-off
    np.testing.assert_allclose(q, [s.q[-1] for s in planned.segments], rtol=0.0, atol=1e-17)
    np.testing.assert_array_equal(q[0], start)  # the M03 block, before any motion
    motion_rows = [n for n, m in enumerate(program.moves) if m.kind != "dwell"]
    np.testing.assert_array_equal(program_axes(program, GROOVING)[motion_rows], GROOVES_FULL)


def test_an_axis_the_machine_lacks_is_refused_like_the_planner_does():
    program = parse_program("G00 X1. A5.\n", "a.nc")
    with pytest.raises(NCProgramError, match=r"a\.nc, line 1, key 'A': axis A is not on"):
        map_program(program, GROOVING, lambda q: q)
    with pytest.raises(InputError, match=r"start must have shape \(4,\)"):
        program_axes(grooves(), GROOVING, start=[0.0, 0.0])


@pytest.mark.parametrize(("function", "got"), [
    (np.zeros((16, 4)), "got ndarray of shape (16, 4)"), ("shift", "got str"),
    (None, "got NoneType")])
def test_a_compensation_that_is_not_a_function_is_refused_by_name(function, got):
    # the compensated values given in place of the function (or its name) raised
    # "TypeError: 'numpy.ndarray' object is not callable" from inside map_program
    with pytest.raises(InputError) as info:
        map_program(grooves(), GROOVING, function)
    assert info.value.key == "function"
    assert str(info.value).startswith(
        "key 'function': expected the compensation as a function q -> q_compensated of the "
        f"(N, 4) axis values of the motion blocks (columns X Y Z C, m and rad), {got}; ")


# --------------------------------------------------------------- (a) a tool offset


@pytest.mark.parametrize("rounded", [False, True])
def test_a_tool_offset_is_subtracted_along_its_axes(rounded):
    """On grooving_4axis the tool side carries no rotary axis, so tool_mount stays parallel
    to the machine axes, and the edge offset (dx, dy, 0) moves the edge by (dx, dy, 0)
    relative to the workpiece whatever C is (C turns the workpiece about its own centre,
    and X, Y command the tool relative to it). The axis values that put the edge back are
    the programmed ones minus the offset: X - dx, Y - dy, Z and C unchanged."""
    d = np.array([12.3456, -7.8, 0.0]) * UM  # not on the 1 nm grid: rounding shows
    errors = ErrorModel.from_dict({"tool": {"offset_um": (d / UM).tolist()}})
    program = grooves()
    result = model_based(program, GROOVING, errors, rounded=rounded)
    assert isinstance(result, Compensated)
    assert result.unmatched == ""
    assert result.max_position_residual < POSE_M
    assert result.max_rotation_residual < POSE_M
    q = targets(result.program, GROOVING)
    expected = GROOVES_FULL - np.r_[d, 0.0]
    if rounded:  # to the nm and 0.00001 deg grid, worked out here on its own
        expected = np.column_stack([np.round(expected[:, :3] / NM) * NM,
                                    np.round(expected[:, 3] / (1e-5 * DEG)) * (1e-5 * DEG)])
    np.testing.assert_allclose(q, expected, rtol=0.0, atol=1e-15)
    # the edge on the machine with the offset is where the nominal program puts it on the
    # nominal machine: exactly before rounding, within half a nanometre per axis after
    reached = GROOVING.tool_pose(q, errors)
    wanted = GROOVING.tool_pose(GROOVES_FULL)
    miss = np.linalg.norm(reached[:, :3, 3] - wanted[:, :3, 3], axis=1)
    limit = math.sqrt(3) * NM / 2 + POSE_M if rounded else POSE_M
    assert miss.max() < limit
    assert rotation_angle(reached[:, :3, :3], wanted[:, :3, :3]).max() < POSE_M


# ------------------------------------------------------------- (b) rotary-axis errors


def test_workpiece_rotation_and_c_offsets_are_undone_to_the_resolution():
    """A workpiece turned by gamma and a C axis off centre: five axes match the whole pose,
    so the compensated program gives the nominal poses exactly before rounding and to the
    rounding bound after."""
    errors = ErrorModel.from_dict({"workpiece": {"gamma_deg": 0.5},
                                   "location": {"C": {"EX0C_um": 2.0, "EY0C_um": -3.0}}})
    program = tilted()
    nominal_q = targets(program, ROBONANO)
    wanted = ROBONANO.tool_pose(nominal_q)
    before = ROBONANO.tool_pose(nominal_q, errors)
    assert np.linalg.norm(before[:, :3, 3] - wanted[:, :3, 3], axis=1).max() > 1 * UM
    for rounded in (False, True):
        result = model_based(program, ROBONANO, errors, rounded=rounded)
        assert result.unmatched == ""
        q = targets(result.program, ROBONANO)
        reached = ROBONANO.tool_pose(q, errors)
        miss = np.linalg.norm(reached[:, :3, 3] - wanted[:, :3, 3], axis=1)
        turn = rotation_angle(reached[:, :3, :3], wanted[:, :3, :3])
        if rounded:
            position, rotation = rounding_bound(ROBONANO, q, errors)
            assert np.all(miss <= position + POSE_M)
            assert np.all(turn <= rotation + POSE_M)
            assert miss.max() > 1e-3 * NM  # rounding did happen
        else:
            assert miss.max() < POSE_M
            assert turn.max() < POSE_M


def test_orientation_five_axes_cannot_give_is_reported_and_the_point_kept():
    """A workpiece tilted about X: the tool would have to roll, which X Y Z B C cannot do.
    The tip (or a chosen tool point) still lands where the nominal program puts it."""
    errors = ErrorModel.from_dict({"workpiece": {"alpha_deg": 0.1}})
    program = tilted()
    nominal_q = targets(program, ROBONANO)
    wanted = ROBONANO.tool_pose(nominal_q)
    tip = model_based(program, ROBONANO, errors, rounded=False)
    assert "cannot turn the tool" in tip.unmatched
    assert tip.max_rotation_residual > 1e-4  # ~alpha, 1.7 mrad
    reached = ROBONANO.tool_pose(targets(tip.program, ROBONANO), errors)
    assert np.linalg.norm(reached[:, :3, 3] - wanted[:, :3, 3], axis=1).max() < POSE_M
    assert tip.max_position_residual < POSE_M

    point = np.array([0.3, -0.5, 1.0]) * MM
    kept = model_based(program, ROBONANO, errors, point=point, rounded=False)
    reached = ROBONANO.tool_pose(targets(kept.program, ROBONANO), errors)

    def at(poses):
        return poses[:, :3, :3] @ point + poses[:, :3, 3]

    miss = np.linalg.norm(at(reached) - at(wanted), axis=1)
    assert miss.max() < POSE_M
    assert kept.max_position_residual == pytest.approx(miss.max(), abs=1e-15)
    # the tip program leaves that point off by the unmatched turn times its lever
    tip_reached = ROBONANO.tool_pose(targets(tip.program, ROBONANO), errors)
    assert np.linalg.norm(at(tip_reached) - at(wanted), axis=1).max() > 100 * NM


def test_no_errors_give_the_program_back():
    program = tilted()
    result = model_based(program, ROBONANO, None)
    same_program(result.program, program)
    assert result.max_position_residual < POSE_M


# ----------------------------------------------------------------- (c) the function route


def test_the_function_sees_every_axis_and_only_axis_values_change():
    start = np.array([1.0 * MM, 3.0 * MM, 10.0 * MM, 20.0 * DEG])
    shift = np.array([1.0 * UM, 0.0, -2.0 * UM, 0.0])
    calls = []

    def function(q):
        calls.append(q.copy())
        return q + shift

    program = grooves()
    out = map_program(program, GROOVING, function, start=start)
    assert len(calls) == 1
    seen = calls[0]
    assert seen.shape == (6, 4)  # the six motion blocks, rapids included
    # Y and C until programmed, and X before N10, are at the start
    np.testing.assert_array_equal(seen[:3, 1], start[1])
    np.testing.assert_array_equal(seen[0, 3], start[3])
    np.testing.assert_array_equal(seen[:, 0], [0.0, 0.0, 0.0, 5.123456 * MM, 6 * MM, 6 * MM])

    # every motion block carries every axis, shifted (the shifts are on the grid)
    got = targets(out, GROOVING)
    np.testing.assert_allclose(got, seen + shift, rtol=0.0, atol=1e-17)
    assert got[0, 1] == 3.0 * MM and got[0, 3] == 20.0 * DEG  # exactly, after rounding

    # everything but the targets is unchanged; a dwell stays where the move before it ended
    assert (out.number, out.source, out.work_offsets) == (
        program.number, program.source, program.work_offsets)
    for before, after in zip(program.moves, out.moves, strict=True):
        assert dataclasses.replace(after, target=before.target) == before
    assert out.moves[0].kind == "dwell" and dict(out.moves[0].target) == {}
    assert out.moves[0].m_codes == (3,) and out.moves[0].spindle_rpm == 1000.0
    dwell = next(n for n, m in enumerate(out.moves) if m.dwell_s == 0.5)
    assert out.moves[dwell].target == out.moves[dwell - 1].target
    assert [m.block_number for m in out.moves] == [5, 10, 20, 30, 40, 50, 60, 70]
    assert out.moves[6].m_codes == (8,)


def test_an_identity_function_keeps_programmed_values_exactly():
    program = grooves()
    out = map_program(program, GROOVING, lambda q: q)
    for before, after in zip(program.moves, out.moves, strict=True):
        for axis, value in before.target.items():
            assert after.target[axis] == value


def test_a_program_without_motion_does_not_call_the_function():
    program = parse_program("O5\nM03 S100\nG04 P20\n")

    def function(q):
        raise AssertionError("called")

    same_program(map_program(program, GROOVING, function), program)


# ------------------------------------------------------------------- (d) the round trip


def test_writing_and_reading_the_output_gives_it_back(tmp_path):
    """Through G91, a G55 block and work offsets off the nanometre grid: the output is on
    the grid the writer uses (relative to G54), so the text reads back as the same floats."""
    offsets = {"G54": {"X": 0.1234567891 * MM, "Z": -7.77777777 * UM},
               "G55": {"X": 10.0 * MM + 0.1 * NM}}
    text = """%
O0100
G90 G21 G94 G54
N10 G00 X1. Y-2. Z3. C10.
N20 G01 Z-0.0015 F75.5
N30 G91 X0.25 Y0.125
N40 G90 G55 X2.
N50 G04 P1000
N60 G54 C-12.34567 M08
%
"""
    program = parse_program(text, "offsets.nc", work_offsets=offsets)
    shift = np.array([math.pi * UM, -math.e * UM, 1.0 / 3.0 * UM, 1e-3 * math.sqrt(2) * DEG])
    out = map_program(program, GROOVING, lambda q: q + shift)
    path = tmp_path / "out.nc"
    write_program(out, path)
    back = read_program(path, work_offsets=offsets)
    same_program(back, out)
    assert format_program(back) == format_program(out)
    # rounding moved each value by at most half a step from the exact mapping
    exact = targets(map_program(program, GROOVING, lambda q: q + shift, rounded=False),
                    GROOVING)
    assert np.all(np.abs(targets(out, GROOVING) - exact) <= GROOVING.resolution / 2 + 1e-18)


def test_the_model_based_output_reads_back_identically(tmp_path):
    errors = ErrorModel.from_dict({"workpiece": {"gamma_deg": 0.5, "delta_um": [3.0, 1.0, 0.5]},
                                   "location": {"C": {"EX0C_um": 2.0}}})
    out = model_based(tilted(), ROBONANO, errors).program
    write_program(out, tmp_path / "out.nc")
    same_program(read_program(tmp_path / "out.nc"), out)


def test_to_resolution_is_idempotent_and_on_the_grid():
    rng = np.random.default_rng(0)
    q = rng.uniform(-0.1, 0.1, (50, 4))
    once = to_resolution(q, GROOVING)
    np.testing.assert_array_equal(to_resolution(once, GROOVING), once)
    assert np.all(np.abs(once - q) <= GROOVING.resolution / 2 + 1e-18)
    steps = once / GROOVING.resolution
    np.testing.assert_allclose(steps, np.round(steps), rtol=0.0, atol=1e-6)


TOOLS_TOML = """
[tool.1]
length_mm = 2.5
shape = "ball:0.5"

[tool.2]
length_mm = 0.0
shape = "flat:0.3"
"""

TOOL_CHANGE_NC = """O7
G90 G21 G17 G94
T1 M06
G00 G43 H1 X-3. Y-2. Z1.
G01 Z-0.005 F60.
X3.
G00 Z1.
T2
M06
G00 G43 H2 X-3. Y2. Z1.
G01 Z-0.005 F60.
X3.
G00 Z1.
M30
"""


def test_compensation_and_the_writer_keep_the_tool_changes(tmp_path):
    # A program read with a tool table: T1 (2.5 mm longer, a ball) cuts the first groove,
    # T2 (a flat end mill) the second. The rewrite kept the moves and dropped the tools, so
    # the compensated program cut both grooves with the cut's own tool, 2.5 mm off in Z.
    from machinesim import cut

    table = tmp_path / "tools.toml"
    table.write_text(TOOLS_TOML)
    machine = load_machine("grooving_4axis")
    program = parse_program(TOOL_CHANGE_NC, tools=table)
    assert [(c.number, c.move, c.length_m) for c in program.tool_changes] == [
        (1, 1, 2.5 * MM), (2, 6, 0.0)]
    same = model_based(program, machine, None).program
    assert same.tool_changes == program.tool_changes and same.tool_table == str(table)
    # the text carries the T words where the reader finds the same changes again
    back = parse_program(format_program(same), tools=table)
    assert [(c.number, c.move, c.length_m, c.shape) for c in back.tool_changes] == [
        (c.number, c.move, c.length_m, c.shape) for c in program.tool_changes]
    np.testing.assert_array_equal(back.targets, same.targets)
    # and cut the same part as the program read from its own text
    removed = [cut(p, machine, "v:90", "block:10x10x2@-5,-5,0")[1].removed_volume_m3
               for p in (program, same, back)]
    assert removed[1] == pytest.approx(removed[0], rel=1e-12)
    assert removed[2] == pytest.approx(removed[0], rel=1e-12)


def test_a_tool_tilt_at_b_zero_is_left_unmatched_not_chased_by_turns_of_a_and_c():
    """robonano_ui with its tool tilted 10 urad about tool_mount X, at A = a, B = 0: B takes
    the part about Y, -tau sin a; the part across it, tau cos a, only A against C could make,
    turning tau / |sin B| (B a few urad): it is left unmatched and reported (a warning: a
    pose off B = 0 matches it, tests/test_compensation_singular.py). It had turned C by
    253 deg (an AxisLimitError blaming the errors' size and units), A against it."""
    from machinesim.exceptions import MachineSimWarning

    machine = load_machine("robonano_ui")
    tau = 10e-6
    errors = ErrorModel.from_dict({"tool": {"rotation_urad": [10.0, 0.0, 0.0]}})
    program = parse_program("G90 G01 F100 X10. Y5. Z0 A17.18873 B0 C-114.59156\n")
    nominal = program_axes(program, machine)[0]
    a = nominal[3]
    with pytest.warns(MachineSimWarning, match="singularity"):
        result = model_based(program, machine, errors, rounded=False)
    q = program_axes(result.program, machine)[0]
    assert result.max_position_residual < 1e-13
    assert result.max_rotation_residual == pytest.approx(tau * math.cos(a), rel=1e-9)
    assert "cannot turn the tool about" in result.unmatched
    np.testing.assert_allclose(q[4] - nominal[4], -tau * math.sin(a), rtol=1e-9, atol=0)
    np.testing.assert_allclose(q[[3, 5]], nominal[[3, 5]], rtol=0, atol=1e-9)  # A, C kept
    np.testing.assert_allclose(q[:3], nominal[:3], rtol=0, atol=1e-12)  # tip on the centres


@pytest.mark.parametrize("b_deg, left", [(0.078, True), (0.084, False)])
def test_the_weak_turn_cut_off_on_robonano_ui_is_where_sin_b_over_root_2_is_ik_weak_turn(
        b_deg, left):
    """A against C turns the tool by |sin B| per rad of each, and a step of unit length
    turns each by 1/sqrt(2): the singular value the cut-off reads is |sin B| / sqrt(2), so
    the 10 urad tilt across B is left unmatched up to asin(sqrt(2) IK_WEAK_TURN) = 0.0810 deg
    (by hand) and matched beyond (tolerances.py had said 0.057 deg, asin(IK_WEAK_TURN), where
    B = 0.06 deg is still left)."""
    from machinesim.exceptions import MachineSimWarning
    from machinesim.tolerances import IK_WEAK_TURN

    cut_deg = math.degrees(math.asin(math.sqrt(2.0) * IK_WEAK_TURN))
    assert cut_deg == pytest.approx(0.08103, abs=1e-5)
    assert (b_deg < cut_deg) == left
    machine = load_machine("robonano_ui")
    errors = ErrorModel.from_dict({"tool": {"rotation_urad": [10.0, 0.0, 0.0]}})
    program = parse_program(f"G90 G01 F100 X10. Y5. Z0 A17.18873 B{b_deg} C-114.59156\n")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = model_based(program, machine, errors, rounded=False)
    assert result.max_position_residual < 1e-13
    assert bool(result.unmatched) == left
    assert (result.max_rotation_residual > 9e-6) == left
    # what is left there is a singularity's (the poses around match it): told, by the same cut
    assert bool(result.singular) == left
    assert any(issubclass(w.category, MachineSimWarning) for w in caught) == left


def test_a_compensated_program_says_what_it_left_with_units():
    """Its repr had named the residuals' fields without their units
    (max_position_residual=0.0, max_rotation_residual=5.877471754111438e-39). Now they
    come with m and rad, and what was left unmatched, or 'all matched'. A tool offset on
    grooving_4axis is matched exactly (docs/compensation.md); a tilt about X of 1e-5 rad
    cannot be, by four axes that turn only about Z: 1e-5 rad left."""
    program, machine = read_program("models/examples/grooves.nc"), load_machine("grooving_4axis")
    shifted = model_based(program, machine, ErrorModel.from_dict(
        {"tool": {"offset_um": [4.0, -2.0, 0.0]}}), start=None, point=None)
    assert repr(shifted).startswith("Compensated(Program(16 moves, number=1, ")
    assert re.search(r", position residual \S+ m, rotation residual \S+ rad before "
                     r"rounding; all matched\)$", repr(shifted))
    tilted = model_based(program, machine, ErrorModel.from_dict(
        {"tool": {"rotation_urad": [10.0, 0.0, 0.0]}}), start=None, point=None)
    assert f"rotation residual {1e-5:.3g} rad before rounding; {tilted.unmatched})" in repr(
        tilted) and tilted.unmatched
