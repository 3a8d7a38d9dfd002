"""Read-only float64 arrays: what every frozen result of machinesim holds."""

from __future__ import annotations

import numpy as np

__all__ = ["frozen"]


def frozen(values, *, copy: bool = True) -> np.ndarray:
    """``values`` as a read-only float64 array.

    With ``copy=False`` an array that is already float64 and contiguous is frozen in place
    (no copy: for large arrays the caller has just made and hands over).
    """
    array = np.array(values, dtype=np.float64) if copy else np.ascontiguousarray(
        values, dtype=np.float64)
    array.flags.writeable = False
    return array
