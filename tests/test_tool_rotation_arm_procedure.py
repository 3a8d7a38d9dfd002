"""Paper 000's procedure class (`ToolRotationArm`) run through `run`: the injected tool
setting identified, its report and its pickled result, a fit that warns, the
compensated program, and the Python API's refusals of arguments of the wrong kind."""

from __future__ import annotations

import json
import math
from types import MappingProxyType

import numpy as np
import pytest
from tool_rotation_arm_helpers import PAPER_E, PAPER_R, errors_for, worst_gain

from machinesim import ErrorModel, Lab, load_machine
from machinesim.exceptions import InputError
from machinesim.experiment import Identified, run
from machinesim.identification import tool_rotation_arm as arm
from machinesim.identification.fit import misfit_limit
from machinesim.nc import ProgramBuilder
from machinesim.procedures import tool_rotation_arm as procedure
from machinesim.procedures.tool_rotation_arm import ToolRotationArm
from machinesim.report import ReportFolder, check_summary

MM, UM, NM = 1e-3, 1e-6, 1e-9


@pytest.fixture(scope="module")
def machine():
    return load_machine("planer_4axis")


@pytest.fixture(scope="module")
def r0(machine):
    return arm.arm_radius(machine)


@pytest.fixture(scope="module")
def exact_run():
    """The paper's case on a lab with the noise off, run through `run`."""
    machine = load_machine("planer_4axis")
    r0 = arm.arm_radius(machine)
    lab = Lab(machine, errors_for(PAPER_R, PAPER_E, r0), noise=False, seed=3)
    return run(ToolRotationArm(), lab), lab


def test_the_procedure_identifies_the_injected_tool_setting(exact_run, r0):
    result, lab = exact_run
    truth = lab.reveal().parameters()
    assert set(result.identified) == {"tool.y", "tool.z"}
    # same sign and size as the truth: tool.y = e_ys, tool.z = -(r - r0); noise off, only the
    # microscope's display rounding is left (bounds of the noise-off test above)
    gain = worst_gain()
    value, std = result.identified["tool.y"]
    assert value == pytest.approx(truth["tool.y"], abs=gain[2] * 0.1 * NM)
    assert std == result.identification.detail.estimate.e_ys_sigma
    value, std = result.identified["tool.z"]
    assert value == pytest.approx(truth["tool.z"], abs=gain[1] * 0.1 * NM)
    assert std == result.identification.detail.estimate.r_sigma
    detail = result.identification.detail
    assert (detail.r0, detail.r, detail.e_ys) == (r0, detail.estimate.r, detail.estimate.e_ys)
    assert result.injected == {"tool.y": truth["tool.y"], "tool.z": truth["tool.z"]}
    assert result.figure("depth_error").before > 50.0
    assert result.figure("depth_error").after < 2e-3  # um; the 1 nm grid, as above
    assert result.figure("depth_variation").after < 2e-3


def test_a_pattern_not_read_is_said_before_and_after(exact_run):
    # the uncompensated pattern may not be cut at all (an edge offset near the capture lifts
    # it off the surface beyond the first angles): its figures were n/a with no word why
    # (--e-ys-um -990, exit 0), and a compensated pattern not read was n/a the same way. Both
    # now say what the reading found; the run goes on, so that a campaign's trial keeps its
    # identified values and its other figures (a workpiece tilted 1 mrad, which the
    # procedure does not identify, leaves the compensated pattern unreadable)
    result, lab = exact_run
    air = ProgramBuilder(1).rapid(Z=5e-3).build()        # cuts nothing: no groove to read
    programs = dict(result.programs, pattern_before=air)
    evaluation = ToolRotationArm().evaluate(lab, result.identification, programs)
    why = evaluation.details["pattern_before"]["why"]
    assert evaluation.details["pattern_before"]["measured"] is False
    assert why.startswith("key 'z': Expected uncut land at both ends of the profile")
    for figure in evaluation.figures:
        assert figure.before is None and figure.after < 2e-3
        assert f"before not measured, the uncompensated pattern: {why}" in figure.note
        assert "after not measured" not in figure.note
    evaluation = ToolRotationArm().evaluate(lab, result.identification,
                                            dict(result.programs, pattern_compensated=air))
    why = evaluation.details["pattern_after"]["why"]
    assert evaluation.details["pattern_after"]["measured"] is False
    assert why.startswith("key 'z': Expected uncut land at both ends of the profile")
    for figure in evaluation.figures:
        assert figure.after is None and figure.before > 0.0
        assert f"after not measured, the compensated pattern: {why}" in figure.note
        assert "before not measured" not in figure.note


def test_the_procedure_report_follows_the_one_schema(exact_run, tmp_path):
    result, _ = exact_run
    check_summary(json.loads(json.dumps(result.summary())))
    ReportFolder(tmp_path).write_result(result)
    summary = json.loads((tmp_path / "summary.json").read_text())
    check_summary(summary)
    assert summary["seed"] == 3 and summary["noise"] is False
    assert [f["name"] for f in summary["figures"]] == ["depth_error", "depth_variation",
                                                       "pitch_error"]
    for name in ("pattern_before.nc", "pattern_compensated.nc", "pattern_after.ply"):
        assert (tmp_path / name).stat().st_size > 0


def test_a_result_pickles_and_comes_back_the_same_without_its_lab(exact_run, tmp_path):
    """A Result pickles (saved, or sent to a Dask worker and back): before, its read-only
    mappings (injected, identified, ...) and its calibration part (a manifold3d value) made
    pickle.dumps fail ("cannot pickle 'mappingproxy' object"). The copy has the same figures
    and identified values, writes the same report byte for byte, and the pickle holds no lab:
    its only error models are the fits' own estimates."""
    import io
    import pickle

    from machinesim.errors.model import ErrorModel as Model

    result, lab = exact_run
    kept = []

    class Recording(pickle.Pickler):
        def persistent_id(self, obj):
            kept.append(obj)
            return None

    buffer = io.BytesIO()
    Recording(buffer, protocol=pickle.HIGHEST_PROTOCOL).dump(result)
    back = pickle.loads(buffer.getvalue())
    assert back.figures == result.figures and len(back.figures) == 3
    assert dict(back.identified) == dict(result.identified)
    assert dict(back.identification.parameters) == dict(result.identified)
    assert dict(back.injected) == dict(result.injected)
    with pytest.raises(TypeError):  # read-only again
        back.identified["tool.y"] = (0.0, 0.0)
    assert back.identification.detail.estimate == result.identification.detail.estimate
    part, copy = (r.evaluation.parts["calibration"] for r in (result, back))
    assert copy.volume == part.volume and copy.manifold.volume() == pytest.approx(part.volume)
    assert all(np.array_equal(a, b) for a, b in zip(copy.mesh(), part.mesh(), strict=True))
    ReportFolder(tmp_path / "original").write_result(result)
    ReportFolder(tmp_path / "copy").write_result(back)
    names = sorted(p.name for p in (tmp_path / "original").iterdir())
    assert names == sorted(p.name for p in (tmp_path / "copy").iterdir())
    assert {"summary.json", "identified.md", "pattern_after.ply"} <= set(names)
    for name in names:
        assert ((tmp_path / "copy" / name).read_bytes()
                == (tmp_path / "original" / name).read_bytes()), name
    assert not any(isinstance(obj, Lab) for obj in kept)
    detail = result.identification.detail
    fitted = {id(detail.check.estimate.errors), id(detail.check_lateral.estimate.errors)}
    assert {id(obj) for obj in kept if isinstance(obj, Model)} == fitted
    assert lab.reveal() not in [obj for obj in kept if isinstance(obj, Model)]


def test_a_budget_added_after_the_report_joins_its_summary_and_a_later_report_drops_it(
        exact_run, tmp_path):
    """A scenario may write its report first and its error budget later (`add_budget`): the
    summary then holds the budget's rows and files; a later report into the same folder
    without a budget removes the old one, never pairing a result with another run's."""
    from dataclasses import replace

    from machinesim.budget import Budget, error_budget
    from machinesim.experiment import Figure

    result, _ = exact_run
    half = replace(result, figures=tuple(
        Figure(f.name, f.unit, f.before, None if f.after is None else f.after / 2)
        for f in result.figures))
    budget = error_budget(lambda off: result if off is None else half, ["stage_positioning"])
    folder = ReportFolder(tmp_path)
    folder.write_result(result)
    assert "budget" not in json.loads((tmp_path / "summary.json").read_text())
    text = folder.add_budget(result, budget)
    summary = json.loads((tmp_path / "summary.json").read_text())
    check_summary(summary)
    assert Budget.from_dict(summary["budget"]) == budget and budget.table() in text
    assert all(row.share == pytest.approx(0.75) for row in budget.rows if row.after_all)
    assert {"budget.md", "budget.png", "pattern_after.ply"} <= set(summary["files"])
    ReportFolder(tmp_path).write_result(result)
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert "budget" not in summary and "budget.md" not in summary["files"]
    assert not (tmp_path / "budget.md").exists() and not (tmp_path / "budget.png").exists()


def test_a_fit_that_warns_reaches_identified_md_and_summary_json(exact_run, tmp_path):
    """The notes of the generic fit (`Estimate.notes`) reach the report: a reading the model
    cannot hold, 1 um more depth at 20 deg alone, makes the heights' cross-check warn that
    the readings do not fit the model; identified.md lists the warning under its table and
    summary.json under ``notes``, word for word. Before, a report never said a fit warned."""
    from dataclasses import replace

    result, _ = exact_run
    calibration = result.measurements
    bump = 1 * UM
    readings = tuple(replace(r, dz=r.dz + bump) if round(math.degrees(r.angle)) == 20 else r
                     for r in calibration.readings)
    identified = ToolRotationArm().identify(replace(calibration, readings=readings))
    # a second way: eq 1 is linear in (1, 1 - cos t, sin t), the same at every station, and
    # every reading has the same sigma, so ordinary least squares of the depths on that
    # basis leaves the fit's residual: the bump's part outside the span, and the 1 nm
    # display's rounding
    t = np.concatenate([np.full(r.dz.size, r.angle) for r in readings])
    dz = np.concatenate([r.dz for r in readings])
    sigma = readings[0].dz_sigma[0]
    assert all(np.all(r.dz_sigma == sigma) for r in readings)
    basis = np.column_stack([np.ones_like(t), 1.0 - np.cos(t), np.sin(t)])
    left = dz - basis @ np.linalg.lstsq(basis, dz, rcond=None)[0]
    rms = math.sqrt(left @ left / t.size)
    normalised = math.sqrt(left @ left / sigma**2 / (t.size - 3))
    heights = identified.detail.check.estimate
    assert heights.residual_rms == pytest.approx(rms, rel=1e-9)
    alone = np.where(np.isclose(t, math.radians(20)), bump, 0.0)
    alone -= basis @ np.linalg.lstsq(basis, alone, rcond=None)[0]
    assert rms == pytest.approx(math.sqrt(alone @ alone / t.size), abs=0.01 * UM)
    note = ("fit_check (heights): the readings do not fit the model: normalised residual "
            f"{normalised:.3g} (about 1 when the model holds every error the readings show "
            f"and sigma is right; above {misfit_limit(t.size - 3):.3g} by chance with "
            f"probability 0.001 at {t.size - 3} degrees of freedom; residual RMS {rms:.3g} "
            "m): an error missing from the "
            "parameters or the prior, or sigma too small; the values may be far off")
    assert identified.notes[0] == note
    assert identified.notes == (
        *(f"fit_check (heights): {n}" for n in heights.notes),
        *(f"fit_check (lateral): {n}" for n in identified.detail.check_lateral.estimate.notes))
    assert not result.identification.notes and "notes" not in result.summary()  # unbumped
    warned = replace(result, identification=identified, identified=identified.parameters)
    ReportFolder(tmp_path).write_result(warned)
    text = (tmp_path / "identified.md").read_text()
    assert ("\nThe identification's fits noted, from the readings alone:\n\n"
            + "\n".join(f"- {n}" for n in identified.notes) + "\n") in text
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["notes"] == list(identified.notes) and summary["notes"][0] == note
    check_summary(summary)
    for bad in ("one string", [note, ""], [note, 3]):
        with pytest.raises(InputError, match="key 'notes'.*list of non-empty strings"):
            check_summary({**summary, "notes": bad})


def test_the_compensated_program_is_the_model_based_one(exact_run):
    """Route 1 (the paper's formulas through map_program) and route 2 (the identified model
    through Machine.axis_values) give the same NC program: every axis on the same 1 nm and
    0.00001-deg steps (both round to the machine's resolution)."""
    result, _ = exact_run
    route = result.evaluation.details["model_based"]
    assert route["max_linear_axis_difference_nm"] == 0.0
    assert route["max_rotary_axis_difference_urad"] == 0.0
    # before rounding, the identified model puts the edge on the path to IK round-off
    assert route["max_position_residual_nm"] < 1e-3


LAB_REFUSAL = ("key 'lab': expected a machinesim.Lab to run on, got NoneType None (make one "
               "with Lab(machine, errors, seed=...))")


@pytest.mark.parametrize(("call", "message"), [
    (lambda: ToolRotationArm().measure(None), LAB_REFUSAL),
    (lambda: ToolRotationArm().evaluate(None, None, {}), LAB_REFUSAL),
    (lambda: ToolRotationArm().identify({}), "key 'measurements': ToolRotationArm.identify "
     "expects the measurements ToolRotationArm.measure(lab) returned (a Calibration), got "
     "dict {}"),
    (lambda: ToolRotationArm().compensate(None), "key 'identified': ToolRotationArm.compensate "
     "expects the Identified ToolRotationArm.identify(measurements) returned, got NoneType "
     "None"),
    (lambda: ToolRotationArm(plan=5), "key 'plan': expected a CalibrationPlan "
     "(machinesim.cam.prisms), e.g. CalibrationPlan(), got int 5"),
    (lambda: ToolRotationArm(pattern="prisms"), "key 'pattern': expected a PrismPattern "
     "(machinesim.cam.prisms), e.g. PrismPattern(), got str 'prisms'"),
    (lambda: procedure.max_capture("x"), "key 'plan': expected a CalibrationPlan "
     "(machinesim.cam.prisms), e.g. CalibrationPlan(), got str 'x'"),
    (lambda: procedure.holder_depth([]), "key 'angles': expected one or more tool angles "
     "(finite numbers, rad), got []"),
    (lambda: procedure.holder_depth([0.0, math.nan]), "key 'angles': expected one or more "
     "tool angles (finite numbers, rad), got [0.0, nan]"),
])
def test_the_python_api_refuses_arguments_of_the_wrong_kind(call, message):
    """Each was a bare AttributeError (or min()'s ValueError) from deep inside; the lab's is
    the check `run` makes (machinesim.experiment.check_lab)."""
    with pytest.raises(InputError) as caught:
        call()
    assert str(caught.value) == message


ARM_PROGRAMS = ("key 'programs': ToolRotationArm.evaluate expects the programs "
                "ToolRotationArm.compensate(identified) returned (a dict of 'pattern_before' "
                "(a Program) and 'pattern_compensated' (a Program)), got ")


def _evaluate(detail, programs):
    """ToolRotationArm's evaluate on a planer lab, ``detail`` in the Identified (None: the
    kind identify gives, its fields empty)."""
    detail = procedure.ArmIdentification(*[None] * 6) if detail is None else detail
    lab = Lab(load_machine("planer_4axis"), ErrorModel(), noise=False)
    return ToolRotationArm().evaluate(lab, Identified({}, detail), programs)


@pytest.mark.parametrize(("call", "message"), [
    (lambda: ToolRotationArm().compensate(Identified({}, {})), "key 'identified': "
     "ToolRotationArm.compensate expects the Identified ToolRotationArm.identify(measurements) "
     "returned, its detail an ArmIdentification, got an Identified whose detail is dict {}"),
    (lambda: _evaluate(5, {}), "key 'identified': ToolRotationArm.evaluate expects the "
     "Identified ToolRotationArm.identify(measurements) returned, its detail an "
     "ArmIdentification, got an Identified whose detail is int 5"),
    (lambda: _evaluate(None, {}), ARM_PROGRAMS + "a dict without 'pattern_before' and "
     "'pattern_compensated'"),
    (lambda: _evaluate(None, None), ARM_PROGRAMS + "NoneType None"),
    (lambda: _evaluate(None, {"pattern_before": ProgramBuilder(1).build(),
                              "pattern_compensated": "G1 Z0"}),
     ARM_PROGRAMS + "a dict whose 'pattern_compensated' is str 'G1 Z0'"),
    (lambda: _evaluate(None, MappingProxyType({"pattern_before": ProgramBuilder(1).build()})),
     ARM_PROGRAMS + "a mappingproxy without 'pattern_compensated'"),
])
def test_each_step_refuses_what_the_step_before_did_not_give(call, message):
    """Another detail was refused in words that named no step; evaluate without the programs
    compensate returned cut the calibration part again and then raised KeyError
    'pattern_before' (None: a TypeError): now each is refused, naming the step, before
    anything is cut (machinesim.procedures.step_inputs). A Result's programs (a
    mappingproxy) are a mapping as good as compensate's dict."""
    with pytest.raises(InputError) as caught:
        call()
    assert str(caught.value) == message
