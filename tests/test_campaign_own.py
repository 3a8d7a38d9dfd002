"""A campaign of a user's own procedure (docs/procedures/your_own.md's example, the tool
offset from an R-test checked on a groove): given as a ``module:Class`` reference, the class
or an instance, in this process and on a local Dask worker, each trial gives what
`machinesim.experiment.run` gives on a lab of the trial's errors and seed; a folder begun
with one procedure is not resumed with another."""

from __future__ import annotations

import json
import re
import sys

import numpy as np
import pytest
from fenced import ROOT

import machinesim
from machinesim.campaign import CampaignSpec, run
from machinesim.campaign.trials import trial_seed
from machinesim.errors.model import as_error_model
from machinesim.exceptions import InputError
from machinesim.experiment import run as run_experiment

MACHINE = "grooving_4axis"
ERRORS = {"tool": {"offset_um": [4.0, -3.0, 2.0]}}  # the page's
VARY = ["tool.y=uniform:-5um,5um"]
SEED = 3
#: The module the page's example class is saved as (`example`).
MODULE = "own_procedure_example"


@pytest.fixture(scope="module")
def example(tmp_path_factory):
    """The page's first block up to its run, saved as a module on sys.path (this process's,
    and so the Dask workers' it starts), with a second procedure of another name."""
    page = (ROOT / "docs" / "procedures" / "your_own.md").read_text(encoding="utf-8")
    block = re.search(r"```python\n(.*?)```", page, re.S)[1]
    code = block[:block.index("errors = {")]
    folder = tmp_path_factory.mktemp("own")
    (folder / f"{MODULE}.py").write_text(
        code + "\n\nclass Other(ToolOffsetRTest):\n    name = \"other\"\n", encoding="utf-8")
    sys.path.insert(0, str(folder))
    try:
        module = __import__(MODULE)
        yield module
    finally:
        sys.path.remove(str(folder))
        sys.modules.pop(MODULE, None)


def _options(**more):
    return dict(machine=MACHINE, errors=ERRORS, vary=VARY, seed=SEED, progress=False,
                report=False, **more)


def _as_run_gives(dataset, procedure_class) -> None:
    """Each trial of ``dataset`` as `experiment.run` gives it on the trial's lab: the page's
    errors with the drawn tool.y, seeded with the trial's seed."""
    for i in dataset.trial.values:
        drawn = float(dataset.drawn.sel(trial=i, varied="tool.y"))
        model = as_error_model(ERRORS).with_parameters({"tool.y": drawn})
        result = run_experiment(procedure_class(),
                                machinesim.Lab(MACHINE, model, seed=trial_seed(SEED, i)))
        for name in ("tool.x", "tool.y", "tool.z"):
            value, std = result.identified[name]
            assert dataset.identified.sel(trial=i, parameter=name) == value, (i, name)
            assert dataset.identified_std.sel(trial=i, parameter=name) == std, (i, name)
            assert dataset.injected.sel(trial=i, parameter=name) == result.injected[name]
        for figure in result.figures:
            assert dataset.before.sel(trial=i, figure=figure.name) == figure.before
            assert dataset.after.sel(trial=i, figure=figure.name) == figure.after
        # the page's hand values: the groove shifted by the tool's Y offset, compensated
        assert abs(result.figure("groove_y_error").before - drawn * 1e6) < 0.05
        assert abs(result.figure("groove_y_error").after) < 0.05


def test_the_pages_procedure_as_a_campaign_gives_what_experiment_run_gives(example,
                                                                            tmp_path):
    here = run(f"{MODULE}:ToolOffsetRTest", 3, out=tmp_path / "here", workers=0,
               **_options())
    assert not here.failed.values.any()
    assert len(set(here.drawn.values.ravel())) == 3  # three draws, not one three times
    _as_run_gives(here, example.ToolOffsetRTest)
    assert here.attrs["procedure"] == f"{MODULE}:ToolOffsetRTest"
    assert here.attrs["procedure_name"] == "tool_offset_rtest"
    assert here.attrs["machine"] == MACHINE
    assert json.loads(here.attrs["base_errors"])["tool"]["offset_m"] == [4e-6, -3e-6, 2e-6]
    assert list(here.parameter_unit.values) == ["m", "m", "m"]
    stored = json.loads((tmp_path / "here" / "campaign.json").read_text())
    assert (stored["procedure"], stored["name"], stored["machine"]) == (
        f"{MODULE}:ToolOffsetRTest", "tool_offset_rtest", MACHINE)
    trial = json.loads((tmp_path / "here" / "trials" / "trial_000002.json").read_text())
    assert trial["procedure"] == f"{MODULE}:ToolOffsetRTest"
    # the class and an instance are the same campaign, trial by trial
    for given in (example.ToolOffsetRTest, example.ToolOffsetRTest()):
        again = run(given, 3, out=tmp_path / type(given).__name__, workers=0, **_options())
        for name in ("identified", "before", "after"):
            assert np.array_equal(again[name].values, here[name].values), name


def test_the_pages_procedure_on_a_dask_worker_by_its_reference(example, tmp_path):
    pytest.importorskip("distributed")
    there = run(f"{MODULE}:ToolOffsetRTest", 2, out=tmp_path / "there", workers=1,
                **_options())
    assert not there.failed.values.any(), there.attrs["errors"]
    _as_run_gives(there, example.ToolOffsetRTest)


def test_a_resume_with_another_procedure_is_refused(example, tmp_path):
    out = tmp_path / "out"
    run(f"{MODULE}:ToolOffsetRTest", 1, out=out, workers=0, **_options())
    with pytest.raises(InputError, match=r"holds another campaign \(.*procedure: "
                       rf"'{MODULE}:ToolOffsetRTest' there, '{MODULE}:Other' now"):
        run(example.Other, 2, out=out, workers=0, **_options())
    with pytest.raises(InputError, match=r"holds another campaign \(errors: "):
        run(f"{MODULE}:ToolOffsetRTest", 2, out=out, workers=0,
            **{**_options(), "errors": {"tool": {"offset_um": [4.0, -3.0, 3.0]}}})
    with pytest.raises(InputError, match=r"holds another campaign \(.*procedure: "
                       r"'own_procedure_example:ToolOffsetRTest' there, 'tool_rotation_arm'"):
        run("tool_rotation_arm", 2, out=out, workers=0, progress=False, report=False)
    # the same procedure resumes: trial 0 read, trial 1 run
    assert run(example.ToolOffsetRTest(), 2, out=out, workers=0,
               **_options()).sizes["trial"] == 2


def test_what_a_campaign_of_your_own_procedure_refuses(example, tmp_path):
    with pytest.raises(InputError, match=r"key 'procedure': procedure 'no_such_module:X': "
                       r"cannot import 'no_such_module' .*expected an importable "
                       r"'package\.module:ClassName'"):
        CampaignSpec("no_such_module:X", 1, machine_name=MACHINE)
    with pytest.raises(InputError, match=rf"{MODULE} has no 'ToolOffsetRtest' \(did you "
                       r"mean ToolOffsetRTest\?\)"):
        CampaignSpec(f"{MODULE}:ToolOffsetRtest", 1, machine_name=MACHINE)
    with pytest.raises(InputError, match=r"key 'machine': machine=None; expected the name "
                       r"of the machine"):
        CampaignSpec(example.ToolOffsetRTest, 1)
    with pytest.raises(InputError, match=r"key 'machine': machine='grooving_4axis' is for a "
                       r"procedure of your own; tool_rotation_arm runs on planer_4axis"):
        CampaignSpec("tool_rotation_arm", 1, machine_name=MACHINE)

    class Unsendable(example.ToolOffsetRTest):  # copied for each trial, never pickled
        def __deepcopy__(self, memo):
            return Unsendable()

        def __reduce__(self):
            raise TypeError("holds an open device")

    with pytest.raises(InputError, match=r"cannot be pickled for the Dask workers "
                       r"\(TypeError: holds an open device\); expected an importable "
                       r"'package\.module:ClassName' reference .* or workers=0"):
        run(Unsendable(), 1, out=tmp_path / "dask", workers=1, **_options())
    assert not (tmp_path / "dask").exists()
    lacking = type("Lacking", (), {"name": "x", "lab_uses": {}, "measure": lambda s, lab: 0})
    with pytest.raises(InputError, match=r"has no identify, compensate, evaluate"):
        CampaignSpec(lacking, 1, machine_name=MACHINE)


def test_the_command_runs_your_own_procedure_from_the_folder_it_is_run_in(example, tmp_path,
                                                                          monkeypatch):
    """``machinesim campaign package.module:Class --machine NAME --errors FILE``: the module
    found in the current folder, which an installed command's sys.path does not hold."""
    from machinesim.campaign.cli import main

    source = (sys.modules[MODULE].__file__)
    (tmp_path / "here_procedure.py").write_text(open(source, encoding="utf-8").read(),
                                                encoding="utf-8")
    (tmp_path / "errors.toml").write_text("[tool]\noffset_um = [4.0, -3.0, 2.0]\n",
                                          encoding="utf-8")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "path", [p for p in sys.path if p not in ("", str(tmp_path))])
    assert main(["here_procedure:ToolOffsetRTest", "--machine", MACHINE, "--errors",
                 "errors.toml", "--trials", "1", "--seed", str(SEED), "--vary", VARY[0],
                 "--workers", "0", "--out", "out", "--quiet"]) == 0
    stored = json.loads((tmp_path / "out" / "campaign.json").read_text())
    assert stored["procedure"] == "here_procedure:ToolOffsetRTest"
    assert stored["errors"]["tool"]["offset_m"] == [4e-6, -3e-6, 2e-6]


@pytest.mark.parametrize(("given", "said"), [
    ([], "key '--machine': --machine not given; expected the name of the machine procedure "
         f"{MODULE}:ToolOffsetRTest is for (e.g. --machine grooving_4axis)"),
    (["--machine", ""], "--machine ''; expected the name of the machine"),
])
def test_the_command_names_its_machine_option(example, given, said, tmp_path, capsys):
    """The command said "machine=None ... (e.g. machine='grooving_4axis')", the Python
    parameter, where the user forgot --machine; a shipped procedure given --machine or
    --errors said machine=... / errors=... the same way. Nothing is written."""
    from machinesim.campaign.cli import main

    common = ["--trials", "1", "--workers", "0", "--out", str(tmp_path / "out"), "--quiet"]
    assert main([f"{MODULE}:ToolOffsetRTest", *given, *common]) == 2
    assert said in capsys.readouterr().err
    for option in ("--machine", "--errors"):
        assert main(["tool_rotation_arm", option, "x", *common]) == 2
        assert (f"key '{option}': {option} 'x' is for a procedure of your own; "
                "tool_rotation_arm runs on") in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("uses", [3, None, 2.5])
def test_lab_uses_that_are_no_tuple_of_names_are_refused(example, uses):
    """``lab_uses = {"measure": 3}``: an InputError naming it, not the TypeError of iterating
    over a number."""
    bad = type("BadUses", (example.ToolOffsetRTest,), {"lab_uses": {"measure": uses}})
    with pytest.raises(InputError, match=r"key 'procedure': procedure .*BadUses: "
                       rf"lab_uses\['measure'\] {uses!r}; expected a tuple of microscope"):
        CampaignSpec(bad, 1, machine_name=MACHINE)


def test_a_procedure_without_paper_is_refused_before_any_trial(example):
    """`experiment.run` puts ``procedure.paper`` into each result: one without it is refused
    when the campaign is set up, not failed trial by trial after its cuts."""
    for paper in (None, 3):
        bad = type("NoPaper", (example.ToolOffsetRTest,), {"paper": paper})
        with pytest.raises(InputError, match=r"key 'procedure': procedure .*NoPaper: paper "
                           rf"{paper!r}; expected a text"):
            CampaignSpec(bad, 1, machine_name=MACHINE)
    assert CampaignSpec(example.ToolOffsetRTest, 1, machine_name=MACHINE).own


def test_a_fault_of_your_own_procedure_is_said_to_be_yours(example, tmp_path):
    """A trial whose procedure's own code raises (no MachineSimError) fails naming that
    code, not as "a fault of machinesim ... please report it"; one that machinesim's code
    raises under it is still machinesim's."""
    source = tmp_path / "faulty_procedure.py"
    source.write_text(f"from {MODULE} import ToolOffsetRTest\n\n\n"
                      "class Faulty(ToolOffsetRTest):\n"
                      "    def identify(self, reading):\n"
                      "        raise ValueError('my own bug')\n", encoding="utf-8")
    sys.path.insert(0, str(tmp_path))
    try:
        from faulty_procedure import Faulty

        failed = run(Faulty(), 1, out=tmp_path / "out", workers=0, **_options())
    finally:
        sys.path.remove(str(tmp_path))
        sys.modules.pop("faulty_procedure", None)
    message = json.loads(failed.attrs["errors"])["0"]
    assert message.startswith("ValueError: my own bug (not a MachineSimError: raised by your "
                              "procedure's code at faulty_procedure.py:6 in identify, met "
                              "by this trial's draws; a failed trial is kept as done"), message
    assert "fault of machinesim" not in message

    from machinesim.campaign.trials import unexpected

    def machinesims():  # a frame of machinesim innermost: machinesim's fault, as before
        from machinesim.campaign.trials import trial_seed as seeded

        return seeded(-1, 0)

    try:
        machinesims()
    except Exception as error:  # noqa: BLE001 - whatever trial_seed raises on a bad seed
        said = unexpected(error, example.ToolOffsetRTest())
    assert "a fault of machinesim" in said, said


def test_the_commands_help_says_where_your_procedures_module_is_looked_for(capsys):
    from machinesim.campaign.cli import main

    with pytest.raises(SystemExit):
        main(["--help"])
    shown = " ".join(capsys.readouterr().out.split())
    assert "package.module:ClassName: a procedure of your own" in shown
    assert "its module is looked for in the current folder too" in shown
    assert "with --scheduler it must import on every worker of that cluster" in shown


def test_a_resume_with_other_errors_names_the_entry_that_differs(example, tmp_path):
    """The refusal of a folder begun with other errors names the entries that differ, not
    the whole error model (96,016 characters with a table of 2,001 positions)."""
    from machinesim.campaign.results import CampaignFolder

    positions = np.linspace(-140.0, 140.0, 2001).tolist()

    def spec(z_um):
        errors = {"tool": {"offset_um": [4.0, -3.0, z_um]},
                  "component": {"X": {"position_mm": positions, "EZX_um": [0.0] * 2001}}}
        return CampaignSpec(example.ToolOffsetRTest, 1, machine_name=MACHINE,
                            errors=errors).describe()

    CampaignFolder(tmp_path / "out", spec(2.0))
    with pytest.raises(InputError) as info:
        CampaignFolder(tmp_path / "out", spec(3.0))
    message = str(info.value)
    assert ("holds another campaign (errors: tool.offset_m [4e-06, -3e-06, 2e-06] there, "
            "[4e-06, -3e-06, 3e-06] now); give another --out or empty it") in message
    assert len(message) < 300, len(message)


def test_a_campaign_notes_its_errors_files_unit_slips_as_cut_does(example, tmp_path):
    # machinesim cut, view and the scenarios note an error file's values perhaps written in
    # other units (unit_slips.unit_slip_notes); a campaign of one's own procedure given the
    # same file ran its trials without a word. EX0C_um = 4e-6 is 4 pm, below anything a
    # machine shows: noted once, before the trials, as a MachineSimWarning (the campaign's
    # channel, one 'machinesim: warning:' line on the command line); the page's errors none
    import warnings

    from machinesim.errors.unit_slips import unit_slip_notes
    from machinesim.exceptions import MachineSimWarning
    from machinesim.machines import load_machine

    path = tmp_path / "slip.toml"
    path.write_text("[tool]\noffset_um = [4.0, -3.0, 2.0]\n[location.C]\nEX0C_um = 4e-6\n")
    [note] = unit_slip_notes(as_error_model(path), load_machine(MACHINE))
    assert note.startswith(f"{path}, line 4: location.C.EX0C_um = 4e-06 is at most"), note
    options = {**_options(), "errors": path}
    with pytest.warns(MachineSimWarning) as caught:
        run(f"{MODULE}:ToolOffsetRTest", 1, out=tmp_path / "slip", workers=0, **options)
    assert [str(w.message) for w in caught if str(w.message) == note] == [note]
    with warnings.catch_warnings():
        warnings.simplefilter("error", MachineSimWarning)
        run(f"{MODULE}:ToolOffsetRTest", 1, out=tmp_path / "page", workers=0, **_options())


class _Stub:
    """A procedure that reads nothing: each hostile variant below changes one step."""

    name = "stub"
    paper = "tests/test_campaign_own.py"
    lab_uses = {"measure": (), "evaluate": ()}

    def measure(self, lab):
        return None

    def identify(self, reading):
        from machinesim.experiment import Identified

        return Identified({"tool.x": (0.0, 1e-9)})

    def compensate(self, identified):
        return {}

    def evaluate(self, lab, identified, programs):
        from machinesim.experiment import Evaluation, Figure

        return Evaluation(figures=(Figure("f", "um", 1.0, 0.5),))


class _NoEvaluation(_Stub):
    def evaluate(self, lab, identified, programs):
        return None


class _NoPrograms(_Stub):
    def compensate(self, identified):
        return ["groove"]


class _NoParameter(_Stub):
    def identify(self, reading):
        from machinesim.experiment import Identified

        return Identified({"tool.x": (0.0, 1e-9), "tool.offset": (1e-6, 1e-9)})


class _LabParameter(_Stub):
    def identify(self, reading):
        from machinesim.experiment import Identified

        return Identified({"microscope.sigma": (12e-9, 1e-9)})


class _RaisingName(_Stub):
    @property
    def name(self):
        raise RuntimeError("not connected")


@pytest.mark.parametrize(("procedure", "said"), [
    (_NoEvaluation, "InputError: key 'evaluate': stub.evaluate returned NoneType; expected an "
                    "Evaluation (Evaluation(figures=()) for none)"),
    (_NoPrograms, "InputError: key 'compensate': stub.compensate returned list; expected a "
                  "mapping of names to programs (an empty dict for none)"),
    # refused by experiment.run itself, as outside a campaign: no error of the machine's
    (_NoParameter, "InputError: key 'identify': stub.identify named 'tool.offset', no "
                   "error parameter of grooving_4axis (axes XYZC): its value would be "
                   "reported against an injected 0"),
    (_LabParameter, "InputError: key 'identify': stub.identify named 'microscope.sigma', "
                    "no error parameter of grooving_4axis (axes XYZC): its value would be "
                    "reported against an injected 0"),
])
def test_a_procedure_whose_step_returns_what_no_step_may_fails_its_trials_saying_so(
        procedure, said, tmp_path):
    """evaluate returning None failed every trial as "AttributeError: 'NoneType' object has
    no attribute 'figures' (not a MachineSimError: a fault of machinesim ...; please report
    it)"; compensate returning a list as a TypeError said alike; an identified name no error
    parameter has ran every trial, then ended the campaign refusing to assemble them ("has
    no unit ...; delete the trial files that name it")."""
    failed = run(procedure, 2, out=tmp_path / "out", workers=0, machine=MACHINE,
                 progress=False, report=False)
    assert failed.failed.values.all()
    for message in json.loads(failed.attrs["errors"]).values():
        assert message.startswith(said), message
    # the good stub runs: what the variants changed is what they are refused for
    good = run(_Stub, 2, out=tmp_path / "good", workers=0, machine=MACHINE, progress=False,
               report=False)
    assert not good.failed.values.any() and list(good.after.values.ravel()) == [0.5, 0.5]


def test_a_procedure_whose_name_raises_is_refused_naming_it(tmp_path):
    with pytest.raises(InputError, match=r"key 'procedure': procedure .*_RaisingName: reading "
                       r"its name raised RuntimeError: not connected; expected a text, its key"):
        run(_RaisingName, 1, out=tmp_path / "out", workers=0, machine=MACHINE, progress=False,
            report=False)
    assert not (tmp_path / "out").exists()
