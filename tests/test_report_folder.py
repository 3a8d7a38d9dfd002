"""A scenario's report folder written whole: staged and published at once, the previous
report kept when a run is stopped, fails or fills the disk, tables and budgets written
both or neither, folders it must not replace refused; the scenario's options."""

from __future__ import annotations

import contextlib
import json
import math
import os
import subprocess
import sys
from argparse import Namespace

import pytest
from report_helpers import _siblings, _snapshot

from machinesim._arguments import typed_number
from machinesim._io import process_space
from machinesim._staged import StagedFolder, clear_stale_folders
from machinesim.exceptions import InputError
from machinesim.report import ReportFolder
from machinesim.scenario_runs import (
    jobs_option,
    parse_floats,
    scenario_arguments,
    scenario_status,
)


def test_parse_floats_names_the_option():
    assert parse_floats("1,2.5,-3", 3, "--delta-um") == [1.0, 2.5, -3.0]
    with pytest.raises(InputError, match="--delta-um '1,2': expected 3 comma-separated"):
        parse_floats("1,2", 3, "--delta-um")
    # float() read '0_5' as 5 and full-width digits as digits: --tool-offset-um 0_5,0,0 ran
    # with dx = 5 um, exit 0
    assert parse_floats(" 1, -2e1 ,+.5", 3, "--delta-um") == [1.0, -20.0, 0.5]
    for text in ("0_5,0,0", "\uff11,0,0", "1,2,3_0"):
        with pytest.raises(InputError) as refused:
            parse_floats(text, 3, "--delta-um")
        assert str(refused.value) == (f"--delta-um {text!r}: expected 3 comma-separated "
                                      "finite numbers (ASCII digits, a point, an exponent: "
                                      "250,-3.5e2,0)")


def test_a_scenarios_number_options_take_numbers_as_typed(capsys):
    # --r-mm 0_5 ran an arm of 5 mm (float() reads the underscore as a digit separator),
    # --r-mm with full-width digits ran 120 mm, --seed 1_0 ran seed 10, --jobs with a
    # full-width 2 ran two workers: each without a word
    parser = scenario_arguments("a scenario", "reports/x")
    parser.add_argument("--r-mm", type=typed_number)
    jobs_option(parser)
    args = parser.parse_args(["--r-mm", "1.2e2", "--seed", "+7", "--jobs", "2"])
    assert (args.r_mm, args.seed, args.jobs) == (120.0, 7, 2)
    assert parser.parse_args(["--r-mm", "inf"]).r_mm == float("inf")  # the scenario's check
    for option, text, expected in (
            ("--r-mm", "0_5", "expected a number (ASCII digits, a point, an exponent: "
             "120.555, -1.78e2), got '0_5'"),
            ("--r-mm", "\uff11\uff12\uff10", "expected a number (ASCII digits, a point, "
             "an exponent: 120.555, -1.78e2), got '\uff11\uff12\uff10'"),
            ("--seed", "1_0", "expected a non-negative integer, got '1_0'"),
            ("--seed", "\uff13", "expected a non-negative integer, got '\uff13'"),
            ("--jobs", "\uff12", "'\uff12': expected a whole number of worker processes, 1 or "
             "more"),
            # int() refuses more digits than its limit: "invalid _seed value: '1000...'"
            ("--seed", "1" + "0" * sys.get_int_max_str_digits(), "expected a whole number "
             f"of at most {sys.get_int_max_str_digits()} digits (Python's limit), got one of "
             f"{sys.get_int_max_str_digits() + 1} digits")):
        with pytest.raises(SystemExit) as stop:
            parser.parse_args([option, text])
        assert stop.value.code == 2
        assert capsys.readouterr().err.splitlines()[-1] == (
            f"{parser.prog}: error: argument {option}: {expected}")


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
    # the parent made for it goes too: a failed --out new/report left new/, empty
    assert not out.exists() and not out.parent.exists()
    assert scenario_status(_report({"a.md": "a\n"}, stop_after=0), Namespace(out=out)) == 130
    assert not out.exists() and not out.parent.exists()
    out.parent.mkdir()  # a parent that was there stays
    assert scenario_status(failing, Namespace(out=out), "s") == 2
    assert sorted(os.listdir(out.parent)) == [] and out.parent.is_dir()


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
    # a summary.json of the user's own (not JSON, or no list of files) was taken for a
    # report's: alone in the folder it was replaced without a word, and beside a report's
    # files the refusal said "does not list" of a file it could not read
    for content, message in (({"notes.txt": "mine"}, "holds files (notes.txt) but no summary.json"),
                             ({"summary.json": '{"files": ["summary.json"]}',
                               "notes.txt": "mine"},
                              "holds files its summary.json does not list (notes.txt)"),
                             ({"summary.json": "[]"}, "holds a summary.json that is no "
                              "report's (it lists no files under 'files', as a report's "
                              "does), so it is not a report folder"),
                             ({"summary.json": '{"files": ["a', "a.md": "a"},
                              "holds a summary.json that is no report's (it is not JSON: "
                              "Unterminated string starting at: line 1 column 12 (char 11))")):
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


def test_a_report_folder_name_too_long_for_the_file_system_is_refused_naming_out(
        tmp_path, capsys):
    # --out with a 300-character name printed "s: error: /abs/path/xxx...: File name too
    # long" (an OSError of the folder's stat), naming neither --out nor what was expected
    limit = os.pathconf(tmp_path, "PC_NAME_MAX")
    for out in (tmp_path / ("x" * (limit + 1)), tmp_path / ("y" * (limit + 1)) / "report"):
        assert scenario_status(_report({"a.md": "a\n"}), Namespace(out=out), "s") == 2
        assert capsys.readouterr().err == (
            f"s: error: key 'out': --out {str(out)!r}: cannot make the report folder there "
            "(File name too long); expected a folder, or a path where one can be made\n")
    assert os.listdir(tmp_path) == []


def test_a_report_folder_that_is_a_symbolic_link_loop_is_refused_as_one(tmp_path, capsys):
    # --out loop (a link to itself) was refused as "a file is there", which ls belies
    out = tmp_path / "loop"
    out.symlink_to("loop")
    assert scenario_status(_report({"a.md": "a\n"}), Namespace(out=out), "s") == 2
    assert capsys.readouterr().err == (
        f"s: error: key 'out': --out {str(out)!r}: cannot make the report folder there (it "
        "cannot be reached: too many levels of symbolic links (a loop)); expected a folder, "
        "or a path where one can be made\n")
    assert os.listdir(tmp_path) == ["loop"]


def test_a_scenarios_errors_file_that_cannot_be_read_is_named_as_the_option(tmp_path):
    # "nope.toml: cannot read the file: No such file or directory" named no option, where
    # machinesim cut names --errors
    from machinesim import load_machine
    from machinesim.scenario_runs import errors_file

    machine = load_machine("grooving_4axis")
    missing = tmp_path / "nope.toml"
    with pytest.raises(InputError) as info:
        errors_file(missing, machine)
    assert str(info.value) == f"{missing}: no such file; expected the error model (--errors)"
    with pytest.raises(InputError) as info:
        errors_file(tmp_path, machine)
    assert str(info.value) == (f"{tmp_path}: is a folder; expected the error model (--errors) "
                               "file")


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
    # '-inf' and '-nan' too, for the option's check to name them: "--e-ys-um -inf" and
    # "--tool-offset-um -inf,0,0" ended in "expected one argument"
    assert parser.parse_args(["--e-ys-um", "-inf"]).e_ys_um == -math.inf
    assert math.isnan(parser.parse_args(["--e-ys-um", "-NaN"]).e_ys_um)
    assert parser.parse_args(["--c-offset-um", "-Infinity,0"]).c_offset_um == "-Infinity,0"
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


def test_a_reader_that_stops_reading_stdout_and_stderr_does_not_cost_the_report(tmp_path):
    """``scenario ... 2>&1 | head -1``: the next progress line on stderr met the closed pipe
    and ended the run in status 2, with no report and no line (stderr was the pipe). Now
    stderr goes to the null device as stdout does, and the report is written whole, exit
    0; and the same with stderr a full disk (``2>/dev/full``)."""
    script = PRINTING_REPORT.replace('print("table row", k)',
                                     'print("progress", k, file=sys.stderr, flush=True)')
    assert script != PRINTING_REPORT
    out = tmp_path / "report"
    child = subprocess.Popen([sys.executable, "-c", script, str(out)],
                             stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    assert child.stdout.readline() == "progress 0\n"
    child.stdout.close()  # as head does after its line
    assert child.wait(timeout=120) == 0
    assert (out / "a.md").read_text() == "a\n"
    assert json.loads((out / "summary.json").read_text())["files"] == ["a.md", "summary.json"]
    if os.path.exists("/dev/full"):
        full_out = tmp_path / "full"
        with open("/dev/full", "w") as full:
            assert subprocess.run([sys.executable, "-c", script, str(full_out)],
                                  stderr=full, timeout=120, check=False).returncode == 0
        assert (full_out / "a.md").read_text() == "a\n"


def test_a_run_started_with_stdout_closed_writes_its_report(tmp_path, capsys, monkeypatch):
    """``scenario ... >&-``: Python's sys.stdout is None, and the first print ended in
    "AttributeError: 'NoneType' object has no attribute 'write'" (then 'flush') with two
    tracebacks, exit 1, no report. Now the report is written whole, exit 0, one line."""
    out = tmp_path / "report"
    monkeypatch.setattr(sys, "stdout", None)
    assert scenario_status(_report({"a.md": "a\n"}), Namespace(out=out), "s") == 0
    assert sys.stdout is None  # as it was
    monkeypatch.undo()
    assert capsys.readouterr().err == (
        "s: stdout was closed when the run began (no file descriptor 1); this run's report "
        f"was written whole to {str(out)!r}\n")
    assert json.loads((out / "summary.json").read_text())["files"] == ["a.md", "summary.json"]


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


def test_a_scenario_shows_a_machinesim_warning_as_one_line(tmp_path, capsys):
    # Python's own form named the warning's source line in machinesim and printed it
    # ('/.../experiment.py:180: MachineSimWarning: ...'), where the command lines print one
    # 'machinesim: warning:' line
    import warnings

    from machinesim.exceptions import MachineSimWarning

    def report(args):
        warnings.warn("case_4: 40% of the measured line reads the stock's top",
                      MachineSimWarning, stacklevel=2)

    assert scenario_status(report, Namespace(out=None), "s") == 0
    err = capsys.readouterr().err
    assert err == ("machinesim: warning: case_4: 40% of the measured line reads the stock's "
                   "top\n")
