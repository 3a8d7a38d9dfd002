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
"""

from __future__ import annotations

import math
import re
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, Protocol

import numpy as np

from machinesim._frozen import reduce_frozen
from machinesim.errors import AXES
from machinesim.errors.model import _PARAMETER_RE
from machinesim.exceptions import InputError, brief
from machinesim.identification.fit import MODEL_MISFIT

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

#: Units a figure may be reported in (the report's unit table; see docs/reports.md).
FIGURE_UNITS = ("m", "mm", "um", "nm", "rad", "mrad", "urad", "deg", "arcsec", "s", "min",
                "h", "percent", "count", "ratio")


def _number(value, name: str) -> float | None:
    """A figure's value: a float, None for None or NaN (not measured); an infinity refused.

    An infinite figure was kept as None too, and written to summary.json as null, which the
    schema reads as "not measured": a reading that diverged (a division by zero) passed as one
    not taken. JSON has no infinity, and no length, angle, time or share is one: it is refused
    here, naming the figure, before any report is written."""
    if value is None:
        return None
    try:
        number = float(value)
    except (TypeError, ValueError, OverflowError) as error:  # 10**400: beyond float64
        raise InputError(f"Expected {name} as a number or None, got {brief(repr(value))}",
                         key=name) from error
    if math.isinf(number):
        raise InputError(f"figure {name}: {number!r}; expected a finite number, or None (NaN) "
                         "where nothing was measured: an infinite figure is no measurement "
                         "(a reading or a ratio that divided by zero?), and the report has "
                         "no way to write it but as not measured", key=name)
    return None if math.isnan(number) else number


@dataclass(frozen=True)
class Figure:
    """One row of a paper's table: a figure before and after compensation.

    Attributes
    ----------
    name : str
        What is measured, as a key (``"a_dx"``, ``"edge_distance_L1_L5"``).
    unit : str
        Unit of the four values, one of `FIGURE_UNITS`.
    before, after : float or None
        The simulated values; None where not measured (or not measurable): NaN is taken
        as None, an infinity refused (`_number`).
    paper_before, paper_after : float or None
        The paper's values; None where the paper gives none.
    note : str
        Optional: what a reader must know (``"paper: > 50"``).
    after_std : float or None
        Optional: the standard uncertainty of ``after`` over labs with the same stated
        instruments (another lab, or this one another day, lands this far from ``after``,
        one standard deviation): how close to a paper's "after" a faithful replay can be
        expected to come. None where the procedure does not give it.
    """

    name: str
    unit: str
    before: float | None
    after: float | None
    paper_before: float | None = None
    paper_after: float | None = None
    note: str = ""
    after_std: float | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise InputError(f"Expected a figure name, got {self.name!r}", key="name")
        if self.unit not in FIGURE_UNITS:
            raise InputError(f"figure {self.name!r}: unit {self.unit!r}; expected one of "
                             f"{', '.join(FIGURE_UNITS)}", key="unit")
        for name in ("before", "after", "paper_before", "paper_after", "after_std"):
            object.__setattr__(self, name, _number(getattr(self, name), f"{self.name}.{name}"))
        if self.after_std is not None and self.after_std < 0.0:
            raise InputError(f"figure {self.name!r}: after_std {self.after_std!r}; expected "
                             "a standard uncertainty >= 0", key="after_std")

    __reduce__ = reduce_frozen  # a loaded copy is checked as a made one (`_frozen`)

    def as_dict(self) -> dict:
        """The figure as summary.json holds it."""
        out = {"name": self.name, "unit": self.unit, "before": self.before,
               "after": self.after, "paper_before": self.paper_before,
               "paper_after": self.paper_after}
        if self.note:
            out["note"] = self.note
        if self.after_std is not None:
            out["after_std"] = self.after_std
        return out


def _parameters(values: Mapping, what: str) -> Mapping[str, tuple[float, float]]:
    if not isinstance(values, Mapping):
        raise InputError(f"Expected {what} as a mapping name -> (value, std), got "
                         f"{type(values).__name__} {brief(repr(values))}", key=what)
    out = {}
    for name, value in values.items():
        pair = value if isinstance(value, tuple | list) else (value, math.nan)
        if len(pair) != 2 or any(isinstance(v, str | bytes | bool) for v in pair):
            raise InputError(f"Expected {what}[{name!r}] as (value, std), got {value!r}",
                             key=name)
        try:
            out[str(name)] = (float(pair[0]), float(pair[1]))
        except (TypeError, ValueError, OverflowError):  # 10**400: beyond float64
            raise InputError(f"Expected {what}[{name!r}] as numbers (value, std), got "
                             f"{brief(repr(value))}", key=name) from None
    return MappingProxyType(out)


@dataclass(frozen=True)
class Identified:
    """What a procedure identified.

    Attributes
    ----------
    parameters : Mapping[str, (float, float)]
        Error parameter name (as `Machine.parameter_names` spells it) -> (value, std), SI
        (m, rad); std NaN where the procedure gives none. A bare number means std unknown.
    detail : Any
        The procedure's own result (its paper's quantities), for `compensate` and reports.
    notes : tuple of str
        What the identification's fits said a reader should know before trusting the values
        (`machinesim.identification.fit.Estimate.notes`: a combination the readings cannot
        see, two parameters they barely tell apart, readings that do not fit the model,
        lengths given in um or mm), each led by the fit it comes from (`fit_notes`); from
        the measurements alone, as the rest. identified.md lists them under its table and
        summary.json under ``notes``.
    """

    parameters: Mapping[str, tuple[float, float]]
    detail: Any = None
    notes: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "parameters", _parameters(self.parameters, "parameters"))
        notes = self.notes
        if isinstance(notes, str) or not isinstance(notes, tuple | list) or not all(
                isinstance(n, str) and n.strip() for n in notes):
            raise InputError(f"Expected Identified's notes as a tuple of non-empty strings, "
                             f"got {brief(repr(notes))}", key="notes")
        object.__setattr__(self, "notes", tuple(notes))

    __reduce__ = reduce_frozen  # pickles (parameters is read-only: a mappingproxy)


#: A number in a note (a residual, a correlation, a std), not part of a name (``EX0C``,
#: ``EAC[3]``): `note_kind` leaves it out.
_NUMBER = re.compile(r"(?<![\w.\[])[-+]?\d+(?:\.\d*)?(?:e[-+]?\d+)?(?![\w\]])")


def note_kind(note: str) -> str:
    """``note`` with its numbers as ``#``: the same note of two trials (``the readings do not
    fit the model: normalised residual 25.7 ...`` and ``... 31.2 ...``) is one kind."""
    return _NUMBER.sub("#", note)


def fit_notes(fit: str, estimate, *, sigma_leaves_out: str | None = None) -> tuple[str, ...]:
    """The notes of ``estimate`` (a `machinesim.identification.fit.Estimate`), each led by
    ``fit``, the fit that made it (``"fit_check (heights)"``): for an `Identified`'s
    ``notes``.

    ``sigma_leaves_out`` names the errors the procedure's readings carry as it states them
    (an artefact's made scatter, a stage's registration) that the fit's sigma leaves out
    and the procedure's std adds: when the readings do not fit the model, a note says so,
    so that the fit's misfit is read beside what the procedure knows of its readings.
    """
    notes = tuple(f"{fit}: {note}" for note in estimate.notes)
    if sigma_leaves_out and estimate.normalised_residual_rms > MODEL_MISFIT:
        notes += (f"{fit}: its sigma leaves out {sigma_leaves_out}, which may account for "
                  "that misfit; the std this report gives includes it",)
    return notes


@dataclass(frozen=True)
class Evaluation:
    """The test pieces before and after compensation, as measured.

    Attributes
    ----------
    figures : tuple of Figure
        One per row of the paper's table.
    details : Mapping
        Further results for summary.json, every numeric key with its unit suffix.
    parts, programs : Mapping[str, object]
        Parts (`machinesim.workpiece.Part`) and NC programs to write into the report.
    """

    figures: tuple[Figure, ...]
    details: Mapping = field(default_factory=dict)
    parts: Mapping = field(default_factory=dict)
    programs: Mapping = field(default_factory=dict)

    __reduce__ = reduce_frozen  # pickles, a procedure's read-only mappings too


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


@dataclass(frozen=True)
class Result:
    """One run of a procedure on a lab.

    Attributes
    ----------
    paper, procedure, machine : str
    seed : int
    noise : bool
    realism : tuple of str
        The lab's realism switches that were on (`machinesim.realism.Realism.on`).
    injected : Mapping[str, float]
        What was injected, SI: each identified parameter with the value the machine had (the
        injected errors plus the machine's background, what the identification is compared
        with; left out for a component parameter whose name means another table entry or
        coefficient there than in the injected model), and each other non-zero parameter of
        the injected model as written. The background's own parameters are not listed
        (``background``). In `ErrorModel.parameters`'s order.
    identified : Mapping[str, (float, float)]
        (value, std), SI.
    figures : tuple of Figure
    measurements : Any
        What `measure` returned.
    identification : Identified
    programs : Mapping[str, Program]
        The compensated programs.
    evaluation : Evaluation
    elapsed_s : Mapping[str, float]
        Wall time of each step and in all, s.
    not_identified : Mapping[str, float]
        Parameters injected into the lab (non-zero; the background apart) that are not
        among the identified ones, with their injected values (SI): outside the procedure's
        model, or measured otherwise (a compensation table) without being named.
    background : Mapping
        Empty without background errors; else ``file``, the background's error model
        (``models/errors/background_<machine>.toml`` for the shipped one, None for a model
        given as such), and ``nonzero_count``, how many of its parameters are non-zero.
    polynomials : tuple of str
        The component errors the injected model gives as polynomials (``component.X.EYX``):
        their parameters in ``injected`` and ``not_identified`` are coefficients, the other
        component parameters table entries.
    """

    paper: str
    procedure: str
    machine: str
    seed: int
    noise: bool
    injected: Mapping[str, float]
    identified: Mapping[str, tuple[float, float]]
    figures: tuple[Figure, ...]
    measurements: Any
    identification: Identified
    programs: Mapping[str, Any]
    evaluation: Evaluation
    elapsed_s: Mapping[str, float]
    not_identified: Mapping[str, float] = field(default_factory=dict)
    realism: tuple[str, ...] = ()
    background: Mapping = field(default_factory=dict)
    polynomials: tuple[str, ...] = ()

    #: A result pickles (saved, or sent to a Dask worker and back), its read-only mappings
    #: as dicts: the pickle holds these fields and nothing more, no lab. A loaded copy is
    #: checked as a made one (`machinesim.result_file.check_result`).
    __reduce__ = reduce_frozen

    def __post_init__(self) -> None:
        from machinesim.result_file import check_result

        check_result(self)

    @property
    def notes(self) -> tuple[str, ...]:
        """The identification's notes (`Identified.notes`; none from an ``identification``
        that is no `Identified`)."""
        return tuple(getattr(self.identification, "notes", ()))

    def figure(self, name: str) -> Figure:
        """The figure called ``name``."""
        for f in self.figures:
            if f.name == name:
                return f
        raise InputError(f"no figure {name!r}; this result has "
                         f"{', '.join(f.name for f in self.figures)}", key="name")

    def summary(self) -> dict:
        """summary.json of this result, in the schema of docs/reports.md."""
        seed = self.seed  # a SeedSequence (a campaign's trial): its entropy and spawn key
        spawned = isinstance(seed, np.random.SeedSequence)
        return {
            "paper": self.paper, "procedure": self.procedure, "machine": self.machine,
            "seed": seed.entropy if spawned else seed, "noise": self.noise,
            **({"spawn_key": list(seed.spawn_key)} if spawned and seed.spawn_key else {}),
            "realism": {"preset": _preset(self.realism), "on": list(self.realism)},
            "injected": dict(self.injected),
            "identified": {name: {"value": v, "std": s}
                           for name, (v, s) in self.identified.items()},
            "figures": [f.as_dict() for f in self.figures],
            "details": dict(self.evaluation.details),
            "elapsed_s": dict(self.elapsed_s),
            **({"not_identified": list(self.not_identified)} if self.not_identified else {}),
            **({"background": dict(self.background)} if self.background else {}),
            **({"notes": list(notes)} if (notes := self.notes) else {}),
        }


def _preset(on: tuple[str, ...]) -> str:
    """The name of the realism preset with these switches on, or the switches joined by +."""
    from machinesim.realism import Realism

    return str(Realism.with_only(*on))


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
    programs = step("compensate", procedure.compensate, identified)
    evaluation = step("evaluate", procedure.evaluate, lab, identified, programs)
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
