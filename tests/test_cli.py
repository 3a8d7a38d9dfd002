"""The command line: clear one-line errors, never a traceback, outputs written together or not
at all, reports without NaN, and the options that reach the NC reader and the cutter."""

from __future__ import annotations

import inspect
import json
import math
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from cli_helpers import CUT, assert_clean_failure, run

import machinesim
import machinesim.cutting
import machinesim.nc
from machinesim.cli import main

ROOT = Path(__file__).resolve().parents[1]
GROOVES = ROOT / "models" / "examples" / "grooves.nc"
GROOVING = ROOT / "models" / "grooving_4axis.urdf"
#: grooves.nc: four 90-deg V grooves 20 um deep right across the 10 mm block: each removes
#: a triangle of depth d and width 2 d (area d^2) over 10 mm.
GROOVES_MM3 = 4 * 0.020**2 * 10.0


def entry_point() -> list[str]:
    """The installed ``machinesim`` script (what users run), else ``python -m``."""
    script = Path(sys.executable).parent / "machinesim"
    return [str(script)] if script.exists() else [sys.executable, "-m", "machinesim.cli"]


def no_nan(constant: str):
    raise AssertionError(f"{constant} in a JSON report")


def test_machines_lists_each_machine_with_its_axes(capsys):
    assert main(["machines"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert [line.split()[:2] for line in out] == [
        ["grooving_4axis", "XYZC"], ["planer_4axis", "XYZA"], ["robonano_a0ib", "XYZBC"],
        ["robonano_ui", "XYZABC"], ["sts_lathe", "XZC"]]
    assert "A -45..45 deg" in out[1]


def test_help_documents_every_cut_option_with_an_example(capsys):
    with pytest.raises(SystemExit):
        main(["cut", "--help"])
    out = capsys.readouterr().out
    for option in ("--machine", "--tool", "--stock", "--errors", "--out", "--report", "--roi",
                   "--tools", "--integer-input", "--allow-overtravel"):
        assert option in out
    assert "e.g. block:10x10x2" in out and "e.g. v:90" in out
    assert ":d=" in out and "flat:0.5:h=3:d=4" in " ".join(out.split())  # docs/cli.md's --tool
    assert "millimetres" in out and "metres" in out


def test_cut_help_names_every_stock_form_and_each_example_builds(capsys):
    # the help named block and cylinder only, while --stock reads spheres and crown too
    # (docs/cli.md); each e.g. of the help must be a stock the command builds
    with pytest.raises(SystemExit):
        main(["cut", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    stock = text[text.index("--stock STOCK stock spec"):text.index("--errors ERRORS injected")]
    for form in ("block:LxWxH", "cylinder:RxH", "spheres:LxWxH:R[:dimples]",
                 "crown[:OVERSIZE]"):
        assert form in stock, form
    from machinesim.workpiece import stock_from_spec
    examples = re.findall(r"e\.g\. ([a-z]+:[0-9x.:]+(?:@[-0-9.]+,[-0-9.]+,[-0-9.]+)?)", stock)
    assert len(examples) == 4, examples
    for example in examples:
        assert stock_from_spec(example).volume > 0.0, example


# --------------------------------------------------------------------- a good cut


def test_a_cut_writes_part_and_report_with_units_and_no_nan(tmp_path, capsys):
    out, report = tmp_path / "part.stl", tmp_path / "report.json"
    code, stdout, err = run(["cut", GROOVES, *CUT, "--out", out, "--report", report], capsys)
    assert code == 0, err
    data = json.loads(report.read_text(), parse_constant=no_nan)
    assert data["removed_volume_mm3"] == pytest.approx(GROOVES_MM3, rel=1e-9)
    assert data["part_file"] == str(out) and data["part_unit"] == "mm"
    assert f"wrote {out} (binary STL, millimetres" in stdout
    assert sorted(p.name for p in tmp_path.iterdir()) == ["part.stl", "report.json"]


@pytest.mark.parametrize("closed", [(2,), (1, 2)], ids=["stderr", "stdout and stderr"])
def test_a_cut_started_with_closed_output_streams_writes_its_files(tmp_path, closed):
    # `machinesim cut ... 2>&-` (a daemon's or a cron line's closed descriptors): Python sets
    # sys.stderr to None, and the cut ended in "internal error: AttributeError: 'NoneType'
    # object has no attribute 'isatty'", exit 1, nothing written
    out, report = tmp_path / "part.ply", tmp_path / "report.json"
    done = subprocess.run(
        [*entry_point(), "cut", str(GROOVES), *CUT[:-1], "--out", str(out), "--report",
         str(report)], preexec_fn=lambda: [os.close(fd) for fd in closed], timeout=300)
    assert done.returncode == 0 and out.is_file()
    assert json.loads(report.read_text())["removed_volume_mm3"] == pytest.approx(
        GROOVES_MM3, rel=1e-9)


def test_integer_input_increment_reads_axis_words_in_nanometres(tmp_path, capsys):
    program = tmp_path / "increment.nc"
    program.write_text(GROOVES.read_text().replace("Z-0.02", "Z-20000"))  # 20000 nm = 20 um
    report = tmp_path / "report.json"
    code, _, err = run(["cut", program, *CUT, "--integer-input", "increment",
                        "--out", tmp_path / "part.ply", "--report", report], capsys)
    assert code == 0, err
    data = json.loads(report.read_text(), parse_constant=no_nan)
    assert data["removed_volume_mm3"] == pytest.approx(GROOVES_MM3, rel=1e-9)
    # FANUC's IS-C reads it 100 times deeper (0.0001 mm): 2 mm, and says which words
    code, _, err = run(["cut", program, *CUT, "--integer-input", "is-c",
                        "--out", tmp_path / "deep.ply", "--report", report], capsys)
    nc = json.loads(report.read_text())["nc"]
    assert nc["integer_input"] == "is-c" and nc["integer_words"][0]["word"] == "Z"
    assert "note: numbers without a decimal point" not in err  # the rule was chosen
    # read with the default rule, the 20000 is 20 m: the note names the word and its line
    code, _, err = run(["cut", program, *CUT, "--out", tmp_path / "deep.ply",
                        "--allow-overtravel"], capsys)
    line = nc["integer_words"][0]["line"]
    assert (f"note: numbers without a decimal point (Z at line {line}) were read in mm"
            in err)


def test_an_overtravel_refusal_says_how_numbers_without_a_point_were_read(tmp_path, capsys):
    """A program posted for FANUC IS-B (X11000 is 11 mm) read in mm leaves the travel: the
    refusal names the words read without a point and the rule to give, since the notes of a
    cut that is refused are never printed. Read as IS-B it cuts the slot: 2 mm wide (flat
    1 mm radius), 0.1 mm deep, across the 10 mm block, 2 mm^3."""
    program = tmp_path / "isb.nc"
    program.write_text("%\nO0002\nG90 G21 G17\nG00 X-1000 Y5000 Z1000\nG01 Z-100 F100\n"
                       "X11000\nG00 Z1000\nM30\n%\n")
    mill = ["--machine", ROOT / "models" / "examples" / "mill3.urdf", "--tool", "flat:1.0",
            "--stock", "block:10x10x2", "--quiet"]
    code, _, err = run(["cut", program, *mill, "--out", tmp_path / "p.ply"], capsys)
    assert_clean_failure(code, err, "axis X = 11000.000000 mm at line 6 outside its travel",
                         "numbers without a decimal point (X at line 4, Y at line 4, Z at "
                         "line 4) were read in mm", "--integer-input is-b")
    report = tmp_path / "r.json"
    code, _, err = run(["cut", program, *mill, "--integer-input", "is-b", "--out",
                        tmp_path / "p.ply", "--report", report], capsys)
    assert code == 0, err
    # the flat's polygon lies within 1 um inside its circle: the slot at most 1e-3 narrower
    assert json.loads(report.read_text())["removed_volume_mm3"] == pytest.approx(2.0, rel=1e-3)


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


# ------------------------------------------------------------ refusals: one line, no files


def test_rotary_limits_that_read_as_degrees_are_one_warning_line(tmp_path, capsys):
    # Python's own form named machinesim's source line and printed it: two lines, neither
    # the user's
    urdf = tmp_path / "mill.urdf"
    urdf.write_text(GROOVING.read_text().replace(
        'lower="-6.283185307179586" upper="6.283185307179586"', 'lower="-100" upper="100"'))
    code, _, err = run(["cut", GROOVES, "--machine", urdf, "--tool", "bogus",
                        "--stock", "block:10x10x2", "--out", tmp_path / "part.ply"], capsys)
    warning, error = err.strip().splitlines()
    assert warning.startswith(f"machinesim: warning: {urdf}, line ") and \
        "joint 'C': <limit lower=-100.0 upper=100.0> is read in rad" in warning
    assert code == 2 and error.startswith("machinesim: error: --tool 'bogus'")


def test_a_missing_or_folder_program_is_one_line_naming_it(tmp_path, capsys):
    out = tmp_path / "part.ply"
    code, _, err = run(["cut", tmp_path / "nope.nc", *CUT, "--out", out], capsys)
    assert_clean_failure(code, err, "nope.nc: no such file; expected the NC program")
    code, _, err = run(["cut", tmp_path, *CUT, "--out", out], capsys)
    assert_clean_failure(code, err, f"{tmp_path}: is a folder; expected the NC program file")
    assert list(tmp_path.iterdir()) == []


def test_an_empty_file_or_machine_name_is_refused_as_empty_not_as_the_current_folder(
        tmp_path, capsys):
    # Path('') is '.': `cut '' ...` said "'.': is a folder; expected the NC program file",
    # quoting a '.' never typed, `view ''` showed the current folder, and a scenario's
    # --out '' wrote its report over the current folder (an unset shell variable each)
    from machinesim.scenario_runs import scenario_arguments

    out = ["--out", tmp_path / "part.ply"]
    cases = [
        (["cut", "", *CUT, *out], "cut", "program", "a file name"),
        # (CUT without its own --machine: an option given twice is refused as such)
        (["cut", GROOVES, *CUT[2:], *out, "--machine", ""], "cut", "--machine",
         "a name or a path"),
        (["cut", GROOVES, *CUT, *out, "--errors", ""], "cut", "--errors", "a file name"),
        (["cut", GROOVES, *CUT, *out, "--servo", ""], "cut", "--servo", "a file name"),
        (["cut", GROOVES, *CUT, *out, "--tools", ""], "cut", "--tools", "a file name"),
        (["view", "", "--html", tmp_path / "v.html"], "view", "target", "a name or a path"),
        (["view", "part.ply", "--report", ""], "view", "--report", "a file name"),
        (["view", "part.ply", "--nominal", ""], "view", "--nominal", "a file name"),
        (["view", "grooving_4axis", "--program", ""], "view", "--program", "a file name"),
        (["view", "grooving_4axis", "--errors", ""], "view", "--errors", "a file name"),
        (["view", "grooving_4axis", "--program", GROOVES, "--tools", ""], "view", "--tools",
         "a file name"),
    ]
    for argv, command, option, expected in cases:
        code, _, err = run(argv, capsys)
        assert code == 2, (argv, err)
        assert err.splitlines()[-1] == (f"machinesim {command}: error: argument {option}: "
                                        f"'' is empty; expected {expected}"), (argv, err)
        assert "'.'" not in err and "Traceback" not in err, err
    for option, expected in (("--out", "a folder name"), ("--errors", "a file name")):
        with pytest.raises(SystemExit) as stop:
            scenario_arguments("a scenario", "reports/x").parse_args([option, ""])
        assert stop.value.code == 2
        assert capsys.readouterr().err.splitlines()[-1].endswith(
            f"error: argument {option}: '' is empty; expected {expected}")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("bad", ["out", "report"])
def test_an_unwritable_output_leaves_neither_file(tmp_path, capsys, bad):
    paths = {"out": tmp_path / "part.ply", "report": tmp_path / "report.json"}
    paths[bad] = tmp_path / "missing folder" / paths[bad].name
    code, _, err = run(["cut", GROOVES, *CUT, "--out", paths["out"], "--report", paths["report"]],
                       capsys)
    assert_clean_failure(code, err, f"{paths[bad]}: cannot write the", "does not exist")
    assert list(tmp_path.iterdir()) == []


def test_a_failure_while_writing_leaves_neither_file(tmp_path, capsys, monkeypatch):
    """Both destinations pass the checks, then the disk fails on the second rename."""
    import machinesim._io as io

    out, report = tmp_path / "part.ply", tmp_path / "report.json"
    real = os.replace

    def second_fails(src, dst):
        if Path(dst) == report:
            raise OSError(28, "No space left on device")
        real(src, dst)

    monkeypatch.setattr(io.os, "replace", second_fails)
    code, _, err = run(["cut", GROOVES, *CUT, "--out", out, "--report", report], capsys)
    assert_clean_failure(code, err, "report.json: cannot write: No space left on device")
    assert list(tmp_path.iterdir()) == []


def test_outputs_naming_one_file_or_an_input_are_refused(tmp_path, capsys):
    out = tmp_path / "part.ply"
    code, _, err = run(["cut", GROOVES, *CUT, "--out", out, "--report", out], capsys)
    assert_clean_failure(code, err, "--out and --report name the same file")
    program = tmp_path / "grooves.nc"
    program.write_bytes(GROOVES.read_bytes())
    code, _, err = run(["cut", program, *CUT, "--out", out, "--report", program], capsys)
    assert_clean_failure(code, err, "grooves.nc: the report (--report) would overwrite an input")
    assert program.read_bytes() == GROOVES.read_bytes()
    program.unlink()
    code, _, err = run(["cut", GROOVES, *CUT, "--out", tmp_path / "part.obj"], capsys)
    assert_clean_failure(code, err, "part.obj: expected a file name ending in .ply, .stl or .glb")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("roi", ["nan,1,0,1", "0,inf,0,1", "1,0,0,1", "0,1,0", "a,b,c,d", ""])
def test_a_bad_roi_is_refused_before_cutting(tmp_path, capsys, roi):
    code, _, err = run(["cut", GROOVES, *CUT, "--out", tmp_path / "p.ply", f"--roi={roi}"],
                       capsys)
    assert_clean_failure(code, err, f"--roi {roi!r}: expected X0,X1,Y0,Y1 in mm")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("chord_nm", ["1e30", "1e-6", "0.01", "0.999", "0", "nan"])
def test_a_chord_tolerance_outside_1_nm_to_1_m_is_refused(tmp_path, capsys, chord_nm):
    # --chord-nm 1e30 was taken: an arc's chords allowed 1e21 m off it, exit 0; 1e-6 and
    # 0.01 too: a 3 mm half circle with ball:0.5 was 1.36 million and 13,607 sweeps (1,364
    # in 40 s at 1 nm), and ran on without a word
    code, _, err = run(["cut", GROOVES, *CUT, "--out", tmp_path / "p.ply", "--chord-nm",
                        chord_nm], capsys)
    assert code == 2
    assert err == (f"machinesim: error: --chord-nm {float(chord_nm)!r}: expected a length in "
                   "nm from 1, the axes' resolution (no machine follows a path more finely, "
                   "and the chords grow in number as 1/sqrt(NM): ten times 1 nm's at 0.01), "
                   "to 1e+09 (1 m, more than any machine's travel)\n")
    assert list(tmp_path.iterdir()) == []


def test_the_chord_tolerances_bounds_are_cut(tmp_path, capsys):
    code, _, err = run(["cut", GROOVES, *CUT, "--out", tmp_path / "p.ply", "--chord-nm",
                        "1e9", "--quiet"], capsys)
    assert code == 0, err
    # 1 nm on a half circle of R = 0.05 mm, 10 um deep with a 0.05 mm ball: chords of angle
    # 2 acos(1 - 1 nm / R), so ceil(pi / that) of them (249), plus the plunge and the
    # retract out of the groove
    program = tmp_path / "half.nc"
    program.write_text("G90 G21 G17\nG00 X4.95 Y5. Z0.1\nG01 Z-0.01 F100.\n"
                       "G02 X5.05 Y5. I0.05 J0.\nG00 Z1.\nM30\n")
    chords = math.ceil(math.pi / (2.0 * math.acos(1.0 - 1e-9 / 0.05e-3)))
    report = tmp_path / "r.json"
    code, _, err = run(["cut", program, "--machine", "grooving_4axis", "--tool", "ball:0.05",
                        "--stock", "block:10x10x2", "--quiet", "--out", tmp_path / "p.ply",
                        "--report", report, "--chord-nm", "1"], capsys)
    assert code == 0, err
    summary = json.loads(report.read_text())
    assert summary["path_chord_tolerance_nm"] == 1.0
    assert summary["sweeps_count"] == chords + 2 == 251


def test_a_reversed_roi_is_named_once(tmp_path, capsys):
    # the line read "machinesim: error: key '--roi': --roi '5,4,1,3': expected ...", the
    # option named twice
    code, _, err = run(["cut", GROOVES, *CUT, "--out", tmp_path / "p.ply", "--roi", "5,4,1,3"],
                       capsys)
    assert code == 2
    assert err == ("machinesim: error: --roi '5,4,1,3': expected X0,X1,Y0,Y1 in mm, four finite "
                   "numbers with X0 < X1 and Y0 < Y1, e.g. 0,1,0,1\n")
    assert list(tmp_path.iterdir()) == []


def test_roi_windows_that_miss_the_stock_are_refused_before_cutting(tmp_path, capsys):
    # the stock clipped to them is nothing: an empty part was written, exit 0, with "does it
    # reach the stock?"; windows that only touch its side (x 10 .. 11) hold none of it
    out = tmp_path / "p.ply"
    code, _, err = run(["cut", GROOVES, *CUT, "--out", out, "--roi", "100,200,100,200",
                        "--roi", "10,11,0,10"], capsys)
    assert_clean_failure(code, err)
    assert err == ("machinesim: error: --roi 100,200,100,200 --roi 10,11,0,10: no window "
                   "overlaps the stock, which spans x 0 .. 10 mm and y 0 .. 10 mm (workpiece "
                   "frame): the part, the stock within the windows, would be empty; expected a "
                   "window over the stock\n")
    assert list(tmp_path.iterdir()) == []
    # a window over a corner no groove crosses: cut, and the warning names the windows
    code, _, err = run(["cut", GROOVES, *CUT, "--out", out, "--roi", "0,1,0,1"], capsys)
    assert code == 0, err
    assert err == ("warning: the program removed no material (does it reach the stock in the "
                   "--roi windows?)\n")


def test_an_error_model_that_does_not_fit_the_machine_names_its_file_first(tmp_path, capsys):
    # a table of X errors over -1000 .. 1000 mm: grooving_4axis's X travels -250 .. 250 mm
    errors = tmp_path / "wide.toml"
    errors.write_text("[component.X]\nposition_mm = [-1000, 0, 1000]\nEXX_um = [0, 1, 0]\n")
    code, _, err = run(["cut", GROOVES, *CUT, "--errors", errors, "--out",
                        tmp_path / "p.ply"], capsys)
    assert code == 2
    assert err.startswith(f"machinesim: error: {errors}, line 3, key 'component.X.EXX_um': table "
                          "positions -1000 .. 1000 mm lie outside the travel of axis X, "
                          "-250 .. 250 mm (machine grooving_4axis, "), err
    assert len(err.splitlines()) == 1 and list(tmp_path.iterdir()) == [errors]


def test_a_machine_with_zero_rapid_rate_is_refused_not_a_nan_report(tmp_path, capsys):
    urdf = tmp_path / "slow.urdf"
    urdf.write_text(GROOVING.read_text().replace('velocity="0.025"', 'velocity="0"', 1))
    code, _, err = run(["cut", GROOVES, "--machine", urdf, "--tool", "v:90", "--stock",
                        "block:10x10x2", "--out", tmp_path / "p.ply", "--report",
                        tmp_path / "r.json"], capsys)
    # grooving_4axis.urdf's joint Y has its <limit> on line 41 (named at its own line)
    assert_clean_failure(code, err, "slow.urdf, line 41: joint 'Y'", "velocity=0.0",
                         "rapid rate > 0")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["slow.urdf"]


def test_a_report_that_would_hold_nan_is_refused_and_nothing_is_written(tmp_path, capsys,
                                                                       monkeypatch):
    real = machinesim.cutting.cut

    def nan_time(*args, **kwargs):
        from dataclasses import replace

        part, report = real(*args, **kwargs)
        return part, replace(report, machining_time_s=float("nan"))

    monkeypatch.setattr(machinesim.cutting, "cut", nan_time)
    out, report = tmp_path / "part.ply", tmp_path / "report.json"
    code, _, err = run(["cut", GROOVES, *CUT, "--out", out, "--report", report], capsys)
    assert_clean_failure(code, err, "machining_time_s = nan", "nothing was written")
    assert list(tmp_path.iterdir()) == []


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


def test_ctrl_c_during_the_cut_exits_130_and_writes_nothing(tmp_path, capsys, monkeypatch):
    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(machinesim.cutting, "cut", interrupted)
    code, _, err = run(["cut", GROOVES, *CUT, "--out", tmp_path / "part.ply"], capsys)
    assert_clean_failure(code, err, "interrupted; nothing was written", status=130)
    assert list(tmp_path.iterdir()) == []


def test_a_stop_whose_terminal_is_gone_still_exits_with_its_status(tmp_path, monkeypatch):
    """SIGHUP as the terminal closes: the last line cannot be written (EIO, as a pty whose
    other end closed answers). The status is still 129 and nothing is written. The failed
    write had raised out of the handler: status 1, after a traceback to the same dead
    terminal (seen with the cut's stderr on a pty closed before SIGHUP)."""
    import errno

    from machinesim._interrupts import HungUp

    class Closed:
        def write(self, text):
            raise OSError(errno.EIO, "Input/output error")

        def flush(self):
            raise OSError(errno.EIO, "Input/output error")

    def hung_up(*args, **kwargs):
        raise HungUp

    monkeypatch.setattr(machinesim.cutting, "cut", hung_up)
    monkeypatch.setattr(sys, "stderr", Closed())
    assert main([str(a) for a in ["cut", GROOVES, *CUT, "--out", tmp_path / "part.ply"]]) == 129
    assert list(tmp_path.iterdir()) == []


def _cut_with_a_hook(tmp_path, hook: str, terminal: dict) -> subprocess.CompletedProcess:
    """``machinesim cut`` of the grooves to tmp_path's part.ply and report.json (each holding
    "old" before), in a process that first runs ``hook`` (Python, which may wrap ``os`` calls
    to send the process a signal at a known point), with a terminal's signal dispositions."""
    for name in ("part.ply", "report.json"):
        (tmp_path / name).write_text("old")
    code = f"{hook}\nimport sys\nfrom machinesim.cli import main\nsys.exit(main())\n"
    return subprocess.run([sys.executable, "-c", code, "cut", str(GROOVES), *CUT,
                           "--out", str(tmp_path / "part.ply"),
                           "--report", str(tmp_path / "report.json")],
                          capture_output=True, text=True, cwd=ROOT, timeout=120,
                          env={**os.environ, "PYTHONPATH": str(ROOT)}, **terminal)


def test_a_closed_terminal_while_the_part_is_written_leaves_the_old_files_and_no_temporary(
        tmp_path, as_in_a_terminal):
    """SIGHUP (the terminal closed, an ssh session dropped) once the part's bytes are in its
    temporary file: handled as SIGTERM is, status 129 and one line; the old part and report
    stay and no temporary file is left. (SIGHUP's default action ended the process there:
    status -1, and .part.ply.*.tmp stayed beside the part for good.)"""
    hook = ("import os, signal, time\nreal = os.fsync\n"
            "def fsync(fd):\n    real(fd)\n    os.kill(os.getpid(), signal.SIGHUP)\n"
            "    time.sleep(5)\nos.fsync = fsync")
    result = _cut_with_a_hook(tmp_path, hook, as_in_a_terminal)
    assert_clean_failure(result.returncode, result.stderr, "machinesim: hung up; nothing was "
                         "written", status=129)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["part.ply", "report.json"]
    assert {p.read_text() for p in tmp_path.iterdir()} == {"old"}


def test_a_ctrl_c_as_the_outputs_are_renamed_in_says_they_were_written(tmp_path,
                                                                        as_in_a_terminal):
    """SIGINT just as the report is renamed over the old one: the renames finish (the stop is
    held back until then: part and report are this run's, whole), and the line says so. It
    said 'interrupted; nothing was written' (status 130) beside this run's part and report,
    the old ones gone."""
    hook = ("import os, signal, time\nreal = os.replace\n"
            "def replace(src, dst):\n    real(src, dst)\n"
            "    if str(dst).endswith('report.json'):\n"
            "        os.kill(os.getpid(), signal.SIGINT)\n        time.sleep(0.5)\n"
            "os.replace = replace")
    result = _cut_with_a_hook(tmp_path, hook, as_in_a_terminal)
    part, report = tmp_path / "part.ply", tmp_path / "report.json"
    assert_clean_failure(result.returncode, result.stderr, status=130)
    assert result.stderr == (f"machinesim: interrupted; {part} and {report} were written "
                             "whole before it; nothing else was written\n")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["part.ply", "report.json"]
    data = json.loads(report.read_text())
    assert data["part_file"] == str(part)
    assert data["removed_volume_mm3"] == pytest.approx(GROOVES_MM3, rel=1e-9)
    from machinesim.viewer.meshes import read_ply

    assert len(read_ply(part)[1]) > 0  # a whole PLY (a torn one is refused)


def test_a_binary_or_malformed_view_report_is_one_line(tmp_path, capsys):
    part = tmp_path / "part.ply"
    assert run(["cut", GROOVES, *CUT, "--out", part], capsys)[0] == 0
    cases = {b"\x00\xff\xfe binary": "not UTF-8 text", b'{"a": ': "not valid JSON",
             b"[1, 2]": "expected a JSON object (a cut report), got a list",
             b'{"a": NaN}': "NaN is not a finite number"}
    for content, words in cases.items():
        report = tmp_path / "report.json"
        report.write_bytes(content)
        code, _, err = run(["view", part, "--report", report, "--html", tmp_path / "v.html"],
                           capsys)
        assert_clean_failure(code, err, f"{report}", words)
    assert not (tmp_path / "v.html").exists()


def test_view_refuses_an_unwritable_page_before_building_it(tmp_path, capsys):
    code, _, err = run(["view", "grooving_4axis", "--html", tmp_path / "no" / "v.html"], capsys)
    assert_clean_failure(code, err, "v.html: cannot write the page (--html)", "does not exist")


# ------------------------------------------------------ options reaching other modules


def test_tools_and_integer_input_reach_the_nc_reader(tmp_path, capsys, monkeypatch):
    seen = {}
    real = machinesim.nc.read_program

    def reader(path, **kwargs):
        seen.update(kwargs)
        return real(path, integer_input=kwargs.get("integer_input", "calculator"))

    monkeypatch.setattr(machinesim.nc, "read_program", reader)
    table = tmp_path / "tools.toml"
    table.write_text("")
    code, _, err = run(["cut", GROOVES, *CUT, "--out", tmp_path / "p.ply", "--tools", table,
                        "--integer-input", "calculator"], capsys)
    assert code == 0, err
    # and G28's reference is the machine's home: Z at the top of its travel (100 mm)
    # arcs as fine as the V tool (drawn exactly): the axes' 1 nm
    assert seen.pop("tools").source == str(table)  # read once, handed over as a table
    assert seen == {"integer_input": "calculator",
                    "reference": {"X": 0.0, "Y": 0.0, "Z": 0.1, "C": 0.0},
                    "chord_tolerance": 1e-9}
    code, _, err = run(["cut", GROOVES, *CUT, "--out", tmp_path / "p.ply", "--tools",
                        tmp_path / "none.toml"], capsys)
    assert_clean_failure(code, err, "none.toml: no such file; expected the tool table (--tools)")


def test_each_tool_cuts_at_its_length_and_the_summary_says_what_it_removed(tmp_path, capsys):
    # Two 90-deg V grooves 10 um deep and 10 mm long (each d^2 x L = 1e-3 mm^3): T1 the
    # model's tool, T2 2.5 mm longer with G43 H2 lifting Z by as much, so both cut at the
    # programmed depth; the change to T2 is made 5 mm up, clear of the part.
    table = tmp_path / "tools.toml"
    table.write_text('[tool.1]\nlength_mm = 0.0\n'   # no shape: the cut's --tool
                     '[tool.2]\nlength_mm = 2.5\nshape = "v:90"\n')
    program = tmp_path / "two_tools.nc"
    program.write_text("T1 M06\nG00 X0 Y1. Z1.\nG01 Z-0.01 F100.\nX10.\nG00 Z5.\n"
                       "T2 M06\nG43 H2 Z1.\nG00 X0 Y3.\nG01 Z-0.01\nX10.\nG00 Z5.\nM30\n")
    report = tmp_path / "r.json"
    code, out, err = run(["cut", program, "--machine", "grooving_4axis", "--tool", "v:90",
                          "--stock", "block:12x4x1@-1,0,0", "--tools", table, "--out",
                          tmp_path / "p.ply", "--report", report, "--quiet"], capsys)
    assert code == 0, err
    assert "T1 from line 1: length 0 mm, removed 0.001 mm^3" in out
    assert "T2 from line 6: length 2.5 mm, removed 0.001 mm^3" in out
    tools = json.loads(report.read_text(), parse_constant=no_nan)["tools"]
    assert [(t["tool"], t["line"]) for t in tools] == [(1, 1), (2, 6)]  # nothing before T1
    for t in tools:
        assert t["removed_volume_mm3"] == pytest.approx(0.01**2 * 10.0, rel=1e-9)


def test_the_nc_reader_takes_a_tool_table(tmp_path):
    table = tmp_path / "tools.toml"
    table.write_text("")
    try:
        with_table = machinesim.nc.read_program(GROOVES, tools=table)
    except TypeError as exc:
        if "tools" not in str(exc):
            raise
        pytest.skip("machinesim.nc.read_program(path, tools=...) is not there yet (the NC "
                    "part of issue 12): the CLI passes --tools to it")
    assert with_table.moves == machinesim.nc.read_program(GROOVES).moves


def _overtravel_program(tmp_path) -> Path:
    program = tmp_path / "overtravel.nc"
    program.write_text("G90 G21 G94\nG00 X-300. Y2. Z0.1\nG00 X0.\nM30\n")  # X travel +-250 mm
    return program


def test_allow_overtravel_reaches_the_cutter(tmp_path, capsys, monkeypatch):
    seen = []
    real = machinesim.cutting.cut

    def cutter(*args, **kwargs):
        seen.append(kwargs.pop("allow_overtravel", None))
        return real(*args, **kwargs)

    monkeypatch.setattr(machinesim.cutting, "cut", cutter)
    for flag in ([], ["--allow-overtravel"]):
        code, _, err = run(["cut", GROOVES, *CUT, "--out", tmp_path / "p.ply", *flag], capsys)
        assert code == 0, err
    assert seen == [None, True]  # without the flag, the cutter's default (refuse) holds


def test_overtravel_is_refused_by_default_and_listed_when_allowed(tmp_path, capsys):
    if "allow_overtravel" not in inspect.signature(machinesim.cutting.cut).parameters:
        pytest.skip("machinesim.cutting.cut(..., allow_overtravel=) is not there yet (the CUT "
                    "part of issue 12): the CLI passes --allow-overtravel to it")
    program = _overtravel_program(tmp_path)
    out, report = tmp_path / "p.ply", tmp_path / "r.json"
    code, _, err = run(["cut", program, *CUT, "--out", out, "--report", report], capsys)
    assert_clean_failure(code, err, "X", "-300")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["overtravel.nc"]
    code, _, err = run(["cut", program, *CUT, "--out", out, "--report", report,
                        "--allow-overtravel"], capsys)
    assert code == 0, err
    data = json.loads(report.read_text(), parse_constant=no_nan)
    assert any("axis X = -300" in v for v in data["limit_violations"])
    assert "outside travel" in err


# --------------------------------------------------- the real entry point, in a process


def _run_process(args, **kwargs) -> subprocess.CompletedProcess:
    return subprocess.run([*entry_point(), *map(str, args)], capture_output=True, text=True,
                          timeout=120, check=False, **kwargs)


def test_the_installed_command_reports_file_errors_in_one_line(tmp_path):
    result = _run_process(["cut", tmp_path / "missing.nc", *CUT, "--out", tmp_path / "p.ply"])
    assert_clean_failure(result.returncode, result.stderr, "missing.nc: no such file")
    result = _run_process(["cut", GROOVES, *CUT, "--out", tmp_path / "p.ply",
                           "--report", tmp_path / "nowhere" / "r.json"])
    assert_clean_failure(result.returncode, result.stderr, "r.json: cannot write the report")
    assert list(tmp_path.iterdir()) == []


def test_python_dash_m_machinesim_is_the_command_line():
    """``python -m machinesim`` runs the command, as a user without the script on PATH
    types it (it had said "No module named machinesim.__main__")."""
    result = subprocess.run([sys.executable, "-m", "machinesim", "machines"], cwd=ROOT,
                            capture_output=True, text=True, timeout=120, check=False)
    assert result.returncode == 0, result.stderr
    assert tuple(line.split()[0] for line in result.stdout.splitlines()) == \
        machinesim.list_machines()


def test_a_bad_tool_or_stock_is_named_once_by_its_option_or_its_table_key(tmp_path, capsys):
    # it had read "key 'tool': tool spec 'ball:-1': key 'radius': radius must be ...", and
    # from a tool table "key 'tool.1.shape': key 'tool': tool spec ...: key 'radius': ..."
    argv = ["cut", GROOVES, "--machine", "grooving_4axis", "--stock", "block:10x10x2",
            "--quiet", "--out", tmp_path / "p.ply"]
    code, _, err = run([*argv, "--tool", "ball:-1"], capsys)
    assert_clean_failure(code, err)
    assert err == ("machinesim: error: --tool 'ball:-1': radius must be a positive finite "
                   "number, got -1 mm (-0.001 m)\n")
    table = tmp_path / "tools.toml"
    table.write_text('[tool.1]\nlength_mm = 0.0\nshape = "ball:-1"\n')
    code, _, err = run([*argv, "--tool", "v:90", "--tools", table], capsys)
    assert_clean_failure(code, err)
    assert err == (f"machinesim: error: {table}, line 3, key 'tool.1.shape': tool spec "
                   "'ball:-1': "
                   "radius must be a positive finite number, got -1 mm (-0.001 m)\n")
    assert list(tmp_path.iterdir()) == [table]
    code, _, err = run([*argv[:4], "--tool", "v:90", "--stock", "block:10x10", *argv[6:]],
                       capsys)
    assert_clean_failure(code, err)
    assert err.startswith("machinesim: error: --stock 'block:10x10': expected 3 numbers "
                          "separated by 'x' in '10x10'; forms: 'block:LxWxH', ")


def test_a_huge_tool_is_refused_cleanly(tmp_path):
    result = _run_process(["cut", GROOVES, "--machine", "grooving_4axis", "--tool", "ball:1e9",
                           "--stock", "block:10x10x2", "--out", tmp_path / "p.ply"])
    if result.returncode < 0:
        pytest.skip(f"machinesim.tools does not bound tool sizes yet (the CUT part of issue "
                    f"12): ball:1e9 kills the process with signal {-result.returncode}")
    assert_clean_failure(result.returncode, result.stderr, "ball:1e9")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.skipif(not Path("/proc/self/maps").exists(), reason="needs Linux /proc")
def test_ctrl_c_while_loading_exits_130_in_one_line(tmp_path, as_in_a_terminal, interrupted):
    """SIGINT once the process maps SciPy's own libraries (not numpy's scipy_openblas): only
    the viewer loads SciPy, inside `main`, so the process is importing it or building the
    page."""
    page = tmp_path / "machine.html"
    process = subprocess.Popen([*entry_point(), "view", "robonano_a0ib", "--html", str(page)],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               **as_in_a_terminal)
    _, err = interrupted(process, "site-packages/scipy/")
    assert_clean_failure(process.returncode, err, "interrupted", status=130)
    assert not page.exists()


# ------------------------------------------------------------------ warnings on stderr


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


def cut_with_report(tmp_path, capsys, text: str, tool: str, stock: str):
    """Cut the NC ``text`` on grooving_4axis with ``tool`` and ``stock``; (stderr, the
    report's JSON) of a run that must succeed."""
    program, report = tmp_path / "program.nc", tmp_path / "r.json"
    program.write_text(text)
    code, _, err = run(["cut", program, "--machine", "grooving_4axis", "--tool", tool,
                        "--stock", stock, "--quiet", "--out", tmp_path / "p.ply",
                        "--report", report], capsys)
    assert code == 0, err
    return err, json.loads(report.read_text(), parse_constant=no_nan)


def test_a_haas_header_with_g187_and_g103_cuts_the_part_it_cuts_without_them(tmp_path, capsys):
    """A Fusion-style Haas header (safe start, G187 P3 E.. finish smoothness, G103 P1 look-ahead
    limit) had been refused at its G187 and G103 as unknown G codes, and with them the whole
    program. The cut follows the programmed path through its servo model, with no smoothing of
    the control's, so the program cuts the same part as the one without those lines (the same
    mesh, byte for byte, the same volume and time), and the report lists them at their lines."""
    body = ["%", "O01001 (POCKET)", "(T1 D=1. CR=0. - FLAT END MILL)",
            "N10 G00 G17 G40 G49 G80 G90", "N15 G21", "N20 G28 G91 Z0.", "N25 G90",
            "N30 T1 M06", "N35 S10000 M03", "N40 G187 P3 E0.01", "N45 G103 P1", "N50 G54",
            "N55 G00 X1. Y1.", "N60 Z1.", "N65 G01 Z-0.05 F100.", "N70 X4. F300.", "N75 Y2.",
            "N80 G02 X3. Y3. I-1. J0.", "N85 G01 X1.", "N90 G00 Z5.", "N95 G103",
            "N100 G187", "N105 G28 G91 Z0.", "N110 M30", "%"]
    haas = tmp_path / "haas"
    haas.mkdir()
    err, with_them = cut_with_report(haas, capsys, "\n".join(body) + "\n", "flat:1",
                                     "block:5x4x1")
    plain = tmp_path / "plain"
    plain.mkdir()
    _, without = cut_with_report(plain, capsys, "\n".join(
        line for line in body if "G187" not in line and "G103" not in line) + "\n", "flat:1",
        "block:5x4x1")
    assert with_them["removed_volume_mm3"] > 0.0
    for key in ("removed_volume_mm3", "machining_time_s"):
        assert with_them[key] == without[key], key
    assert (haas / "p.ply").read_bytes() == (plain / "p.ply").read_bytes()
    states = {state["word"]: state["line"] for state in with_them["nc"]["states"]}
    assert {word: states[word] for word in ("G187 P3 E0.01", "G103 P1", "G103", "G187")} == {
        "G187 P3 E0.01": body.index("N40 G187 P3 E0.01") + 1,
        "G103 P1": body.index("N45 G103 P1") + 1, "G103": body.index("N95 G103") + 1,
        "G187": body.index("N100 G187") + 1}


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


def test_the_report_lists_how_the_program_was_read(tmp_path, capsys):
    # the corpus CAM program, its stock far from the tool: the report says which modal
    # states it set (first line of each, found in the text here), the integer rule and the
    # tool table
    corpus = ROOT / "tests" / "nc_corpus"
    program, tools = corpus / "cam_header.nc", corpus / "tools.toml"
    lines = program.read_text().splitlines()

    def line_of(block: str) -> int:
        return next(n for n, text in enumerate(lines, 1) if text.startswith(block))

    report = tmp_path / "r.json"
    code, _, err = run(["cut", program, "--machine", "grooving_4axis", "--tool", "ball:0.5",
                        "--stock", "block:1x1x1@100,100,-50", "--tools", tools, "--quiet",
                        "--integer-input", "increment", "--out", tmp_path / "p.ply",
                        "--report", report], capsys)
    assert code == 0, err
    nc = json.loads(report.read_text(), parse_constant=no_nan)["nc"]
    expected = [("G40", "N10 "), ("G80", "N10 "), ("T1", "N30 "), ("T2", "N120 "),
                ("G05.1 Q1", "N130 "), ("G64", "N135 "), ("G05.1 Q0", "N165 ")]
    assert nc == {"integer_input": "increment", "integer_words": [],
                  "states": [{"word": w, "line": line_of(b)} for w, b in expected],
                  "units": [{"word": "G21", "line": line_of("N15 G21")}],
                  "tool_table": str(tools)}
    code, _, err = run(["cut", GROOVES, *CUT, "--out", tmp_path / "g.ply", "--report", report],
                       capsys)
    assert code == 0, err
    nc = json.loads(report.read_text(), parse_constant=no_nan)["nc"]
    assert nc["integer_input"] == "calculator" and nc["tool_table"] is None
    assert nc["integer_words"] == []  # the example program writes every number with a point


def test_the_cut_starts_at_the_machines_home_and_g28_returns_there(tmp_path, capsys):
    """A CAM header's G28 G91 Z0 lifts the tool to the machine's home (Z at the top of its
    travel, 100 mm on grooving_4axis), as a reference return does, and the program starts
    there: neither the first rapid nor the G28 touches the block whose top is work zero.
    The machining time is the rapids' by hand: X, Y, Z at 25 mm/s each."""
    err, data = cut_with_report(tmp_path, capsys, "N10 G90 G21 G17\nN20 G00 X-5. Y5. Z5.\n"
                                "N30 G28 G91 Z0.\nN40 G90 G00 X15. Y5.\nN50 M30\n", "flat:1",
                                "block:10x10x2")
    assert data["rapids_that_cut_lines"] == []
    assert "rapid cut" not in err and data["removed_volume_mm3"] == 0.0
    # home (0, 0, 100) -> (-5, 5, 5): Z 95 mm; -> Z 100: 95 mm; -> X 15: 20 mm
    assert data["machining_time_s"] == pytest.approx((95 + 95 + 20) / 25.0, rel=1e-12)


def test_version_prints_the_installed_packages_version(capsys):
    from importlib.metadata import version

    with pytest.raises(SystemExit) as exit_:
        main(["--version"])
    assert exit_.value.code == 0
    assert capsys.readouterr().out.strip() == f"machinesim {version('machinesim')}"


def test_a_work_offset_the_command_is_not_given_is_taken_as_zero_and_said(tmp_path, capsys):
    # G55 and G57 select systems machinesim cut has no offsets for: the part is G54's (the
    # same program without them), and each is named with its line, on stderr and in the report
    body = "G0 X1. Y1. Z0.1\nG1 Z-0.01 F100.\nX3.\nG0 Z0.1\n"
    plain, offset = tmp_path / "g54.nc", tmp_path / "g55.nc"
    plain.write_text(f"G90 G21\n{body}M30\n")
    offset.write_text(f"G90 G21 G55\n{body}G57\nM30\n")
    parts = []
    for program in (plain, offset):
        out = tmp_path / f"{program.stem}.ply"
        code, _, err = run(["cut", program, "--machine", "grooving_4axis", "--tool", "v:90",
                            "--stock", "block:5x3x1", "--quiet", "--out", out,
                            "--report", tmp_path / f"{program.stem}.json"], capsys)
        assert code == 0, err
        parts.append(out.read_bytes())
    assert parts[0] == parts[1]
    notes = [line for line in err.splitlines() if "work offset" in line]
    assert notes == [f"note: {word} at line {line} selects a work offset this command is not "
                     "given: taken as zero, the same as G54 (docs/nc.md)"
                     for word, line in (("G55", 1), ("G57", 6))]
    states = json.loads((tmp_path / "g55.json").read_text(), parse_constant=no_nan)
    assert {"word": "G55", "line": 1} in states["nc"]["states"]


@pytest.mark.parametrize("head, units", [("G90 G21", [{"word": "G21", "line": 1}]),
                                         ("G90", [])])
def test_a_program_without_g20_or_g21_is_read_in_mm_and_said(tmp_path, capsys, head, units):
    # an inch program without G20 would come out 25.4 times too small: say how it was read
    err, summary = _cut_small(tmp_path, capsys, "v:90",
                              f"{head}\nG0 X1. Y1. Z0.1\nG1 Z-0.01 F100.\nX3.\nG0 Z0.1\nM30\n")
    note = ("the program selects neither G20 (inch) nor G21 (mm): its lengths were read in "
            "mm; add G20 at its start if it is written in inches")
    assert summary["nc"]["units"] == units
    assert (f"note: {note}" in err.splitlines()) == (not units)
    assert (note in summary["notes"]) == (not units)


def _cut_small(tmp_path, capsys, tool: str, text: str):
    """(stderr, report) of ``machinesim cut`` of ``text`` with ``tool`` on a 5 x 3 mm block."""
    program, report = tmp_path / "p.nc", tmp_path / "r.json"
    program.write_text(text)
    code, _, err = run(["cut", program, "--machine", "grooving_4axis", "--tool", tool,
                        "--stock", "block:5x3x1", "--quiet", "--out", tmp_path / "p.ply",
                        "--report", report], capsys)
    assert code == 0, err
    return err, json.loads(report.read_text(), parse_constant=no_nan)


@pytest.mark.parametrize("body, noted", [
    ("G1 Z-0.01 F100.\nX3.\n", False),                      # straight feeds: no chord
    ("G1 Z-0.01 F100.\nG2 X3. Y1. R1.\n", True),             # an arc
    ("G1 Z-0.01 F100.\nX3. C10.\n", True),                   # a feed that turns C
    ("G1 Z-0.01 F100.\nG0 C10.\nG1 X3.\n", False),          # C turned by a rapid only
])
def test_the_chord_note_is_given_when_arcs_or_rotary_feeds_were_split(tmp_path, capsys, body,
                                                                    noted):
    err, summary = _cut_small(tmp_path, capsys, "ball:0.5",
                              f"G90 G21\nG0 X1. Y1. Z0.1 C0.\n{body}G0 Z0.1\nM30\n")
    note = ("arcs and rotary moves were split into chords within 100 nm, a tenth of the "
            "tool's own facets (--chord-nm sets it; docs/cutting.md)")
    assert (f"note: {note}" in err.splitlines()) == noted
    assert (note in summary["notes"]) == noted


@pytest.mark.parametrize("argv, hint", [
    (["cut", "a.nc", "--machine", "grooving_4axis", "--tol", "v:90", "--stock", "block:1x1x1",
      "--out", "x.ply"], "--tol is not an option here; did you mean --tool?"),
    (["cut", "a.nc", "--machine", "grooving_4axis", "--tool", "v:90", "--stock", "block:1x1x1",
      "--out", "x.ply", "--rio", "1"], "--rio is not an option here; did you mean --roi?"),
    (["view", "grooving_4axis", "--progam", "x.nc"],
     "--progam is not an option here; did you mean --program?"),
])
def test_a_misspelt_option_is_named_with_the_one_meant(argv, hint, capsys):
    # argparse alone said only "the following arguments are required: --tool", or listed
    # the word without the option it resembles
    code, out, err = run(argv, capsys)
    assert code == 2 and out == ""
    assert err.splitlines()[-1].endswith(hint), err


CUT_WORDS = ["cut", "a.nc", "--machine", "grooving_4axis", "--tool", "v:90", "--stock",
       "block:1x1x1", "--out", "x.ply"]
CAMPAIGN_WORDS = ["campaign", "tool_rotation_arm", "--trials", "2", "--out", "c"]


@pytest.mark.parametrize("argv, refusal", [
    (CUT_WORDS + ["--tool", "ball:2"], "argument --tool: given 2 times (--tool v:90, "
     "--tool ball:2); give it once: only the last would count"),
    (CUT_WORDS + ["--report=r.json", "--repo", "s.json"], "argument --report: given 2 times "
     "(--report=r.json, --repo s.json); give it once: only the last would count"),
    (CAMPAIGN_WORDS + ["--seed", "1", "--vary", "a=1", "--seed", "2"], "argument --seed: "
     "given 2 times (--seed 1, --seed 2); give it once: only the last would count"),
])
def test_an_option_given_twice_is_refused_naming_both(argv, refusal, capsys):
    # argparse kept the last and dropped the others without a word: --seed 1 --seed 2 ran
    # seed 2
    code, out, err = run(argv, capsys)
    assert code == 2 and out == ""
    assert err.splitlines()[-1].endswith(f"error: {refusal}"), err


def test_options_that_add_up_and_switches_may_be_repeated_and_after_double_dash_none():
    from machinesim.cli import _parser

    args = _parser().parse_args(CUT_WORDS + ["--roi", "0,1,0,1", "--roi", "1,2,1,2",
                                             "--quiet", "--quiet"])  # a switch: once or twice
    assert args.roi == ["0,1,0,1", "1,2,1,2"] and args.tool == "v:90" and args.quiet
    args = _parser().parse_args(CAMPAIGN_WORDS + ["--vary", "a=1", "--vary", "b=2", "--seed", "3"])
    assert args.vary == ["a=1", "b=2"] and args.seed == 3
    # a word after -- is no option: a program named --out
    args = _parser().parse_args(["cut", *CUT_WORDS[2:], "--", "--out"])
    assert args.program.name == "--out" and args.out.name == "x.ply"


def test_a_scenario_refuses_its_seed_given_twice(capsys):
    from machinesim.scenario_runs import scenario_arguments

    parser = scenario_arguments("a scenario", "out")
    assert parser.parse_args(["--seed", "1", "--noise", "off"]).seed == 1
    with pytest.raises(SystemExit) as exited:
        parser.parse_args(["--seed", "1", "--seed", "2"])
    assert exited.value.code == 2
    assert capsys.readouterr().err.splitlines()[-1].endswith(
        "error: argument --seed: given 2 times (--seed 1, --seed 2); give it once: only the "
        "last would count")


def test_a_long_cut_without_a_terminal_logs_its_progress_as_lines(capsys):
    """stderr not a terminal (a log): a cut shorter than LOG_PROGRESS_AFTER_S says nothing,
    a longer one a line once it is due, then at most one per LOG_PROGRESS_EVERY_S, and one
    at the end (clock by hand: 0, 5, 12, 20, 41, 50 s)."""
    from machinesim import cli

    times = iter([0.0, 5.0, 9.0])
    show = cli._progress_bar(False, clock=lambda: next(times))
    show(0, 100)
    show(100, 100)  # done at 9 s: shorter than 10 s, nothing said
    assert capsys.readouterr().err == ""
    times = iter([0.0, 5.0, 12.0, 20.0, 41.0, 50.0])
    show = cli._progress_bar(False, clock=lambda: next(times))
    for done in (0, 10, 30, 60, 100):
        show(done, 100)
    assert capsys.readouterr().err.splitlines() == [
        "  cutting: 10/100 sweeps (10 %), 12 s",   # first due at 10 s
        "  cutting: 100/100 sweeps (100 %), 50 s",  # 20 and 41 s: before 12 + 30 s
    ]
    assert cli._progress_bar(True) is None  # --quiet


def test_a_log_names_the_stage_building_the_sweeps_before_cutting(capsys):
    """The sweeps of a ball end mill take tens of seconds to build before the cut (a raster
    of 3,819: 22 s, said nothing): the engine's stage is named in the line."""
    from machinesim import cli

    times = iter([0.0, 11.0, 20.0, 45.0])
    show = cli._progress_bar(False, clock=lambda: next(times))
    show(500, 3848, stage="building")
    show(3848, 3848, stage="building")
    show(3819, 3819)
    assert capsys.readouterr().err.splitlines() == [
        "  building: 500/3848 sweeps (12 %), 11 s",
        "  building: 3848/3848 sweeps (100 %), 20 s",
        "  cutting: 3819/3819 sweeps (100 %), 45 s",
    ]


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
