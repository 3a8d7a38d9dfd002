"""A report folder written by the Python API (`write_result`): whole or not at all, a second
result replacing the first, file and folder names, and the figures and budgets it refuses."""

from __future__ import annotations

import json
import re
from argparse import Namespace

import numpy as np
import pytest
from report_helpers import _siblings, _snapshot

from machinesim.exceptions import InputError
from machinesim.report import ReportFolder, check_summary
from machinesim.scenario_runs import scenario_status


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


def test_write_result_refuses_a_folder_whose_summary_json_is_no_reports(tmp_path):
    # a folder holding only a summary.json of the user's own (no list of files) was
    # replaced by the report, the file lost
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "summary.json").write_text('{"my": "own"}')
    with pytest.raises(InputError, match=r"report folder .*: holds a summary.json that is no "
                                         r"report's \(it lists no files under 'files'"):
        ReportFolder(mine).write_result(_toy_result())
    assert _snapshot(mine) == {"summary.json": b'{"my": "own"}'} and _siblings(mine) == []


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


@pytest.mark.parametrize("value", ["1.23", b"1", True, np.True_])
def test_a_figure_given_as_text_or_a_flag_is_refused_naming_it(value):
    # Figure("x", "um", "1.23", ...) was read as 1.23 and True as 1.0: a table row formatted
    # to text, or a comparison's outcome, went into the report as a measurement
    from machinesim.experiment import Figure

    for field in ("before", "after", "paper_before", "paper_after", "after_std"):
        with pytest.raises(InputError, match=rf"Expected x\.{field} as a number or None, "
                                             rf"got {re.escape(repr(value))}") as info:
            Figure("x", "um", **{"before": 1.0, "after": 0.5, field: value})
        assert info.value.key == f"x.{field}"
    assert Figure("x", "count", np.int64(3), 2).before == 3.0  # numbers of any kind pass


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
