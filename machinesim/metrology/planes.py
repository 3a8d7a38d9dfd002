"""Edges of fitted planes: where two faces meet, and the distance across a part between two
such edges (paper 002, Table 3: the crown's edge distances L).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from machinesim.arrays import frozen
from machinesim.exceptions import InputError
from machinesim.metrology._arrays import as_floats, shown

__all__ = ["Line3D", "line_distance", "plane_intersection"]

#: Two planes whose normals' cross product (the sine of their angle) is below this are
#: parallel: the line where they meet would move by more than 1e12 times any error in them.
PARALLEL_SINE = 1e-12


@dataclass(frozen=True, eq=False)
class Line3D:
    """A straight line in space (m).

    Attributes
    ----------
    point : ndarray, shape (3,)
        A point on the line.
    direction : ndarray, shape (3,)
        Unit direction.
    """

    point: np.ndarray
    direction: np.ndarray


def plane_intersection(first, second) -> Line3D:
    """The line where two planes meet (`machinesim.metrology.PlaneFit` or anything with a
    ``point`` and a unit ``normal``): its point nearest the midpoint of the planes' points.

    Raises
    ------
    InputError
        When either is not a plane (a point and a unit normal of 3 finite numbers each), or
        the planes are parallel (`PARALLEL_SINE`).
    """
    for name, plane in (("first", first), ("second", second)):
        _parts(plane, name, ("point", "normal"), "a plane with a point and a unit normal, "
               "each 3 finite numbers (a PlaneFit from fit_plane)")
    direction = np.cross(first.normal, second.normal)
    norm = np.linalg.norm(direction)
    if not norm > PARALLEL_SINE:
        raise InputError(f"Expected two planes that meet, got parallel normals "
                         f"{np.asarray(first.normal).tolist()} and "
                         f"{np.asarray(second.normal).tolist()}")
    direction = direction / norm
    normals = np.array([first.normal, second.normal, direction])
    offsets = np.array([first.normal @ first.point, second.normal @ second.point,
                        direction @ (0.5 * (first.point + second.point))])
    return Line3D(frozen(np.linalg.solve(normals, offsets)), frozen(direction))


def line_distance(first: Line3D, second: Line3D) -> float:
    """Distance between two (nearly) parallel lines, across their mean direction, m.

    Raises
    ------
    InputError
        When either is not a line (a point and a unit direction of 3 finite numbers each,
        a `Line3D` from `plane_intersection`).
    """
    (p, d), (q, e) = (_parts(line, name, ("point", "direction"), "a line with a point and a "
                             "unit direction, each 3 finite numbers (a Line3D from "
                             "plane_intersection)")
                      for line, name in ((first, "first"), (second, "second")))
    mean = d + (e if d @ e >= 0.0 else -e)
    mean = mean / np.linalg.norm(mean)
    gap = q - p
    return float(np.linalg.norm(gap - (gap @ mean) * mean))


def _parts(value, name: str, fields: tuple[str, str], want: str) -> list[np.ndarray]:
    """The point and unit vector ``fields`` of a plane or line as float64 arrays of 3 finite
    numbers, or an InputError naming ``name`` (never a bare AttributeError)."""
    try:
        values = [as_floats(getattr(value, k), name) for k in fields]
    except AttributeError:
        values = []
    if (len(values) != 2 or any(v.shape != (3,) or not np.isfinite(v).all() for v in values)
            or not np.isclose(np.linalg.norm(values[1]), 1.0)):
        raise InputError(f"Expected {name} as {want}, got {shown(value)}", key=name)
    return values
