"""machinesim.campaign: distributions, seeding, determinism, resume, statistics, CLI.

Trials run paper 000's calibration alone (``identify_only``: ~1.5 s each), a few per test.
The Dask LocalCluster test is in test_campaign_dask.py.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from scipy import stats

import machinesim.campaign.runner as runner
import machinesim.campaign.shipped as shipped_module
import machinesim.campaign.spec as spec_module
import machinesim.campaign.trials as trials_module
from machinesim.campaign import CampaignSpec, parse_distribution, parse_vary, run, run_trial
from machinesim.campaign.statistics import coverage_interval, ranks, spearman, z_scores, z_summary
from machinesim.campaign.trials import MAX_TRIALS, PROCEDURES, draw, trial_seed
from machinesim.cli import main as cli_main
from machinesim.exceptions import InputError, MachineSimError

UM, NM = 1e-6, 1e-9
ARM = dict(identify_only=True)
EXAMPLE_ERRORS = Path(__file__).resolve().parents[1] / "models" / "errors" / "example.toml"


# ------------------------------------------------------------------------- distributions


def test_distribution_units_are_parsed_to_si():
    d = parse_distribution("normal:0,5um", "tool.y")
    assert (d.kind, d.a, d.b) == ("normal", 0.0, 5 * UM)
    d = parse_distribution("uniform:-10um,0.01mm", "tool.y")
    assert (d.a, d.b) == pytest.approx((-10 * UM, 10 * UM), rel=1e-15)
    d = parse_distribution("0.2deg", "workpiece.alpha")
    assert (d.kind, d.a) == ("fixed", pytest.approx(math.radians(0.2), rel=1e-15))
    name, d = parse_vary("robot.repeatability=uniform:10um,100um")
    assert name == "robot.repeatability" and (d.a, d.b) == pytest.approx((10 * UM, 100 * UM))


@pytest.mark.parametrize("text, words", [
    ("tool.y=normal:0,5", ["'5'", "no unit"]),
    ("tool.y=normal:0,5deg", ["tool.y is a length"]),
    ("workpiece.beta=uniform:1um,2um", ["workpiece.beta is an angle"]),
    ("tool.y=uniform:5um,1um", ["'5um' >= high '1um'"]),
    ("tool.y=normal:0,-1um", ["std '-1um'"]),
    ("tool.y=gauss:0,1um", ["'gauss'", "normal, uniform, fixed"]),
    ("tool.y=normal:0,1um,2um", ["takes 2", "got 3"]),
    ("tool.y=normal:0,1furlong", ["unit 'furlong'"]),
    ("tool.y=normal:0,5\u00b5m", ["unit '\u00b5m'", "m mm um nm"]),  # the micro sign
    ("tool.y=normal:0,5Um", ["unit 'Um'"]),
    ("tool.y=normal:0,1um,", ["takes 2"]),
    ("tool.y", ["PARAM=DIST"]),
    ("robot.repeatability=uniform:-1um,10um", ["below zero"]),
    # the message said "a normal within 3 std of zero" for a mean that must be 3 std above it
    ("microscope.sigma=normal:50nm,20nm", ["below zero", "a normal whose MEAN is at least 3 STD"]),
    # a table entry's unit was not checked: 5deg set paper 003's X positioning error to 87 mm
    ("component.X.EXX[2]=5deg", ["component.X.EXX[2] is a length"]),
    ("component.C.EAC[3]=normal:0,3um", ["component.C.EAC[3] is an angle"]),
    ("tool_geometry.nose_radius=50urad", ["tool_geometry.nose_radius is a length"]),
])
def test_bad_distributions_name_the_value(text, words):
    with pytest.raises(InputError) as info:
        parse_vary(text)
    for word in words:
        assert word in str(info.value)


@pytest.mark.parametrize("text", [
    "A" * 100_000 + "=5nm", "tool.y=" + "a" * 100_000, "tool.y=5" + "a" * 100_000,
    "tool.y=" + "a" * 100_000 + ":1,2", "tool.y=uniform:" + "1" * 100_000 + ",2nm",
    "tool.y=normal:0nm," + "1" * 100_000, "a" * 100_000])
def test_a_huge_vary_is_quoted_by_its_ends_and_length(text):
    # a 100,000-character --vary was quoted whole in its refusal: a 100 kB line on stderr
    # (the key was already shown by its ends, the value not)
    from machinesim.campaign import CampaignSpec

    with pytest.raises(InputError) as info:
        CampaignSpec("tool_rotation_arm", 1, (parse_vary(text),))
    message = str(info.value)
    assert len(message) < 2_000 and "characters)" in message, message[:300]


@pytest.mark.parametrize("text", ["normal:60nm,20nm", "normal:0.6um,200nm", "normal:30nm,10nm"])
def test_a_lab_parameters_normal_with_its_mean_3_std_above_zero_is_taken(text):
    # 0.6um,200nm was refused as reaching below zero: 0.6 * 1e-6 < 3 * (200 * 1e-9) in floats
    name, d = parse_vary(f"microscope.sigma={text}")
    assert d.a == pytest.approx(3 * d.b, rel=1e-15)


def test_draws_follow_the_distributions():
    rng = np.random.default_rng(1)
    n = 20000
    normal = parse_distribution("normal:3um,2um")
    x = np.array([normal.draw(rng) for _ in range(n)])
    assert abs(x.mean() - 3 * UM) < 5 * 2 * UM / math.sqrt(n)
    assert x.std() == pytest.approx(2 * UM, rel=0.03)
    uniform = parse_distribution("uniform:-10um,30um")
    y = np.array([uniform.draw(rng) for _ in range(n)])
    assert y.min() >= -10 * UM and y.max() <= 30 * UM
    # uniform on [a, b]: mean (a + b) / 2, std (b - a) / sqrt(12)
    assert abs(y.mean() - 10 * UM) < 5 * (40 * UM / math.sqrt(12)) / math.sqrt(n)
    assert y.std() == pytest.approx(40 * UM / math.sqrt(12), rel=0.03)


# ---------------------------------------------------------------------------------- seeding


def test_trial_seed_is_the_spawned_child_whatever_n():
    for n in (5, 17):
        children = np.random.SeedSequence(42).spawn(n)
        for i in (0, 3, n - 1):
            assert np.array_equal(trial_seed(42, i).generate_state(4),
                                  children[i].generate_state(4))


def test_a_parameter_draws_the_same_whatever_else_varies():
    one = CampaignSpec("tool_rotation_arm", 4, (parse_vary("tool.y=normal:0,5um"),), seed=3)
    two = CampaignSpec("tool_rotation_arm", 4, (parse_vary("microscope.sigma=uniform:1nm,9nm"),
                                                parse_vary("tool.y=normal:0,5um")), seed=3)
    other = CampaignSpec("tool_rotation_arm", 4, (parse_vary("tool.y=normal:0,5um"),), seed=4)
    for i in range(4):
        assert draw(one, i)[0]["tool.y"] == draw(two, i)[0]["tool.y"]
        assert draw(one, i)[0]["tool.y"] != draw(other, i)[0]["tool.y"]
    assert len({draw(one, i)[0]["tool.y"] for i in range(4)}) == 4



def test_a_trial_draws_its_varied_parameters_once_and_a_spec_reads_its_base_model_once(
        monkeypatch):
    # run_trial drew every varied parameter twice (the record's, then the lab's), and a
    # campaign's spec read and checked its base model (paper 003's tables) twice
    from machinesim.campaign.distributions import Distribution
    from machinesim.errors import ErrorModel

    read, real_read = [], ErrorModel.from_toml.__func__

    def reading(cls, *args, **options):
        read.append(args[0])
        return real_read(cls, *args, **options)

    monkeypatch.setattr(ErrorModel, "from_toml", classmethod(reading))
    monkeypatch.setattr(shipped_module, "_MODEL_FILES", {}, raising=False)  # as in a new process
    spec = CampaignSpec("xy_plane_errors", 1,
                        (parse_vary("laser_interferometer.sigma=uniform:10nm,20nm"),),
                        identify_only=True)
    assert len(read) == 1
    drawn, real_draw = [], Distribution.draw

    def drawing(self, rng):
        drawn.append(real_draw(self, rng))
        return drawn[-1]

    monkeypatch.setattr(Distribution, "draw", drawing)
    record = run_trial(spec, 0)
    assert record["error"] is None
    assert drawn == [record["drawn"]["laser_interferometer.sigma"]]
    assert len(read) == 1  # the trial's own base model is the one read (error_model_file)


def test_an_error_model_file_is_parsed_once_while_its_bytes_stay_the_same(tmp_path,
                                                                          monkeypatch):
    # every trial of paper 003 parsed its base model's TOML anew (2.4 ms a trial)
    from machinesim.errors import ErrorModel
    from machinesim.machines import models_dir

    read, real_read = [], ErrorModel.from_toml.__func__

    def reading(cls, path):
        read.append(path)
        return real_read(cls, path)

    monkeypatch.setattr(ErrorModel, "from_toml", classmethod(reading))
    monkeypatch.setattr(shipped_module, "_MODEL_FILES", {}, raising=False)
    first = PROCEDURES["xy_plane_errors"].base()
    assert PROCEDURES["xy_plane_errors"].base() is first and len(read) == 1
    shipped = models_dir() / "errors" / "xy_plane_grooving_4axis.toml"
    assert read == [shipped] and first == real_read(ErrorModel, shipped)
    # an edited file is read again, even within the file system's time resolution
    copy = tmp_path / "model.toml"
    copy.write_text("[location.C]\nEX0C_um = 1.0\n")
    assert shipped_module.error_model_file(copy).parameters()["location.C.EX0C"] == 1e-6
    copy.write_text("[location.C]\nEX0C_um = 2.0\n")
    assert shipped_module.error_model_file(copy).parameters()["location.C.EX0C"] == 2e-6
    assert shipped_module.error_model_file(copy).parameters()["location.C.EX0C"] == 2e-6
    assert len(read) == 3


def test_robot_landing_scatter_matches_the_repeatability():
    # ISO 9283 RP of an isotropic Gaussian scatter: RP = (2 sqrt(2/pi) + 3 sqrt(3 - 8/pi)) s
    spec = CampaignSpec("workpiece_setting", 1, (parse_vary("robot.repeatability=50um"),))
    x = np.array([draw(spec, i)[1]["workpiece.x"] for i in range(3000)])
    s = 50 * UM / (2 * math.sqrt(2 / math.pi) + 3 * math.sqrt(3 - 8 / math.pi))
    assert x.std() == pytest.approx(s, rel=0.05)
    assert abs(x.mean()) < 5 * s / math.sqrt(x.size)


def test_unknown_parameter_and_bad_trials_are_refused():
    with pytest.raises(InputError, match="workpiece.q") as info:
        CampaignSpec("tool_rotation_arm", 2, (("workpiece.q", parse_distribution("1um")),))
    # the list offered is what may vary: it offered robot.repeatability and the nose radius,
    # which the next run then refused as never read by paper 000
    offered = str(info.value).partition("uses: ")[2].split(", ")
    assert offered == list(CampaignSpec("tool_rotation_arm", 2).parameters())
    assert "microscope.sigma" in offered and "robot.repeatability" not in offered
    with pytest.raises(InputError, match="--trials 0"):
        CampaignSpec("tool_rotation_arm", 0)
    with pytest.raises(InputError, match="'paper_999'"):
        CampaignSpec("paper_999", 2)


def test_an_unknown_parameter_of_paper_003_lists_its_tables_as_ranges_and_a_near_name():
    # the list offered spelt each of the tables' 104 entries (2500 characters on one line,
    # the few other names lost among them) and said nothing of a near miss
    import re

    with pytest.raises(InputError) as info:
        CampaignSpec("xy_plane_errors", 1, (parse_vary("laser_interferometer.sigm=1nm"),),
                     identify_only=True)
    message = str(info.value)
    assert "(did you mean laser_interferometer.sigma?)" in message
    offered = message.partition("uses: ")[2].split(", ")
    assert "component.C.EAC[0..16]" in offered and "component.X.EXX[0..6]" in offered
    assert len(message) < 1200
    expanded = []
    for name in offered:  # the ranges read back are every parameter, each once
        table = re.fullmatch(r"(.+)\[(\d+)\.\.(\d+)\]", name)
        expanded += ([f"{table[1]}[{k}]" for k in range(int(table[2]), int(table[3]) + 1)]
                     if table else [name])
    used = CampaignSpec("xy_plane_errors", 1, identify_only=True).parameters()
    assert len(used) == 128 and sorted(expanded) == sorted(used)


def test_an_instruments_sigma_with_noise_off_is_refused():
    # ignored: two trials at 72 and 183 nm identified the same values to the last bit
    with pytest.raises(InputError, match="--vary microscope.sigma: with --noise off"):
        CampaignSpec("tool_rotation_arm", 2, (parse_vary("microscope.sigma=5nm"),),
                     noise=False)
    CampaignSpec("workpiece_setting", 2, (parse_vary("robot.repeatability=30um"),),
                 noise=False)  # the landing is no noise: it stays


def test_quick_is_refused_where_it_changes_nothing():
    """--quick shrinks the crown's measuring windows (`RobotLoadedWorkpiece._crown_layout`,
    its only reader): the grooves' campaign, the other procedures and a probing-only trial
    read no crown, and took it silently (the folder then said quick: true)."""
    assert CampaignSpec("workpiece_setting", 1, quick=True).quick
    for name in ("workpiece_setting_grooves", "tool_rotation_arm", "tool_setting_6axis",
                 "xy_plane_errors"):
        with pytest.raises(InputError, match=rf"--quick changes nothing here \({name} has no "
                           r"crown windows to shrink\); it is for workpiece_setting "):
            CampaignSpec(name, 1, quick=True)
    with pytest.raises(InputError, match=r"--identify-only reads no crown"):
        CampaignSpec("workpiece_setting", 1, identify_only=True, quick=True)


def test_a_grooves_trial_whose_landing_the_rapids_would_run_into_fails_at_once():
    """A block landed 70 um high meets the groove program's rapids (CLEARANCE, 60 um, over
    the crossing): the trial fails with the crash named instead of cutting it (the
    scenario refuses the same landing, `groove_rapids_crash`); 50 um is cut."""
    spec = CampaignSpec("workpiece_setting_grooves", 1, (parse_vary("workpiece.z=70um"),))
    record = run_trial(spec, 0)
    assert record["error"].startswith("InputError: the drawn landing sets the grooves' block "
                                      "70.0 um high: its top stands 70.0 um high at the "
                                      "crossing"), record["error"]
    assert record["injected"] == {} and record["figures"] == {}
    spec = CampaignSpec("workpiece_setting_grooves", 1, (parse_vary("workpiece.z=50um"),))
    spec.entry.check(spec.entry.base().with_parameters(draw(spec, 0)[1]))  # no crash


def test_a_parameter_the_procedure_never_reads_is_refused():
    """What may vary follows each procedure's ``lab_uses``: paper 000 reads the microscope
    only (a V tool, no robot); paper 002 lands with a robot, probes, and cuts with a round
    nose read by the microscope after; paper 003's R-test states its own sigma."""
    from machinesim.experiment import LAB_USES

    arm = CampaignSpec("tool_rotation_arm", 1).parameters()
    assert "microscope.sigma" in arm and "workpiece.x" in arm  # not identified, still cut
    for name in ("laser_interferometer.sigma", "robot.repeatability",
                 "tool_geometry.nose_radius", "touch_probe.sigma"):
        assert name not in arm
    crown = set(CampaignSpec("workpiece_setting", 1).parameters())
    assert {"robot.repeatability", "touch_probe.sigma", "microscope.sigma",
            "tool_geometry.nose_radius", "tool.y"} <= crown
    probing = set(CampaignSpec("workpiece_setting", 1, identify_only=True).parameters())
    assert crown - probing == {"microscope.sigma", "tool_geometry.nose_radius"}
    with pytest.raises(InputError, match=r"--vary microscope.sigma: workpiece_setting "
                       r"--identify-only never reads it \(it reads with no microscope"):
        CampaignSpec("workpiece_setting", 1, (parse_vary("microscope.sigma=5nm"),),
                     identify_only=True)
    with pytest.raises(InputError, match="--vary r_test.sigma: xy_plane_errors never"):
        CampaignSpec("xy_plane_errors", 1, (parse_vary("r_test.sigma=5nm"),))
    # every procedure's defaults are among what it may vary, its uses among LAB_USES
    for name, entry in PROCEDURES.items():
        assert set(entry.lab) <= set(CampaignSpec(name, 1).parameters()), name
        for uses in entry.build({}).lab_uses.values():
            assert set(uses) <= set(LAB_USES), name


@pytest.mark.parametrize(("vary", "shown"), [
    ("tool.y=5m", "its value"),
    ("tool.y=uniform:2m,3m", "every value it draws"),
    ("tool.y=uniform:-3m,-1.5m", "every value it draws"),
    ("workpiece.alpha=uniform:200deg,300deg", "every value it draws"),
    ("tool.y=normal:-2m,1m", "its mean"),  # the centre beyond: refused, tails or not
])
def test_a_distribution_the_error_model_refuses_every_draw_of_is_refused_before_trials(
        vary, shown):
    # campaign --vary tool.y=5m ran every trial to the same ErrorModelError, then exited 1;
    # the bound is errors.LARGEST_ERROR: 1 m, 180 deg either way
    bound = "180 deg" if "deg" in vary else "1000 mm (1 m)"
    with pytest.raises(InputError, match="error model takes") as info:
        CampaignSpec("tool_setting_6axis", 2, (parse_vary(vary),))
    message = str(info.value)
    assert f"--vary {vary}" in message and shown in message
    assert f"expected at most {bound}" in message and "either way" in message


@pytest.mark.parametrize("vary", ["tool.y=fixed:1m", "tool.y=uniform:-5m,5m",
                                  "tool.y=normal:0,2m", "tool.y=normal:0.9m,1m"])
def test_a_distribution_some_of_whose_draws_the_error_model_takes_is_left_to_its_trials(vary):
    # at the bound (1 m) and across it: some trials may run, those beyond fail one by one
    spec = CampaignSpec("tool_setting_6axis", 2, (parse_vary(vary),))
    assert spec.vary[0][0] == "tool.y"


def test_cli_a_distribution_beyond_the_error_model_runs_no_trial(tmp_path, capsys):
    out = tmp_path / "c"
    status = cli_main(["campaign", "tool_setting_6axis", "--trials", "2", "--workers", "0",
                       "--quiet", "--vary", "tool.y=5m", "--out", str(out)])
    err = capsys.readouterr().err
    assert status == 2 and "key '--vary tool.y=5m'" in err and "(1 m)" in err
    assert not out.exists()


# ----------------------------------------------------------- trials, determinism, resume


@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    out = tmp_path_factory.mktemp("arm")
    vary = ["tool.y=normal:-178um,20um", "microscope.sigma=uniform:5nm,60nm"]
    ds = run("tool_rotation_arm", 3, vary=vary, seed=11, out=out, workers=0,
             progress=False, **ARM)
    return out, vary, ds


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


def test_microscope_sigma_reaches_the_instrument():
    def reported_std(sigma):
        spec = CampaignSpec("tool_rotation_arm", 1, (parse_vary(f"microscope.sigma={sigma}"),),
                            **ARM)
        return run_trial(spec, 0)["identified"]["tool.y"][1]

    quiet, loud = reported_std("2nm"), reported_std("200nm")
    # the fit's std scales with the readings' noise (rounding to 1 nm aside): ~100 x
    assert 30 < loud / quiet < 150


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


def _interrupt_after_one_trial(monkeypatch) -> list[int]:
    """Make the campaign runner stop with a Ctrl-C when a second trial starts; returns the
    list the one trial that ran is appended to."""
    real, ran = runner.run_trial, []

    def interrupted(spec, i):
        if ran:
            raise KeyboardInterrupt
        ran.append(i)
        return real(spec, i)

    monkeypatch.setattr(runner, "run_trial", interrupted)
    return ran


def test_interrupted_campaign_keeps_its_finished_trials(tmp_path, monkeypatch):
    _interrupt_after_one_trial(monkeypatch)
    with pytest.raises(KeyboardInterrupt):
        run("tool_rotation_arm", 2, seed=5, out=tmp_path, workers=0, progress=False, **ARM)
    assert sorted(p.name for p in (tmp_path / "trials").iterdir()) == ["trial_000000.json"]
    assert not (tmp_path / "campaign.nc").exists()


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

# ------------------------------------------------------------------------------ statistics


def test_coverage_interval_on_sorted_integers_by_hand():
    # M = 100, p = 0.95: q = 95; symmetric r = (M - q + 1) / 2 = 3 -> [y_3, y_98] (JCGM 101
    # 7.7.1); shortest: every window of q + 1 values is 95 wide, the first wins -> [y_1, y_96]
    y = np.arange(1.0, 101.0)
    rng = np.random.default_rng(0)
    assert coverage_interval(rng.permutation(y), kind="symmetric") == (3.0, 98.0)
    assert coverage_interval(y, kind="shortest") == (1.0, 96.0)
    assert all(math.isnan(v) for v in coverage_interval([1.0, 2.0]))


def test_coverage_interval_on_known_distributions():
    rng = np.random.default_rng(7)
    z = rng.standard_normal(200_000)
    low, high = coverage_interval(z, kind="symmetric")
    assert (low, high) == pytest.approx((-1.959964, 1.959964), abs=0.02)
    # exponential(1): the shortest 95 % interval is [0, ln 20]
    e = rng.exponential(size=200_000)
    low, high = coverage_interval(e, kind="shortest")
    assert low == pytest.approx(0.0, abs=1e-3) and high == pytest.approx(math.log(20), abs=0.03)
    low, high = coverage_interval(e, kind="symmetric")        # [-ln 0.975, -ln 0.025]
    assert (low, high) == pytest.approx((-math.log(0.975), -math.log(0.025)), abs=0.03)


def test_z_scores_of_honest_and_dishonest_uncertainty():
    rng = np.random.default_rng(3)
    truth = rng.uniform(-1, 1, 50_000)
    std = rng.uniform(0.5, 2.0, truth.size)
    found = truth + std * rng.standard_normal(truth.size)
    honest = z_summary(z_scores(found, truth, std))
    assert honest["mean"] == pytest.approx(0.0, abs=0.02)
    assert honest["std"] == pytest.approx(1.0, abs=0.02)
    assert honest["within_1_96_ratio"] == pytest.approx(0.95, abs=0.005)
    optimistic = z_summary(z_scores(found, truth, std / 2))
    assert optimistic["std"] == pytest.approx(2.0, abs=0.04)
    assert math.isnan(z_scores([1.0], [0.0], [math.nan])[0])


def test_spearman_against_scipy_and_monotonic_maps():
    rng = np.random.default_rng(5)
    x = rng.integers(0, 6, 300).astype(float)           # many ties
    y = x + rng.normal(0, 2, x.size)
    assert spearman(x, y) == pytest.approx(stats.spearmanr(x, y).statistic, abs=1e-12)
    assert spearman(x[:50], np.exp(x[:50] + 0.01 * np.arange(50))) == pytest.approx(
        stats.spearmanr(x[:50], np.exp(x[:50] + 0.01 * np.arange(50))).statistic)
    u = rng.uniform(size=40)
    assert spearman(u, u**3) == pytest.approx(1.0) and spearman(u, -u) == pytest.approx(-1.0)
    assert list(ranks([3.0, 1.0, 3.0, 2.0])) == [3.5, 1.0, 3.5, 2.0]


# ------------------------------------------------------------------------------------ CLI


def test_cli_bad_input_is_one_line_naming_the_value(tmp_path, capsys):
    status = cli_main(["campaign", "tool_rotation_arm", "--trials", "2", "--vary",
                       "tool.y=uniform:5um", "--out", str(tmp_path / "c")])
    err = capsys.readouterr().err
    assert status == 2 and "tool.y=uniform:5um" in err and "takes 2" in err
    assert "Traceback" not in err


def test_cli_an_empty_out_is_refused_not_the_current_folder(tmp_path, monkeypatch, capsys):
    # --out "$DIR" with DIR unset: Path("") is ".", and the campaign was written there
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as info:
        cli_main(["campaign", "tool_rotation_arm", "--trials", "1", "--workers", "0",
                  "--identify-only", "--out", ""])
    err = capsys.readouterr().err
    assert info.value.code == 2 and "argument --out: '' is empty" in err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("vary, why", [
    # ignored: results bit-identical to the run without it
    ("laser_interferometer.sigma=1um", "it reads with no laser_interferometer at the lab's noise"),
    # accepted, then every trial failed with "a VTool has no nose radius"
    ("tool_geometry.nose_radius=50um", "it cuts with no tool that has a nose radius"),
    # paper 000 has no robot: it injected a landing's workpiece setting errors
    ("robot.repeatability=30um", "no robot loads its workpiece"),
])
def test_cli_refuses_what_the_procedure_never_reads_before_any_trial(tmp_path, capsys,
                                                                     vary, why):
    out = tmp_path / "c"
    status = cli_main(["campaign", "tool_rotation_arm", "--trials", "2", "--workers", "0",
                       "--vary", vary, "--out", str(out)])
    err = capsys.readouterr().err
    assert status == 2, err
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    name = vary.partition("=")[0]
    assert f"--vary {name}: tool_rotation_arm never reads it ({why})" in err
    used = err.partition("the parameters tool_rotation_arm uses: ")[2].strip().split(", ")
    assert "microscope.sigma" in used and "tool.y" in used and name not in used
    assert not out.exists()  # no campaign.json, no trial file


def test_cli_runs_the_documented_variation(tmp_path, capsys):
    """docs/campaigns.md's paper 000 study, one probing trial of it."""
    status = cli_main(["campaign", "tool_rotation_arm", "--trials", "1", "--workers", "0",
                       "--identify-only", "--quiet", "--vary",
                       "microscope.sigma=uniform:5nm,200nm", "--out", str(tmp_path)])
    assert status == 0
    assert "1 trial (0 failed)" in capsys.readouterr().out
    assert len(list((tmp_path / "trials").glob("trial_*.json"))) == 1


def test_cli_runs_a_campaign(tmp_path, capsys):
    status = cli_main(["campaign", "tool_rotation_arm", "--trials", "1", "--workers", "0",
                       "--identify-only", "--quiet", "--vary", "tool.y=fixed:-100um",
                       "--out", str(tmp_path)])
    assert status == 0
    ds = xr.open_dataset(tmp_path / "campaign.nc").load()
    assert ds["injected"].sel(parameter="tool.y").item() == pytest.approx(-100 * UM)
    assert "1 trial (0 failed)" in capsys.readouterr().out


def test_cli_a_campaign_whose_every_trial_failed_says_why_and_fails(tmp_path, capsys):
    # a 3 mm edge offset lies beyond the calibration plan's 1 mm capture range: every trial
    # cuts its ramps and finds no groove starting on them (a 1 m offset, which the lab's
    # tool adjuster refuses, is refused before any trial now: test_campaign_folders.py)
    status = cli_main(["campaign", "tool_rotation_arm", "--trials", "2", "--workers", "0",
                       "--identify-only", "--quiet", "--vary", "tool.y=fixed:3mm",
                       "--out", str(tmp_path)])
    err = capsys.readouterr().err
    assert status == 1
    assert "every trial failed" in err and "exceeds the plan's capture range 1 mm" in err
    summary = json.loads((tmp_path / "summary.json").read_text())
    (failure,) = summary["failures"]
    assert failure["trials"] == [0, 1] and "the groove does not start on the ramp" in \
        failure["message"]
    assert "- 2 trials (0, 1): InputError" in (tmp_path / "summary.md").read_text()


def test_out_that_is_a_file_is_refused(tmp_path):
    afile = tmp_path / "taken"
    afile.write_text("x")
    with pytest.raises(MachineSimError, match="expected the campaign folder"):
        run("tool_rotation_arm", 1, out=afile, workers=0, progress=False, **ARM)


def test_the_xy_plane_procedure_varies_a_c_location_error_on_its_tables():
    """Paper 003's procedure starts from its error tables (`ProcedureEntry.base`): a drawn
    C offset lands in the lab and the C squareness test finds it within its reported std."""
    spec = CampaignSpec("xy_plane_errors", 4, (parse_vary("location.C.EX0C=normal:3um,1um"),),
                        seed=3, identify_only=True)
    record = run_trial(spec, 0)
    assert record["error"] is None
    drawn = record["drawn"]["location.C.EX0C"]
    value, std = record["identified"]["location.C.EX0C"]
    assert record["injected"]["location.C.EX0C"] == drawn
    assert abs(value - drawn) < 5 * std and std < 50e-9


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


def test_a_polynomials_coefficient_is_no_length_and_is_not_varied_as_one(monkeypatch):
    """parameter_kind read component.X.EYX[1], a polynomial's coefficient (m/m), as a
    length, so --vary took normal:0,1um for it and drew 1e-6 m/m. With the model it is
    neither kind, and a campaign refuses varying it, naming its unit."""
    import dataclasses

    from machinesim.campaign.distributions import parameter_kind
    from machinesim.errors import ErrorModel

    example = ErrorModel.from_toml(EXAMPLE_ERRORS)
    assert [parameter_kind(f"component.X.EYX[{k}]", example) for k in range(3)] == [
        "length", None, None]
    assert parameter_kind("component.X.EXX[2]", example) == "length"  # a table's value
    assert parameter_kind("component.C.ECC[1]", example) == "angle"
    assert parameter_kind("component.X.EYX[1]") == "length"  # the name alone: a table's
    monkeypatch.setitem(PROCEDURES, "tool_setting_6axis", dataclasses.replace(
        PROCEDURES["tool_setting_6axis"], base=lambda: example))
    with pytest.raises(InputError, match=r"--vary component.X.EYX\[2\]: a polynomial's "
                                         r"coefficient, in m/m\^2 \(SI\)"):
        CampaignSpec("tool_setting_6axis", 1, (parse_vary("component.X.EYX[2]=normal:0,1um"),))
    spec = CampaignSpec("tool_setting_6axis", 1, (parse_vary("component.X.EYX[0]=1um"),
                                                  parse_vary("component.X.EXX[1]=1um")))
    assert [name for name, _ in spec.vary] == ["component.X.EYX[0]", "component.X.EXX[1]"]


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


def test_a_machines_warning_is_shown_once_not_once_per_trial(tmp_path, monkeypatch,
                                                             degree_like_planer):
    """The campaign's process loads the machine (its spec's checks), then each worker
    process loads it again (here each trial, as if each ran in a fresh worker): its warning
    (rotary limits that read as degrees) was shown by this process and once more by each
    load. A trial keeps it (`kept_warnings`) and the campaign shows each message once
    (warnings recorded: 1 of 4 loads; tests/test_campaign_dask.py, the same on workers)."""
    import warnings

    import machinesim.machines as machines
    from machinesim.exceptions import MachineSimWarning

    load = machines.load_machine
    monkeypatch.setattr(machines, "load_machine", lambda name: load(degree_like_planer))
    monkeypatch.setattr(spec_module, "_MACHINES", {})
    real = trials_module.run_trial

    def trial(spec, i):  # each trial loads the machine again, as a fresh worker would
        spec_module._MACHINES.clear()
        machines._load.cache_clear()
        return real(spec, i)

    monkeypatch.setattr(runner, "run_trial", trial)
    with warnings.catch_warnings(record=True) as shown:
        warnings.simplefilter("always")
        ds = run("tool_rotation_arm", 3, out=tmp_path / "c", workers=0, progress=False,
                 report=False, **ARM)
    assert not ds["failed"].values.any()
    degrees = [w for w in shown if issubclass(w.category, MachineSimWarning)]
    assert len(degrees) == 1 and "joint 'A': <limit lower=-45.0 upper=45.0> is read in " \
        "rad" in str(degrees[0].message)
    record = json.loads((tmp_path / "c/trials/trial_000000.json").read_text())
    assert "warnings" not in record  # a trial's result, not where its machine came from


def test_the_campaign_command_alone_shows_a_machines_warning_as_one_line(tmp_path,
                                                                         degree_like_planer):
    """``python -m machinesim.campaign.cli`` showed the machine's warning in Python's own
    form (urdf.py:459: MachineSimWarning: ..., then the source line), where ``machinesim
    campaign`` shows one line."""
    import subprocess
    import sys

    code = ("import sys\nimport machinesim.machines as machines\nload = machines.load_machine\n"
            "machines.load_machine = lambda name: load(sys.argv[1])\n"
            "from machinesim.campaign.cli import main\nsys.exit(main(sys.argv[2:]))")
    done = subprocess.run(
        [sys.executable, "-c", code, degree_like_planer, "tool_rotation_arm", "--trials", "1",
         "--workers", "0", "--identify-only", "--quiet", "--out", str(tmp_path / "c")],
        capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert "MachineSimWarning" not in done.stderr, done.stderr
    (line,) = [x for x in done.stderr.splitlines() if "lower=-45.0 upper=45.0" in x]
    assert line.startswith("machinesim: warning: ")


def test_cli_refuses_an_absurd_trial_count_at_once(tmp_path, capsys):
    """--trials 1e11 used to leave the command silent for minutes (it looked for that many
    trial files); it is refused before anything runs or is written."""
    for trials in ("100000000000", str(MAX_TRIALS + 1), "0"):
        status = cli_main(["campaign", "tool_rotation_arm", "--trials", trials, "--out",
                           str(tmp_path / "c")])
        err = capsys.readouterr().err
        assert status == 2, err
        assert len(err.splitlines()) == 1 and "Traceback" not in err
        assert f"--trials {trials}; expected a whole number from 1 to 100000" in err
        assert not (tmp_path / "c").exists()
    with pytest.raises(InputError, match="from 1 to 100000"):
        CampaignSpec("tool_rotation_arm", MAX_TRIALS + 1)
    assert CampaignSpec("tool_rotation_arm", MAX_TRIALS).trials == MAX_TRIALS


def test_cli_ctrl_c_says_which_trials_are_kept_and_the_rerun_resumes(tmp_path, capsys,
                                                                      monkeypatch):
    real = runner.run_trial
    ran = _interrupt_after_one_trial(monkeypatch)
    command = ["campaign", "tool_rotation_arm", "--trials", "2", "--workers", "0",
               "--identify-only", "--quiet", "--seed", "5", "--out", str(tmp_path)]
    assert cli_main(command) == 130
    err = capsys.readouterr().err
    assert err.strip() == (
        f"machinesim: interrupted; kept the 1 finished trial file in {tmp_path / 'trials'} "
        "(trial_000000.json) and campaign.json: run the same command again to resume (only "
        "the missing trials run)")
    assert sorted(p.name for p in (tmp_path / "trials").iterdir()) == ["trial_000000.json"]

    ran.clear()
    monkeypatch.setattr(runner, "run_trial", lambda spec, i: ran.append(i) or real(spec, i))
    assert cli_main(command) == 0
    assert ran == [1]  # resumed: only the missing trial ran
    assert "2 trials (0 failed)" in capsys.readouterr().out


def test_the_interrupted_line_says_which_trials_between_the_kept_ones_are_missing(tmp_path):
    # with workers trials finish out of order: 5 files, 0 .. 5, read as six finished
    from machinesim.campaign.cli import interrupted

    (tmp_path / "trials").mkdir()
    for i in (0, 1, 2, 3, 5):
        (tmp_path / f"trials/trial_{i:06d}.json").write_text("{}")
    assert (f"kept the 5 finished trial files in {tmp_path / 'trials'} (trial_000000.json .. "
            "trial_000005.json, 1 between them not finished) and campaign.json"
            ) in interrupted(tmp_path)


def test_cli_ctrl_c_before_any_trial_says_so(tmp_path, capsys, monkeypatch):
    def interrupted(spec, i):
        raise KeyboardInterrupt

    monkeypatch.setattr(runner, "run_trial", interrupted)
    assert cli_main(["campaign", "tool_rotation_arm", "--trials", "2", "--workers", "0",
                     "--identify-only", "--quiet", "--out", str(tmp_path / "c")]) == 130
    err = capsys.readouterr().err.strip()
    assert err == (f"machinesim: interrupted; no trial had finished; kept "
                   f"{tmp_path / 'c' / 'campaign.json'}: run the same command again to start "
                   "it over")
    # what it says is all that is left: the lock and the empty trials/ it made are gone
    assert sorted(p.name for p in (tmp_path / "c").iterdir()) == ["campaign.json"]


def test_cli_ctrl_c_before_campaign_json_leaves_nothing_it_made(tmp_path, capsys,
                                                                 monkeypatch):
    """A Ctrl-C after the lock was taken and trials/ made, before campaign.json was written,
    said 'interrupted; nothing was written' while the folder held campaign.lock and an
    empty trials/: what the run made and holds nothing is taken away, what was there
    before stays."""
    import machinesim.campaign.results as results

    def stopped(path, what):
        raise KeyboardInterrupt

    monkeypatch.setattr(results, "check_writable", stopped)
    command = ["campaign", "tool_rotation_arm", "--trials", "2", "--workers", "0",
               "--identify-only", "--quiet", "--out"]
    new = tmp_path / "a" / "b"  # two folders this run makes
    assert cli_main([*command, str(new)]) == 130
    assert capsys.readouterr().err.strip() == "machinesim: interrupted; nothing was written"
    assert list(tmp_path.iterdir()) == []
    # a folder there before, with a lock of an earlier run and an empty trials/: kept
    old = tmp_path / "old"
    (old / "trials").mkdir(parents=True)
    (old / "campaign.lock").write_text('{"pid": 1, "host": "elsewhere"}\n')
    assert cli_main([*command, str(old)]) == 130
    assert capsys.readouterr().err.strip() == "machinesim: interrupted; nothing was written"
    assert sorted(p.name for p in old.iterdir()) == ["campaign.lock", "trials"]
    assert list((old / "trials").iterdir()) == []
    # an empty folder there before: kept, empty
    empty = tmp_path / "empty"
    empty.mkdir()
    assert cli_main([*command, str(empty)]) == 130
    assert list(empty.iterdir()) == []


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


def test_a_varied_microscope_noise_leaves_an_objectives_own():
    """``microscope.sigma`` reaches the default microscope, not a reading through another
    objective, whose noise is that objective's (paper 002's crown through the 10x read the
    campaign's draw instead)."""
    from machinesim import Lab
    from machinesim.campaign.trials import _LabWithInstruments
    from machinesim.realism import OBJECTIVE_10X

    lab = _LabWithInstruments(Lab("robonano_a0ib", seed=1), {"microscope": 1e-9})
    assert lab.microscope().readout.sigma == 1e-9
    assert lab.microscope(objective=OBJECTIVE_10X).readout.sigma == OBJECTIVE_10X.sigma
    assert lab.microscope(sigma=2e-9).readout.sigma == 2e-9  # the procedure's own still wins


def test_paper_003s_table_entries_vary_on_its_base_model():
    """xy_plane_errors sets every --vary on its tables' model, so their entries are its
    parameters: they were refused as 'not a parameter of grooving_4axis'."""
    spec = CampaignSpec("xy_plane_errors", 1, (parse_vary("component.X.EXX[2]=normal:0,1um"),),
                        identify_only=True)
    assert "component.X.EXX[2]" in spec.parameters()
    assert parse_vary("component.C.EAC[3]=3urad")[1].a == pytest.approx(3e-6, rel=1e-15)
    with pytest.raises(InputError, match=r"--vary component.X.EXX\[99\]: not a parameter"):
        CampaignSpec("xy_plane_errors", 1, (parse_vary("component.X.EXX[99]=normal:0,1um"),))


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


def test_the_campaign_command_alone_escapes_its_last_line_as_machinesim_does(tmp_path, capsys,
                                                                            monkeypatch):
    """``python -m machinesim.campaign.cli`` printed its error and interrupted lines itself,
    a folder's ESC sequence raw (red text from there on), where ``machinesim campaign`` escapes them
    (`machinesim.exceptions.say`, the one path both now take)."""
    import shutil

    from machinesim.campaign.cli import main as campaign_main

    out = tmp_path / "c\x1b[31mx"
    ran = _interrupt_after_one_trial(monkeypatch)
    command = ["tool_rotation_arm", "--trials", "2", "--workers", "0", "--identify-only",
               "--quiet", "--out", str(out)]
    assert campaign_main(command) == 130
    alone = capsys.readouterr().err
    shutil.rmtree(out)
    ran.clear()
    assert cli_main(["campaign", *command]) == 130
    together = capsys.readouterr().err
    assert "\x1b" not in alone and alone.count("\n") == 1
    assert "c\\x1b[31mx" in alone and "interrupted; kept the 1 finished trial" in alone
    assert alone.replace("machinesim campaign: ", "machinesim: ", 1) == together

    def refused(args):
        raise MachineSimError(f"{out}.urdf: not a URDF file")  # a path in a message's text

    monkeypatch.setattr("machinesim.campaign.cli.run_campaign", refused)
    assert campaign_main(command) == 2
    assert capsys.readouterr().err == (f"machinesim campaign: error: "
                                       f"{tmp_path}/c\\x1b[31mx.urdf: not a URDF file\n")


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


def test_cli_out_of_memory_in_a_trial_names_what_was_kept(tmp_path, capsys, monkeypatch):
    """A trial that runs out of memory ends the campaign (no record: it runs again on
    resuming); the command's one line had said only 'out of memory: ... cut a window of it
    (--roi), or fewer passes', not that the finished trials were kept, as a Ctrl-C says."""
    from machinesim.experiment import run as real_run

    def hungry(procedure, lab):
        if lab.seed.spawn_key == (1,):
            raise MemoryError
        return real_run(procedure, lab)

    monkeypatch.setattr(trials_module, "run", hungry)
    out = tmp_path / "c"
    status = cli_main(["campaign", "tool_rotation_arm", "--trials", "2", "--workers", "0",
                       "--identify-only", "--quiet", "--out", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 1, err
    assert len(err) == 1 and err[0].startswith("machinesim: error: out of memory: "), err
    assert err[0].endswith(
        f"; kept the 1 finished trial file in {out / 'trials'} (trial_000000.json) and "
        "campaign.json: run the same command again to resume (only the missing trials run)")
