"""machinesim.campaign.run given what a user may pass by mistake: refused with an InputError
naming the value before a folder is made or a trial runs, or, where only a trial's draw
shows it, that trial failed with its message."""

from __future__ import annotations

import io
import json
import os
import re

import pytest

import machinesim.campaign.runner as runner
from machinesim.campaign import CampaignSpec, run
from machinesim.exceptions import InputError

ARM = dict(identify_only=True, workers=0, progress=False)


@pytest.mark.parametrize("flag, value", [("noise", "off"), ("noise", "on"), ("noise", 0),
                                         ("identify_only", "yes"), ("quick", None)])
def test_a_switch_that_is_not_true_or_false_is_refused(flag, value):
    """``noise="off"`` (the command's ``--noise off`` in Python) is a true string: it ran
    every trial with the noise on, and wrote "off" into campaign.json."""
    with pytest.raises(InputError, match=rf"{flag}={value!r}; expected True or False"):
        CampaignSpec("tool_rotation_arm", 1, **{flag: value})


@pytest.mark.parametrize("flag", ["progress", "report"])
def test_run_refuses_a_progress_or_report_that_is_not_true_or_false(flag, tmp_path):
    with pytest.raises(InputError, match=rf"{flag}='no'; expected True or False"):
        run("tool_rotation_arm", 1, out=tmp_path / "c", **{**ARM, flag: "no"})
    assert not (tmp_path / "c").exists()


def test_noise_false_reads_exact_values(tmp_path):
    """The switch as a bool does what it says (numpy's bool too): with the noise off the
    arm's calibration reads exact values, so two seeds identify the same."""
    import numpy as np

    one = run("tool_rotation_arm", 1, out=tmp_path / "a", noise=np.False_, seed=1, **ARM)
    two = run("tool_rotation_arm", 1, out=tmp_path / "b", noise=False, seed=2, **ARM)
    assert one.identified.values.tolist() == two.identified.values.tolist()
    assert one.attrs["noise"] == 0


@pytest.mark.parametrize("given, words", [
    ({"trials": 0}, "key 'trials': trials=0; expected a whole number from 1 to 100000 "),
    ({"trials": 2.0}, "key 'trials': trials=2.0; expected a whole number from 1 to 100000 "),
    ({"seed": -1}, "key 'seed': seed=-1; expected a whole number >= 0"),
    ({"workers": -1}, r"key 'workers': workers=-1; expected a whole number >= 0 \(0: no "),
    ({"workers": "two"}, "key 'workers': workers='two'; expected a whole number >= 0")])
def test_a_count_that_is_no_whole_number_is_refused_naming_the_argument(given, words,
                                                                        tmp_path):
    """campaign.run(..., trials=0) had answered "key '--trials': --trials 0; ...", naming the
    command line's flag to a Python caller; the command keeps --trials (test_campaign_cli)."""
    arguments = {"trials": 1, **ARM, **given}
    with pytest.raises(InputError, match=words) as info:
        run("tool_rotation_arm", out=tmp_path / "c", **arguments)
    assert "--" not in str(info.value)
    assert not (tmp_path / "c").exists()


@pytest.mark.parametrize("vary, words", [
    (5, "vary=5; expected PARAM=DIST texts"),
    ([5], r"vary item 5; expected PARAM=DIST or a \(name, DIST\) pair"),
    ([("tool.y",)], r"vary item \('tool.y',\); expected PARAM=DIST or a \(name, DIST\)"),
    ({"tool.y": "normal:0,5"}, "'5' has no unit")])
def test_a_vary_that_is_no_parameter_and_distribution_is_refused(vary, words, tmp_path):
    with pytest.raises(InputError, match=words):
        run("tool_rotation_arm", 1, vary=vary, out=tmp_path / "c", **ARM)
    assert not (tmp_path / "c").exists()


@pytest.mark.parametrize("out", [None, 123, ""])
def test_an_out_that_is_no_folder_name_is_refused(out):
    with pytest.raises(InputError, match=rf"out={out!r}; expected the campaign folder"):
        run("tool_rotation_arm", 1, out=out, **ARM)


def test_a_dict_or_pairs_of_dist_texts_vary_as_the_commands_texts(tmp_path):
    """``{"tool.y": "-170um"}`` and ``[("tool.y", "-170um")]`` draw what
    ``"tool.y=-170um"`` draws (a fixed -170 um); ``vary=None`` varies nothing; numpy's
    integers are whole numbers for ``workers`` as for ``trials``."""
    import numpy as np

    texts = run("tool_rotation_arm", 1, vary=["tool.y=-170um"], out=tmp_path / "a", **ARM)
    for i, vary in enumerate(({"tool.y": "-170um"}, [("tool.y", "-170um")])):
        ds = run("tool_rotation_arm", 1, vary=vary, out=tmp_path / f"b{i}", **ARM)
        assert ds.drawn.values.tolist() == texts.drawn.values.tolist() == [[-170 * 1e-6]]
    none = run("tool_rotation_arm", 1, vary=None, out=tmp_path / "c",
               **{**ARM, "workers": np.int64(0)})
    assert "drawn" not in none and none.attrs["vary"] == "{}"  # nothing varied


def test_a_landing_beyond_the_error_models_range_fails_its_trial_not_the_campaign(tmp_path):
    """``robot.repeatability=10m`` (m for um) lands the part metres off: trial 0's landing
    (per-axis s = RP / 3.616) is beyond the error model's 1 m. It was drawn before the
    trial's guard, so the whole campaign stopped with a bare "key 'delta'" message after
    making its folder; it is that trial's failure now, naming the repeatability, as a
    tool.y of 1000 mm is. (A fixed 10m is refused before any trial now, test_campaign_folders;
    a uniform from 10 um, which the robot takes at its LOW, draws trial 0's beyond it.)"""
    import json

    ds = run("workpiece_setting", 1, vary=["robot.repeatability=uniform:10um,10m"],
             out=tmp_path / "c", **ARM)
    assert ds.failed.values.tolist() == [1]
    assert ds.drawn.values[0, 0] > 75.8e-3  # beyond the robot's 75.7 mm (20 mm lever)
    error = json.loads(ds.attrs["errors"])["0"]
    drawn = ds.drawn.values[0, 0]
    assert error.startswith("InputError: key 'robot.repeatability': the robot's landing at "
                            f"robot.repeatability {drawn * 1e6:g} um: a robot of "
                            f"repeatability {drawn:g} m"), error


def test_a_noise_drawn_below_zero_is_kept_as_the_zero_the_lab_read_with():
    """``normal:60nm,20nm`` draws below zero in 0.13 % of trials, which the lab takes as
    zero (docs/campaigns.md); the trial's ``drawn`` (the Dataset's, the sensitivities')
    held the negative draw: trial 1497 of seed 0 draws 60 nm + 20 nm x -3.02, -0.47 nm."""
    from machinesim.campaign import parse_vary, run_trial
    from machinesim.campaign.trials import draw, trial_seed
    from machinesim.streams import stream

    raw = 60e-9 + 20e-9 * stream(trial_seed(0, 1497), "campaign",
                                 "microscope.sigma").standard_normal()
    assert raw == pytest.approx(-0.4728e-9, abs=1e-13)
    spec = CampaignSpec("tool_rotation_arm", 1500,
                        (parse_vary("microscope.sigma=normal:60nm,20nm"),), identify_only=True)
    drawn, _, lab = draw(spec, 1497)
    assert drawn == {"microscope.sigma": 0.0} and lab == {"microscope.sigma": 0.0}
    record = run_trial(spec, 1497)
    assert record["drawn"] == {"microscope.sigma": 0.0} and record["error"] is None


def test_a_run_with_every_trial_already_there_prints_no_empty_line(tmp_path, capsys):
    """The progress line is ended with a newline only where one was shown: resuming a
    finished campaign printed a blank line before its result."""
    run("tool_rotation_arm", 1, out=tmp_path / "c", **{**ARM, "progress": True})
    err = capsys.readouterr().err  # no terminal: a whole line, no '\r'
    assert err.startswith("campaign: 1/1 trials") and err.endswith(" s left\n") and "\r" not in err
    run("tool_rotation_arm", 1, out=tmp_path / "c", **{**ARM, "progress": True})
    assert capsys.readouterr().err == ""


def test_a_distribution_built_in_python_is_checked_and_kept_by_its_values(tmp_path):
    """A `Distribution` passed as such went past every check of its text (a negative noise
    taken and drawn as zero, a kind "gauss" drawn as fixed) and campaign.json kept its empty
    text: extending a folder begun with uniform 10..20 nm with uniform 500..900 nm was taken
    as the same campaign, trial 2 drawing 554 nm beside 10 and 13 nm."""
    from machinesim.campaign import Distribution, parse_distribution
    from machinesim.campaign.results import CampaignFolder

    def spec(dist, name="microscope.sigma"):
        return CampaignSpec("tool_rotation_arm", 1, ((name, dist),), identify_only=True)

    built = spec(Distribution("uniform", 1e-8, 2e-8))
    assert built.describe()["vary"] == {"microscope.sigma": "uniform:1e-08m,2e-08m"}
    again = parse_distribution(built.describe()["vary"]["microscope.sigma"], "microscope.sigma")
    assert (again.kind, again.a, again.b) == ("uniform", 1e-8, 2e-8)  # exact round trip
    assert spec(Distribution("fixed", 3e-3), "workpiece.alpha").describe()["vary"] == \
        {"workpiece.alpha": "fixed:0.003rad"}
    CampaignFolder(tmp_path, built.describe())
    with pytest.raises(InputError, match="holds another campaign"):
        CampaignFolder(tmp_path, spec(Distribution("uniform", 5e-7, 9e-7)).describe())
    for dist, words in ((Distribution("uniform", -1e-8, 2e-8), "reaches below zero"),
                        (Distribution("gauss", 1e-8, 2e-8), "distribution 'gauss'"),
                        (Distribution("normal", 0.0, 1e-6, text="normal:0,2um"),
                         "text 'normal:0,2um' is not its values")):
        with pytest.raises(InputError, match=words):
            spec(dist, "tool.y" if "2um" in dist.text else "microscope.sigma")


def test_a_refused_python_distribution_shows_both_of_its_numbers():
    """``Distribution("poisson", 1, 2)`` was refused as ``poisson:1.0m``, its second number
    dropped; a fixed one with a second number was taken, the number ignored."""
    from machinesim.campaign import Distribution
    from machinesim.campaign.distributions import checked

    with pytest.raises(InputError, match=r"tool\.y=poisson:1\.0m,2\.0m'"):
        checked("tool.y", Distribution("poisson", 1, 2))
    with pytest.raises(InputError, match=r"fixed takes 1 number\(s\), got 2"):
        checked("tool.y", Distribution("fixed", 1e-6, 3e-6))
    with pytest.raises(InputError, match="'x'; expected numbers in SI"):
        checked("tool.y", Distribution("normal", "x", 1e-6))
    assert checked("tool.y", Distribution("fixed", 1e-6)).text == "fixed:1e-06m"


class _Clock:
    def __init__(self) -> None:
        self.now = 1000.0

    def __call__(self) -> float:
        return self.now


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def _steps(stream, times, total):
    """The progress of ``total`` trials, one finished at each of ``times`` (s), on ``stream``."""
    clock = _Clock()
    progress = runner._Progress(total, 0, stream, clock=clock)
    progress.start()
    for t in times:
        clock.now = 1000.0 + t
        progress.step({"error": None})
    progress.end()
    return stream.getvalue()


def test_progress_into_a_log_is_whole_lines_at_most_one_every_30_s():
    """Without a terminal the progress line went on writing its '\\r' updates, ~90 bytes a
    trial into a log file (one 'line' of 9 MB for 100000 trials); now whole lines: the first
    trial's, then at most one every LOG_EVERY_S (30 s), and the last."""
    log = _steps(io.StringIO(), [1.0 * k for k in range(1, 101)], 100)  # a trial a second
    assert "\r" not in log and log.endswith("\n")
    lines = log.splitlines()
    # trials 1, 31, 61, 91 (30 s apart), and 100, the last: trial k at k s, 1.00 trials/s
    assert [line.split(" trials (")[0] for line in lines] == \
        [f"campaign: {k}/100" for k in (1, 31, 61, 91, 100)]
    assert lines[1] == "campaign: 31/100 trials (0 resumed, 0 failed), 1.00 trials/s, 69 s left"
    assert lines[-1].endswith(", 1.00 trials/s, 0 s left")
    # stopped before the last (a Ctrl-C): the latest state is the last line
    stopped = _steps(io.StringIO(), [1.0 * k for k in range(1, 46)], 100).splitlines()
    assert [line.split(" trials (")[0] for line in stopped] == \
        [f"campaign: {k}/100" for k in (1, 31, 45)]


def test_progress_in_a_terminal_is_one_line_rewritten():
    shown = _steps(_Terminal(), [0.5 * k for k in range(1, 5)], 4)
    assert shown.count("\r") == 4 and shown.endswith(" s left\n") and shown.count("\n") == 1
    # updates within TTY_EVERY_S of the one before wait: 100 trials in 1 ms, two rewrites
    assert _steps(_Terminal(), [1e-5 * k for k in range(1, 101)], 100).count("\r") == 2


def _fake_trial(spec, i):
    return {"trial": i, "drawn": {}, "injected": {}, "identified": {}, "figures": {},
            "elapsed_s": 0.0, "error": None}


def test_a_second_campaign_on_a_folder_in_use_is_refused_naming_the_folder_and_pid(
        tmp_path, monkeypatch):
    """Two campaigns on one --out at once both ran the same missing trials, each writing
    every file. A campaign holds DIR/campaign.lock (its pid and host) while it runs; the
    second is refused, naming the folder and the first's pid, and runs nothing."""
    import json
    import socket
    import subprocess
    import sys

    ran = []
    monkeypatch.setattr(runner, "run_trial", lambda spec, i: ran.append(i) or _fake_trial(spec, i))
    out = tmp_path / "c"
    run("tool_rotation_arm", 1, out=out, report=False, **ARM)  # a campaign there, one trial
    assert ran == [0] and _lock_free(out / "campaign.lock")  # released at the end
    other = subprocess.Popen(  # a campaign's process, holding the folder's lock
        [sys.executable, "-c", "import sys, time\n"
         "from machinesim.campaign.results import locked\n"
         "with locked(sys.argv[1]):\n    print('held', flush=True)\n    time.sleep(60)",
         str(out)], stdout=subprocess.PIPE, text=True)
    try:
        assert other.stdout.readline() == "held\n"
        lock = {"pid": other.pid, "host": socket.gethostname()}
        assert json.loads((out / "campaign.lock").read_text()) == lock
        with pytest.raises(InputError) as info:
            run("tool_rotation_arm", 3, out=out, report=False, **ARM)
        message = str(info.value)
        assert message.startswith(f"{out}: another campaign is running in this folder "
                                  f"(pid {other.pid}, holding {out / 'campaign.lock'})")
        assert ran == [0] and json.loads((out / "campaign.lock").read_text()) == lock
        (out / "campaign.lock").write_text("")  # held, its pid not written yet (or damaged)
        with pytest.raises(InputError, match="does not say which process"):
            run("tool_rotation_arm", 3, out=out, report=False, **ARM)
    finally:
        other.kill()
        other.wait()
    assert ran == [0]


def test_a_folder_another_run_is_making_a_campaign_folder_is_refused_as_busy(tmp_path):
    """Two campaigns started on one new --out at the same instant: the second found the
    first's campaign.json being written (its temporary file there, no campaign.json yet),
    and before taking the lock refused the folder as "holds .campaign.json.PID@...tmp but
    no campaign.json: not a campaign folder (a scenario's report, ...)", where it is a
    campaign's, running. It is refused as the running campaign's, as a moment later; a
    temporary file a killed run left (no lock held) is refused as foreign, as it was."""
    import fcntl
    import os
    import socket

    out = tmp_path / "c"
    out.mkdir()
    temporary = out / f".campaign.json.{os.getpid()}@0f62b50f-wfu1kvvo.tmp"
    temporary.write_text("{")
    fd = os.open(out / "campaign.lock", os.O_RDWR | os.O_CREAT)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)  # the first run, making the folder
        os.write(fd, json.dumps({"pid": os.getpid(), "host": socket.gethostname()}).encode())
        with pytest.raises(InputError) as info:
            run("tool_rotation_arm", 1, out=out, report=False, **ARM)
        assert str(info.value).startswith(
            f"{out}: another campaign is running in this folder (pid {os.getpid()}, "
            f"holding {out / 'campaign.lock'})"), info.value
    finally:
        os.close(fd)  # the first run killed: its temporary file left, its lock free
    with pytest.raises(InputError, match=r"holds \.campaign\.json\..*\.tmp but no campaign"):
        run("tool_rotation_arm", 1, out=out, report=False, **ARM)
    assert sorted(os.listdir(out)) == sorted(["campaign.lock", temporary.name])


def test_a_second_ctrl_c_while_the_cluster_closes_waits_for_the_close(tmp_path, monkeypatch):
    """An impatient user's Ctrl-C pressed again while the campaign closed its local cluster
    after the first broke into the close: the cluster was left to Dask's atexit, which the
    next Ctrl-C broke into too, "Exception ignored in atexit callback: <function
    close_clusters ...> ... KeyboardInterrupt" after the command's line. The close now
    finishes first, and the Ctrl-C held meanwhile is raised after it."""
    import signal

    closed = []

    class Client:
        def close(self):
            os.kill(os.getpid(), signal.SIGINT)  # the second Ctrl-C, as the client closes
            closed.append("client")

    class Cluster:
        def close(self):
            closed.append("cluster")

    def windowed(client, function, spec, indices):
        raise KeyboardInterrupt  # the first Ctrl-C, while the trials run
        yield

    monkeypatch.setattr(runner, "_client", lambda *args: (Client(), Cluster()))
    monkeypatch.setattr(runner, "windowed", windowed)
    usual = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with pytest.raises(KeyboardInterrupt):
            run("tool_rotation_arm", 2, out=tmp_path / "c", **{**ARM, "workers": 2})
    finally:
        signal.signal(signal.SIGINT, usual)
    assert closed == ["client", "cluster"]


def _lock_free(path) -> bool:
    """Whether no open file holds the lock ``path`` (flock: a lock another open file of
    this very process holds refuses it too)."""
    import fcntl
    import os

    fd = os.open(path, os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        return False
    finally:
        os.close(fd)
    return True


def test_a_lock_left_by_a_killed_campaign_is_taken_over(tmp_path, monkeypatch):
    """A campaign killed by SIGKILL leaves its lock file, which no process holds any more:
    the next run on the folder takes it over, whichever pid it names: one gone, this very
    process's (a container started again gives its process the same pid), or a live
    process's that is no campaign (the pid taken again since), which was refused as held,
    or one of another host (a shared file system), refused as held as well, though the
    file stays after every run. The file then names this run, no longer held."""
    import json
    import os
    import socket
    import subprocess
    import sys

    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()
    other = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    held = []

    def trial(spec, i):
        held.append(json.loads((out / "campaign.lock").read_text())["pid"])
        return _fake_trial(spec, i)

    monkeypatch.setattr(runner, "run_trial", trial)
    out = tmp_path / "c"
    out.mkdir()
    try:
        here = socket.gethostname()
        for trials, pid, host in ((1, gone.pid, here), (2, os.getpid(), here),
                                  (3, other.pid, here), (4, 1, "elsewhere")):
            (out / "campaign.lock").write_text(json.dumps({"pid": pid, "host": host}))
            run("tool_rotation_arm", trials, out=out, report=False, **ARM)
            assert json.loads((out / "campaign.lock").read_text()) == {"pid": os.getpid(),
                                                                        "host": here}
            assert _lock_free(out / "campaign.lock")
    finally:
        other.kill()
        other.wait()
    assert held == [os.getpid()] * 4  # trials 0, 1, 2, then 3, under this run's lock


def test_a_python_without_posix_file_locks_is_told_so(tmp_path, monkeypatch):
    """Campaigns lock their folder with fcntl.flock; a Python without fcntl (Windows) gets
    a FileError saying so, before anything is made, not a traceback."""
    import sys

    from machinesim.campaign.results import locked
    from machinesim.exceptions import FileError

    monkeypatch.setitem(sys.modules, "fcntl", None)  # import fcntl: ImportError
    with pytest.raises(FileError, match="campaigns need POSIX file locks"):
        with locked(tmp_path / "c"):
            pass
    assert not (tmp_path / "c").exists()


def _race_for_the_lock(out: str, lined_up, ran, refused) -> None:
    """One of two runs racing for ``out``'s stale lock (`test_two_runs_...`): each waits for
    the other where it has read the lock it found (the stale pid, as a stale lock was taken
    over before) or is about to lock it (flock), and one then goes on 0.2 s after the other
    (the one the slower to replace the stale lock)."""
    import contextlib
    import fcntl
    import os
    import threading
    import time

    from machinesim.campaign import lock

    first = [True]

    def both_there() -> None:
        index = 1
        with contextlib.suppress(threading.BrokenBarrierError):
            index = lined_up.wait(10)
        if index == 0:
            time.sleep(0.2)

    read, flock = lock._lock_holder, fcntl.flock

    def lined_up_holder(path):
        held = read(path)
        if first[0]:
            first[0] = False
            both_there()
        return held

    def lined_up_flock(fd, operation):
        if first[0]:
            first[0] = False
            both_there()
        return flock(fd, operation)

    lock._lock_holder, fcntl.flock = lined_up_holder, lined_up_flock
    try:
        with lock.locked(out):
            ran.put(os.getpid())
            time.sleep(1.0)  # the run: the other is refused meanwhile, not after
    except InputError as error:
        refused.put(str(error))


def test_two_runs_finding_one_stale_lock_at_once_do_not_both_take_it(tmp_path):
    """A killed campaign's lock is taken over; two runs that found it at the same instant
    both took it (each removed the stale file, or the other's fresh one, and made its own)
    and ran the same trials side by side. Now the lock is the kernel's (flock on the open
    file, released when its process ends): of two processes lined up on one stale lock,
    exactly one runs, three times over, and the other is refused naming the one that runs."""
    import json
    import multiprocessing
    import socket
    import subprocess
    import sys

    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()
    context = multiprocessing.get_context("spawn")
    for k in range(3):
        out = tmp_path / f"c{k}"
        out.mkdir()
        (out / "campaign.lock").write_text(json.dumps({"pid": gone.pid,
                                                       "host": socket.gethostname()}))
        lined_up, ran, refused = context.Barrier(2), context.Queue(), context.Queue()
        racers = [context.Process(target=_race_for_the_lock,
                                  args=(str(out), lined_up, ran, refused)) for _ in range(2)]
        for racer in racers:
            racer.start()
        for racer in racers:
            racer.join(60)
        assert [racer.exitcode for racer in racers] == [0, 0]
        winners = [ran.get(timeout=5) for _ in range(ran.qsize())]
        assert len(winners) == 1, f"race {k}: {len(winners)} runs took the lock"
        message = refused.get(timeout=5)
        assert f"another campaign is running in this folder (pid {winners[0]}," in message
        assert json.loads((out / "campaign.lock").read_text()) == {
            "pid": winners[0], "host": socket.gethostname()}  # kept, naming the last run


def test_a_trial_that_raises_a_fault_fails_that_trial_and_the_campaign_goes_on(
        tmp_path, monkeypatch):
    """A trial whose run raised anything but a MachineSimError (a ZeroDivisionError some
    draw met) ended the whole campaign in a traceback, and the same command, resumed, ran
    that trial into it again: a campaign that could never finish. It is that trial's
    failure now, named as a fault with where it was raised; the other trials run."""
    import machinesim.campaign.trials as trials
    from machinesim.experiment import run as real_run

    def failing(procedure, lab):
        if lab.seed.spawn_key == (1,):
            return 1 / 0
        return real_run(procedure, lab)

    monkeypatch.setattr(trials, "run", failing)
    ds = run("tool_rotation_arm", 2, out=tmp_path, workers=0, progress=False,
             identify_only=True)
    assert list(ds["failed"].values) == [0, 1]
    message = json.loads(ds.attrs["errors"])["1"]
    assert message.startswith("ZeroDivisionError: division by zero (not a MachineSimError: "
                              "a fault of machinesim met by this trial's draws, raised at ")
    assert re.search(r"raised at test_campaign_api\.py:\d+ in failing; please report it "
                     r"with the campaign's command\)$", message)
    assert json.loads((tmp_path / "trials" / "trial_000001.json").read_text())["error"] \
        == message
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["failures"] == [{"message": message, "trials": [1]}]


def test_a_trial_out_of_memory_is_no_failure_of_its_draws_and_runs_again_on_resuming(
        tmp_path, monkeypatch):
    """A MemoryError (the machine's memory, under the command's cap, with other trials beside
    it) was kept as the trial's failure, said to be 'a fault of machinesim ... please report
    it', and the resumed campaign skipped the trial for good. It ends the campaign as before
    the faults were kept: the finished trials kept, and the same command runs it again."""
    import machinesim.campaign.trials as trials
    from machinesim.experiment import run as real_run

    def hungry(procedure, lab):
        if lab.seed.spawn_key == (1,):
            raise MemoryError
        return real_run(procedure, lab)

    monkeypatch.setattr(trials, "run", hungry)
    with pytest.raises(MemoryError):
        run("tool_rotation_arm", 2, out=tmp_path, workers=0, progress=False,
            identify_only=True)
    assert sorted(p.name for p in (tmp_path / "trials").iterdir()) == ["trial_000000.json"]
    monkeypatch.setattr(trials, "run", real_run)  # memory again: the same command resumes
    ds = run("tool_rotation_arm", 2, out=tmp_path, workers=0, progress=False,
             identify_only=True)
    assert list(ds["failed"].values) == [0, 0]
    assert json.loads(ds.attrs["errors"]) == {}


@pytest.mark.parametrize("client", ["tcp://127.0.0.1:8786", 3])
def test_a_client_that_is_no_dask_client_is_refused_before_anything_is_written(tmp_path,
                                                                               client):
    # a scheduler's address given as client= was taken, campaign.json written, and the
    # campaign ended in Dask's 'ValueError: No clients found'
    out = tmp_path / "out"
    with pytest.raises(InputError) as info:
        run("tool_rotation_arm", 1, out=out, client=client, progress=False,
            identify_only=True)
    assert str(info.value) == (f"key 'client': client={client!r}; expected a "
                               "distributed.Client (a scheduler's address goes as "
                               "scheduler='tcp://host:8786')")
    assert not out.exists()


@pytest.mark.parametrize("procedure", [["tool_rotation_arm"], {"a": 1}, None, "arm"])
def test_a_procedure_that_is_no_procedures_name_is_refused_by_name(tmp_path, procedure):
    # a list or a dict raised "TypeError: unhashable type: 'list'" from the look-up
    with pytest.raises(InputError) as info:
        CampaignSpec(procedure, 1)
    assert str(info.value).startswith(f"key 'procedure': procedure {procedure!r}; expected "
                                      "one of tool_rotation_arm, ")
    with pytest.raises(InputError, match=r"key 'procedure': procedure "):
        run(procedure, 1, out=tmp_path / "out", workers=0, progress=False)
    assert not (tmp_path / "out").exists()
