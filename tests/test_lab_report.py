"""What a run on a lab reports: its progress step by step, what the identification's fit
noted and a misfit beside the errors its sigma leaves out, and the injected parameters
(named when not identified, as written, in the error model's order)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from lab_helpers import TRUTH

import machinesim
from machinesim import ErrorModel, Lab
from machinesim.exceptions import InputError

ROOT = Path(__file__).resolve().parents[1]


def test_run_tells_its_progress_step_by_step_in_order():
    """`run(..., progress=)` is told each step as it begins and when it ends, in the
    protocol's order, with the time the step took (as `Result.elapsed_s` records it)."""
    from machinesim.experiment import Evaluation, Figure, Identified, run

    class Counting:
        name, paper = "counting", "none"

        def measure(self, lab):
            return 1e-6  # a reading, m

        def identify(self, measurements):
            return Identified({"workpiece.x": (measurements, float("nan"))}, None)

        def compensate(self, identified):
            return {}

        def evaluate(self, lab, identified, programs):
            return Evaluation((Figure("x", "um", 1.0, 0.0),))

    told = []
    result = run(Counting(), Lab("robonano_a0ib", TRUTH, noise=False), progress=told.append)
    steps = ("measure", "identify", "compensate", "evaluate")
    assert told[0::2] == [f"{s} ..." for s in steps]
    assert told[1::2] == [f"{s} done in {result.elapsed_s[f'{s}_s']:.1f} s" for s in steps]
    assert run(Counting(), Lab("robonano_a0ib", TRUTH, noise=False)).figures == result.figures


def test_what_the_identifications_fit_noted_reaches_the_report(tmp_path):
    """`Identified.notes` (a procedure's fits' `Estimate.notes`, `fit_notes`) go through `run`
    into summary.json's ``notes`` and under identified.md's table, word for word; a run
    whose fits noted nothing has neither. Readings along x alone cannot tell workpiece.x
    from tool.x (both move the tool against the workpiece along x): the fit names the
    combination it cannot see."""
    from machinesim.experiment import Evaluation, Figure, Identified, fit_notes, run
    from machinesim.identification.fit import fit, observations
    from machinesim.report import ReportFolder, check_summary

    class Both:
        name, paper = "both", "none"

        def __init__(self, names):
            self.names = names

        def measure(self, lab):
            return lab.machine, [3e-6, 3e-6]

        def identify(self, measurements):
            machine, values = measurements
            q = np.zeros((2, len(machine.axes)))
            q[1, 0] = 0.01
            estimate = fit(machine, observations(q, directions=[1.0, 0.0, 0.0], values=values,
                                                 sigma=1e-9), self.names)
            return Identified({n: (v, s) for n, v, s in zip(
                estimate.names, estimate.values, estimate.std, strict=True)}, None,
                fit_notes("both's fit", estimate))

        def compensate(self, identified):
            return {}

        def evaluate(self, lab, identified, programs):
            return Evaluation((Figure("x", "um", 1.0, 0.0),))

    lab = Lab("robonano_a0ib", {"workpiece": {"delta_um": [3.0, 0.0, 0.0]}}, seed=1)
    result = run(Both(["workpiece.x", "tool.x"]), lab)
    note = ("both's fit: rank 1 of 2: the readings cannot see the combination workpiece.x + "
            "tool.x: its value is the prior's, so workpiece.x, tool.x are not identified on "
            "their own and their values are one solution among many; a compensation through "
            "them is right only for what the readings saw. Fix a datum (leave a parameter "
            "out of the fit) or add readings that see it")
    assert result.identification.notes == result.notes == (note,)
    folder = ReportFolder(tmp_path / "warned")
    folder.write_result(result)
    summary = json.loads((tmp_path / "warned/summary.json").read_text())
    assert summary["notes"] == [note]
    check_summary(summary)
    assert (tmp_path / "warned/identified.md").read_text().endswith(
        "\n\nThe identification's fits noted, from the readings alone:\n\n- " + note + "\n")
    # workpiece.x alone is seen: no note, no "notes" key, identified.md as before
    quiet = run(Both(["workpiece.x"]), lab)
    assert quiet.notes == () and "notes" not in quiet.summary()
    ReportFolder(tmp_path / "quiet").write_result(quiet)
    assert "fits noted" not in (tmp_path / "quiet/identified.md").read_text()
    assert "notes" not in json.loads((tmp_path / "quiet/summary.json").read_text())
    for bad in ("a note", [note, ""], (3,)):
        with pytest.raises(InputError, match="key 'notes'.*tuple of non-empty strings"):
            Identified({}, None, bad)


def test_a_misfit_is_read_beside_the_errors_the_fits_sigma_leaves_out():
    """A procedure whose readings carry errors it states but its fit's sigma leaves out (a
    stage's registration, an artefact's made scatter) adds, to the fit's misfit note, that
    they may account for it; without a misfit, or without such errors, nothing is added.
    Two readings of one pose 1 um apart with sigma 1 nm misfit any model (residuals of
    0.5 um, 500 sigma); two equal ones fit."""
    from machinesim.experiment import fit_notes
    from machinesim.identification.fit import MODEL_MISFIT, fit, observations

    machine = machinesim.load_machine("robonano_a0ib")
    q = np.zeros((2, len(machine.axes)))

    def estimate(values):
        return fit(machine, observations(q, directions=[1.0, 0.0, 0.0], values=values,
                                         sigma=1e-9), ["workpiece.x"])

    apart = estimate([3e-6, 4e-6])
    assert apart.normalised_residual_rms > 100 * MODEL_MISFIT
    plain = fit_notes("stage fit", apart)
    assert [n.split(": ", 1)[1][:30] for n in plain] == ["the readings do not fit the mo"]
    added = fit_notes("stage fit", apart, sigma_leaves_out="the stage's registration")
    assert added == plain + ("stage fit: its sigma leaves out the stage's registration, "
                             "which may account for that misfit; the std this report "
                             "gives includes it",)
    assert fit_notes("stage fit", estimate([3e-6, 3e-6]),
                     sigma_leaves_out="the stage's registration") == ()


def test_injected_parameters_the_procedure_does_not_identify_are_named(tmp_path):
    """A procedure identifies its model's parameters; what else was injected is listed, in
    Result, summary.json and identified.md, rather than left out of the report unseen (the
    machine's background errors apart: they are summarised, not injected by the user)."""
    from toy_procedure import WorkpieceX

    from machinesim.experiment import run
    from machinesim.realism import Realism
    from machinesim.report import ReportFolder

    injected = {"workpiece": {"delta_um": [3.0, 0.0, 0.0]},
                "location": {"B": {"EX0B_um": 2.0}}, "tool": {"offset_um": [0.0, -1.5, 0.0]}}
    lab = Lab("robonano_a0ib", injected, seed=1, realism=Realism.lab())
    result = run(WorkpieceX(), lab)
    # as injected: the machine's background adds to EX0B, and is no part of the list nor of
    # ``injected``, which holds the identified workpiece.x and the rest as the user gave it
    assert dict(result.not_identified) == {"tool.y": -1.5e-6, "location.B.EX0B": 2e-6}
    assert dict(result.injected) == {"tool.y": -1.5e-6, "workpiece.x": 3e-6,
                                     "location.B.EX0B": 2e-6}
    folder = ReportFolder(tmp_path / "report")
    text = folder.write_result(result)
    assert ("Injected and not among the identified parameters: tool.y (-1.500000e-06), "
            "location.B.EX0B (2.000000e-06).") in text
    assert text.split("### Identified")[1] in (tmp_path / "report/identified.md").read_text()
    summary = json.loads((tmp_path / "report/summary.json").read_text())
    assert summary["not_identified"] == ["tool.y", "location.B.EX0B"]
    # the lab's realism is in the report (noise alone cannot tell "lab" from "noise_only")
    assert summary["realism"] == {"preset": "lab", "on": list(Realism.names())}
    exact = run(WorkpieceX(), Lab("robonano_a0ib", {"workpiece": {"delta_um": [3.0, 0, 0]}}))
    assert not exact.not_identified and "not_identified" not in exact.summary()
    assert exact.summary()["realism"] == {"preset": "noise_only", "on": ["instrument_noise"]}
    # without the instruments' noise the std holds only rounding: identified.md says so
    from machinesim.report import identified_notes

    assert "no noise" not in identified_notes(exact)
    assert identified_notes(run(WorkpieceX(), Lab("robonano_a0ib", noise=False))).startswith(
        "The lab's instruments had no noise: each std holds what the readings' rounding")
    some = Realism.with_only("instrument_noise", "stage_positioning")
    assert run(WorkpieceX(), Lab("robonano_a0ib", seed=1, realism=some)).summary()[
        "realism"] == {"preset": "instrument_noise+stage_positioning",
                       "on": ["instrument_noise", "stage_positioning"]}
    # a component table's entries (which the background's table may cancel at a point, so
    # that ``injected`` lacks them: the report ended in a KeyError) are one item
    tables = {"component": {"X": {"position_mm": [-100.0, 0.0, 100.0],
                                  "EXX_um": [1.0, 0.0, -1.0]}}}
    lab = Lab("robonano_a0ib", tables, seed=1, realism=Realism.lab())
    text = ReportFolder(tmp_path / "tables").write_result(run(WorkpieceX(), lab))
    assert ("Injected and not among the identified parameters: component.X.EXX "
            "(2 table entries).") in text


def test_injected_lists_the_injected_model_as_written_not_the_tabulated_sum(tmp_path):
    """A polynomial injected on an axis whose background is a table makes the truth a table
    of thousands of entries (`add_errors`); ``injected`` listed every one (21,316 on
    grooving_4axis with models/errors/example.toml), and ``component.X.EYX[2]`` there was a
    table entry where the user's file and ``not_identified`` gave a coefficient. Now it holds
    the identified parameters' true values and the rest as the file wrote them; the
    background is a count and its file."""
    import tomllib

    from machinesim.experiment import Evaluation, Figure, Identified, run
    from machinesim.realism import Realism
    from machinesim.report import ReportFolder, check_summary

    class CentreX:
        name, paper = "centre_x", "none"

        def __init__(self, names=("location.C.EX0C",)):
            self.names = names

        def measure(self, lab):
            return 0.0

        def identify(self, measurements):
            return Identified({name: (measurements, 1e-9) for name in self.names}, None)

        def compensate(self, identified):
            return {}

        def evaluate(self, lab, identified, programs):
            return Evaluation((Figure("x", "um", 1.0, 0.0),))

    def errors(curvature_um_mm2):
        return {"location": {"C": {"EX0C_um": 2.0, "EB0C_urad": 15.0}},
                "component": {"X": {"EYX_poly_um_mm": [0.0, 0.5, curvature_um_mm2]}}}

    results, sizes = [], []
    for curvature in (2e-5, 2e-3):
        lab = Lab("grooving_4axis", errors(curvature), seed=1, realism=Realism.lab())
        sizes.append(len(lab.reveal().parameters()))
        results.append(run(CentreX(), lab))
    # the truth's tabulation grows with the curvature (finer spacing); injected does not
    assert 1000 < sizes[0] < sizes[1]
    for result, curvature in zip(results, (2e-5, 2e-3), strict=True):
        # EX0C identified: 2 um injected + 0.3 um of background_grooving_4axis.toml
        assert dict(result.injected) == pytest.approx(
            {"location.C.EX0C": 2.3e-6, "location.C.EB0C": 15e-6,
             "component.X.EYX[1]": 0.5e-6 / 1e-3, "component.X.EYX[2]": curvature * 1e-6 / 1e-6},
            rel=1e-15, abs=0.0)
    # the background, summarised: its file and its non-zero values, counted from the file
    shipped = tomllib.loads((ROOT / "models/errors/background_grooving_4axis.toml").read_text())
    nonzero = sum(value != 0.0 for kind in ("location", "component")
                  for table in shipped[kind].values() for key, values in table.items()
                  if not key.startswith("position")
                  for value in (values if isinstance(values, list) else [values]))
    assert nonzero > 20
    assert dict(results[0].background) == {
        "file": "models/errors/background_grooving_4axis.toml", "nonzero_count": nonzero}
    # the report round-trips: summary.json holds what Result holds, and passes its schema
    ReportFolder(tmp_path / "report").write_result(results[0])
    summary = json.loads((tmp_path / "report/summary.json").read_text())
    check_summary(summary)
    assert summary["injected"] == dict(results[0].injected)
    assert summary["background"] == dict(results[0].background)
    assert summary["not_identified"] == ["location.C.EB0C", "component.X.EYX[1]",
                                         "component.X.EYX[2]"]
    # identified.md's note names them as what they are: coefficients, not table entries
    assert results[0].polynomials == ("component.X.EYX",)
    assert ("Injected and not among the identified parameters: location.C.EB0C "
            "(1.500000e-05), component.X.EYX (2 polynomial coefficients).") in (
        tmp_path / "report/identified.md").read_text()
    rows = json.loads((tmp_path / "report/identified.json").read_text())["rows"]
    assert rows == [["location.C.EX0C", pytest.approx(2.3e-6, rel=1e-15), 0.0, 1e-9,
                     pytest.approx(-2.3e-6, rel=1e-15)]]
    # a procedure naming component.X.EYX[2] (a coefficient in the user's file, a table entry
    # in the truth) gets no true value rather than one of the other meaning
    named = run(CentreX(("component.X.EYX[2]", "component.X.EXX[1]")),
                Lab("grooving_4axis", errors(2e-5), seed=1, realism=Realism.lab()))
    assert "component.X.EYX[2]" not in named.injected
    assert "component.X.EXX[1]" not in named.injected  # the background's, on other positions
    ReportFolder(tmp_path / "named").write_result(named)
    rows = json.loads((tmp_path / "named/identified.json").read_text())["rows"]
    assert [row[1] for row in rows] == [None, None]  # NaN: no true value of that meaning
    # without a background nothing is summarised, and a table entry has one meaning
    plain = run(CentreX(("component.X.EXX[1]",)),
                Lab("grooving_4axis", {"component": {"X": {"position_mm": [-100.0, 0.0, 100.0],
                                                           "EXX_um": [1.0, 0.5, -1.0]}}},
                    noise=False))
    assert dict(plain.injected) == {"component.X.EXX[0]": 1e-6, "component.X.EXX[1]": 0.5e-6,
                                    "component.X.EXX[2]": -1e-6}
    assert not plain.background and "background" not in plain.summary()


def test_injected_keeps_the_error_models_order_for_identified_names_never_written():
    """An identified name the injected model does not hold (a location error, a nose radius
    left at zero) came after the model's own names, so ``injected`` (and summary.json) read
    component.X.EYX[1] before location.C.EX0C. Every name now stands where
    `ErrorModel.parameters` puts it: tool, tool_geometry, workpiece, location, component."""
    from machinesim.experiment import Evaluation, Figure, Identified, run

    class Named:
        name, paper = "named", "none"

        def measure(self, lab):
            return 0.0

        def identify(self, measurements):
            names = ("location.C.EX0C", "tool_geometry.nose_radius", "workpiece.x")
            return Identified({name: (measurements, 1e-9) for name in names}, None)

        def compensate(self, identified):
            return {}

        def evaluate(self, lab, identified, programs):
            return Evaluation((Figure("x", "um", 1.0, 0.0),))

    lab = Lab("grooving_4axis", {"tool": {"offset_um": [0.0, 3.0, 0.0]},
                                 "component": {"X": {"EYX_poly_um_mm": [0.0, 0.5]}}},
              noise=False)
    result = run(Named(), lab)
    assert list(result.injected) == ["tool.y", "tool_geometry.nose_radius", "workpiece.x",
                                     "location.C.EX0C", "component.X.EYX[1]"]
    assert list(result.summary()["injected"]) == list(result.injected)
    # the order is ErrorModel.parameters' own: a full model's names, shuffled, sort back
    from machinesim.experiment import _in_parameter_order

    full = ErrorModel.from_dict({
        "tool": {"offset_um": [1.0, 2.0, 3.0], "rotation_urad": [4.0, 5.0, 6.0]},
        "tool_geometry": {"nose_radius_um": 7.0},
        "workpiece": {"delta_um": [1.0, 2.0, 3.0], "alpha_urad": 1.0, "beta_urad": 2.0,
                      "gamma_urad": 3.0},
        "location": {"C": {"EY0C_um": 1.0, "EX0C_um": 2.0, "EA0C_urad": 3.0},
                     "X": {"EC0X_urad": 4.0}},
        "component": {"Z": {"EXZ_poly_um_mm": [1.0, 2.0]},
                      "X": {"position_mm": [0.0, 1.0], "EYX_um": [1.0, 2.0],
                            "EXX_um": [3.0, 4.0], "ECX_urad": [5.0, 6.0]}}})
    names = list(full.parameters())
    assert len(names) == 6 + 1 + 6 + 4 + 2 + 6
    shuffled = [names[i] for i in np.random.default_rng(0).permutation(len(names))]
    assert shuffled != names
    assert _in_parameter_order(shuffled) == names
    # a name of no error-model form keeps its place among such names, after the rest
    assert _in_parameter_order(["b.other", "component.X.EXX[0]", "a.other", "tool.x"]) == [
        "tool.x", "component.X.EXX[0]", "b.other", "a.other"]
