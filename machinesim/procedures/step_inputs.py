"""What a procedure's steps take from the step before, checked at the door.

`machinesim.experiment.run` hands ``identify`` what ``measure`` returned, ``compensate`` and
``evaluate`` what ``identify`` returned and ``evaluate`` what ``compensate`` returned; a
caller of the steps one by one may hand them anything. Each step refuses, before it
reads, what the step before it would not have given (a dict for the measurements, another
procedure's `Identified`, programs without the ones it cuts): an `InputError` keyed by the
argument, naming the step, what it expected and what it got, where a KeyError or an
AttributeError came from deep inside it before. What the step before gives passes
untouched (the checks read types and keys, never values).

A shape is a type (the value is one of it) or a mapping of key -> type (the value a dict,
or another mapping such as a `machinesim.experiment.Result`'s ``programs``, holding each
key, its value of that type; ``object``: any value).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

from machinesim.exceptions import InputError, brief
from machinesim.experiment import Identified
from machinesim.nc import Program

__all__ = ["check_identified", "check_measurements", "check_programs", "refuse"]

Shape = type | Mapping[str, type]


def refuse(procedure: str, step: str, key: str, expected: str, got: str):
    """Raise the `InputError` of ``procedure.step`` given ``key`` it did not expect:
    ``"{procedure}.{step} expects {expected}, got {got}"``, keyed ``key``."""
    raise InputError(f"{procedure}.{step} expects {expected}, got {got}", key=key)


def check_measurements(measurements, procedure: str, shape: Shape) -> None:
    """Refuse, in ``procedure.identify``, anything but what its ``measure`` returns (key
    ``measurements``)."""
    wrong = _mismatch(measurements, shape)
    if wrong is not None:
        refuse(procedure, "identify", "measurements",
               f"the measurements {procedure}.measure(lab) returned ({_describe(shape)})",
               wrong)


def check_identified(identified, procedure: str, step: str, detail: Shape) -> None:
    """Refuse, in ``procedure.step`` (``compensate``, ``evaluate``), anything but the
    `Identified` its ``identify`` returns, whose detail has ``detail``'s shape (key
    ``identified``)."""
    expected = f"the Identified {procedure}.identify(measurements) returned"
    if not isinstance(identified, Identified):
        refuse(procedure, step, "identified", expected, _value(identified))
    wrong = _mismatch(identified.detail, detail)
    if wrong is not None:
        refuse(procedure, step, "identified", f"{expected}, its detail {_describe(detail)}",
               f"an Identified whose detail is {wrong}")


def check_programs(programs, procedure: str, names: Iterable[str]) -> None:
    """Refuse, in ``procedure.evaluate``, programs without the ones it cuts: a dict holding
    a `machinesim.nc.Program` under each of ``names`` (key ``programs``)."""
    shape = dict.fromkeys(names, Program)
    wrong = _mismatch(programs, shape)
    if wrong is not None:
        refuse(procedure, "evaluate", "programs",
               f"the programs {procedure}.compensate(identified) returned "
               f"({_describe(shape)})", wrong)


def _mismatch(value, shape: Shape) -> str | None:
    """What ``value`` is, where it does not have ``shape``; None where it does."""
    if isinstance(shape, type):
        return None if isinstance(value, shape) else _value(value)
    if not isinstance(value, Mapping):
        return _value(value)
    kind_of = "a dict" if isinstance(value, dict) else _article(type(value).__name__)
    missing = [repr(key) for key in shape if key not in value]
    if missing:
        return f"{kind_of} without {_listed(missing)}"
    for key, kind in shape.items():
        if not isinstance(value[key], kind):
            return f"{kind_of} whose {key!r} is {_value(value[key])}"
    return None


def _describe(shape: Shape) -> str:
    """``shape`` in words: "a Calibration", "a dict of 'xy' (an XYPlaneMeasurements) and
    'machine'"."""
    if isinstance(shape, type):
        return _article(shape.__name__)
    return "a dict of " + _listed([repr(key) if kind is object
                                   else f"{key!r} ({_article(kind.__name__)})"
                                   for key, kind in shape.items()])


def _article(name: str) -> str:
    return f"{'an' if name[0] in 'AEIOUX' else 'a'} {name}"


def _listed(words: list[str]) -> str:
    return words[0] if len(words) == 1 else f"{', '.join(words[:-1])} and {words[-1]}"


def _value(value) -> str:
    return f"{type(value).__name__} {brief(repr(value))}"
