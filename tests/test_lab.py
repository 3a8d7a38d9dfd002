"""The lab keeps the truth: no public door to the injected errors, seeded per-instrument
noise, and a scan that keeps identification and compensation away from the truth."""

from __future__ import annotations

import ast
import json
from pathlib import Path

import numpy as np
import pytest

import machinesim
from machinesim import ErrorModel, Lab
from machinesim.exceptions import InputError
from machinesim.nc import ProgramBuilder

ROOT = Path(__file__).resolve().parents[1]
TRUTH = {"tool": {"offset_um": [5.0, -3.0, 1.0]}, "location": {"C": {"EX0C_um": 2.0}}}


def groove():
    return (ProgramBuilder(1).rapid(X=1e-3, Y=1e-3, Z=1e-3).linear(Z=-1e-5, feed_mm_per_min=100)
            .linear(X=8e-3, feed_mm_per_min=100).rapid(Z=1e-3).build())


def _holds_truth(value, truth) -> bool:
    if value is truth or isinstance(value, ErrorModel):
        return True
    if isinstance(value, dict | list | tuple):
        items = value.values() if isinstance(value, dict) else value
        return any(_holds_truth(v, truth) for v in items)
    return False


def _public(obj):
    for name in dir(obj):
        if name.startswith("_"):
            continue
        value = getattr(obj, name)
        if callable(value):
            continue
        yield name, value


def test_no_public_attribute_of_the_lab_or_its_instruments_holds_the_truth():
    lab = Lab("robonano_a0ib", TRUTH, seed=3)
    truth = lab.reveal()
    part, _ = lab.cut(groove(), "v:90", "block:10x10x2")
    things = [lab, lab.touch_probe(part), lab.laser_interferometer(), lab.microscope(),
              lab.white_light_interferometer(), lab.r_test(), lab.encoders()]
    for thing in things:
        for name, value in _public(thing):
            assert not _holds_truth(value, truth), f"{type(thing).__name__}.{name}"
    methods = {name for name in dir(lab) if not name.startswith("_")}
    assert methods == {"adjust_tool", "artefact_scatter", "cut", "encoders",
                       "laser_interferometer", "machine",
                       "make_artefacts", "microscope", "noise", "r_test", "realism", "reveal",
                       "reveal_adjustments", "reveal_artefacts", "reveal_background",
                       "reveal_instruments", "reveal_servo", "reuse_cuts", "seed",
                       "touch_probe", "tune_servo", "turn", "white_light_interferometer"}


def test_with_realism_no_public_attribute_holds_the_truth_or_an_imperfection():
    from machinesim.metrology.imperfections import Lobing, Registration, ZonalForm
    from machinesim.realism import Realism

    lab = Lab("robonano_a0ib", TRUTH, seed=3, realism=Realism.lab())
    truth = lab.reveal()
    part, _ = lab.cut(groove(), "v:90", "block:10x10x2")
    things = [lab, lab.touch_probe(part), lab.laser_interferometer(), lab.microscope(),
              lab.white_light_interferometer(), lab.r_test()]
    hidden = (Registration, Lobing, ZonalForm)
    for thing in things:
        for name, value in _public(thing):
            assert not _holds_truth(value, truth), f"{type(thing).__name__}.{name}"
            assert not isinstance(value, hidden), f"{type(thing).__name__}.{name}"


def test_the_lab_cuts_with_its_truth_as_cut_does_with_the_errors():
    lab = Lab("robonano_a0ib", TRUTH, noise=False)
    part, report = lab.cut(groove(), "v:90", "block:10x10x2")
    direct, direct_report = machinesim.cut(groove(), "robonano_a0ib", "v:90", "block:10x10x2",
                                           ErrorModel.from_dict(TRUTH))
    assert np.array_equal(part.mesh()[0], direct.mesh()[0])
    assert report.removed_volume_m3 == direct_report.removed_volume_m3
    with pytest.raises(InputError, match="own errors"):
        lab.cut(groove(), errors=None)


def test_a_reading_does_not_change_when_another_instrument_reads_first():
    def read(extra: bool):
        lab = Lab("robonano_a0ib", TRUTH, seed=11)
        part, _ = lab.cut(groove(), "v:90", "block:10x10x2")
        if extra:
            lab.touch_probe(part).touch([5e-3, 5e-3, 1e-3, 0.0, 0.0], "-Z", 2e-3)
            lab.white_light_interferometer().profile(part, (2e-3, 0.0), (2e-3, 2e-3))
            lab.microscope(label="elsewhere").profile(part, (1e-3, 0.0), (1e-3, 2e-3))
        return lab.microscope().profile(part, (5e-3, 0.0), (5e-3, 2e-3), spacing=1e-5).z

    alone, after_others = read(False), read(True)
    assert np.array_equal(alone, after_others)
    # and the noise is there: a second microscope has its own stream
    lab = Lab("robonano_a0ib", TRUTH, seed=11)
    part, _ = lab.cut(groove(), "v:90", "block:10x10x2")
    first = lab.microscope().profile(part, (5e-3, 0.0), (5e-3, 2e-3), spacing=1e-5).z
    second = lab.microscope().profile(part, (5e-3, 0.0), (5e-3, 2e-3), spacing=1e-5).z
    assert np.array_equal(first, alone) and not np.array_equal(first, second)


def test_noise_off_reads_exactly_and_seeds_differ_with_noise_on():
    lab = Lab("robonano_a0ib", TRUTH, noise=False, seed=1)
    part, _ = lab.cut(groove(), "v:90", "block:10x10x2")
    z = lab.microscope(resolution=0.0).profile(part, (5e-3, 0.0), (5e-3, 0.5e-3)).z
    assert np.all(z == 0.0)  # land far from the groove: exactly the top face
    noisy = [Lab("robonano_a0ib", TRUTH, seed=s).microscope().profile(
        part, (5e-3, 0.0), (5e-3, 0.5e-3)).z for s in (1, 2)]
    assert not np.array_equal(*noisy)


def test_bad_lab_arguments_are_clear_errors():
    with pytest.raises(InputError, match="seed"):
        Lab("robonano_a0ib", seed=-1)
    with pytest.raises(InputError, match="noise"):
        Lab("robonano_a0ib", noise="yes")
    with pytest.raises(InputError, match="errors"):
        Lab("robonano_a0ib", errors=3.0)
    with pytest.raises(machinesim.MachineSimError, match="axis 'A' is not on this machine"):
        Lab("robonano_a0ib", {"location": {"A": {"EX0A_um": 1.0}}})


# ---------------------------------------------------------------------------- the honesty scan

#: Where the truth must never be reached: identification, compensation, and the shipped
#: procedures (whose measure and evaluate hold a lab, to cut and read with, never to reveal).
HONEST = [*sorted((ROOT / "machinesim" / "identification").glob("*.py")),
          ROOT / "machinesim" / "compensation.py", ROOT / "machinesim" / "compensation_table.py",
          *sorted((ROOT / "machinesim" / "procedures").glob("*.py"))]


def _violations(path: Path) -> list[str]:
    tree = ast.parse(path.read_text(), filename=str(path))
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute):
            attr = node.attr
            owner = node.value.id if isinstance(node.value, ast.Name) else None
            if attr == "reveal":
                found.append(f"{path.name}:{node.lineno} calls reveal()")
            elif attr.startswith("_") and not attr.startswith("__") and owner not in (
                    "self", "cls"):
                found.append(f"{path.name}:{node.lineno} reaches private .{attr}")
            elif "_Lab__" in attr:
                found.append(f"{path.name}:{node.lineno} reaches the lab's truth")
            elif attr in ("__dict__", "__closure__", "__globals__"):
                found.append(f"{path.name}:{node.lineno} reaches .{attr}")
            elif attr == "seed":
                found.append(f"{path.name}:{node.lineno} reads a seed (the noise replayed)")
        elif isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.args:
            name, args = node.func.id, node.args
            private = (len(args) > 1 and isinstance(args[1], ast.Constant)
                       and str(args[1].value).startswith("_"))
            if name == "vars" or (name in ("getattr", "setattr") and private):
                found.append(f"{path.name}:{node.lineno} uses {name}() past the public API")
            elif name in ("stream", "default_rng"):
                found.append(f"{path.name}:{node.lineno} builds a noise stream ({name})")
        elif isinstance(node, ast.Name) and node.id in ("Lab",):
            found.append(f"{path.name}:{node.lineno} names the Lab")
    return found


def test_identification_and_compensation_never_reach_the_truth():
    assert HONEST, "nothing to scan"
    found = [v for path in HONEST if path.exists() for v in _violations(path)]
    assert not found, "\n".join(found)


def test_the_honesty_scan_catches_what_it_must(tmp_path):
    bad = tmp_path / "bad.py"
    bad.write_text("def f(lab, probe):\n    t = lab.reveal()\n    e = probe._pose\n"
                   "    n = stream(lab.seed, 'r_test', 'ball')\n"
                   "    return getattr(lab, '_Lab__truth'), vars(probe), f.__closure__\n")
    found = _violations(bad)
    assert len(found) == 7, found


def test_no_instrument_hands_out_its_noise_stream():
    # With the generator a procedure could draw the noise again and subtract it: the R-test's
    # fit then came within 0.1 nm of the injected errors instead of its 10-30 nm of noise.
    from machinesim.realism import Realism

    lab = Lab("robonano_a0ib", TRUTH, seed=3, realism=Realism.lab())
    part, _ = lab.cut(groove(), "v:90", "block:10x10x2")
    things = [lab.touch_probe(part), lab.laser_interferometer(), lab.microscope(),
              lab.white_light_interferometer(), lab.r_test(), lab.encoders()]
    for thing in things:
        for name, value in _public(thing):
            assert not isinstance(value, np.random.Generator), f"{type(thing).__name__}.{name}"


def test_whether_a_tool_adjustment_is_taken_does_not_depend_on_the_hidden_tool(tmp_path):
    # The check is of the move alone, against the adjuster's stroke: a check of where the
    # tool lands would tell, by refusing or not, where the hidden tool is.
    from machinesim.realism import TOOL_ADJUSTER_STROKE_M

    messages = set()
    for offset_um in (-995_000.0, -4000.0, 0.0, 4000.0, 995_000.0):
        lab = Lab("robonano_a0ib", {"tool": {"offset_um": [offset_um, 0.0, 0.0]}}, seed=1)
        lab.adjust_tool([0.75 * TOOL_ADJUSTER_STROKE_M, 0.0, 0.0])
        with pytest.raises(InputError, match="beyond its stroke") as info:
            lab.adjust_tool([0.25 * TOOL_ADJUSTER_STROKE_M * (1 + 1e-6), 0.0, 0.0])
        lab.adjust_tool([0.25 * TOOL_ADJUSTER_STROKE_M, 0.0, 0.0])  # to the stroke's end
        messages.add(str(info.value))
    assert len(messages) == 1  # word for word the same, wherever the tool is
    # an injected offset that leaves no room for the stroke is refused when the lab is made
    with pytest.raises(InputError, match="1 m less the tool adjuster's stroke"):
        Lab("robonano_a0ib", {"tool": {"offset_um": [995_001.0, 0.0, 0.0]}})
    # given in a file (in metres), the message names the file and its table
    path = tmp_path / "far.toml"
    path.write_text("# far off\n[tool]\noffset_m = [0.0, 1.0, 0.0]\n")
    with pytest.raises(InputError) as info:
        Lab("robonano_a0ib", path)
    assert str(info.value).startswith(f"{path}, line 3, key '[tool] offset': a tool offset of "
                                      "[0.0, 1000.0, 0.0] mm")


def test_the_r_test_reads_the_ball_displacement_of_a_tool_offset_turned_by_b_and_c():
    # A tool offset d (tool_mount frame) on robonano_a0ib is carried by B (about Y) and seen
    # from the workpiece turned by -C: at B = 0 and C = 0 the ball is displaced by d itself.
    d = np.array([5.0, -3.0, 2.0]) * 1e-6
    lab = Lab("robonano_a0ib", {"tool": {"offset_um": (d * 1e6).tolist()}}, noise=False)
    reading = lab.r_test(resolution=0.0).read(np.zeros((1, 5)))
    assert np.allclose(reading.displacement[0], d, rtol=0, atol=1e-15)
    # the length of the displacement is the offset's, whatever B and C (a rigid offset)
    q = np.zeros((6, 5))
    q[:, 3] = np.radians([-30, 0, 30, 10, -20, 45])
    q[:, 4] = np.radians([0, 90, 180, 270, 33, -120])
    shown = lab.r_test(resolution=0.0).read(q).displacement
    assert np.allclose(np.linalg.norm(shown, axis=1), np.linalg.norm(d), rtol=0, atol=1e-15)


def test_run_tells_its_progress_step_by_step_in_order():
    """`run(..., progress=)` is told each step as it begins and when it ends, in the
    protocol's order, with the time the step took (as `Result.elapsed_s` records it)."""
    from machinesim.experiment import Evaluation, Figure, Identified, run

    class Counting:
        name, paper = "counting", "none"

        def measure(self, lab):
            return 1.0

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


def test_the_api_refuses_what_it_cannot_use_with_a_machinesim_error():
    from machinesim.campaign.runner import _vary
    from machinesim.experiment import run
    from machinesim.procedures.tool_rotation_arm import ToolRotationArm

    machine = machinesim.load_machine("robonano_a0ib")
    q = np.array([1e-3, 2e-3, 0.0, 0.3, 1.1])
    # errors as a dict, as Lab and cut take them, pose the tool as the ErrorModel does
    as_dict = machine.tool_pose(q, TRUTH)
    assert np.array_equal(as_dict, machine.tool_pose(q, ErrorModel.from_dict(TRUTH)))
    assert not np.array_equal(as_dict, machine.tool_pose(q))
    with pytest.raises(InputError, match="expected axis values as numbers"):
        machine.tool_pose("abc")
    with pytest.raises(InputError, match="expected a machinesim.Lab"):
        run(ToolRotationArm(), "planer_4axis")
    with pytest.raises(InputError, match="without measure, identify"):
        run("tool_rotation_arm", Lab("planer_4axis"))
    # a background the realism would not use is refused, naming it
    with pytest.raises(InputError, match="key 'background'.*no background_errors"):
        Lab("planer_4axis", background={})
    # one "PARAM=DIST" string is one variation, not one per character
    assert [name for name, _ in _vary("microscope.sigma=uniform:5nm,200nm")] == [
        "microscope.sigma"]


def test_a_background_file_refused_names_its_line(tmp_path):
    # the refusal of a background file's key kept the file but dropped the key's line
    path = tmp_path / "own.toml"
    path.write_text("[location.C]\nEX0C_um = 1.0\n[tool]\noffset_um = [1.0, 2.0]\n")
    with pytest.raises(InputError) as info:
        Lab("planer_4axis", realism=machinesim.Realism.lab(), background=path)
    assert str(info.value) == (f"{path}, line 4, key 'background': expected 3 values, got 2: "
                               "[1.0, 2.0] (list)")


def test_every_error_kind_the_docs_name_is_importable_from_the_package():
    import machinesim.exceptions as exceptions

    kinds = {name for name, value in vars(exceptions).items()
             if isinstance(value, type) and issubclass(value, exceptions.MachineSimError)}
    assert kinds >= {"InputError", "ModelError", "UnreachableError", "AxisLimitError",
                     "HolderContactError", "NCProgramError"}
    for name in kinds:
        assert getattr(machinesim, name) is getattr(exceptions, name)
        assert name in machinesim.__all__
    # the refusals a user meets first are caught by the name the package gives
    with pytest.raises(machinesim.ModelError):
        machinesim.load_machine("no_such_machine")


def test_a_labs_machine_seed_noise_and_realism_are_fixed_when_it_is_made():
    # each was a plain attribute: lab.seed = 3 after an instrument had left the next one
    # numbered on from the old lab (neither the old lab's reading nor a fresh Lab(seed=3)'s),
    # lab.seed = -5 was refused only at the next instrument, lab.machine = "sts_lathe" failed
    # in repr with "'str' object has no attribute 'name'", and lab.noise = False on a realism
    # with instrument noise left the two saying otherwise
    from machinesim.exceptions import ReadOnlyError, brief
    from machinesim.realism import Realism

    lab = Lab("robonano_a0ib", TRUTH, seed=1, realism=Realism.lab())
    machine = lab.machine
    lab.laser_interferometer()
    for name, value in (("seed", 3), ("seed", -5), ("machine", "sts_lathe"), ("noise", False),
                        ("realism", Realism.ideal())):
        with pytest.raises(ReadOnlyError) as info:
            setattr(lab, name, value)
        assert str(info.value).startswith(f"Lab.{name} cannot be set (to "
                                          f"{brief(repr(value))}): ")
        assert str(info.value).endswith(f"; make another Lab with the {name} wanted")
        assert isinstance(info.value, machinesim.MachineSimError | AttributeError)
        assert isinstance(info.value, AttributeError)
        with pytest.raises(ReadOnlyError, match=rf"^Lab\.{name} cannot be deleted: "):
            delattr(lab, name)
    assert (lab.machine, lab.seed, lab.noise, lab.realism) == (machine, 1, True, Realism.lab())
    assert repr(lab) == "Lab(robonano_a0ib, noise=on, seed=1, realism=lab)"
    # the lab reads on as made: its next instrument is the one a fresh lab hands out second
    fresh = Lab("robonano_a0ib", TRUTH, seed=1, realism=Realism.lab())
    fresh.laser_interferometer()
    assert lab.laser_interferometer()._rng.random() == fresh.laser_interferometer()._rng.random()
    # a pickle and a copy carry them; reuse_cuts stays the lab's switch to set
    import copy
    import pickle

    again = pickle.loads(pickle.dumps(Lab("robonano_a0ib", seed=7, noise=False)))
    assert (again.machine.name, again.seed, again.noise) == ("robonano_a0ib", 7, False)
    assert copy.copy(again).seed == 7
    again.reuse_cuts = False
    assert again.reuse_cuts is False


def test_a_realism_given_by_its_scenario_name_says_how_to_make_it():
    # the scenarios take --realism ideal; Lab(..., realism="ideal") said only "got str"
    from machinesim.realism import Realism

    with pytest.raises(InputError, match=r"got str 'ideal': make one with "
                                         r"machinesim\.realism\.Realism\.ideal\(\), "
                                         r"\.noise_only\(\) or \.lab\(\)"):
        Lab("sts_lathe", realism="ideal")
    assert Lab("sts_lathe", realism=Realism.ideal()).realism == Realism.ideal()


def test_a_cut_option_the_lab_does_not_take_is_refused_with_the_options_it_takes():
    # lab.cut(..., chord=1e-9) ended in TypeError: cut() got an unexpected keyword argument
    # 'chord' and progress=5 in TypeError: 'int' object is not callable from the engine,
    # after the planning; the instruments refuse an option they do not take with a list
    lab = Lab("robonano_a0ib", noise=False)
    with pytest.raises(InputError, match=r"Lab.cut has no option 'chord'; it takes start, "
                                         r"chord_tolerance, servo, progress, allow_overtravel, "
                                         r"allow_holder_contact, turn_step") as info:
        lab.cut(groove(), "v:90", "block:10x10x2", chord=1e-9)
    assert info.value.key == "chord"
    with pytest.raises(InputError, match=r"Lab.cut with turn_step has no option 'chord'; it "
                                         r"takes floor, start, turn_step, turn_axis, "
                                         r"chord_tolerance, servo, allow_overtravel, "
                                         r"allow_holder_contact, progress"):
        lab.cut(groove(), "v:90", "block:10x10x2", turn_step=0.5, chord=1e-9)
    for cutter in (lambda **o: lab.cut(groove(), "v:90", "block:10x10x2", **o),
                   lambda **o: machinesim.cut(groove(), "robonano_a0ib", **o)):
        with pytest.raises(InputError, match=r"Expected progress as a callable\(done, total\) "
                                             r"or None, got 5") as info:
            cutter(progress=5)
        assert info.value.key == "progress"
    told = []
    _, report = lab.cut(groove(), "v:90", "block:10x10x3", progress=lambda *a: told.append(a))
    assert told and told[-1] == (report.sweeps, report.sweeps)


def test_reveal_takes_true_or_false_for_the_background():
    # lab.reveal(background="no") (a string, so true) gave the injected errors plus the
    # background, the column a report puts beside the injected ones
    from machinesim.realism import Realism

    lab = Lab("robonano_a0ib", TRUTH, realism=Realism.lab())
    assert lab.reveal(background=False) is not lab.reveal()
    with pytest.raises(InputError, match=r"Expected background as True or False, got 'no'"):
        lab.reveal(background="no")


def test_run_refuses_a_progress_it_cannot_call_before_measuring():
    # run(procedure, lab, progress=5) ended in TypeError: 'int' object is not callable
    from machinesim.experiment import run
    from machinesim.procedures.tool_rotation_arm import ToolRotationArm

    with pytest.raises(InputError, match=r"Expected progress as a callable\(text\) or None, "
                                         r"got 5") as info:
        run(ToolRotationArm(), Lab("planer_4axis", noise=False), progress=5)
    assert info.value.key == "progress"


def test_run_refuses_a_lab_whose_tool_an_earlier_run_moved():
    # sts_turning's evaluate aligns the tool (lab.adjust_tool); a second run on that lab, or
    # any run on a lab so moved, identified what the machine then had (tool.y 0) and
    # reported it against the 3 um the lab was made with: a 3 um error nobody made
    from machinesim.experiment import run
    from machinesim.procedures.tool_rotation_arm import ToolRotationArm

    arm = ToolRotationArm()
    lab = Lab("planer_4axis", {"tool": {"offset_um": [0.0, 3.0, 2.0]}}, noise=False)
    first = run(arm, lab)
    assert first.identified["tool.y"][0] == pytest.approx(3e-6, abs=1e-9)
    again = run(arm, lab)  # a lab no run moved is run on again as made: the same readings
    assert again.identified == first.identified
    lab.adjust_tool((0.0, -3e-6, 0.0))  # as paper 004's alignment moves it
    with pytest.raises(InputError, match=r"this lab's tool has been moved by lab\.adjust_tool "
                                         r".*run each procedure on a new Lab") as info:
        run(arm, lab)
    assert info.value.key == "lab"


def test_run_refuses_a_procedures_class_for_a_procedure():
    # run(ToolRotationArm, lab), the class for its instance, passed the check (its methods
    # are callable) and ended in TypeError: measure() missing 1 required positional argument
    from machinesim.experiment import run
    from machinesim.procedures.tool_rotation_arm import ToolRotationArm

    with pytest.raises(InputError) as info:
        run(ToolRotationArm, Lab("planer_4axis", noise=False))
    assert str(info.value) == ("key 'procedure': expected a procedure, got the class "
                               "ToolRotationArm itself; make one: run(ToolRotationArm(), lab)")
    assert info.value.key == "procedure"


def test_run_refuses_a_lab_whose_servo_an_earlier_run_tuned():
    # sts_turning's evaluate tunes the servo to Table 6 "after" before Case 4; run again on
    # that lab (noise off, no tool error: no tool move to refuse), its Case 1, the control
    # "as found", was cut with the "after" loops. A lab set back to the loops it was made
    # with (the very ones, or equal ones) is as made: run stops here only at its first step
    from machinesim.experiment import run
    from machinesim.procedures.tool_rotation_arm import ToolRotationArm
    from machinesim.servo import table6_servo

    class Started(Exception):
        pass

    def stop(text):
        raise Started(text)

    axes = ("x", "y", "z", "a")
    before = table6_servo("before", axis_order=axes)
    lab = Lab("planer_4axis", noise=False, servo=before)
    with pytest.raises(Started, match="measure"):
        run(ToolRotationArm(), lab, progress=stop)
    lab.tune_servo(table6_servo("after", axis_order=axes))
    assert lab.reveal_servo(as_made=True) is before
    with pytest.raises(InputError, match=r"this lab's servo loops have been tuned by "
                                         r"lab\.tune_servo since it was made .*'before' case "
                                         r".*run each procedure on a new Lab") as info:
        run(ToolRotationArm(), lab, progress=stop)
    assert info.value.key == "lab"
    lab.tune_servo(table6_servo("before", axis_order=axes))  # equal to those it was made with
    with pytest.raises(Started, match="measure"):
        run(ToolRotationArm(), lab, progress=stop)
    lab.tune_servo(before)
    with pytest.raises(Started, match="measure"):
        run(ToolRotationArm(), lab, progress=stop)
    lab.adjust_tool((1e-6, 0.0, 0.0))
    lab.tune_servo(table6_servo("after", axis_order=axes))
    with pytest.raises(InputError, match=r"this lab's tool has been moved by lab\.adjust_tool "
                                         r"and its servo loops tuned by lab\.tune_servo since"):
        run(ToolRotationArm(), lab, progress=stop)
    ideal = Lab("planer_4axis", noise=False)  # no loops as made: any set is a tuning
    ideal.tune_servo(table6_servo("before", axis_order=axes))
    with pytest.raises(InputError, match=r"servo loops have been tuned"):
        run(ToolRotationArm(), ideal, progress=stop)
    with pytest.raises(InputError, match=r"Expected as_made as True or False, got 'no'"):
        ideal.reveal_servo(as_made="no")


def test_a_tool_adjustment_given_in_mm_is_refused_naming_the_unit():
    # adjust_tool([10, 0, 0]), 10 mm meant, is a 10 m move: it was refused by the +-5 mm
    # stroke with no word of the unit; a move longer than the whole stroke (10 mm) asks
    lab = Lab("robonano_a0ib", seed=1)
    with pytest.raises(InputError, match=r"offset is in m, 10 m: given in mm or um\?"):
        lab.adjust_tool([10, 0, 0])
    # a move the adjuster could make from elsewhere in its stroke is no unit slip
    lab.adjust_tool([-4e-3, 0.0, 0.0])
    with pytest.raises(InputError, match="beyond its stroke") as info:
        lab.adjust_tool([9.5e-3, 0.0, 0.0])
    assert "given in mm" not in str(info.value)
