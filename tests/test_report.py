"""Report folders: units in every key, tables in Markdown and JSON, whole files."""

from __future__ import annotations

import contextlib
import json
import os
import subprocess
import sys
from argparse import Namespace

import numpy as np
import pytest

from machinesim._io import process_space
from machinesim._staged import StagedFolder, clear_stale_folders
from machinesim.exceptions import InputError
from machinesim.report import ReportFolder, check_summary, check_units
from machinesim.scenario_runs import (
    parse_floats,
    scenario_arguments,
    scenario_status,
)


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


def test_parse_floats_names_the_option():
    assert parse_floats("1,2.5,-3", 3, "--delta-um") == [1.0, 2.5, -3.0]
    with pytest.raises(InputError, match="--delta-um '1,2': expected 3 comma-separated"):
        parse_floats("1,2", 3, "--delta-um")


# ------------------------------------------------------------- a report folder written whole


def _snapshot(folder):
    return {p.relative_to(folder).as_posix(): p.read_bytes()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def _report(files, stop_after=None):
    """A scenario's ``report(args)`` writing ``files`` (name -> text) into ``args.out`` through
    `ReportFolder`, then summary.json; with ``stop_after``, Ctrl-C after that many files."""
    def report(args):
        folder = ReportFolder(args.out)
        for k, (name, text) in enumerate(files.items()):
            if k == stop_after:
                raise KeyboardInterrupt
            folder.write_text(name, text)
        folder.write_summary({"paper": "000", "procedure": "p", "machine": "m", "seed": 0,
                              "noise": False, "injected": {}, "identified": {},
                              "figures": []})
        folder.publish(last=True)
        print(f"Report written to {folder.final}")
    return report


def _siblings(folder):
    return sorted(p.name for p in folder.parent.iterdir() if p != folder)


@contextlib.contextmanager
def _disk_full_at(name):
    """Within it, staging a file called ``name`` (`machinesim._io._stage`) fails as a full
    disk does (ENOSPC); other files are staged as ever."""
    import errno

    from machinesim import _io

    real = _io._stage

    def full(path, raw):
        if path.name == name:
            raise OSError(errno.ENOSPC, "No space left on device", str(path))
        return real(path, raw)

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(_io, "_stage", full)
        yield


def test_a_rerun_stopped_midway_leaves_the_previous_report_whole(tmp_path, capsys):
    out = tmp_path / "report"
    first = {"a.md": "first a\n", "b.md": "first b\n", "only_first.md": "first\n"}
    assert scenario_status(_report(first), Namespace(out=out), "s") == 0
    assert f"Report written to {out}" in capsys.readouterr().out
    before = _snapshot(out)
    assert sorted(before) == ["a.md", "b.md", "only_first.md", "summary.json"]

    second = {"a.md": "second a\n", "b.md": "second b\n", "c.md": "second c\n"}
    status = scenario_status(_report(second, stop_after=2), Namespace(out=out), "s")
    err = capsys.readouterr().err
    assert status == 130
    assert err.strip() == (f"s: interrupted; this run's report was not written: {str(out)!r} "
                           "is as it was before (the previous report, whole, or nothing)")
    assert _snapshot(out) == before  # byte for byte the first run's, a.md and b.md included
    assert _siblings(out) == []  # no staging folder left

    # a run that ends replaces the folder whole: nothing of the first run stays
    assert scenario_status(_report(second), Namespace(out=out), "s") == 0
    after = _snapshot(out)
    assert sorted(after) == ["a.md", "b.md", "c.md", "summary.json"]
    assert after["a.md"] == b"second a\n"
    assert json.loads(after["summary.json"])["files"] == ["a.md", "b.md", "c.md",
                                                          "summary.json"]
    assert _siblings(out) == []


def test_an_error_midway_leaves_the_previous_report_and_no_folder_is_made(tmp_path, capsys):
    out = tmp_path / "new" / "report"

    def failing(args):
        ReportFolder(args.out).write_text("a.md", "a\n")
        raise InputError("bad value")

    assert scenario_status(failing, Namespace(out=out), "s") == 2
    assert capsys.readouterr().err.strip() == "s: error: bad value"
    assert not out.exists() and _siblings(out) == []
    assert scenario_status(_report({"a.md": "a\n"}, stop_after=0), Namespace(out=out)) == 130
    assert not out.exists() and _siblings(out) == []


def test_a_published_report_survives_an_interrupt_of_what_follows(tmp_path, capsys):
    """Paper 002 publishes its report before its budget's reruns: stopped there, the folder
    holds that report whole, without the budget's files."""
    out = tmp_path / "report"

    def report(args):
        folder = ReportFolder(args.out)
        folder.write_text("table.md", "table\n")
        folder.publish()
        folder.write_text("budget.md", "budget\n")
        raise KeyboardInterrupt

    assert scenario_status(report, Namespace(out=out), "s") == 130
    assert "holds this run's report as written whole" in capsys.readouterr().err
    assert _snapshot(out) == {"table.md": b"table\n"} and _siblings(out) == []


def test_a_stale_staging_folder_of_a_killed_run_is_removed(tmp_path):
    out = tmp_path / "report"
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True).stdout.strip()
    stale = tmp_path / f".report.partial-{dead}@{process_space()}.0badf00d"
    stale.mkdir()
    (stale / "half.ply").write_text("half")
    # killed in the middle of a swap: the previous report aside, none under the name
    aside = tmp_path / f".report.old-{dead}@{process_space()}.0badf00d"
    aside.mkdir()
    (aside / "summary.json").write_text('{"files": ["summary.json"]}')
    clear_stale_folders(out)
    assert _siblings(out) == [] and sorted(p.name for p in out.iterdir()) == ["summary.json"]
    stale.mkdir()
    assert scenario_status(_report({"a.md": "a\n"}), Namespace(out=out)) == 0
    assert _siblings(out) == [] and (out / "a.md").read_text() == "a\n"


def test_a_report_folder_that_is_the_working_directory_is_refused_before_the_run(
        tmp_path, monkeypatch, capsys):
    """``scenario --out .`` in an empty folder swapped the working directory out and removed
    it, then ended in a FileNotFoundError traceback (exit 1), the shell standing in the
    removed folder; a report folder holding the working directory is refused alike."""
    from pathlib import Path

    out = tmp_path / "report"
    out.mkdir()
    monkeypatch.chdir(out)
    ran = []
    for given in (Path("."), Path(str(out))):
        assert scenario_status(lambda args: ran.append(1), Namespace(out=given), "s") == 2
        err = capsys.readouterr().err
        assert err.strip() == (
            f"s: error: key 'out': {str(given)!r} is the working directory ({str(out)!r}); "
            "the report replaces its folder whole, which would remove the folder this "
            "command and its shell stand in: expected a folder apart from it, e.g. --out "
            "report"), err
    assert ran == [] and os.getcwd() == str(out) and list(out.iterdir()) == []
    assert _siblings(out) == []
    # in Python too, and for a folder that holds the working directory
    (out / "sub").mkdir()
    monkeypatch.chdir(out / "sub")
    with pytest.raises(InputError, match=r"'\.\.' holds the working directory") as info:
        StagedFolder("..")
    assert info.value.key == "out" and [p.name for p in out.iterdir()] == ["sub"]
    # a folder beside it is written as before
    assert scenario_status(_report({"a.md": "a\n"}), Namespace(out=Path("../r")), "s") == 0
    assert (tmp_path / "report" / "r" / "a.md").read_text() == "a\n"


def test_another_hosts_live_staging_folder_is_left_alone(tmp_path, monkeypatch):
    """A report folder shared with another host (NFS) or container: its live run's staging
    folder carries a PID that is no process here, and was removed as a killed run's."""
    import socket

    out = tmp_path / "report"
    ended = subprocess.Popen([sys.executable, "-c", "pass"])
    ended.wait()
    with monkeypatch.context() as other_host:  # the other host's run begins its report
        other_host.setattr(socket, "gethostname", lambda: "another-host")
        other_host.setattr(os, "getpid", lambda: ended.pid)
        theirs = StagedFolder(out)
    (theirs.path / "half.ply").write_text("being written")
    clear_stale_folders(out)
    assert (theirs.path / "half.ply").read_text() == "being written"


def test_a_folder_that_is_not_a_report_is_refused_not_replaced(tmp_path, capsys):
    for content, message in (({"notes.txt": "mine"}, "holds files (notes.txt) but no summary.json"),
                             ({"summary.json": '{"files": ["summary.json"]}',
                               "notes.txt": "mine"},
                              "holds files its summary.json does not list (notes.txt)")):
        out = tmp_path / "report"
        out.mkdir()
        for name, text in content.items():
            (out / name).write_text(text)
        assert scenario_status(_report({"a.md": "a\n"}), Namespace(out=out), "s") == 2
        err = capsys.readouterr().err
        assert len(err.splitlines()) == 1 and f"--out {str(out)!r}: " in err, err
        assert message in err, err
        assert {n: t.encode() for n, t in content.items()} == _snapshot(out)
        assert _siblings(out) == []
        for path in out.iterdir():
            path.unlink()
        out.rmdir()


def test_a_scenario_names_a_misspelt_option_with_the_one_meant(capsys):
    parser = scenario_arguments("a scenario", "reports/x")
    with pytest.raises(SystemExit) as stop:
        parser.parse_args(["--sede", "3", "--out", "somewhere"])
    assert stop.value.code == 2
    assert capsys.readouterr().err.splitlines()[-1].endswith(
        "unrecognized arguments: --sede 3; --sede is not an option here; did you mean --seed?")


def test_an_option_takes_a_value_list_that_starts_with_a_minus_sign(capsys):
    # argparse takes '-707,-707' or '-1e3' for an option (only '-178' looks like a number to
    # it): "--c-offset-um -707,-707" ended in "expected one argument"
    parser = scenario_arguments("a scenario", "reports/x")
    parser.add_argument("--c-offset-um")
    parser.add_argument("--e-ys-um", type=float)
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args(["--c-offset-um", "-707,-707", "--e-ys-um", "-1e3", "--quick",
                              "--seed", "3"])
    assert (args.c_offset_um, args.e_ys_um, args.quick, args.seed) == ("-707,-707", -1000.0,
                                                                        True, 3)
    assert parser.parse_args(["--e-ys-um", "-.5"]).e_ys_um == -0.5
    # a flag's next word is not its value, and a value refused is refused as before
    with pytest.raises(SystemExit):
        parser.parse_args(["--quick", "-5"])
    with pytest.raises(SystemExit):
        parser.parse_args(["--seed", "-3"])
    assert "--seed: expected a non-negative integer, got '-3'" in capsys.readouterr().err


PRINTING_REPORT = """
import sys
from argparse import Namespace
from machinesim.report import ReportFolder
from machinesim.scenario_runs import scenario_status

def report(args):
    folder = ReportFolder(args.out)
    for k in range(20000):  # far more than a pipe holds (64 KiB)
        print("table row", k)
    folder.write_text("a.md", "a\\n")
    folder.write_summary({"paper": "000", "procedure": "p", "machine": "m", "seed": 0,
                          "noise": False, "injected": {}, "identified": {}, "figures": []})

sys.exit(scenario_status(report, Namespace(out=sys.argv[1]), "s"))
"""


def test_a_reader_that_stops_reading_stdout_does_not_cost_the_report(tmp_path):
    """``scenario ... | head -1``: the report folder is written whole, exit 0, one line on
    stderr saying so (it was lost with 'error: Broken pipe', exit 2)."""
    out = tmp_path / "report"
    child = subprocess.Popen([sys.executable, "-c", PRINTING_REPORT, str(out)],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert child.stdout.readline() == "table row 0\n"
    child.stdout.close()  # as head does after its line
    err = child.stderr.read()
    assert child.wait(timeout=120) == 0, err
    assert "Traceback" not in err and len(err.splitlines()) == 1, err
    assert "stdout was closed early" in err and "written whole" in err, err
    assert (out / "a.md").read_text() == "a\n"
    assert json.loads((out / "summary.json").read_text())["files"]


def test_a_full_disk_names_the_file_as_in_the_report_and_says_the_old_report_is_kept(
        tmp_path, capsys):
    """A write that fails midway (disk full) named the staging folder's file, removed on the
    way out, and not what became of the previous report."""
    import errno

    out = tmp_path / "report"
    assert scenario_status(_report({"a.md": "a\n"}), Namespace(out=out), "s") == 0
    kept = _snapshot(out)
    capsys.readouterr()

    def full(args):
        folder = ReportFolder(args.out)
        folder.write_text("a.md", "b\n")
        raise OSError(errno.ENOSPC, "No space left on device", str(folder.path / "plot.png"))

    assert scenario_status(full, Namespace(out=out), "s") == 2
    assert capsys.readouterr().err.strip() == (
        f"s: error: {out / 'plot.png'}: No space left on device; this run's report was not "
        f"written: {str(out)!r} is as it was before (the previous report, whole, or nothing)")
    assert _snapshot(out) == kept and _siblings(out) == []


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


# ------------------------------------------------- a report folder written by the Python API


def _toy_result(parts=("before", "after"), after=0.5):
    """A result of a toy procedure on a noise-free lab: one figure, the given parts."""
    from toy_procedure import WorkpieceX

    from machinesim import Lab
    from machinesim.experiment import run

    return run(WorkpieceX(after, parts), Lab("robonano_a0ib", noise=False))


def test_write_result_outside_a_scenario_writes_the_folder_whole_or_not_at_all(
        tmp_path, monkeypatch):
    # A new user's ReportFolder(DIR).write_result(result), DIR holding an older report of
    # other parts and a notes.txt of their own, left both beside the new report: its
    # summary.json's "files" (documented as exactly the folder's files) listed neither; and
    # a Ctrl-C between two of its files left new tables beside the old summary.json
    out = tmp_path / "out"
    ReportFolder(out).write_result(_toy_result(parts=("old_a", "old_b")))
    (out / "notes.txt").write_text("mine\n")
    before = _snapshot(out)
    with pytest.raises(InputError, match=r"report folder .*: holds files its summary.json "
                                         r"does not list \(notes.txt\)") as info:
        ReportFolder(out).write_result(_toy_result())
    assert info.value.key == "out" and _snapshot(out) == before
    (out / "notes.txt").unlink()
    previous = _snapshot(out)
    # stopped between two files: the folder is the previous report, byte for byte
    calls = []

    def stop_at_the_second_part(self, name, part):
        calls.append(name)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return write_part(self, name, part)

    write_part = ReportFolder.write_part
    monkeypatch.setattr(ReportFolder, "write_part", stop_at_the_second_part)
    with pytest.raises(KeyboardInterrupt):
        ReportFolder(out).write_result(_toy_result())
    monkeypatch.setattr(ReportFolder, "write_part", write_part)
    assert _snapshot(out) == previous and _siblings(out) == []
    # written: exactly the new report's files, as its summary lists them
    folder = ReportFolder(out)
    folder.write_text("extra.md", "written through the folder before the result\n")
    folder.write_result(_toy_result())
    listed = json.loads((out / "summary.json").read_text())["files"]
    assert sorted(p.name for p in out.iterdir()) == listed == [
        "after.ply", "before.ply", "extra.md", "figures.json", "figures.md",
        "identified.json", "identified.md", "summary.json"]
    assert _siblings(out) == []
    # a budget added later, by another ReportFolder of the folder, keeps the report's files
    from machinesim.budget import Budget, BudgetRow

    report = _snapshot(out)
    ReportFolder(out).add_budget(_toy_result(), Budget((BudgetRow("s", "x", "um", 0.5, 0.3,
                                                                  0.64),)))
    listed = json.loads((out / "summary.json").read_text())["files"]
    assert sorted(p.name for p in out.iterdir()) == listed == sorted(
        [*report, "budget.md", "budget.png"])
    assert all(_snapshot(out)[name] == report[name] for name in report if name != "summary.json")


def test_a_second_result_through_one_folder_replaces_the_first_report_whole(tmp_path):
    # folder.write_result(first); folder.write_result(second) left the first's parts
    # (old_a.ply, old_b.ply) beside the second's report, and its summary.json listed them as
    # the second's. Now the folder is what ReportFolder(path).write_result(second) makes,
    # with what was written through the folder besides the results: since the first
    # (notes.md), and before it (extra.md, which had gone too: a file the user wrote,
    # deleted by a later result without a word)
    from machinesim.budget import Budget, BudgetRow

    first, second = _toy_result(parts=("old_a", "old_b")), _toy_result(parts=("new",))
    budget = Budget((BudgetRow("s", "x", "um", 0.5, 0.3, 0.64),))
    fresh = ReportFolder(tmp_path / "fresh")
    fresh.write_text("extra.md", "before the first result\n")
    fresh.write_text("notes.md", "this run\n")
    fresh.write_result(second)
    expected = _snapshot(tmp_path / "fresh")
    assert sorted(expected) == ["extra.md", "figures.json", "figures.md", "identified.json",
                                "identified.md", "new.ply", "notes.md", "summary.json"]
    for with_budget in (False, True):
        out = tmp_path / f"out_{with_budget}"
        folder = ReportFolder(out)
        folder.write_text("extra.md", "before the first result\n")
        folder.write_result(first)
        if with_budget:
            folder.write_text("notes.md", "between the result and its budget\n")
            folder.add_budget(first, budget)
            assert (out / "budget.png").is_file()
        folder.write_text("notes.md", "this run\n")
        folder.write_result(second)
        assert _snapshot(out) == expected, with_budget
        assert json.loads((out / "summary.json").read_text())["files"] == sorted(expected)
    # inside a scenario (a staged folder) alike
    def report(args):
        folder = ReportFolder(args.out)
        folder.write_text("extra.md", "before the first result\n")
        folder.write_result(first)
        folder.publish()
        folder.write_text("notes.md", "this run\n")
        folder.write_result(second)
        folder.publish(last=True)

    staged = tmp_path / "staged"
    assert scenario_status(report, Namespace(out=staged), "s") == 0
    assert _snapshot(staged) == expected
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fresh", "out_False", "out_True",
                                                          "staged"]  # no staging folder left


def test_a_report_file_name_stays_in_its_folder_and_a_result_is_a_result(tmp_path):
    folder = ReportFolder(tmp_path / "out")
    for name in ("../escape.json", "sub/x.json", "", ".", "..", "/tmp/x.json"):
        with pytest.raises(InputError, match=r"report file name .*: expected a file name "
                                             r"within the report folder"):
            folder.write_json(name, {"depth_um": 1.0})
    assert not (tmp_path / "escape.json").exists() and folder.files == []
    for wrong in (None, {"paper": "000"}):
        with pytest.raises(InputError, match=r"Expected a machinesim.experiment.Result "
                                             r"\(experiment.run\(procedure, lab\)\), got"):
            folder.write_result(wrong)
    with pytest.raises(InputError, match=r"Expected the report folder as a path, got None"):
        ReportFolder(None)


def test_a_report_folder_of_a_script_is_named_as_the_script_gave_it_not_as_an_option(tmp_path):
    # ReportFolder("afile") from a script of one's own said "--out 'afile': cannot make
    # the report folder there", naming an option the script's user never typed
    (tmp_path / "afile").write_text("x")
    for path in (tmp_path / "afile", tmp_path / "afile" / "sub"):
        with pytest.raises(InputError, match=r"report folder '.*afile.*': cannot make the "
                                             r"report folder there") as info:
            ReportFolder(path)
        assert "--out" not in str(info.value) and info.value.key == "out"


def test_two_figures_of_one_name_are_refused(tmp_path):
    # a result held 'x' in um and 'x' in nm: summary.json listed both, Result.figure('x')
    # gave the first and a campaign's trial record (name -> values) kept the second alone
    from toy_procedure import WorkpieceX

    from machinesim import Lab
    from machinesim.experiment import Evaluation, Figure, run

    class TwoX(WorkpieceX):
        def evaluate(self, lab, identified, programs):
            return Evaluation((Figure("x", "um", 1.0, 0.5), Figure("y", "um", 1.0, 0.5),
                               Figure("x", "nm", 1000.0, 2.0)))

    with pytest.raises(InputError, match=r"Result.figures: figures 0 and 2 are both named "
                                         r"'x' \(um, nm\); expected each figure once"):
        run(TwoX(), Lab("robonano_a0ib", noise=False))
    figure = {"name": "x", "unit": "um", "before": 1.0, "after": 0.5, "paper_before": None,
              "paper_after": None}
    base = {"paper": "001", "procedure": "p", "machine": "m", "seed": 0, "noise": False,
            "injected": {}, "identified": {}}
    check_summary({**base, "figures": [figure, {**figure, "name": "y"}]})
    with pytest.raises(InputError, match=r"figures\[1\] is named 'x', as figures\[0\] is"):
        ReportFolder(tmp_path / "out").write_summary(
            {**base, "figures": [figure, {**figure, "unit": "nm"}]})
    assert not (tmp_path / "out" / "summary.json").exists()


def test_a_result_of_a_lab_seeded_with_a_seed_sequence_writes_its_report(tmp_path):
    # a campaign's trial 2 of seed 5 replayed (its lab seeded SeedSequence(5, spawn_key=(2,)),
    # docs/campaigns.md): the Result took the seed, its report was refused, "summary.json:
    # expected 'seed' as int, got SeedSequence(...)", and nothing written
    from toy_procedure import WorkpieceX

    from machinesim import Lab
    from machinesim.experiment import run

    for sequence, key in ((np.random.SeedSequence(5).spawn(3)[2], [2]),
                          (np.random.SeedSequence(5), None)):
        result = run(WorkpieceX(0.5), Lab("robonano_a0ib", noise=False, seed=sequence))
        out = tmp_path / str(key)
        ReportFolder(out).write_result(result)
        summary = json.loads((out / "summary.json").read_text())
        assert summary["seed"] == 5 and summary.get("spawn_key") == key
        again = np.random.SeedSequence(summary["seed"],
                                       spawn_key=tuple(summary.get("spawn_key", ())))
        assert np.array_equal(again.generate_state(4), sequence.generate_state(4))
        check_summary(summary)
    base = {"paper": "001", "procedure": "p", "machine": "m", "seed": 0, "noise": False,
            "injected": {}, "identified": {}, "figures": []}
    with pytest.raises(InputError, match=r"'spawn_key' as a list of ints >= 0, got \[-1\]"):
        check_summary({**base, "spawn_key": [-1]})


def test_a_budget_of_figures_the_result_has_not_or_in_another_unit_is_refused(tmp_path):
    # the toy's figure is x in um: a budget giving x in nm, or a_dx, was written beside it,
    # one summary.json holding x in um and x in nm
    from machinesim.budget import Budget

    result = _toy_result(parts=())
    row = {"source": "instrument_noise", "figure": "x", "unit": "um", "after_all": 0.5,
           "after_without": 0.4, "share": 0.36}
    for change, message in (({"unit": "nm"}, r"figure 'x' in nm, the summary's figures in "
                                             r"um; expected the budget of this run's figures"),
                            ({"figure": "a_dx"}, r"figure 'a_dx' in um, the summary's figures "
                                                 r"none of that name \(its figures: x\)")):
        out = tmp_path / change.get("figure", "x")
        with pytest.raises(InputError, match=r"budget\[0\] gives " + message):
            ReportFolder(out).write_result(result, budget=Budget.from_dict([{**row, **change}]))
        assert not out.exists() or not any(out.iterdir())
    ReportFolder(tmp_path / "right").write_result(result, budget=Budget.from_dict([row]))
    summary = json.loads((tmp_path / "right" / "summary.json").read_text())
    assert summary["budget"] == [row]


def test_an_infinite_figure_is_refused_naming_it_not_written_as_not_measured(tmp_path):
    # an infinite figure was kept as None and written as null, which summary.json's schema
    # reads as "not measured": a reading that diverged passed as one never taken
    from machinesim.experiment import Figure

    for field in ("before", "after", "paper_before", "paper_after", "after_std"):
        for value in (np.inf, -np.inf):
            with pytest.raises(InputError, match=rf"figure x\.{field}: -?inf; expected a "
                                                 r"finite number, or None \(NaN\)") as info:
                Figure("x", "um", **{"before": 1.0, "after": 0.5, field: value})
            assert info.value.key == f"x.{field}"
    assert Figure("x", "um", np.nan, 0.5).before is None  # NaN: not measured, as documented
    with pytest.raises(InputError, match=r"figure x\.after: inf"):
        _toy_result(parts=(), after=np.inf)
    # a summary built by hand, or any other infinite number, is refused when written, naming
    # its key, and nothing is written
    base = {"paper": "001", "procedure": "p", "machine": "m", "seed": 0, "noise": False,
            "injected": {}, "identified": {}}
    figure = {"name": "a_dx", "unit": "um", "before": 1.0, "after": np.inf,
              "paper_before": None, "paper_after": None}
    out = tmp_path / "out"
    with pytest.raises(InputError, match=r"figures\[0\]\.after must be a finite number or "
                                         r"null, got inf"):
        ReportFolder(out).write_summary({**base, "figures": [figure]})
    with pytest.raises(InputError, match=r"identified\['tool.x'\]\.std must be a finite "
                                         r"number or null, got inf"):
        ReportFolder(out).write_summary({**base, "figures": [], "identified": {
            "tool.x": {"value": 1e-6, "std": np.inf}}})
    with pytest.raises(Exception, match=r"details\.gap_um = -inf"):
        ReportFolder(out).write_summary({**base, "figures": [], "details": {"gap_um": -np.inf}})
    with pytest.raises(Exception, match=r"rows\[0\]\[1\] = inf"):
        ReportFolder(out).write_table("t", ["a_um", "b_um"], [[1.0, np.inf]])
    assert sorted(p.name for p in out.iterdir()) == []  # neither t.md nor t.json
    summary = {**base, "figures": [{**figure, "after": np.nan}]}
    ReportFolder(out).write_summary(summary)
    assert json.loads((out / "summary.json").read_text())["figures"][0]["after"] is None


def test_summary_json_carries_its_schema_version_and_a_reader_checks_it(tmp_path):
    # summary.json had no version: a reader could not tell a file of another schema
    from machinesim.report import SCHEMA_VERSION, read_summary

    out = tmp_path / "out"
    ReportFolder(out).write_result(_toy_result(parts=()))
    text = (out / "summary.json").read_text()
    assert SCHEMA_VERSION == 1 and text.startswith('{\n  "schema_version": 1,\n')
    summary = read_summary(out)
    assert summary == json.loads(text) and read_summary(out / "summary.json") == summary
    # a file written before the field: read as version 1 (its only change since)
    older = {k: v for k, v in summary.items() if k != "schema_version"}
    (tmp_path / "old.json").write_text(json.dumps(older))
    assert read_summary(tmp_path / "old.json") == older
    for version, said in ((2, r"schema_version 2; this machinesim reads schema version 1 "
                              r"\(docs/reports.md\) \(written by a newer machinesim\?"),
                          ("1", r"schema_version '1'; this machinesim reads schema version 1"),
                          (True, r"schema_version True; this machinesim reads"),
                          (0, r"schema_version 0; this machinesim reads schema version 1 "
                              r"\(docs/reports.md\)$")):
        path = tmp_path / f"v{version}.json"
        path.write_text(json.dumps({**summary, "schema_version": version}))
        with pytest.raises(InputError, match=said) as info:
            read_summary(path)
        assert info.value.source == str(path) and info.value.key == "schema_version"
        with pytest.raises(InputError, match=said):
            check_summary({**summary, "schema_version": version})
    edited = tmp_path / "edited.json"
    edited.write_text(json.dumps({**summary, "seed": -1}))
    with pytest.raises(InputError, match=r"edited.json, key 'seed': seed must be >= 0, got -1"):
        read_summary(edited)


def test_a_budget_whose_after_is_not_the_results_is_refused_naming_both(tmp_path):
    # a budget of another run of the same figure names and units (another seed) was written
    # beside this run's figures: its "after, all on" 0.6 beside the figure's after 0.5
    from machinesim.budget import Budget

    result = _toy_result(parts=())  # figure x: after 0.5 um
    row = {"source": "instrument_noise", "figure": "x", "unit": "um", "after_all": 0.5,
           "after_without": 0.4, "share": 0.36}
    said = (r"budget\[0\] \(instrument_noise\) gives figure 'x' an after of 0.6 um with every "
            r"source on, the summary's figure an after of 0.5; expected the budget of this "
            r"run \(another run's")
    for how in ("write_result", "add_budget"):
        out = tmp_path / how
        if how == "add_budget":
            ReportFolder(out).write_result(result)
        before = sorted((p.name, p.read_bytes()) for p in out.iterdir()) if out.exists() else []
        wrong = Budget.from_dict([{**row, "after_all": 0.6}])
        with pytest.raises(InputError, match=said) as info:
            if how == "add_budget":
                ReportFolder(out).add_budget(result, wrong)
            else:
                ReportFolder(out).write_result(result, budget=wrong)
        assert info.value.key == "budget"
        after = sorted((p.name, p.read_bytes()) for p in out.iterdir()) if out.exists() else []
        assert after == before  # nothing written
    # exact: the last bit differs, the budget is another run's
    with pytest.raises(InputError, match=r"an after of 0.5000000000000001 um"):
        ReportFolder(tmp_path / "bit").write_result(
            result, budget=Budget.from_dict([{**row, "after_all": 0.5000000000000001}]))
    summary = {**result.summary(), "budget": [row]}
    check_summary(summary)
    unmeasured = {**summary, "figures": [{**summary["figures"][0], "after": None}]}
    with pytest.raises(InputError, match=r"the summary's figure an after of none \(not "
                                         r"measured\)"):
        check_summary(unmeasured)
    ReportFolder(tmp_path / "right").add_budget(result, Budget.from_dict([row]))
    assert json.loads((tmp_path / "right" / "summary.json").read_text())["budget"] == [row]


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


def test_a_tables_markdown_and_json_are_written_both_or_neither(tmp_path):
    # written one after the other, a full disk at name.json left the new name.md beside the
    # old name.json: one table's two files telling two different tables
    from machinesim.exceptions import MachineSimError

    out = ReportFolder(tmp_path / "out")
    out.write_table("t", ["depth_um"], [[1.0]])
    before = _snapshot(tmp_path / "out")
    with _disk_full_at("t.json"), pytest.raises(MachineSimError,
                                                match="No space left on device"):
        out.write_table("t", ["depth_um"], [[2.0]])
    assert _snapshot(tmp_path / "out") == before and _siblings(tmp_path / "out") == []
    out.write_table("t", ["depth_um"], [[2.0]])
    assert json.loads((tmp_path / "out/t.json").read_text())["rows"] == [[2.0]]
    assert "| 2.000 |" in (tmp_path / "out/t.md").read_text()


def test_a_budgets_table_and_plot_are_written_both_or_neither(tmp_path):
    # write_budget wrote budget.md, then the plot: a full disk at the plot left the new
    # table beside the old plot
    from machinesim.budget import Budget
    from machinesim.exceptions import MachineSimError

    row = {"source": "s", "figure": "x", "unit": "um", "after_all": 0.5,
           "after_without": 0.3, "share": 0.64}
    out = ReportFolder(tmp_path / "out")
    out.write_budget(Budget.from_dict([row]))
    before = _snapshot(tmp_path / "out")
    assert sorted(before) == ["budget.md", "budget.png"]
    other = Budget.from_dict([{**row, "after_without": 0.4, "share": 0.36}])
    with _disk_full_at("budget.png"), pytest.raises(MachineSimError,
                                                    match="No space left on device"):
        out.write_budget(other)
    assert _snapshot(tmp_path / "out") == before and _siblings(tmp_path / "out") == []
    out.write_budget(other)
    assert "36" in (tmp_path / "out/budget.md").read_text()
    assert (tmp_path / "out/budget.png").read_bytes() != before["budget.png"]


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
