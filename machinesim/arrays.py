"""Read-only float64 arrays: what every frozen result of machinesim holds."""

from __future__ import annotations

import numpy as np

__all__ = ["frozen"]


def frozen(values) -> np.ndarray:
    """A read-only float64 copy of ``values``."""
    array = np.array(values, dtype=np.float64)
    array.flags.writeable = False
    return array
