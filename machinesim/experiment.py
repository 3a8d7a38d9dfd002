"""One experiment shape for every procedure: test pieces, measurements, identification,
compensated programs, evaluation; and `run`, which drives it on a `Lab`.

A procedure (paper 000's tool-rotation arm, 001's 6-axis tool setting, 002's workpiece
setting, ...) is an object with four steps:

``measure(lab)``
    Cut the test pieces on the lab and read them with the lab's instruments. Returns the
    measurements (readings, profiles, fitted features): plain values, no lab inside. A
    staged procedure (one whose later test pieces are cut with what earlier ones found)
    calls its own identification between the cuts, from the readings only.
``identify(measurements)``
    The identification, from the measurements alone: returns an `Identified`.
``compensate(identified)``
    The compensated NC programs, by name (`machinesim.compensation`).
``evaluate(lab, identified, programs)``
    Cut before and after compensation, measure, and return an `Evaluation`: the paper's
    table as `Figure` rows, with parts and programs for the report.

`run(procedure, lab)` calls the four in order and returns a frozen `Result`; only `run`
asks the lab for the truth (`Lab.reveal`), and only to put it beside the identified values
in the report. Nothing a procedure receives can reach it.

What the steps and `run` give back (`Figure`, `Identified`, `Evaluation`, `Result`) is
`machinesim.results`, imported here by the names it had.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from types import MappingProxyType
from typing import Any, Protocol

import numpy as np

from machinesim.errors import AXES
from machinesim.errors.model import _PARAMETER_RE
from machinesim.exceptions import InputError, brief
from machinesim.results import FIGURE_UNITS as FIGURE_UNITS  # re-exported
from machinesim.results import (
    Evaluation,
    Figure,
    Identified,
    Result,
    fit_notes,
    note_kind,
)

__all__ = ["LAB_USES", "Evaluation", "Figure", "Identified", "Procedure", "Result",
           "check_instance", "check_lab", "fit_notes", "note_kind", "run"]

#: What a procedure may read of its lab beyond the machine's error parameters, as its
#: ``lab_uses`` names it, step by step (``"measure"``, ``"evaluate"``): the instruments it
#: reads with at the lab's noise (`machinesim.Lab`'s methods; not one it gives its own
#: ``sigma``), ``"robot"`` where a robot loads its workpiece (the setting is a landing,
#: `machinesim.loading.RobotLoader`) and ``"tool_geometry"`` where it cuts with a tool that
#: has a nose radius for the error model's ``tool_geometry.nose_radius`` to change (a round
#: nose, a ball or flat end mill; a V tool has none and refuses it). A campaign varies these
#: only where the procedure declares them (`machinesim.campaign.CampaignSpec`).
LAB_USES = ("microscope", "white_light_interferometer", "touch_probe", "laser_interferometer",
            "r_test", "robot", "tool_geometry")


class Procedure(Protocol):
    """What `run` needs of a procedure (see the module docstring); ``lab_uses`` (by step,
    names of `LAB_USES`) is what a campaign needs besides."""

    name: str
    paper: str
    lab_uses: Mapping[str, tuple[str, ...]]

    def measure(self, lab) -> Any: ...

    def identify(self, measurements) -> Identified: ...

    def compensate(self, identified: Identified) -> Mapping[str, Any]: ...

    def evaluate(self, lab, identified: Identified, programs: Mapping[str, Any]) -> Evaluation: ...


def check_lab(lab) -> None:
    """Refuse a ``lab`` that is no `machinesim.Lab` (nor a wrapper of one, which has its
    ``reveal``): `run`'s check, and a procedure's ``measure`` and ``evaluate``'s, each an
    `InputError` with key ``lab``."""
    if not callable(getattr(lab, "reveal", None)):  # a Lab, or a wrapper of one
        raise InputError(f"expected a machinesim.Lab to run on, got {type(lab).__name__} "
                         f"{lab!r:.60} (make one with Lab(machine, errors, seed=...))",
                         key="lab")


def check_instance(value, expected: type | tuple[type, ...], key: str, what: str) -> None:
    """Refuse ``value``, the argument ``key``, unless it is an ``expected``: an `InputError`
    naming the argument, the type and value it got and ``what`` was expected (a procedure's
    plan, a tool); what a step takes from the step before is checked by
    `machinesim.procedures.step_inputs`."""
    if not isinstance(value, expected):
        raise InputError(f"expected {what}, got {type(value).__name__} {brief(repr(value))}",
                         key=key)


def _check_as_made(lab) -> None:
    """Refuse a lab that is no longer as it was made: its tool moved by `Lab.adjust_tool`, or
    its servo loops set by `Lab.tune_servo` to others than it was made with (an earlier run's
    doing: paper 004's `evaluate` aligns the tool, then tunes the servo before Case 4).

    `run` compares what a procedure identifies with the errors the lab was made with
    (`Lab.reveal`, which keeps them as injected), and the machine no longer has those when its
    tool was moved: sts_turning run twice on one lab, or any procedure run on a lab moved by
    3 um in Y, identified the tool's Y offset as 0 and reported it against the 3 um injected,
    an error the identification had not made. And a run cuts each case with the loops the lab
    has then: on a tuned lab sts_turning's Case 1 ("before", the control as found) was cut
    with the "after" loops. Moves summing to zero, or loops set back to those it was made
    with (the same, or an equal `PIDServo`), leave the lab as made.

    Nothing else a lab's methods change needs refusing, as each leaves the machine as made
    and a labelled reading as it was: `make_artefacts` draws a label's spheres from streams
    of (seed, label) alone, so a label asked for again, even after another design under it,
    gives the same spheres; an instrument draws its noise and imperfections from
    (seed, kind, label), afresh each time it is handed out, and only an unlabelled one is
    numbered in the order asked for ("microscope/1" on a second run: another draw of the
    same noise, not another machine; the shipped procedures label theirs); `cut` hands back
    a cut made before only for the same errors, servo and inputs (`machinesim.cutting.memo`).
    """
    from machinesim.servo import PIDServo

    changed, why = [], []
    moved = getattr(lab, "reveal_adjustments", None)
    # not callable: no Lab (a stand-in of one), or one without an adjuster or servo loops
    if callable(moved) and np.any(np.asarray(moved(), dtype=float) != 0.0):
        changed.append("tool has been moved by lab.adjust_tool")
        why.append("a run compares what it identifies with the errors the lab was made "
                   "with, which the machine no longer has")
    servo = getattr(lab, "reveal_servo", None)
    if callable(servo):
        now, made = servo(), servo(as_made=True)
        same = now is made or (isinstance(now, PIDServo) and isinstance(made, PIDServo)
                               and now == made)
        if not same:
            changed.append("servo loops have been tuned by lab.tune_servo" if not changed
                           else "its servo loops tuned by lab.tune_servo")
            why.append("a run cuts its cases on the control as the lab was made (a "
                       "'before' case with the loops as found), which it no longer has")
    if changed:
        raise InputError(f"this lab's {' and '.join(changed)} since it was made (an earlier "
                         f"run's doing, e.g. sts_turning's evaluate): {'; and '.join(why)}; "
                         "expected a lab as made: run each procedure on a new "
                         "Lab(machine, errors, seed=..., servo=...) with the same arguments",
                         key="lab")


def run(procedure: Procedure, lab, *, progress: Callable[[str], None] | None = None
        ) -> Result:
    """Drive ``procedure`` on ``lab``: measure, identify, compensate, evaluate.

    Parameters
    ----------
    procedure : Procedure
    lab : machinesim.Lab
        As made: a lab run on before is run on again as it was (the same labels read the
        same noise), but one whose tool `Lab.adjust_tool` moved (paper 004's alignment) or
        whose servo loops `Lab.tune_servo` set to others (paper 004's Case 4) is refused, an
        `InputError`: its machine no longer has the errors the result is compared with, nor
        the control its cases are cut on.
    progress : callable(str), optional
        Told, in one line each, when a step begins and how long it took (for runs of
        minutes: a scenario passes a printer to stderr).

    Returns
    -------
    Result
    """
    clock = {}
    began = time.perf_counter()

    def step(name, function, *args):
        start = time.perf_counter()
        if progress is not None:
            progress(f"{name} ...")
        value = function(*args)
        clock[f"{name}_s"] = time.perf_counter() - start
        if progress is not None:
            progress(f"{name} done in {clock[f'{name}_s']:.1f} s")
        return value

    check_lab(lab)
    _check_as_made(lab)
    if progress is not None and not callable(progress):
        raise InputError(f"Expected progress as a callable(text) or None, got {progress!r:.60}",
                         key="progress")
    if isinstance(procedure, type):  # its methods are callable, unbound: measure(lab) failed
        raise InputError(f"expected a procedure, got the class {procedure.__name__} itself; "
                         f"make one: run({procedure.__name__}(), lab)", key="procedure")
    missing = [name for name in ("measure", "identify", "compensate", "evaluate")
               if not callable(getattr(procedure, name, None))]
    if missing:
        raise InputError(f"expected a procedure (measure, identify, compensate, evaluate), "
                         f"got {type(procedure).__name__} {procedure!r:.60}, without "
                         f"{', '.join(missing)} (e.g. machinesim.procedures."
                         "tool_rotation_arm.ToolRotationArm())", key="procedure")
    measurements = step("measure", procedure.measure, lab)
    identified = step("identify", procedure.identify, measurements)
    if not isinstance(identified, Identified):
        raise InputError(f"{procedure.name}.identify returned {type(identified).__name__}; "
                         "expected an Identified", key="identify")
    _refuse_unknown_parameters(procedure.name, lab.machine, identified.parameters)
    _refuse_values_beyond_any_error(procedure.name, identified.parameters)
    programs = step("compensate", procedure.compensate, identified)
    if not isinstance(programs, Mapping):  # dict(programs) below raised a TypeError
        raise InputError(f"{procedure.name}.compensate returned {type(programs).__name__}; "
                         "expected a mapping of names to programs (an empty dict for none)",
                         key="compensate")
    evaluation = step("evaluate", procedure.evaluate, lab, identified, programs)
    if not isinstance(evaluation, Evaluation):  # a None had raised "AttributeError:
        # 'NoneType' object has no attribute 'figures'", said to be machinesim's fault
        raise InputError(f"{procedure.name}.evaluate returned {type(evaluation).__name__}; "
                         "expected an Evaluation (Evaluation(figures=()) for none)",
                         key="evaluate")
    clock["total_s"] = time.perf_counter() - began
    injected, not_identified, background, polynomials = _truth(lab, identified.parameters)
    return Result(
        paper=procedure.paper, procedure=procedure.name, machine=lab.machine.name,
        seed=lab.seed, noise=lab.noise, injected=MappingProxyType(injected),
        identified=identified.parameters, figures=tuple(evaluation.figures),
        measurements=measurements, identification=identified,
        programs=MappingProxyType(dict(programs)), evaluation=evaluation,
        elapsed_s=MappingProxyType(clock), not_identified=MappingProxyType(not_identified),
        realism=lab.realism.on, background=MappingProxyType(background),
        polynomials=polynomials)


def _refuse_unknown_parameters(name: str, machine, identified: Mapping) -> None:
    """Refuse an identified name that no error of ``machine`` has: ``tool.xx``,
    ``location.B.EX0B`` on a machine without B, ``component.Q.EXX[0]`` had run on, its value
    reported beside an injected 0; a quantity of the procedure's own (``arm.r``) ran to its
    report, whose summary.json holds error parameters only, and was refused there, after
    the whole run. Judged on the machine's axes and the names' form alone, not on the
    truth's tables, which the procedure does not know."""
    import difflib

    known = machine.parameter_names(None)
    for parameter in identified:
        if parameter in known:
            continue
        match = _PARAMETER_RE.fullmatch(parameter) if isinstance(parameter, str) else None
        if match is not None and match["caxis"] in machine.axes:
            continue  # a table's entry or a polynomial's coefficient, of an axis it has
        close = difflib.get_close_matches(str(parameter), known, n=1, cutoff=0.8)
        hint = f" (did you mean {close[0]}?)" if close else ""
        raise InputError(f"{name}.identify named {parameter!r}, no error parameter of "
                         f"{machine.name} (axes {''.join(machine.axes)}){hint}: its value would "
                         "be reported against an injected 0; expected the names "
                         "Machine.parameter_names gives (a quantity of the procedure's own, "
                         "such as an arm's radius, goes in Identified.detail and an "
                         "Evaluation's figures)", key="identify")


def _refuse_values_beyond_any_error(name: str, identified: Mapping) -> None:
    """Refuse an identified offset or angle no error model can hold (`LARGEST_ERROR`: 1 m,
    pi rad, as an errors file is bounded), and warn of one beyond the errors of any machine
    (`unit_slips.LARGEST_LIKELY_ERROR_M`, 10 mm; 10 deg): an identify that reported its
    um as m (``tool.x`` 4.0 for 4 um) ran to a report of 4 m against an injected 4 um. A
    component table's entry or polynomial coefficient (its unit the axis's) is left out."""
    import warnings

    from machinesim.errors._checks import LARGEST_ERROR
    from machinesim.errors.unit_slips import LARGEST_LIKELY_ERROR_M, LARGEST_LIKELY_ERROR_RAD
    from machinesim.exceptions import MachineSimWarning
    from machinesim.identification.identifiability import parameter_unit

    for parameter, (value, _) in identified.items():
        unit = parameter_unit(parameter)
        if unit == "SI" or not np.isfinite(value):
            continue
        length = unit == "m"
        shown = f"{value * 1e3:.6g} mm" if length else f"{np.degrees(value):.6g} deg"
        hint = ("were its values given in um or mm, where SI (m) is expected?" if length
                else "were its values given in urad, mrad or deg, where rad is expected?")
        if abs(value) >= LARGEST_ERROR["length" if length else "angle"]:
            raise InputError(f"{name}.identify gave {parameter} = {value!r} {unit} "
                             f"({shown}), beyond what an error model holds (1 m, 180 deg): "
                             f"{hint}", key="identify")
        if abs(value) >= (LARGEST_LIKELY_ERROR_M if length else LARGEST_LIKELY_ERROR_RAD):
            warnings.warn(f"{name}.identify gave {parameter} = {value!r} {unit} ({shown}), "
                          f"beyond the errors of any machine (10 mm, 10 deg): {hint}",
                          MachineSimWarning, stacklevel=3)


def _truth(lab, identified: Mapping) -> tuple[dict, dict, dict, tuple[str, ...]]:
    """A `Result`'s ``injected``, ``not_identified``, ``background`` and ``polynomials``,
    from the lab's truth, after the procedure has finished.

    Each identified parameter takes the value the machine had (`Lab.reveal`: the injected
    errors plus the machine's background), what its identification is compared with; every
    other name is the injected model's own (``reveal(background=False)``), as its file wrote
    it. The sum of a polynomial and a table is a table of up to thousands of entries
    (`machinesim.background.add_errors`), whose ``component.X.EYX[2]`` is an entry where the
    injected model's is a coefficient: neither its entries nor the background's are listed,
    and an identified component parameter whose name means one thing in the truth and
    another in the injected or background model has no true value here (the report reads
    NaN) rather than the wrong one. The background is summarised: its file and how many of
    its parameters are non-zero. ``injected`` is in `ErrorModel.parameters`'s order, an
    identified name the injected model does not hold (a location error it has none of) too.
    """
    truth, own, extra = lab.reveal(), lab.reveal(background=False), lab.reveal_background()
    true, written = truth.parameters(), own.parameters()
    injected = {}
    for name in _in_parameter_order({**dict.fromkeys(written), **dict.fromkeys(identified)}):
        if name in identified:
            if _one_meaning(name, truth, (own, extra)):
                injected[name] = true.get(name, 0.0)
        elif written[name] != 0.0:
            injected[name] = written[name]
    not_identified = {name: value for name, value in written.items()
                      if value != 0.0 and name not in identified}
    count = sum(value != 0.0 for value in extra.parameters().values())
    background = {} if count == 0 else {"file": _file(extra.source), "nonzero_count": count}
    polynomials = tuple(f"component.{axis}.{symbol}" for axis, table in own.component.items()
                        for symbol, error in table.items() if error.kind == "poly")
    return injected, not_identified, background, polynomials


#: `ErrorModel.parameters`'s order of the tool's and the workpiece's parameters.
_TOOL_ORDER = ("x", "y", "z", "rx", "ry", "rz")
_WORKPIECE_ORDER = ("x", "y", "z", "alpha", "beta", "gamma")


def _in_parameter_order(names) -> list[str]:
    """``names`` in `ErrorModel.parameters`'s order: tool, tool_geometry, workpiece,
    location, component, axes and symbols in X Y Z A B C order and a component's k rising;
    a name of no error-model form after them, in the order given."""

    def place(name: str) -> tuple:
        match = _PARAMETER_RE.fullmatch(name)
        if match is None:
            return (5,)
        if match["tool"]:
            return (0, _TOOL_ORDER.index(match["tool"]))
        if match["geometry"]:
            return (1,)
        if match["workpiece"]:
            return (2, _WORKPIECE_ORDER.index(match["workpiece"]))
        axis, symbol = (match["laxis"], match["lsym"]) if match["laxis"] else (
            match["caxis"], match["csym"])
        k = int(match["k"]) if match["k"] else 0
        return (3 if match["laxis"] else 4, AXES.find(axis), AXES.find(symbol[1:2] or "?"),
                symbol, k)

    return sorted(names, key=place)


def _one_meaning(name: str, truth, models) -> bool:
    """Whether the parameter ``name`` means in ``truth`` what it means in each of ``models``
    that holds it: a component parameter is a table entry or a polynomial coefficient, and
    entry k of a table on other positions is another error."""
    if not name.startswith("component."):
        return True
    axis, rest = name.removeprefix("component.").split(".", 1)
    symbol = rest.split("[", 1)[0]
    held = truth.component.get(axis, {}).get(symbol)
    for model in models:
        error = model.component.get(axis, {}).get(symbol)
        if error is None:
            continue
        if held is None or error.kind != held.kind or (
                error.kind == "table" and not np.array_equal(error.positions, held.positions)):
            return False
    return True


def _file(source: str | None) -> str | None:
    """A background's file as summary.json names it: a shipped one relative to the project
    (``models/errors/background_<machine>.toml``), another as given, None for a model given
    as such."""
    if source is None:
        return None
    from pathlib import Path

    from machinesim.machines import models_dir

    path, shipped = Path(source).resolve(), models_dir().resolve()
    if path.is_relative_to(shipped):
        return f"models/{path.relative_to(shipped).as_posix()}"
    return source
