"""``--jobs N`` of every scenario with an error budget (`machinesim.scenario_runs.jobs_option`):
the same option, and the scenario's own procedure and lab inputs give the same budget on
worker processes as in its process, to the bit (docs/budget.md, "Reruns on every core")."""

from __future__ import annotations

import importlib.util
import pickle
import sys
from functools import partial
from pathlib import Path

import numpy as np
import pytest

from machinesim.budget import LabInputs, _rerun_without, error_budget, realism_budget
from machinesim.experiment import run
from machinesim.realism import Realism

ROOT = Path(__file__).resolve().parents[1]
#: The scenarios whose budget takes --jobs.
BUDGETED = ("sts_turning", "tool_rotation_arm", "tool_setting_6axis", "workpiece_setting",
            "xy_plane_errors")


def _scenario(name: str):
    spec = importlib.util.spec_from_file_location(f"{name}_scenario",
                                                  ROOT / "scenarios" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _main(module, argv: list[str]):
    """The scenario's ``main`` on the command line ``argv``."""
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(sys, "argv", [f"{module.__name__}.py", *argv])
        return module.main()


@pytest.mark.parametrize("name", BUDGETED)
def test_every_budgeted_scenario_takes_jobs_with_the_same_words(name, capsys):
    module = _scenario(name)
    with pytest.raises(SystemExit) as stop:
        _main(module, ["--jobs", "0"])
    assert stop.value.code == 2
    assert "argument --jobs: '0': expected a whole number of worker processes, 1 or more" \
        in capsys.readouterr().err
    with pytest.raises(SystemExit) as stop:
        _main(module, ["--help"])
    assert stop.value.code == 0
    text = " ".join(capsys.readouterr().out.split())
    assert ("--jobs N the budget's reruns at a time, each on a worker process (default 1: "
            "one after the other in this process; the cores this process may use:") in text


class _Captured(Exception):
    """Raised by the stand-in for realism_budget: what the scenario passed it."""


def _budget_inputs(name: str, argv: list[str], tmp_path) -> dict:
    """What scenario ``name`` hands `realism_budget` on ``argv --jobs 2``: its procedure,
    make_lab and jobs (its run with every source on is not made: a stand-in)."""
    module = _scenario(name)

    def captured(procedure, result, realism, make_lab, enabled=True, *, progress=None,
                 jobs=1):
        raise _Captured({"procedure": procedure, "make_lab": make_lab, "jobs": jobs,
                         "realism": realism})

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(module, "run", lambda procedure, lab, progress=None: None)
        patch.setattr(module, "realism_budget", captured)
        with pytest.raises(_Captured) as got:
            _main(module, [*argv, "--jobs", "2", "--out", str(tmp_path / "out")])
    return got.value.args[0]


def _only(realism: Realism, *keep: str) -> Realism:
    return realism.without(*[s for s in realism.on if s not in keep])


@pytest.mark.parametrize("name", ["tool_rotation_arm", "tool_setting_6axis"])
def test_the_budget_on_two_workers_is_the_budget_in_this_process(name, tmp_path):
    """Papers 000 and 001: their procedure and lab inputs as the scenario builds them, the
    budget of two microscope sources (the reruns read the first run's cuts), jobs 2 against
    jobs 1."""
    given = _budget_inputs(name, [], tmp_path)
    assert given["jobs"] == 2 and isinstance(given["make_lab"], LabInputs)
    procedure, make_lab = given["procedure"], given["make_lab"]
    realism = _only(given["realism"], "registration", "lateral_noise")
    assert set(realism.on) & set(procedure.realism_sources) == {"registration",
                                                                 "lateral_noise"}
    everything = run(procedure, make_lab(realism))
    serial = realism_budget(procedure, everything, realism, make_lab)
    parallel = realism_budget(procedure, everything, realism, make_lab, jobs=2)
    assert parallel.to_dict() == serial.to_dict()  # floats compared exactly
    assert serial.sources == ("lateral_noise", "registration")


@pytest.mark.parametrize(("name", "source"), [("xy_plane_errors", "background_errors")])
def test_a_rerun_on_a_worker_is_the_rerun_in_this_process(name, source, tmp_path):
    """Paper 003, dearer (every rerun cuts again): one source's rerun, with the scenario's
    own procedure and lab inputs, run here and on a worker process (`error_budget` jobs 2):
    the same budget to the bit."""
    given = _budget_inputs(name, [], tmp_path)
    assert given["jobs"] == 2 and isinstance(given["make_lab"], LabInputs)
    rerun = partial(_rerun_without, procedure=given["procedure"],
                    make_lab=given["make_lab"], realism=given["realism"])
    here = rerun(source)
    serial = error_budget(lambda off: here, [source], everything=here)
    parallel = error_budget(rerun, [source], everything=here, jobs=2)
    assert parallel.to_dict() == serial.to_dict()  # floats compared exactly
    assert [row.share for row in parallel.rows] == [0.0] * len(parallel.rows)


def test_paper_004s_rerun_reaches_a_worker_whole(tmp_path):
    """Paper 004's rerun turns four cases again (about 100 s of CPU a run, too dear to run
    twice here): what a worker is handed, its procedure with the lab inputs (Table 6
    "before" as the servo), pickles, and unpickled pickles to the same bytes, so the worker
    rebuilds the lab the scenario would (`in_processes` sends ``pickle.dumps((function,
    item))``)."""
    given = _budget_inputs("sts_turning", [], tmp_path)
    assert given["jobs"] == 2 and isinstance(given["make_lab"], LabInputs)
    assert given["make_lab"].servo is not None  # the scenario's servo goes with the inputs
    rerun = partial(_rerun_without, procedure=given["procedure"],
                    make_lab=given["make_lab"], realism=given["realism"])
    got, source = pickle.loads(pickle.dumps((rerun, "lateral_noise")))
    assert source == "lateral_noise"
    made, sent = got.keywords["make_lab"], given["make_lab"]
    realism = given["realism"].without(source)
    assert repr(made(realism)) == repr(sent(realism))
    assert repr(got.keywords["procedure"]) == repr(given["procedure"])
    t = np.linspace(0.0, 0.05, 501)  # a ramp of X, Z and C: the loops follow it alike
    q = np.column_stack([1e-3 * t, -2e-3 * t, 30.0 * t])
    assert np.array_equal(made.servo.follow(t, q), sent.servo.follow(t, q))
