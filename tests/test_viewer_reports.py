"""`machinesim view` of a report folder: its summary's schema version, a nominal it names
that is missing, another part file, a folder not yet written, the figures' table."""

from __future__ import annotations

import json

import pytest
from viewer_helpers import BUDGET, run

from machinesim.exceptions import InputError
from machinesim.workpiece import stock_from_spec


def test_a_report_folders_summary_of_another_schema_version_is_refused(tmp_path):
    # report_scene read summary.json's keys as this version's whatever its schema_version
    # (a newer machinesim's report was shown as if of version 1); read_summary refuses it
    from machinesim.report import read_summary
    from machinesim.viewer import report_scene

    stock_from_spec("block:1x1x1").export_ply(tmp_path / "part.ply")
    summary = tmp_path / "summary.json"
    for version in (1, None):  # none: written before the field, read as version 1
        summary.write_text(json.dumps({"pv_nm": 123.0} if version is None
                                      else {"schema_version": version, "pv_nm": 123.0}))
        assert "pv_nm: 123" in report_scene(tmp_path, BUDGET).notes
    for version, newer in ((2, True), ("1", False), (True, False)):
        summary.write_text(json.dumps({"schema_version": version, "pv_nm": 123.0}))
        with pytest.raises(InputError) as info:
            report_scene(tmp_path, BUDGET)
        with pytest.raises(InputError) as read:
            read_summary(summary)
        assert info.value.key == read.value.key == "schema_version"
        assert info.value.source == str(summary)
        assert info.value.message == read.value.message  # the same check's words
        assert ("written by a newer machinesim" in info.value.message) is newer


def test_a_report_folder_whose_summary_names_a_missing_nominal_is_warned_about(tmp_path):
    # the parts were coloured by height, as if no nominal had been named, without a word
    from machinesim.viewer import report_scene

    stock_from_spec("block:1x1x1").export_ply(tmp_path / "part.ply")
    stock_from_spec("block:1x1x1").export_ply(tmp_path / "nom.ply")
    summary = tmp_path / "summary.json"
    (tmp_path / "sub").mkdir()
    stock_from_spec("block:1x1x1").export_ply(tmp_path / "sub" / "nom.ply")
    # a file, but not one of the folder's parts: "sub/nom.ply" and an absolute path were
    # coloured by height without a word
    for named in ("nominal.ply", ["nom.ply"], "sub/nom.ply", str(tmp_path / "sub" / "nom.ply")):
        summary.write_text(json.dumps({"nominal_ply": named}))
        scene = report_scene(tmp_path, BUDGET)
        assert scene.warnings == [f"{summary} names the nominal part {named!r} (nominal_ply), "
                                  "which is not a file in the folder: each part is coloured "
                                  "by its height, not by its deviation"]
        assert [legend.title for legend in scene.legends] == [
            "nom.ply: height z (workpiece frame)", "part.ply: height z (workpiece frame)"]
    summary.write_text(json.dumps({"nominal_ply": "nom.ply"}))
    scene = report_scene(tmp_path, BUDGET)
    assert scene.warnings == []
    assert [legend.title for legend in scene.legends] == [
        "part.ply: deviation from nominal (height, part - nominal)"]
    # the nominal a folder under a part's name: refused as such a part is, where the parts
    # had been coloured by height without a word
    for name in ("nominal_dir.ply", "nominal.ply"):
        (tmp_path / name).mkdir()
        summary.write_text(json.dumps({"nominal_ply": name} if name != "nominal.ply" else {}))
        with pytest.raises(InputError, match=f"{name}: is a folder; expected a PLY part file"):
            report_scene(tmp_path, BUDGET)
        (tmp_path / name).rmdir()


def test_a_report_of_another_part_file_is_warned_about(tmp_path, capsys):
    # a report from another run was shown beside the part without a word
    stock_from_spec("block:1x1x1").export_ply(tmp_path / "nominal.ply")
    report = tmp_path / "report.json"
    report.write_text(json.dumps({"removed_volume_mm3": 0.026, "part_file": "part.ply",
                                  "part_unit": "m"}))
    assert run([str(tmp_path / "nominal.ply"), "--report", str(report),
                "--html", str(tmp_path / "n.html")]) == 0
    err = capsys.readouterr().err
    assert (f"warning: the report {report} describes the part file 'part.ply', not "
            "nominal.ply: its figures may be of another cut") in err
    assert "gives the part in" not in err
    report.write_text(json.dumps({"part_file": "sub/nominal.stl", "part_unit": "mm"}))
    assert run([str(tmp_path / "nominal.ply"), "--report", str(report),
                "--html", str(tmp_path / "n.html")]) == 0
    err = capsys.readouterr().err
    assert "'sub/nominal.stl', not nominal.ply" in err
    assert f"the report {report} gives the part in 'mm'; a PLY part is read in metres" in err
    report.write_text(json.dumps({"part_file": "sub/nominal.ply", "part_unit": "m"}))
    assert run([str(tmp_path / "nominal.ply"), "--report", str(report),
                "--html", str(tmp_path / "n.html")]) == 0
    assert "warning" not in capsys.readouterr().err


def test_a_report_folder_not_yet_written_is_no_such_folder(tmp_path):
    # docs/viewer.md's `machinesim view reports/tool_rotation_arm/` before the scenario ran
    # said "unknown machine 'reports/tool_rotation_arm/'", as if a machine name were misspelt
    missing = str(tmp_path / "reports" / "tool_rotation_arm") + "/"
    with pytest.raises(InputError) as caught:
        run([missing, "--html", str(tmp_path / "x.html")])
    assert str(caught.value) == (
        f"{missing}: no such file or folder; expected a machine name (see 'machinesim "
        "machines'), a machine's .urdf, a part .ply or a report folder")
    assert not list(tmp_path.glob("*.html"))


def test_a_report_folders_figures_are_a_table_of_name_before_after_and_unit(tmp_path):
    # the overlay showed a summary's figures as one line of raw dicts ("figures: [{'name':
    # 'depth_error', 'unit': 'um', ...}]"), or "figures: [7 entries]", or (past its first
    # 15 entries) not at all: they are now a table above the notes, to 4 digits, null n/a
    from machinesim.viewer import report_scene
    from machinesim.viewer.scene import overlay_html

    stock_from_spec("block:1x1x1").export_ply(tmp_path / "part.ply")
    figures = [
        {"name": "depth_error", "unit": "um", "before": 1.23456789, "after": -0.0123456,
         "paper_before": 1.2, "paper_after": None, "note": "the groove's depth less design"},
        {"name": "edge_distance_planes_L1_L5", "unit": "deg", "before": None, "after": 2e-5,
         "paper_before": None, "paper_after": None},
    ]
    summary = tmp_path / "summary.json"
    summary.write_text(json.dumps({"paper": "001", "figures": figures, "seed": 0}))
    scene = report_scene(tmp_path, BUDGET)
    [table] = scene.tables
    assert table.header == ("figure", "before", "after", "unit")
    assert table.rows == (("depth_error", "1.235", "-0.01235", "um"),
                          ("edge_distance_planes_L1_L5", "n/a", "2e-05", "deg"))
    assert scene.notes == ["paper: 001", "seed: 0"]  # the figures are not a note too
    page = overlay_html(scene)
    assert ("<tr><th>figure</th><th>before</th><th>after</th><th>unit</th></tr>\n"
            "<tr><td>depth_<wbr>error</td><td>1.235</td><td>-0.01235</td><td>um</td></tr>"
            in page)
    assert page.index('class="ms-table"') < page.index("<div>paper: 001</div>")
    assert "{'name'" not in page and "figures:" not in page
    # a 'figures' that is no list of named figures stays a note, as any key
    for odd in ([1, 2], {"a": 1.0}, [{"name": "x"}]):
        summary.write_text(json.dumps({"figures": odd}))
        scene = report_scene(tmp_path, BUDGET)
        assert scene.tables == [] and scene.notes[0].startswith("figures"), scene.notes
