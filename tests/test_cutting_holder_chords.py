"""The holder's allowance sweep by sweep (`machinesim.cutting.holder_allowance`): a straight
pass gets the rounding of its words, whatever chords the program has elsewhere; a chord, or a
straight pass whose holder meets a wall chords cut before, one chord."""

from __future__ import annotations

import numpy as np
import pytest

from machinesim.cutting import cut, cut_turned
from machinesim.exceptions import HolderContactError
from machinesim.nc import parse_program

MM = 1e-3

#: flat:1.0:h=1 (1 mm in radius, 1 mm of body, the holder as wide)
KWARGS = {"tool": "flat:1.0:h=1", "stock": "block:10x10x3"}


def _slot_then_step(dx_mm: float, tail: str = "") -> str:
    """A slot along Y at x = 5 mm, 0.5 then 1 mm down, then a pass 1.5 mm down ``dx_mm``
    over (line 12): the holder, from z = -0.5 mm up over x = 4 + dx to 6 + dx mm, enters the
    slot's wall (x = 6 mm) by ``dx_mm`` (by hand); ``tail`` after it."""
    return ("G21 G90\nG00 X5. Y-1. Z1.\nG01 Z-0.5 F100.\nY11.\nG00 Z1.\nG00 X5. Y-1.\n"
            "G01 Z-1.0\nY11.\nG00 Z1.\n"
            f"G00 X{5 + dx_mm:.3f} Y-1.\nG01 Z-1.5\nY11.\nG00 Z5.\n{tail}M30\n")


#: an arc 10 mm off the block, in air
ARC_IN_AIR = "G00 X20. Y20.\nG02 X22. Y20. I1. J0. F100.\nG00 Z5.\n"
#: half a turn of C, 10 mm off the block, in air
TURN_IN_AIR = "G00 X20. Y20.\nG01 C180. F100.\nG00 Z5.\n"


@pytest.mark.parametrize("f", [cut, cut_turned])
def test_an_arc_read_coarse_elsewhere_forgives_no_holder_in_a_straight_wall(f):
    # the arc, read within 1 mm, gave every move a 1 mm allowance (at most half the
    # holder's 1 mm radius: 0.5 mm), and the holder 0.2 mm into the wall was cut, exit 0
    with pytest.raises(HolderContactError, match=r"line 12 takes the top of the tool's body"):
        f(parse_program(_slot_then_step(0.2, ARC_IN_AIR), chord_tolerance=1 * MM),
          "grooving_4axis", **KWARGS)
    _, report = f(parse_program(_slot_then_step(0.0, ARC_IN_AIR), chord_tolerance=1 * MM),
                  "grooving_4axis", **KWARGS)
    assert report.holder_contact == ()  # in the slot, touching its wall


@pytest.mark.parametrize("f", [cut, cut_turned])
def test_a_rotary_move_elsewhere_under_a_coarse_chord_forgives_no_holder_in_a_wall(f):
    # the C turn, split within 1 mm (7 sub-steps), gave every move a 1 mm allowance
    with pytest.raises(HolderContactError, match=r"line 12 takes the top of the tool's body"):
        f(parse_program(_slot_then_step(0.2, TURN_IN_AIR)), "grooving_4axis",
          chord_tolerance=1 * MM, **KWARGS)
    _, report = f(parse_program(_slot_then_step(0.0, TURN_IN_AIR)), "grooving_4axis",
                  chord_tolerance=1 * MM, **KWARGS)
    assert report.holder_contact == ()


def test_each_move_gets_its_own_chord():
    from machinesim import motion
    from machinesim.cutting.program import holder_tolerance
    from machinesim.machines import load_machine

    machine = load_machine("grooving_4axis")
    program = parse_program(_slot_then_step(0.2, ARC_IN_AIR + TURN_IN_AIR),
                            chord_tolerance=1e-5)
    plan = motion.plan(program, machine, chord_tolerance=1e-4)
    own = holder_tolerance(program, 1e-4, plan)
    written = np.sqrt(2.0) * 1e-6  # the words' rounding at 3 decimals of mm
    lines = np.asarray(plan.lines)
    arc, turn = lines == 15, lines == 18  # the G02 and the G01 C180.
    assert arc.sum() > 1 and turn.sum() == 1  # the arc's chords, the turn one move
    assert (own[arc] == 1e-5).all()  # as read
    assert (own[turn] == 1e-4).all()  # as split
    assert (own[~arc & ~turn] == written).all()  # written, cut exactly
    # a finer chord tolerance leaves the words' rounding as it is; the turn, a feed that turns
    # C in a program with arcs, keeps the arcs' (the reader keeps no arc length for the
    # chords of an arc that turns a rotary axis, so they are not told apart)
    fine = holder_tolerance(program, 1e-9, plan)
    assert (fine[~arc & ~turn] == written).all() and (fine[turn] == 1e-5).all()


def _bore_then_across(out_mm: float = 0.0, tools: str = "") -> str:
    """A helical bore, radius 0.4 mm about the origin, 0.25 mm down each G02 half turn to
    1.5 mm, a full circle there (arcs read within 10 um: 8 chords a half turn, their ends at
    multiples of pi / 8), then a straight pass across it at the bottom between two middles
    of those chords, on the circle (angles pi / 16 and 15 pi / 16, written to 4 decimals,
    21 nm inside), ``out_mm`` further in Y; with ``tools``, T2 (its holder as wide) cuts the
    pass (from line 11, or with a tool change 12)."""
    lines = ["G21 G90 G94", "G00 X0.4 Y0. Z0.1", "G01 Z0. F100."]
    for k in range(6):
        x = -0.4 if k % 2 == 0 else 0.4
        lines.append(f"G02 X{x:.4f} Y0. Z{-0.25 * (k + 1):.4f} I{x:.4f} J0.")
    lines.append("G02 X0.4 Y0. I-0.4 J0.")
    if tools:
        lines.append("T2 M06")
    y = 0.4 * np.sin(np.pi / 16) + out_mm
    c = 0.4 * np.cos(np.pi / 16)
    lines += [f"G01 X{c:.4f} Y{y:.4f}", f"X{-c:.4f}", "G00 Z1.", "M30"]
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("change", [False, True])
def test_a_straight_pass_whose_holder_meets_a_wall_arcs_cut_gets_their_chord(tmp_path,
                                                                            change):
    """The pass's holder, from z = -0.5 mm up, stands at its ends on the circle, where the
    half turns' chords cut the wall in their middles R (1 - cos(pi / 16)) = 7.686 um short
    of it (by hand): within the arcs' chord (10 um), no crash. Judged by its own allowance
    alone (100 nm, a straight move's) it is refused; it gets the chord of the arcs that cut
    the wall about its holder before, by the same tool or an earlier one. 0.1 mm further in
    Y (its ends 31 um outside the circle) it is refused."""
    kwargs = {"tool": "flat:1.0:h=1", "stock": "block:5x5x3@-2.5,-2.5,0"}
    table = None
    if change:
        table = tmp_path / "tools.toml"
        table.write_text('[tool.2]\nlength_mm = 0.0\nshape = "flat:1.0:h=1"\n')
    line = 12 if change else 11  # the move out to the pass

    def read(out_mm):
        return parse_program(_bore_then_across(out_mm, "T2" if change else ""),
                             chord_tolerance=1e-5, tools=table)

    part, report = cut(read(0.0), "grooving_4axis", **kwargs)
    allowed, by_body = cut(read(0.0), "grooving_4axis", allow_holder_contact=True, **kwargs)
    assert by_body.holder_contact  # the box step finds the pass's holder below the top
    assert report.holder_contact == ()
    assert part.volume == pytest.approx(allowed.volume, rel=1e-12)
    with pytest.raises(HolderContactError, match=rf"line {line} \(lines {line}, "):
        cut(read(0.1), "grooving_4axis", **kwargs)


#: an arc read within 1 mm at the slot's far end, 0.1 mm deep, about (5, 10.5) mm: its body
#: (1 mm in radius) cuts the block's top to x 3.5 .. 6.5 mm over y 9.5 .. 10 mm, its box
#: meeting the room of the pass along the whole slot there and nowhere else
ARC_AT_THE_END = "G00 X4.5 Y10.5\nG01 Z-0.1\nG02 X5.5 Y10.5 I0.5 J0.\nG00 Z5.\n"


@pytest.mark.parametrize("f", [cut, cut_turned])
def test_a_chorded_cut_at_one_end_forgives_no_holder_in_the_wall_along_the_pass(f):
    # the pass (line 16) runs its holder 0.2 mm into the slot's straight wall over y 0 ..
    # 9.5 mm, far from any chord: the arc, whose box met the pass's room at y 9.5 mm, lent
    # the whole pass its 1 mm (0.5 mm, half the holder's radius), and it was cut, exit 0
    def slot(dx_mm):
        return parse_program(_slot_then_step(dx_mm, "").replace(
            f"G00 X{5 + dx_mm:.3f} Y-1.", ARC_AT_THE_END + f"G00 X{5 + dx_mm:.3f} Y-1."),
            chord_tolerance=1 * MM)

    with pytest.raises(HolderContactError, match=r"line 16 takes the top of the tool's body"):
        f(slot(0.2), "grooving_4axis", **KWARGS)
    _, report = f(slot(0.0), "grooving_4axis", **KWARGS)
    assert report.holder_contact == ()  # in the slot, touching its wall


def test_a_chorded_cut_lends_only_inside_its_box_on_each_leg_of_a_tilted_workpiece(
        monkeypatch):
    # the same slot, arc and pass on a tilted workpiece (paper 002's setting error), after a
    # feed at C = 90 deg in air: the end mill stands in two orientations, and cut_turned's
    # check walks each leg in its own frame (holder_legs.in_material_by_legs), the slot's sweeps
    # being the program's from the C = 90 leg's count on. There too the arc's 1 mm holds
    # only inside its box, turned into the leg's frame: 0.2 mm into the wall is refused
    from machinesim.cutting import holder_legs

    tilted = {"workpiece": {"alpha_deg": 0.01, "beta_deg": -0.02}}
    away = "G00 C90. X20. Y20. Z5.\nG01 X22. F100.\nG00 Z5.\nG00 C0.\n"

    def slot(dx_mm):
        return parse_program(_slot_then_step(dx_mm, "").replace(
            f"G00 X{5 + dx_mm:.3f} Y-1.", ARC_AT_THE_END + f"G00 X{5 + dx_mm:.3f} Y-1.")
            .replace("G21 G90\n", "G21 G90\n" + away), chord_tolerance=1 * MM)

    lent = []
    walk = holder_legs.in_material_by_legs

    def spy(*args):  # (stock, tool, paths, legs, candidates, tolerance, lent)
        lent.append((len(args[3]), dict(args[6] or {}) if len(args) > 6 else {}))
        return walk(*args)

    monkeypatch.setattr(holder_legs, "in_material_by_legs", spy)
    with pytest.raises(HolderContactError, match=r"line 20 takes the top of the tool's body"):
        cut_turned(slot(0.2), "grooving_4axis", errors=tilted, **KWARGS)
    assert lent and lent[-1][0] == 2 and lent[-1][1]  # two legs, the pass's chord borrowed
    _, report = cut_turned(slot(0.0), "grooving_4axis", errors=tilted, **KWARGS)
    assert report.holder_contact == ()  # in the slot, touching its wall


def test_a_leg_of_a_tilted_workpiece_borrows_inside_the_lenders_boxes_turned_into_its_frame():
    # the bore and the pass across it, 0.8 mm off the C axis, cut at C = 90 deg on a tilted
    # workpiece after a feed at C = 0 in air: cut_turned's check walks the C = 90 leg in its
    # own frame, 90 deg about the axis from the workpiece's. The arcs' boxes, kept in the
    # workpiece frame, are turned into it with the stock: left unturned they lay about the
    # bore's place turned 90 deg away, and the pass the arcs' chord forgives was refused
    import re

    tilted = {"workpiece": {"alpha_deg": 0.01, "beta_deg": -0.02}}
    kwargs = {"tool": "flat:1.0:h=1", "stock": "block:5x5x3@-2.5,-2.5,0", "errors": tilted}

    def read(out_mm):
        lines = [re.sub(r"X(-?[0-9.]+)", lambda m: f"X{float(m.group(1)) + 0.8:.4f}", line)
                 for line in _bore_then_across(out_mm).splitlines()]
        lines.insert(1, "G00 C0. X4. Y4. Z1.\nG01 X4.5 F100.\nG00 Z1.\nG00 C90.")
        return parse_program("\n".join(lines) + "\n", chord_tolerance=1e-5)

    _, report = cut_turned(read(0.0), "grooving_4axis", **kwargs)
    assert report.holder_contact == ()
    with pytest.raises(HolderContactError, match=r"line 15 \(lines 15, 16\)"):
        cut_turned(read(0.1), "grooving_4axis", **kwargs)
