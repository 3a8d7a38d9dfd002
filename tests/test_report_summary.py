"""Report summaries and tables: units in every key, tables in Markdown and JSON, the
summary's schema enforced and versioned, the documented keys, numbers beyond a float and
nesting too deep refused, `read_summary` naming what it cannot read."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

from machinesim.exceptions import InputError
from machinesim.report import ReportFolder, check_summary, check_units


def test_summary_and_tables_round_trip(tmp_path):
    folder = ReportFolder(tmp_path / "out")
    text = folder.write_table("table", ["angle_deg", "depth_um"], [[0, 10.0], [10, 10.25]])
    assert "| angle_deg | depth_um |" in text and "10.250" in text
    assert json.loads((tmp_path / "out" / "table.json").read_text())["rows"][1] == [10, 10.25]
    # SI values a nanometre apart and a std of picometres keep their digits
    text = folder.write_table("si", ["value", "std"], [[-2.250339e-06, 7.2e-12]], digits=6,
                              significant=True)
    assert "| -2.250339e-06 | 7.200000e-12 |" in text
    folder.write_summary({
        "paper": "000", "procedure": "tool_rotation_arm", "machine": "planer_4axis",
        "seed": 3, "noise": True, "injected": {"tool.y": np.float64(-178e-6)},
        "identified": {"tool.y": {"value": -177.9e-6, "std": 1e-9}},
        "figures": [{"name": "depth_error", "unit": "um", "before": np.nan, "after": 0.4,
                     "paper_before": None, "paper_after": None}],
        "details": {"depth_error_um": [np.nan, 60.9]}})
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["injected"]["tool.y"] == -178e-6
    assert summary["figures"][0]["before"] is None
    assert summary["details"]["depth_error_um"] == [None, 60.9]
    assert summary["files"] == ["si.json", "si.md", "summary.json", "table.json", "table.md"]


def test_a_pipe_within_a_table_cell_keeps_the_markdown_row_whole(tmp_path):
    """paper 003's figures.md wrote a note with '|angle between the groove sets - 90 deg|'
    bare: its row had 10 cells under a header of 8. A cell's (and a column's) '|' is '\\|'
    in the Markdown, which reads it as the character; the JSON keeps the text."""
    note = "largest |angle - 90 deg| over\nthe windows"
    text = ReportFolder(tmp_path / "out").write_table("t", ["a_um", "b|c"], [[1.0, note]])
    rows = [line for line in text.splitlines() if line.startswith("|")]
    # a row's cells are what lies between its unescaped pipes: 2 in every row
    assert [len(re.split(r"(?<!\\)\|", row)) - 2 for row in rows] == [2, 2, 2], text
    assert rows[2] == "| 1.000 | largest \\|angle - 90 deg\\| over the windows |"
    assert rows[0] == "| a_um | b\\|c |"
    table = json.loads((tmp_path / "out" / "t.json").read_text())
    assert table == {"columns": ["a_um", "b|c"], "rows": [[1.0, note]]}


def test_the_summary_schema_is_enforced(tmp_path):
    base = {"paper": "001", "procedure": "p", "machine": "m", "seed": 0, "noise": False,
            "injected": {}, "identified": {}, "figures": []}
    figure = {"name": "a_dx", "unit": "um", "before": 490.0, "after": None,
              "paper_before": 490.04, "paper_after": 4.06}
    check_summary(base)
    check_summary({**base, "background": {"file": None, "nonzero_count": 3}})
    for change, message in (({"seed": True}, "'seed' as int"),
                            # the background is a file and a count, not its parameters
                            ({"background": {"location.C.EX0C": 3e-7}}, "'background' as"),
                            ({"background": {"file": None, "nonzero_count": 0}},
                             "nonzero_count"),
                            ({"injected": {"r_mm": 1.0}}, "not an error parameter name"),
                            ({"identified": {"tool.x": 1.0}}, '"value": v'),
                            ({"figures": [{"name": "a"}]}, "lacks unit"),
                            ({"details": {"depth": 1.0}}, "names no unit"),
                            # what the schema says of each value, not only of its key
                            ({"seed": -5}, "seed must be >= 0"),
                            ({"injected": {"tool.x": "big"}}, "must be a finite number"),
                            ({"identified": {"tool.x": {"value": "x", "std": 1e-9}}},
                             "value must be a finite number"),
                            ({"identified": {"tool.x": {"value": 0.0, "std": -1.0}}},
                             "std must be >= 0"),
                            ({"figures": [3]}, r"figures\[0\] must be an object"),
                            ({"figures": [{**figure, "unit": "furlongs"}]},
                             "unit 'furlongs'; expected one of m, mm"),
                            ({"figures": [{**figure, "before": "abc"}]},
                             "before must be a finite number or null"),
                            ({"figures": [{**figure, "after_std": -0.1}]},
                             "after_std must be >= 0"),
                            ({"files": 3}, "'files' as a list of file names"),
                            ({"details": {"depth": [1.0, 2.0]}}, "'details.depth' holds")):
        with pytest.raises(InputError, match=message):
            check_summary({**base, **change})
    with pytest.raises(InputError, match="expected an object, got list"):
        check_summary([])
    check_summary({**base, "figures": [figure], "identified": {
        "tool.x": {"value": 1e-6, "std": None}}, "files": ["summary.json"]})


def test_a_number_without_a_unit_is_refused():
    check_units({"after": {"depth_error_um": 1.0, "rows": [[1, 2]]}, "seed": 1})
    # a key names the unit of what it holds: a list, or an object's numbers
    check_units({"yaw_urad": {"y_mm": [0.0, 20.0], "value": [1.0, 2.0]}})
    with pytest.raises(InputError, match="'after.depths' holds a number"):
        check_units({"after": {"depths": [[1.0], [2.0]]}})
    with pytest.raises(InputError, match="'after.depth' holds a number but names no unit"):
        check_units({"after": {"depth": 1.0}})


def test_every_key_of_the_documented_summary_is_in_the_documented_table():
    """docs/reports.md's summary.json example against its table of keys: `elapsed_s` and
    `files`, in every summary.json, were in the example and missing from the table."""
    import re
    from pathlib import Path

    text = (Path(__file__).parents[1] / "docs" / "reports.md").read_text()
    example = json.loads(re.search(r"## summary.json\n\n```json\n(.*?)\n```", text,
                                   re.DOTALL).group(1))
    table = set()
    for line in text.splitlines():
        first = line.split(" | ")[0]
        if line.startswith("| `") and " | " in line:
            table.update(re.findall(r"`([a-z_]+)`", first))
    assert set(example) <= table, sorted(set(example) - table)


def test_a_summary_number_beyond_a_float_is_refused_and_a_seed_of_any_size_is_written(
        tmp_path):
    # math.isfinite of an int beyond the largest float raised OverflowError: read_summary of
    # a summary.json edited to an after of 1 and 400 zeros ended in a traceback, and so did
    # write_result of a Lab seeded with 2**1100 (a seed numpy takes: an int of any size)
    from toy_procedure import WorkpieceX

    from machinesim import Lab
    from machinesim.experiment import run
    from machinesim.report import read_summary

    seed = 2**1100
    out = tmp_path / "out"
    ReportFolder(out).write_result(run(WorkpieceX(0.5, ()), Lab("robonano_a0ib", noise=False,
                                                                seed=seed)))
    summary = read_summary(out)
    assert summary["seed"] == seed and summary["figures"][0]["after"] == 0.5
    huge = 10**400
    for change, said in (({"figures": [{**summary["figures"][0], "before": huge}]},
                          r"figures\[0\].before must be a finite number or null, got "
                          r"1000000000000000000000000000000000000000\.\.\.000000000000 "
                          r"\(401 characters\)"),
                         ({"injected": {"tool.x": huge}}, r"injected\['tool.x'\] must be a "
                                                          "finite number"),
                         ({"budget": [{"source": "s", "figure": "x", "unit": "um",
                                       "after_all": 0.5, "after_without": 0.4,
                                       "share": huge}]},
                          r"budget\[0\].share must be a finite number")):
        path = tmp_path / "edited.json"
        path.write_text(json.dumps({**summary, **change}))
        with pytest.raises(InputError, match=said):
            read_summary(path)


def test_read_summary_names_a_path_that_is_none_and_a_campaigns_summary(tmp_path):
    # read_summary(None) was "TypeError: expected str, bytes or os.PathLike object", and a
    # campaign folder's summary.json was refused as a damaged report's: "key 'paper':
    # expected 'paper' as str, got None"
    from machinesim.report import read_summary

    for path in (None, 3):
        with pytest.raises(InputError, match="reading a report summary .*expected a file "
                                             "name") as info:
            read_summary(path)
        assert info.value.key == "path"
    campaign = tmp_path / "campaign"
    campaign.mkdir()
    (campaign / "summary.json").write_text(json.dumps(
        {"schema_version": 1, "procedure": "tool_rotation_arm", "seed": 1,
         "trials_count": 3, "failed_count": 0, "figures": {}}))
    for path in (campaign, campaign / "summary.json"):
        with pytest.raises(InputError, match=r"a campaign's summary.json \(machinesim "
                                             r"campaign.*not a scenario report's") as info:
            read_summary(path)
        assert info.value.source == str(campaign / "summary.json")


def test_a_summary_nested_too_deeply_for_its_checks_is_refused_naming_it(tmp_path):
    # lists 500 deep under a key of its own parse (read_json's bound is the parser's), and
    # check_units' recursion ended read_summary in RecursionError
    from machinesim.report import read_summary

    path = tmp_path / "summary.json"
    base = {"schema_version": 1, "paper": "001", "procedure": "p", "machine": "m",
            "seed": 0, "noise": False, "injected": {}, "identified": {}, "figures": []}
    path.write_text(json.dumps(base)[:-1] + ', "extra": ' + "[" * 500 + "]" * 500 + "}")
    with pytest.raises(InputError, match="nested too deeply to be a report summary") as info:
        read_summary(path)
    assert info.value.source == str(path)
    path.write_text(json.dumps(base))
    assert read_summary(path) == base
