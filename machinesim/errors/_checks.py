"""Validation helpers shared by the error-model values and their TOML reader.

Each raises `ErrorModelError` naming the source, the key, the value that arrived and what
was expected; the number checks return float64 copies.
"""

from __future__ import annotations

import math
import re
from decimal import Decimal
from typing import Any

import numpy as np

from machinesim.arrays import beyond_float64
from machinesim.exceptions import ErrorModelError
from machinesim.units import ANGLE, FACTORS, LENGTH, angle_text, length_text

#: Axis letters, in the canonical order of sections and symbols.
AXES = "XYZABC"
#: Linear axes (positions and translation symbols in lengths); the others are rotary.
LINEAR_AXES = "XYZ"

_SYMBOL_RE = re.compile(r"E(.)(0?)(.)")


def _fail(message: str, source: str | None, key: str | None) -> ErrorModelError:
    return ErrorModelError(message, source=source, key=key)


def _describe(value: Any) -> str:
    text = repr(value.tolist() if isinstance(value, np.ndarray) else value)
    return f"{text if len(text) <= 80 else text[:77] + '...'} ({type(value).__name__})"


def _number(value: Any, source: str | None, key: str | None) -> float:
    """A finite float from an int or float (bools and strings refused)."""
    if isinstance(value, bool | np.bool_) or not isinstance(
        value, int | float | np.integer | np.floating
    ):
        raise _fail(f"expected a number, got {_describe(value)}", source, key)
    if (huge := beyond_float64(value)) is not None:
        raise _fail(f"expected a finite number, got {huge}", source, key)
    number = float(value)
    if not math.isfinite(number):
        raise _fail(f"expected a finite number, got {number}", source, key)
    return number


def _numbers(value: Any, source: str | None, key: str | None, size: int | None = None):
    """A read-only float64 copy of a 1-D list of finite numbers (non-empty, or `size` long)."""
    if isinstance(value, np.ndarray) and value.ndim == 1 and value.dtype.kind in "iuf":
        array = value.astype(np.float64)
        if not np.all(np.isfinite(array)):
            bad = array[~np.isfinite(array)][0]
            raise _fail(f"expected finite numbers, got {bad} in {_describe(value)}", source, key)
    elif isinstance(value, list | tuple):
        array = np.array([_number(item, source, key) for item in value], dtype=np.float64)
    else:
        raise _fail(f"expected a list of numbers, got {_describe(value)}", source, key)
    if size is not None and array.size != size:
        message = f"expected {size} values, got {array.size}: {_describe(value)}"
        raise _fail(message, source, key)
    if array.size == 0:
        raise _fail("expected at least one value, got an empty list", source, key)
    array.flags.writeable = False
    return array


#: Largest error an error model takes, in SI, by quantity: an angle beyond half a turn is a
#: different setting, not an error of one; a length beyond a metre is beyond any machine here.
LARGEST_ERROR = {"angle": math.pi, "length": 1.0}
#: Relative slack on `LARGEST_ERROR`: a value at the bound, written by `ErrorModel.to_toml`
#: in another unit and read back, carries two roundings (a few 1e-16): -180 deg written as
#: -3141592.653589793 urad read back 4e-16 beyond pi and was refused.
_BOUND_SLACK = 1e-15


def _shown(value: float, unit: str) -> str:
    """A value (SI: m or rad) as a message shows it: in ``unit``, the unit its key was
    written in (``um``, ``deg``), or, where that is SI itself (the Python API's values, a
    key in ``_m``), in mm or deg with the SI value beside it, as every other message of
    machinesim gives it (`machinesim.units.length_text`, `angle_text`)."""
    if unit == "m":
        return length_text(value)
    if unit == "rad":
        return angle_text(value)
    return f"{value / FACTORS[unit]:g} {unit}"


def _in_unit(value: float, factor: float) -> str:
    """``value`` (SI) over ``factor`` (SI per unit), as ``:g`` shows it, also where the
    quotient overflows float64 (9.6e307 m is 9.6e313 um): worked out in decimal then."""
    with np.errstate(over="ignore"):
        quotient = np.float64(value) / factor
    if math.isfinite(quotient) or not math.isfinite(value):
        return f"{quotient:g}"
    return format(Decimal(value) / Decimal(factor), ".6g")


def _limit(quantity: str, unit: str, factor: float) -> str:
    """`LARGEST_ERROR` of `quantity` in `unit` (`factor` SI per unit), and in SI beside it:
    ``1e+06 um (1 m)``; for an SI `unit`, in mm or deg first (`_shown`)."""
    largest = LARGEST_ERROR[quantity]
    si = "rad" if quantity == "angle" else "m"
    return _shown(largest, unit) if unit == si else (
        f"{largest / factor:g} {unit} ({largest:g} {si})")


def _check_size(values, quantity: str, unit: str, factor: float, source: str | None,
                key: str | None) -> None:
    """Refuse an error value (SI, scalar or array) larger than `LARGEST_ERROR` for its quantity."""
    worst = float(np.max(np.abs(values)))
    if worst > LARGEST_ERROR[quantity] * (1.0 + _BOUND_SLACK):
        raise _fail(f"{_shown(worst, unit)} is no {quantity} error: expected at most "
                    f"{_limit(quantity, unit, factor)} either way", source, key)


def _check_si(values, quantity: str, key: str | None) -> None:
    """`_check_size` for values already in SI (m or rad)."""
    _check_size(values, quantity, "rad" if quantity == "angle" else "m", 1.0, None, key)


def _check_increasing(positions: np.ndarray, source: str | None, key: str | None,
                      unit: str) -> None:
    """Refuse positions that do not increase, naming them in ``unit``, the unit they were
    written in (``mm`` from a ``position_mm`` key; ``m or rad`` from Python)."""
    # compared, not subtracted: the difference of -1e308 and 1e308 overflowed, and numpy's
    # RuntimeWarning reached the command line's stderr with a line of numpy's source
    if np.any(not_up := positions[1:] <= positions[:-1]):
        i = int(np.argmax(not_up))
        raise _fail(
            f"positions must be strictly increasing, got {positions[i].item()!r} then "
            f"{positions[i + 1].item()!r} {unit} (indices {i}, {i + 1}) in "
            f"{positions.tolist()!r}",
            source,
            key,
        )


def _quantity(letter: str) -> str:
    """'length' for X Y Z (translation, linear axis), 'angle' for A B C (rotation, rotary)."""
    return "length" if letter in LINEAR_AXES else "angle"


#: What a ratio written as a unit means in an error model's keys (no unit of the file is one):
#: a scale error is the slope of a positioning polynomial, and a slope across an axis is an
#: angle. 10 ppm of X had been refused as an unknown length unit with no word of how to write it.
_RATIO_HINTS = {
    "ppm": ("; ppm is a ratio, not a length or an angle: a scale error of s ppm is the slope "
            "of the axis's positioning polynomial in um per m, e.g. [component.X] "
            "EXX_poly_um_m = [0.0, s], and a slope of s ppm across an axis (a squareness, a "
            "tilt) is an angle of s urad"),
}


def _check_unit(unit: str, quantity: str, source: str | None, key: str) -> float:
    """The factor to SI of `unit`, which must be a `quantity` ('length' or 'angle') unit."""
    units = LENGTH if quantity == "length" else ANGLE
    if unit in units:
        return units[unit]
    expected = f"expected {'a length' if quantity == 'length' else 'an angle'} unit "
    expected += f"({', '.join(units)})"
    if unit in FACTORS:
        other = "an angle" if quantity == "length" else "a length"
        raise _fail(f"{expected}, got {unit!r}, {other} unit", source, key)
    raise _fail(f"unit {unit!r} is not recognised; {expected}{_RATIO_HINTS.get(unit, '')}",
                source, key)


def _check_axis(axis: Any, source: str | None, key: str) -> None:
    if axis not in tuple(AXES):
        raise _fail(f"axis letter {axis!r} is not one of {', '.join(AXES)}", source, key)


def _check_symbol(symbol: str, axis: str, location: bool, source: str | None, key: str):
    """Refuse `symbol` unless it is an ISO 230 location (E<d>0<axis>) or component symbol."""
    kind, form = ("location", f"E<d>0{axis}") if location else ("component", f"E<d>{axis}")
    match = _SYMBOL_RE.fullmatch(symbol)
    if match is None or match[1] not in AXES or match[3] not in AXES:
        message = f"{symbol!r} is not an ISO 230 {kind} error symbol; expected {form}"
        raise _fail(f"{message} with d one of {', '.join(AXES)}", source, key)
    if bool(match[2]) != location:
        other = "a component (position-dependent)" if location else "a location (constant)"
        raise _fail(f"{symbol!r} is {other} symbol; [{kind}.{axis}] takes {form}", source, key)
    if match[3] != axis:
        raise _fail(f"symbol {symbol!r} is of axis {match[3]}, not [{kind}.{axis}]", source, key)
