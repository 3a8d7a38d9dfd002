"""The orientation the inverse leaves at a singularity of the axes, told where it matters.

A machine's axes turn the tool, with its edge held, in as many directions at a generic pose
as its structure gives (`machinesim.inverse.turn_rank`); at a singular pose in fewer. What
is left unmatched there (a generic pose would have matched it) is `singular_residual`, a
`MachineSimWarning` of `model_based` and `Compensated.singular`; what the structure never
matches (a tilt on four axes) is only in ``unmatched``.

Truths: the machines' structure counted by hand, and robonano_ui's gimbal lock at B = 0
worked on paper (the tool tilt tau about tool_mount X at A = a is tau (cos a, sin a, 0) in
B's frame; B takes the part about Y, the part about machine X is left), held against the
forward chain.
"""

from __future__ import annotations

import math
import re
import warnings

import numpy as np
import pytest

from machinesim import ErrorModel, load_machine
from machinesim.compensation import model_based, program_axes
from machinesim.compensation_table import ModelCompensation
from machinesim.exceptions import MachineSimWarning
from machinesim.inverse import turn_rank
from machinesim.nc import parse_program
from machinesim.rotations import rotation_log

UI = load_machine("robonano_ui")
GROOVING = load_machine("grooving_4axis")
TAU = 10e-6  # rad, the tool's tilt about tool_mount X
TILT = ErrorModel.from_dict({"tool": {"rotation_urad": [10.0, 0.0, 0.0]}})
A, C = 0.3, -2.0  # rad: A17.18873 C-114.59156 in the programs below


def ui_program(b_deg: str):
    return parse_program(f"G90 G01 F100 X10. Y5. Z0 A17.18873 B{b_deg} C-114.59156\n"
                         f"X11.\n", "ui.nc")


@pytest.mark.parametrize("name, whole, tool_axis", [
    ("grooving_4axis", 1, 0),  # C turns the work about Z, the tool's own axis
    ("planer_4axis", 1, 1),    # A tilts the tool about X
    ("robonano_a0ib", 2, 2),   # B about Y, C about Z: always square
    ("robonano_ui", 3, 2),     # A, B, C: every direction; a tool axis has two
    ("sts_lathe", 0, 0),       # X, Z and C are all needed for the edge's position
])
def test_turn_rank_counts_the_directions_the_structure_turns_the_tool_in(name, whole,
                                                                        tool_axis):
    machine = load_machine(name)
    assert turn_rank(machine) == whole
    assert turn_rank(machine, axis_only=True) == tool_axis


def test_turn_rank_takes_a_machine_or_its_name_and_refuses_anything_else():
    # a name (as machinesim's other entry points take) was a TypeError "'>=' not supported
    # between instances of 'builtin_function_or_method' and 'float'" (str.lower taken for
    # the travel), None an AttributeError, a dict "unhashable type"; axis_only "no" True
    from machinesim.exceptions import InputError, ModelError

    assert turn_rank("robonano_ui") == 3 and turn_rank("robonano_ui", axis_only=True) == 2
    for bad in (None, 3, {}):
        with pytest.raises(InputError) as info:
            turn_rank(bad)
        assert info.value.key == "machine"
    with pytest.raises(ModelError, match="nope"):
        turn_rank("nope")
    with pytest.raises(InputError) as info:
        turn_rank(UI, axis_only="no")
    assert info.value.key == "axis_only"


@pytest.mark.parametrize("b_deg", ["0", "0.03"])
def test_a_tilt_left_at_gimbal_lock_is_a_singular_residual(b_deg):
    """At B = 0 (and 0.03 deg, where A against C turns the tool by 3.7e-4 rad per rad,
    under `IK_WEAK_TURN`) the part tau cos a across B's axis is left. A turns about
    Ry(b) Z, C about Z: together about their bisector Ry(b/2) Z, against each other
    (weakly) about Ry(b/2) X = (cos b/2, 0, -sin b/2), the direction left; in the
    workpiece frame (C turns it about -Z) Rz(c) of that. The residual, from the reached
    (tilted) to the wanted orientation, is -tau cos a times it, to second order in tau."""
    b = math.radians(float(b_deg))
    q = program_axes(ui_program(b_deg), UI)[:1]
    solution = UI.axis_values(UI.tool_pose(q), TILT, q_start=q)
    expected = -TAU * math.cos(A) * np.array([math.cos(b / 2) * math.cos(C),
                                              math.cos(b / 2) * math.sin(C), -math.sin(b / 2)])
    np.testing.assert_allclose(solution.singular_residual[0], expected, rtol=0,
                               atol=2 * TAU ** 2)
    np.testing.assert_array_equal(solution.singular_residual, solution.rotation_residual)
    # the second method: the forward chain at the solution against the wanted pose
    reached = UI.tool_pose(solution.q, TILT)[0, :3, :3]
    wanted = UI.tool_pose(q)[0, :3, :3]
    np.testing.assert_allclose(rotation_log(wanted @ reached.T), expected, rtol=0,
                               atol=2 * TAU ** 2)
    assert re.fullmatch(r"robonano_ui \(XYZABC\) cannot turn the tool about X/Y(/Z)? here, at "
                        r"a singularity of its axes \(the poses around can\): orientation "
                        r"left unmatched by up to 0\.00049772 deg", solution.unmatched)


@pytest.mark.parametrize("b_deg", ["0", "0.03"])
def test_model_based_warns_of_blocks_at_a_singularity_naming_lines_size_and_direction(b_deg):
    with pytest.warns(MachineSimWarning) as caught:
        result = model_based(ui_program(b_deg), UI, TILT, rounded=False)
    size = f"{TAU * math.cos(A) * 1e6:.4g}"  # 9.553 urad
    assert size == "9.553"
    direction = re.escape(f"{-math.cos(C):+.4f}, {-math.sin(C):+.4f}, ")  # -(machine X)
    assert re.fullmatch(
        rf"robonano_ui \(XYZABC\) stands at a singularity of its axes at 2 of 2 pose\(s\) "
        rf"\(line 1, line 2\): there they turn the tool about a direction by less than 0\.001 "
        rf"rad per unit of axis motion, which they turn it about at the poses around, and the "
        rf"tool orientation is left unmatched by up to {size} urad \(line [12]\) about "
        rf"\({direction}[+-]0\.000\d\) in the workpiece frame\. A pose off the "
        rf"singularity is matched", result.singular)
    assert [str(w.message) for w in caught] == [f"ui.nc: {result.singular}"]
    assert result.max_rotation_residual == pytest.approx(TAU * math.cos(A), rel=1e-6)


def test_the_singularity_warning_names_each_line_once_with_its_n_word():
    """The warning named poses, not lines: an arc at B = 0 (its chords poses of one line)
    was listed 'line 2, line 3, line 3, line 3, ... line 3 ...' (nine times the arc's
    line). Each line is named once, with its block's N word as the reader's messages do
    ('line 3 (N30)'); the count stays that of the poses."""
    program = parse_program("G90 G17 G01 F100 X10. Y5. Z0 A17.18873 B0 C-114.59156\n"
                            "N30 G03 X5. Y10. I-5. J0\nN40 G01 X4.\nG01 X3.\n", "arc.nc",
                            chord_tolerance=1e-5)
    poses = int(np.sum(program.kinds != 2))  # the motion blocks (no dwell)
    assert poses > 12
    with pytest.warns(MachineSimWarning):
        result = model_based(program, UI, TILT, rounded=False)
    assert re.search(rf"at {poses} of {poses} pose\(s\) \(line 1, line 2 \(N30\), "
                     r"line 3 \(N40\), line 4\): there", result.singular), result.singular


def test_a_pose_off_the_singularity_is_matched_and_nothing_is_told():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        result = model_based(ui_program("30."), UI, TILT, rounded=False)
        q = program_axes(ui_program("30."), UI)
        solution = UI.axis_values(UI.tool_pose(q), TILT, q_start=q)
    assert result.singular == "" and result.unmatched == ""
    assert result.max_rotation_residual < 1e-15
    np.testing.assert_array_equal(solution.singular_residual, 0.0)


def test_a_tilt_four_axes_never_match_is_no_singularity():
    """grooving_4axis (X Y Z C): its tool tilted 1.7 mrad and 0.56 mrad about X and Y, which
    C (about Z) never turns, at any pose: left, reported as unmatched, not warned of."""
    errors = ErrorModel.from_dict({"tool": {"rotation_urad": [-1700.0, -560.0, 0.0]}})
    program = parse_program("G90 G21\nG00 X0. Y0. Z1. C0.\nG01 Z-0.002 F100.\n"
                            "G01 X5. C45.\nG01 X-20. Y10. C-170.\n", "grooves.nc")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        result = model_based(program, GROOVING, errors, rounded=False)
    assert result.singular == ""
    assert re.fullmatch(r"grooving_4axis \(XYZC\) cannot turn the tool about X/Y at 4 poses: "
                        r"orientation left unmatched by up to 0\.09\d+ deg", result.unmatched)
    assert result.max_rotation_residual == pytest.approx(math.hypot(1700e-6, 560e-6),
                                                         rel=1e-3)
    q = program_axes(program, GROOVING)
    solution = GROOVING.axis_values(GROOVING.tool_pose(q), errors, q_start=q)
    np.testing.assert_array_equal(solution.singular_residual, 0.0)
    assert np.all(np.linalg.norm(solution.rotation_residual, axis=1) > 1e-3)


def test_the_model_compensation_of_single_commands_warns_naming_the_row():
    q = np.vstack([program_axes(ui_program("30."), UI)[:1], program_axes(ui_program("0"),
                                                                         UI)[:1]])
    with pytest.warns(MachineSimWarning, match=r"^the compensated axis values: robonano_ui "
                                               r"\(XYZABC\) stands at a singularity of its "
                                               r"axes at 1 of 2 pose\(s\) \(row 1\).* 9\.553 "
                                               r"urad \(row 1\)"):
        ModelCompensation(UI, TILT).apply(q)
