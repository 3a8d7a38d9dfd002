"""The text a lab hands out tells none of its truth: refusals, notes and reprs from its cuts
and turns name what was commanded, never an injected value (in any unit), its key or the
file it came from (the honesty rule; tests/honesty_walk.py follows references, not text)."""

from __future__ import annotations

import re

import numpy as np
import pytest
from lab_helpers import groove

import machinesim
from machinesim import Lab
from machinesim.exceptions import InputError
from machinesim.nc import parse_program

#: a lathe program turning a face from X = 5 mm to 0 over 50 turns, its tip at z = 0
FACING = parse_program("%\nO1\nG90 G21 G94\nG00 X5. Z0.1 C0.\nG01 Z0. F10.\n"
                       "G01 X0. C18000. F36000.\nG00 Z0.1\n%\n")


def _tells(text: str, *values_m: float) -> bool:
    """Does ``text`` hold one of ``values_m`` (m) in m, mm, um or nm, to 6 digits?"""
    for token in re.findall(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?", text):
        digits = token.lstrip("+-").split("e")[0].split("E")[0].replace(".", "").lstrip("0")
        if len(digits) < 4:
            continue
        written = float(token)
        for value in values_m:
            for scaled in (value, value * 1e3, value * 1e6, value * 1e9):
                if abs(abs(written) - abs(scaled)) <= 1e-5 * abs(scaled):
                    return True
    return False


def test_tells_finds_a_value_in_any_unit():
    assert _tells("nose radius 0.00314159 mm", 3.14159e-6)
    assert _tells("got -1.14159e-06 m", -1.14159e-6)
    assert not _tells("nose radius 1 mm, 3.1 um", 3.14159e-6)


@pytest.mark.parametrize("turning", [False, True])
def test_a_tool_the_nose_radius_error_does_not_fit_is_refused_naming_the_tool(tmp_path,
                                                                             turning):
    """A lab's cut with a V tool, or with a nose radius the lab's error takes below zero, had
    been refused with `with_nose_radius_error`'s message: "<file>, line 2, key
    'tool_geometry.nose_radius_um': the error model has tool_geometry.nose_radius_um =
    -3.14159 ... got -0.00114159 mm": the truth, its total with the tool and its file. Now
    the tool as commanded (2 um of radius), and nothing of the error but that it is there."""
    path = tmp_path / "secret_truth.toml"
    path.write_text("[tool_geometry]\nnose_radius_um = -3.14159\n")
    lab = Lab("sts_lathe" if turning else "robonano_a0ib", str(path), noise=False)
    with pytest.raises(InputError) as refused:
        if turning:
            lab.turn(FACING, "nose:0.002:90")
        else:
            lab.cut(groove(), "nose:0.002:90", "block:10x10x2")
    text = str(refused.value)
    assert "RoundNoseTool of radius 0.002 mm as commanded" in text
    assert not _tells(text, -3.14159e-6, 2e-6 - 3.14159e-6)
    assert "secret_truth" not in text and "nose_radius_um" not in text
    assert refused.value.__context__ is None and refused.value.__cause__ is None
    if not turning:
        with pytest.raises(InputError) as refused:
            Lab("robonano_a0ib", {"tool_geometry": {"nose_radius_um": 3.14159}},
                noise=False).cut(groove(), "v:90", "block:10x10x2")
        assert not _tells(str(refused.value), 3.14159e-6)
        assert "VTool cannot take" in str(refused.value)
        assert refused.value.__context__ is None
    # the cutters themselves, given the errors, still name them (the user wrote them)
    with pytest.raises(InputError, match=r"nose_radius_um = -3.14159 does not fit"):
        if turning:
            machinesim.cutting.lathe.turn(FACING, "sts_lathe", "nose:0.002:90", str(path))
        else:
            machinesim.cut(groove(), "robonano_a0ib", "nose:0.002:90", "block:10x10x2",
                           str(path))


def test_a_lab_turned_face_names_the_nose_radius_as_commanded_and_keeps_how_it_was_cut():
    """Lab.turn handed out turn()'s TurnedPart: its repr said "nose radius 0.203142 mm" for
    nose:0.2:90 in a lab with a nose radius error of 3.14159 um (0.2 mm + the error), and its
    public ``tool`` and ``paths`` held the erred tool and the paths set off by the tool
    setting error. Its face is now a TurnedFace: the same heights, the radius as commanded,
    and nothing public but ``heights_at``, ``heights`` and ``top``."""
    errors = {"tool": {"offset_um": [1.2345678, 0.0, 0.0]},
              "tool_geometry": {"nose_radius_um": 3.14159}}
    face, _ = Lab("sts_lathe", errors, noise=False).turn(FACING, "nose:0.2:90")
    part, _ = machinesim.cutting.lathe.turn(FACING, "sts_lathe", "nose:0.2:90", errors)
    assert repr(face) == ("TurnedFace(1 run, 201 path points over 50 turns, nose radius "
                          "0.2 mm as commanded, top 0 m)")
    assert "0.203142 mm" in repr(part)  # turn() given the errors tells them
    assert not _tells(repr(face), 3.14159e-6, 0.2e-3 + 3.14159e-6, 1.2345678e-6)
    assert {name for name in dir(face) if not name.startswith("_")} == {
        "heights", "heights_at", "top"}
    x = np.linspace(-4e-3, 4e-3, 801)
    np.testing.assert_array_equal(face.heights_at(x, 0 * x), part.heights_at(x, 0 * x))
    np.testing.assert_array_equal(face.heights(x[:5], x[:3]), part.heights(x[:5], x[:3]))


def test_an_empty_turn_in_a_lab_does_not_say_how_far_above_the_tip_stayed():
    """A facing cut with its tip at z = 0 on a top at 0 cuts nothing when the lab's tool sits
    1.2345678 um high: the note said "the tool's tip stays 1.23457 um or more above the
    stock's top": the injected tool.z to 6 digits. turn() given the errors still says so."""
    errors = {"tool": {"offset_um": [0.0, 0.0, 1.2345678]}}
    _, report = Lab("sts_lathe", errors, noise=False).turn(FACING, "nose:1.0:90")
    assert report.empty_cut
    assert report.notes[0].startswith("nothing was cut: the tool's tip stays above the "
                                      "stock's top (z = 0 um) throughout")
    assert not any(_tells(note, 1.2345678e-6) for note in report.notes)
    _, told = machinesim.cutting.lathe.turn(FACING, "sts_lathe", "nose:1.0:90", errors)
    assert "stays 1.23457 um or more above" in told.notes[0]
