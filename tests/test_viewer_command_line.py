"""`machinesim view` from the command line as a new user meets it: hostile inputs in each
view mode (a part, a report folder, a machine with a program) end in a clear refusal or
note, never a traceback or a silently wrong page (docs/viewer.md)."""

from __future__ import annotations

import pytest
import viewer_helpers
from viewer_helpers import run

#: `machinesim view`'s scene recorded, not drawn (a fixture: imported by name, pytest's
#: argument of that name would read as its redefinition)
captured = viewer_helpers.captured

#: A 10 um deep V groove 2 mm along X, as test_errors_hostile cuts it.
GROOVE = "G90 G21\nG00 X0 Y0 Z1.\nG01 Z-0.01 F100.\nG01 X2.\nG00 Z1.\nM30\n"


def test_an_error_file_gets_the_unit_slip_notes_cut_gives(tmp_path, captured, capsys):
    # c_2 = 1 um/mm**2 reaches 1 * 250**2 um = 62.5 mm at the ends of grooving_4axis's X
    # (-250 .. 250 mm), by hand: machinesim cut notes it (test_errors_hostile); view printed
    # no note and drew the page
    program = tmp_path / "p.nc"
    program.write_text(GROOVE)
    errors = tmp_path / "poly.toml"
    errors.write_text("[component.X]\nEXX_poly_um_mm = [0.0, 0.0, 1.0]\n")
    assert run(["grooving_4axis", "--program", str(program), "--tool", "v:90", "--errors",
                str(errors), "--html", str(tmp_path / "p.html")]) == 0
    err = capsys.readouterr().err
    assert (f"note: {errors}, line 2: component.X.EXX_poly_um_mm = [0.0, 0.0, 1.0] reaches "
            "62.5 mm at X = -250 mm within X's travel, beyond the errors of any machine: were "
            "its coefficients written for other units than its key asks?") in err, err
    assert captured["errors"].written


def test_a_program_selecting_two_tools_without_a_table_gets_cuts_note(tmp_path, captured,
                                                                       capsys):
    # T1 M6 and T2 M6 read without --tools: --tool cuts every move, which machinesim cut
    # notes (docs/nc.md, 'Tool table'); view animated it with no word
    program = tmp_path / "two.nc"
    program.write_text("G90 G21\nT1 M6\nG00 X0 Y0 Z1.\nG01 Z-0.01 F100.\nG01 X2.\nT2 M6\n"
                       "G00 Z1.\nM30\n")
    assert run(["grooving_4axis", "--program", str(program), "--tool", "v:90", "--html",
                str(tmp_path / "two.html")]) == 0
    err = capsys.readouterr().err
    assert ("note: the program selects 2 tools (T1 at line 2, T2 at line 6) but was read "
            "without a tool table, so the cut's own tool (VTool) cut every move") in err, err
    # one tool selected: no note
    program.write_text("G90 G21\nT1 M6\nG00 X0 Y0 Z1.\nG01 Z-0.01 F100.\nG01 X2.\nM30\n")
    assert run(["grooving_4axis", "--program", str(program), "--tool", "v:90", "--html",
                str(tmp_path / "one.html")]) == 0
    assert "tools" not in capsys.readouterr().err


def test_a_table_radius_the_tool_has_not_gets_cuts_note(tmp_path, captured, capsys):
    # tool 1: radius 2 mm and no shape, beside --tool flat:1 (radius 1 mm): flat:1 cuts for
    # it, which machinesim cut notes; view animated it with no word
    program = tmp_path / "t1.nc"
    program.write_text("G90 G21\nT1 M6\nG43 H1\nG00 X0 Y0 Z1.\nG01 Z-0.01 F100.\nG01 X2.\n"
                       "G00 Z1.\nM30\n")
    tools = tmp_path / "tools.toml"
    tools.write_text("[tool.1]\nlength_mm = 0.0\nradius_mm = 2.0\n")
    assert run(["grooving_4axis", "--program", str(program), "--tools", str(tools), "--tool",
                "flat:1", "--html", str(tmp_path / "t1.html")]) == 0
    err = capsys.readouterr().err
    assert ("note: T1 (line 2): the tool table gives radius 2 mm and no shape, so the cut's "
            "own tool (radius 1 mm, FlatEndMill) cut for it") in err, err


@pytest.mark.parametrize("text", ["", "[component.X]\n"])
def test_an_error_file_setting_no_error_gets_cuts_note(tmp_path, captured, capsys, text):
    # an empty file, or a section without keys: machinesim cut notes that it sets no error;
    # view said nothing on the command line
    program = tmp_path / "p.nc"
    program.write_text(GROOVE)
    errors = tmp_path / "none.toml"
    errors.write_text(text)
    assert run(["grooving_4axis", "--program", str(program), "--errors", str(errors),
                "--html", str(tmp_path / "p.html")]) == 0
    err = capsys.readouterr().err
    assert (f"note: {errors} sets no error (no key in any section): viewed on the machine as "
            "built, every error zero") in err, err
    assert not captured["errors"].written


def test_location_errors_the_program_never_shows_get_cuts_note(tmp_path, captured, capsys):
    # the groove never turns C: EX0C moves nothing there, which machinesim cut notes; C's
    # zero offset EC0C turns the part at C = 0 and is not named
    program = tmp_path / "p.nc"
    program.write_text(GROOVE)
    errors = tmp_path / "c.toml"
    errors.write_text("[location.C]\nEC0C_urad = 1.0\nEX0C_um = 2.0\n")
    assert run(["grooving_4axis", "--program", str(program), "--errors", str(errors),
                "--html", str(tmp_path / "p.html")]) == 0
    err = capsys.readouterr().err
    assert (f"note: {errors}, line 3: location.C EX0C moves nothing in this program: C stays "
            "at 0 from its start to its end") in err, err
    assert "EC0C" not in err, err


def test_an_error_file_gets_the_notes_a_cut_report_holds_once_each(tmp_path, captured,
                                                                   capsys):
    # one list: what machinesim.cut's report ends with on the same file and program (cut from
    # machinesim cut's start, the machine's home), each printed once, in its order
    import machinesim
    from machinesim.errors import ErrorModel
    from machinesim.nc import parse_program

    program = tmp_path / "p.nc"
    program.write_text(GROOVE)
    errors = tmp_path / "c.toml"
    errors.write_text("[location.C]\nEX0C_um = 4e-6\nEB0C_urad = 3.0\n")
    machine = machinesim.load_machine("grooving_4axis")
    _, report = machinesim.cut(parse_program(GROOVE), machine, errors=ErrorModel.from_toml(
        errors), start=machine.home)
    cuts = [note for note in report.notes if note.startswith(str(errors))]
    assert len(cuts) == 2, report.notes  # the unit slip, EX0C and EB0C idle
    assert run(["grooving_4axis", "--program", str(program), "--tool", "v:90", "--errors",
                str(errors), "--html", str(tmp_path / "p.html")]) == 0
    err = capsys.readouterr().err
    noted = [line.removeprefix("note: ") for line in err.splitlines()
             if line.startswith(f"note: {errors}")]
    assert noted == cuts, err


@pytest.mark.parametrize("port", ["7005", "6000"])
def test_a_port_beside_html_is_refused(tmp_path, port):
    # an --html page has no server: the port was taken and ignored (exit 0), as --tool
    # without --program had been before it was refused
    from machinesim.exceptions import InputError

    page = tmp_path / "m.html"
    with pytest.raises(InputError, match=f"--port {port} is the live server's, and --html "
                                         "writes a page that needs none"):
        run(["robonano_a0ib", "--html", str(page), "--port", port])
    assert not page.exists()


def test_a_turning_program_is_refused_before_any_stage_is_cut(tmp_path, monkeypatch):
    # C turns 0 to 360 deg while Z feeds on sts_lathe: refused as cut refuses it, but only
    # after the stages had been cut (384 s for this program) by the part without errors
    import machinesim.viewer.machine as viewer_machine
    from machinesim.exceptions import NCProgramError

    def no_stages(*args, **kwargs):
        raise AssertionError("a stage was cut before the refusal")

    monkeypatch.setattr(viewer_machine, "_stages", no_stages)
    program = tmp_path / "turn.nc"
    program.write_text("G90 G21\nG00 X1. Z1.\nG01 Z0. F10.\nG01 C360. Z-0.01\nM30\n")
    with pytest.raises(NCProgramError, match="line 4.*feeds while it turns the work spindle C "
                                             "of sts_lathe \\(0 to 360 deg\\)"):
        run(["sts_lathe", "--program", str(program), "--html", str(tmp_path / "t.html")])
