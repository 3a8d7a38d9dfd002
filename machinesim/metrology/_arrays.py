"""Checks shared by the metrology modules: numbers, arrays, height maps, point sets, regular
grids, read-only results.

Every number and array an instrument or a fit takes goes through `as_number`, `as_count`,
`as_flag` or `as_floats`: a real number (int, float, numpy scalar) or an array of them,
never a string (``sigma="1"`` would otherwise be read as 1 m while ``sigma="12nm"`` is
refused), a bool (``True`` as 1 m) or None; anything else is an `InputError` naming the
argument.
"""

from __future__ import annotations

import math
import numbers

import numpy as np

from machinesim.arrays import frozen  # noqa: F401  (re-exported for the metrology modules)
from machinesim.exceptions import InputError

#: A grid is regular (as x3p and surfalize need it) when every coordinate lies within this
#: fraction of a spacing of the arithmetic progression: 1 pm at a 1 um spacing, far below any
#: lateral resolution, while linspace grids (~1e-13) pass.
REGULAR_GRID = 1e-6
#: The signs `as_number` checks.
_SIGNS = {"any": None, ">= 0": lambda v: v >= 0.0, "> 0": lambda v: v > 0.0}


def shown(value, width: int = 60) -> str:
    """``repr(value)`` cut to ``width`` characters (an array may be long)."""
    text = repr(value)
    return text if len(text) <= width else text[:width - 3] + "..."


def as_number(value, name: str, *, sign: str = "any", unit: str = "m",
              limit: float | None = None, why: str = "") -> float:
    """``value`` as a finite float, or an InputError naming ``name``, the value and the want.

    Parameters
    ----------
    value : int, float or numpy scalar (or 0-d numeric array)
        A str (even ``"1"``), a bool, None or a sequence is refused, not converted.
    name : str
        The argument, for the message.
    sign : {"any", ">= 0", "> 0"}
        What the value must be.
    unit : str
        For the message (``"m"``, ``"rad"``, ...).
    limit : float, optional
        Largest value accepted; ``why`` (a phrase) says where that bound comes from.
    """
    if isinstance(value, np.ndarray) and value.ndim == 0 and value.dtype.kind in "iuf":
        value = value.item()
    if isinstance(value, bool | np.bool_) or not isinstance(value, numbers.Real):
        raise InputError(f"Expected {name} as a number ({unit}), got {shown(value)}",
                         key=name)
    try:
        number = float(value)
    except OverflowError:  # an int beyond float64 (10**400): no finite float
        raise InputError(f"Expected a finite {name} ({unit}), got an int of "
                         f"{int(value).bit_length()} bits, beyond float64", key=name) from None
    check = _SIGNS[sign]
    if not math.isfinite(number) or (check is not None and not check(number)):
        want = f"a finite {name}" if check is None else f"{name} {sign}"
        raise InputError(f"Expected {want} ({unit}), got {number!r}", key=name)
    if limit is not None and number > limit:
        raise InputError(f"Expected {name} <= {limit:g} {unit}{why}, got {number!r}",
                         key=name)
    return number


def as_count(value, name: str, *, least: int = 1) -> int:
    """``value`` as an int of at least ``least``: an int or numpy integer (``np.int64(41)``
    is 41), never a bool (True is no 1), a float (``41.0``) or a str."""
    if isinstance(value, bool | np.bool_) or not isinstance(value, int | np.integer) \
            or value < least:
        raise InputError(f"Expected {name} as a whole number >= {least}, got {shown(value)}",
                         key=name)
    return int(value)


def as_flag(value, name: str) -> bool:
    """``value`` as a bool: True or False only (``"no"`` would otherwise count as True)."""
    if not isinstance(value, bool | np.bool_):
        raise InputError(f"Expected {name} as True or False, got {shown(value)}", key=name)
    return bool(value)


def as_floats(value, name: str, what: str = "numbers (m)") -> np.ndarray:
    """``value`` as a float64 array (a copy) of any shape, or an InputError naming ``name``.

    Numbers only: text (``"abc"``, ``["1", "2"]``), booleans (among numbers too, ``(True,
    0)``), None and ragged nesting are refused, not converted. NaN and infinity pass: the
    caller decides on them.
    """
    try:
        array = np.asarray(value)
    except (TypeError, ValueError) as error:  # ragged nesting
        raise InputError(f"Expected {name} as {what} in a regular (non-ragged) array, got "
                         f"{shown(value)}", key=name) from error
    kind = array.dtype.kind
    if kind == "O" and all(isinstance(v, numbers.Real) and not isinstance(v, bool | np.bool_)
                           for v in array.flat):
        kind = "f"
    # a bool among numbers in a list or tuple is made a number by numpy ((True, 0) an int
    # array, [0.5, False] a float one): Registration(offset=(True, 0, 0)) read 1 m. Only a
    # 0 or 1 can be one, so a list without either is not looked through
    if kind not in "iuf" or (isinstance(value, (list, tuple)) and kind != "O"
                             and _holds_bool(value, array)):
        raise InputError(f"Expected {name} as {what}, got {shown(value)}", key=name)
    try:
        return np.array(array, dtype=np.float64)
    except OverflowError:  # an int beyond float64 (10**400), held as an object
        raise InputError(f"Expected {name} as {what} within float64's range, got an int "
                         "too large to convert", key=name) from None


def _holds_bool(items, array: np.ndarray) -> bool:
    """Whether the list or tuple ``items`` (of lists ...), read by numpy as ``array``, holds
    a bool, Python's or numpy's: a few items are looked through, of more only the 0s and
    1s (measured on a list of 200,000 rows of 3, which numpy reads in ~80 ms: one 0 among
    them costs ~10 ms more, z = 0 in every row ~0.12 s; an ndarray is not looked at)."""
    if array.size <= 64:
        return _any_bool(items)
    suspects = (array == 0) | (array == 1)
    count = int(suspects.sum())
    if count > 10_000:  # the object array costs as much as numpy's reading, once
        return any(isinstance(v, _BOOLS) for v in np.asarray(items, dtype=object)[suspects])
    for index in np.argwhere(suspects).tolist():
        item = items
        for k in index:
            item = item[k]
        if isinstance(item, _BOOLS):
            return True
    return False


def _any_bool(items) -> bool:
    for v in items:
        if isinstance(v, _BOOLS) or (isinstance(v, (list, tuple)) and _any_bool(v)) or (
                isinstance(v, np.ndarray) and v.dtype.kind == "b"):
            return True
    return False


_BOOLS = (bool, np.bool_)


def point_rows(points, width: int, name: str) -> np.ndarray:
    """Points as a float64 (N, width) copy without the rows that hold NaN."""
    points = as_floats(points, name)
    if points.ndim != 2 or points.shape[1] != width:
        raise InputError(f"Expected {name} with shape (N, {width}), got {points.shape}", key=name)
    if np.isinf(points).any():
        raise InputError(f"Expected finite {name} or NaN, got infinity", key=name)
    return points[~np.isnan(points).any(axis=1)]


def map_arrays(x, y, z) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A height map as float64 copies: increasing axes x (nx,), y (ny,); z (ny, nx) or NaN."""
    x, y, z = (as_floats(value, name) for value, name in ((x, "x"), (y, "y"), (z, "z")))
    if x.ndim != 1 or y.ndim != 1 or z.shape != (y.size, x.size):
        raise InputError(f"Expected x (nx,), y (ny,) and z (ny, nx), got {x.shape}, {y.shape} "
                         f"and {z.shape}")
    for name, axis in (("x", x), ("y", y)):
        if not np.isfinite(axis).all() or np.any(np.diff(axis) <= 0.0):
            raise InputError(f"Expected finite, strictly increasing {name}", key=name)
    if np.isinf(z).any():
        raise InputError("Expected finite z or NaN, got infinity", key="z")
    return x, y, z


def profile_arrays(s, z, minimum: int) -> tuple[np.ndarray, np.ndarray]:
    """A profile's seen samples as float64 copies: s strictly increasing, NaN heights left out."""
    s, z = as_floats(s, "s"), as_floats(z, "z")
    if s.ndim != 1 or s.shape != z.shape:
        raise InputError(f"Expected s and z of the same shape (k,), got {s.shape} and {z.shape}")
    if not np.isfinite(s).all() or np.any(np.diff(s) <= 0.0):
        raise InputError("Expected finite, strictly increasing s", key="s")
    if np.isinf(z).any():
        raise InputError("Expected finite z or NaN, got infinity", key="z")
    seen = ~np.isnan(z)
    if seen.sum() < minimum:
        raise InputError(f"Expected at least {minimum} finite samples, got {int(seen.sum())}",
                         key="z")
    return s[seen], z[seen]


def regular_step(axis: np.ndarray, name: str) -> float:
    """Spacing of a regular grid axis (m), or an InputError naming the axis."""
    if axis.size < 2:
        raise InputError(f"Expected at least two samples along {name}, got {axis.size}", key=name)
    step = float(axis[-1] - axis[0]) / (axis.size - 1)
    deviation = float(np.abs(axis - (axis[0] + np.arange(axis.size) * step)).max())
    if deviation > REGULAR_GRID * step:
        raise InputError(f"Expected a regular grid along {name}, got samples up to "
                         f"{deviation:.3g} m off a {step:.6g} m spacing", key=name)
    return step
