"""machinesim.campaign: a campaign's identity across spellings, the checks run before any
trial, and folders that cannot be written.

Trials run paper 000's calibration alone (``identify_only``: ~1.5 s each), a few per file.
"""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

import machinesim.campaign.runner as runner
from machinesim.campaign import CampaignSpec, parse_vary, run
from machinesim.campaign.results import CampaignFolder, campaign_id, legacy_campaign_id
from machinesim.exceptions import FileError, InputError

ARM = dict(identify_only=True)
VARY = ["tool.y=normal:-178um,20um", "microscope.sigma=uniform:5nm,60nm"]
#: VARY spelt otherwise: the same distributions
SPELT = ["tool.y=normal:-0.178mm,0.02mm", "microscope.sigma=uniform:5 nm,0.06um"]


@pytest.fixture(scope="module")
def begun(tmp_path_factory):
    """A campaign of two trials begun with VARY: (folder, Dataset)."""
    out = tmp_path_factory.mktemp("begun")
    return out, run("tool_rotation_arm", 2, vary=VARY, seed=11, out=out, workers=0,
                    progress=False, report=False, **ARM)


def trials_run(monkeypatch) -> list[int]:
    """The indices of the trials the runner runs from now on, in order (each still run)."""
    ran, real = [], runner.run_trial
    monkeypatch.setattr(runner, "run_trial", lambda spec, i: ran.append(i) or real(spec, i))
    return ran


def _spec(vary, seed=11) -> dict:
    return CampaignSpec("tool_rotation_arm", 2, tuple(parse_vary(t) for t in vary), seed=seed,
                        **ARM).describe()


# ------------------------------------------------------------------------------ identity


def test_an_identity_is_of_the_distributions_meaning_not_their_spelling():
    # campaign_id hashed the DIST texts as spelt: 10nm and 0.01um were two campaigns
    ten = _spec(["microscope.sigma=10nm"])
    assert campaign_id(ten) == campaign_id(_spec(["microscope.sigma=0.01um"])) \
        == campaign_id(_spec(["microscope.sigma=fixed:1e-8m"]))
    assert campaign_id(_spec(VARY)) == campaign_id(_spec(SPELT))
    assert campaign_id(ten) != campaign_id(_spec(["microscope.sigma=11nm"]))
    assert campaign_id(ten) != campaign_id(_spec(["microscope.sigma=normal:10nm,1nm"]))
    assert campaign_id(ten) != campaign_id(_spec(["microscope.sigma=10nm"], seed=12))
    # nothing varied: the identity it always had (nothing to read otherwise)
    bare = _spec([])
    assert campaign_id(bare) == legacy_campaign_id(bare)


@pytest.mark.parametrize(("one", "other", "same"), [
    # 4e-12 apart: one identity (12 digits), yet refused as another campaign on resume,
    # while each folder took the other's trial files for its own
    ("tool.y=fixed:1um", "tool.y=fixed:1.000000000004um", True),
    # 2e-13 apart across a 12th digit: resumed as the same campaign (within 1e-12), yet two
    # identities, each folder refusing the other's trial files
    ("tool.y=fixed:1.0000000000049um", "tool.y=fixed:1.0000000000051um", False),
    ("microscope.sigma=uniform:5nm,60nm", "microscope.sigma=uniform:5 nm,0.06um", True),
    ("microscope.sigma=10nm", "microscope.sigma=10.00000001nm", False),
])
def test_a_folder_resumes_exactly_the_campaigns_whose_trial_files_it_takes(one, other,
                                                                           same):
    from machinesim.campaign.results import same_campaign

    a, b = _spec([one]), _spec([other])
    assert same_campaign(a, b) is same_campaign(b, a) is same
    assert (campaign_id(a) == campaign_id(b)) is same


def test_a_trial_file_of_the_same_campaign_spelt_otherwise_is_this_campaigns(
        begun, tmp_path, monkeypatch):
    # a trial file of the campaign begun with VARY, copied into the folder of the one begun
    # with SPELT, was refused as "the trial file of another campaign"
    source, ds = begun
    CampaignFolder(tmp_path, _spec(SPELT))  # begun with SPELT, as the runner begins it
    shutil.copy(source / "trials/trial_000001.json", tmp_path / "trials")
    ran = trials_run(monkeypatch)
    again = run("tool_rotation_arm", 2, vary=SPELT, seed=11, out=tmp_path, workers=0,
                progress=False, report=False, **ARM)
    assert ran == [0]
    # trial 0 drew from 0.06um here, from 60nm there: the same to the units' last bit
    np.testing.assert_allclose(again["drawn"].values, ds["drawn"].values, rtol=1e-12)
    np.testing.assert_allclose(again["identified"].values, ds["identified"].values,
                               rtol=1e-9)
    written = json.loads((tmp_path / "trials/trial_000000.json").read_text())
    copied = json.loads((source / "trials/trial_000000.json").read_text())
    assert written["campaign"] == copied["campaign"]
    # another value is another campaign: its file is refused, naming it
    other = tmp_path / "other"
    CampaignFolder(other, _spec([VARY[0], "microscope.sigma=uniform:5nm,61nm"]))
    shutil.copy(source / "trials/trial_000001.json", other / "trials")
    with pytest.raises(InputError, match="trial_000001.json.*of another campaign"):
        run("tool_rotation_arm", 2, vary=[VARY[0], "microscope.sigma=uniform:5nm,61nm"],
            seed=11, out=other, workers=0, progress=False, report=False, **ARM)
    assert ran == [0]


def test_a_folder_written_with_the_identity_of_the_texts_resumes(begun, tmp_path,
                                                                  monkeypatch):
    # its trial files hold the identity of campaign.json's texts as spelt, which campaigns
    # wrote before the identity took their meaning: still this folder's, not "another
    # campaign's" to delete and run anew
    source, ds = begun
    shutil.copytree(source, tmp_path / "old")
    old = tmp_path / "old"
    stored = json.loads((old / "campaign.json").read_text())
    assert legacy_campaign_id(stored) != campaign_id(stored)
    for path in (old / "trials").iterdir():
        record = json.loads(path.read_text())
        path.write_text(json.dumps({**record, "campaign": legacy_campaign_id(stored)}))
    ran = trials_run(monkeypatch)
    again = run("tool_rotation_arm", 3, vary=VARY, seed=11, out=old, workers=0,
                progress=False, report=False, **ARM)
    assert ran == [2]
    for name in ("drawn", "identified", "identified_std", "injected"):
        assert np.array_equal(again[name].values[:2], ds[name].values), name
    assert json.loads((old / "trials/trial_000002.json").read_text())["campaign"] \
        == campaign_id(stored)


# ------------------------------------------------------------- checks before any trial


def test_a_campaign_its_procedure_refuses_fails_before_any_trial(tmp_path, monkeypatch):
    # paper 002's grooves with the block set 100 um high: the groove program's rapids come
    # down to 60 um over the crossing, and the procedure's own check (groove_rapids_crash)
    # failed each trial with that message, one by one, the campaign's folder of failures
    # written all the same; now refused at once with the same message, nothing written
    ran = trials_run(monkeypatch)
    out = tmp_path / "grooves"
    with pytest.raises(InputError) as info:
        run("workpiece_setting_grooves", 50, vary=["workpiece.z=100um"], out=out, workers=0,
            progress=False)
    message = str(info.value)
    assert message.startswith("key '--vary': the trials of workpiece_setting_grooves would "
                              "fail one by one as they start: the errors they are drawn "
                              "around (workpiece.z=100um; the robot's landing at its mean) "
                              "are refused: InputError: "), message
    assert "the drawn landing sets the grooves' block 100.0 um high" in message
    assert "rapids would run into the block" in message
    assert ran == [] and not out.exists()
    # every draw of a uniform 100..200 um crashes too, and all but 0.13 % of a normal whose
    # 3 sigma below its mean (70 um, 61 um) still crash
    for text in ("uniform:100um,200um", "normal:100um,10um", "normal:70um,3um"):
        with pytest.raises(InputError, match="rapids would run into the block"):
            run("workpiece_setting_grooves", 50, vary=[f"workpiece.z={text}"], out=out,
                workers=0, progress=False)
    assert ran == [] and not out.exists()


@pytest.mark.parametrize(("procedure", "vary", "options"), [
    ("workpiece_setting_grooves", ["workpiece.z=50um"], {}),  # below the 60 um: cut
    ("workpiece_setting_grooves", ["workpiece.z=uniform:0um,100um"], {}),  # some draws cut
    ("workpiece_setting_grooves", ["workpiece.z=normal:0um,100um"], {}),
    # centred on the 60 um where the rapids crash, half its trials below it cut: it was
    # refused at its mean; now checked at 60 - 3 x 30 um, below zero, so at 0
    ("workpiece_setting_grooves", ["workpiece.z=normal:60um,30um"], {}),
    ("workpiece_setting_grooves", ["workpiece.z=normal:80um,9um"], {}),  # 53 um, cut
    ("workpiece_setting_grooves", ["workpiece.z=100um"], {"identify_only": True}),  # no cut
    ("workpiece_setting_grooves", ["robot.repeatability=300um"], {}),  # 23 % of landings
    ("tool_rotation_arm", VARY, {}),
    ("xy_plane_errors", ["location.C.EX0C=normal:0,5um"], {}),
])
def test_a_campaign_some_of_whose_trials_the_procedure_takes_is_not_refused(
        procedure, vary, options):
    from machinesim.campaign.preflight import check_before_trials

    spec = CampaignSpec(procedure, 4, tuple(parse_vary(t) for t in vary), **options)
    check_before_trials(spec)  # no refusal


def test_cli_a_tool_offset_the_lab_refuses_fails_before_any_trial(tmp_path, capsys):
    # a 1 m tool offset leaves the lab's tool adjuster no stroke: every trial failed at its
    # start with that message, the command exiting 1 after writing a campaign of failures
    from machinesim.cli import main as cli_main

    out = tmp_path / "arm"
    status = cli_main(["campaign", "tool_rotation_arm", "--trials", "2", "--workers", "0",
                       "--identify-only", "--quiet", "--vary", "tool.y=fixed:1m",
                       "--out", str(out)])
    err = capsys.readouterr().err
    assert status == 2 and not out.exists()
    assert "the errors they are drawn around (tool.y=fixed:1m) are refused" in err
    assert "a tool offset of [0.0, 1000.0, -0.055] mm" in err
    assert "1 m less the tool adjuster's stroke" in err


@pytest.mark.parametrize(("procedure", "vary", "limit"), [
    ("tool_rotation_arm", "microscope.sigma=2mm", "OPTICAL_LIMIT"),
    ("tool_rotation_arm", "microscope.sigma=uniform:2mm,3mm", "OPTICAL_LIMIT"),
    ("tool_rotation_arm", "microscope.sigma=normal:3mm,0.5mm", "OPTICAL_LIMIT"),
    ("xy_plane_errors", "laser_interferometer.sigma=2m", "READOUT_LIMIT"),
    ("workpiece_setting", "touch_probe.sigma=2m", "READOUT_LIMIT"),
])
def test_an_instruments_noise_beyond_what_it_takes_fails_before_any_trial(
        tmp_path, monkeypatch, procedure, vary, limit):
    # an instrument's noise every draw of which lies beyond its 1 mm limit (a unit slip)
    # failed every trial with the instrument's message, the command exiting 1 after writing
    # a campaign of failures; now refused at once, nothing written
    ran = trials_run(monkeypatch)
    out = tmp_path / "noise"
    with pytest.raises(InputError) as info:
        run(procedure, 3, vary=[vary], out=out, workers=0, progress=False, identify_only=True)
    message = str(info.value)
    name, text = vary.split("=")
    assert message.startswith(f"key '--vary': the trials of {procedure} --identify-only "
                              f"would fail one by one as they start: the errors they are "
                              f"drawn around ({name}={text}"), message
    assert "key 'sigma': Expected sigma <= 0.001 m" in message and limit in message
    assert ran == [] and not out.exists()
    # a noise some of whose draws the instrument takes runs
    spec = CampaignSpec(procedure, 3, (parse_vary(f"{name}=uniform:0.5mm,3mm"),),
                        identify_only=True)
    from machinesim.campaign.preflight import check_before_trials

    check_before_trials(spec)


def test_a_robot_repeatability_whose_landings_no_setting_takes_fails_before_any_trial(
        tmp_path, monkeypatch):
    # robot.repeatability=2m (a unit slip for 2 mm) ran every trial to its landing's refusal
    # ('... is no angle error'), writing a campaign of failures, exit 1; the robot refuses it
    # now (RobotLoader, its landings' reach), once, before any trial
    ran = trials_run(monkeypatch)
    out = tmp_path / "robot"
    with pytest.raises(InputError) as info:
        run("workpiece_setting", 3, vary=["robot.repeatability=2m"], out=out, workers=0,
            progress=False, identify_only=True)
    message = str(info.value)
    assert message.startswith("key '--vary': the trials of workpiece_setting --identify-only "
                              "would fail one by one as they start: the errors they are "
                              "drawn around (robot.repeatability=2m; "), message
    assert "key 'repeatability': a robot of repeatability 2 m" in message
    assert "expected a repeatability of at most 0.0757352 m" in message
    assert ran == [] and not out.exists()
    # one some of whose draws the robot takes runs
    from machinesim.campaign.preflight import check_before_trials

    check_before_trials(CampaignSpec("workpiece_setting", 3,
                                     (parse_vary("robot.repeatability=uniform:10um,2m"),),
                                     identify_only=True))


# ------------------------------------------------------------ folders that cannot be written
# The suite runs as root, for whom a folder's mode bits stop no write: these folders cannot
# be written because of what is in their way (a file) or the file system (/proc).


def test_a_folder_under_a_file_is_refused_before_any_trial_naming_the_file(tmp_path,
                                                                           monkeypatch):
    # 'cannot make the campaign folder: Not a directory' named the folder asked for, not
    # the file in its way
    (tmp_path / "file.txt").write_text("a file")
    ran = trials_run(monkeypatch)
    for out in (tmp_path / "file.txt/campaign", tmp_path / "file.txt/a/b"):
        with pytest.raises(FileError) as info:
            run("tool_rotation_arm", 2, out=out, workers=0, progress=False, **ARM)
        assert str(info.value) == (
            f"{out}: cannot make the campaign folder: '{tmp_path / 'file.txt'}' is a file, "
            "not a folder; expected a folder that can be made and written, or one there")
    assert ran == [] and (tmp_path / "file.txt").read_text() == "a file"
    # a campaign folder whose trials/ is a file
    (tmp_path / "made").mkdir()
    (tmp_path / "made/campaign.json").write_text(json.dumps(_spec([])))
    (tmp_path / "made/trials").write_text("not a folder")
    with pytest.raises(FileError, match=r"'[^']*made/trials' is a file, not a folder"):
        run("tool_rotation_arm", 2, seed=11, out=tmp_path / "made", workers=0,
            progress=False, **ARM)
    assert ran == []


def test_a_folder_through_a_symbolic_link_to_nothing_is_refused_naming_the_link(
        tmp_path, monkeypatch):
    # --out LINK (or LINK/sub), LINK a symbolic link whose target is gone: mkdir meets the
    # link ('File exists'), told as "'.' takes no new folder (File exists)", naming a
    # folder that was never the problem
    link = tmp_path / "link"
    link.symlink_to(tmp_path / "gone" / "campaign")
    ran = trials_run(monkeypatch)
    for out in (link, link / "sub"):
        with pytest.raises(FileError) as info:
            run("tool_rotation_arm", 2, out=out, workers=0, progress=False, **ARM)
        assert str(info.value) == (
            f"{out}: cannot make the campaign folder: '{link}' is a symbolic link to "
            f"'{tmp_path / 'gone' / 'campaign'}', which does not exist; expected a folder "
            "that can be made and written, or one there")
    assert ran == [] and not (tmp_path / "gone").exists()


def test_a_lock_file_that_is_a_link_or_a_fifo_is_refused_and_nothing_is_overwritten(
        tmp_path, monkeypatch):
    # campaign.lock a symbolic link to another file: the run wrote its pid over that file
    # ('precious' became '{"pid": ..., "host": ...}'); a FIFO (or a link to /dev/null):
    # "machinesim: error: Invalid argument", naming no file
    import os

    ran = trials_run(monkeypatch)
    victim = tmp_path / "victim.txt"
    victim.write_text("precious\n")
    for k, (make, said) in enumerate((
            (lambda lock: lock.symlink_to(victim),
             f"campaign.lock is a symbolic link (to '{victim}'); expected the campaign's own "
             "lock file, which each run writes its pid into: remove the link"),
            (lambda lock: os.mkfifo(lock),
             "campaign.lock is a named pipe (FIFO), not a regular file; expected the "
             "campaign's own lock file: remove it"))):
        out = tmp_path / f"campaign{k}"
        out.mkdir()
        make(out / "campaign.lock")
        with pytest.raises(FileError) as info:
            run("tool_rotation_arm", 2, out=out, workers=0, progress=False, **ARM)
        assert str(info.value) == f"{out}: {said}"
        assert sorted(p.name for p in out.iterdir()) == ["campaign.lock"]
    assert ran == [] and victim.read_text() == "precious\n"


def test_a_lock_that_is_a_folder_or_a_link_to_nothing_is_refused_naming_what_it_is(
        tmp_path, monkeypatch):
    # campaign.lock a folder was refused as "cannot make the campaign's lock campaign.lock:
    # Is a directory", an open that failed for another reason ('No such file or directory':
    # the folder removed meanwhile) alike, each with no "expected"
    import errno
    import os

    ran = trials_run(monkeypatch)
    expected = "expected the campaign's own lock file, which each run writes its pid into"
    out = tmp_path / "folder"
    (out / "campaign.lock").mkdir(parents=True)
    with pytest.raises(FileError) as info:
        run("tool_rotation_arm", 2, out=out, workers=0, progress=False, **ARM)
    assert str(info.value) == (f"{out}: campaign.lock is a folder, not a regular file; "
                               f"{expected}: move the folder away or remove it")
    assert sorted(p.name for p in out.iterdir()) == ["campaign.lock"]
    # a link to nothing: the link, its target named
    out = tmp_path / "dangling"
    out.mkdir()
    (out / "campaign.lock").symlink_to(tmp_path / "nowhere" / "lock")
    with pytest.raises(FileError) as info:
        run("tool_rotation_arm", 2, out=out, workers=0, progress=False, **ARM)
    assert str(info.value) == (f"{out}: campaign.lock is a symbolic link (to "
                               f"'{tmp_path / 'nowhere' / 'lock'}'); {expected}: remove the "
                               "link")
    assert not (tmp_path / "nowhere").exists()
    # any other refusal of the open names what is (not) there and what was expected
    real_open = os.open

    def refused(path, *args, **kwargs):
        if str(path).endswith("campaign.lock"):
            raise FileNotFoundError(errno.ENOENT, os.strerror(errno.ENOENT), str(path))
        return real_open(path, *args, **kwargs)

    out = tmp_path / "gone"
    monkeypatch.setattr(os, "open", refused)
    with pytest.raises(FileError) as info:
        run("tool_rotation_arm", 2, out=out, workers=0, progress=False, **ARM)
    monkeypatch.setattr(os, "open", real_open)
    assert str(info.value) == (f"{out}: cannot open or make the campaign's lock campaign.lock, "
                               "which does not exist: No such file or directory; "
                               f"{expected}, in a folder this run can write")
    assert ran == []


@pytest.mark.skipif(not __import__("os").path.isdir("/proc/self"), reason="no /proc")
def test_a_folder_the_file_system_will_not_make_is_refused_before_any_trial(monkeypatch):
    # /proc takes no new folder: mkdir says 'No such file or directory' of a folder whose
    # parent is there, which the message gave as the whole reason
    ran = trials_run(monkeypatch)
    out = "/proc/self/machinesim_campaign"
    with pytest.raises(FileError) as info:
        run("tool_rotation_arm", 2, out=out, workers=0, progress=False, **ARM)
    assert str(info.value).startswith(f"{out}: cannot make the campaign folder: '/proc/self' "
                                      "takes no new folder (")
    assert ran == []


@pytest.mark.parametrize("stop", [OSError(28, "No space left on device"),
                                  KeyboardInterrupt()])
def test_a_trial_file_whose_write_is_cut_short_is_not_left(begun, tmp_path, monkeypatch,
                                                           stop):
    """A full disk, or a Ctrl-C, while trial 2's file is written: the run stops (a
    FileError naming the file, or the interrupt), trials 0 and 1 stay whole, trial 2's file
    is not there, half written or at all, nor its temporary file; the rerun runs trial 2."""
    import machinesim._io as io_module

    source, ds = begun
    shutil.copytree(source, tmp_path / "c")
    out = tmp_path / "c"
    kept = {p.name: p.read_bytes() for p in (out / "trials").iterdir()}
    real = io_module.os.fsync

    def cut_short(fd):
        raise stop

    monkeypatch.setattr(io_module.os, "fsync", cut_short)
    ran = trials_run(monkeypatch)
    with pytest.raises(FileError if isinstance(stop, OSError) else KeyboardInterrupt) as info:
        run("tool_rotation_arm", 3, vary=VARY, seed=11, out=out, workers=0, progress=False,
            report=False, **ARM)
    if isinstance(stop, OSError):
        assert str(info.value) == (f"{out / 'trials/trial_000002.json'}: cannot write: "
                                   "No space left on device")
    assert ran == [2]
    assert {p.name: p.read_bytes() for p in (out / "trials").iterdir()} == kept
    monkeypatch.setattr(io_module.os, "fsync", real)
    again = run("tool_rotation_arm", 3, vary=VARY, seed=11, out=out, workers=0,
                progress=False, report=False, **ARM)
    assert ran == [2, 2]
    for name in ("drawn", "identified"):
        assert np.array_equal(again[name].values[:2], ds[name].values), name
