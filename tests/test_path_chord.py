"""How finely a cut follows arcs and rotary moves: a tenth of its finest tool's own facets,
never finer than the axes' 1 nm (`machinesim.tools.path_chord_tolerance`)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from machinesim.cli import main
from machinesim.cutting import cut
from machinesim.nc import read_program
from machinesim.tools import BallEndMill, FlatEndMill, RoundNoseTool, VTool, path_chord_tolerance

MM = 1e-3
#: A quarter arc G02 of radius 1 mm, 20 um into a 10 x 10 mm block, entered from beside it.
QUARTER = ("G90 G21 G94 G17\nG00 X4. Y6. Z1.\nG00 Z-0.02\nG01 X5. F300.\n"
           "G02 X6. Y5. I0. J-1.\nG00 Z1.\nM30\n")


@pytest.mark.parametrize(("tools", "expected_m"), [
    ([VTool(math.pi / 2)], 1e-9),                        # drawn exactly: the axes' 1 nm
    ([RoundNoseTool(2 * MM, math.pi / 2)], 1e-9),        # a nose within 1 nm: 0.1 nm -> 1 nm
    ([BallEndMill(0.5 * MM)], 1e-7),                     # 1 um facets: 100 nm
    ([FlatEndMill(1 * MM)], 1e-7),
    ([BallEndMill(0.5 * MM, chord_tol=4e-6)], 4e-7),
    ([BallEndMill(0.5 * MM), VTool(math.pi / 2)], 1e-9),  # the finest tool sets it
    ([BallEndMill(0.01 * MM, chord_tol=5e-9)], 1e-9),
])
def test_the_path_chord_is_a_tenth_of_the_finest_tools_facets_and_at_least_1_nm(tools,
                                                                                 expected_m):
    assert path_chord_tolerance(tools) == pytest.approx(expected_m, rel=1e-12)


def test_a_program_file_cut_with_a_ball_follows_its_arcs_at_a_tenth_of_the_balls_facets(
        tmp_path):
    # The quarter arc of radius R = 1 mm within 100 nm: chords of angle 2 acos(1 - tol / R),
    # so ceil((pi / 2) / that) of them (56), not the 1 nm reading's 556.
    path = tmp_path / "quarter.nc"
    path.write_text(QUARTER)
    ball = BallEndMill(0.2 * MM)
    chord = path_chord_tolerance([ball])
    program = read_program(path, chord_tolerance=chord)
    arc = [m for m in program.moves if m.line == 5]
    assert len(arc) == math.ceil((math.pi / 2) / (2 * math.acos(1 - chord / MM))) == 56
    assert len([m for m in read_program(path).moves if m.line == 5]) == math.ceil(
        (math.pi / 2) / (2 * math.acos(1 - 1e-9 / MM)))
    # every chord's middle lies within the tolerance inside the circle about (5, 5) mm
    ends = np.array([[m.target["X"], m.target["Y"]] for m in arc])
    ends = np.vstack([[5 * MM, 6 * MM], ends])
    middle = np.linalg.norm((ends[1:] + ends[:-1]) / 2 - [5 * MM, 5 * MM], axis=1)
    assert np.all(MM - middle <= chord * (1 + 1e-9)) and np.max(MM - middle) > 0.9 * chord
    # cut() given the file's path reads it so, as the command line does
    _, from_path = cut(path, "grooving_4axis", tool=ball, stock="block:10x10x2")
    _, from_program = cut(program, "grooving_4axis", tool=ball, stock="block:10x10x2")
    assert from_path.sweeps == from_program.sweeps
    assert from_path.removed_volume_m3 == from_program.removed_volume_m3 > 0.0


@pytest.mark.parametrize(("tool", "option", "chord_nm", "noted"), [
    ("ball:0.5", [], 100.0, True), ("v:90", [], 1.0, False),
    ("ball:0.5", ["--chord-nm", "5"], 5.0, False)])
def test_the_command_line_reports_the_chord_it_cut_with(tmp_path, capsys, tool, option,
                                                        chord_nm, noted):
    # a line with an arc in it: the chord is noted only where something was split by it
    # (tests/test_cli.py has the cases without arcs)
    program = tmp_path / "line.nc"
    program.write_text("G90 G21\nG00 X-1. Y5. Z1.\nG01 Z-0.01 F100.\nX4.\nG02 X6. R1.\n"
                       "G01 X11.\nG00 Z1.\nM30\n")
    report = tmp_path / "r.json"
    code = main([str(a) for a in ["cut", program, "--machine", "grooving_4axis", "--tool",
                                  tool, "--stock", "block:10x10x2", "--quiet", "--out",
                                  tmp_path / "p.ply", "--report", report, *option]])
    err = capsys.readouterr().err
    assert code == 0, err
    assert json.loads(report.read_text())["path_chord_tolerance_nm"] == pytest.approx(chord_nm)
    assert ("note: arcs and rotary moves were split into chords within 100 nm" in err) == noted
