"""The error budget's reruns on worker processes (`machinesim.budget.error_budget` ``jobs``,
`machinesim._processes.in_processes`): the same budget to the bit, Ctrl-C and errors end
every worker."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import textwrap
import time
from functools import partial
from pathlib import Path

import numpy as np
import psutil
import pytest

from machinesim._processes import in_processes
from machinesim.budget import error_budget
from machinesim.exceptions import InputError

ROOT = Path(__file__).resolve().parents[1]


def _workers(parent: psutil.Process) -> list[psutil.Process]:
    """``parent``'s worker processes (multiprocessing's spawned ones; not its resource
    tracker, one per process, which ends with it). A child that has ended and not been
    reaped (a zombie: another test's, under a PID 1 that reaps none) has no command line and
    is no worker: psutil raised ZombieProcess for it in CI."""
    found = []
    for child in parent.children():
        try:
            if "spawn_main" in " ".join(child.cmdline()):
                found.append(child)
        except (psutil.ZombieProcess, psutil.NoSuchProcess):
            continue
    return found


def _arm_lab(realism):
    """Paper 000's lab (docs/budget.md): planer_4axis, e_ys = -178 um, r = 120.555 mm."""
    from machinesim import Lab, load_machine
    from machinesim.errors import ErrorModel
    from machinesim.identification.tool_rotation_arm import arm_radius

    machine = load_machine("planer_4axis")
    errors = ErrorModel().with_parameters({"tool.y": -178.0e-6,
                                           "tool.z": -(120.555e-3 - arm_radius(machine))})
    return Lab(machine, errors, seed=0, realism=realism)


def _arm_rerun(source, realism):
    """Module level, so that a partial of it pickles: the worker imports this file."""
    from machinesim.experiment import run
    from machinesim.procedures.tool_rotation_arm import ToolRotationArm

    return run(ToolRotationArm(), _arm_lab(realism.without(source)))


def test_reruns_on_two_worker_processes_give_the_serial_budget_to_the_bit():
    from machinesim.experiment import run
    from machinesim.procedures.tool_rotation_arm import ToolRotationArm
    from machinesim.realism import Realism

    realism = Realism.lab()
    everything = run(ToolRotationArm(), _arm_lab(realism))
    sources = ("registration", "lateral_noise")
    rerun = partial(_arm_rerun, realism=realism)
    serial = error_budget(rerun, sources, everything=everything)
    told = []
    parallel = error_budget(rerun, sources, everything=everything, jobs=2,
                            done=lambda source, seconds: told.append((source, seconds)))
    assert parallel.to_dict() == serial.to_dict()  # floats compared exactly
    assert parallel.table() == serial.table()
    assert sorted(source for source, _ in told) == sorted(sources)  # one line each
    assert all(seconds > 0.0 for _, seconds in told)
    # docs/budget.md's table of this lab: registration is 98.6 % of the depth error after
    depth = {row.source: row for row in serial.rows if row.figure == "depth_error"}
    assert round(depth["registration"].after_all, 4) == 0.3490
    assert round(depth["registration"].after_without, 5) == 0.04187
    assert round(100.0 * depth["registration"].share, 1) == 98.6


def _figures_of(source):
    from types import SimpleNamespace

    from machinesim.experiment import Figure

    if source == "broken":
        raise InputError(f"rerun of {source!r}: refused here", key=source)
    return SimpleNamespace(figures=(Figure("dx", "um", 1.0, 0.5 if source == "a" else 0.3),))


def test_a_rerun_that_does_not_pickle_is_refused_before_any_worker_starts():
    everything = _figures_of("all")
    with pytest.raises(InputError, match=r"must pickle .*jobs 1"):
        error_budget(lambda source: everything, ["a", "b"], everything=everything, jobs=2)
    with pytest.raises(InputError, match=r"expected 1 or more worker processes, got jobs=0"):
        error_budget(_figures_of, ["a", "b"], everything=everything, jobs=0)
    assert not _workers(psutil.Process())


def test_a_workers_error_reaches_the_caller_and_every_worker_ends():
    everything = _figures_of("all")
    budget = error_budget(_figures_of, ["a", "b"], everything=everything, jobs=2)
    assert [row.after_without for row in budget.rows] == [0.5, 0.3]
    with pytest.raises(InputError, match=r"rerun of 'broken': refused here"):
        error_budget(_figures_of, ["a", "broken", "b"], everything=everything, jobs=2)
    assert not _workers(psutil.Process())


#: A parent whose two workers sleep: stopped by Ctrl-C (or SIGTERM), it says so in one line.
SLEEPING_PARENT = textwrap.dedent("""
    import sys, time
    from machinesim._interrupts import ctrl_c_remembered, stopped
    from machinesim._processes import in_processes
    try:
        with ctrl_c_remembered():
            in_processes(time.sleep, [60.0, 60.0, 60.0], 2)
    except KeyboardInterrupt as stop:
        print("parent:", stopped(stop)[0], flush=True)
        sys.exit(stopped(stop)[1])
""")


@pytest.mark.parametrize("how", ["ctrl_c_to_the_group", "sigterm_to_the_parent"])
def test_a_stop_ends_every_worker_and_no_worker_says_anything(how, as_in_a_terminal):
    parent = subprocess.Popen([sys.executable, "-c", SLEEPING_PARENT], cwd=ROOT,
                              env={**os.environ, "PYTHONPATH": str(ROOT)},
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                              start_new_session=True,  # its own group, as a terminal's job
                              **as_in_a_terminal)  # and SIGINT as a terminal's job has it
    try:
        deadline = time.monotonic() + 60.0
        workers = []
        while time.monotonic() < deadline:  # both workers up
            workers = _workers(psutil.Process(parent.pid))
            if len(workers) == 2:
                break
            time.sleep(0.2)
        assert len(workers) == 2
        time.sleep(3.0)  # their imports done, each sleeping in a call
        if how == "ctrl_c_to_the_group":
            os.killpg(parent.pid, signal.SIGINT)
        else:
            parent.send_signal(signal.SIGTERM)
        out, err = parent.communicate(timeout=30)
    finally:
        if parent.poll() is None:
            os.killpg(parent.pid, signal.SIGKILL)
    expected = ("interrupted", 130) if how == "ctrl_c_to_the_group" else ("terminated", 143)
    assert (out.strip(), parent.returncode) == (f"parent: {expected[0]}", expected[1])
    assert err == ""  # no worker's traceback
    gone, alive = psutil.wait_procs(workers, timeout=10)
    assert not alive


#: A parent given a Ctrl-C while its workers start (sent from the pool's submit, so pending
#: while SIGINT is blocked there), with no thread of its own that could take it meanwhile
#: (single-thread BLAS, as the campaign's workers run): the KeyboardInterrupt is raised as
#: the block ends. It says how many workers are left, then ends those itself.
CTRL_C_WHILE_STARTING = textwrap.dedent("""
    import os, signal, time
    from concurrent.futures import ProcessPoolExecutor
    import psutil
    from machinesim._processes import in_processes
    real = ProcessPoolExecutor.submit
    def submit(self, *args, **kwargs):
        os.kill(os.getpid(), signal.SIGINT)
        return real(self, *args, **kwargs)
    ProcessPoolExecutor.submit = submit
    try:
        in_processes(time.sleep, [60.0, 60.0, 60.0], 2)
    except KeyboardInterrupt:
        left = [c for c in psutil.Process().children()
                if c.status() != psutil.STATUS_ZOMBIE and "spawn_main" in " ".join(c.cmdline())]
        print("workers left:", len(left), flush=True)
        for c in left:
            c.kill()
        psutil.wait_procs(left, timeout=10)
""")


def test_a_ctrl_c_while_the_workers_start_ends_them(as_in_a_terminal):
    one_thread = {name: "1" for name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS",
                                         "MKL_NUM_THREADS")}
    parent = subprocess.Popen([sys.executable, "-c", CTRL_C_WHILE_STARTING], cwd=ROOT,
                              env={**os.environ, **one_thread, "PYTHONPATH": str(ROOT)},
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                              start_new_session=True, **as_in_a_terminal)
    try:
        out, err = parent.communicate(timeout=30)
    finally:
        if parent.poll() is None:
            os.killpg(parent.pid, signal.SIGKILL)
    # the old code raised it outside its stop: 'workers left: 2', and the parent, its
    # workers killed, then hung at its exit (90 s, spinning) in the pool's exit handler
    assert (out.strip(), parent.returncode) == ("workers left: 0", 0), err
    assert err == ""


def test_results_come_back_in_the_order_given_whatever_order_they_finish():
    told = []
    assert in_processes(abs, [-3, 2, -1], 2, done=lambda i, s: told.append(i)) == [3, 2, 1]
    assert sorted(told) == [0, 1, 2]


def test_jobs_of_the_scenario_is_checked():
    result = subprocess.run([sys.executable, str(ROOT / "scenarios" / "workpiece_setting.py"),
                             "--jobs", "0", "--budget", "off"], capture_output=True,
                            text=True, cwd=ROOT, env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert result.returncode == 2
    assert "argument --jobs: '0': expected a whole number of worker processes, 1 or more" \
        in result.stderr


def _cut_keys(_):
    from machinesim.lab import CUTS

    return sorted(CUTS._cuts)


def test_each_worker_starts_with_the_cuts_this_process_made():
    """A rerun whose source acts on an instrument alone hands back the first run's part in
    a worker as it does here (`machinesim.lab.CUTS`), not a part cut again."""
    from machinesim import Lab
    from machinesim.budget import _remember_cuts
    from machinesim.cutting.memo import CutMemo
    from machinesim.lab import CUTS
    from machinesim.nc import ProgramBuilder

    memo = CutMemo()
    groove = (ProgramBuilder(1).rapid(X=1e-3, Y=1e-3, Z=1e-3)
              .linear(Z=-1e-5, feed_mm_per_min=100).linear(X=8e-3, feed_mm_per_min=100)
              .rapid(Z=1e-3).build())
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr("machinesim.lab.CUTS", memo)
        Lab("robonano_a0ib", seed=0).cut(groove, "v:90", "block:10x10x2")
        assert len(memo) == 1
        keys = in_processes(_cut_keys, [0, 1], 2, setup=partial(_remember_cuts, memo))
    assert keys == [sorted(memo._cuts)] * 2
    assert CUTS is not memo


def test_a_worker_that_dies_is_a_clear_error_and_the_others_end():
    from machinesim._processes import WorkerDied

    with pytest.raises(WorkerDied, match=r"ended without an answer \(killed: out of memory"):
        in_processes(os._exit, [3, 3], 2, what="budget rerun")
    assert not _workers(psutil.Process())


def test_realism_budget_builds_each_labs_rerun_on_a_worker_from_its_inputs():
    """`realism_budget(..., jobs=2)` with a `LabInputs` (which pickles; a scenario's nested
    make_lab does not, and is refused by name): the budget of the serial path to the bit,
    and one progress line per rerun."""
    from machinesim import load_machine
    from machinesim.budget import LabInputs, realism_budget
    from machinesim.errors import ErrorModel
    from machinesim.experiment import run
    from machinesim.identification.tool_rotation_arm import arm_radius
    from machinesim.procedures.tool_rotation_arm import ToolRotationArm
    from machinesim.realism import Realism

    machine = load_machine("planer_4axis")
    errors = ErrorModel().with_parameters({"tool.y": -178.0e-6,
                                           "tool.z": -(120.555e-3 - arm_radius(machine))})
    make_lab = LabInputs(machine, errors, seed=0)
    realism = Realism.lab().without("instrument_noise", "artefact_errors",
                                    "background_errors", "stage_positioning",
                                    "lateral_resolution", "probe_pretravel",
                                    "probe_ball_form", "air_refraction")
    procedure = ToolRotationArm()
    assert set(realism.on) & set(procedure.realism_sources) == {"registration",
                                                                 "lateral_noise"}
    everything = run(procedure, make_lab(realism))
    # the lab LabInputs builds is the one a scenario's make_lab built
    assert run(procedure, _arm_lab(realism)).figures == everything.figures
    serial = realism_budget(procedure, everything, realism, make_lab)
    told = []

    def stage(name):
        return lambda text: told.append((name, text))

    parallel = realism_budget(procedure, everything, realism, make_lab, progress=stage,
                              jobs=2)
    assert parallel.to_dict() == serial.to_dict()  # floats compared exactly
    assert told[0] == ("budget", "2 sources switched off in turn, 2 at a time on worker "
                       "processes")
    assert sorted(name for name, _ in told[1:]) == ["budget, lateral_noise off",
                                                    "budget, registration off"]
    assert all(re.fullmatch(r"done in \d+ s \([12] of 2\)", text) for _, text in told[1:])

    def nested(realism):
        return make_lab(realism)

    with pytest.raises(InputError, match=r"must pickle .*jobs 1"):
        realism_budget(procedure, everything, realism, nested, jobs=2)
    assert not _workers(psutil.Process())


def test_one_source_is_rerun_here_whatever_the_jobs():
    """A budget of one source runs its rerun in this process, its steps shown, as
    scenarios/workpiece_setting.py's does: a scenario's --jobs 2 with one source (paper
    000's --realism noise_only) had started a worker for it, refusing a make_lab that does
    not pickle."""
    from machinesim.budget import realism_budget
    from machinesim.experiment import run
    from machinesim.procedures.tool_rotation_arm import ToolRotationArm
    from machinesim.realism import Realism

    realism = Realism.with_only("registration")
    procedure = ToolRotationArm()
    everything = run(procedure, _arm_lab(realism))
    told = []

    def stage(name):
        return lambda text: told.append((name, text))

    budget = realism_budget(procedure, everything, realism, lambda r: _arm_lab(r),
                            progress=stage, jobs=2)  # a lambda: it does not pickle
    steps = list(told)
    assert {name for name, _ in steps} == {"budget, registration off"}  # its steps, here
    assert any(text.startswith("measure") for _, text in steps)
    told.clear()
    serial = realism_budget(procedure, everything, realism, lambda r: _arm_lab(r),
                            progress=stage)
    assert budget.to_dict() == serial.to_dict()
    assert [name for name, _ in told] == [name for name, _ in steps]
    assert not _workers(psutil.Process())


def test_jobs_is_checked_before_the_run_with_every_source_on():
    """A budget's ``jobs`` is refused before any run: 0 had been refused only after the
    run with every source on (minutes on a real procedure), and True (== 1) taken as one
    job; a numpy integer is a count."""
    from types import SimpleNamespace

    from machinesim.budget import realism_budget
    from machinesim.experiment import Figure
    from machinesim.realism import Realism

    calls = []

    def run(off):
        calls.append(off)
        return SimpleNamespace(figures=(Figure("f", "um", 3.0, 2.0 if off is None else 1.0),))

    for jobs in (0, True, 1.0, "2"):
        with pytest.raises(InputError, match=re.escape(
                f"budget reruns: expected 1 or more worker processes, got jobs={jobs!r}")):
            error_budget(run, ["a"], jobs=jobs)
        with pytest.raises(InputError, match="got jobs="):
            realism_budget(SimpleNamespace(realism_sources=()), None, Realism.lab(),
                           None, jobs=jobs)
    assert calls == []
    # np.int64(1) is one job, here: the all-on run and the rerun, 1 - 2 in quadrature
    budget = error_budget(run, ["a"], jobs=np.int64(1))
    assert calls == [None, "a"]
    assert budget.share("a", "f") == pytest.approx(1.0 - 1.0 / 4.0)


def test_a_function_the_workers_cannot_load_is_named_not_a_worker_killed(tmp_path):
    """A function defined under ``if __name__ == "__main__":`` pickles by its name in the
    parent, but a spawned worker imports the script as ``__mp_main__`` without that block:
    the pool's loading had killed each worker (a traceback on stderr each) and the call
    was told as a worker 'killed: out of memory, or by a signal'."""
    script = tmp_path / "budget_script.py"
    script.write_text(textwrap.dedent("""
        from machinesim._processes import in_processes
        from machinesim.exceptions import InputError

        if __name__ == "__main__":
            def halved(x):
                return x / 2

            try:
                in_processes(halved, [1.0, 2.0], 2, what="budget rerun")
            except InputError as error:
                print("refused:", error)
    """))
    result = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                            cwd=tmp_path, env={**os.environ, "PYTHONPATH": str(ROOT)},
                            timeout=120)
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith(
        "refused: key 'jobs': budget reruns on worker processes: a worker process could "
        "not load the "
        "function or its item (AttributeError: Can't get attribute 'halved' on <module "
        "'__mp_main__'")
    assert "or run them in this process instead (jobs 1)" in result.stdout
    assert "Traceback" not in result.stderr
