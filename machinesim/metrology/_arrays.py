"""Checks shared by the feature fits: height maps, point sets, regular grids, read-only results."""

from __future__ import annotations

import numpy as np

from machinesim.arrays import frozen  # noqa: F401  (re-exported for the metrology modules)
from machinesim.exceptions import InputError

#: A grid is regular (as x3p and surfalize need it) when every coordinate lies within this
#: fraction of a spacing of the arithmetic progression: 1 pm at a 1 um spacing, far below any
#: lateral resolution, while linspace grids (~1e-13) pass.
REGULAR_GRID = 1e-6




def point_rows(points, width: int, name: str) -> np.ndarray:
    """Points as a float64 (N, width) copy without the rows that hold NaN."""
    try:
        points = np.array(points, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise InputError(f"Expected {name} as numbers (m), got {points!r}", key=name) from error
    if points.ndim != 2 or points.shape[1] != width:
        raise InputError(f"Expected {name} with shape (N, {width}), got {points.shape}", key=name)
    if np.isinf(points).any():
        raise InputError(f"Expected finite {name} or NaN, got infinity", key=name)
    return points[~np.isnan(points).any(axis=1)]


def map_arrays(x, y, z) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A height map as float64 copies: increasing axes x (nx,), y (ny,); z (ny, nx) or NaN."""
    try:
        x = np.array(x, dtype=np.float64)
        y = np.array(y, dtype=np.float64)
        z = np.array(z, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise InputError(f"Expected x, y and z as numbers (m): {error}") from error
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
    try:
        s = np.array(s, dtype=np.float64)
        z = np.array(z, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise InputError(f"Expected s and z as numbers (m): {error}") from error
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
