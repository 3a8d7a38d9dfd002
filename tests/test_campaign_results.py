"""machinesim.campaign: what its trials give and what the campaign makes of them: the draws
found by the identification, in any order, campaign.nc, summary.json and summary.md (units,
spreads, notes, failed trials), the histograms.

Trials run paper 000's calibration alone (``identify_only``: ~1.5 s each), a few per test;
``campaign`` (tests/conftest.py) is one of 3 trials, shared with test_campaign_resume.py.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from machinesim.campaign import CampaignSpec, parse_vary, run, run_trial
from machinesim.campaign.trials import PROCEDURES
from machinesim.cli import main as cli_main
from machinesim.exceptions import InputError

UM = 1e-6
ARM = dict(identify_only=True)
EXAMPLE_ERRORS = Path(__file__).resolve().parents[1] / "models" / "errors" / "example.toml"


def test_trial_draws_reach_the_lab_and_identification_finds_them(campaign):
    _, _, ds = campaign
    assert not ds["failed"].values.any()
    drawn_y = ds["drawn"].sel(varied="tool.y").values
    assert np.array_equal(ds["injected"].sel(parameter="tool.y").values, drawn_y)
    error = ds["identified"] - ds["injected"]
    # microscope noise of at most 60 nm: e_ys found within a few hundred nm
    assert float(abs(error.sel(parameter="tool.y")).max()) < 0.5 * UM


def test_shuffled_order_and_foreign_global_seeding_change_nothing(campaign):
    _, vary, ds = campaign
    spec = CampaignSpec("tool_rotation_arm", 3, tuple(parse_vary(v) for v in vary), seed=11,
                        **ARM)
    for i in (2, 0):  # another order, and numpy's global RNG (the legacy one) disturbed
        np.random.seed(1000 + i)  # noqa: NPY002 (the legacy global state is the point)
        np.random.standard_normal(7)  # noqa: NPY002
        record = run_trial(spec, i)
        assert [record["identified"][p][0] for p in ("tool.y", "tool.z")] == \
            list(ds["identified"].sel(trial=i).values)
        assert [record["identified"][p][1] for p in ("tool.y", "tool.z")] == \
            list(ds["identified_std"].sel(trial=i).values)


def test_dataset_file_holds_the_trials_seed_and_versions(campaign):
    out, vary, ds = campaign
    on_disk = xr.open_dataset(out / "campaign.nc").load()
    for name in ("drawn", "injected", "identified", "identified_std"):
        assert np.array_equal(on_disk[name].values, ds[name].values)
    assert on_disk.attrs["seed"] == 11
    assert on_disk["parameter_unit"].values.tolist() == ["m", "m"]  # tool.y, tool.z
    assert on_disk["varied_unit"].values.tolist() == ["m", "m"]  # tool.y, microscope.sigma
    assert set(json.loads(on_disk.attrs["versions"])) >= {"machinesim", "numpy", "dask"}
    summary = json.loads((out / "summary.json").read_text())
    assert summary["trials_count"] == 3 and "z_scores.png" in summary["files"]
    assert (out / "z_scores.png").stat().st_size > 1000


def test_a_seed_beyond_32_bits_is_kept_whole_in_campaign_nc_and_the_summary(tmp_path):
    # netCDF 3 has 32-bit integers: campaign.nc failed to be written (an internal error,
    # 'could not safely cast array from int64 to int32') once every trial had run
    seed = 2**64 + 3
    run("tool_rotation_arm", 1, seed=seed, out=tmp_path, workers=0, progress=False, **ARM)
    with xr.open_dataset(tmp_path / "campaign.nc") as on_disk:
        assert int(on_disk.attrs["seed"]) == seed
    assert json.loads((tmp_path / "summary.json").read_text())["seed"] == seed


def test_the_after_is_held_against_its_stated_spread(tmp_path):
    """Paper 001's figures state their spread over labs (`Figure.after_std`): the campaign
    keeps it per trial and summarises after / after_std as z-scores, computed here by hand
    from the Dataset. Two trials of the noisy lab."""
    from machinesim.campaign.summary import summarise

    ds = run("tool_setting_6axis", 2, seed=3, out=tmp_path, workers=0, progress=False)
    assert not ds["failed"].values.any()
    std = ds["after_std"].sel(figure="a_dx").values
    assert np.all(std > 0.0)
    z = ds["after"].sel(figure="a_dx").values / std
    summary = summarise(ds)
    assert summary["figures"]["a_dx"]["after_z"]["mean"] == pytest.approx(z.mean(), rel=1e-12)
    assert summary["figures"]["a_dx"]["after_z"]["std"] == pytest.approx(z.std(ddof=1),
                                                                         rel=1e-12)
    text = (tmp_path / "summary.md").read_text()
    assert "against its stated spread" in text
    # nothing varied: every table row has as many cells as its header (a trailing empty
    # "rho" cell once made the header one longer than its separator)
    tables = [block.splitlines() for block in text.split("\n\n") if block.startswith("|")]
    assert len(tables) == 3
    for table in tables:
        assert len({line.count("|") for line in table}) == 1, table


def _table(text: str, first: str) -> dict:
    """summary.md's table whose first column is headed ``first``: row name -> column -> cell."""
    lines = next(block.splitlines() for block in text.split("\n\n")
                 if block.startswith(f"| {first} |"))
    header, *rows = ([c.strip() for c in line.strip("|").split("|")]
                     for k, line in enumerate(lines) if k != 1)
    return {row[0]: dict(zip(header, row, strict=True)) for row in rows}


def test_summary_md_counts_the_trials_each_statistic_is_from(tmp_path):
    """summary.md said "0 failed" and gave an after mean over 1 of 2 trials, the count only
    in summary.json. A workpiece tilt of about +1 mrad (which paper 000 does not identify,
    but the lab cuts with) leaves the compensated pattern unreadable (its after None) while
    -0.4 mrad reads: with seed 0, trial 1 draws +1.02 mrad. The counts summary.md shows are
    those of the trial files, and it names the trials without an after."""
    status = cli_main(["campaign", "tool_rotation_arm", "--trials", "2", "--workers", "0",
                       "--quiet", "--vary", "workpiece.alpha=uniform:-2mrad,2mrad", "--out",
                       str(tmp_path)])
    assert status == 0
    records = [json.loads(p.read_text()) for p in sorted((tmp_path / "trials").glob("*.json"))]
    assert len(records) == 2 and all(r["error"] is None for r in records)
    text = (tmp_path / "summary.md").read_text()
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert "(seed 0, 0 failed)" in text
    shown = _table(text, "figure")
    assert set(shown) == set(records[0]["figures"])
    missing = {}
    for name, row in shown.items():
        for k, which in ((1, "before"), (2, "after")):
            values = [r["figures"][name][k] for r in records]
            measured = sum(v is not None for v in values)
            assert int(row[f"{which} trials"]) == measured, (name, which)
            assert summary["figures"][name][which]["count"] == measured
            missing[which, name] = [r["trial"] for r, v in zip(records, values, strict=True)
                                    if v is None]
            assert summary["figures"][name]["not_measured"][which] == missing[which, name]
    assert missing["after", "depth_error"] == [1]  # the case this test is about
    assert missing["before", "depth_error"] == []
    after_mean = np.mean([records[0]["figures"]["depth_error"][2]])
    assert float(shown["depth_error"]["after mean"]) == pytest.approx(after_mean, rel=1e-3)
    assert ("- after compensation, 1 trial (1): depth_error, depth_variation, pitch_error"
            in text)
    identified = _table(text, "parameter")
    for name, row in identified.items():
        assert int(row["trials"]) == sum(name in r["identified"] for r in records)


def test_trials_written_before_the_after_std_still_assemble():
    """A trial file from before figures carried after_std (three values) reads as NaN."""
    from machinesim.campaign.results import assemble
    from machinesim.campaign.summary import summarise

    record = {"trial": 0, "drawn": {}, "injected": {"tool.y": 1e-6},
              "identified": {"tool.y": [1.1e-6, 1e-7]}, "figures": {"a_dx": ["um", 5.0, 0.2]},
              "elapsed_s": 1.0, "error": None}
    spec = {"procedure": "tool_setting_6axis", "seed": 0, "vary": {}, "noise": True,
            "identify_only": False}
    ds = assemble([record], spec, 1)
    assert math.isnan(float(ds["after_std"].values[0, 0]))
    assert float(ds["after"].values[0, 0]) == 0.2
    assert "after_z" not in summarise(ds)["figures"]["a_dx"]


def test_each_parameter_carries_its_si_unit_through_campaign_nc(monkeypatch):
    """campaign.nc held m and rad unmarked, told apart by the name alone, and a polynomial's
    coefficient (m/m^k) not at all. Each parameter and varied parameter now has its unit
    from the error model (`ErrorModel.parameter_unit`), read back from the file and given
    by summary.json and summary.md. Paper 003's model has tables: EXX's entries are
    lengths, EAC's angles; the example model's EYX is a polynomial."""
    import dataclasses

    from machinesim.campaign.results import assemble
    from machinesim.campaign.summary import _markdown, summarise
    from machinesim.errors import ErrorModel

    def record(t, names, drawn=None):
        return {"trial": t, "drawn": drawn or {}, "injected": dict.fromkeys(names, 1e-6),
                "identified": {n: [1.5e-6, 1e-6] for n in names}, "figures": {},
                "elapsed_s": 1.0, "error": None}

    names = ["component.X.EXX[2]", "component.C.EAC[3]", "location.C.EB0C", "tool.y"]
    spec = {"procedure": "xy_plane_errors", "seed": 0, "noise": True, "identify_only": True,
            "vary": {"component.C.EAC[3]": "1urad", "laser_interferometer.sigma": "1nm"}}
    drawn = {"component.C.EAC[3]": 1e-6, "laser_interferometer.sigma": 1e-9}
    ds = assemble([record(0, names, drawn)], spec, 1)
    on_disk = xr.open_dataset(bytes(ds.to_netcdf())).load()
    assert on_disk["parameter_unit"].values.tolist() == ["m", "rad", "rad", "m"]
    assert on_disk["varied_unit"].values.tolist() == ["rad", "m"]
    summary = summarise(on_disk)
    assert [summary["parameters"][n]["unit"] for n in names] == ["m", "rad", "rad", "m"]
    rows = _table(_markdown(summary), "parameter")
    assert [rows[n]["unit"] for n in names] == ["m", "rad", "rad", "m"]
    # a polynomial's coefficients: the name's kind (parameter_kind) said a length for each
    example = ErrorModel.from_toml(EXAMPLE_ERRORS)
    monkeypatch.setitem(PROCEDURES, "tool_setting_6axis", dataclasses.replace(
        PROCEDURES["tool_setting_6axis"], base=lambda: example))
    poly = [f"component.X.EYX[{k}]" for k in range(3)]
    spec = {**spec, "procedure": "tool_setting_6axis", "vary": {}}
    ds = assemble([record(0, poly)], spec, 1)
    on_disk = xr.open_dataset(bytes(ds.to_netcdf())).load()
    assert on_disk["parameter_unit"].values.tolist() == ["m", "m/m", "m/m^2"]
    assert _markdown(summarise(on_disk)).count("| m/m^2 |") == 1
    # a trial file naming a parameter the model has no unit for: named, not a traceback
    with pytest.raises(InputError, match=r"'component.X.EZX\[0\]' \(trials/trial_000001.json "
                                         r"first names it\) has no unit .*no such error"):
        assemble([record(0, poly), record(1, ["component.X.EZX[0]"])], spec, 2)


def test_trials_that_give_a_figure_in_two_units_are_refused():
    """Trial 0 gave a_dx as 5 um, trial 1 as 5000 nm: the Dataset held 5 and 5000 in one
    column of figure_unit 'um' (the first trial's), its mean 2502.5 um."""
    from machinesim.campaign.results import assemble

    spec = {"procedure": "tool_setting_6axis", "seed": 0, "vary": {}, "noise": True,
            "identify_only": False}
    records = [{"trial": t, "drawn": {}, "injected": {}, "identified": {},
                "figures": {"a_dx": [unit, before, 0.2, None]}, "elapsed_s": 1.0,
                "error": None} for t, (unit, before) in enumerate([("um", 5.0), ("nm", 5e3)])]
    for order in (records, records[::-1]):
        with pytest.raises(InputError, match=r"gives figure 'a_dx' in (nm|um), trial [01] in "
                                             r"(um|nm): .* \(trials/trial_000000.json, "
                                             r"trials/trial_000001.json\)"):
            assemble(order, spec, 2)
    records[1]["figures"]["a_dx"] = ["um", 5.0, 0.2, None]
    assert assemble(records, spec, 2)["before"].values[:, 0].tolist() == [5.0, 5.0]


def test_a_campaign_keeps_the_identifications_notes_and_says_how_many_trials_gave_them(
        tmp_path, capsys):
    """A fit's notes (`Identified.notes`: readings that do not fit the model, ...) were not
    kept: a campaign of 1000 trials of which 30 misfit said nothing. Paper 000 does not
    identify the workpiece's tilt: with workpiece.alpha 1 mrad its heights and its lateral
    readings both leave the model (normalised residuals of about 26 and 350), with none
    they fit it. Each trial keeps its notes, the Dataset their count, summary.md and the
    command say how many trials gave any and which note."""
    status = cli_main(["campaign", "tool_rotation_arm", "--trials", "2", "--workers", "0",
                       "--identify-only", "--quiet", "--vary", "workpiece.alpha=1mrad",
                       "--out", str(tmp_path / "tilted")])
    err = capsys.readouterr().err
    assert status == 0
    misfit = "the readings do not fit the model: normalised residual "
    for i in range(2):
        record = json.loads((tmp_path / f"tilted/trials/trial_00000{i}.json").read_text())
        assert [note.partition(misfit)[0] for note in record["notes"]] == \
            ["fit_check (heights): ", "fit_check (lateral): "]
    ds = xr.open_dataset(tmp_path / "tilted/campaign.nc").load()
    assert ds["notes_count"].values.tolist() == [2.0, 2.0]
    summary = json.loads((tmp_path / "tilted/summary.json").read_text())
    assert summary["noted_count"] == 2
    assert sorted(note["note"].partition(misfit)[0] for note in summary["notes"]) == \
        ["fit_check (heights): ", "fit_check (lateral): "]
    assert [note["trials"] for note in summary["notes"]] == [[0, 1], [0, 1]]
    text = (tmp_path / "tilted/summary.md").read_text()
    assert "## Notes of the identification" in text and "2 of 2 trials gave notes" in text
    assert f"- 2 trials (0, 1): fit_check (heights): {misfit}" in text
    assert "campaign: 2 trials gave notes of the identification; the most common (2 of " \
        f"them): fit_check (heights): {misfit}" in err
    # no tilt: the readings fit, nothing is noted
    status = cli_main(["campaign", "tool_rotation_arm", "--trials", "2", "--workers", "0",
                       "--identify-only", "--quiet", "--out", str(tmp_path / "level")])
    assert status == 0 and "notes" not in capsys.readouterr().err
    ds = xr.open_dataset(tmp_path / "level/campaign.nc").load()
    assert ds["notes_count"].values.tolist() == [0.0, 0.0]
    summary = json.loads((tmp_path / "level/summary.json").read_text())
    assert summary["noted_count"] == 0 and summary["notes"] == []
    assert "Notes of the identification" not in (tmp_path / "level/summary.md").read_text()


def test_a_failed_trials_figures_and_values_are_left_out():
    """A trial file whose ``error`` says the trial failed, edited to hold figures and
    identified values as well: they went into campaign.nc and the statistics as a trial
    that ran (after mean 2.0 of 1, 2, 3 here); a failed trial is its draws and message
    alone. The two trials that ran: mean after 1.5, std 0.7071 (hand: sqrt(0.5))."""
    from machinesim.campaign.results import assemble
    from machinesim.campaign.summary import summarise

    records = [{"trial": t, "drawn": {}, "injected": {"tool.y": 0.0},
                "identified": {"tool.y": [1e-6 * (t + 1), 1e-7]},
                "figures": {"depth_error": ["um", 5.0, 1.0 + t]}, "notes": [],
                "elapsed_s": 1.0, "error": "InputError: no" if t == 2 else None}
               for t in range(3)]
    spec = {"procedure": "tool_rotation_arm", "seed": 0, "vary": {}, "noise": True,
            "identify_only": False}
    ds = assemble(records, spec, 3)
    assert np.array_equal(ds["after"].values[:, 0], [1.0, 2.0, np.nan], equal_nan=True)
    assert np.isnan(ds["identified"].values[2, 0]) and np.isnan(ds["injected"].values[2, 0])
    assert ds["failed"].values.tolist() == [0, 0, 1]
    after = summarise(ds)["figures"]["depth_error"]["after"]
    assert after["count"] == 2 and after["mean"] == 1.5
    assert after["std"] == pytest.approx(math.sqrt(0.5), rel=1e-15)
    # a figure only a failed trial names is no figure of the campaign
    records[2]["figures"]["other"] = ["um", 1.0, 1.0]
    assert list(assemble(records, spec, 3)["figure"].values) == ["depth_error"]


def test_notes_that_differ_only_in_their_numbers_are_one_in_the_summary():
    """Counted by hand: trials 0 and 2 misfit (residuals 25.7 and 31.2, one note), trial 2
    also notes two parameters barely told apart, trial 1 notes nothing, trial 3 failed and
    trial 4's file is from before notes were kept (neither known: NaN). Parameters that
    differ only in a digit of their name (EAC[3], EAC[4]) are two notes, not one."""
    from machinesim.campaign.results import assemble, note_kind
    from machinesim.campaign.summary import _markdown, summarise

    misfit = "fit: the readings do not fit the model: normalised residual {} (about 1)"
    pair = "fit: component.C.EAC[{}] and tool.y are correlated +0.999{}: barely told apart"
    notes = [[misfit.format(25.7)], [], [misfit.format(31.2), pair.format(3, 91)], [], None]
    records = []
    for t, noted in enumerate(notes):
        record = {"trial": t, "drawn": {}, "injected": {}, "identified": {}, "figures": {},
                  "elapsed_s": 1.0, "error": "InputError: no" if t == 3 else None}
        if noted is not None:
            record["notes"] = noted
        records.append(record)
    spec = {"procedure": "tool_rotation_arm", "seed": 0, "vary": {}, "noise": True,
            "identify_only": True}
    ds = assemble(records[::-1], spec, 5)  # in any order
    assert np.array_equal(ds["notes_count"].values, [1, 0, 2, np.nan, np.nan], equal_nan=True)
    summary = summarise(ds)
    assert summary["noted_count"] == 2
    assert summary["notes"] == [{"note": misfit.format(25.7), "trials": [0, 2]},
                                {"note": pair.format(3, 91), "trials": [2]}]
    assert note_kind(pair.format(3, 5)) == note_kind(pair.format(3, 91)) != \
        note_kind(pair.format(4, 91))
    text = _markdown(summary)
    assert "2 of 5 trials gave notes" in text
    assert f"- 2 trials (0, 2): {misfit.format(25.7)}\n- 1 trial (2): {pair.format(3, 91)}" \
        in text


def test_the_histograms_count_trials_in_whole_numbers(monkeypatch):
    """Four trials in five bins: the y axis counted them in steps of 0.25 (matplotlib's
    default locator); a count of trials takes whole numbers only."""
    from matplotlib.figure import Figure

    from machinesim.campaign.results import assemble
    from machinesim.campaign.summary import _plots

    records = [{"trial": i, "drawn": {}, "injected": {"tool.y": 1e-6},
                "identified": {"tool.y": [1e-6 + i * 1e-8, 1e-7]},
                "figures": {"a_dx": ["um", 5.0 + i, 0.2 + 0.01 * i, 0.01]},
                "elapsed_s": 1.0, "error": None} for i in range(4)]
    spec = {"procedure": "tool_setting_6axis", "seed": 0, "vary": {}, "noise": True,
            "identify_only": False}
    ticks = {}
    real = Figure.savefig

    def keep_ticks(figure, *args, **kwargs):
        for ax in figure.axes:
            if ax.get_ylabel() == "trials":
                ticks[ax.get_xlabel()] = ax.get_yticks()
        return real(figure, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", keep_ticks)
    _plots(assemble(records, spec, 4))
    assert set(ticks) == {"a_dx before (um)", "a_dx after (um)"}
    for values in ticks.values():
        assert len(values) > 1 and np.all(values == np.round(values)), values


def test_the_histograms_tick_labels_do_not_run_into_each_other(monkeypatch):
    """Paper 001's a_dx after compensation, 8 trials between -1.5 and 0.5 nm: the default
    x axis printed 8 labels of 8 characters that ran into one another
    (-0.0015.0001.25...), and before, 500 um +- 1 nm, read -0.0005 .. 0.001 with +5e2 at the
    axis' end."""
    from matplotlib.figure import Figure

    from machinesim.campaign.results import assemble
    from machinesim.campaign.summary import _plots

    after = np.linspace(-0.0015, 0.0005, 8)
    records = [{"trial": i, "drawn": {}, "injected": {}, "identified": {},
                "figures": {"a_dx": ["um", 500.0 + (i - 3) * 0.0003, after[i], math.nan]},
                "elapsed_s": 1.0, "error": None} for i in range(8)]
    spec = {"procedure": "tool_setting_6axis", "seed": 0, "vary": {}, "noise": True,
            "identify_only": False}
    labels = {}
    real = Figure.savefig

    def keep_labels(figure, *args, **kwargs):
        figure.canvas.draw()
        renderer = figure.canvas.get_renderer()
        for ax in figure.axes:
            shown = [t for t in ax.get_xticklabels() if t.get_visible() and t.get_text()]
            low, high = ax.get_xlim()
            shown = [t for t in shown if low <= t.get_position()[0] <= high]
            labels[ax.get_xlabel()] = ([t.get_text() for t in shown],
                                       [t.get_window_extent(renderer) for t in shown],
                                       ax.xaxis.get_offset_text().get_text())
        return real(figure, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", keep_labels)
    _plots(assemble(records, spec, 8))
    assert set(labels) == {"a_dx before (um)", "a_dx after (um)"}
    for name, (texts, boxes, offset) in labels.items():
        assert len(texts) >= 2, (name, texts)
        for left, right in zip(boxes, boxes[1:], strict=False):
            assert left.x1 < right.x0, (name, texts)  # a gap between neighbours
        assert offset == "", (name, offset)  # no +5e2 to add in one's head
    assert all(499.99 < float(text) < 500.01 for text in labels["a_dx before (um)"][0]), labels


def test_summary_md_gives_each_identification_errors_unit():
    """The identification's errors are SI, metres and radians in one column: paper 003's
    location.C.EA0C error of -1.479e-08 (rad) stood beside EX0C's -6.832e-10 (m) unmarked."""
    from machinesim.campaign.results import assemble
    from machinesim.campaign.summary import _markdown, summarise

    records = [{"trial": i, "drawn": {},
                "injected": {"location.C.EX0C": 3e-6, "location.C.EA0C": 2e-5},
                "identified": {"location.C.EX0C": [3e-6 + i * 1e-9, 1e-9],
                               "location.C.EA0C": [2e-5 - i * 1e-8, 1e-8]},
                "figures": {}, "elapsed_s": 1.0, "error": None} for i in range(3)]
    spec = {"procedure": "xy_plane_errors", "seed": 0, "vary": {}, "noise": True,
            "identify_only": True}
    shown = _table(_markdown(summarise(assemble(records, spec, 3))), "parameter")
    assert {name: row["unit"] for name, row in shown.items()} == \
        {"location.C.EX0C": "m", "location.C.EA0C": "rad"}
    assert float(shown["location.C.EA0C"]["error mean"]) == pytest.approx(-1e-8)
