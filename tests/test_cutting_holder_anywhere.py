"""The holder check reads the whole stock, whatever windows (``roi``) the part is cut in: the
holder meeting the part outside them is a crash all the same, and a cut that refuses it
without windows refuses it with them."""

from __future__ import annotations

import numpy as np
import pytest

from machinesim.cutting import cut, remove
from machinesim.exceptions import HolderContactError
from machinesim.nc import parse_program
from machinesim.rotations import rot_x
from machinesim.tools import FlatEndMill
from machinesim.workpiece import block

MM = 1e-3

#: A shallow pass at x = 1 mm, in the window below, then a pass at x = 8 mm 11 mm down with
#: a 10 mm body: the body's top 1 mm below the block's top, its holder in the block (x 0 to
#: 10 mm), outside the window.
CRASH = ("G21 G90 G17\nG00 X1. Y-1. Z1.\nG01 Z-0.05 F100.\nG01 Y11.\nG00 Z1.\n"
         "G00 X8. Y-1.\nG01 Z-11. F100.\nG01 Y11.\nG00 Z15.\nM30\n")
WINDOW = [(0.0, 3 * MM, 0.0, 10 * MM)]


@pytest.mark.parametrize("roi", [None, WINDOW])
def test_a_holder_crash_outside_the_windows_is_refused(roi):
    # with the window it was cut, exit 0, no word (the window's part is that of the pass
    # at x = 1 mm alone)
    with pytest.raises(HolderContactError, match=r"line 8 takes the top of the tool's body"):
        cut(parse_program(CRASH), "grooving_4axis", tool="flat:1.0",
            stock="block:10x10x10", roi=roi)


def test_a_tilted_end_mill_is_judged_over_the_whole_stock_too():
    # an end mill tilted 1 mrad (cut in its own frame, where the stock was cut down to the
    # windows before the holder was judged): the same pass 11 mm down at x = 8 mm
    stock, tool = block(10 * MM, 10 * MM, 10 * MM), FlatEndMill(1 * MM)
    path = np.tile(np.eye(4), (2, 1, 1))
    path[:, :3, :3] = rot_x(1e-3)
    path[:, :3, 3] = [[8 * MM, -1 * MM, -11 * MM], [8 * MM, 11 * MM, -11 * MM]]
    for roi in (None, WINDOW):
        met = []
        remove(stock, tool, [path], roi=roi, on_holder_contact=met.append)
        assert met == [(0,)]


def _two_tools(tmp_path, x_mm: float):
    """T1 (the cut's flat:1.0:h=12) cuts a slot 5 mm deep along Y at x = 8 mm; T2, a flat
    end mill 1 mm across with a 2 mm body, runs 4 mm down along Y at ``x_mm``: in the slot
    (x 7 to 9 mm) its holder is in air, at x = 6 mm it meets the slot's wall."""
    table = tmp_path / "tools.toml"
    table.write_text('[tool.1]\nlength_mm = 0.0\n'
                     '[tool.2]\nlength_mm = 0.0\nshape = "flat:0.5:h=2"\n')
    text = ("G21 G90\nT1 M06\nG00 X8. Y-2. Z1.\nG01 Z-5. F100.\nY12.\nG00 Z15.\n"
            f"T2 M06\nG00 X{x_mm:.1f} Y-1. Z1.\nG01 Z-4. F100.\nY11.\nG00 Z15.\nM30\n")
    return parse_program(text, tools=table)


@pytest.mark.parametrize("roi", [None, WINDOW])
def test_a_later_tool_is_judged_against_what_the_earlier_left_outside_the_windows(tmp_path,
                                                                                  roi):
    # with the window the part T2 was given held the window alone: its crash at x = 6 mm
    # was cut without a word; in the slot (the rooms' box re-cut by T1 alone) it is cut
    kwargs = {"tool": "flat:1.0:h=12", "stock": "block:10x10x10", "roi": roi}
    _, report = cut(_two_tools(tmp_path, 8.0), "grooving_4axis", **kwargs)
    assert report.holder_contact == ()
    with pytest.raises(HolderContactError, match=r"line 10 takes the top of the tool's body"):
        cut(_two_tools(tmp_path, 6.0), "grooving_4axis", **kwargs)


def _turned_slot(x_mm: float = 0.0) -> str:
    """A shallow pass at C = 0; at C = 90 deg three passes along X through the C axis, 1, 2
    and 3 mm down (a slot 1 mm wide along the workpiece's Y); at C = 0 again a pass along Y
    3 mm down at X = ``x_mm`` (line 22): in the slot for 0, in its wall for 0.6 mm. The
    tool's body is 2 mm tall."""
    lines = ["G21 G90", "G00 C0. X-3. Y2. Z1.", "G01 Z-0.1 F300.", "X3.", "G00 Z1.",
             "G00 C90."]
    for k in (1, 2, 3):
        lines += ["G00 X-4. Y0. Z1.", f"G01 Z-{k}. F300.", "X4.", "G00 Z1."]
    lines += ["G00 C0.", f"G00 X{x_mm:.1f} Y-4. Z1.", "G01 Z-3. F300.", "Y4.", "G00 Z5.",
              "M30"]
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("roi", [None, [(-5 * MM, -2 * MM, -5 * MM, 5 * MM)]])
def test_turned_groups_judge_the_holder_in_the_programs_order(roi):
    # the last pass (line 22), at C = 0, runs in the slot the C = 90 deg passes cut before
    # it: cut cuts it; cut_turned cut the C = 0 group first and refused it (its holder in
    # a block not yet slotted). Moved 0.6 mm into the slot's wall both refuse it, with a
    # window off the slot too (cut_turned judged the stock cut down to the window)
    from machinesim.cutting import cut_turned

    kwargs = {"tool": "flat:1.0:h=2", "stock": "block:10x10x5@-5,-5,0", "roi": roi}
    parts = [f(parse_program(_turned_slot()), "grooving_4axis", **kwargs)
             for f in (cut, cut_turned)]
    assert all(report.holder_contact == () for _, report in parts)
    assert parts[1][0].volume == pytest.approx(parts[0][0].volume, rel=1e-12)
    for f in (cut, cut_turned):
        with pytest.raises(HolderContactError,
                           match=r": line 22( \(lines 22, 23\))? takes the top of the tool"):
            f(parse_program(_turned_slot(0.6)), "grooving_4axis", **kwargs)


def _slot_then_step(dx_mm: float) -> str:
    """Straight moves only: a slot along Y at x = 5 mm, 0.5 then 1 mm down, then a pass
    1.5 mm down ``dx_mm`` over (line 12): a 1 mm body (flat:1.0:h=1) there has its holder
    from z = -0.5 mm up, over x = 4.55 to 5.55 mm for 0.05, into the slot's wall (x = 5.5 mm)
    by 50 um."""
    return ("G21 G90\nG00 X5. Y-1. Z1.\nG01 Z-0.5 F100.\nY11.\nG00 Z1.\nG00 X5. Y-1.\n"
            "G01 Z-1.0\nY11.\nG00 Z1.\n"
            f"G00 X{5 + dx_mm:.3f} Y-1.\nG01 Z-1.5\nY11.\nG00 Z5.\nM30\n")


@pytest.mark.parametrize("name", ["cut", "cut_turned"])
def test_a_coarse_chord_tolerance_forgives_no_holder_in_a_straight_wall(name):
    # the holder was judged within the cut's chord tolerance (100 um here, --chord-nm takes
    # up to 1 m) though no move is split into chords: straight moves are cut exactly, and
    # the holder 50 um into the wall was cut without a word
    from machinesim.cutting import cut_turned
    from machinesim.cutting.program import holder_tolerance

    f = {"cut": cut, "cut_turned": cut_turned}[name]
    kwargs = {"tool": "flat:1.0:h=1", "stock": "block:10x10x3", "chord_tolerance": 1e-4}
    _, report = f(parse_program(_slot_then_step(0.0)), "grooving_4axis", **kwargs)
    assert report.holder_contact == ()  # in the slot: touching its wall, no more
    with pytest.raises(HolderContactError, match=r"line 12 takes the top of the tool's body"):
        f(parse_program(_slot_then_step(0.05)), "grooving_4axis", **kwargs)
    # no chords: only the words' rounding (whatever the chord tolerance; written to 3
    # decimals of mm, sqrt(2) um: `written_rounding`), move by move; an arc read within
    # 10 um gives its chords their 10 um, the rapid before it its words' rounding (no
    # decimals: taken as 3)
    from machinesim import motion

    straight = parse_program(_slot_then_step(0.05))
    plan = motion.plan(straight, _machine(), chord_tolerance=1e-4)
    assert (holder_tolerance(straight, 1e-4, plan) == np.sqrt(2.0) * 1e-6).all()
    assert (holder_tolerance(straight, 1e-9, plan) == np.sqrt(2.0) * 1e-6).all()
    arcs = parse_program("G21 G90 G17\nG00 X1. Y0. Z0.\nG02 X-1. Y0. I-1. J0. F100.\nM30\n",
                         chord_tolerance=1e-5)
    own = holder_tolerance(arcs, 1e-7, motion.plan(arcs, _machine()))
    assert own[0] == np.sqrt(2.0) * 1e-6 and len(own) > 2 and (own[1:] == 1e-5).all()


def _machine():
    from machinesim.machines import load_machine

    return load_machine("grooving_4axis")


#: A workpiece set tilted (paper 002's setting error, as models/errors/example.toml has it):
#: an end mill's floors are level only in its own frame, which differs at each C.
TILTED = {"workpiece": {"alpha_deg": 0.01, "beta_deg": -0.02}}


def test_turned_groups_on_a_tilted_workpiece_judge_the_holder_in_each_c_positions_frame(
        monkeypatch):
    # the program's C = 0, 90 deg, 0 legs share no tool frame, and the check walked the
    # sweeps in the workpiece frame, where each end mill floor is tilted with its own
    # round-off: the walk's material broke into slivers (a contour in 3 levels under a short
    # body with one pass at C = 90 deg: 235 s of CPU, 27 s without that pass). Each leg is
    # now walked where the tool stands upright: every sweep the walk builds is a pure
    # translation. The verdicts are cut's: in the slot, cut; 0.6 mm into its wall, refused
    from machinesim.cutting import cut_turned
    from machinesim.cutting.sweepset import SweepSet
    from machinesim.errors import as_error_model

    built = []
    hulls = SweepSet.hulls

    def spy(self, keep, progress=None):
        built.append(self.poses[:, :3, :3].copy())
        return hulls(self, keep, progress)

    errors = as_error_model(TILTED)
    kwargs = {"tool": "flat:1.0:h=2", "stock": "block:10x10x5@-5,-5,0", "errors": errors}
    monkeypatch.setattr(SweepSet, "hulls", spy)
    _, report = cut_turned(parse_program(_turned_slot()), "grooving_4axis", **kwargs)
    assert report.holder_contact == ()
    # the check's walk, then the two turn groups' own cuts (in their frames, as before)
    assert len(built) > 2 and all((rotation == np.eye(3)).all() for rotation in built)
    monkeypatch.undo()
    for f in (cut, cut_turned):
        with pytest.raises(HolderContactError,
                           match=r": line 22( \(lines 22, 23\))? takes the top of the tool"):
            f(parse_program(_turned_slot(0.6)), "grooving_4axis", **kwargs)


def test_the_turn_between_two_c_positions_keeps_a_level_face_level():
    # the tool frames at C = a and b on a tilted workpiece, F = W^T Rz(-C), differ by Rz(b - a)
    # (the tilt cancels): the turn the walk makes between them is that, its Z row and column
    # exact, so a level face keeps its height to the bit; with the C axis itself tilted
    # (10 urad about X) the frames differ by more, and the turn is the product as it is
    from machinesim.cutting.holder_legs import _between
    from machinesim.rotations import rot_y, rot_z

    tilt = rot_x(np.radians(0.01)) @ rot_y(np.radians(-0.02))
    for a, b in ((0.0, np.pi / 2), (np.pi / 2, 0.0), (0.3, -2.1)):
        f_a, f_b = tilt.T @ rot_z(-a), tilt.T @ rot_z(-b)
        turn = _between(f_b, f_a)
        assert (turn[2] == [0.0, 0.0, 1.0]).all() and (turn[:, 2] == [0.0, 0.0, 1.0]).all()
        np.testing.assert_allclose(turn, rot_z(b - a), atol=1e-15)
        point = np.array([1.3e-3, -2.7e-3, -4e-4])
        assert (turn @ point)[2] == point[2]
    f_a, f_b = tilt.T, (rot_x(1e-5) @ tilt).T @ rot_z(-np.pi / 2)
    np.testing.assert_array_equal(_between(f_b, f_a), f_b.T @ f_a)
