"""A campaign's report (summary.json, summary.md, plots) over trials whose records are made
here (`runner.run_trial` replaced), so that what the report must say follows from them by
hand; no procedure runs."""

from __future__ import annotations

import json

import machinesim.campaign.runner as runner
from machinesim.campaign import run

RUN = dict(workers=0, progress=False)


def _record(i, error=None):
    """Trial i's record: a figure and an identified parameter, or a failure with ``error``."""
    if error is not None:
        return {"trial": i, "drawn": {}, "injected": {}, "identified": {}, "figures": {},
                "notes": [], "elapsed_s": 0.0, "error": error}
    return {"trial": i, "drawn": {}, "injected": {"tool.y": 1e-6},
            "identified": {"tool.y": [1e-6 + 1e-9 * i, 2e-9]},
            "figures": {"depth_error": ["um", 50.0 + i, 0.1 * i]},
            "notes": [], "elapsed_s": 0.0, "error": None}


def test_a_shorter_summary_leaves_no_plot_of_the_longer_one(tmp_path, monkeypatch):
    """Trial 0 fails, 1 and 2 run: the report of 3 trials has a histogram and z-scores. The
    same campaign summarised again with --trials 1 (its one trial failed) has neither, and
    their files of the 3 trials stayed beside it, unlisted in its summary.json: a
    z_scores.png of trials 1 and 2 next to a summary whose every trial failed."""
    monkeypatch.setattr(runner, "run_trial", lambda spec, i: _record(
        i, "InputError: the probe missed the sphere" if i == 0 else None))
    run("tool_rotation_arm", 3, out=tmp_path, identify_only=True, **RUN)
    first = json.loads((tmp_path / "summary.json").read_text())["files"]
    assert {"hist_depth_error.png", "z_scores.png"} <= set(first)

    run("tool_rotation_arm", 1, out=tmp_path, identify_only=True, **RUN)
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["failed_count"] == 1 and summary["trials_count"] == 1
    assert summary["files"] == ["campaign.nc", "summary.json", "summary.md"]
    made = {"campaign.json", "campaign.lock", "trials"}
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted({*summary["files"], *made})

    run("tool_rotation_arm", 3, out=tmp_path, identify_only=True, **RUN)  # extended again
    assert json.loads((tmp_path / "summary.json").read_text())["files"] == first
    assert {"hist_depth_error.png", "z_scores.png"} <= {p.name for p in tmp_path.iterdir()}


def test_a_file_of_ones_own_beside_the_report_is_left_alone(tmp_path, monkeypatch):
    """Only what the earlier summary.json listed goes: a plot of one's own stays."""
    monkeypatch.setattr(runner, "run_trial", lambda spec, i: _record(i))
    run("tool_rotation_arm", 2, out=tmp_path, identify_only=True, **RUN)
    (tmp_path / "hist_mine.png").write_bytes(b"not the campaign's")
    monkeypatch.setattr(runner, "run_trial", lambda spec, i: _record(i, "InputError: x"))
    (tmp_path / "trials" / "trial_000000.json").unlink()
    run("tool_rotation_arm", 1, out=tmp_path, identify_only=True, **RUN)
    assert (tmp_path / "hist_mine.png").read_bytes() == b"not the campaign's"
    assert not (tmp_path / "z_scores.png").exists()


def _missed(height_m):
    return ("InputError: key 'centre': Expected the scans through [-0.006, -0.006, "
            f"{height_m!r}] m to touch the sphere at 20 of 41 points or more, they did not")


def test_failures_that_differ_only_in_their_numbers_are_one(tmp_path, monkeypatch, capsys):
    """Trials 0, 1 and 3 fail as the probe misses its sphere, each at its own height; 2 ends
    in another error. summary.md listed four messages of one trial each and the command
    said the most common message was one trial's: the missed sphere is one failure of
    three trials, shown with trial 0's numbers."""
    from machinesim.cli import main as cli_main

    messages = {0: _missed(2.889850000000456e-04), 1: _missed(2.3864000000066313e-05),
                2: "InputError: key 'tool.y': a tool offset of [0.0, 1000.0, 0.0] mm",
                3: _missed(-1.5e-06)}
    monkeypatch.setattr(runner, "run_trial", lambda spec, i: _record(i, messages[i]))
    status = cli_main(["campaign", "tool_rotation_arm", "--trials", "4", "--workers", "0",
                       "--identify-only", "--quiet", "--out", str(tmp_path)])
    assert status == 1
    err = capsys.readouterr().err
    assert f"the most common message (3 of them): {messages[0]} (summary.md" in err
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["failures"] == [{"message": messages[0], "trials": [0, 1, 3]},
                                   {"message": messages[2], "trials": [2]}]
    text = (tmp_path / "summary.md").read_text()
    assert f"- 3 trials (0, 1, 3): {messages[0]}\n- 1 trial (2): {messages[2]}\n" in text


def test_a_message_kind_keeps_an_entrys_index_and_a_words_digits():
    from machinesim.campaign.summary import message_kind

    assert message_kind("component.X.EXX[2] of 1.5e-3 mm in trial_000002.json, [1, -2.5]") \
        == "component.X.EXX[2] of # mm in trial_000002.json, [#, #]"


def test_the_heading_counts_one_trial_as_one(tmp_path, monkeypatch):
    """summary.md of a one-trial campaign began '# Campaign: ..., 1 trials'."""
    monkeypatch.setattr(runner, "run_trial", lambda spec, i: _record(i))
    run("tool_rotation_arm", 1, out=tmp_path, identify_only=True, **RUN)
    heading = (tmp_path / "summary.md").read_text().splitlines()[0]
    assert heading == "# Campaign: tool_rotation_arm, 1 trial (seed 0, 0 failed)"
    run("tool_rotation_arm", 2, out=tmp_path, identify_only=True, **RUN)
    heading = (tmp_path / "summary.md").read_text().splitlines()[0]
    assert heading == "# Campaign: tool_rotation_arm, 2 trials (seed 0, 0 failed)"


def test_a_trial_file_named_otherwise_is_no_trials(tmp_path, monkeypatch):
    """trials/trial_1.json (a copy renamed by hand) counted as trial 1 done: with
    trial_000001.json gone the campaign stopped on 'trial_000001.json: no such file' and
    never ran trial 1; with both there, on 'trial 1; expected each of the records ...
    once', naming neither file. It is no trial's file: trial 1 runs and is written as
    trial_000001.json; trial_1.json is left as it is."""
    ran = []
    monkeypatch.setattr(runner, "run_trial", lambda spec, i: ran.append(i) or _record(i))
    run("tool_rotation_arm", 2, out=tmp_path, identify_only=True, **RUN)
    trials = tmp_path / "trials"
    (trials / "trial_000001.json").rename(trials / "trial_1.json")
    run("tool_rotation_arm", 2, out=tmp_path, identify_only=True, **RUN)
    assert ran == [0, 1, 1]
    (trials / "trial_1.json").write_bytes((trials / "trial_000001.json").read_bytes())
    ds = run("tool_rotation_arm", 2, out=tmp_path, identify_only=True, **RUN)
    assert ran == [0, 1, 1] and ds.sizes["trial"] == 2
    assert sorted(p.name for p in trials.iterdir()) == [
        "trial_000000.json", "trial_000001.json", "trial_1.json"]


def test_trials_without_campaign_json_are_refused_whatever_their_names(tmp_path):
    """A trials/ folder without campaign.json holding trial_1.json is refused as one with
    trial_000001.json is, naming it."""
    import pytest

    from machinesim.exceptions import InputError

    (tmp_path / "trials").mkdir()
    (tmp_path / "trials" / "trial_1.json").write_text("{}")
    with pytest.raises(InputError, match=r"holds trials/trial_1\.json but no campaign\.json"):
        run("tool_rotation_arm", 1, out=tmp_path, identify_only=True, **RUN)


def test_a_campaign_nc_written_without_a_report_has_no_earlier_one_beside_it(
        tmp_path, monkeypatch):
    """run(report=False) after a report of 2 trials wrote campaign.nc of 3 and left
    summary.json (trials_count 2, its files naming that campaign.nc), summary.md and the
    plots of the 2: a summary beside a campaign.nc it is not of."""
    import xarray as xr

    monkeypatch.setattr(runner, "run_trial", lambda spec, i: _record(i))
    run("tool_rotation_arm", 2, out=tmp_path, identify_only=True, **RUN)
    assert (tmp_path / "summary.json").is_file() and (tmp_path / "z_scores.png").is_file()
    (tmp_path / "notes.txt").write_text("mine")
    run("tool_rotation_arm", 3, out=tmp_path, identify_only=True, report=False, **RUN)
    with xr.open_dataset(tmp_path / "campaign.nc") as on_disk:
        assert on_disk.sizes["trial"] == 3
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "campaign.json", "campaign.lock", "campaign.nc", "notes.txt", "trials"]


def test_figures_near_float64s_end_are_summarised_without_overflow(tmp_path):
    """An after of 1e308 in each of three trials (a trial file edited, or a procedure's
    figure): its sum overflowed, numpy warned 'overflow encountered in reduce', the mean and
    std were null, and the histogram ended the campaign in 'Too many bins for data range'
    (as did an equal after of 1e17: numpy's bin of +-0.5 around it is none). Now mean 1e308
    and std 0 (three equal values), no warning, the report written; 1, 2, 3 as before
    (mean 2, std 1)."""
    import warnings

    import pytest

    from machinesim.campaign.results import assemble
    from machinesim.campaign.summary import write_report

    spec = {"procedure": "tool_rotation_arm", "seed": 0, "vary": {}, "noise": True,
            "identify_only": False}
    for k, (afters, mean, std) in enumerate([((1e308,) * 3, 1e308, 0.0),
                                             ((1e17,) * 3, 1e17, 0.0),
                                             ((-1e308, 1.0, 1e308), 0.0, 1e308),
                                             ((1.0, 2.0, 3.0), 2.0, 1.0)]):
        records = [{**_record(t), "figures": {"depth_error": ["um", 50.0, after]},
                    "identified": {"tool.y": [after * 1e-12, 2e-9]}}
                   for t, after in enumerate(afters)]
        (tmp_path / str(k)).mkdir()
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            summary = write_report(assemble(records, spec, 3), tmp_path / str(k))
        after = summary["figures"]["depth_error"]["after"]
        assert after["count"] == 3 and after["mean"] == pytest.approx(mean, abs=1e-300)
        assert after["std"] == pytest.approx(std, rel=1e-15)
        assert (tmp_path / str(k) / "hist_depth_error.png").stat().st_size > 0
        assert (tmp_path / str(k) / "z_scores.png").stat().st_size > 0
