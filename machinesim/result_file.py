"""A run saved to a file and read back: `save_result`, `load_result`, and `check_result`,
the checks a `machinesim.experiment.Result` passes when made and when loaded.

A result pickles (docs/reports.md): its fields and no lab. A pickle loaded back had skipped
every constructor's checks, so a file cut short, written by another version of machinesim
(a field missing), or edited (a figure in a unit no figure has, a seed of NaN, text where a
number stands) was accepted and failed later, in a report, or printed nonsense. Now the
copy is checked as the original was (`machinesim._frozen`: the fields, then each class's
``__post_init__``), and `load_result` names the file with the field.

A pickle runs code of the classes it names as it loads: these checks catch damage and
version skew, not malice. Load only results you (or your own runs) saved.
"""

from __future__ import annotations

import math
import numbers
import pickle
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from machinesim._io import check_readable_file, write_atomic
from machinesim.exceptions import FileError, InputError, brief
from machinesim.experiment import Evaluation, Figure, Identified, Result

__all__ = ["check_result", "load_result", "save_result"]


def save_result(result: Result, path) -> Path:
    """Write ``result`` to ``path`` (a pickle), whole or not at all; return the path."""
    if not isinstance(result, Result):
        raise InputError(f"Expected a machinesim.experiment.Result (experiment.run(procedure, "
                         f"lab)), got {type(result).__name__}", key="result")
    write_atomic(path, pickle.dumps(result, protocol=pickle.HIGHEST_PROTOCOL))
    return Path(path)


def load_result(path) -> Result:
    """The `Result` `save_result` wrote to ``path``, checked as a made one.

    Raises
    ------
    InputError
        Naming the file, and the field where one is at fault: a file that cannot be read,
        is cut short or is no pickle, holds no Result, or a Result (or a figure, its
        identification) whose field is missing, unknown or fails the constructor's check.
    """
    path = check_readable_file(path, "saved result")
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise FileError(f"cannot read the saved result: {exc.strerror or exc}",
                        source=str(path)) from None
    try:
        result = pickle.loads(raw)
    except InputError as error:  # a field refused by its class's checks
        raise InputError(f"the saved result: {error.message}", source=str(path),
                         key=error.key) from None
    except (pickle.UnpicklingError, EOFError, ValueError, TypeError, AttributeError,
            ImportError, IndexError, KeyError, MemoryError, OverflowError) as error:
        raise InputError(f"not a whole saved result ({type(error).__name__}: "
                         f"{brief(str(error))}): cut short, damaged, or written by another "
                         "version of machinesim; expected what save_result writes",
                         source=str(path)) from None
    if not isinstance(result, Result):
        raise InputError(f"holds a {type(result).__name__}, not a machinesim.experiment."
                         "Result; expected what save_result writes", source=str(path))
    return result


def check_result(result: Result) -> None:
    """Refuse a `Result` whose fields are not what `machinesim.experiment.run` makes: an
    `InputError` naming the field (``Result.__post_init__``, so a loaded copy too)."""

    def refuse(key: str, expected: str) -> None:
        value = getattr(result, key)
        raise InputError(f"Result.{key}: expected {expected}, got {type(value).__name__} "
                         f"{brief(repr(value))}", key=key)

    for key in ("paper", "procedure", "machine"):
        if not isinstance(getattr(result, key), str) or not getattr(result, key):
            refuse(key, "a non-empty string")
    seed = result.seed
    if not (isinstance(seed, np.random.SeedSequence) or (
            isinstance(seed, int | np.integer) and not isinstance(seed, bool) and seed >= 0)):
        refuse("seed", "a non-negative int or a numpy SeedSequence")
    if not isinstance(result.noise, bool):
        refuse("noise", "True or False")
    for key in ("injected", "not_identified"):
        values = getattr(result, key)
        if not isinstance(values, Mapping) or not all(
                isinstance(k, str) and _finite(v) for k, v in values.items()):
            refuse(key, "a mapping of parameter names to finite numbers (SI)")
    identified = result.identified
    if not isinstance(identified, Mapping) or not all(
            isinstance(k, str) and isinstance(v, tuple) and len(v) == 2 and _finite(v[0])
            and _float(v[1]) is not None and not v[1] < 0.0 for k, v in identified.items()):
        refuse("identified", "a mapping of parameter names to (value, std): a finite number "
                             "and a number >= 0 or NaN (SI)")
    elapsed = result.elapsed_s
    if not isinstance(elapsed, Mapping) or not all(
            isinstance(k, str) and _finite(v) and v >= 0.0 for k, v in elapsed.items()):
        refuse("elapsed_s", "a mapping of step names to times >= 0 (s)")
    if not isinstance(result.figures, tuple) or not all(
            isinstance(f, Figure) for f in result.figures):
        refuse("figures", "a tuple of Figure")
    seen: dict[str, int] = {}
    for i, figure in enumerate(result.figures):
        j = seen.setdefault(figure.name, i)
        if j != i:  # a report, a campaign and Result.figure read a figure by its name
            first = result.figures[j]
            raise InputError(f"Result.figures: figures {j} and {i} are both named "
                             f"{figure.name!r} ({first.unit}, {figure.unit}); expected each "
                             "figure once, under a name of its own: a report, a campaign and "
                             "Result.figure read a figure by its name", key="figures")
    if not isinstance(result.identification, Identified):
        refuse("identification", "an Identified")
    if not isinstance(result.evaluation, Evaluation):
        refuse("evaluation", "an Evaluation")
    for key in ("programs", "background"):
        if not isinstance(getattr(result, key), Mapping):
            refuse(key, "a mapping")
    for key in ("realism", "polynomials"):
        values = getattr(result, key)
        if not isinstance(values, tuple) or not all(isinstance(v, str) for v in values):
            refuse(key, "a tuple of names")


def _float(value) -> float | None:
    """``value`` as a float: a real number (no bool) within float64's range, else None (an
    int of 10**400 is a number float() refuses: 'int too large to convert')."""
    if not isinstance(value, numbers.Real) or isinstance(value, bool | np.bool_):
        return None
    try:
        return float(value)
    except OverflowError:
        return None


def _finite(value) -> bool:
    number = _float(value)
    return number is not None and math.isfinite(number)
