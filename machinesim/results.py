"""What a procedure's steps give back and what `machinesim.experiment.run` returns: the
paper's table as `Figure` rows, the `Identified` parameters (with the notes of the fits
that found them, `fit_notes`), the `Evaluation` of the test pieces before and after
compensation, and the frozen `Result` of one run with its summary.json (docs/reports.md).

Each checks what it is made with (a figure's unit and numbers, an identification's
parameters as (value, std)) and pickles as it was made (`machinesim._frozen`); a `Result`
is checked as `machinesim.result_file.check_result` reads one. The experiment's shape and
its driver are `machinesim.experiment`.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np

from machinesim._frozen import reduce_frozen
from machinesim.exceptions import InputError, brief

__all__ = ["FIGURE_UNITS", "Evaluation", "Figure", "Identified", "Result", "fit_notes",
           "note_kind"]

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
    if isinstance(value, str | bytes | bool | np.bool_):  # "1.23" was read as 1.23, True as 1
        raise InputError(f"Expected {name} as a number or None, got {brief(repr(value))}",
                         key=name)
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
        if out[str(name)][1] < 0.0:  # a spread: summary.json and a campaign's trial files
            # refuse a negative one as they are read, after the run that made it had ended
            raise InputError(f"Expected {what}[{name!r}]'s std >= 0 (or NaN: none stated), "
                             f"got {brief(repr(value))}", key=name)
    return MappingProxyType(out)


@dataclass(frozen=True)
class Identified:
    """What a procedure identified.

    Attributes
    ----------
    parameters : Mapping[str, (float, float)]
        Error parameter name (as `Machine.parameter_names` spells it) -> (value, std), SI
        (m, rad); std >= 0, NaN where the procedure gives none. A bare number means std
        unknown.
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

    def __repr__(self) -> str:
        detail = "" if self.detail is None else f"; detail {type(self.detail).__name__}"
        return (f"Identified({len(self.parameters)} parameters: "
                f"{_listed(self.parameters)}; {_count(self.notes, 'note')}{detail})")


def _count(items, what: str) -> str:
    return f"{len(items)} {what}{'' if len(items) == 1 else 's'}"


def _listed(parameters: Mapping[str, tuple[float, float]], polynomials=()) -> str:
    """``name = value unit +- std unit`` for a repr (identifiability.listed): a component
    table's entry in its symbol's unit, a polynomial's coefficient (``polynomials``) 'SI'."""
    from machinesim.identification.identifiability import listed, parameter_unit

    def unit_of(name: str) -> str:
        if not name.startswith("component."):
            return parameter_unit(name)
        error, symbol = name.split("[")[0], name.split(".")[2]
        if error in polynomials or len(symbol) < 2:
            return "SI"
        return "m" if symbol[1] in "XYZ" else "rad"

    names = list(parameters)
    pairs = np.array([parameters[n] for n in names], dtype=float).reshape(-1, 2)
    return (listed(names, pairs[:, 0], pairs[:, 1], unit_of, "(no std)") if names
            else "none")


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
    if sigma_leaves_out and estimate.misfit:
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


@dataclass(frozen=True, repr=False)
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

    def __repr__(self) -> str:
        def shown(value) -> str:
            return "none" if value is None else f"{value:.4g}"

        figures = ", ".join(f"{f.name} {shown(f.before)} -> {shown(f.after)} {f.unit}"
                            for f in self.figures)
        seed = self.seed  # a campaign trial's SeedSequence: its entropy and spawn key
        if isinstance(seed, np.random.SeedSequence):
            seed = f"{seed.entropy} spawn {tuple(seed.spawn_key)}"
        return (f"Result({self.procedure} ({self.paper}) on {self.machine}, seed "
                f"{seed}, noise {'on' if self.noise else 'off'}, realism "
                f"{_preset(self.realism)}; identified "
                f"{_listed(self.identified, self.polynomials)}; figures before -> after: "
                f"{figures or 'none'}; {_count(self.notes, 'note')})")

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
