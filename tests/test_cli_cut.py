"""`machinesim cut` as it should go: the part and report with units and no NaN, the options
that reach the NC reader and the cutter (integer input, tool tables, the chord tolerance,
overtravel), a Haas header, the machine's home, and what the report and notes say of how
the program was read."""

from __future__ import annotations

import inspect
import json
import math
from pathlib import Path

import numpy as np
import pytest
from cli_helpers import CUT, GROOVES, ROOT, assert_clean_failure, cut_with_report, no_nan, run

import machinesim
import machinesim.cutting
import machinesim.nc

#: grooves.nc: four 90-deg V grooves 20 um deep right across the 10 mm block: each removes
#: a triangle of depth d and width 2 d (area d^2) over 10 mm.
GROOVES_MM3 = 4 * 0.020**2 * 10.0


def test_a_cut_writes_part_and_report_with_units_and_no_nan(tmp_path, capsys):
    out, report = tmp_path / "part.stl", tmp_path / "report.json"
    code, stdout, err = run(["cut", GROOVES, *CUT, "--out", out, "--report", report], capsys)
    assert code == 0, err
    data = json.loads(report.read_text(), parse_constant=no_nan)
    assert data["removed_volume_mm3"] == pytest.approx(GROOVES_MM3, rel=1e-9)
    assert data["part_file"] == str(out) and data["part_unit"] == "mm"
    assert f"wrote {out} (binary STL, millimetres" in stdout
    assert sorted(p.name for p in tmp_path.iterdir()) == ["part.stl", "report.json"]


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


def test_the_integer_note_of_an_inch_program_names_inches(tmp_path, capsys):
    """Under G20, calculator-type input reads `X1` as 1 inch, and the note says so with the
    increments in inches (docs/nc.md, "Integer input"); it had said "read in mm" and
    offered is-b as 0.001 mm. The groove shows how X1 was read: a 90-deg V 0.0008 inch
    deep (area d^2) that runs right across the 10 mm block, as 1 inch (25.4 mm) from
    X-0.04 inch does, and 1 mm would not."""
    program = tmp_path / "inch.nc"
    program.write_text("G90 G20 G94\nG00 X-0.04 Y0.2 Z0.004\nZ-0.0008\nG01 X1 F4.\n"
                       "G00 Z0.004\nM30\n")
    report = tmp_path / "r.json"
    code, _, err = run(["cut", program, *CUT, "--out", tmp_path / "p.ply", "--report",
                        report], capsys)
    assert code == 0, err
    depth_mm = 0.0008 * 25.4
    data = json.loads(report.read_text())
    assert data["removed_volume_mm3"] == pytest.approx(10.0 * depth_mm**2, rel=1e-6)
    assert ("note: numbers without a decimal point (X at line 4) were read in inches (G20) "
            "and deg" in err), err
    assert "is-b (0.0001 inch), is-c (0.00001 inch) or increment (0.0000001 inch)" in err
    assert "mm" not in err.split("note: numbers without a decimal point")[1].splitlines()[0]


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


def _two_v_tools(tmp_path, capsys, t2_y_mm):
    """`machinesim cut` of two 90-deg V grooves 10 um deep and 10 mm long, T1 the model's
    tool at Y1, T2 2.5 mm longer (G43 H2 lifting Z by as much) at Y ``t2_y_mm``: (exit
    code, stdout, stderr, report path)."""
    table = tmp_path / "tools.toml"
    table.write_text('[tool.1]\nlength_mm = 0.0\n'   # no shape: the cut's --tool
                     '[tool.2]\nlength_mm = 2.5\nshape = "v:90"\n')
    program = tmp_path / "two_tools.nc"
    program.write_text("T1 M06\nG00 X0 Y1. Z1.\nG01 Z-0.01 F100.\nX10.\nG00 Z5.\n"
                       f"T2 M06\nG43 H2 Z1.\nG00 X0 Y{t2_y_mm}.\nG01 Z-0.01\nX10.\n"
                       "G00 Z5.\nM30\n")
    report = tmp_path / "r.json"
    code, out, err = run(["cut", program, "--machine", "grooving_4axis", "--tool", "v:90",
                          "--stock", "block:12x4x1@-1,0,0", "--tools", table, "--out",
                          tmp_path / "p.ply", "--report", report, "--quiet"], capsys)
    return code, out, err, report


def test_each_tool_cuts_at_its_length_and_the_summary_says_what_it_removed(tmp_path, capsys):
    # Two 90-deg V grooves 10 um deep and 10 mm long (each d^2 x L = 1e-3 mm^3): T1 the
    # model's tool, T2 2.5 mm longer with G43 H2 lifting Z by as much, so both cut at the
    # programmed depth; the change to T2 is made 5 mm up, clear of the part.
    code, out, err, report = _two_v_tools(tmp_path, capsys, t2_y_mm=3)
    assert code == 0, err
    assert "T1 from line 1: length 0 mm, removed 0.001 mm^3" in out
    assert "T2 from line 6: length 2.5 mm, removed 0.001 mm^3" in out
    tools = json.loads(report.read_text(), parse_constant=no_nan)["tools"]
    assert [(t["tool"], t["line"]) for t in tools] == [(1, 1), (2, 6)]  # nothing before T1
    for t in tools:
        assert t["removed_volume_mm3"] == pytest.approx(0.01**2 * 10.0, rel=1e-9)


def test_a_tool_that_retraces_an_earlier_tools_groove_removed_nothing(tmp_path, capsys):
    # T1 cuts a 90-deg V groove 10 um deep and 10 mm long (d^2 x L = 1e-3 mm^3); T2, the same
    # V 2.5 mm longer, runs the same groove at the same depth: its volume is what the booleans
    # leave of nothing, round-off ('T18 ... removed 2.01832e-13 mm^3' had read as material)
    code, out, err, report = _two_v_tools(tmp_path, capsys, t2_y_mm=1)
    assert code == 0, err
    assert "T1 from line 1: length 0 mm, removed 0.001 mm^3" in out
    line = next(t for t in out.splitlines() if t.startswith("  T2 "))
    assert line.startswith("  T2 from line 6: length 2.5 mm, removed nothing")
    assert "mm^3" not in line or "mm^3 of round-off" in line
    summary = json.loads(report.read_text(), parse_constant=no_nan)
    first, second = summary["tools"]
    assert first["removed_volume_mm3"] == pytest.approx(0.01**2 * 10.0, rel=1e-9)
    assert (first["empty_cut"], second["empty_cut"]) == (False, True)
    assert abs(second["removed_volume_mm3"]) <= 1e-9 * first["removed_volume_mm3"]
    assert summary["removed_volume_mm3"] == pytest.approx(0.01**2 * 10.0, rel=1e-9)


def test_each_tools_run_tells_its_progress_under_its_name(tmp_path):
    # two tools, two grooves: the runs are built and cut in turn, each counted on its own;
    # the progress had told both as plain "cutting"/"building", counts restarting unexplained
    table = tmp_path / "tools.toml"
    table.write_text('[tool.1]\nlength_mm = 0.0\n[tool.2]\nlength_mm = 2.5\nshape = "v:90"\n')
    program = tmp_path / "two_tools.nc"
    program.write_text("T1 M06\nG00 X0 Y1. Z1.\nG01 Z-0.01 F100.\nX10.\nG00 Z5.\n"
                       "T2 M06\nG43 H2 Z1.\nG00 X0 Y3.\nG01 Z-0.01\nX10.\nG00 Z5.\nM30\n")
    staged, plain = [], []

    def cut(progress):
        return machinesim.cut(machinesim.nc.read_program(program, tools=table),
                              "grooving_4axis", tool="v:90", stock="block:12x4x1@-1,0,0",
                              progress=progress)[1]

    report = cut(lambda done, total, stage="cutting": staged.append((stage, done, total)))
    cut(lambda done, total: plain.append((done, total)))
    names = [stage.split(" ", 1)[1] for stage, _, _ in staged]
    first = names.index("(T2 from line 6)")  # T1's run told first, whole, then T2's
    assert set(names[:first]) == {"(T1 from line 1)"} and set(names[first:]) == {
        "(T2 from line 6)"}
    ends = [(done, total) for stage, done, total in staged if stage.startswith("cutting")
            and done == total]
    assert sum(total for _, total in ends) == report.sweeps == 2  # a groove each
    # a callable of (done, total) alone is told the cut as before, without the building
    assert plain == [(done, total) for stage, done, total in staged
                     if stage.startswith("cutting")]


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


def test_the_chord_note_names_the_axes_whose_errors_bend_straight_feeds(tmp_path, capsys):
    # A straightness table on X (EZX 2 um at 5 mm, a curve) makes the planner split a
    # straight X feed into chords within the 100 nm of a ball, as it splits a rotary move:
    # 11 sweeps where the nominal machine cuts 1. The note had not been given (no arc, no
    # rotary feed); it now names X. Without the table, or with --chord-nm, none.
    errors = tmp_path / "bend.toml"
    errors.write_text("[component.X]\nposition_mm = [-10.0, -5.0, 0.0, 5.0, 10.0]\n"
                      "EZX_um = [0.0, 2.0, 0.0, -2.0, 0.0]\n")
    program, report = tmp_path / "p.nc", tmp_path / "r.json"
    program.write_text("G90 G21\nG0 X-1. Y1. Z0.1\nG1 Z-0.01 F100.\nX6.\nG0 Z0.1\nM30\n")
    note = ("arcs and rotary moves, and feeds along X (its errors vary along it in --errors: "
            "a straight move there is a curve), were split into chords within 100 nm, a "
            "tenth of the tool's own facets (--chord-nm sets it; docs/cutting.md)")
    for extra, noted, sweeps in (([], False, 1), (["--errors", errors], True, 11),
                                 (["--errors", errors, "--chord-nm", "100"], False, 11)):
        code, _, err = run(["cut", program, "--machine", "grooving_4axis", "--tool",
                            "ball:0.5", "--stock", "block:5x3x1", "--quiet", "--out",
                            tmp_path / "p.ply", "--report", report, *extra], capsys)
        assert code == 0, err
        summary = json.loads(report.read_text(), parse_constant=no_nan)
        assert summary["sweeps_count"] == sweeps
        assert (f"note: {note}" in err.splitlines()) == noted
        assert (note in summary["notes"]) == noted


@pytest.mark.parametrize("table, noted, sweeps", [
    ("position_mm = [-10.0, -5.0, 0.0, 5.0, 10.0]\nEZX_um = [2.0, 2.0, 2.0, 2.0, 2.0]\n",
     False, 1),  # the same 2 um everywhere: the groove moved, straight
    ("position_mm = [-100.0, -50.0, 50.0, 100.0]\nEZX_um = [1.0, 0.0, 0.0, 1.0]\n",
     False, 1),  # bent beyond +-50 mm only: X -1 .. 6 mm is straight
    ("position_mm = [5.5, 10.0]\nEZX_um = [0.0, 2.0]\n", True, 8),  # bends from 5.5 mm
], ids=["constant", "flat-over-the-feeds", "bends-from-5.5mm"])
def test_the_chord_note_is_not_given_for_errors_that_bend_no_feed(tmp_path, capsys, table,
                                                                 noted, sweeps):
    # A table that takes one value over the feeds along its axis moves them and bends none:
    # the planner cuts the X feed as one sweep, and the note's 'a straight move there is a
    # curve ... split into chords' was given all the same (any component table counted)
    errors = tmp_path / "e.toml"
    errors.write_text(f"[component.X]\n{table}")
    program, report = tmp_path / "p.nc", tmp_path / "r.json"
    program.write_text("G90 G21\nG0 X-1. Y1. Z0.1\nG1 Z-0.01 F100.\nX6.\nG0 Z0.1\nM30\n")
    code, _, err = run(["cut", program, "--machine", "grooving_4axis", "--tool", "ball:0.5",
                        "--stock", "block:5x3x1", "--quiet", "--out", tmp_path / "p.ply",
                        "--report", report, "--errors", errors], capsys)
    assert code == 0, err
    summary = json.loads(report.read_text(), parse_constant=no_nan)
    assert summary["sweeps_count"] == sweeps
    assert ("feeds along X" in err) == noted
    assert any("feeds along X" in note for note in summary["notes"]) == noted


def test_a_table_bends_a_span_as_sampled_finely():
    # _bends (by the table's sloping segments) against the table sampled at 2,001 points
    from machinesim._program_options import _bends
    from machinesim.errors.families import ComponentError

    rng = np.random.default_rng(3)
    for _ in range(50):
        positions = np.sort(rng.choice(np.arange(-8, 9), size=5, replace=False)).astype(float)
        table = ComponentError("table", positions, rng.integers(0, 2, size=5).astype(float))
        low = rng.integers(-10, 10, size=40).astype(float) + rng.choice([0.0, 0.5], size=40)
        high = low + rng.choice([0.5, 1.0, 3.0, 7.0], size=40)
        sampled = [np.ptp(table.evaluate(np.linspace(a, b, 2001))) > 0 for a, b in
                   zip(low, high, strict=True)]
        assert _bends(table, low, high).tolist() == sampled


def test_a_tool_table_shape_perhaps_in_um_is_warned_of_once_at_its_line(tmp_path, capsys):
    """`shape = "flat:500"` (500 um meant) warned twice, naming the spec alone ('tool spec
    'flat:500': ...'), not the table, its line or key: once now, at them."""
    table = tmp_path / "tools.toml"
    table.write_text('[tool.1]\nlength_mm = 0.0\nshape = "flat:500"\n')
    program = tmp_path / "t1.nc"
    program.write_text("G21 G90\nT1 M06\nG00 X0 Y0 Z1.\nG01 Z-0.01 F100.\nX5.\nM30\n")
    code, _, err = run(["cut", program, "--machine", "grooving_4axis", "--tool", "flat:0.5",
                        "--stock", "block:10x10x2", "--quiet", "--tools", table, "--out",
                        tmp_path / "p.ply"], capsys)
    assert code == 0, err
    warned = [line for line in err.splitlines() if "flat:500" in line]
    assert warned == [f"machinesim: warning: {table}, line 3, key 'tool.1.shape': tool spec "
                      "'flat:500': a radius of 500 mm is a tool 1 m across, wider than any "
                      "shipped machine's travel (0.5 m at most). A spec's sizes are mm: if it "
                      "is in um, 500 um is flat:0.5"], err
