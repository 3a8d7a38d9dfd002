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
    # (tests/test_cli_cut.py has the cases without arcs)
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


@pytest.mark.parametrize("first_c", ["", "G00 C0.\n"])
def test_a_first_rotary_feed_from_home_is_noted_as_split(tmp_path, capsys, first_c):
    # G01 C10. with no C word before it (a new-user pass's trunnion program, G01 A1.): C
    # turns from the home's 0 and the move is cut in sub-steps of the 100 nm chord, as
    # after a G00 C0., but its previous target was NaN and the note was left out
    program = tmp_path / "turn.nc"
    program.write_text(f"G90 G21\n{first_c}G00 X5. Y0. Z1.\nG01 Z-0.01 F100.\n"
                       "G01 C10. F360.\nG00 Z1.\nM30\n")
    report = tmp_path / "r.json"
    code = main([str(a) for a in ["cut", program, "--machine", "grooving_4axis", "--tool",
                                  "ball:0.5", "--stock", "block:10x10x2@0,-5,0", "--quiet",
                                  "--out", tmp_path / "p.ply", "--report", report]])
    err = capsys.readouterr().err
    assert code == 0, err
    # 10 deg at 5 mm split within 100 nm: chords of at most sqrt(8 x 100 nm / 5 mm) rad
    steps = math.ceil(math.radians(10.0) / math.sqrt(8 * 100e-9 / 5e-3))
    assert json.loads(report.read_text())["sweeps_count"] >= steps == 14
    assert "note: arcs and rotary moves were split into chords within 100 nm" in err


def _chord_refusal(value) -> str:
    """The refusal of a ``chord_tolerance`` of ``value`` (m), written out: the words of
    ``--chord-nm``'s (tests/test_cli_refusals.py), in m."""
    return (f"chord_tolerance {value!r}: expected a length in m from 1e-09, the axes' "
            "resolution (no machine follows a path more finely, and the chords grow in "
            "number as 1/sqrt(chord_tolerance): ten times 1 nm's at 1e-11), to 1 (1 m, more "
            "than any machine's travel)")


@pytest.mark.parametrize("chord", [1e-11, 0.999e-9, 0.0, -1e-9, float("nan"), 1.001, "fine"])
@pytest.mark.parametrize("call", ["cut", "cut_turned", "machine_scene"])
def test_the_api_refuses_a_chord_tolerance_outside_1_nm_to_1_m_before_any_work(tmp_path, call,
                                                                               chord):
    # --chord-nm 0.01 was refused while cut(..., chord_tolerance=1e-11) ran on: a 3 mm half
    # circle with ball:0.5 is 13,607 sweeps at 0.01 nm (>120 s), 1,364 at 1 nm. Refused
    # before anything is read: the program file and the machine named here do not exist.
    from machinesim.cutting import cut_turned
    from machinesim.exceptions import InputError
    from machinesim.viewer import machine_scene

    missing = tmp_path / "missing.nc"
    calls = {"cut": lambda: cut(missing, "no_such_machine", chord_tolerance=chord),
             "cut_turned": lambda: cut_turned(read_program(_quarter(tmp_path)),
                                              "no_such_machine", chord_tolerance=chord),
             "machine_scene": lambda: machine_scene("no_such_machine", chord_tolerance=chord)}
    with pytest.raises(InputError) as refused:
        calls[call]()
    assert str(refused.value) == _chord_refusal(chord)


def _quarter(tmp_path):
    path = tmp_path / "quarter.nc"
    path.write_text(QUARTER)
    return path


@pytest.mark.parametrize("chord", [1e-9, 1.0])
def test_the_api_takes_the_chord_tolerances_bounds(tmp_path, chord):
    # the bounds themselves are taken, as --chord-nm's are (tests/test_cli_cut.py); the quarter
    # arc read at 1 um, so that 1 nm costs no more sweeps than 1 m
    program = read_program(_quarter(tmp_path), chord_tolerance=1e-6)
    _, report = cut(program, "grooving_4axis", tool="v:90", stock="block:10x10x2",
                       chord_tolerance=chord)
    assert report.removed_volume_m3 > 0.0


#: The quarter arc above the block (Z 1 mm): nothing is cut, so a reading of 1 nm is quick.
QUARTER_ABOVE = QUARTER.replace("G00 Z-0.02\n", "")


def test_a_program_keeps_the_chord_tolerance_its_arcs_were_read_with(tmp_path):
    import pickle

    from machinesim.nc import Move, Program, parse_program

    assert parse_program(QUARTER).arc_chord_tolerance == 1e-9  # parse_program's default
    assert read_program(_quarter(tmp_path), chord_tolerance=1e-7).arc_chord_tolerance == 1e-7
    read = parse_program(QUARTER, chord_tolerance=2e-7)
    assert pickle.loads(pickle.dumps(read)).arc_chord_tolerance == 2e-7
    assert read.with_targets(read.targets).arc_chord_tolerance == 2e-7  # as compensated
    # no arc read, or moves built in Python: no chords to speak of
    assert parse_program("G00 X1.\nG01 Y1. F100.\n", chord_tolerance=1e-7).arc_chord_tolerance \
        is None
    assert Program([Move("rapid", {"X": 0.001})]).arc_chord_tolerance is None


def test_cut_notes_a_program_whose_arcs_were_read_finer_or_coarser_than_it_cuts():
    # parse_program splits arcs within 1 nm; cut() follows a ball's path within 100 nm, and
    # ran the 1 nm chords as given, 10 times as many sweeps (37,964 against 3,836 on a
    # 12.8 mm helical bore with flat:1.35), without a word. The ratio is sqrt(100 / 1): the
    # chords' number goes as 1/sqrt(tolerance) (556 against 56 on this quarter arc).
    from machinesim.nc import parse_program

    ball = BallEndMill(0.2 * MM)
    fine = parse_program(QUARTER_ABOVE)
    assert len(fine) - len(parse_program(QUARTER_ABOVE, chord_tolerance=1e-7)) == 556 - 56
    _, report = cut(fine, "grooving_4axis", tool=ball, stock="block:10x10x2")
    assert ("the program's 1 arc block was read as chords within 1 nm, finer than the 100 nm "
            "this cut follows: about 10 times as many sweeps on them, for a part within 100 nm "
            "of the same; read it with read_program/parse_program(..., chord_tolerance=1e-07) "
            "(machinesim.tools.path_chord_tolerance([tool])), or give cut() the file's path "
            "(docs/cutting.md)") in report.notes
    # read as the cut follows (0.1 * 1e-6 against 1e-7 written: the same), or cut with a V
    # tool, which follows 1 nm: nothing to say
    for program, tool in ((parse_program(QUARTER_ABOVE, chord_tolerance=1e-7), ball),
                          (fine, "v:90")):
        _, report = cut(program, "grooving_4axis", tool=tool, stock="block:10x10x2")
        assert not any("arc block" in note for note in report.notes), report.notes
    # coarser than the cut follows: the part keeps the reading's chords
    _, report = cut(parse_program(QUARTER_ABOVE, chord_tolerance=1e-6), "grooving_4axis",
                    tool="v:90", stock="block:10x10x2")
    assert ("the program's 1 arc block was read as chords within 1000 nm, coarser than the "
            "1 nm this cut follows: the part follows them only within 1000 nm (read with "
            "chord_tolerance=1e-09 to follow them as closely)") in report.notes


def test_cut_turned_and_the_viewer_note_a_program_whose_arcs_were_read_otherwise():
    # cut() said so (above); cut_turned and the viewer's cut of a program, through the same
    # arc_chord_note, said nothing. Read at 1 um and cut at cut_turned's 1 nm: coarser; read
    # at parse_program's 1 nm and drawn with a ball (100 nm, path_chord_tolerance): finer,
    # sqrt(100 / 1) = 10 times the sweeps.
    from machinesim.cutting import cut_turned
    from machinesim.nc import parse_program
    from machinesim.viewer import machine_scene

    coarse = parse_program(QUARTER_ABOVE, chord_tolerance=1e-6)
    _, report = cut_turned(coarse, "grooving_4axis", tool="v:90", stock="block:10x10x2")
    assert ("the program's 1 arc block was read as chords within 1000 nm, coarser than the "
            "1 nm this cut follows: the part follows them only within 1000 nm (read with "
            "chord_tolerance=1e-09 to follow them as closely)") in report.notes
    scene = machine_scene("grooving_4axis", parse_program(QUARTER_ABOVE),
                          tool=BallEndMill(0.2 * MM), stock="block:10x10x2", max_stages=2)
    assert ("the program's 1 arc block was read as chords within 1 nm, finer than the 100 nm "
            "this cut follows: about 10 times as many sweeps on them, for a part within 100 nm "
            "of the same; read it with read_program/parse_program(..., chord_tolerance=1e-07) "
            "(machinesim.tools.path_chord_tolerance([tool]))") in scene.notes
    # read as each cut follows: nothing to say
    _, report = cut_turned(parse_program(QUARTER_ABOVE), "grooving_4axis", tool="v:90",
                           stock="block:10x10x2")
    assert not any("arc block" in note for note in report.notes), report.notes
