"""File names that hold control bytes (an ESC that starts a terminal sequence, a newline, a
byte that is not UTF-8): a refusal names them escaped, on one line, never raw."""

from __future__ import annotations

import os
import sys
from argparse import Namespace

import pytest

from machinesim.cli import main
from machinesim.exceptions import InputError, ModelError, printable

CUT = ["--machine", "grooving_4axis", "--tool", "v:90", "--stock", "block:10x10x2"]


def _err(argv, capsys) -> tuple[int, str]:
    code = main([str(a) for a in argv])
    return code, capsys.readouterr().err


def test_printable_escapes_control_bytes_and_keeps_names_of_any_script():
    assert printable("dir with spaces ü/grö ves.nc") == "dir with spaces ü/grö ves.nc"
    assert printable("a\nb\x1b[31m.nc") == "a\\nb\\x1b[31m.nc"
    assert printable("one\n  two\x07", keep="\n") == "one\n  two\\x07"
    assert printable("\udcff.nc") == "\\udcff.nc"  # a byte 0xff of a name, as Python reads it


def test_a_missing_program_whose_name_holds_control_bytes_is_named_escaped(tmp_path,
                                                                           capsys):
    # 'machinesim cut $'a\nb\x1b[31m.nc' ...' wrote the ESC sequence to the terminal (red
    # text from there on) and broke the one-line message in two at the newline
    name = tmp_path / "a\nb\x1b[31m.nc"
    code, err = _err(["cut", name, *CUT, "--out", tmp_path / "p.ply"], capsys)
    assert code == 2
    assert err == (f"machinesim: error: {tmp_path}/a\\nb\\x1b[31m.nc: no such file; expected "
                   "the NC program\n")


def test_a_program_read_from_a_name_with_an_esc_is_named_escaped(tmp_path, capsys):
    name = tmp_path / "y\x1b]0;title\x07.nc"  # a title-setting sequence
    name.write_text("G90 G21\nG01 X1.\nM30\n")  # no feed: refused at line 2
    code, err = _err(["cut", name, *CUT, "--out", tmp_path / "p.ply"], capsys)
    assert code == 2
    assert err.startswith(f"machinesim: error: {tmp_path}/y\\x1b]0;title\\x07.nc, line 2, ")
    assert "key 'G01': G01 feeds with no F in force" in err
    assert "\x1b" not in err and "\x07" not in err and err.count("\n") == 1


def test_a_machine_file_message_that_quotes_its_name_is_escaped(tmp_path, capsys):
    # a URDF's messages put the path in their text, not as an InputError's source
    urdf = tmp_path / "m\x1b[2J.urdf"  # 'clear the screen'
    urdf.write_text("")
    (tmp_path / "g.nc").write_text("G90 G21\nG00 X1.\nM30\n")
    code, err = _err(["cut", tmp_path / "g.nc", "--machine", urdf, "--tool", "v:90",
                      "--stock", "block:1x1x1", "--out", tmp_path / "p.ply"], capsys)
    assert code == 2 and "\x1b" not in err and "m\\x1b[2J.urdf" in err, err


@pytest.mark.parametrize("raised", [
    InputError("expected a TOML file", source="e\x1b[31m.toml"),
    ModelError("x\x1b[31m.urdf: not readable XML"),
    OSError(28, "No space left on device", "r\x1b[31m/a.md"),
])
def test_a_scenario_names_a_file_escaped(raised, capsys):
    from machinesim.scenario_runs import scenario_status

    def report(args):
        raise raised

    assert scenario_status(report, Namespace(out=None), "s") == 2
    err = capsys.readouterr().err
    assert "\x1b" not in err and "\\x1b[31m" in err and err.count("\n") == 1, err
    assert err.startswith("s: error: ")


@pytest.mark.skipif(sys.platform != "linux", reason="a name that is not UTF-8")
def test_a_name_that_is_not_utf8_is_named_escaped(tmp_path, capsys):
    name = os.fsdecode(os.fsencode(str(tmp_path)) + b"/\xff.nc")
    code, err = _err(["cut", name, *CUT, "--out", tmp_path / "p.ply"], capsys)
    assert code == 2 and err == (f"machinesim: error: {tmp_path}/\\udcff.nc: no such file; "
                                 "expected the NC program\n")


def test_notes_and_warnings_that_quote_a_name_are_escaped(tmp_path, capsys):
    # a cut that succeeds prints its notes and warnings, which quote the files: the name's
    # ESC had reached the terminal raw there, as in the refusals
    program = tmp_path / "p\x1b[31m.nc"
    program.write_text("(nothing to run)\n")
    errors = tmp_path / "e\x1b[31m.toml"
    errors.write_text("")
    code = main([str(a) for a in ["cut", program, *CUT, "--errors", errors,
                                  "--out", tmp_path / "p.ply", "--quiet"]])
    err = capsys.readouterr().err
    assert code == 0 and "\x1b" not in err, err
    assert (f"note: {tmp_path}/e\\x1b[31m.toml sets no error (no key in any section)"
            in err), err
    assert f"warning: the program has no moves ({tmp_path}/p\\x1b[31m.nc holds no" in err, err


def test_a_viewer_warning_that_quotes_a_name_is_escaped(tmp_path, capsys):
    from machinesim.workpiece import stock_from_spec

    part = tmp_path / "part.ply"
    stock_from_spec("block:1x1x1").export_ply(part)
    report = tmp_path / "r\x1b[31m.json"
    report.write_text('{"part_file": "other.ply"}')  # another cut's report: warned about
    code = main(["view", str(part), "--report", str(report), "--html",
                 str(tmp_path / "v.html")])
    err = capsys.readouterr().err
    assert code == 0 and "\x1b" not in err, err
    assert f"warning: the report {tmp_path}/r\\x1b[31m.json describes the part file" in err


def test_a_machine_warning_line_is_escaped(capsys):
    import warnings

    from machinesim.exceptions import MachineSimWarning, warnings_as_lines

    with warnings_as_lines():
        warnings.warn("m\x1b[31m.urdf: joint 'B' limits read as degrees", MachineSimWarning,
                      stacklevel=1)
    assert capsys.readouterr().err == ("machinesim: warning: m\\x1b[31m.urdf: joint 'B' "
                                       "limits read as degrees\n")
