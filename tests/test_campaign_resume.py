"""machinesim.campaign: resuming a campaign in its folder: only the missing trials run, the
trial files' checks (damaged, another trial's, another campaign's, another schema), a stop
while the report is made, the folder's lock and the campaign's identity across spellings of
its distributions.

``campaign`` (tests/conftest.py): paper 000's calibration, 3 trials (``identify_only``).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import machinesim.campaign.runner as runner
from machinesim.campaign import run
from machinesim.exceptions import InputError, MachineSimError

ARM = dict(identify_only=True)


def trials_run(monkeypatch) -> list[int]:
    """The indices of the trials the runner runs from now on, in order (each still run)."""
    ran, real = [], runner.run_trial
    monkeypatch.setattr(runner, "run_trial", lambda spec, i: ran.append(i) or real(spec, i))
    return ran


def test_resume_runs_only_the_missing_trials(campaign, tmp_path, monkeypatch):
    source, vary, ds = campaign
    for name in ("campaign.json", "trials/trial_000000.json", "trials/trial_000002.json"):
        (tmp_path / name).parent.mkdir(exist_ok=True)
        (tmp_path / name).write_bytes((source / name).read_bytes())
    ran = trials_run(monkeypatch)
    again = run("tool_rotation_arm", 3, vary=vary, seed=11, out=tmp_path, workers=0,
                progress=False, report=False, **ARM)
    assert ran == [1]
    for name in ("drawn", "identified", "identified_std", "injected"):
        assert np.array_equal(again[name].values, ds[name].values)


def test_resuming_reads_each_trial_file_once_says_so_and_holds_no_record(
        campaign, tmp_path, monkeypatch, capsys):
    """Resuming read every finished trial file before any trial ran, in silence (0.2 ms a
    file: ~23 s for 100000), and held every record until the Dataset was built (~13 kB
    each of paper 003's: 1.3 GB for 100000); the new trials' files were read back too.
    Now each file is read once, into the Dataset's columns, with a progress line."""
    import gc
    import weakref

    from machinesim.campaign.results import CampaignFolder

    source, vary, ds = campaign
    (tmp_path / "trials").mkdir()
    for name in ("campaign.json", "trials/trial_000000.json", "trials/trial_000002.json"):
        (tmp_path / name).write_bytes((source / name).read_bytes())

    class Record(dict):  # a dict one can hold a weak reference to
        pass

    read, records, real_read = [], [], CampaignFolder.read_trial

    def reading(self, i):
        read.append(i)
        record = Record(real_read(self, i))
        records.append(weakref.ref(record))
        return record

    alive_while_trial_1_ran = []
    real_trial = runner.run_trial

    def trial(spec, i):
        gc.collect()
        alive_while_trial_1_ran.extend(r() is not None for r in records)
        return real_trial(spec, i)

    monkeypatch.setattr(CampaignFolder, "read_trial", reading)
    monkeypatch.setattr(runner, "run_trial", trial)
    # as a log file would show a read of many files: quiet for no time here, not 10 s
    monkeypatch.setattr(runner, "LOG_READ_QUIET_S", 0.0, raising=False)
    again = run("tool_rotation_arm", 3, vary=vary, seed=11, out=tmp_path, workers=0,
                report=False, **ARM)
    assert read == [0, 2]  # trial 1's file is not read back
    assert alive_while_trial_1_ran == [False, False]
    for name in ("drawn", "identified", "identified_std", "injected", "elapsed_s"):
        assert np.array_equal(again[name].values[[0, 2]], ds[name].values[[0, 2]])
    assert np.array_equal(again["identified"].values, ds["identified"].values)
    reading_lines = [line for line in capsys.readouterr().err.splitlines() if "reading" in line]
    trials_path = tmp_path / "trials"
    assert reading_lines == [f"campaign: reading the finished trials in {trials_path}: {k}/2"
                             for k in (1, 2)]


def test_a_smaller_trials_says_which_trial_files_it_leaves_out(campaign, tmp_path, capsys):
    source, vary, ds = campaign
    (tmp_path / "trials").mkdir()
    for name in ("campaign.json", *(f"trials/trial_{i:06d}.json" for i in range(3))):
        (tmp_path / name).write_bytes((source / name).read_bytes())
    # progress=False (--quiet: no progress line) still says so: the summary is of fewer
    # trials than the folder holds (it said nothing under --quiet)
    two = run("tool_rotation_arm", 2, vary=vary, seed=11, out=tmp_path, workers=0,
              report=False, progress=False, **ARM)
    assert two.sizes["trial"] == 2
    assert np.array_equal(two["identified"].values, ds["identified"].values[:2])
    err = capsys.readouterr().err
    assert "holds 1 trial file beyond --trials 2 (from trial 2): left out" in err


def test_a_damaged_trial_file_is_refused_before_the_missing_trials_run(campaign, tmp_path,
                                                                        monkeypatch):
    source, vary, _ = campaign
    (tmp_path / "trials").mkdir()
    for name in ("campaign.json", "trials/trial_000000.json"):
        (tmp_path / name).write_bytes((source / name).read_bytes())
    whole = (source / "trials/trial_000002.json").read_bytes()
    (tmp_path / "trials/trial_000002.json").write_bytes(whole[: len(whole) // 2])
    ran = []
    monkeypatch.setattr(runner, "run_trial", lambda spec, i: ran.append(i))
    with pytest.raises(MachineSimError) as info:
        run("tool_rotation_arm", 3, vary=vary, seed=11, out=tmp_path, workers=0,
            progress=False, report=False, **ARM)
    assert "trial_000002.json" in str(info.value)
    assert ran == []  # trial 1, missing, did not run first


def test_a_trial_file_holding_another_trial_says_what_it_holds(campaign, tmp_path,
                                                                monkeypatch):
    # trial 2's file copied over trial 1's (or a '{}', a list) said "expected the record of
    # trial 1" alone: neither what the file held nor what to do
    source, vary, _ = campaign
    (tmp_path / "trials").mkdir()
    (tmp_path / "campaign.json").write_bytes((source / "campaign.json").read_bytes())
    path = tmp_path / "trials/trial_000001.json"
    ran = []
    monkeypatch.setattr(runner, "run_trial", lambda spec, i: ran.append(i))
    for text, found in (((source / "trials/trial_000002.json").read_text(),
                         "the record of trial 2"),
                        ("{}", "no trial number ('trial')"), ("[1, 2]", "a JSON list"),
                        # true and 1.0 equal 1: a true ended the campaign in numpy's "truth
                        # value of an array ... is ambiguous", a 1.0 was refused naming no file
                        (_with_trial(source / "trials/trial_000001.json", "true"),
                         "the record of trial True"),
                        (_with_trial(source / "trials/trial_000001.json", "1.0"),
                         "the record of trial 1.0")):
        path.write_text(text)
        with pytest.raises(InputError) as info:
            run("tool_rotation_arm", 3, vary=vary, seed=11, out=tmp_path, workers=0,
                progress=False, report=False, **ARM)
        assert str(info.value) == (f"{path}, key 'trial': holds {found}; expected the record "
                                   "of trial 1: delete it and run again to compute the trial "
                                   "anew")
    assert ran == []


def _with_trial(path, number: str) -> str:
    """The trial file ``path``'s text with its trial number written as ``number``."""
    record = json.loads(path.read_text())
    return json.dumps({**record, "trial": "@"}).replace('"@"', number)


#: A number an edited file holds beyond float64 (JSON takes it, float() does not).
_HUGE = 10**400


@pytest.mark.parametrize(("record", "key"), [
    ({"trial": 0}, "drawn"),
    # ints beyond float64 ended the campaign in 'OverflowError: int too large to convert'
    ({"trial": 0, "drawn": {}, "injected": {}, "identified": {}, "figures": {},
      "elapsed_s": _HUGE, "error": None}, "elapsed_s"),
    ({"trial": 0, "drawn": {}, "injected": {"tool.y": -_HUGE}, "identified": {},
      "figures": {}, "elapsed_s": 1.0, "error": None}, "injected"),
    ({"trial": 0, "drawn": {}, "injected": {}, "identified": {"tool.y": [_HUGE, 1.0]},
      "figures": {}, "elapsed_s": 1.0, "error": None}, "identified"),
    # a figure's name becomes hist_NAME.png: a '/' was refused once every trial had run, a
    # NUL ended the campaign in 'ValueError: embedded null byte'
    ({"trial": 0, "drawn": {}, "injected": {}, "identified": {},
      "figures": {"a/b": ["um", 1.0, 0.5]}, "elapsed_s": 1.0, "error": None}, "figures"),
    ({"trial": 0, "drawn": {}, "injected": {}, "identified": {},
      "figures": {"a\x00b": ["um", 1.0, 0.5]}, "elapsed_s": 1.0, "error": None}, "figures"),
    ({"trial": 0, "drawn": {}, "injected": {}, "identified": {"../x": [1.0, 1.0]},
      "figures": {}, "elapsed_s": 1.0, "error": None}, "identified"),
    ({"trial": 0, "drawn": {}, "injected": {}, "identified": {"tool.y": 5e-6},
      "figures": {}, "elapsed_s": 1.0, "error": None}, "identified"),
    ({"trial": 0, "drawn": {}, "injected": {}, "identified": {}, "figures": {},
      "elapsed_s": 1.0, "error": 3}, "error"),
    # a blank message was taken as a failure that names nothing
    ({"trial": 0, "drawn": {}, "injected": {}, "identified": {}, "figures": {},
      "elapsed_s": 1.0, "error": ""}, "error"),
    ({"trial": 0, "drawn": {}, "injected": {}, "identified": {}, "figures": {},
      "elapsed_s": 1.0, "error": " \n"}, "error"),
    ({"trial": 0, "drawn": {}, "injected": {}, "identified": {}, "figures": {},
      "notes": "misfit", "elapsed_s": 1.0, "error": None}, "notes"),
    # a std is a spread: an edited -1 was taken, flipping that trial's z-score
    ({"trial": 0, "drawn": {}, "injected": {}, "identified": {"tool.y": [1e-6, -1e-9]},
      "figures": {}, "elapsed_s": 1.0, "error": None}, "identified"),
    ({"trial": 0, "drawn": {}, "injected": {}, "identified": {},
      "figures": {"depth_error": ["um", 1.0, 0.5, -0.1]}, "elapsed_s": 1.0, "error": None},
     "figures"),
    # a unit no figure has went into the Dataset's figure_unit as it stood
    ({"trial": 0, "drawn": {}, "injected": {}, "identified": {},
      "figures": {"depth_error": ["furlong", 1.0, 0.5]}, "elapsed_s": 1.0, "error": None},
     "figures"),
])
def test_a_trial_file_that_is_json_but_no_trial_record_is_refused_naming_the_key(
        campaign, tmp_path, record, key):
    # valid JSON, the right trial number, not a record: an internal KeyError (or TypeError)
    # while assembling, after the missing trials had run
    source, vary, _ = campaign
    (tmp_path / "trials").mkdir()
    (tmp_path / "campaign.json").write_bytes((source / "campaign.json").read_bytes())
    (tmp_path / "trials/trial_000000.json").write_text(json.dumps(record))
    with pytest.raises(InputError) as info:
        run("tool_rotation_arm", 1, vary=vary, seed=11, out=tmp_path, workers=0,
            progress=False, report=False, **ARM)
    assert "trial_000000.json" in str(info.value) and f"key '{key}'" in str(info.value)


def test_a_trial_file_whose_error_is_blank_is_refused():
    # "" was taken as a failure: the trial counted as failed, its message a blank line in
    # summary.md's "Failed trials"; a failure names what failed
    from machinesim.campaign.results import _check_record

    record = {"trial": 0, "drawn": {}, "injected": {}, "identified": {}, "figures": {},
              "elapsed_s": 1.0}
    _check_record({**record, "error": "InputError: no"}, Path("t.json"), ())
    _check_record({**record, "error": None}, Path("t.json"), ())
    for blank in ("", " \n"):
        with pytest.raises(InputError, match="expected null or the failed trial's message, "
                           "which names what failed") as info:
            _check_record({**record, "error": blank}, Path("t.json"), ())
        assert info.value.key == "error" and info.value.source == "t.json"


@pytest.mark.parametrize(("edit", "said"), [
    (lambda drawn: drawn.pop("tool.y"), "drawn has no value of 'tool.y'"),
    (lambda drawn: drawn.update({"tool.y": None}), "drawn has no value of 'tool.y'"),
    (lambda drawn: drawn.update({"tool.z": 1e-6}),
     "drawn has values of 'tool.z', which the campaign does not vary"),
])
def test_a_trial_file_whose_drawn_is_not_of_the_varied_parameters_is_refused(
        campaign, tmp_path, edit, said):
    # a trial file edited to lack a varied parameter's value (or to hold null) gave that
    # trial a NaN in campaign.nc's drawn, silently, its other numbers kept as a good trial's;
    # one naming a parameter the campaign does not vary was taken, the name dropped
    source, vary, ds = campaign
    (tmp_path / "trials").mkdir()
    for name in ("campaign.json", "trials/trial_000000.json", "trials/trial_000002.json"):
        (tmp_path / name).write_bytes((source / name).read_bytes())
    record = json.loads((source / "trials/trial_000001.json").read_text())
    (tmp_path / "trials/trial_000001.json").write_text(json.dumps(record))
    again = run("tool_rotation_arm", 3, vary=vary, seed=11, out=tmp_path, workers=0,
                progress=False, report=False, **ARM)  # as written: read, the same numbers
    assert np.array_equal(again.drawn.values, ds.drawn.values)
    edit(record["drawn"])
    (tmp_path / "trials/trial_000001.json").write_text(json.dumps(record))
    with pytest.raises(InputError, match=said) as info:
        run("tool_rotation_arm", 3, vary=vary, seed=11, out=tmp_path, workers=0,
            progress=False, report=False, **ARM)
    assert info.value.key == "drawn" and info.value.source.endswith("trial_000001.json")
    assert "(tool.y, microscope.sigma)" in str(info.value)


def test_a_trial_file_nested_too_deeply_is_refused_naming_it(campaign, tmp_path):
    # lists 500 deep under a key added by hand parse (read_json's bound is the parser's),
    # and reading the record back (NaN for null, recursively) ended in RecursionError
    source, vary, _ = campaign
    (tmp_path / "trials").mkdir()
    for name in ("campaign.json", "trials/trial_000000.json", "trials/trial_000002.json"):
        (tmp_path / name).write_bytes((source / name).read_bytes())
    text = (source / "trials/trial_000001.json").read_text().rstrip()
    (tmp_path / "trials/trial_000001.json").write_text(
        text[:-1] + ', "extra": ' + "[" * 500 + "]" * 500 + "}")
    with pytest.raises(InputError, match="nested too deeply to be a trial's record") as info:
        run("tool_rotation_arm", 3, vary=vary, seed=11, out=tmp_path, workers=0,
            progress=False, report=False, **ARM)
    assert info.value.source.endswith("trial_000001.json")


def test_a_campaign_json_that_is_not_an_object_is_refused(tmp_path):
    (tmp_path / "campaign.json").write_text("[]")
    with pytest.raises(InputError) as info:
        run("tool_rotation_arm", 1, seed=11, out=tmp_path, workers=0, progress=False, **ARM)
    assert "campaign.json: []; expected the campaign spec" in str(info.value)


def test_a_stop_while_the_report_is_made_leaves_campaign_nc_and_summary_of_one_run(
        campaign, tmp_path, monkeypatch):
    # extending 2 trials to 3, stopped once the trials are done and the report is being
    # made: campaign.nc was written first, then the summary, so a SIGTERM between them left
    # a campaign.nc of 3 trials beside a summary.json and summary.md of 2
    import machinesim.campaign.summary as summary

    source, vary, _ = campaign
    (tmp_path / "trials").mkdir()
    for name in ("campaign.json", "trials/trial_000000.json", "trials/trial_000001.json"):
        (tmp_path / name).write_bytes((source / name).read_bytes())
    run("tool_rotation_arm", 2, vary=vary, seed=11, out=tmp_path, workers=0, progress=False,
        **ARM)

    def stopped(summary_data):
        raise KeyboardInterrupt

    monkeypatch.setattr(summary, "_markdown", stopped)
    with pytest.raises(KeyboardInterrupt):
        run("tool_rotation_arm", 3, vary=vary, seed=11, out=tmp_path, workers=0,
            progress=False, **ARM)
    with xr.open_dataset(tmp_path / "campaign.nc") as on_disk:
        trials_in_nc = on_disk.sizes["trial"]
    written = json.loads((tmp_path / "summary.json").read_text())
    assert (trials_in_nc, written["trials_count"]) == (2, 2)
    assert (tmp_path / "trials/trial_000002.json").is_file()  # kept for the rerun


def test_trial_files_without_campaign_json_are_not_taken_for_this_campaign(campaign, tmp_path):
    # the trials of seed 11 with campaign.json gone were taken as trials of seed 12: a
    # summary of seed 12 over seed 11's draws
    source, vary, _ = campaign
    (tmp_path / "trials").mkdir()
    (tmp_path / "trials/trial_000000.json").write_bytes(
        (source / "trials/trial_000000.json").read_bytes())
    with pytest.raises(InputError) as info:
        run("tool_rotation_arm", 1, vary=vary, seed=12, out=tmp_path, workers=0,
            progress=False, **ARM)
    assert "holds 1 trial file" in str(info.value) and "no campaign.json" in str(info.value)
    assert not (tmp_path / "campaign.json").exists()


def test_a_trial_file_of_another_campaign_is_refused_naming_it(campaign, tmp_path,
                                                                 monkeypatch):
    """A trial file held no campaign's identity: seed 11's trial_000001.json copied into a
    seed 12 folder was taken as seed 12's trial 1 (its draws, its identification)."""
    from machinesim.campaign.results import campaign_id

    source, vary, ds = campaign
    stored = json.loads((source / "campaign.json").read_text())
    record = json.loads((source / "trials/trial_000001.json").read_text())
    assert record["campaign"] == campaign_id(stored) == campaign_id(dict(reversed(
        stored.items())))  # of the spec's values, not its keys' order
    assert campaign_id({**stored, "seed": 12}) != record["campaign"]
    run("tool_rotation_arm", 1, vary=vary, seed=12, out=tmp_path, workers=0, progress=False,
        report=False, **ARM)
    (tmp_path / "trials/trial_000001.json").write_bytes(
        (source / "trials/trial_000001.json").read_bytes())
    ran = trials_run(monkeypatch)
    with pytest.raises(InputError) as info:
        run("tool_rotation_arm", 2, vary=vary, seed=12, out=tmp_path, workers=0,
            progress=False, report=False, **ARM)
    message = str(info.value)
    assert "trial_000001.json" in message and "of another campaign" in message
    assert record["campaign"] in message and ran == []
    # a file written before trial files held the identity is the folder's, as before
    (tmp_path / "trials/trial_000001.json").unlink()
    for name in ("campaign.json", "trials/trial_000000.json", "trials/trial_000001.json"):
        (tmp_path / "old" / name).parent.mkdir(parents=True, exist_ok=True)
        old = json.loads((source / name).read_text())
        old.pop("campaign", None)
        (tmp_path / "old" / name).write_text(json.dumps(old))
    again = run("tool_rotation_arm", 2, vary=vary, seed=11, out=tmp_path / "old", workers=0,
                progress=False, report=False, **ARM)
    assert ran == [] and np.array_equal(again["identified"].values,
                                        ds["identified"].values[:2])


def test_a_scenario_report_folder_is_refused_not_written_over(tmp_path):
    # a campaign given a scenario's report folder wrote its summary.json and summary.md over
    # the scenario's, and trials/ and campaign.nc among its files
    report = {"summary.json": '{"paper": "000"}', "figures.md": "| figure |"}
    for name, text in report.items():
        (tmp_path / name).write_text(text)
    with pytest.raises(InputError) as info:
        run("tool_rotation_arm", 1, seed=11, out=tmp_path, workers=0, progress=False, **ARM)
    assert "holds figures.md, summary.json but no campaign.json" in str(info.value)
    assert {p.name: p.read_text() for p in tmp_path.iterdir()} == report


def test_another_campaign_in_the_same_folder_is_refused(campaign):
    out, vary, _ = campaign
    with pytest.raises(InputError) as info:
        run("tool_rotation_arm", 3, vary=vary, seed=12, out=out, workers=0, progress=False,
            **ARM)
    assert "seed: 11 there, 12 now" in str(info.value) and str(out) in str(info.value)


def test_a_distribution_spelt_otherwise_resumes_the_same_campaign(campaign, tmp_path,
                                                                    monkeypatch):
    # --vary texts were compared as text: normal:-0.178mm,0.02mm for normal:-178um,20um was
    # refused as another campaign ("holds another campaign (vary: ... there, ... now)")
    source, vary, ds = campaign
    (tmp_path / "trials").mkdir()
    for name in ("campaign.json", "trials/trial_000000.json", "trials/trial_000001.json"):
        (tmp_path / name).write_bytes((source / name).read_bytes())
    stored = (tmp_path / "campaign.json").read_text()
    ran = trials_run(monkeypatch)
    spelt = ["tool.y=normal:-0.178mm,0.02mm", "microscope.sigma = uniform:5 nm,0.06um"]
    again = run("tool_rotation_arm", 3, vary=spelt, seed=11, out=tmp_path, workers=0,
                progress=False, report=False, **ARM)
    assert ran == [2]
    # trial 2 drew from the texts the campaign began with, in their order: 0.06um is 6e-08
    # and 60nm 6.000000000000001e-08 in floats, and trial 2's sigma from the new text
    # 3.846127131519505e-08, not 3.8461271315195055e-08
    for name in ("drawn", "identified", "identified_std", "injected"):
        assert np.array_equal(again[name].values, ds[name].values), name
    assert (tmp_path / "campaign.json").read_text() == stored
    assert json.loads(again.attrs["vary"]) == json.loads(stored)["vary"]
    # given in another order, the Dataset keeps the campaign's order (no trial runs)
    flipped = run("tool_rotation_arm", 3, vary=spelt[::-1], seed=11, out=tmp_path,
                  workers=0, progress=False, report=False, **ARM)
    assert list(flipped["varied"].values) == ["tool.y", "microscope.sigma"]
    assert np.array_equal(flipped["drawn"].values, ds["drawn"].values)
    # another distribution is still another campaign, both shown
    with pytest.raises(InputError) as info:
        run("tool_rotation_arm", 3, vary=["tool.y=normal:-0.178mm,0.021mm", spelt[1]],
            seed=11, out=tmp_path, workers=0, progress=False, report=False, **ARM)
    assert "'normal:-178um,20um'" in str(info.value)
    assert "'normal:-0.178mm,0.021mm'" in str(info.value)
    assert ran == [2]


@pytest.mark.parametrize(("now", "same"), [
    ({"tool.y": "fixed:0.01 mm"}, True),
    ({"tool.y": "1e-5m"}, True),
    ({"tool.y": "10.001um"}, False),
    ({"tool.y": "normal:10um,1nm"}, False),
    ({"tool.y": "10um", "tool.z": "0"}, False),
])
def test_same_campaign_compares_distributions_by_meaning(now, same):
    from machinesim.campaign.results import same_campaign

    old = {"procedure": "tool_rotation_arm", "seed": 1, "vary": {"tool.y": "10um"}}
    assert same_campaign(old, {**old, "vary": now}) is same
    assert same_campaign(old, {**old, "seed": 2}) is False
    assert same_campaign({**old, "vary": {"tool.y": "10 furlong"}}, {**old, "vary": now}) \
        is False


def test_a_lock_removed_by_a_stopped_run_is_not_taken(tmp_path, monkeypatch):
    """A run that opened the lock file before the run holding it was stopped (and removed
    it) takes the folder's lock file, not the removed one: two runs would have held two
    files, each its own 'lock'."""
    import os

    from machinesim.campaign import lock

    real_same, calls = lock._same_file, []

    def removed_once(fd, path):  # the file open is unlinked just after the flock
        calls.append(path)
        if len(calls) == 1:
            path.unlink()
        return real_same(fd, path)

    monkeypatch.setattr(lock, "_same_file", removed_once)
    with lock.locked(tmp_path):
        assert lock._lock_holder(tmp_path / "campaign.lock")[0] == os.getpid()
    assert len(calls) == 2


def test_trial_files_and_the_summary_carry_their_schema_version(campaign, tmp_path,
                                                                 monkeypatch):
    # neither a trial file nor the campaign's summary.json said which version of its
    # record it held: a file of another one was read as this one's
    from machinesim.campaign.results import TRIAL_SCHEMA_VERSION
    from machinesim.campaign.summary import SCHEMA_VERSION

    source, vary, _ = campaign
    assert TRIAL_SCHEMA_VERSION == SCHEMA_VERSION == 1
    text = (source / "trials/trial_000000.json").read_text()
    assert text.startswith('{\n  "schema_version": 1,\n')
    assert (source / "summary.json").read_text().startswith('{\n  "schema_version": 1,\n')
    (tmp_path / "trials").mkdir()
    for name in ("campaign.json", "trials/trial_000001.json", "trials/trial_000002.json"):
        (tmp_path / name).write_bytes((source / name).read_bytes())
    record = json.loads(text)
    path = tmp_path / "trials/trial_000000.json"
    monkeypatch.setattr(runner, "run_trial", lambda spec, i: pytest.fail("a trial ran"))
    for version, said in ((2, "schema_version 2; this machinesim reads trial files of schema "
                              "version 1 (written by a newer machinesim? update this one, or "
                              "run the campaign into another --out)"),
                          ("1", "schema_version '1'; this machinesim reads trial files of "
                                "schema version 1")):
        path.write_text(json.dumps({**record, "schema_version": version}))
        with pytest.raises(InputError) as info:
            run("tool_rotation_arm", 3, vary=vary, seed=11, out=tmp_path, workers=0,
                progress=False, report=False, **ARM)
        assert str(info.value) == f"{path}, key 'schema_version': {said}"
    # a file written before the field: read as version 1, the same record
    path.write_text(json.dumps({k: v for k, v in record.items() if k != "schema_version"}))
    ds = run("tool_rotation_arm", 3, vary=vary, seed=11, out=tmp_path, workers=0,
             progress=False, report=False, **ARM)
    assert ds["identified"].equals(campaign[2]["identified"])
