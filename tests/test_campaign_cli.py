"""machinesim campaign, the command: its refusals, a machine's warning once, Ctrl-C and an
out-of-memory trial saying which trials are kept (and the API's interruption too).

Trials run paper 000's calibration alone (``identify_only``: ~1.5 s each), a few per test.
"""

from __future__ import annotations

import json

import pytest
import xarray as xr

import machinesim.campaign.runner as runner
import machinesim.campaign.spec as spec_module
import machinesim.campaign.trials as trials_module
from machinesim.campaign import CampaignSpec, run
from machinesim.campaign.trials import MAX_TRIALS
from machinesim.cli import main as cli_main
from machinesim.exceptions import InputError, MachineSimError

UM = 1e-6
ARM = dict(identify_only=True)


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


@pytest.mark.parametrize(("option", "value", "expected"), [
    ("--trials", "1e3", "--trials '1e3'; expected a whole number from 1 to 100000"),
    ("--seed", "1e3", "--seed '1e3'; expected a whole number >= 0"),
    ("--workers", "two", "--workers 'two'; expected a whole number >= 0 (0: no Dask)"),
])
def test_cli_refuses_a_whole_number_option_that_is_not_one_as_in_python(
        tmp_path, capsys, option, value, expected):
    """'--seed 1e3' was argparse's "invalid int value: '1e3'" with the usage, while '--seed
    -1' and CampaignSpec(seed=1e3) are the campaign's own one line: now all are."""
    options = {"--trials": "2", "--seed": "0", "--workers": "0", option: value}
    command = ["campaign", "tool_rotation_arm", "--out", str(tmp_path / "c")]
    for name, given in options.items():
        command += [name, given]
    status = cli_main(command)
    err = capsys.readouterr().err
    assert status == 2, err
    assert len(err.splitlines()) == 1, err
    assert err.startswith(f"machinesim: error: key '{option}': {expected}"), err
    assert not (tmp_path / "c").exists()


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


def test_cli_a_full_disk_says_which_trials_are_kept_and_the_rerun_resumes(tmp_path, capsys,
                                                                          monkeypatch):
    """A disk that fills after the first trial: the refusal said only "cannot write: No
    space left on device", not that the finished trial is kept and a rerun resumes."""
    import errno
    import os

    from machinesim import _io

    real_fsync, real = os.fsync, runner.run_trial
    ran = []

    def full_once_a_trial_ran(fd):
        if len(ran) > 1:  # as the second trial's file is written
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        real_fsync(fd)

    monkeypatch.setattr(runner, "run_trial", lambda spec, i: ran.append(i) or real(spec, i))
    command = ["campaign", "tool_rotation_arm", "--trials", "2", "--workers", "0",
               "--identify-only", "--quiet", "--seed", "5", "--out", str(tmp_path)]
    monkeypatch.setattr(_io.os, "fsync", full_once_a_trial_ran)
    assert cli_main(command) == 2
    err = capsys.readouterr().err
    trial = tmp_path / "trials" / "trial_000001.json"
    assert err.strip() == (
        f"machinesim: error: {trial}: cannot write: No space left on device; the campaign "
        f"stopped; kept the 1 finished trial file in {tmp_path / 'trials'} "
        "(trial_000000.json) and campaign.json: run the same command again to resume (only "
        "the missing trials run) once the file can be written"), err

    monkeypatch.setattr(_io.os, "fsync", real_fsync)
    ran.clear()
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


@pytest.mark.parametrize("chained", [True, False], ids=["its cause", "swallowed"])
def test_a_ctrl_c_a_library_turned_into_an_import_error_is_the_interrupted_line(
        tmp_path, capsys, monkeypatch, chained):
    """A Ctrl-C landing as a pybind11 module initialised (matplotlib's, scipy's, imported as
    the command runs) comes out of the import as "ImportError: initialization failed", the
    Ctrl-C its cause; the command said "machinesim: internal error: ImportError:
    initialization failed (a bug in machinesim ...)", status 1. A library that swallows the
    Ctrl-C and raises something else (no cause) is the same stop."""
    import os
    import signal
    import time

    import machinesim.campaign.cli as campaign_cli

    def importing(args):
        if chained:
            try:
                raise KeyboardInterrupt  # as the signal's handler raises it in the import
            except KeyboardInterrupt as stop:
                raise ImportError("initialization failed") from stop
        try:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(5)  # the handler raises within
        except BaseException:  # noqa: BLE001 - a library's own catch-all, as in an import
            pass
        raise ImportError("initialization failed")

    monkeypatch.setattr(campaign_cli, "run_campaign", importing)
    # Python's own Ctrl-C, as a terminal's command has it: a runner started as a shell's
    # background job inherits SIGINT ignored, and the os.kill above would then do nothing
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        status = cli_main(["campaign", "tool_rotation_arm", "--trials", "2", "--workers", "0",
                           "--quiet", "--out", str(tmp_path / "c")])
    finally:
        signal.signal(signal.SIGINT, previous)
    assert status == 130
    assert capsys.readouterr().err.strip() == "machinesim: interrupted; nothing was written"
    # an ImportError of no stop is still what it is
    monkeypatch.setattr(campaign_cli, "run_campaign", lambda args: __import__("no_such_mod"))
    assert cli_main(["campaign", "tool_rotation_arm", "--trials", "2", "--workers", "0",
                     "--quiet", "--out", str(tmp_path / "c")]) == 1
    assert "internal error: ModuleNotFoundError" in capsys.readouterr().err


@pytest.mark.parametrize("command", [True, False], ids=["the command", "an importer"])
def test_a_ctrl_c_while_the_command_line_loads_is_one_line(command):
    """SIGINT 0.12 to 0.19 s after ``machinesim campaign ...`` started landed in the imports
    of machinesim.cli (before its main), and ended in Python's traceback of that import
    (status -2); one landing in numpy's loading read "machinesim: internal error:
    ImportError: IMPORTANT: PLEASE READ THIS ... Importing the numpy C-extensions failed" (25
    lines, status 1). machinesim._cli_start, cli's first import, says one line and ends
    with 130 when the program is the command; a program that imports it keeps its Ctrl-C."""
    import os
    import signal
    import subprocess
    import sys

    code = ("import os, signal, sys, time\n"
            f"sys.argv[0] = {'machinesim' if command else 'mine.py'!r}\n"
            "import machinesim._cli_start\n"
            "os.kill(os.getpid(), signal.SIGINT)\n"
            "time.sleep(5)\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
                          env={**os.environ}, timeout=60)
    if command:
        assert (done.returncode, done.stderr) == (
            130, "machinesim: interrupted; nothing was written\n")
    else:
        assert done.returncode == -signal.SIGINT and "KeyboardInterrupt" in done.stderr


@pytest.mark.parametrize(("name", "how", "status"), [("SIGTERM", "terminated", 143),
                                                   ("SIGHUP", "hung up", 129),
                                                   ("SIGTERM", None, -15)],
                         ids=["sigterm", "sighup", "a spawned worker"])
def test_a_sigterm_or_sighup_while_the_command_line_loads_is_one_line(name, how, status,
                                                                      as_in_a_terminal):
    """``kill PID`` (or a closed terminal) while machinesim.cli loads ended the process by
    the signal, no line, -15 (-1) to a parent, where the same in the command says
    'terminated' and 143 (docs/cli.md's exit codes). A process multiprocessing spawned
    (multiprocessing.spawn loaded before the command's module: a campaign's Dask worker)
    keeps the default: its parent ends it with SIGTERM, and it never reaches main."""
    import os
    import subprocess
    import sys

    code = ("import os, signal, sys, time\n"
            + ("import multiprocessing.spawn\n" if how is None else "")
            + "sys.argv[0] = 'machinesim'\n"
            "import machinesim._cli_start\n"
            f"os.kill(os.getpid(), signal.{name})\n"
            "time.sleep(5)\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env={**os.environ}, timeout=60, **as_in_a_terminal)
    said = "" if how is None else f"machinesim: {how}; nothing was written\n"
    assert (done.returncode, done.stderr) == (status, said)


def test_the_command_lines_main_puts_pythons_ctrl_c_back():
    """Once main runs, a Ctrl-C is the command's (ctrl_c_remembered's: the trials kept are
    named), not the loading's "nothing was written". Once it returned, the command is done
    and said: a Ctrl-C is ignored to the exit (`machinesim.scenario_start.finished`), which
    replaces Python's handler only (the loading's would have stayed)."""
    import signal
    import subprocess
    import sys

    code = ("import signal, sys\n"
            "sys.argv[0] = 'machinesim'\n"
            "import machinesim.cli, machinesim._cli_start as start\n"
            "print(signal.getsignal(signal.SIGINT) is start.on_ctrl_c)\n"
            "try:\n    machinesim.cli.main(['--version'])\nexcept SystemExit:\n    pass\n"
            "print(signal.getsignal(signal.SIGINT) is signal.SIG_IGN)\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
                          check=True, timeout=60)
    said = done.stdout.split()  # True, the version's line, True
    assert (said[0], said[-1]) == ("True", "True"), done.stdout


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
