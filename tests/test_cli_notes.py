"""Notes and warnings on stderr (and in the report) about a cut that goes on: a program cut
short, a part in pieces or nothing left, errors files that set nothing or are written in
another unit, holder contact, rapids that cut, sideways feeds, table tools that disagree
with the cut's, and the N word beside the line."""

from __future__ import annotations

import json

import numpy as np
import pytest
from cli_helpers import CUT, GROOVES, ROOT, cut_with_report, no_nan, run

import machinesim
import machinesim.cutting
import machinesim.nc


def test_a_program_without_m30_is_noted_as_perhaps_cut_short(tmp_path, capsys):
    """A file that ends inside the slot (no retract, no M30), as a transfer cut short leaves
    it: cut as it stands (the slot 2 mm wide, 0.1 mm deep across the 10 mm block: 2 mm^3,
    the 1 um polygon at most 1e-3 narrower), and the note says where it ran out. With M30,
    or M02, no note."""
    program = tmp_path / "short.nc"
    program.write_text("%\nO1\nG90 G21\nG00 X-1. Y5. Z1.\nG01 Z-0.1 F100.\nX11.\n")
    argv = ["cut", program, "--machine", ROOT / "models" / "examples" / "mill3.urdf",
            "--tool", "flat:1.0", "--stock", "block:10x10x2", "--quiet",
            "--out", tmp_path / "p.ply", "--report", tmp_path / "r.json"]
    code, _, err = run(argv, capsys)
    assert code == 0, err
    report = json.loads((tmp_path / "r.json").read_text())
    assert report["removed_volume_mm3"] == pytest.approx(2.0, rel=1e-3)
    note = ("the program has no M30 or M02 (its last move is at line 6): it ran to the end "
            "of the file, where a FANUC control stops with an alarm")
    assert f"note: {note}" in err and any(n.startswith(note) for n in report["notes"])
    for end in ("M30", "M02"):
        program.write_text(f"%\nO1\nG90 G21\nG00 X-1. Y5. Z1.\nG01 Z-0.1 F100.\nX11.\n"
                           f"G00 Z1.\n{end}\n%\n")
        code, _, err = run(argv, capsys)
        assert code == 0 and "no M30 or M02" not in err, err
        assert machinesim.nc.read_program(program).end_words == {end: 8}


def test_a_groove_through_the_stock_is_said_to_leave_the_part_in_pieces(tmp_path, capsys):
    """A 0.5 mm ball at Z-3 across a 2 mm block (y = 2 mm on 12 x 12 mm from -1): the part
    is two blocks, 12 x 2.5 x 2 = 60 and 12 x 8.5 x 2 = 204 mm^3 (the groove, 1 mm
    wide, took 24), which the part file held with exit 0 and no word; now a warning names
    them, and the report counts them. The grooves of the example leave one piece."""
    program = tmp_path / "deep.nc"
    program.write_text("G90 G21 G17\nG00 X-1. Y2. Z1.\nG01 Z-3. F100.\nX11.\nG00 Z1.\nM30\n")
    report = tmp_path / "deep.json"
    code, _, err = run(["cut", program, "--machine", "grooving_4axis", "--tool", "ball:0.5",
                        "--stock", "block:12x12x2@-1,-1,0", "--quiet", "--out",
                        tmp_path / "deep.ply", "--report", report], capsys)
    assert code == 0, err
    assert ("warning: the part is in 2 separate pieces (204, 60 mm^3), where the stock was "
            "one: a cut went through it") in err, err
    assert json.loads(report.read_text())["part_pieces_count"] == 2
    # the viewer says so too: its overlay shows a report's first 14 keys, not this last one
    code, _, err = run(["view", tmp_path / "deep.ply", "--report", report, "--html",
                        tmp_path / "deep.html"], capsys)
    assert code == 0, err
    assert ("warning: the report says the part is in 2 separate pieces, where the stock was "
            "one: a cut went through it") in err, err
    code, _, err = run(["cut", GROOVES, *CUT, "--out", tmp_path / "g.ply", "--report",
                        tmp_path / "g.json"], capsys)
    assert code == 0 and "separate pieces" not in err, err
    assert json.loads((tmp_path / "g.json").read_text())["part_pieces_count"] == 1
    code, _, err = run(["view", tmp_path / "g.ply", "--report", tmp_path / "g.json", "--html",
                        tmp_path / "g.html"], capsys)
    assert code == 0 and "separate pieces" not in err, err


def test_a_cut_that_leaves_nothing_of_the_stock_says_so(tmp_path, capsys):
    """A 60 mm face mill 3 mm down across a 10 x 10 x 2 mm block takes all of it: 200 mm^3
    removed, a PLY of 0 vertices, which the command wrote with exit 0 and only the bottom's
    warning; `machinesim view` then refuses the file. A warning now says nothing is left.
    Half as deep (1 mm: 100 mm^3 taken) leaves one piece and no such word."""
    for depth, removed in ((3.0, 200.0), (1.0, 100.0)):
        program = tmp_path / f"face{depth:g}.nc"
        program.write_text(f"G90 G21 G17\nG00 X-40. Y5. Z1.\nG01 Z-{depth:g} F200.\n"
                           "X50.\nG00 Z1.\nM30\n")
        report = tmp_path / f"face{depth:g}.json"
        code, _, err = run(["cut", program, "--machine", "grooving_4axis", "--tool",
                            "flat:30:h=20", "--stock", "block:10x10x2", "--quiet", "--out",
                            tmp_path / f"face{depth:g}.ply", "--report", report], capsys)
        assert code == 0, err
        summary = json.loads(report.read_text())
        assert summary["removed_volume_mm3"] == pytest.approx(removed, rel=1e-12)
        assert summary["part_pieces_count"] == (0 if depth > 2 else 1)
        said = "warning: nothing of the stock is left: the cut removed all of it (200 mm^3)"
        assert (said in err) == (depth > 2), err
        # cut()'s note, read from its report: in the JSON's notes, a warning on stderr once
        noted = [n for n in summary["notes"] if n.startswith("nothing of the stock is left")]
        assert len(noted) == (depth > 2) and "note: nothing" not in err, err


def test_a_program_without_moves_is_noted_in_python_as_on_the_command_line(tmp_path,
                                                                           capsys):
    """cut(parse_program('%\\nO1\\nM30\\n%', 'x.nc'), 'grooving_4axis') gave empty_cut=True
    with notes=(), where machinesim cut warned "the program has no moves": the report's notes
    carry it now, and the command line prints it once, as a warning, and writes it once.
    A program with moves that miss the stock has no such note."""
    said = ("the program has no moves (x.nc holds no G00/G01/G02/G03 block that runs), so "
            "nothing was removed")
    _, report = machinesim.cut(machinesim.nc.parse_program("%\nO1\nM30\n%", "x.nc"),
                               "grooving_4axis")
    assert report.empty_cut and report.notes == (said,)
    _, report = machinesim.cut(machinesim.nc.parse_program("G90 G21\nG00 X1. Z30.\nM30\n",
                                                           "x.nc"), "grooving_4axis")
    assert report.empty_cut and not any("no moves" in note for note in report.notes)
    program = tmp_path / "x.nc"
    program.write_text("%\nO1\nM30\n%\n")
    code, _, err = run(["cut", program, "--machine", "grooving_4axis", "--tool", "v:90",
                        "--stock", "block:10x10x2", "--quiet", "--out", tmp_path / "p.ply",
                        "--report", tmp_path / "r.json"], capsys)
    said = said.replace("x.nc", str(program))
    assert code == 0 and err.count("has no moves") == 1, err
    assert f"warning: {said}" in err, err
    assert json.loads((tmp_path / "r.json").read_text())["notes"].count(said) == 1


def test_an_errors_file_that_sets_nothing_is_noted(tmp_path, capsys):
    """An errors file with a section and no key (or empty) cuts with every error zero, as
    the docs say; a note says so, where a file meant to hold errors was taken silently. One
    that writes zeros on purpose, or the example, gets no note."""
    empty, zeros = tmp_path / "empty.toml", tmp_path / "zeros.toml"
    empty.write_text("# to fill in\n[tool]\n")
    zeros.write_text("[tool]\noffset_um = [0.0, 0.0, 0.0]\n")
    code, _, err = run(["cut", GROOVES, *CUT, "--errors", empty, "--out",
                        tmp_path / "a.ply"], capsys)
    assert code == 0 and (f"note: {empty} sets no error (no key in any section): cut on the "
                          "machine as built, every error zero") in err, err
    for errors in (zeros, ROOT / "models" / "errors" / "example.toml"):
        code, _, err = run(["cut", GROOVES, *CUT, "--errors", errors, "--out",
                            tmp_path / "b.ply"], capsys)
        assert code == 0 and "sets no error" not in err, err


def test_an_error_written_in_si_in_a_micrometre_key_is_noted(tmp_path, capsys):
    """EX0C_um = 4e-6 (4 um written in metres) is 4 pm, and tool Y 3e-6 um 3 pm: below a
    hundredth of the axes' 1 nm, no error a machine shows; each is noted with its size
    (by hand: 4e-6 um x 1e-6 m/um) and its line (counted by hand: the notes had named no
    line, where the refusals do). 5 urad and the example's values are not."""
    slip = tmp_path / "slip.toml"
    slip.write_text("[tool]\noffset_um = [0.0, 3e-6, 0.0]\n[location.C]\nEX0C_um = 4e-6\n"
                    "EA0C_urad = 5.0\n")
    code, _, err = run(["cut", GROOVES, *CUT, "--errors", slip, "--out", tmp_path / "a.ply"],
                       capsys)
    assert code == 0, err
    assert (f"note: {slip}, line 4: location.C.EX0C_um = 4e-06 is at most 4e-06 um "
            "(4e-12 m), below anything a machine shows: was it written in m, where the key "
            "asks um?") in err, err
    assert (f"note: {slip}, line 2: tool.offset_um = [0.0, 3e-06, 0.0] is at most 3e-06 um "
            "(3e-12 m)" in err), err
    assert "EA0C_urad" not in err
    code, _, err = run(["cut", GROOVES, *CUT, "--errors", ROOT / "models" / "errors" /
                        "example.toml", "--out", tmp_path / "b.ply"], capsys)
    assert code == 0 and "below anything a machine shows" not in err, err


def test_an_error_written_in_micrometres_in_a_millimetre_key_is_noted(tmp_path, capsys):
    """offset_mm = [0, -178, 0] (the README's 178 um written under mm) sets the tool 178 mm
    off: the grooves miss the block, and the cut's only word was 'removed no material (does
    it reach the stock?)', which points at the program. A note names the key and its size
    (by hand: 178 mm; gamma 0.5 rad is 28.65 deg). 9.99 mm, 9.99 deg and the example's
    values are not noted."""
    slip = tmp_path / "slip.toml"
    slip.write_text("[tool]\noffset_mm = [0.0, -178.0, 0.0]\n[workpiece]\ngamma_rad = 0.5\n")
    code, _, err = run(["cut", GROOVES, *CUT, "--errors", slip, "--out", tmp_path / "a.ply",
                        "--report", tmp_path / "a.json"], capsys)
    assert code == 0, err
    assert "the program removed no material" in err
    note = (f"{slip}, line 2: tool.offset_mm = [0.0, -178.0, 0.0] reaches 178 mm, beyond "
            "the errors of any machine (a tool or workpiece set that far off misses its part): "
            "was it written in um, where the key asks mm?")
    assert f"note: {note}" in err, err
    assert note in json.loads((tmp_path / "a.json").read_text())["notes"]
    assert (f"note: {slip}, line 4: workpiece.gamma_rad = 0.5 reaches 28.65 deg, beyond the "
            "errors of any machine (a part or an axis turned that far is another setting): was it "
            "written in mrad or urad, where the key asks rad?") in err, err
    near = tmp_path / "near.toml"
    near.write_text("[tool]\noffset_mm = [9.99, 0.0, 0.0]\n[workpiece]\ngamma_deg = 9.99\n")
    for errors in (near, ROOT / "models" / "errors" / "example.toml"):
        code, _, err = run(["cut", GROOVES, *CUT, "--errors", errors, "--allow-overtravel",
                            "--out", tmp_path / "b.ply"], capsys)
        assert code == 0 and "beyond the errors of any machine" not in err, err


def test_a_table_written_in_micrometres_of_travel_is_noted(tmp_path, capsys):
    """position_um = [-250, 0, 250] beside EXX_um, for grooving_4axis's X of -250 .. 250 mm
    (position_mm meant), spans 0.5 mm: the table steps 7.6 um within 0.5 mm of X = 0 and
    holds 4.1 um beyond, where the grooves are cut (the tool 4.1 um off along X at X = 5 mm,
    by hand from the table's last value). A note names the key, its span against the
    travel (by hand: 0.5 of 500 mm) and the unit perhaps meant, after the file and the
    key's line (2, counted by hand); the same table in mm, and
    the example's, are not noted."""
    slip = tmp_path / "slip.toml"
    slip.write_text("[component.X]\nposition_um = [-250.0, 0.0, 250.0]\n"
                    "EXX_um = [-3.5, 0.0, 4.1]\n")
    errors = machinesim.ErrorModel.from_toml(slip)
    machine = machinesim.load_machine("grooving_4axis")
    moved = machine.tool_pose(np.array([5e-3, 0.0, 0.0, 0.0]), errors)[:3, 3] - [5e-3, 0, 0]
    assert np.allclose(moved, [4.1e-6, 0.0, 0.0], rtol=0, atol=1e-15)
    code, _, err = run(["cut", GROOVES, *CUT, "--errors", slip, "--out", tmp_path / "a.ply",
                        "--report", tmp_path / "a.json"], capsys)
    assert code == 0, err
    note = (f"{slip}, line 2: component.X.position_um = [-250.0, 0.0, 250.0] spans 0.5 mm "
            "of X's "
            "500 mm travel, and its tables hold their end values beyond -0.25 mm .. 0.25 mm: "
            "was it written in mm, where the key asks um?")
    assert f"note: {note}" in err, err
    assert note in json.loads((tmp_path / "a.json").read_text())["notes"]
    meant = tmp_path / "meant.toml"
    meant.write_text("[component.X]\nposition_mm = [-250.0, 0.0, 250.0]\n"
                     "EXX_um = [-3.5, 0.0, 4.1]\n")
    for errors in (meant, ROOT / "models" / "errors" / "example.toml"):
        code, _, err = run(["cut", GROOVES, *CUT, "--errors", errors, "--out",
                            tmp_path / "b.ply"], capsys)
        assert code == 0 and "tables hold their end values" not in err, err


def test_each_holder_contact_and_each_rapid_that_cuts_is_one_warning_line(tmp_path, capsys):
    # a V tool 20 um tall (v:90:h=0.02): line 5 feeds 30 um deep right across the block, so
    # the holder touches there; lines 8 and 9 are rapids that plunge 5 um into the block and
    # run 3 mm along X through it (lines counted in the text below, % being line 1)
    program = tmp_path / "crash.nc"
    program.write_text("%\nG90 G21 G94 G54\nG00 X-0.5 Y2. Z0.1\nG00 Z-0.03\n"
                       "G01 X5.5 F500.\nG00 Z0.1\nG00 X1. Y1.\nG00 Z-0.005\nG00 X4.\n"
                       "G00 Z0.1\nM30\n%\n")
    argv = ["cut", program, "--machine", "grooving_4axis", "--tool", "v:90:h=0.02",
            "--stock", "block:5x3x1", "--quiet", "--out", tmp_path / "p.ply"]
    # by default the holder's crash is refused, naming the file and line; nothing written
    code, _, err = run(argv, capsys)
    assert code == 2
    assert err.startswith(f"machinesim: error: {program}: line 5 takes the top of the "
                          "tool's body (0.02 mm"), err
    assert "--allow-holder-contact" in err and not (tmp_path / "p.ply").exists()
    code, _, err = run([*argv, "--allow-holder-contact"], capsys)
    assert code == 0, err
    warnings = [line for line in err.splitlines() if line.startswith("warning:")]
    assert warnings == ["warning: holder touched the part at line 5",
                        "warning: rapid cut the part at line 8",
                        "warning: rapid cut the part at line 9"], err


def test_each_feed_that_drags_a_v_tool_sideways_is_one_warning_line(tmp_path, capsys):
    # line 4 feeds along X (the V tool's own direction: clean), line 5 at 45 deg in XY and
    # line 6 along Y (both drag the edge sideways); line 2's rapid starts on the block's
    # corner at z = 0 and grazes it, which is no cut and no warning
    err, data = cut_with_report(tmp_path, capsys, "G90 G21\nG0 X1. Y1. Z0.1\nG1 Z-0.01 F100.\n"
                                "X3.\nX4. Y2.\nY2.5\nG0 Z0.1\nM30\n", "v:90", "block:5x3x1")
    warnings = [line.split(" (")[0] for line in err.splitlines() if line.startswith("warning:")]
    assert warnings == ["warning: tool dragged sideways at line 5",
                        "warning: tool dragged sideways at line 6"], err
    assert data["sideways_lines"] == [5, 6]


def test_many_sideways_feeds_print_twenty_warning_lines_and_a_count(tmp_path, capsys):
    """A V tool engraving a 45-deg zigzag of 30 feeds, each dragging its edge sideways: 20
    warning lines, then one that counts the other 10 and names the report's key, which
    lists all 30 (one line each had flooded stderr with 9,873 lines on a spiral)."""
    feeds = "".join(f"X{1 + 0.1 * k:.1f} Y{1.5 + 0.1 * (k % 2):.1f}\n" for k in range(1, 31))
    text = f"G90 G21\nG0 X1. Y1.5 Z0.1\nG1 Z-0.01 F100.\n{feeds}G0 Z0.1\nM30\n"
    err, data = cut_with_report(tmp_path, capsys, text, "v:90", "block:5x3x1")
    assert data["sideways_lines"] == list(range(4, 34))
    warnings = [line for line in err.splitlines() if line.startswith("warning:")]
    assert [w.split(" (")[0] for w in warnings[:20]] == [
        f"warning: tool dragged sideways at line {n}" for n in range(4, 24)]
    assert warnings[20:] == ["warning: ... and 10 more lines as these (lines 24 to 33; the "
                             "report, --report, lists every one as sideways_lines)"]


def test_a_table_tool_with_a_radius_and_no_shape_is_noted_when_the_cut_tool_differs(
        tmp_path, capsys):
    # T1 is a 2 mm end mill by its radius (1 mm) but the table gives no shape: cut with
    # v:90 (no radius) it is noted on stderr and in the report; with ball:1.0 it agrees
    program = tmp_path / "t1.nc"
    program.write_text("G90 G21\nT1 M06\nG0 X1. Y1. Z0.1\nG1 Z-0.01 F100.\nX3.\n"
                       "G0 Z0.1\nM30\n")
    tools = tmp_path / "tools.toml"
    tools.write_text('[tool.1]\nname = "2 mm end mill"\nlength_mm = 0.0\nradius_mm = 1.0\n')
    notes = {}
    for tool in ("v:90", "ball:1.0"):
        report = tmp_path / f"{tool[0]}.json"
        code, _, err = run(["cut", program, "--machine", "grooving_4axis", "--tool", tool,
                            "--stock", "block:5x3x1", "--tools", tools, "--quiet",
                            "--out", tmp_path / "p.ply", "--report", report], capsys)
        assert code == 0, err
        notes[tool] = ([line for line in err.splitlines() if line.startswith("note:")],
                       json.loads(report.read_text(), parse_constant=no_nan)["notes"])
    expected = ("T1 (line 2): the tool table gives radius 1 mm and no shape, so the cut's "
                "own tool (no radius, VTool) cut for it")
    assert len(notes["v:90"][0]) == 1 and notes["v:90"][0][0].startswith("note: " + expected)
    assert len(notes["v:90"][1]) == 1 and notes["v:90"][1][0].startswith(expected)
    # the ball agrees with the table, and the program has no arc to split: nothing noted
    assert notes["ball:1.0"] == ([], [])


def test_a_table_tool_whose_radius_and_shape_disagree_is_noted(tmp_path, capsys):
    # T1 gives radius 2 mm beside shape ball:0.5: the ball cuts (the volume of the same
    # program cut with --tool ball:0.5 alone), and a note says the two disagree (it said
    # nothing); radius 0.5 mm agrees, and nothing is noted
    program = tmp_path / "t1.nc"
    program.write_text("G90 G21\nT1 M06\nG0 X1. Y1. Z0.1\nG1 Z-0.01 F100.\nX3.\n"
                       "G0 Z0.1\nM30\n")
    removed = {}
    for radius in (2.0, 0.5):
        tools = tmp_path / f"tools_{radius}.toml"
        tools.write_text(f'[tool.1]\nlength_mm = 0.0\nradius_mm = {radius}\n'
                         'shape = "ball:0.5"\n')
        report = tmp_path / f"r_{radius}.json"
        code, _, err = run(["cut", program, "--machine", "grooving_4axis", "--tool", "v:90",
                            "--stock", "block:5x3x1", "--tools", tools, "--quiet",
                            "--out", tmp_path / "p.ply", "--report", report], capsys)
        assert code == 0, err
        noted = [line for line in err.splitlines() if "the tool table gives radius" in line]
        removed[radius] = json.loads(report.read_text())["removed_volume_mm3"]
        if radius == 2.0:
            assert noted == ["note: T1 (line 2): the tool table gives radius 2 mm and shape "
                             "'ball:0.5' (radius 0.5 mm); the shape cut (the radius, the D "
                             "register, is not read: G41/G42 are refused)"], err
        else:
            assert noted == [], err
    code, _, err = run(["cut", program, "--machine", "grooving_4axis", "--tool", "ball:0.5",
                        "--stock", "block:5x3x1", "--quiet", "--out", tmp_path / "b.ply",
                        "--report", tmp_path / "b.json"], capsys)
    alone = json.loads((tmp_path / "b.json").read_text())["removed_volume_mm3"]
    assert removed[2.0] == removed[0.5] == pytest.approx(alone, rel=1e-12)


def test_a_cuts_warnings_and_refusals_name_the_n_word_beside_the_line(tmp_path, capsys):
    # the program of the test above with N words on lines 5 and 8 (none on line 9) and a
    # rapid to X 2 m on line 11 (N110), beyond grooving_4axis's travel: a machinist finds a
    # block by its N word, an editor by its line, so a message names both where there is an
    # N word ('line 5 (N50)'), and the line alone where there is none (line 9, as before)
    program = tmp_path / "crash.nc"
    program.write_text("%\nG90 G21 G94 G54\nG00 X-0.5 Y2. Z0.1\nG00 Z-0.03\n"
                       "N50 G01 X5.5 F500.\nG00 Z0.1\nG00 X1. Y1.\nN80 G00 Z-0.005\n"
                       "G00 X4.\nG00 Z0.1\nN110 G00 X2000.\nM30\n%\n")
    argv = ["cut", program, "--machine", "grooving_4axis", "--tool", "v:90:h=0.02",
            "--stock", "block:5x3x1", "--quiet", "--out", tmp_path / "p.ply",
            "--allow-overtravel"]
    code, _, err = run(argv, capsys)
    assert code == 2
    assert err.startswith(f"machinesim: error: {program}: line 5 (N50) takes the top of the "
                          "tool's body (0.02 mm"), err
    code, _, err = run([*argv, "--allow-holder-contact"], capsys)
    assert code == 0, err
    warnings = [line for line in err.splitlines() if line.startswith("warning:")]
    assert warnings[:3] == ["warning: holder touched the part at line 5 (N50)",
                            "warning: rapid cut the part at line 8 (N80)",
                            "warning: rapid cut the part at line 9"], err
    assert len(warnings) == 4 and " at line 11 (N110) outside its travel " in warnings[3], err
    code, _, err = run(argv[:-1], capsys)  # refused for the travel first: named alike
    assert code == 2 and " at line 11 (N110) outside its travel " in err, err


def test_location_errors_of_an_axis_the_program_keeps_at_zero_are_noted(tmp_path, capsys):
    """C's line offset and tilt (EX0C 5 um, EB0C 3 urad) on a slot cut at C = 0 throughout
    move nothing (E J E^-1 is the identity at C = 0): the part is bit for bit the one cut
    without errors, which a user injecting them to see them had no word of. Now a note names
    them; EC0C, C's zero offset, turns the part at C = 0 too and is not named. The same slot
    cut at C = 180 deg shows them (the slot 2 EX0C off) and has no note."""
    slot = "G90 G21\nG00 {c}X0.5 Y5. Z0.1\nG01 Z-0.02 F50.\nX10.5 F100.\nG00 Z0.1\nM30\n"
    errors = tmp_path / "c.toml"
    errors.write_text("[location.C]\nEX0C_um = 5.0\nEB0C_urad = 3.0\n")
    zero_offset = tmp_path / "c0.toml"
    zero_offset.write_text("[location.C]\nEC0C_urad = 10.0\n")
    parts, notes = {}, {}
    for name, c, stock, errs in (("plain", "", "block:12x10x2", None),
                                 ("idle", "", "block:12x10x2", errors),
                                 ("zero", "", "block:12x10x2", zero_offset),
                                 ("turned", "C180. ", "block:12x10x2@-11.5,-11,0", errors)):
        program = tmp_path / f"{name}.nc"
        program.write_text(slot.format(c=c))
        argv = ["cut", program, "--machine", "robonano_a0ib", "--tool", "v:90", "--stock",
                stock, "--quiet", "--out", tmp_path / f"{name}.ply", "--report",
                tmp_path / f"{name}.json"] + (["--errors", errs] if errs else [])
        code, _, err = run(argv, capsys)
        assert code == 0, err
        parts[name] = machinesim.viewer.read_ply(tmp_path / f"{name}.ply")[0]
        notes[name] = (err, json.loads((tmp_path / f"{name}.json").read_text())["notes"])
    note = (f"{errors}, line 2: location.C EX0C, EB0C move nothing in this program: C stays "
            "at 0 from its start to its end, and the offsets and tilts of its line show only "
            "as it turns; the part is the one the machine without them cuts")
    assert f"note: {note}" in notes["idle"][0] and note in notes["idle"][1]
    assert np.array_equal(parts["idle"], parts["plain"])
    for name in ("plain", "zero", "turned"):
        assert "move nothing" not in notes[name][0], (name, notes[name][0])
    # where they do move the slot, by hand: the far end's bottom corner (nominal x = 10.5 mm,
    # y = 5 mm, or -10.5, -5 mm at C = 180 deg). EC0C turns the tool by 10 urad about C's
    # line: (x - e y, y + e x), 50 nm back and 105 nm across. At C = 180 deg the slot is
    # turned about C's true line, 2 EX0C + 2 EB0C h along X (h = 24.98 mm, the slot bottom
    # above the C joint frame): 10 um + 0.14988 um
    def far_end(vertices, sign):
        slot = vertices[(vertices[:, 2] < -1e-9) & (vertices[:, 2] > -1e-4)]
        end = slot[sign * slot[:, 0] >= (sign * slot[:, 0]).max() - 1e-15]
        return end[np.argmin(end[:, 2])]

    np.testing.assert_allclose(far_end(parts["zero"], 1) - far_end(parts["plain"], 1),
                               [-50e-9, 105e-9, 0.0], atol=1e-12)
    np.testing.assert_allclose(far_end(parts["turned"], -1)[:2], [-10.5e-3 + 10.14988e-6, -5e-3],
                               atol=1e-11)
