"""One known error injected, a V slot cut, the part's mesh measured, and the slot moved as the
error's definition says, each figure derived by hand (docs/machines.md, "How errors enter";
every error is the tool's displacement relative to the workpiece, ISO 230-1's sense).

tests/test_kinematics_poses.py holds the poses to an independent chain; these go through
`machinesim.cut` to the part: the cut applies the errors at the chord ends of each move and
splits a move where a position-dependent error bends its path.

The slot: a 90 deg V tool plunged 20 um at X = 0.5 mm and fed to X = 10.5 mm. Its edge lies
in the tool's YZ plane, so the slot's ends are vertical faces at the edge's two X positions
and its bottom vertices lie on the edge's path.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import machinesim
from machinesim.metrology import height_map
from machinesim.nc import ProgramBuilder

MM, UM, URAD = 1e-3, 1e-6, 1e-6
X0, X1, DEPTH, Y_SLOT = 0.5 * MM, 10.5 * MM, 20 * UM, 5 * MM
#: Below every X and Y coordinate's float64 round-off at 12 mm (1.7e-18 m) by far, and far
#: below the smallest deviation checked (5 nm): vertices are exact corners of the sweeps.
EXACT = 1e-15
#: The cut's chord tolerance for a V tool (docs/cutting.md): a bent path is cut as chords
#: whose sag stays within it.
CHORD = 1e-9


def _slot(b_deg: float = 0.0, c_deg: float = 0.0, y: float = Y_SLOT):
    build = ProgramBuilder(1)
    if b_deg or c_deg:
        build.rapid(**({"B": math.radians(b_deg)} if b_deg else {}),
                    **({"C": math.radians(c_deg)} if c_deg else {}))
    return (build.rapid(X=X0, Y=y, Z=0.1 * MM).linear(Z=-DEPTH, feed_mm_per_min=50.0)
            .linear(X=X1, feed_mm_per_min=100.0).rapid(Z=0.1 * MM).build())


def _slot_vertices(name, errors, program=None, stock="block:12x10x2"):
    # from the machine's home, Z at the top, as the command line starts: from zero on every
    # axis an error that lowers the tool (EAX's 4 um) has the first rapid scratch the top
    machine = machinesim.load_machine(name)
    part, _ = machinesim.cut(_slot() if program is None else program, machine, tool="v:90",
                             stock=stock, errors=errors, start=machine.home)
    vertices = part.mesh()[0]
    return part, vertices[(vertices[:, 2] < -1e-9) & (vertices[:, 2] > -100 * UM)]


def _ends(slot: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The lowest vertex of each end face: the edge's tip where the feed starts and ends."""
    low_x = slot[slot[:, 0] <= slot[:, 0].min() + EXACT]
    high_x = slot[slot[:, 0] >= slot[:, 0].max() - EXACT]
    return low_x[np.argmin(low_x[:, 2])], high_x[np.argmin(high_x[:, 2])]


@pytest.mark.parametrize("component", [
    {"EXX_poly_um_mm": [0.0, 0.01]},                                   # 0.01 um/mm = 10 ppm
    {"position_mm": [0.0, 100.0], "EXX_um": [0.0, 1.0]},               # the same, a table
])
def test_a_10_ppm_scale_error_lengthens_a_10_mm_slot_by_100_nm(component):
    """EXX = 1e-5 x: positive EXX is the tool beyond its target (ISO 230-2's deviation, actual
    minus target), so each end moves out by 1e-5 times its X: 5 nm at 0.5 mm, 105 nm at
    10.5 mm, the slot 100 nm longer."""
    errors = machinesim.ErrorModel.from_dict({"component": {"X": component}})
    start, end = _ends(_slot_vertices("grooving_4axis", errors)[1])
    assert start[0] == pytest.approx(X0 * (1 + 1e-5), abs=EXACT)
    assert end[0] == pytest.approx(X1 * (1 + 1e-5), abs=EXACT)
    assert end[0] - start[0] - (X1 - X0) == pytest.approx(100e-9, abs=EXACT)


def test_a_straightness_error_a_x_squared_bows_the_slot_bottom_by_the_parabola():
    """EZX = a x^2, a = 1e-3 um/mm^2 (100 nm at 10 mm): the tool rides a x^2 higher, so the
    bottom rises by the parabola, to the chords' sag; the nominal cut is flat to 1e-15."""
    x = np.array([1.0, 3.0, 5.0, 7.5, 10.0]) * MM
    bottoms = []
    for errors in (None, {"component": {"X": {"EZX_poly_um_mm": [0.0, 0.0, 1e-3]}}}):
        part, _ = _slot_vertices("grooving_4axis", errors)
        bottoms.append(height_map(part, x, np.array([Y_SLOT]))[0])
    np.testing.assert_allclose(bottoms[0], -DEPTH, atol=EXACT)
    bow = bottoms[1] - bottoms[0]
    expected = 1e-3 * UM / MM**2 * x**2                    # 1, 9, 25, 56.25, 100 nm
    assert np.all(bow >= expected - EXACT)                 # chords lie above a parabola's arc
    np.testing.assert_allclose(bow, expected, atol=CHORD)


def test_an_angular_error_moves_the_tool_by_its_abbe_offset_times_the_angle():
    """grooving_4axis: X's carriage frame is at base (0, 400, 550) mm, the edge at (0, -400,
    -350) mm from it (Z's (0, -400, -250), tool_mount's -80, tool_tip's -20), so a constant
    angle e of X's motion moves the edge by e x (0, -0.4, -0.35) m: ECX (yaw) by (0.4 e, 0, 0),
    EAX (roll) by (0, 0.35 e, -0.4 e). e = 10 urad: 4 um along X; 3.5 um along Y and 4 um
    down, the slot 24 um deep. The edge's small turn leaves its tip where it is."""
    nominal = np.array(_ends(_slot_vertices("grooving_4axis", None)[1]))
    for symbol, shift in (("ECX", (4.0, 0.0, 0.0)), ("EAX", (0.0, 3.5, -4.0))):
        errors = {"component": {"X": {f"{symbol}_poly_urad_mm": [10.0]}}}
        ends = np.array(_ends(_slot_vertices("grooving_4axis", errors)[1]))
        # to 0.3 nm: the roll's second order (0.02 nm) and the edge's turn over the
        # slot's 20 um of flank where the lowest vertex is found (10 urad x 20 um, 0.2 nm)
        np.testing.assert_allclose(ends - nominal, np.array([shift, shift]) * UM, atol=3e-10,
                                   err_msg=symbol)


def test_an_angular_error_of_a_moving_table_grows_with_the_travel():
    """planer_4axis moves the workpiece on X: its carriage frame lies 100 mm below the
    workpiece origin (table 95, workpiece 5) and goes with the table, while Y carries the tool,
    so the tool at X = x, Y = 5 mm sits at (x, 5 mm, 100 mm) from it. ECX = e turns the tool
    about the carriage point by e relative to the workpiece: e z x (x, 5 mm, 100 mm) =
    (-5 mm e, e x, 0), a slot yawed by e (10 urad: 5 nm at 0.5 mm, 105 nm at 10.5 mm) and set
    back 50 nm, where a tool-side X's yaw shifted it whole."""
    errors = {"component": {"X": {"ECX_poly_urad_mm": [10.0]}}}
    start, end = _ends(_slot_vertices("planer_4axis", errors)[1])
    nominal = _ends(_slot_vertices("planer_4axis", None)[1])
    # the end faces' lowest corners to the edge's turn over the slot's 20 um of flank, where
    # they are found (10 urad x 20 um, 0.2 nm)
    np.testing.assert_allclose(np.array([start, end]) - np.array(nominal),
                               [[-10 * URAD * Y_SLOT, 10 * URAD * X0, 0.0],
                                [-10 * URAD * Y_SLOT, 10 * URAD * X1, 0.0]],
                               atol=2e-10)


def test_c_axis_location_errors_move_a_slot_cut_at_c_180_about_the_true_axis_line():
    """robonano_a0ib with C's line at (EX0C, EY0C) = (5, -3) um and tilted by EA0C = 20 urad,
    EB0C = -10 urad (ISO 230-7: the line's place and direction, turned about C's joint frame,
    25 mm below the workpiece origin). At C = 180 deg the workpiece point under the edge is the
    edge's place p turned by 180 deg about that line: p' = 2 (c + n (n . (p - c))) - p, n the
    line's direction, c its point at the joint frame. The slot, cut at X 0.5 .. 10.5 mm, Y 2 mm,
    lies nominally at (-x, -2 mm, -20 um) in the workpiece."""
    location = {"EX0C_um": 5.0, "EY0C_um": -3.0, "EA0C_urad": 20.0, "EB0C_urad": -10.0}
    program = _slot(c_deg=180.0, y=2 * MM)
    stock = "block:12x10x2@-11.5,-6,0"
    ends = np.array(_ends(_slot_vertices("robonano_a0ib", {"location": {"C": location}},
                                         program, stock)[1]))
    a, b = 20 * URAD, -10 * URAD
    n = np.array([math.sin(b) * math.cos(a), -math.sin(a), math.cos(a) * math.cos(b)])
    c = np.array([5 * UM, -3 * UM, -25 * MM])
    for end, x in zip(ends[::-1], (X0, X1), strict=True):  # -x: the feed's start is max x
        p = np.array([x, 2 * MM, -DEPTH])
        expected = 2 * (c + n * (n @ (p - c))) - p
        np.testing.assert_allclose(end, expected, atol=1e-12)
    # to first order, h = 24.98 mm the slot bottom's height over the joint frame:
    # dx = 2 EX0C + 2 EB0C h = 10 - 0.4996 um, dy = 2 EY0C - 2 EA0C h = -6 - 0.9992 um,
    # dz = 2 (EB0C x - EA0C y): 90 nm deeper at x = 0.5 mm, 290 nm at 10.5 mm
    np.testing.assert_allclose(ends - [[-X1, -2 * MM, -DEPTH], [-X0, -2 * MM, -DEPTH]],
                               [[9.5004 * UM, -6.9992 * UM, -0.29 * UM],
                                [9.5004 * UM, -6.9992 * UM, -0.09 * UM]], atol=1e-10)


def test_a_tool_setting_offset_turns_with_the_tool_on_b():
    """robonano_a0ib, B = 30 deg: the offset (1, 0, 2) um is in the tool_mount frame, which B
    turns about Y: (cos 30 + 2 sin 30, 0, -sin 30 + 2 cos 30) = (1.866, 0, 1.232) um; the slot
    ends 1.866 um further along X and 1.232 um shallower."""
    offset = {"tool": {"offset_um": [1.0, 0.0, 2.0]}}
    nominal = np.array(_ends(_slot_vertices("robonano_a0ib", None, _slot(b_deg=30.0))[1]))
    moved = np.array(_ends(_slot_vertices("robonano_a0ib", offset, _slot(b_deg=30.0))[1]))
    c, s = math.cos(math.pi / 6), math.sin(math.pi / 6)
    shift = np.array([c + 2 * s, 0.0, -s + 2 * c]) * UM
    np.testing.assert_allclose(moved - nominal, [shift, shift], atol=1e-12)
