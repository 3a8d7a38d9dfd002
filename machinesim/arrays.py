"""Read-only float64 arrays: what every frozen result of machinesim holds; and integers that
no float64 holds (`beyond_float64`)."""

from __future__ import annotations

import numpy as np

__all__ = ["beyond_float64", "frozen"]


def beyond_float64(value) -> str | None:
    """``"an integer of N bits, beyond float64"`` when ``value`` is an integer too large for
    a float64 (TOML reads an integer of any length exactly, and ``float`` then overflows),
    else None: the words a refusal of it uses."""
    if isinstance(value, bool) or not isinstance(value, int):
        return None
    try:
        float(value)
    except OverflowError:
        return f"an integer of {value.bit_length()} bits, beyond float64 (about 1.8e308)"
    return None


def frozen(values, *, copy: bool = True) -> np.ndarray:
    """``values`` as a read-only float64 array.

    With ``copy=False`` an array that is already float64 and contiguous is frozen in place
    (no copy: for large arrays the caller has just made and hands over).
    """
    array = np.array(values, dtype=np.float64) if copy else np.ascontiguousarray(
        values, dtype=np.float64)
    array.flags.writeable = False
    return array
