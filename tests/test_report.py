"""Report folders: units in every key, tables in Markdown and JSON, whole files."""

from __future__ import annotations

import json

import numpy as np
import pytest

from machinesim.exceptions import InputError
from machinesim.report import ReportFolder, check_summary, check_units, parse_floats


def test_summary_and_tables_round_trip(tmp_path):
    folder = ReportFolder(tmp_path / "out")
    text = folder.write_table("table", ["angle_deg", "depth_um"], [[0, 10.0], [10, 10.25]])
    assert "| angle_deg | depth_um |" in text and "10.250" in text
    assert json.loads((tmp_path / "out" / "table.json").read_text())["rows"][1] == [10, 10.25]
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
    assert summary["files"] == ["summary.json", "table.json", "table.md"]


def test_the_summary_schema_is_enforced(tmp_path):
    base = {"paper": "001", "procedure": "p", "machine": "m", "seed": 0, "noise": False,
            "injected": {}, "identified": {}, "figures": []}
    check_summary(base)
    for change, message in (({"seed": True}, "'seed' as int"),
                            ({"injected": {"r_mm": 1.0}}, "not an error parameter name"),
                            ({"identified": {"tool.x": 1.0}}, '"value": v'),
                            ({"figures": [{"name": "a"}]}, "lacks unit"),
                            ({"details": {"depth": 1.0}}, "names no unit")):
        with pytest.raises(InputError, match=message):
            check_summary({**base, **change})


def test_a_number_without_a_unit_is_refused():
    check_units({"after": {"depth_error_um": 1.0, "rows": [[1, 2]]}, "seed": 1})
    with pytest.raises(InputError, match="'after.depth' holds a number but names no unit"):
        check_units({"after": {"depth": 1.0}})


def test_parse_floats_names_the_option():
    assert parse_floats("1,2.5,-3", 3, "--delta-um") == [1.0, 2.5, -3.0]
    with pytest.raises(InputError, match="--delta-um '1,2': expected 3 comma-separated"):
        parse_floats("1,2", 3, "--delta-um")
