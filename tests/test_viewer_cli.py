"""`machinesim view` through its parser (`run_view`): a machine, a part and a report folder
exported, bad input refused with a clear message, and a program viewed as `cut` reads it."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import pytest
from viewer_helpers import BUDGET, ERRORS, STOCK, grooves, run

from machinesim import load_machine
from machinesim.cutting import cut
from machinesim.exceptions import AxisLimitError, InputError, ModelError
from machinesim.viewer.cli import add_view_parser
from machinesim.viewer.scene import Scene
from machinesim.workpiece import stock_from_spec


def test_cli_exports_a_machine_a_part_and_a_report_folder(tmp_path, capsys):
    program = tmp_path / "grooves.nc"
    program.write_text("G90 G21\nG00 X-0.2 Y0.4 Z0.1\nG00 Z-0.02\nG01 X1.2 F500\n"
                       "G00 Z0.1\nM30\n")
    assert run(["grooving_4axis", "--program", str(program), "--stock", STOCK,
                "--tool", "v:150", "--max-triangles", str(BUDGET),
                "--html", str(tmp_path / "m.html")]) == 0
    assert "self-contained" in capsys.readouterr().out

    part, report = cut(grooves(), "grooving_4axis", tool="v:150", stock=STOCK, errors=ERRORS)
    nominal, _ = cut(grooves(), "grooving_4axis", tool="v:150", stock=STOCK)
    part.export_ply(tmp_path / "part.ply")
    nominal.export_ply(tmp_path / "nominal.ply")
    (tmp_path / "report.json").write_text(json.dumps(report.to_dict()))
    assert run([str(tmp_path / "part.ply"), "--report", str(tmp_path / "report.json"),
                "--nominal", str(tmp_path / "nominal.ply"), "--max-triangles", str(BUDGET),
                "--html", str(tmp_path / "p.html")]) == 0
    text = (tmp_path / "p.html").read_text(encoding="utf-8")
    assert "removed_volume_mm3" in text and "deviation from nominal" in text

    folder = tmp_path / "report"
    folder.mkdir()
    for name in ("nominal.ply", "part.ply"):
        (folder / name).write_bytes((tmp_path / name).read_bytes())
    (folder / "summary.json").write_text(json.dumps({"pv_nm": 123.0}))
    assert run([str(folder), "--max-triangles", str(BUDGET),
                "--html", str(tmp_path / "r.html")]) == 0
    text = (tmp_path / "r.html").read_text(encoding="utf-8")
    assert "pv_nm: 123" in text and "part.ply: deviation from nominal" in text
    assert "coloured by deviation from nominal.ply" in text


def test_cli_refuses_bad_input_with_a_clear_message(tmp_path):
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(InputError, match="no part meshes"):
        run([str(empty), "--html", str(tmp_path / "x.html")])
    with pytest.raises(InputError, match="no such part file"):
        run([str(tmp_path / "missing.ply"), "--html", str(tmp_path / "x.html")])
    with pytest.raises(InputError, match="^--program does not apply to a part; see"):
        run([str(tmp_path / "missing.ply"), "--program", "p.nc"])
    # it read "--report, --nominal do(es) not apply to a machine"
    with pytest.raises(InputError, match="^--report and --nominal do not apply to a machine; "):
        run(["robonano_a0ib", "--report", "r.json", "--nominal", "n.ply"])
    with pytest.raises(InputError, match="^--program, --report and --nominal do not apply to "
                       "a report folder; "):
        run([str(empty), "--program", "p.nc", "--report", "r.json", "--nominal", "n.ply"])
    with pytest.raises(InputError, match="expected a file name ending in .html"):
        run(["robonano_a0ib", "--html", str(tmp_path / "x.png")])
    # headless Chromium shows ERR_UNSAFE_PORT for 6000 (X11) and 6665 (IRC): the server
    # started and the screenshot failed with 'the page raised: Uncaught'
    for port in ("6000", "6665"):
        with pytest.raises(InputError, match=f"--port {port}: browsers refuse to open pages"):
            run(["robonano_a0ib", "--port", port])
    with pytest.raises(ModelError, match="unknown machine 'nosuch'"):
        run(["nosuch", "--html", str(tmp_path / "x.html")])
    with pytest.raises(InputError, match="reads parts as float64 PLY .*not .stl"):
        run([str(tmp_path / "part.stl"), "--html", str(tmp_path / "x.html")])
    # a part saved under another ending was 'unknown machine', as if a name were misspelt
    (tmp_path / "part.dat").write_bytes(stock_from_spec("block:1x1x1").encode("ply"))
    with pytest.raises(InputError, match=r"part.dat: expected a part file ending in \.ply, a "
                                         r"machine's \.urdf or a report folder"):
        run([str(tmp_path / "part.dat"), "--html", str(tmp_path / "x.html")])
    assert not list(tmp_path.glob("*.html"))


def test_view_reads_a_program_as_cut_reads_it_and_refuses_a_second_tool(tmp_path, monkeypatch,
                                                                       capsys):
    import machinesim.viewer.machine as viewer_machine
    from machinesim.nc import read_program

    program = tmp_path / "integers.nc"
    program.write_text("G90 G21\nG00 X-200 Y400 Z100\nG00 Z-20\nG01 X1200 F500\n"
                       "G02 X1400 Y600 R200\nG00 Z100\nM30\n")
    seen = {}

    def capture(machine, program, **kwargs):
        seen.update(program=program, **kwargs)
        return Scene("captured")

    monkeypatch.setattr(viewer_machine, "machine_scene", capture)
    assert run(["grooving_4axis", "--program", str(program), "--integer-input", "increment",
                "--chord-nm", "3", "--stock", STOCK, "--html", str(tmp_path / "m.html")]) == 0
    # increment input: X1200 is 1.2 um; the arc split within the 3 nm asked for
    home = load_machine("grooving_4axis").home
    expected = read_program(program, integer_input="increment", chord_tolerance=3 * 1e-9,
                            reference=dict(zip("XYZC", home, strict=True)))
    assert seen["program"].moves == expected.moves
    assert seen["chord_tolerance"] == 3 * 1e-9
    # with G21 nothing is noted; without it the unit it was read in is (as cut notes it)
    assert "G20" not in capsys.readouterr().err
    program.write_text(program.read_text().replace("G90 G21", "G90"))
    assert run(["grooving_4axis", "--program", str(program), "--stock", STOCK,
                "--html", str(tmp_path / "m.html")]) == 0
    assert ("note: the program selects neither G20 (inch) nor G21 (mm): its lengths were "
            "read in mm" in capsys.readouterr().err)
    assert expected.targets[2, 0] == pytest.approx(1.2e-6, rel=1e-12)

    tools = tmp_path / "tools.toml"
    tools.write_text("[tool.1]\nlength_mm = 2.5\n")
    changed = tmp_path / "changed.nc"
    changed.write_text("G90 G21\nT1 M06\nG00 G43 H1 Z1.\nG01 X0.5 F500\nM30\n")
    with pytest.raises(InputError, match="T1 at line 2 .*length 2.5 mm.*machinesim cut --tools"):
        run(["grooving_4axis", "--program", str(changed), "--tools", str(tools),
             "--html", str(tmp_path / "t.html")])
    with pytest.raises(InputError, match="--integer-input read a program: give one"):
        run(["grooving_4axis", "--integer-input", "increment"])
    with pytest.raises(InputError, match="--chord-nm does not apply to a part"):
        run([str(tmp_path / "missing.ply"), "--chord-nm", "2"])


def test_cli_refuses_a_display_budget_no_page_holds_naming_the_option(tmp_path):
    # --max-triangles 1000000000 ended in the height map's "Expected at most 1e+08 samples in
    # one reading (MAX_SAMPLES) ... take fewer x or y samples", and 10**20 in "out of memory:
    # ... a cut of many sweeps whose faces nearly coincide", neither naming the option
    stock_from_spec("block:1x1x1").export_ply(tmp_path / "part.ply")
    most = ((1 << 29) - 24) // 30  # V8's longest string, ~30 characters a triangle
    for budget in (0, most + 1, 10**9, 10**20):
        with pytest.raises(InputError) as info:
            run([str(tmp_path / "part.ply"), "--max-triangles", str(budget),
                 "--html", str(tmp_path / "p.html")])
        assert str(info.value) == (
            f"--max-triangles {budget}: expected a count from 1 to {most:,} (a page holds "
            "about 30 characters a triangle, and a browser's JavaScript engine reads at most "
            "536,870,888: more opens blank)")
    assert not (tmp_path / "p.html").exists()


def test_cli_refuses_tool_stock_and_duration_where_no_program_runs(tmp_path):
    # `view robonano_a0ib --tool v:90 --stock block:1x1x1 --duration 5`, and the same on a
    # part or a report folder, took the three and ignored them: the page showed the machine
    # (or the part) alone and the command exited 0
    page = str(tmp_path / "x.html")
    for given in (["--tool", "v:90"], ["--stock", "block:1x1x1", "--duration", "5"]):
        names, joined = ", ".join(given[::2]), " and ".join(given[::2])
        with pytest.raises(InputError, match=f"^{names} (is|are) for the program the machine "
                                             "runs .*: give one with --program$"):
            run(["robonano_a0ib", *given, "--html", page])
        with pytest.raises(InputError, match=f"^{joined} do(es)? not apply to a part"):
            run([str(tmp_path / "part.ply"), *given, "--html", page])
        with pytest.raises(InputError, match=f"^{joined} do(es)? not apply to a report folder"):
            run([str(tmp_path), *given, "--html", page])
    assert list(tmp_path.iterdir()) == []
    # the machine alone, and with its errors, is shown as before
    errors = Path(__file__).resolve().parents[1] / "models" / "errors" / "example.toml"
    assert run(["robonano_a0ib", "--errors", str(errors), "--html", page]) == 0


def test_a_program_beyond_the_travel_is_refused_naming_the_command_that_cuts_it(tmp_path):
    # view has no --allow-overtravel: the message sent its user to an option it refuses
    program = tmp_path / "far.nc"
    program.write_text("G90 G21\nG00 X0 Y0 Z1.\nG01 Z-0.01 F100.\nG01 X500. F1000.\n"
                       "G00 Z1.\nM30\n")
    parser = add_view_parser(argparse.ArgumentParser().add_subparsers())
    assert "--allow-overtravel" not in parser.format_help()
    with pytest.raises(AxisLimitError, match=r"axis X = 500\.000000 mm at line 4 outside its "
                                             r"travel -140\.000000 mm \.\. 140\.000000 mm.*"
                                             r"machinesim cut --allow-overtravel"):
        run(["robonano_a0ib", "--program", str(program), "--html", str(tmp_path / "f.html")])
    assert not (tmp_path / "f.html").exists()


def test_a_program_that_misses_the_stock_is_warned_on_the_page_and_on_stderr(tmp_path, capsys):
    # the grooves run at Y 0.4 mm: on a block 0.8 mm wide they cut, moved 5 mm aside they miss
    program = tmp_path / "grooves.nc"
    program.write_text("G90 G21\nG00 X-0.2 Y0.4 Z0.1\nG00 Z-0.02\nG01 X1.2 F500\n"
                       "G00 Z0.1\nM30\n")
    for stock, missed in ((STOCK, False), ("block:1x0.8x0.5@5,5,-0.5", True)):
        page = tmp_path / f"{missed}.html"
        assert run(["grooving_4axis", "--program", str(program), "--stock", stock,
                    "--tool", "v:150", "--max-triangles", str(BUDGET), "--html",
                    str(page)]) == 0
        err = capsys.readouterr().err
        assert ("warning: the program removed no material" in err) == missed
        assert ("<b>warning:</b> the program removed no material"
                in page.read_text(encoding="utf-8")) == missed


def test_a_program_without_moves_is_said_to_have_none_not_to_miss_the_stock(tmp_path,
                                                                           capsys):
    # '%', '%' (or a dwell alone) cut nothing; the page sent its user to --stock's placement
    # ("does it reach the stock?"), where machinesim cut says the program has no moves
    for name, text in (("none", "%\n%\n"), ("dwell", "G90 G21\nG04 P500\nM30\n")):
        program, page = tmp_path / f"{name}.nc", tmp_path / f"{name}.html"
        program.write_text(text)
        assert run(["grooving_4axis", "--program", str(program), "--stock", STOCK,
                    "--tool", "v:150", "--max-triangles", str(BUDGET), "--html",
                    str(page)]) == 0
        err = capsys.readouterr().err
        said = "the program has no moves (no G00/G01/G02/G03 block that runs)"
        assert f"warning: {said}" in err and "does it reach" not in err, err
        assert f"<b>warning:</b> {said}" in page.read_text(encoding="utf-8")


def test_a_program_that_takes_the_whole_stock_animates_and_says_nothing_is_left(tmp_path,
                                                                             capsys):
    # a 60 mm face mill 3 mm down across a 10 x 10 x 2 mm block takes all of it (200 mm^3,
    # as machinesim cut measures): the page had ended in "machinesim: error: the part has no
    # vertices" after a RuntimeWarning of NaN bounds; 1 mm down it draws the finished part
    for depth, gone in ((3.0, True), (1.0, False)):
        program, page = tmp_path / f"face{depth:g}.nc", tmp_path / f"face{depth:g}.html"
        program.write_text(f"G90 G21 G17\nG00 X-40. Y5. Z1.\nG01 Z-{depth:g} F200.\n"
                           "X50.\nG00 Z1.\nM30\n")
        assert run(["grooving_4axis", "--program", str(program), "--stock", "block:10x10x2",
                    "--tool", "flat:30:h=20", "--max-triangles", str(BUDGET), "--html",
                    str(page)]) == 0
        err = capsys.readouterr().err
        # cut()'s note (`nothing_left_note`), by its rule and in its words: the viewer had
        # decided for itself, 'the program removed all of it, so no finished part is drawn'
        said = ("nothing of the stock is left: the cut removed all of it (200 mm^3), and the "
                "part has no faces (a tool wider than the part, or a depth below its bottom?); "
                "no finished part is drawn")
        assert (f"warning: {said}" in err) == gone, err
        assert (f"<b>warning:</b> {said}" in page.read_text(encoding="utf-8")) == gone


def test_a_program_view_notes_how_its_text_was_read_as_cut_does(tmp_path, capsys):
    # X-1 Y0.4 Z0.1 without a decimal point read as mm, a file without M30 and text after
    # its closing %: machinesim cut notes each; view noted only a missing G20/G21
    program = tmp_path / "grooves.nc"
    program.write_text("%\nG90 G21\nG00 X-1 Y0.4 Z0.1\nG00 Z-0.02\nG01 X1.2 F500\n"
                       "G00 Z0.1\n%\nG00 X5.\n")
    offset = tmp_path / "g55.nc"  # a work offset the command line is not given
    offset.write_text("G90 G21 G55\nG00 X-0.2 Y0.4 Z0.1\nG01 Z-0.02 F500.\nX1.2\nM30\n")
    assert run(["grooving_4axis", "--program", str(offset), "--stock", STOCK, "--tool",
                "v:150", "--max-triangles", str(BUDGET), "--html",
                str(tmp_path / "o.html")]) == 0
    assert ("note: G55 at line 1 selects a work offset this command is not given: taken as "
            "zero, the same as G54") in capsys.readouterr().err
    assert run(["grooving_4axis", "--program", str(program), "--stock", STOCK, "--tool",
                "v:150", "--max-triangles", str(BUDGET), "--html",
                str(tmp_path / "g.html")]) == 0
    err = capsys.readouterr().err
    assert ("note: numbers without a decimal point (X at line 3) were read in mm and deg "
            "(calculator-type input, the default)") in err, err
    assert "note: the program has no M30 or M02 (its last move is at line 6)" in err, err
    assert "note: the text from line 8 on, after the % that ends the program" in err, err


def test_a_program_view_notes_its_arcs_split_coarser_than_1_nm_as_cut_does(tmp_path, capsys):
    # an arc under a ball end mill is split within 100 nm by default (a tenth of its 1 um
    # facets): machinesim cut notes it, view noted nothing; --chord-nm given, neither does
    program = tmp_path / "arc.nc"
    program.write_text("G90 G21 G17\nG00 X0.2 Y0.4 Z0.1\nG02 X0.6 Y0.4 I0.2 J0. F500.\nM30\n")
    said = ("note: arcs and rotary moves were split into chords within 100 nm, a tenth of the "
            "tool's own facets (--chord-nm sets it; docs/cutting.md)")
    for chord in ((), ("--chord-nm", "100")):
        assert run(["grooving_4axis", "--program", str(program), "--stock", STOCK, "--tool",
                    "ball:0.5", *chord, "--max-triangles", str(BUDGET), "--html",
                    str(tmp_path / "a.html")]) == 0
        err = capsys.readouterr().err
        assert (said in err) == (not chord), err


def test_a_part_with_no_extent_in_x_or_y_is_refused_naming_its_file(tmp_path):
    # a PLY whose triangles all stand in the plane y = 0 was refused as "the part has no
    # extent in x or y: bounds [0.0, 0.0] .. [1.0, 0.0] m", naming no file: in a report
    # folder of several parts, which one?
    sliver = tmp_path / "sliver.ply"
    sliver.write_text("ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\n"
                      "property double y\nproperty double z\nelement face 1\n"
                      "property list uchar int vertex_indices\nend_header\n"
                      "0 0 0\n0.001 0 0\n0 0 0.001\n3 0 1 2\n")
    expected = (f"{sliver}: the part spans x 0 .. 1 mm, y 0 .. 0 mm: expected an extent in "
                "both x and y, a top surface to map")
    with pytest.raises(InputError) as caught:
        run([str(sliver), "--html", str(tmp_path / "x.html")])
    assert str(caught.value) == expected
    folder = tmp_path / "report"
    folder.mkdir()
    stock_from_spec("block:1x1x1").export_ply(folder / "a.ply")
    (folder / "sliver.ply").write_bytes(sliver.read_bytes())
    with pytest.raises(InputError) as caught:
        run([str(folder), "--html", str(tmp_path / "x.html")])
    assert str(caught.value) == expected.replace(str(sliver), str(folder / "sliver.ply"))
    assert not list(tmp_path.glob("*.html"))
